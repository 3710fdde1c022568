// Export and load of the `elek` model's scattering table (docs/models/elek.md#export-format).
//
// To use it:
//   auto model = atmo::CreateModel("elek", atmo::Preset("atmosphere-plus"));
//   atmo::ExportElekTable(*model, "sky");        // writes sky.exr, sky.raw, sky.json
//   auto again = atmo::CreateModel("elek", atmo::Preset("atmosphere-plus"), {{"table", "sky"}});
// Loading (the model option table=NAME, `--table NAME` on the command line) refuses, with an
// atmo::Error of one line, a manifest whose format version, parameter hash, sizes or table options
// differ from the model's, or whose raw data fails its hash; a manifest of this format version
// written by another atmo version loads, with a one-line warning on stderr.
//
// NAME.raw: little-endian float32 RGBA, texel (x, y, z) of a W x H x D table at index
//   i = x + y W + z W H (4 floats per texel; a preset with more than 3 channels appends one table
//   per batch of three channels); RGB = factored Rayleigh per channel, A = factored Mie of the
//   batch's first channel; texel x sits at u = x / (W - 1) (the seed's layout).
// NAME.exr: the same values as a W x (H D batches) float image, R, G, B, A; slice z of batch b is
//   the band of H rows starting at row H (z + D b).
// NAME_transmittance.exr, NAME_transmittance.raw: the 2D sun-transmittance table (256 x 64 by
//   default), little-endian float32 RGB, texel (x, y) of batch b at float index 3 (x + W (y + H b)),
//   the EXR one band of H rows per batch; Bruneton's (r, mu) mapping, spelled out in the manifest's
//   "transmittance" entry (docs/tables.md). Loading does not read it (the table is recomputed).
// NAME.json: the manifest (parameterisation, sizes, channels, units, parameters, options,
//   atmo version, parameter hash, format version, hash of NAME.raw, the transmittance entry).
#pragma once

#include <filesystem>

#include "atmo/model.h"

namespace atmo {

inline constexpr int kElekTableFormatVersion = 1;

struct ElekTableFiles {
  std::filesystem::path exr;
  std::filesystem::path raw;
  std::filesystem::path json;
  std::filesystem::path transmittance_exr;  // NAME_transmittance.exr
  std::filesystem::path transmittance_raw;  // NAME_transmittance.raw
};

// The file names of NAME (NAME.exr, NAME.raw, NAME.json, NAME_transmittance.exr and .raw).
ElekTableFiles ElekTableFilesFor(const std::filesystem::path& name);

// Writes the five files of a model made by CreateModel("elek", ...) as one set: all five are
// written completely first, then published together, the manifest last, under an exclusive lock
// of their folder (flock), while loading holds a shared one. A failed write changes no file, two
// exports to one name publish one after the other, and a load never sees a mixed set. Throws
// atmo::Error for another model, a model whose table was loaded, or a failed write.
ElekTableFiles ExportElekTable(const Model& model, const std::filesystem::path& name);

}  // namespace atmo
