// Export of model hillaire's tables for engines (docs/tables.md): the transmittance, the
// multiple-scattering, the sky-view (for one observer altitude and sun, with and without the lit
// ground) and the aerial-perspective tables (for one camera), each as EXR and raw float, with one
// JSON manifest that gives sizes, layout, texel centres, every mapping and its inverse, units, the
// parameter hash and the atmo version. build/share/atmo/atmo_tables.glsl (installed to
// share/atmo) samples them in an engine's shader.
//
// To use it:
//   auto model = atmo::CreateModel("hillaire", atmo::Preset("earth"));
//   atmo::HillaireExportView view;                     // observer, sun, aerial-perspective camera
//   view.altitude_m = 100.0;
//   atmo::HillaireTables tables = atmo::ComputeHillaireTables(*model, view);
//   atmo::ExportHillaireTables(tables, "sky");         // sky.json, sky_transmittance.exr, ... .raw
//   atmo::HillaireTables again = atmo::ReadHillaireTables("sky");
// (gl::ComputeHillaireTablesGl in src/atmo/gl/hillaire_gl.h computes them on the GL backend.)
//
// Every table holds three floats per texel: channels 3b, 3b + 1, 3b + 2 of batch b in R, G, B (a
// last batch with fewer than three channels repeats its last one); the batches of a preset with
// more than three channels follow one another in the same file.
#pragma once

#include <cstddef>
#include <filesystem>
#include <string>
#include <string_view>
#include <utility>
#include <vector>

#include "atmo/aerial_perspective.h"
#include "atmo/model.h"
#include "atmo/parameters.h"
#include "atmo/render.h"

namespace atmo {

inline constexpr int kHillaireTablesFormatVersion = 1;

// One exported table: width x height x depth texels, `batches` times, of 3 floats; texel (x, y, z)
// of batch b at float index 3 (x + W (y + H (z + D b))) of `rgb`.
struct ExportedTable {
  std::string name;  // file suffix and manifest key: "transmittance", "sky_view", ...
  int width = 0;
  int height = 0;
  int depth = 1;
  std::size_t batches = 1;
  std::vector<float> rgb;
  std::size_t texel_count() const { return static_cast<std::size_t>(width) * height * depth; }
  // Channel k (0..2) of texel (x, y, z) of batch b.
  float at(int x, int y, int z, std::size_t b, int k) const {
    return rgb[3 * (static_cast<std::size_t>(x) + static_cast<std::size_t>(width) *
                    (y + static_cast<std::size_t>(height) * (z + static_cast<std::size_t>(depth) * b))) + k];
  }
};

// The view-dependent tables' observer and sun, and the aerial-perspective camera.
struct HillaireExportView {
  double altitude_m = 0.0;          // observer, >= 0 and at most the top of the atmosphere
  double sun_elevation_deg = 30.0;
  double sun_azimuth_deg = 180.0;   // compass azimuth (the sky view does not depend on it)
  Camera camera;                    // perspective; the aerial-perspective volume's frustum
  AerialPerspectiveSettings aerial;
};

// The names of the tables, in the order of HillaireTables::tables and of the manifest.
inline constexpr std::string_view kHillaireTableNames[] = {"transmittance",  "multiple_scattering", "sky_view",
                                                           "sky_view_ground", "aerial_radiance",
                                                           "aerial_transmittance"};

struct HillaireTables {
  AtmosphereParameters parameters;
  std::vector<std::pair<std::string, std::string>> options;  // the hillaire settings that made them
  HillaireExportView view;
  std::string backend = "cpu";  // "cpu" or "gl": which computed them
  std::vector<ExportedTable> tables;  // kHillaireTableNames order
  // Throws atmo::Error for a name that is not a table.
  const ExportedTable& table(std::string_view name) const;
};

// Computes the tables with a model made by CreateModel("hillaire", ...), on the CPU. Throws
// atmo::Error for another model, an altitude outside [0, top], a non-finite sun or a camera that
// is not perspective (ValidateCamera and ValidateAerialPerspectiveSettings apply).
HillaireTables ComputeHillaireTables(const Model& model, const HillaireExportView& view);

struct HillaireTableFiles {
  std::filesystem::path json;  // NAME.json, the manifest
  // NAME_<table>.exr and NAME_<table>.raw, kHillaireTableNames order.
  std::vector<std::filesystem::path> exr;
  std::vector<std::filesystem::path> raw;
  std::vector<std::filesystem::path> all() const;  // every file, the manifest last
};
HillaireTableFiles HillaireTableFilesFor(const std::filesystem::path& name);

// Writes every table as NAME_<table>.exr and .raw and the manifest NAME.json as one set: all
// written completely first, then published together, the manifest last, under an exclusive lock
// of their folder (flock; readers take it shared). A failed write changes no file. Throws
// atmo::Error.
HillaireTableFiles ExportHillaireTables(const HillaireTables& tables, const std::filesystem::path& name);

// Reads an export back from its manifest and raw files, checking the format, the sizes and each
// raw file's hash, that the tables make one set (the 2D tables of depth 1 and >= 2 texels a side,
// the sky views' heights even and >= 4, the two sky views and the two aerial tables each of one
// size) and that the view is one ComputeHillaireTables takes (ValidateHillaireExportView). A manifest of another format version is refused in one line; one written by
// another atmo version with this format version loads, with a one-line warning on stderr.
// Throws atmo::Error naming the file and the mismatch.
HillaireTables ReadHillaireTables(const std::filesystem::path& name);

}  // namespace atmo
