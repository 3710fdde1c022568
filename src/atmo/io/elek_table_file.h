// Files of the `elek` table (private side of include/atmo/elek.h).
#pragma once

#include <cstdint>
#include <span>
#include <string>

namespace atmo {

class ElekModel;

// Reads NAME.json and NAME.raw, checks them against the model (format and atmo versions,
// parameter hash, sizes and options, data hash) and installs the table with SetRgba. Throws
// atmo::Error naming the file and the mismatch.
void LoadElekTable(const std::string& name, ElekModel& model);

// FNV-1a 64 of bytes.
std::uint64_t Fnv1a64(std::span<const unsigned char> bytes);

}  // namespace atmo
