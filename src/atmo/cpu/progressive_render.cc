// Progressive Monte Carlo rendering (atmo/render.h): per-pixel sums of path values and of their
// squares, refined in passes that double the path count; rows in parallel with oneTBB.
//
// Determinism: pixel (x, y) traces paths [n_k, n_{k+1}) of its own query in pass k on one thread
// (ReferenceSkyView::AddPaths: the path streams depend on the seed, the view direction and the
// path index only) and adds them to its sums in pass order, so neither the thread count nor the
// scheduling changes a bit of the result.
#include <algorithm>
#include <atomic>
#include <cmath>
#include <functional>
#include <mutex>
#include <optional>
#include <string>
#include <vector>

#include <oneapi/tbb/blocked_range.h>
#include <oneapi/tbb/parallel_for.h>

#include "atmo/error.h"
#include "atmo/moon.h"
#include "atmo/night_sky.h"
#include "atmo/render.h"
#include "cpu/camera.h"
#include "cpu/path_tracer.h"
#include "cpu/sun_disc.h"
#include "models/reference_model.h"

namespace atmo {
namespace {

// The view direction of every pixel, row by row (0 outside a fisheye's circle), and the coverage.
std::vector<glm::dvec3> PixelDirections(const Camera& camera_settings, std::vector<float>& alpha) {
  const shared::CameraParameters camera = ToSharedCamera(camera_settings);
  const int width = camera_settings.width;
  const std::size_t pixel_count = static_cast<std::size_t>(width) * camera_settings.height;
  std::vector<glm::dvec3> views(pixel_count, glm::dvec3(0.0));
  if (camera_settings.kind == CameraKind::kFisheye) alpha.assign(pixel_count, 0.0f);
  for (int y = 0; y < camera_settings.height; ++y) {
    const std::span<glm::dvec3> row(&views[static_cast<std::size_t>(y) * width], static_cast<std::size_t>(width));
    if (camera.kind == shared::kCameraPerspective) {
      PerspectiveRowDirections(camera, y, row);
      continue;
    }
    for (int x = 0; x < width; ++x) {
      shared::vec3 direction;
      const bool seen = shared::GetCameraRayDirection(camera, shared::vec2(x + 0.5, y + 0.5), direction);
      row[x] = seen ? direction : glm::dvec3(0.0);
      if (!alpha.empty()) alpha[static_cast<std::size_t>(y) * width + x] = seen ? 1.0f : 0.0f;
    }
  }
  return views;
}

bool IsZero(const glm::dvec3& v) { return v.x == 0.0 && v.y == 0.0 && v.z == 0.0; }

}  // namespace

bool IsMonteCarlo(const Model& model) { return dynamic_cast<const ReferenceModel*>(&model) != nullptr; }

ProgressiveImage RenderProgressive(const Model& model, const RenderSettings& settings,
                                   const ProgressiveSettings& progressive) {
  const auto* reference = dynamic_cast<const ReferenceModel*>(&model);
  if (reference == nullptr) {
    throw Error("model " + std::string(model.name()) + " is deterministic: progressive rendering needs a Monte "
                "Carlo model (reference)");
  }
  ValidateCamera(settings.camera);
  for (double value : {settings.altitude_m, settings.sun_elevation_deg, settings.sun_azimuth_deg}) {
    if (!std::isfinite(value)) throw Error("altitude and sun angles must be finite");
  }
  const std::size_t nc = model.channel_count();  // channels (wavelengths)
  const std::uint64_t total =
      progressive.samples_per_pixel == 0 ? reference->settings().samples : progressive.samples_per_pixel;
  if (total < 2 || progressive.first_pass_samples < 2) {
    throw Error("progressive rendering needs at least 2 samples per pixel and per pass (a standard error needs two "
                "paths)");
  }

  const std::unique_ptr<SkyView> view =
      model.View(settings.altitude_m, SunDirection(settings.sun_elevation_deg, settings.sun_azimuth_deg));
  const auto& sky = static_cast<const ReferenceSkyView&>(*view);
  const int width = settings.camera.width;
  const int height = settings.camera.height;
  std::vector<float> alpha;
  const std::vector<glm::dvec3> views = PixelDirections(settings.camera, alpha);
  const std::size_t pixel_count = views.size();
  const std::vector<double>& irradiance = model.parameters().solar_irradiance;

  // The sun disc is deterministic: integrated over the pixels once (cpu/sun_disc.h), in the
  // image's unit (times the solar irradiance).
  Image disc(width, height, static_cast<int>(nc));
  if (settings.terms.sun_disc) AddSunDisc(sky, settings.camera, irradiance, disc);
  // The night sky's direct light and its stars, deterministic like the disc (include/atmo/night_sky.h).
  if (settings.terms.night_sky != nullptr) {
    if (settings.terms.night_sky->channel_count() != nc) throw Error("the night sky's channels do not match the sky's");
    const NightSky::Folded night = settings.terms.night_sky->Scaled(irradiance);
    night.Add(views, disc.pixels);
    disc.alpha = alpha;  // AddStars leaves out the pixels a fisheye does not see
    AddStars(night, settings.camera, disc);
    disc.alpha.clear();
  }
  // The moon: its light is traced as the sun's, by the same tracer for a sun in the moon's
  // direction (terms.moon_sky, a view of this model), its own paths (path indices from
  // kMoonPaths on, so that they are independent of the sun's), times the moon's irradiance
  // relative to the sun's; its standard error adds to the sun's in quadrature. Its disc, like the
  // sun's, is integrated over the pixels.
  const ReferenceSkyView* moon_sky = nullptr;
  std::vector<double> moon_scale(nc, 0.0);
  if ((settings.terms.moon == nullptr) != (settings.terms.moon_sky == nullptr)) {
    throw Error("the moon needs both its Moon and its view");
  }
  if (settings.terms.moon != nullptr) {
    moon_sky = dynamic_cast<const ReferenceSkyView*>(settings.terms.moon_sky);
    if (moon_sky == nullptr || moon_sky->channel_count() != nc || settings.terms.moon->relative_irradiance().size() != nc) {
      throw Error("the moon of a progressive render needs a view of the same reference model");
    }
    for (std::size_t c = 0; c < nc; ++c) moon_scale[c] = settings.terms.moon->relative_irradiance()[c] * irradiance[c];
    if (settings.terms.sun_disc) AddMoonDisc(settings.terms, settings.camera, {}, irradiance, disc);
  }
  constexpr std::uint64_t kMoonPaths = std::uint64_t{1} << 62;
  // The night glow's diffuse light: paths of their own (from kGlowPaths on) that score the
  // airglow shell's light scattered once or more (cpu::TraceQuery::glow; its direct light is the
  // night sky's deterministic term above). Traced while the sun is below the horizon: above it
  // the glow is less than 1e-6 of the sky (docs/night.md).
  constexpr std::uint64_t kGlowPaths = (std::uint64_t{1} << 62) + (std::uint64_t{1} << 61);
  std::optional<cpu::GlowSource> glow;
  if (settings.terms.night_sky != nullptr && settings.terms.night_sky->glow() && settings.sun_elevation_deg < 0.0) {
    const NightSkySettings& shell = model.parameters().night_sky;
    const double r = model.parameters().ground_radius_m;
    glow.emplace();
    glow->inner_radius = r + shell.airglow_altitude_m - 0.5 * shell.airglow_thickness_m;
    glow->outer_radius = r + shell.airglow_altitude_m + 0.5 * shell.airglow_thickness_m;
    for (double zenith : settings.terms.night_sky->airglow_zenith()) {
      glow->emission.push_back(zenith / shell.airglow_thickness_m);
    }
  }

  // The lights traced per pixel, each with paths of its own: the sun, then the moon and the glow
  // when there. Their means add, and so do their variances (independent paths).
  struct TracedLight {
    std::function<void(const glm::dvec3& view, std::uint64_t first, std::uint64_t count, cpu::PathTally& tally)> add;
    std::vector<double> scale;  // per channel: the estimate's factor in the image
    std::vector<double> sum, sum_sq;
  };
  std::vector<TracedLight> lights;
  const bool ground = settings.terms.ground;
  lights.push_back({[&](const glm::dvec3& v, std::uint64_t first, std::uint64_t count, cpu::PathTally& t) {
                      sky.AddPaths(v, ground, first, count, t);
                    },
                    irradiance, {}, {}});
  if (moon_sky != nullptr) {
    lights.push_back({[&](const glm::dvec3& v, std::uint64_t first, std::uint64_t count, cpu::PathTally& t) {
                        moon_sky->AddPaths(v, ground, kMoonPaths + first, count, t);
                      },
                      moon_scale, {}, {}});
  }
  if (glow) {
    lights.push_back({[&](const glm::dvec3& v, std::uint64_t first, std::uint64_t count, cpu::PathTally& t) {
                        sky.AddGlowPaths(v, ground, *glow, kGlowPaths + first, count, t);
                      },
                      irradiance, {}, {}});
  }
  for (TracedLight& light : lights) {
    light.sum.assign(pixel_count * nc, 0.0);
    light.sum_sq.assign(pixel_count * nc, 0.0);
  }
  const double paths_in_all = static_cast<double>(total) * static_cast<double>(pixel_count) * lights.size();
  std::atomic<std::uint64_t> rows_done{0};  // rows of all passes, times their path count
  std::mutex progress_mutex;

  ProgressiveImage result;
  std::uint64_t done = 0;
  std::uint64_t next = std::min(total, progressive.first_pass_samples);
  while (done < total) {
    const std::uint64_t count = next - done;
    const auto trace_rows = [&](const oneapi::tbb::blocked_range<int>& rows) {
      cpu::PathTally tally(nc);
      for (int y = rows.begin(); y < rows.end(); ++y) {
        if (progressive.cancel != nullptr && progressive.cancel->load(std::memory_order_relaxed)) return;
        for (int x = 0; x < width; ++x) {
          const std::size_t i = static_cast<std::size_t>(y) * width + x;
          if (IsZero(views[i])) continue;
          for (TracedLight& light : lights) {
            tally.Reset();
            light.add(views[i], done, count, tally);
            for (std::size_t c = 0; c < nc; ++c) {
              light.sum[nc * i + c] += tally.sum[c * cpu::kTallySlots];
              light.sum_sq[nc * i + c] += tally.sum_sq[c * cpu::kTallySlots];
            }
          }
        }
        const std::uint64_t paths = lights.size() * count;
        const std::uint64_t paths_done = rows_done.fetch_add(paths) + paths;
        if (progressive.on_progress && progress_mutex.try_lock()) {
          progressive.on_progress(static_cast<double>(paths_done) * width, paths_in_all);
          progress_mutex.unlock();
        }
      }
    };
    oneapi::tbb::parallel_for(oneapi::tbb::blocked_range<int>(0, height), trace_rows);
    if (progressive.cancel != nullptr && progressive.cancel->load()) return result;  // the last complete pass
    done = next;
    next = std::min(total, 2 * next);

    // The estimate so far: mean and standard error of the mean (sample variance / n).
    result.radiance = Image(width, height, static_cast<int>(nc));
    result.radiance.alpha = alpha;
    result.standard_error = Image(width, height, static_cast<int>(nc));
    result.samples_per_pixel = done;
    ++result.pass;
    const double n = static_cast<double>(done);
    for (std::size_t i = 0; i < pixel_count; ++i) {
      for (std::size_t c = 0; c < nc; ++c) {
        double radiance = 0.0;
        double error_sq = 0.0;
        for (const TracedLight& light : lights) {
          const double mean = light.sum[nc * i + c] / n;
          const double variance = std::max(0.0, (light.sum_sq[nc * i + c] - n * mean * mean) / (n - 1.0));
          radiance += mean * light.scale[c];
          error_sq += variance / n * light.scale[c] * light.scale[c];
        }
        result.radiance.pixels[nc * i + c] = static_cast<float>(radiance + disc.pixels[nc * i + c]);
        result.standard_error.pixels[nc * i + c] = static_cast<float>(std::sqrt(error_sq));
      }
    }
    if (progressive.on_pass) progressive.on_pass(result);
  }
  return result;
}

Image WithStandardErrorChannels(const ProgressiveImage& image) {
  const Image& radiance = image.radiance;
  const std::size_t nc = static_cast<std::size_t>(radiance.channels);
  Image out(radiance.width, radiance.height, static_cast<int>(2 * nc));
  // R, G, B for three channels (or the image's own names), C0..Cn-1 otherwise; then the layer
  // "stderr" of the same names (OpenEXR's LAYER.NAME): stderr.R, stderr.G, stderr.B.
  std::vector<std::string> names = radiance.channel_names;
  if (names.empty()) {
    for (std::size_t c = 0; c < nc; ++c) {
      std::string name(1, nc == 3 ? "RGB"[c] : 'C');
      if (nc != 3) name += std::to_string(c);
      names.push_back(std::move(name));
    }
  }
  for (std::size_t c = 0; c < nc; ++c) names.push_back("stderr." + names[c]);
  out.channel_names = names;
  out.alpha = radiance.alpha;
  const std::size_t pixel_count = static_cast<std::size_t>(radiance.width) * radiance.height;
  for (std::size_t i = 0; i < pixel_count; ++i) {
    for (std::size_t c = 0; c < nc; ++c) {
      out.pixels[2 * nc * i + c] = radiance.pixels[nc * i + c];
      out.pixels[2 * nc * i + nc + c] = image.standard_error.pixels[nc * i + c];
    }
  }
  return out;
}

}  // namespace atmo
