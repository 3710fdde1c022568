// `atmo render`: one frame of a model through a camera, written as EXR (linear, with metadata)
// and PNG (tone-mapped).
//
// A Monte Carlo model (reference) renders progressively (RenderProgressive): --spp paths per
// pixel in passes of 4, 8, 16, ... paths, with a progress bar on stderr when it is a terminal;
// the outputs are rewritten (atomically) after every pass, so they always hold the latest pass,
// and the EXR has the per-pixel standard errors as channels R.stderr, G.stderr, B.stderr.
#include <chrono>
#include <cmath>
#include <cstdio>
#include <numbers>

#include "atmo/error.h"
#include "atmo/image.h"
#include "atmo/render.h"
#include "commands.h"
#include "progress_bar.h"

namespace atmo::cli {

namespace {

// "v0, v1, v2" with %.10g per value.
std::string JoinValues(const std::vector<double>& values) {
  std::string text;
  for (std::size_t i = 0; i < values.size(); ++i) {
    if (i > 0) text += ", ";
    text += Format("%.10g", values[i]);
  }
  return text;
}

std::string JoinOptions(const std::vector<std::string>& options) {
  std::string text;
  for (const std::string& option : options) text += (text.empty() ? "" : " ") + option;
  return text;
}

}  // namespace

int RunRender(const CommonOptions& common, const RenderCommand& command) {
  CheckBackend(common, /*command_has_gl=*/true);
  const bool on_gl = common.backend == "gl";
  AtmosphereParameters parameters = LoadParameters(common);
  if (command.sun_size_deg) {
    const double d = *command.sun_size_deg;
    if (!(d > 0.0 && d <= 20.0)) throw Error("--sun-size must be in (0, 20] degrees (got " + Format("%g", d) + ")");
    parameters.sun_angular_radius_rad = 0.5 * d * std::numbers::pi / 180.0;
  }

  RenderSettings settings;
  settings.camera.kind = ParseCameraKind(command.camera);
  settings.camera.width = command.width;
  settings.camera.height = command.height;
  settings.camera.fov_deg = command.fov_deg;
  // Perspective and equirect views centre on the sun by default; the all-sky fisheye keeps north up.
  settings.camera.yaw_deg =
      command.yaw_deg.value_or(settings.camera.kind == CameraKind::kFisheye ? 0.0 : command.sun_azimuth_deg);
  settings.camera.pitch_deg = command.pitch_deg;
  settings.altitude_m = command.altitude_m.value_or(parameters.observer_altitude_m);
  settings.sun_elevation_deg = command.sun_elevation_deg;
  settings.sun_azimuth_deg = command.sun_azimuth_deg;
  settings.terms.sun_disc = !command.no_sun_disc;
  settings.terms.ground = !command.no_ground;
  if (!std::isfinite(settings.altitude_m)) throw Error("--altitude must be a finite number");

  ToneMapping mapping;
  mapping.op = ParseToneMapper(command.tonemap);
  mapping.exposure = command.exposure.value_or(parameters.exposure);
  mapping.gamma = command.gamma;

  // Fail fast, before precomputing anything, when an output cannot be written.
  if (!command.exr_path.empty()) CheckOutputWritable(command.exr_path);
  if (!command.png_path.empty()) CheckOutputWritable(command.png_path);

  // --spp is the path count of a Monte Carlo model; deterministic models have nothing to sample.
  if (command.spp && common.model != "reference") {
    throw Error("--spp is the number of Monte Carlo paths per pixel of model reference; model '" + common.model +
                "' is deterministic and takes no --spp");
  }
  // On the gl backend the GL passes compute the tables and the frame (RenderOnGl); no CPU model is made.
  const std::unique_ptr<Model> model = on_gl ? nullptr : CreateModelFor(common, parameters);
  const std::string model_name = model != nullptr ? std::string(model->name()) : common.model;

  const auto start = std::chrono::steady_clock::now();
  const auto elapsed_ms = [&] {
    return std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - start).count();
  };
  ImageMetadata metadata = {
      {"atmo:version", ATMO_VERSION},
      {"atmo:model", model_name},
      {"atmo:backend", common.backend},
      {"atmo:preset", parameters.name},
      {"atmo:parameterHash", ParameterHashHex(parameters)},
      {"atmo:radianceUnit", "sr^-1 per unit solar irradiance, times solar_irradiance (" +
                                JoinValues(parameters.solar_irradiance) + ")"},
      {"atmo:renderTimeMs", ""},
      {"atmo:camera", std::string(ToString(settings.camera.kind))},
      {"atmo:sunElevationDeg", Format("%.10g", settings.sun_elevation_deg)},
      {"atmo:sunAzimuthDeg", Format("%.10g", settings.sun_azimuth_deg)},
      {"atmo:altitudeM", Format("%.10g", settings.altitude_m)},
      {"atmo:wavelengthsNm", JoinValues(parameters.wavelengths_nm)},
      {"atmo:cameraFovDeg", Format("%.10g", settings.camera.fov_deg)},
      {"atmo:cameraYawDeg", Format("%.10g", settings.camera.yaw_deg)},
      {"atmo:cameraPitchDeg", Format("%.10g", settings.camera.pitch_deg)},
      {"atmo:terms", std::string(settings.terms.sun_disc ? "sun_disc " : "") + (settings.terms.ground ? "ground" : "")},
      {"atmo:sunAngularDiameterDeg", Format("%.10g", 2.0 * parameters.sun_angular_radius_rad * 180.0 / std::numbers::pi)},
      {"atmo:modelOptions", JoinOptions(common.options)},
  };
  const auto set_metadata = [&](const std::string& key, const std::string& value) {
    for (auto& entry : metadata) {
      if (entry.first == key) {
        entry.second = value;
        return;
      }
    }
    metadata.emplace_back(key, value);
  };
  // Writes the outputs asked for; `exr_image` may carry more channels than `image` (PNG).
  const auto write = [&](const Image& image, const Image& exr_image, double render_ms) {
    std::vector<std::string> written;
    if (!command.exr_path.empty()) {
      set_metadata("atmo:renderTimeMs", Format("%.3f", render_ms));
      WriteExr(command.exr_path, exr_image, metadata);
      written.push_back(command.exr_path);
    }
    if (!command.png_path.empty()) {
      WritePng(command.png_path, image, mapping);
      written.push_back(command.png_path);
    }
    return written;
  };

  std::vector<std::string> written;
  Image image;
  double render_ms = 0.0;
  if (model != nullptr && IsMonteCarlo(*model)) {
    ProgressiveSettings progressive;
    progressive.samples_per_pixel = command.spp.value_or(0);  // 0: the model's samples option
    set_metadata("atmo:standardErrorChannels", "R.stderr, G.stderr, B.stderr: standard error of R, G, B (same unit)");
    ProgressBar progress("render");
    progressive.on_progress = [&](double done, double total) { progress.Update(done, total); };
    progressive.on_pass = [&](const ProgressiveImage& pass) {
      set_metadata("atmo:samplesPerPixel", std::to_string(pass.samples_per_pixel));
      render_ms = elapsed_ms();
      written = write(pass.radiance, WithStandardErrorChannels(pass), render_ms);
    };
    image = RenderProgressive(*model, settings, progressive).radiance;
    progress.Finish();
  } else {
#ifdef ATMO_HAVE_GL
    if (on_gl) {
      const gl::Context context;
      image = RenderOnGl(context, common, parameters, settings);
    } else {
      image = Render(*model, settings);
    }
#else
    image = Render(*model, settings);
#endif
    render_ms = elapsed_ms();
    written = write(image, image, render_ms);
  }

  std::string files;
  for (const std::string& path : written) files += (files.empty() ? "" : ", ") + path;
  std::printf("%s %s (%dx%d %s, %s, %s) in %.1f ms\n", written.empty() ? "rendered" : "wrote",
              written.empty() ? "without writing a file" : files.c_str(), image.width, image.height,
              std::string(ToString(settings.camera.kind)).c_str(), model_name.c_str(),
              parameters.name.c_str(), render_ms);
  return 0;
}

}  // namespace atmo::cli
