// Export and load of the `elek` model's scattering table (docs/models/elek.md#export-format).
//
// To use it:
//   auto model = atmo::CreateModel("elek", atmo::Preset("atmosphere-plus"));
//   atmo::ExportElekTable(*model, "sky");        // writes sky.exr, sky.raw, sky.json
//   auto again = atmo::CreateModel("elek", atmo::Preset("atmosphere-plus"), {{"table", "sky"}});
// Loading (the model option table=NAME, `--table NAME` on the command line) refuses, with an
// atmo::Error of one line, a manifest whose format version, atmo version, parameter hash, sizes or
// table options differ from the model's, or whose raw data fails its hash.
//
// NAME.raw: little-endian float32 RGBA, texel (x, y, z) of a W x H x D table at index
//   i = x + y W + z W H (4 floats per texel; a preset with more than 3 channels appends one table
//   per batch of three channels); RGB = factored Rayleigh per channel, A = factored Mie of the
//   batch's first channel; texel x sits at u = x / (W - 1) (the seed's layout).
// NAME.exr: the same values as a W x (H D batches) float image, R, G, B, A; slice z of batch b is
//   the band of H rows starting at row H (z + D b).
// NAME.json: the manifest (parameterisation, sizes, channels, units, parameters, options,
//   atmo version, parameter hash, format version, hash of NAME.raw).
#pragma once

#include <filesystem>

#include "atmo/model.h"

namespace atmo {

inline constexpr int kElekTableFormatVersion = 1;

struct ElekTableFiles {
  std::filesystem::path exr;
  std::filesystem::path raw;
  std::filesystem::path json;
};

// The three file names of NAME (NAME.exr, NAME.raw, NAME.json).
ElekTableFiles ElekTableFilesFor(const std::filesystem::path& name);

// Writes the three files of a model made by CreateModel("elek", ...) as one set: all three are
// written completely first, then published together, the manifest last, under an exclusive lock
// of their folder (flock), while loading holds a shared one. A failed write changes no file, two
// exports to one name publish one after the other, and a load never sees a mixed set. Throws
// atmo::Error for another model, a model whose table was loaded, or a failed write.
ElekTableFiles ExportElekTable(const Model& model, const std::filesystem::path& name);

}  // namespace atmo
