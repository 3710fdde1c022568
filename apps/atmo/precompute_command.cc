// `atmo precompute`: computes a model's tables and exports them for engines.
//   elek:     NAME.exr, NAME.raw, NAME.json and NAME_transmittance.exr/.raw (include/atmo/elek.h,
//             docs/models/elek.md);
//   hillaire: NAME_<table>.exr and .raw of the transmittance, multiple-scattering, sky-view (with
//             and without the ground) and aerial-perspective tables, and NAME.json
//             (include/atmo/hillaire_tables.h, docs/tables.md).
// The files are written as one set, the manifest last. With --backend gl the tables are computed
// on the GPU and read back for export.
#include <chrono>
#include <cstdio>
#include <filesystem>
#include <string>

#include "atmo/elek.h"
#include "atmo/error.h"
#include "atmo/hillaire_tables.h"
#include "commands.h"
#include "io/hillaire_table_file.h"
#ifdef ATMO_HAVE_GL
#include "gl/hillaire_gl.h"
#endif

namespace atmo::cli {
namespace {

double SecondsSince(std::chrono::steady_clock::time_point t) {
  return std::chrono::duration<double>(std::chrono::steady_clock::now() - t).count();
}

// WxHxD, each in [1, 512].
AerialPerspectiveSettings ParseAerialSize(const std::string& text, double max_distance_m) {
  AerialPerspectiveSettings s;
  s.max_distance_m = max_distance_m;
  char x1 = 0;
  char x2 = 0;
  char rest = 0;
  if (std::sscanf(text.c_str(), "%d%c%d%c%d%c", &s.width, &x1, &s.height, &x2, &s.depth, &rest) != 5 || x1 != 'x' ||
      x2 != 'x') {
    throw Error("--aerial-size " + text + ": expected WxHxD, e.g. 32x32x32");
  }
  ValidateAerialPerspectiveSettings(s);
  return s;
}

// The export's NAME: the prefix of every file it writes (NAME.json, NAME.exr, NAME_<table>.raw, ...),
// so it must end in a file name. "" wrote .json, .exr and .raw, hidden, into the current folder; a
// folder ("out/", "out", ".") wrote hidden files into it, or beside it.
void CheckExportName(const std::string& name) {
  if (name.empty()) throw Error("--out must be the tables' NAME (NAME.json, ...), got an empty name");
  const std::filesystem::path path(name);
  const std::string last = path.filename().string();
  std::error_code ec;
  if (name.back() == '/' || last.empty() || last == "." || last == ".." ||
      std::filesystem::is_directory(path, ec)) {
    throw Error("--out '" + name + "' is a folder; give the tables' NAME (NAME.json, ...), e.g. '" +
                (path / "sky").string() + "'");
  }
}

HillaireExportView ExportView(const PrecomputeCommand& command, const AtmosphereParameters& parameters) {
  HillaireExportView view;
  view.altitude_m = command.altitude_m.value_or(parameters.observer_altitude_m);
  view.sun_elevation_deg = command.sun_elevation_deg;
  view.sun_azimuth_deg = command.sun_azimuth_deg;
  if (HasDate(command.sun)) {
    const SunAtInstant at = SunAtDate(command.sun);
    view.sun_elevation_deg = at.position.elevation_deg;
    view.sun_azimuth_deg = at.position.azimuth_deg;
  }
  view.camera.kind = CameraKind::kPerspective;
  view.camera.width = command.width;
  view.camera.height = command.height;
  view.camera.fov_deg = command.fov_deg;
  view.camera.yaw_deg = command.yaw_deg.value_or(view.sun_azimuth_deg);
  view.camera.pitch_deg = command.pitch_deg;
  view.aerial = ParseAerialSize(command.aerial_size, command.aerial_distance_m);
  ValidateHillaireExportView(parameters, view);  // before any work
  return view;
}

int PrecomputeHillaire(const CommonOptions& common, const PrecomputeCommand& command) {
  const HillaireTableFiles files = HillaireTableFilesFor(command.out);
  std::vector<NamedPath> outputs;
  for (const auto& path : files.all()) outputs.push_back({"--out", path});
  CheckOutputsApart(common, {}, outputs);
  const AtmosphereParameters parameters = LoadParameters(common);
  for (const auto& path : files.all()) CheckOutputWritable(path);
  const HillaireExportView view = ExportView(command, parameters);
  const auto start = std::chrono::steady_clock::now();
  HillaireTables tables;
#ifdef ATMO_HAVE_GL
  if (common.backend == "gl") {
    const gl::Context context;
    tables = gl::ComputeHillaireTablesGl(context, parameters, GlHillaireSettings(common), view);
  }
#endif
  if (common.backend != "gl") tables = ComputeHillaireTables(*CreateModelFor(common, parameters), view);
  const double precompute_s = SecondsSince(start);
  const auto write_start = std::chrono::steady_clock::now();
  ExportHillaireTables(tables, command.out);
  const double write_s = SecondsSince(write_start);
  std::printf("wrote %s and %zu tables as %s_<table>.exr, .raw (hillaire, %s, %s, altitude %.6g m, sun elevation "
              "%.6g deg) in %.2f s: precompute %.2f s, write %.2f s\n",
              files.json.string().c_str(), files.exr.size(), command.out.c_str(), parameters.name.c_str(),
              tables.backend.c_str(), view.altitude_m, view.sun_elevation_deg, SecondsSince(start), precompute_s,
              write_s);
  return 0;
}

}  // namespace

int RunPrecompute(const CommonOptions& common, const PrecomputeCommand& command) {
  CheckBackend(common, /*command_has_gl=*/true);
  CheckExportName(command.out);
  if (common.model == "hillaire") return PrecomputeHillaire(common, command);
  if (common.model != "elek") {
    throw Error("precompute exports the tables of models elek and hillaire; model " + common.model +
                " has none (use --model elek or --model hillaire)");
  }
  const ElekTableFiles files = ElekTableFilesFor(command.out);
  CheckOutputsApart(common, {},
                    {{"--out", files.exr},
                     {"--out", files.raw},
                     {"--out", files.json},
                     {"--out", files.transmittance_exr},
                     {"--out", files.transmittance_raw}});
  const AtmosphereParameters parameters = LoadParameters(common);
  for (const auto& path : {files.exr, files.raw, files.json, files.transmittance_exr, files.transmittance_raw}) {
    CheckOutputWritable(path);
  }
  const auto start = std::chrono::steady_clock::now();
  const std::unique_ptr<Model> model = CreateModelFor(common, parameters);
  const double precompute_s = SecondsSince(start);
  const auto write_start = std::chrono::steady_clock::now();
  ExportElekTable(*model, command.out);
  const double write_s = SecondsSince(write_start);
  // The whole time and its parts, as `atmo render` reports them.
  std::printf("wrote %s, %s, %s, %s, %s (elek, %s) in %.2f s: precompute %.2f s, write %.2f s\n",
              files.exr.string().c_str(), files.raw.string().c_str(), files.transmittance_exr.string().c_str(),
              files.transmittance_raw.string().c_str(), files.json.string().c_str(), parameters.name.c_str(),
              SecondsSince(start), precompute_s, write_s);
  return 0;
}

}  // namespace atmo::cli
