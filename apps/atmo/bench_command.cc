// `atmo bench`: times the model's precomputation passes and one frame, repeated, on the CPU or (models
// hillaire, elek and source4d, --backend gl) on the GL backend, where every pass is the GPU time of its
// dispatch (with more than 3 channels, of its dispatches: one per batch of three channels, summed);
// source4d's transmittance table and quadrature matrices are computed on the CPU there, their
// times named cpu_NAME.
//
// Each repeat runs model->Precompute(), builds the view for a sun at 30 degrees elevation, and
// renders a perspective frame towards the sun. Per pass it reports the median, min and max over the
// repeats of the pass's time in that repeat (summed over the batches of three channels), plus
// "all_luts" (the sum of the model's "*_lut" passes of a repeat), "all_tables" (every pass of the
// repeat but the frame: the whole cost of the tables) and "frame_WxH" (the Render call, timed
// here, into a buffer reused across repeats). On the CPU also
// "colour_frame_WxH": the frame folded into linear sRGB while it is rendered (RenderViewFolded),
// what `atmo render` does in its default unit; for a spectral atmosphere it costs about what a
// 3-channel frame does, where frame_WxH renders every wavelength.
// With --date (sun_options.h) the sun is that of the date and place instead.
#include <algorithm>
#include <chrono>
#include <cstdio>
#include <functional>
#include <map>
#include <optional>

#include <oneapi/tbb/global_control.h>
#include <oneapi/tbb/task_arena.h>

#include "atmo/colour.h"
#include "atmo/error.h"
#include "atmo/render.h"
#include "commands.h"
#ifdef ATMO_HAVE_GL
#include "cpu/camera.h"
#include "gl/context.h"
#include "gl/hillaire_gl.h"
#include "gl/resources.h"
#endif

namespace atmo::cli {

namespace {

// Named samples in order of first appearance.
class PassSamples {
 public:
  void Add(const std::string& name, double ms) {
    auto found = std::find_if(passes_.begin(), passes_.end(), [&](const auto& p) { return p.first == name; });
    if (found == passes_.end()) found = passes_.insert(passes_.end(), {name, {}});
    found->second.push_back(ms);
  }
  const std::vector<std::pair<std::string, std::vector<double>>>& passes() const { return passes_; }

 private:
  std::vector<std::pair<std::string, std::vector<double>>> passes_;
};

double Median(std::vector<double> values) {
  std::sort(values.begin(), values.end());
  const std::size_t n = values.size();
  return n % 2 == 1 ? values[n / 2] : 0.5 * (values[n / 2 - 1] + values[n / 2]);
}

bool EndsWith(const std::string& text, const std::string& suffix) {
  return text.size() >= suffix.size() &&
         text.compare(text.size() - suffix.size(), suffix.size(), suffix) == 0;
}

}  // namespace

int RunBench(const CommonOptions& common, const BenchCommand& command) {
  CheckBackend(common, /*command_has_gl=*/true);
  const AtmosphereParameters parameters = LoadParameters(common);
  const int repeat = command.quick ? 3 : command.repeat;

  RenderSettings settings;
  settings.camera.kind = CameraKind::kPerspective;
  settings.camera.width = command.width;
  settings.camera.height = command.height;
  settings.camera.fov_deg = 90.0;
  settings.camera.yaw_deg = 180.0;
  settings.camera.pitch_deg = 10.0;
  settings.altitude_m = parameters.observer_altitude_m;
  settings.sun_elevation_deg = 30.0;
  settings.sun_azimuth_deg = 180.0;
  // --date: the sun of that instant and place (sun_options.h), the camera towards it.
  if (HasDate(command.sun)) {
    const SunAtInstant sun = SunAtDate(command.sun);
    settings.sun_elevation_deg = sun.position.elevation_deg;
    settings.sun_azimuth_deg = sun.position.azimuth_deg;
    settings.camera.yaw_deg = settings.sun_azimuth_deg;
  }

  const std::string frame_name = Format("frame_%dx%d", command.width, command.height);
  PassSamples samples;
  std::string model_name = common.model;
  std::string device;  // the GL renderer and version
  if (common.backend == "gl") {
#ifdef ATMO_HAVE_GL
    // One context and one set of GPU tables for all repeats. A first, unreported run compiles the
    // programs (and lets the driver finish compiling them at their first dispatch); each repeat
    // then runs every pass, and each pass's time is the GPU's (GpuPassTimer), without read-backs.
    gl::Context context;
    if (command.work_group_forms != "auto") context.set_work_group_forms(command.work_group_forms == "on");
    const shared::CameraParameters camera = ToSharedCamera(settings.camera);
    const glm::dvec3 sun = SunDirection(settings.sun_elevation_deg, settings.sun_azimuth_deg);
    std::function<void(PassTimings*)> run;
    std::unique_ptr<gl::HillaireGl> sky;
    if (common.model == "elek" || common.model == "source4d") {
      // The table's passes then the frame; the textures are made anew each repeat.
      // source4d's tables built on the GPU whatever --source4d-tables says: this times the GL path.
      run = [&](PassTimings* timings) {
        RenderOnGl(context, common, parameters, settings, timings, /*gpu_tables=*/true);
      };
    } else {
      sky = std::make_unique<gl::HillaireGl>(context, parameters, GlHillaireSettings(common));
      run = [&](PassTimings* timings) {
        // Besides each pass: the GPU's span from the first table's start to the last one's end
        // (span_tables: the passes' sum plus the gaps between them, where the GPU waited for
        // commands) and the CPU's time to issue them (submit_tables).
        std::optional<gl::GpuPassTimer> span;
        if (timings != nullptr) span.emplace(timings);
        const auto submit = std::chrono::steady_clock::now();
        sky->Precompute(timings);
        sky->SetView(settings.altitude_m, sun, settings.terms.ground, timings);
        if (timings != nullptr) {
          timings->Add("submit_tables", std::chrono::duration<double, std::milli>(
                                            std::chrono::steady_clock::now() - submit).count());
          span->Stop("span_tables");
        }
        sky->RenderFrame(camera, settings.terms, timings);
      };
    }
    run(nullptr);
    if (!context.software_renderer()) {
      // A GPU idles at a low clock (an H200: 345 MHz of its 1980) and raises it only under load:
      // the passes run untimed for half a second first, so that the repeats see the clock a
      // frame loop would.
      const auto start = std::chrono::steady_clock::now();
      while (std::chrono::steady_clock::now() - start < std::chrono::milliseconds(500)) {
        run(nullptr);
        context.Finish();
      }
    }
    for (int r = 0; r < repeat; ++r) {
      PassTimings timings;
      run(&timings);
      double all_luts_ms = 0.0;
      double all_tables_ms = 0.0;
      // A pass runs once per batch of three channels (a spectral atmosphere has several): its
      // time in this repeat is the sum over the batches (total_ms; `timings` is this repeat's).
      for (const PassTiming& pass : timings.entries()) {
        samples.Add(pass.name, pass.total_ms);
        if (pass.name.rfind("span_", 0) == 0 || pass.name.rfind("submit_", 0) == 0) continue;  // not passes
        // source4d's CPU parts (cpu_NAME) are not GPU passes.
        if (EndsWith(pass.name, "_lut") && pass.name.rfind("cpu_", 0) != 0) all_luts_ms += pass.total_ms;
        // Every pass but the frame's: the tables' whole cost, CPU parts included.
        if (pass.name.rfind("frame", 0) != 0) all_tables_ms += pass.total_ms;
      }
      samples.Add("all_luts", all_luts_ms);
      samples.Add("all_tables", all_tables_ms);
    }
    device = context.renderer() + ", " + context.version() +
             (context.work_group_forms() ? ", work-group forms" : ", a texel per invocation");
#endif
  } else {
    const std::unique_ptr<Model> model = CreateModelFor(common, parameters);
    model_name = std::string(model->name());
    const std::string colour_frame_name = "colour_" + frame_name;
    const std::vector<glm::vec3> srgb_weights =
        ColourWeights(SpectralConversion(parameters.wavelengths_nm), ImageColour::kLinearSrgb);
    // The frames' buffers, reused across repeats as an engine reuses its render target: a fresh
    // 25 MB image per frame spent most of a 1080p frame in page faults and zero-filling.
    Image image;
    Image colour;
    for (int r = 0; r < repeat; ++r) {
      // Passes run during this repeat are those whose call count grows; their time in it is the
      // growth of their total (a pass runs once per batch of three channels).
      std::map<std::string, PassTiming> before;
      for (const PassTiming& pass : model->timings().entries()) before[pass.name] = pass;

      model->Precompute();
      const std::unique_ptr<SkyView> sky = model->View(settings.altitude_m, SunDirection(settings.sun_elevation_deg, settings.sun_azimuth_deg));
      const auto start = std::chrono::steady_clock::now();
      RenderView(*sky, settings.camera, settings.terms, parameters.solar_irradiance, image);
      const double frame_ms =
          std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - start).count();
      const auto colour_start = std::chrono::steady_clock::now();
      RenderViewFolded(*sky, settings.camera, settings.terms, srgb_weights, colour);
      const double colour_frame_ms =
          std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - colour_start).count();

      double all_luts_ms = 0.0;
      double all_tables_ms = 0.0;
      for (const PassTiming& pass : model->timings().entries()) {
        const auto found = before.find(pass.name);
        const int calls = pass.calls - (found != before.end() ? found->second.calls : 0);
        if (calls == 0) continue;
        const double ms = pass.total_ms - (found != before.end() ? found->second.total_ms : 0.0);
        samples.Add(pass.name, ms);
        if (EndsWith(pass.name, "_lut")) all_luts_ms += ms;
        all_tables_ms += ms;
      }
      samples.Add("all_luts", all_luts_ms);
      samples.Add("all_tables", all_tables_ms);
      samples.Add(frame_name, frame_ms);
      samples.Add(colour_frame_name, colour_frame_ms);
    }
  }

  // The parallelism oneTBB uses: the --threads limit, at most the arena's concurrency.
  const std::size_t threads = std::min<std::size_t>(
      oneapi::tbb::global_control::active_value(oneapi::tbb::global_control::max_allowed_parallelism),
      static_cast<std::size_t>(oneapi::tbb::this_task_arena::max_concurrency()));
  std::printf("atmo bench: model %s, backend %s, preset %s, threads %zu, repeats %d, frame %dx%d\n",
              model_name.c_str(), common.backend.c_str(), parameters.name.c_str(), threads, repeat, command.width,
              command.height);
  if (!device.empty()) std::printf("gl device: %s\n", device.c_str());
  if (HasDate(command.sun)) {
    std::printf("sun: elevation %.4f deg, azimuth %.4f deg (--date %s)\n", settings.sun_elevation_deg,
                settings.sun_azimuth_deg, command.sun.date.c_str());
  }
  std::size_t width = 4;
  for (const auto& [name, values] : samples.passes()) width = std::max(width, name.size());
  std::printf("%-*s  %10s  %10s  %10s\n", static_cast<int>(width), "pass", "median_ms", "min_ms", "max_ms");
  for (const auto& [name, values] : samples.passes()) {
    std::printf("%-*s  %10.3f  %10.3f  %10.3f\n", static_cast<int>(width), name.c_str(), Median(values),
                *std::min_element(values.begin(), values.end()),
                *std::max_element(values.begin(), values.end()));
  }
  return 0;
}

}  // namespace atmo::cli
