// CPU rendering: camera rays from the shared camera kernel, radiance from the model, rows in
// parallel with oneTBB.
#include "atmo/render.h"

#include <array>
#include <atomic>
#include <cmath>
#include <mutex>
#include <optional>
#include <string>

#include <oneapi/tbb/blocked_range.h>
#include <oneapi/tbb/parallel_for.h>

#include "atmo/error.h"
#include "atmo/moon.h"
#include "atmo/night_sky.h"
#include "cpu/camera.h"
#include "cpu/sun_disc.h"

namespace atmo {
namespace {

void CheckFinite(double value, const char* name) {
  if (!std::isfinite(value)) throw Error(std::string(name) + " must be finite");
}

void CheckChannels(std::size_t channels) {
  if (channels == 0) throw Error("rendering an image needs at least one channel");
}

const NightSky& CheckedNightSky(const RadianceTerms& terms, std::size_t channels) {
  if (terms.night_sky->channel_count() != channels) {
    throw Error("the night sky has " + std::to_string(terms.night_sky->channel_count()) +
                " channels and the sky " + std::to_string(channels));
  }
  return *terms.night_sky;
}

void CheckMoon(const RadianceTerms& terms, std::size_t channels) {
  if ((terms.moon == nullptr) != (terms.moon_sky == nullptr)) throw Error("the moon needs both its Moon and its view");
  if (terms.moon != nullptr && (terms.moon->relative_irradiance().size() != channels ||
                                terms.moon_sky->channel_count() != channels)) {
    throw Error("the moon's channels do not match the sky's");
  }
}

// The terms of the moon's own view: its scattered light (and the moonlit ground), no sun disc.
RadianceTerms MoonSkyTerms(const RadianceTerms& terms) {
  RadianceTerms moon_terms;
  moon_terms.sun_disc = false;
  moon_terms.ground = terms.ground;
  return moon_terms;
}

}  // namespace

// The moon's disc through `camera`: the disc's radiance attenuated by the moon view's transmittance,
// folded by `fold` (channels -> outputs; identity when null) and times `scale` per output.
void AddMoonDisc(const RadianceTerms& terms, const Camera& camera, std::span<const glm::vec3> fold,
                 std::span<const double> scale, Image& image) {
  const Moon& moon = *terms.moon;
  const SkyView& moon_sky = *terms.moon_sky;
  const std::size_t n = moon_sky.channel_count();
  AddSunDisc(
      camera, moon.direction(), moon.angular_radius_rad(),
      [&](const glm::dvec3& view, std::span<double> out) {
        thread_local std::vector<double> disc, transmittance;
        disc.resize(n);
        transmittance.resize(n);
        moon.DiscRadiance(view, disc);
        bool lit = false;
        for (double d : disc) lit = lit || d > 0.0;
        if (lit) moon_sky.Transmittance(view, transmittance);
        for (std::size_t c = 0; c < n; ++c) disc[c] = lit ? disc[c] * transmittance[c] : 0.0;
        if (fold.empty()) {
          for (std::size_t c = 0; c < n; ++c) out[c] = disc[c];
          return;
        }
        for (int k = 0; k < 3; ++k) {
          double sum = 0.0;
          for (std::size_t c = 0; c < n; ++c) sum += fold[c][k] * disc[c];
          out[k] = sum;
        }
      },
      scale, image);
}

// The stars of a night sky through `camera`: each star's irradiance (times the transmittance, folded
// as `night` folds) shared bilinearly among the 2 x 2 pixels around its direction, each share over
// that pixel's solid angle, so that a star keeps its energy at any resolution and moves smoothly
// from pixel to pixel in a time-lapse. Shares that fall outside the image or the fisheye's circle
// go to the other pixels; the equirect wraps around.
void AddStars(const NightSky::Folded& night_folded, const Camera& camera_settings, Image& image) {
  const NightSky* night = night_folded.night();
  if (night == nullptr || night->stars() == nullptr) return;
  const shared::CameraParameters camera = ToSharedCamera(camera_settings);
  const int width = camera_settings.width;
  const int height = camera_settings.height;
  const bool wraps = camera_settings.kind == CameraKind::kEquirect;
  const std::size_t m = static_cast<std::size_t>(night_folded.outputs());
  std::vector<glm::dvec3> directions;
  std::vector<float> values;
  night_folded.Stars(directions, values);
  for (std::size_t i = 0; i < directions.size(); ++i) {
    shared::vec2 frag;
    if (!shared::GetCameraFragCoordFromDirection(camera, directions[i], frag)) continue;
    // The four pixels whose centres surround the star, and their bilinear shares.
    const double fx = frag.x - 0.5;
    const double fy = frag.y - 0.5;
    const int x0 = static_cast<int>(std::floor(fx));
    const int y0 = static_cast<int>(std::floor(fy));
    const double ax = fx - x0;
    const double ay = fy - y0;
    struct Share {
      int x, y;
      double weight;
    };
    std::array<Share, 4> shares = {Share{x0, y0, (1 - ax) * (1 - ay)}, Share{x0 + 1, y0, ax * (1 - ay)},
                                   Share{x0, y0 + 1, (1 - ax) * ay}, Share{x0 + 1, y0 + 1, ax * ay}};
    double kept = 0.0;
    for (Share& share : shares) {
      if (wraps) share.x = (share.x % width + width) % width;
      const bool inside = share.x >= 0 && share.y >= 0 && share.x < width && share.y < height &&
                          (image.alpha.empty() || image.alpha[static_cast<std::size_t>(share.y) * width + share.x] != 0.0f);
      if (!inside) share.weight = 0.0;
      kept += share.weight;
    }
    if (!(kept > 0.0)) continue;
    const float* star = &values[i * m];
    for (const Share& share : shares) {
      if (share.weight == 0.0) continue;
      const double solid_angle = shared::GetCameraPixelSolidAngle(camera, shared::ivec2(share.x, share.y));
      if (!(solid_angle > 0.0)) continue;
      const float scale = static_cast<float>(share.weight / kept / solid_angle);
      float* pixel = &image.pixels[(static_cast<std::size_t>(share.y) * width + share.x) * m];
      for (std::size_t k = 0; k < m; ++k) pixel[k] += star[k] * scale;
    }
  }
}

namespace {

// The night sky's per-pixel pass (an empty one without terms.night_sky).
NightSky::Folded NightSkyScaled(const RadianceTerms& terms, std::size_t channels, std::span<const double> scale) {
  if (terms.night_sky == nullptr) return {};
  return CheckedNightSky(terms, channels).Scaled(scale);
}

NightSky::Folded NightSkyFolded(const RadianceTerms& terms, std::size_t channels, std::span<const glm::vec3> weights) {
  if (terms.night_sky == nullptr) return {};
  return CheckedNightSky(terms, channels).Fold(weights, 3);
}

}  // namespace

// The directions of shared::GetCameraRayDirection for one row of a perspective camera, with the
// row's part of the sum formed once: normalize(forward + x right + y up).
void PerspectiveRowDirections(const shared::CameraParameters& camera, int row, std::span<glm::dvec3> views) {
  const double w = camera.width;
  const double h = camera.height;
  const double y = (1.0 - 2.0 * (row + 0.5) / h) * camera.tan_half_fov * h / w;
  const glm::dvec3 base = camera.forward + y * camera.up;
  const glm::dvec3 right = camera.right;
  const double tan_half_fov = camera.tan_half_fov;
  const double scale = 2.0 * tan_half_fov / w;
  const int width = camera.width;
  double* out = &views[0].x;
  // Plain arithmetic on the three components, with everything the loop reads in locals (the
  // stores through `out` could otherwise alias them), so that it vectorises (with
  // -fno-math-errno, see src/atmo/CMakeLists.txt, sqrt is one instruction).
#pragma omp simd
  for (int x = 0; x < width; ++x) {
    const double u = (x + 0.5) * scale - tan_half_fov;
    const double dx = base.x + u * right.x;
    const double dy = base.y + u * right.y;
    const double dz = base.z + u * right.z;
    const double inverse_length = 1.0 / std::sqrt(dx * dx + dy * dy + dz * dz);
    out[3 * x] = dx * inverse_length;
    out[3 * x + 1] = dy * inverse_length;
    out[3 * x + 2] = dz * inverse_length;
  }
}

shared::CameraParameters ToSharedCamera(const Camera& camera) {
  const int kind = camera.kind == CameraKind::kFisheye    ? shared::kCameraFisheye
                   : camera.kind == CameraKind::kEquirect ? shared::kCameraEquirect
                                                          : shared::kCameraPerspective;
  return shared::MakeCameraParameters(kind, camera.width, camera.height, glm::radians(camera.fov_deg),
                                      glm::radians(camera.yaw_deg), glm::radians(camera.pitch_deg));
}

void ValidateCamera(const Camera& camera) {
  if (camera.width < 1 || camera.height < 1 || camera.width > kMaxImageSide || camera.height > kMaxImageSide) {
    throw Error("image size " + std::to_string(camera.width) + "x" + std::to_string(camera.height) +
                " is outside 1.." + std::to_string(kMaxImageSide) + " pixels per side");
  }
  CheckFinite(camera.fov_deg, "fov");
  CheckFinite(camera.yaw_deg, "yaw");
  CheckFinite(camera.pitch_deg, "pitch");
  if (camera.kind == CameraKind::kPerspective && (camera.fov_deg <= 0.0 || camera.fov_deg >= 180.0)) {
    throw Error("fov must be in (0, 180) degrees for a perspective camera");
  }
}

glm::dvec3 SunDirection(double elevation_deg, double azimuth_deg) {
  return DirectionFromZenithAzimuth(glm::radians(90.0 - elevation_deg), glm::radians(azimuth_deg));
}

Image Render(const Model& model, const RenderSettings& settings) {
  ValidateCamera(settings.camera);
  CheckFinite(settings.altitude_m, "altitude");
  CheckFinite(settings.sun_elevation_deg, "sun elevation");
  CheckFinite(settings.sun_azimuth_deg, "sun azimuth");
  CheckChannels(model.channel_count());
  const glm::dvec3 sun = SunDirection(settings.sun_elevation_deg, settings.sun_azimuth_deg);
  const std::unique_ptr<SkyView> sky = model.View(settings.altitude_m, sun);
  RadianceTerms terms = settings.terms;
  std::optional<NightSky> night;
  if (terms.night_sky == nullptr && settings.altitude_m >= 0.0) {
    terms.night_sky = &night.emplace(model.parameters(), settings.altitude_m, sun);
  }
  return RenderView(*sky, settings.camera, terms, model.parameters().solar_irradiance);
}

void AddNightSky(const NightSky::Folded& night, const Camera& camera_settings, Image& image) {
  ValidateCamera(camera_settings);
  if (image.width != camera_settings.width || image.height != camera_settings.height ||
      image.channels != night.outputs()) {
    throw Error("AddNightSky: the image does not match the camera or the night sky's outputs");
  }
  const shared::CameraParameters camera = ToSharedCamera(camera_settings);
  const int width = camera_settings.width;
  const std::size_t nc = static_cast<std::size_t>(image.channels);
  oneapi::tbb::parallel_for(oneapi::tbb::blocked_range<int>(0, image.height), [&](const oneapi::tbb::blocked_range<int>& rows) {
    std::vector<glm::dvec3> views(width);
    for (int y = rows.begin(); y < rows.end(); ++y) {
      if (camera.kind == shared::kCameraPerspective) {
        PerspectiveRowDirections(camera, y, views);
      } else {
        for (int x = 0; x < width; ++x) {
          shared::vec3 direction;
          views[x] = shared::GetCameraRayDirection(camera, shared::vec2(x + 0.5, y + 0.5), direction) ? direction
                                                                                                   : glm::dvec3(0.0);
        }
      }
      night.Add(views, std::span<float>(&image.pixels[static_cast<std::size_t>(y) * width * nc],
                                        static_cast<std::size_t>(width) * nc));
    }
  });
  AddStars(night, camera_settings, image);
}

void AddMoonLight(const Moon& moon, const Image& moonlit, const NightSky& night, const Camera& camera,
                  std::span<const double> solar_irradiance, Image& image) {
  ValidateCamera(camera);
  const std::size_t n = moon.relative_irradiance().size();
  if (image.width != camera.width || image.height != camera.height || static_cast<std::size_t>(image.channels) != n ||
      moonlit.width != image.width || moonlit.height != image.height || moonlit.channels != image.channels ||
      solar_irradiance.size() != n || night.channel_count() != n) {
    throw Error("AddMoonLight: the images, the camera, the moon and the night sky do not match");
  }
  for (std::size_t i = 0; i < image.pixels.size(); ++i) {
    image.pixels[i] += moonlit.pixels[i] * static_cast<float>(moon.relative_irradiance()[i % n]);
  }
  AddMoonDiscLight(moon, night, camera, solar_irradiance, image);
}

void AddMoonDiscLight(const Moon& moon, const NightSky& night, const Camera& camera,
                      std::span<const double> solar_irradiance, Image& image) {
  ValidateCamera(camera);
  const std::size_t n = moon.relative_irradiance().size();
  if (image.width != camera.width || image.height != camera.height || static_cast<std::size_t>(image.channels) != n ||
      solar_irradiance.size() != n || night.channel_count() != n) {
    throw Error("AddMoonDiscLight: the image, the camera, the moon and the night sky do not match");
  }
  AddSunDisc(
      camera, moon.direction(), moon.angular_radius_rad(),
      [&](const glm::dvec3& view, std::span<double> out) {
        thread_local std::vector<double> transmittance;
        transmittance.resize(n);
        moon.DiscRadiance(view, out);
        night.Transmittance(view.z, transmittance);
        for (std::size_t c = 0; c < n; ++c) out[c] *= transmittance[c];
      },
      solar_irradiance, image);
}

namespace {

// The frame loop shared by RenderView and RenderViewFolded: camera rays per row (rows in
// parallel), `evaluate(views, row)` writes `channels` values per pixel of the row.
// `image` is reused when its size and channel count match (every pixel is written: no zero fill,
// no fresh pages), else replaced.
template <typename Evaluate>
void RenderRows(const Camera& camera_settings, int channels, const Evaluate& evaluate, const RowProgress& progress,
                Image& image) {
  std::atomic<int> rows_done{0};
  std::mutex reporting;  // one progress call at a time; rows that find it busy do not wait
  const shared::CameraParameters camera = ToSharedCamera(camera_settings);
  const int width = camera_settings.width;
  const std::size_t nc = static_cast<std::size_t>(channels);
  if (image.width != width || image.height != camera_settings.height || image.channels != channels ||
      image.pixels.size() != static_cast<std::size_t>(width) * camera_settings.height * nc) {
    image = Image(width, camera_settings.height, channels);
  }
  image.alpha.clear();
  image.channel_names.clear();
  image.colour_space = ColourSpace::kUnspecified;
  image.envmap = EnvMap::kNone;
  const bool has_alpha = camera_settings.kind == CameraKind::kFisheye;
  if (has_alpha) image.alpha.assign(static_cast<std::size_t>(width) * image.height, 0.0f);
  if (camera_settings.kind == CameraKind::kEquirect) image.envmap = EnvMap::kLatLong;  // docs/environment.md
  oneapi::tbb::parallel_for(oneapi::tbb::blocked_range<int>(0, image.height), [&](const oneapi::tbb::blocked_range<int>& rows) {
    std::vector<glm::dvec3> views(width);
    for (int y = rows.begin(); y < rows.end(); ++y) {
      if (camera.kind == shared::kCameraPerspective) {
        PerspectiveRowDirections(camera, y, views);
      } else {
        for (int x = 0; x < width; ++x) {
          shared::vec3 direction;
          const bool seen = shared::GetCameraRayDirection(camera, shared::vec2(x + 0.5, y + 0.5), direction);
          views[x] = seen ? direction : glm::dvec3(0.0);
          if (has_alpha) image.alpha[static_cast<std::size_t>(y) * width + x] = seen ? 1.0f : 0.0f;
        }
      }
      evaluate(views, std::span<float>(&image.pixels[static_cast<std::size_t>(y) * width * nc],
                                       static_cast<std::size_t>(width) * nc));
      const int done = rows_done.fetch_add(1, std::memory_order_relaxed) + 1;
      if (progress && done < image.height && reporting.try_lock()) {
        progress(done, image.height);
        reporting.unlock();
      }
    }
  });
  if (progress) progress(image.height, image.height);
}

}  // namespace

Image RenderView(const SkyView& sky, const Camera& camera_settings, const RadianceTerms& terms,
                 std::span<const double> solar_irradiance, const RowProgress& progress) {
  Image image;
  RenderView(sky, camera_settings, terms, solar_irradiance, image, progress);
  return image;
}

void RenderView(const SkyView& sky, const Camera& camera_settings, const RadianceTerms& terms,
                std::span<const double> solar_irradiance, Image& image, const RowProgress& progress) {
  ValidateCamera(camera_settings);
  const std::size_t n = sky.channel_count();
  CheckChannels(n);
  if (solar_irradiance.size() != n) throw Error("solar_irradiance must have one value per channel");
  const std::vector<float> irradiance(solar_irradiance.begin(), solar_irradiance.end());
  // The sun disc is integrated over the pixels by its own pass (cpu/sun_disc.h), not sampled at
  // their centres.
  RadianceTerms sky_terms = terms;
  sky_terms.sun_disc = false;
  const NightSky::Folded night = NightSkyScaled(terms, n, solar_irradiance);
  CheckMoon(terms, n);
  const RadianceTerms moon_terms = MoonSkyTerms(terms);
  std::vector<float> moon_scale(n, 0.0f);
  if (terms.moon != nullptr) {
    for (std::size_t c = 0; c < n; ++c) moon_scale[c] = static_cast<float>(terms.moon->relative_irradiance()[c] * solar_irradiance[c]);
  }
  RenderRows(camera_settings, static_cast<int>(n), [&](std::span<const glm::dvec3> views, std::span<float> row) {
    sky.RadianceBatch(views, sky_terms, row);
    for (std::size_t x = 0; x < views.size(); ++x) {
      for (std::size_t c = 0; c < n; ++c) row[n * x + c] *= irradiance[c];
    }
    if (terms.moon_sky != nullptr) {
      // The moonlit sky: the model's sky for a sun in the moon's direction, times the moon's irradiance.
      thread_local std::vector<float> moonlit;
      moonlit.assign(row.size(), 0.0f);
      terms.moon_sky->RadianceBatch(views, moon_terms, moonlit);
      for (std::size_t i = 0; i < row.size(); ++i) row[i] += moonlit[i] * moon_scale[i % n];
    }
    night.Add(views, row);
  }, progress, image);
  AddStars(night, camera_settings, image);
  if (terms.sun_disc) AddSunDisc(sky, camera_settings, solar_irradiance, image);
  if (terms.moon != nullptr && terms.sun_disc) AddMoonDisc(terms, camera_settings, {}, solar_irradiance, image);
}

Image RenderViewFolded(const SkyView& sky, const Camera& camera_settings, const RadianceTerms& terms,
                       std::span<const glm::vec3> weights, const RowProgress& progress) {
  Image image;
  RenderViewFolded(sky, camera_settings, terms, weights, image, progress);
  return image;
}

void RenderViewFolded(const SkyView& sky, const Camera& camera_settings, const RadianceTerms& terms,
                      std::span<const glm::vec3> weights, Image& image, const RowProgress& progress) {
  ValidateCamera(camera_settings);
  const std::size_t n = sky.channel_count();
  CheckChannels(n);
  if (weights.size() != n) throw Error("RenderViewFolded needs one weight per channel");
  RadianceTerms sky_terms = terms;
  sky_terms.sun_disc = false;
  const NightSky::Folded night = NightSkyFolded(terms, n, weights);
  CheckMoon(terms, n);
  const RadianceTerms moon_terms = MoonSkyTerms(terms);
  std::vector<glm::vec3> moon_weights(n, glm::vec3(0.0f));
  if (terms.moon != nullptr) {
    for (std::size_t c = 0; c < n; ++c) moon_weights[c] = weights[c] * static_cast<float>(terms.moon->relative_irradiance()[c]);
  }
  RenderRows(camera_settings, 3, [&](std::span<const glm::dvec3> views, std::span<float> row) {
    sky.RadianceBatchFolded(views, sky_terms, weights, row);
    if (terms.moon_sky != nullptr) {
      thread_local std::vector<float> moonlit;
      moonlit.assign(row.size(), 0.0f);
      terms.moon_sky->RadianceBatchFolded(views, moon_terms, moon_weights, moonlit);
      for (std::size_t i = 0; i < row.size(); ++i) row[i] += moonlit[i];
    }
    night.Add(views, row);
  }, progress, image);
  AddStars(night, camera_settings, image);
  if (terms.moon != nullptr && terms.sun_disc) {
    const std::vector<double> ones(3, 1.0);
    AddMoonDisc(terms, camera_settings, weights, ones, image);
  }
  if (terms.sun_disc) {
    // The disc pass with the disc's radiance folded by the same weights (solar irradiance 1: the
    // weights carry the units).
    const std::vector<double> ones(3, 1.0);
    AddSunDisc(
        camera_settings, sky.sun_direction(), sky.sun_angular_radius_rad(),
        [&](const glm::dvec3& view, std::span<double> out) {
          thread_local std::vector<double> disc;
          disc.resize(n);
          sky.SunDiscRadiance(view, disc);
          for (int k = 0; k < 3; ++k) {
            double sum = 0.0;
            for (std::size_t c = 0; c < n; ++c) sum += weights[c][k] * disc[c];
            out[k] = sum;
          }
        },
        ones, image);
  }
}

CameraKind ParseCameraKind(std::string_view name) {
  if (name == "perspective") return CameraKind::kPerspective;
  if (name == "fisheye") return CameraKind::kFisheye;
  if (name == "equirect") return CameraKind::kEquirect;
  throw Error("unknown camera '" + std::string(name) + "' (use perspective, fisheye or equirect)");
}

std::string_view ToString(CameraKind kind) {
  switch (kind) {
    case CameraKind::kPerspective: return "perspective";
    case CameraKind::kFisheye: return "fisheye";
    case CameraKind::kEquirect: return "equirect";
  }
  return "perspective";
}

}  // namespace atmo
