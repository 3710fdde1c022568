// The memory budget of a process: sizes are checked against it before the large allocations
// (a model's tables, a rendered image, an aerial-perspective volume), so that a size too large for
// the machine is refused in one line with its estimate instead of ending in std::bad_alloc or
// in the kernel's out-of-memory killer (docs/reliability.md, "Memory").
//
// To use it:
//   atmo::SetMemoryLimitBytes(atmo::ParseByteSize("4G"));     // what --max-memory 4G does
//   atmo::CheckMemory("elek tables (size=1024x4096x1024)", bytes);   // throws atmo::Error
#pragma once

#include <cstdint>
#include <string>
#include <string_view>

namespace atmo {

// This machine's physical memory in bytes (0 when the system does not say).
std::uint64_t PhysicalMemoryBytes();

// The limit: by default half of the physical memory (8 GiB when unknown); SetMemoryLimitBytes(0)
// restores the default. Thread-safe.
std::uint64_t MemoryLimitBytes();
void SetMemoryLimitBytes(std::uint64_t bytes);

// Throws atmo::Error when `bytes` is above the limit (or not finite):
// "<what> would need about 12.9 GB, more than the memory limit of 7.8 GB (half of this machine's
// memory; --max-memory changes it)".
void CheckMemory(std::string_view what, double bytes);

// "4G", "512M", "1.5GB", "64k", "1000000" (bytes; K/M/G/T are powers of 1024, a trailing B or iB
// optional, case-insensitive) to bytes, in [1 MiB, 1 PiB]. Throws atmo::Error otherwise.
std::uint64_t ParseByteSize(std::string_view text);

// 1536 -> "1.5 KB", 3.2e9 -> "3.0 GB" (powers of 1024, one decimal).
std::string FormatBytes(double bytes);

}  // namespace atmo
