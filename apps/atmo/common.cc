// Helpers shared by the subcommands of `atmo`: parameters, model options, output checks.
#include <unistd.h>

#include <cctype>
#include <charconv>
#include <cstdarg>
#include <cstdio>
#include <filesystem>
#include <memory>
#include <string>
#include <system_error>

#include "atmo/error.h"
#include "atmo/spectrum.h"
#include "atmo/table_cache.h"
#include "commands.h"
#ifdef ATMO_HAVE_GL
#include "gl/context.h"
#include "gl/elek_gl.h"
#include "gl/hillaire_gl.h"
#include "gl/source4d_gl.h"
#endif

namespace atmo::cli {

namespace fs = std::filesystem;

AtmosphereParameters LoadParameters(const CommonOptions& common) {
  AtmosphereParameters parameters = common.config.empty() ? Preset(common.preset) : LoadParametersFile(common.config);
  if (common.spectral != 0) parameters = MakeSpectral(parameters, common.spectral);
  if (!common.wavelengths.empty()) parameters = MakeSpectral(parameters, common.wavelengths);
  ApplyAerosolRequest(parameters, common.aerosol);
  return parameters;
}

ModelOptions ParseModelOptions(const std::vector<std::string>& options) {
  ModelOptions parsed;
  for (const std::string& option : options) {
    const std::size_t equals = option.find('=');
    if (equals == std::string::npos || equals == 0) {
      throw Error("--option expects KEY=VALUE, got '" + option + "'");
    }
    const std::string key = option.substr(0, equals);
    if (!parsed.emplace(key, option.substr(equals + 1)).second) {
      throw Error("--option " + key + " is given more than once");
    }
  }
  return parsed;
}

void CheckBackend(const CommonOptions& common, bool command_has_gl) {
  if (common.backend == "gl") {
#ifdef ATMO_HAVE_GL
    if (!command_has_gl) {
      throw Error("the gl backend runs `atmo render`, `sample`, `precompute` and `bench`; use --backend cpu");
    }
    if (common.model != "hillaire" && common.model != "elek" && common.model != "source4d") {
      throw Error("the gl backend runs models hillaire, elek and source4d (got model '" + common.model +
                  "'); use --backend cpu");
    }
    return;
#else
    throw Error("the gl backend is not available in this build");
#endif
  }
  if (common.backend != "cpu") throw Error("unknown backend '" + common.backend + "' (known: cpu, gl)");
}

#ifdef ATMO_HAVE_GL
namespace {

// The --option settings without "seed", which the deterministic models ignore (as CreateModel does).
ModelOptions DeterministicModelOptions(const CommonOptions& common) {
  ModelOptions options = ParseModelOptions(common.options);
  options.erase("seed");
  return options;
}

}  // namespace

HillaireSettings GlHillaireSettings(const CommonOptions& common) {
  return HillaireSettings::FromOptions(DeterministicModelOptions(common));
}

ElekSettings GlElekSettings(const CommonOptions& common) {
  return ElekSettings::FromOptions(DeterministicModelOptions(common));
}

Source4dModelSettings GlSource4dSettings(const CommonOptions& common) {
  return Source4dModelSettings::FromOptions(DeterministicModelOptions(common));
}

bool Source4dTablesFromCpu(const CommonOptions& common, const gl::Context& context) {
  if (common.source4d_tables == "auto") return context.software_renderer();
  return common.source4d_tables == "cpu";
}

namespace {

// source4d with the CPU's tables (Precompute: computed, or read from the table cache or the shipped
// tables), kept while the atmosphere and options stay the same: a time-lapse's frames and a
// moonlit frame reuse it.
const Source4dModel& CpuSource4dModel(const CommonOptions& common, const AtmosphereParameters& parameters) {
  static std::string key;
  static std::unique_ptr<Source4dModel> model;
  std::string next = ToJson(parameters);
  for (const std::string& option : common.options) next += '\n' + option;
  if (model == nullptr || next != key) {
    model = std::make_unique<Source4dModel>(parameters, GlSource4dSettings(common));
    model->Precompute();
    key = std::move(next);
  }
  return *model;
}

}  // namespace

Image RenderOnGl(const gl::Context& context, const CommonOptions& common, const AtmosphereParameters& parameters,
                 const RenderSettings& settings, PassTimings* timings, bool gpu_tables) {
  if (common.model == "elek") return gl::RenderElekGl(context, parameters, GlElekSettings(common), settings, timings);
  if (common.model == "source4d") {
    if (!gpu_tables && Source4dTablesFromCpu(common, context)) {
      return gl::RenderSource4dGl(context, CpuSource4dModel(common, parameters), settings, timings);
    }
    // The tables and the frame on the GPU (on a software GL the quadrature matrices on the CPU,
    // their time as cpu_NAME).
    return gl::RenderSource4dGl(context, parameters, GlSource4dSettings(common), settings, timings);
  }
  return gl::RenderHillaireGl(context, parameters, GlHillaireSettings(common), settings, timings);
}
#endif

TableCache TableCacheFor(const CommonOptions& common) {
  TableCache cache = DefaultTableCache();
  if (common.table_cache == "off") {
    cache.folder.clear();
  } else if (!common.table_cache.empty()) {
    std::error_code ec;
    if (std::filesystem::exists(common.table_cache, ec) && !std::filesystem::is_directory(common.table_cache, ec)) {
      throw Error("--table-cache '" + common.table_cache + "' is not a folder");
    }
    cache.folder = common.table_cache;
  }
  return cache;
}

std::unique_ptr<Model> CreateModelFor(const CommonOptions& common, const AtmosphereParameters& parameters) {
#ifdef ATMO_HAVE_GL
  if (common.backend == "gl" && common.model == "elek") {
    // The table computed on the GPU and read back: the model answers from it on the CPU.
    auto model = std::make_unique<ElekModel>(parameters, GlElekSettings(common));
    const gl::Context context;
    gl::PrecomputeElekGl(context, *model);
    return model;
  }
  if (common.backend == "gl" && common.model == "source4d") {
    // The tables computed on the GPU and read back, as for elek; or the CPU's.
    auto model = std::make_unique<Source4dModel>(
        parameters, Source4dModelSettings::FromOptions(DeterministicModelOptions(common)));
    const gl::Context context;
    if (Source4dTablesFromCpu(common, context)) {
      model->Precompute();
    } else {
      gl::PrecomputeSource4dGl(context, *model);
    }
    return model;
  }
  if (common.backend == "gl") throw Error("model " + common.model + " has no CPU model with GL tables; use --backend cpu");
#endif
  // --seed travels as the "seed" option that every model accepts (deterministic ones ignore it).
  ModelOptions options = ParseModelOptions(common.options);
  if (common.seed_given) {
    if (options.count("seed") != 0) throw Error("give the seed once: --seed or --option seed=N");
    options["seed"] = std::to_string(common.seed);
  }
  return CreateModel(common.model, parameters, options);
}

std::optional<std::uint64_t> ParseSeed(const std::string& text) {
  if (text.empty() || text.size() > 20 || text.find_first_not_of("0123456789") != std::string::npos) return {};
  std::uint64_t value = 0;
  const auto [end, error] = std::from_chars(text.data(), text.data() + text.size(), value);
  if (error != std::errc() || end != text.data() + text.size()) return {};  // above 2^64 - 1
  return value;
}

namespace {

// Whether two paths name one file: by identity when both exist (hard and symbolic links, "./x"),
// else by their normalised absolute form.
bool SameFile(const fs::path& a, const fs::path& b) {
  std::error_code ec;
  if (fs::exists(a, ec) && fs::exists(b, ec)) return fs::equivalent(a, b, ec);
  const fs::path ca = fs::weakly_canonical(fs::absolute(a, ec), ec);
  const fs::path cb = fs::weakly_canonical(fs::absolute(b, ec), ec);
  return ca == cb;
}

}  // namespace

void CheckOutputsApart(const CommonOptions& common, std::vector<NamedPath> inputs,
                       const std::vector<NamedPath>& outputs) {
  if (!common.config.empty()) inputs.push_back({"--config", common.config});
  for (const std::string& option : common.options) {
    if (option.rfind("table=", 0) != 0) continue;
    const std::string name = option.substr(6);
    for (const char* extension : {".exr", ".raw", ".json"}) inputs.push_back({"--table", name + extension});
  }
  for (std::size_t i = 0; i < outputs.size(); ++i) {
    const NamedPath& out = outputs[i];
    if (out.path.empty()) continue;
    for (const NamedPath& in : inputs) {
      if (!in.path.empty() && SameFile(out.path, in.path)) {
        throw Error(out.flag + " '" + out.path.string() + "' is the " + in.flag + " input '" + in.path.string() +
                    "'; write the output elsewhere");
      }
    }
    for (std::size_t j = 0; j < i; ++j) {
      if (!outputs[j].path.empty() && SameFile(out.path, outputs[j].path)) {
        throw Error(outputs[j].flag + " and " + out.flag + " name the same file '" + out.path.string() + "'");
      }
    }
  }
}

void CheckExtension(const std::string& flag, const fs::path& path, const std::string& extension) {
  if (path.empty()) return;
  std::string actual = path.extension().string();
  for (char& c : actual) c = static_cast<char>(std::tolower(static_cast<unsigned char>(c)));
  if (actual != extension) {
    throw Error(flag + " '" + path.string() + "' must end in " + extension + " (it is written as " +
                extension.substr(1) + ")");
  }
}

void CheckOutputWritable(const fs::path& path) {
  fs::path folder = path.parent_path();
  if (folder.empty()) folder = ".";
  std::error_code error;
  const std::string prefix = "cannot write '" + path.string() + "': ";
  if (!fs::is_directory(folder, error)) {
    throw Error(prefix + "folder '" + folder.string() + "' does not exist");
  }
  if (::access(folder.c_str(), W_OK | X_OK) != 0) {
    throw Error(prefix + "folder '" + folder.string() + "' is not writable");
  }
  if (fs::is_directory(path, error)) throw Error(prefix + "it is a folder");
  // Where it exists (through links), a regular file: WriteFileAtomically would refuse a device,
  // FIFO or socket at the end; refused here before any work.
  const fs::file_status status = fs::status(path, error);
  if (fs::exists(status) && !fs::is_regular_file(status)) {
    throw Error(prefix + "it is not a regular file (a device, FIFO or socket); atmo writes only regular files");
  }
  if (fs::is_symlink(fs::symlink_status(path, error)) && !fs::exists(status)) {
    throw Error(prefix + "it is a symbolic link to a missing file");
  }
}

std::string Format(const char* format, ...) {
  va_list args;
  va_start(args, format);
  va_list copy;
  va_copy(copy, args);
  const int size = std::vsnprintf(nullptr, 0, format, copy);
  va_end(copy);
  std::string text(size > 0 ? static_cast<std::size_t>(size) : 0, '\0');
  if (size > 0) std::vsnprintf(text.data(), text.size() + 1, format, args);
  va_end(args);
  return text;
}

}  // namespace atmo::cli
