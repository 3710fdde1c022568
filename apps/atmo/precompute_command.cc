// `atmo precompute`: computes a model's table and exports it. Today only model elek has an
// exportable table (NAME.exr, NAME.raw, NAME.json; the format is in include/atmo/elek.h and
// docs/models/elek.md). The files are written atomically, the manifest last. With --backend gl the
// table is computed on the GPU (gl::PrecomputeElekGl) and read back for export.
#include <chrono>
#include <cstdio>

#include "atmo/elek.h"
#include "atmo/error.h"
#include "commands.h"

namespace atmo::cli {

int RunPrecompute(const CommonOptions& common, const PrecomputeCommand& command) {
  CheckBackend(common, /*command_has_gl=*/true);
  if (common.model != "elek") {
    throw Error("precompute exports the table of model elek; model " + common.model + " has none (use --model elek)");
  }
  const ElekTableFiles files = ElekTableFilesFor(command.out);
  CheckOutputsApart(common, {}, {{"--out", files.exr}, {"--out", files.raw}, {"--out", files.json}});
  const AtmosphereParameters parameters = LoadParameters(common);
  for (const auto& path : {files.exr, files.raw, files.json}) CheckOutputWritable(path);
  const auto seconds_since = [](std::chrono::steady_clock::time_point t) {
    return std::chrono::duration<double>(std::chrono::steady_clock::now() - t).count();
  };
  const auto start = std::chrono::steady_clock::now();
  const std::unique_ptr<Model> model = CreateModelFor(common, parameters);
  const double precompute_s = seconds_since(start);
  const auto write_start = std::chrono::steady_clock::now();
  ExportElekTable(*model, command.out);
  const double write_s = seconds_since(write_start);
  // The whole time and its parts, as `atmo render` reports them.
  std::printf("wrote %s, %s, %s (elek, %s) in %.2f s: precompute %.2f s, write %.2f s\n", files.exr.string().c_str(),
              files.raw.string().c_str(), files.json.string().c_str(), parameters.name.c_str(), seconds_since(start),
              precompute_s, write_s);
  return 0;
}

}  // namespace atmo::cli
