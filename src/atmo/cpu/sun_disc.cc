#include "cpu/sun_disc.h"

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <map>
#include <vector>

#include <oneapi/tbb/blocked_range.h>
#include <oneapi/tbb/parallel_for.h>

#include "atmo/error.h"
#include "cpu/camera.h"

namespace atmo {
namespace {

constexpr double kStrataAcrossDisc = 96.0;  // strata per disc diameter (see sun_disc.h)
constexpr int kMinStrata = 4;
constexpr int kMaxStrata = 1024;
constexpr double kSmoothDiscPixels = 16.0;  // above this diameter, pixels inside take 2 x 2 strata
constexpr double kSmallDiscPixels = 1.0;    // below this diameter, the disc is sampled, not the pixels
constexpr int kBoundaryPoints = 64;         // points of the disc's outline projected for its footprint

// splitmix64's finaliser: a well-mixed 64-bit hash.
std::uint64_t Mix(std::uint64_t z) {
  z += 0x9e3779b97f4a7c15ull;
  z = (z ^ (z >> 30)) * 0xbf58476d1ce4e5b9ull;
  z = (z ^ (z >> 27)) * 0x94d049bb133111ebull;
  return z ^ (z >> 31);
}

double UnitInterval(std::uint64_t bits) { return static_cast<double>(bits >> 11) * 0x1.0p-53; }

// The pixels that can see part of the disc: rows y0..y1 and columns x0..x1 (inclusive; taken
// modulo the width when `wrap`, for an equirect disc across its left and right edges).
struct Footprint {
  int x0 = 0, x1 = -1, y0 = 0, y1 = -1;
  bool wrap = false;
};

// Two unit vectors that make an orthonormal basis with the unit vector `sun`.
void PerpendicularBasis(const glm::dvec3& sun, glm::dvec3& e1, glm::dvec3& e2) {
  e1 = glm::normalize(glm::cross(sun, std::abs(sun.z) < 0.9 ? glm::dvec3(0, 0, 1) : glm::dvec3(1, 0, 0)));
  e2 = glm::cross(sun, e1);
}

// Projects the disc's centre and a circle just outside its edge through the camera and bounds
// them, one pixel of margin on each side. False: the camera cannot see the disc.
bool FindFootprint(const shared::CameraParameters& camera, const glm::dvec3& sun, double alpha, Footprint& f) {
  const int w = camera.width;
  const int h = camera.height;
  glm::dvec3 e1, e2;
  PerpendicularBasis(sun, e1, e2);
  const double a = std::min(alpha * 1.01 + 1e-9, 0.5 * shared::kPi);
  shared::vec2 centre;
  const bool centre_seen = shared::GetCameraFragCoordFromDirection(camera, sun, centre);
  double min_x = centre.x, max_x = centre.x, min_y = centre.y, max_y = centre.y;
  int behind = centre_seen ? 0 : 1;
  for (int i = 0; i < kBoundaryPoints; ++i) {
    const double phi = 2.0 * shared::kPi * i / kBoundaryPoints;
    const glm::dvec3 d = std::cos(a) * sun + std::sin(a) * (std::cos(phi) * e1 + std::sin(phi) * e2);
    shared::vec2 p;
    if (!shared::GetCameraFragCoordFromDirection(camera, d, p) && camera.kind == shared::kCameraPerspective) {
      ++behind;
      continue;
    }
    if (camera.kind == shared::kCameraEquirect) p.x += w * std::round((centre.x - p.x) / w);  // unwrap
    min_x = std::min(min_x, p.x);
    max_x = std::max(max_x, p.x);
    min_y = std::min(min_y, p.y);
    max_y = std::max(max_y, p.y);
  }
  if (behind == kBoundaryPoints + 1) return false;  // the whole cap behind a perspective camera
  // As ints: a projection far off the image (a point just in front of a perspective camera's
  // plane goes to ~1e17) or NaN is clamped first, so that the conversion is defined; the clamps
  // to the image follow.
  const double limit = 4.0 * (static_cast<double>(w) + h);
  const auto pixel = [limit](double x) { return static_cast<int>(std::floor(shared::ClampToRange(x, -limit, limit))); };
  f.x0 = pixel(min_x) - 1;
  f.x1 = pixel(max_x) + 1;
  f.y0 = pixel(min_y) - 1;
  f.y1 = pixel(max_y) + 1;
  if (behind > 0) f = {0, w - 1, 0, h - 1, false};  // partly behind: look everywhere (fov < 180)
  if (camera.kind == shared::kCameraEquirect) {
    // A disc over a pole covers every column down to its far edge.
    if (sun.z >= std::cos(a)) f = {0, w - 1, 0, f.y1, false};
    if (-sun.z >= std::cos(a)) f = {0, w - 1, f.y0, h - 1, false};
    if (f.x1 - f.x0 + 1 >= w) {
      f.x0 = 0;
      f.x1 = w - 1;
    } else {
      f.wrap = true;
    }
  } else {
    f.x0 = std::max(f.x0, 0);
    f.x1 = std::min(f.x1, w - 1);
  }
  f.y0 = std::max(f.y0, 0);
  f.y1 = std::min(f.y1, h - 1);
  return f.x0 <= f.x1 && f.y0 <= f.y1;
}

// An upper bound of the angle between a pixel's centre direction and any point of the pixel.
double PixelAngularRadius(const shared::CameraParameters& camera) {
  const double w = camera.width;
  const double h = camera.height;
  if (camera.kind == shared::kCameraEquirect) {
    return 0.5 * std::hypot(shared::kPi / h, 2.0 * shared::kPi / w);
  }
  // The largest angle per pixel: at the fisheye's rim (radially) and the perspective's centre.
  const double step = camera.kind == shared::kCameraFisheye ? 0.5 * shared::kPi / (0.5 * std::min(w, h))
                                                            : 2.0 * camera.tan_half_fov / w;
  return 0.5 * std::sqrt(2.0) * step;
}

// The disc of a camera whose pixels are larger than it (diameter < kSmallDiscPixels): the same
// integral over each pixel, estimated over the disc instead: the cap is cut into
// kStrataAcrossDisc^2 cells of equal solid angle (Shirley and Chiu's concentric map of a square
// grid, which keeps the cells compact, then the cap's area-preserving map), and each cell's centre
// direction adds L dOmega_cell to the pixel it falls in. The cost is the cells' count, where the
// pixels' strata would grow as 1 / diameter^2 (a 16 x 16 image of the sun took 9 million
// samples). A direction the camera does not see (behind a perspective camera, outside a fisheye's
// circle) adds nothing, as the pixels' strata would not reach it.
void AddSmallDisc(const shared::CameraParameters& camera, const glm::dvec3& sun, double alpha,
                  const SunDiscRadianceFunction& radiance, std::span<const double> solar_irradiance, Image& image) {
  const std::size_t nc = solar_irradiance.size();
  glm::dvec3 e1, e2;
  PerpendicularBasis(sun, e1, e2);
  const int n = static_cast<int>(kStrataAcrossDisc);
  const double one_minus_cos_alpha = 2.0 * std::sin(0.5 * alpha) * std::sin(0.5 * alpha);
  const double cell_solid_angle = 2.0 * shared::kPi * one_minus_cos_alpha / (static_cast<double>(n) * n);
  std::map<std::size_t, std::vector<double>> sums;  // per pixel (y * width + x): sum of L dOmega
  std::vector<double> l(nc);
  for (int j = 0; j < n; ++j) {
    for (int i = 0; i < n; ++i) {
      // The concentric map of the cell's centre to the unit disc (radius rho, angle phi).
      const double a = 2.0 * (i + 0.5) / n - 1.0;
      const double b = 2.0 * (j + 0.5) / n - 1.0;
      double rho, phi;
      if (std::abs(a) > std::abs(b)) {
        rho = a;
        phi = 0.25 * shared::kPi * (b / a);
      } else {
        rho = b;
        phi = 0.5 * shared::kPi - 0.25 * shared::kPi * (a / b);
      }
      if (rho < 0.0) {  // the map's negative radii are the other half of the disc
        rho = -rho;
        phi += shared::kPi;
      }
      // Area on the unit disc to solid angle on the cap: 1 - cos(theta) = rho^2 (1 - cos(alpha)).
      const double one_minus_cos = rho * rho * one_minus_cos_alpha;
      const double cos_theta = 1.0 - one_minus_cos;
      const double sin_theta = std::sqrt(std::max(one_minus_cos * (2.0 - one_minus_cos), 0.0));
      const glm::dvec3 d = cos_theta * sun + sin_theta * (std::cos(phi) * e1 + std::sin(phi) * e2);
      shared::vec2 frag;
      if (!shared::GetCameraFragCoordFromDirection(camera, d, frag)) continue;
      const double x = std::floor(frag.x);
      const double y = std::floor(frag.y);
      if (!(x >= 0.0 && x < camera.width && y >= 0.0 && y < camera.height)) continue;
      radiance(d, l);
      std::vector<double>& sum = sums[static_cast<std::size_t>(y) * camera.width + static_cast<std::size_t>(x)];
      sum.resize(nc, 0.0);
      for (std::size_t c = 0; c < nc; ++c) sum[c] += l[c] * cell_solid_angle;
    }
  }
  for (const auto& [index, sum] : sums) {
    const int x = static_cast<int>(index % camera.width);
    const int y = static_cast<int>(index / camera.width);
    const double scale = 1.0 / shared::GetCameraPixelSolidAngle(camera, shared::ivec2(x, y));
    float* pixel = &image.pixels[index * nc];
    for (std::size_t c = 0; c < nc; ++c) pixel[c] += static_cast<float>(sum[c] * scale * solar_irradiance[c]);
  }
}

}  // namespace

void AddSunDisc(const Camera& camera_settings, const glm::dvec3& sun_direction, double sun_angular_radius_rad,
                const SunDiscRadianceFunction& radiance, std::span<const double> solar_irradiance, Image& image) {
  ValidateCamera(camera_settings);
  if (!(sun_angular_radius_rad > 0.0 && sun_angular_radius_rad < 0.5 * shared::kPi)) {
    throw Error("the sun disc pass needs a sun angular radius in (0, pi/2) rad");
  }
  const std::size_t nc = solar_irradiance.size();
  if (nc == 0 || static_cast<std::size_t>(image.channels) != nc || image.width != camera_settings.width ||
      image.height != camera_settings.height) {
    throw Error("the sun disc pass needs an image of the camera's size with one channel per solar irradiance");
  }
  const shared::CameraParameters camera = ToSharedCamera(camera_settings);
  const glm::dvec3 sun = glm::normalize(sun_direction);
  const double alpha = sun_angular_radius_rad;
  const double cos_alpha = std::cos(alpha);
  Footprint footprint;
  if (!FindFootprint(camera, sun, alpha, footprint)) return;

  // The disc's diameter in pixels where it is, from the solid angle per square pixel there.
  shared::vec2 centre;
  double density = 0.0;
  if (shared::GetCameraFragCoordFromDirection(camera, sun, centre)) {
    density = shared::GetCameraSolidAngleDensity(camera, centre);
  }
  const double diameter_px = density > 0.0 ? 2.0 * alpha / std::sqrt(density)
                                            : std::max(footprint.x1 - footprint.x0, footprint.y1 - footprint.y0);
  if (density > 0.0 && diameter_px < kSmallDiscPixels) {
    AddSmallDisc(camera, sun, alpha, radiance, solar_irradiance, image);
    return;
  }
  // Clamped as a double, NaN included, so that the conversion to int is defined.
  const int strata = static_cast<int>(std::ceil(shared::ClampToRange(
      kStrataAcrossDisc / std::max(diameter_px, 1e-6), static_cast<double>(kMinStrata), static_cast<double>(kMaxStrata))));
  const bool smooth_inside = diameter_px > kSmoothDiscPixels;
  const double pixel_radius = 1.05 * PixelAngularRadius(camera);
  const int width = camera_settings.width;

  oneapi::tbb::parallel_for(
      oneapi::tbb::blocked_range<int>(footprint.y0, footprint.y1 + 1), [&](const oneapi::tbb::blocked_range<int>& rows) {
        std::vector<double> l(nc);
        std::vector<double> sum(nc);
        for (int y = rows.begin(); y < rows.end(); ++y) {
          for (int column = footprint.x0; column <= footprint.x1; ++column) {
            const int x = footprint.wrap ? (column % width + width) % width : column;
            // A fisheye pixel whose centre is outside the circle still holds the part of the disc
            // inside it (the pixel's solid angle is that of the part inside): its strata decide.
            shared::vec3 view;
            const bool centre_seen = shared::GetCameraRayDirection(camera, shared::vec2(x + 0.5, y + 0.5), view);
            const double theta = centre_seen ? std::acos(std::clamp(glm::dot(view, sun), -1.0, 1.0)) : alpha;
            if (theta - pixel_radius > alpha) continue;
            // Inside a large disc the radiance is smooth: 2 x 2 strata at their centres (the
            // midpoint rule, second order); on its edge k x k jittered strata find the coverage.
            const bool inside = smooth_inside && centre_seen && theta + pixel_radius < alpha;
            const int n = inside ? 2 : strata;
            const std::uint64_t pixel_key = Mix(static_cast<std::uint64_t>(y) * width + x);
            std::fill(sum.begin(), sum.end(), 0.0);
            bool any = false;
            for (int j = 0; j < n; ++j) {
              for (int i = 0; i < n; ++i) {
                const std::uint64_t key = Mix(pixel_key ^ (static_cast<std::uint64_t>(j) * n + i));
                const shared::vec2 frag(x + (i + (inside ? 0.5 : UnitInterval(key))) / n,
                                        y + (j + (inside ? 0.5 : UnitInterval(Mix(key)))) / n);
                shared::vec3 d;
                if (!shared::GetCameraRayDirection(camera, frag, d) || glm::dot(d, sun) < cos_alpha) continue;
                radiance(d, l);
                const double j_density = shared::GetCameraSolidAngleDensity(camera, frag);
                for (std::size_t c = 0; c < nc; ++c) sum[c] += l[c] * j_density;
                any = true;
              }
            }
            if (!any) continue;
            // The pixel's mean radiance: its integral over the pixel divided by its solid angle.
            const double scale = 1.0 / (static_cast<double>(n) * n * shared::GetCameraPixelSolidAngle(camera, shared::ivec2(x, y)));
            float* pixel = &image.pixels[(static_cast<std::size_t>(y) * width + x) * nc];
            for (std::size_t c = 0; c < nc; ++c) pixel[c] += static_cast<float>(sum[c] * scale * solar_irradiance[c]);
          }
        }
      });
}

void AddSunDisc(const SkyView& sky, const Camera& camera, std::span<const double> solar_irradiance, Image& image) {
  if (!std::isfinite(sky.sun_angular_radius_rad())) {
    throw Error("this model's view does not give the sun's angular radius, which the sun disc pass needs");
  }
  AddSunDisc(
      camera, sky.sun_direction(), sky.sun_angular_radius_rad(),
      [&sky](const glm::dvec3& view, std::span<double> out) { sky.SunDiscRadiance(view, out); }, solar_irradiance,
      image);
}

}  // namespace atmo
