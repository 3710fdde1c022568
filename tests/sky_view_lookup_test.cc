// Tests of the float row lookup of the sky-view table (cpu/sky_view_lookup.h) against the shared
// double-precision path texture(GetSkyViewTextureUvFromBeta(..., GetAzimuthFromSun(...))) (exact
// acos and atan2), on made-up tables, for random and degenerate directions at several observer
// altitudes.
#include <cmath>
#include <cstdio>
#include <limits>
#include <random>
#include <vector>

#include <gtest/gtest.h>

#include "cpu/sky_view_lookup.h"
#include "shared/shared.h"
#include "test_atmospheres.h"

namespace atmo::cpu {
namespace {

// Tolerances on the sampling position, in texels, for tables up to 192 x 108 (measured maxima
// 1.5e-5 and 3.3e-5). They come from float rounding where the shared path uses double: of the
// azimuth (a few 1e-7 rad, times width / (2 pi) = 31 texels per radian) and of the view zenith
// angle past the horizon (~2e-7 rad, times the slope of the latitude mapping, at most ~1.2 outside
// the near-horizon window where the lookup forms it from double-precision constants, times
// height - 1 = 107 texels).
constexpr double kTexelToleranceS = 3e-5;
constexpr double kTexelToleranceT = 5e-5;

constexpr double kPi = 3.14159265358979323846;

struct Directions {
  std::vector<float> x, y, z;
  void Add(const glm::dvec3& v) {
    x.push_back(static_cast<float>(v.x));
    y.push_back(static_cast<float>(v.y));
    z.push_back(static_cast<float>(v.z));
  }
  int size() const { return static_cast<int>(x.size()); }
};

glm::dvec3 FromZenithCosineAndAzimuth(double mu, double azimuth) {
  const double sin_theta = std::sqrt(std::max(0.0, 1.0 - mu * mu));
  return {sin_theta * std::sin(azimuth), sin_theta * std::cos(azimuth), mu};
}

// A smooth random field, periodic in x like the sky-view table: a few random waves.
shared::Texture2D SmoothTable(int width, int height, unsigned seed) {
  std::mt19937 rng(seed);
  std::uniform_real_distribution<double> uniform(0.0, 1.0);
  shared::Texture2D table(width, height, /*repeat=*/true);
  struct Wave {
    int kx;
    double ky, phase_x, phase_y, amplitude;
  };
  std::vector<Wave> waves;
  for (int i = 0; i < 6; ++i) {
    waves.push_back({1 + static_cast<int>(uniform(rng) * 4), 2.0 + 6.0 * uniform(rng), 2.0 * kPi * uniform(rng),
                     2.0 * kPi * uniform(rng), 0.1 + 0.2 * uniform(rng)});
  }
  for (int j = 0; j < height; ++j) {
    for (int i = 0; i < width; ++i) {
      glm::dvec3 value(1.0, 1.5, 2.0);
      for (std::size_t k = 0; k < waves.size(); ++k) {
        const Wave& w = waves[k];
        const double v = w.amplitude * std::cos(2.0 * kPi * w.kx * i / width + w.phase_x) *
                         std::cos(w.ky * j / height + w.phase_y);
        value[static_cast<int>(k % 3)] += v;
      }
      table.at(i, j) = glm::vec3(value);
    }
  }
  return table;
}

// Sharp features: a dark ground below the horizon row, a bright column (a sun) at x = 0 next to
// the wrap, and a step in azimuth.
shared::Texture2D SharpTable(int width, int height) {
  shared::Texture2D table(width, height, /*repeat=*/true);
  for (int j = 0; j < height; ++j) {
    for (int i = 0; i < width; ++i) {
      glm::vec3 value = j < height / 2 ? glm::vec3(0.2f, 0.4f, 0.9f) : glm::vec3(0.01f, 0.01f, 0.01f);
      if (i == 0) value += glm::vec3(100.0f);
      if (i >= width / 3) value *= 1.5f;
      table.at(i, j) = value;
    }
  }
  return table;
}

// The largest difference between neighbouring texels (with the wrap in x), and the largest value:
// bilinear filtering is Lipschitz with constant `gradient` per texel along each axis.
void TableBounds(const shared::Texture2D& table, double* gradient, double* largest) {
  *gradient = 0.0;
  *largest = 0.0;
  for (int j = 0; j < table.height; ++j) {
    for (int i = 0; i < table.width; ++i) {
      const glm::vec3 v = table.at(i, j);
      const glm::vec3 dx = table.at((i + 1) % table.width, j) - v;
      const glm::vec3 dy = j + 1 < table.height ? table.at(i, j + 1) - v : glm::vec3(0.0f);
      for (int c = 0; c < 3; ++c) {
        *gradient = std::max({*gradient, std::fabs(double(dx[c])), std::fabs(double(dy[c]))});
        *largest = std::max(*largest, std::fabs(double(v[c])));
      }
    }
  }
}

// Random directions over the sphere, and the degenerate ones: the zenith and nadir, the
// horizontal plane (mu = +-0), both sides of the sun's azimuth (where u wraps past 1 or below 0),
// and directions at and around the horizon, which dips by acos(sqrt(r^2 - R^2) / r) - pi / 2.
Directions TestDirections(double horizon_mu, const glm::dvec3& sun, unsigned seed) {
  Directions d;
  std::mt19937 rng(seed);
  std::uniform_real_distribution<double> uniform(0.0, 1.0);
  for (int i = 0; i < 4000; ++i) d.Add(FromZenithCosineAndAzimuth(2.0 * uniform(rng) - 1.0, 2.0 * kPi * uniform(rng)));
  d.Add({0.0, 0.0, 1.0});
  d.Add({0.0, 0.0, -1.0});
  d.Add({0.0, 0.0, 0.0});
  d.Add({1.0, 0.0, 0.0});
  d.Add({-1.0, 0.0, -0.0});
  d.Add({0.0, 1.0, 0.0});
  d.Add({0.0, -1.0, -0.0});
  d.Add({1e-30, 0.0, 1.0});
  const double sun_azimuth = std::atan2(sun.x, sun.y);
  for (double mu : {-1.0, -0.9, -0.3, -0.0, 0.0, 0.2, 0.7, 0.999, 1.0}) {
    for (double offset : {0.0, 1e-9, -1e-9, 1e-7, -1e-7, 1e-5, -1e-5, 1e-3, -1e-3}) {
      d.Add(FromZenithCosineAndAzimuth(mu, sun_azimuth + offset));
      d.Add(FromZenithCosineAndAzimuth(mu, sun_azimuth + kPi + offset));
    }
  }
  for (double offset : {0.0, 1e-9, 1e-8, 1e-7, 1e-6, 1e-5, 1e-4, 1e-3, 1e-2, 0.02, 0.03, 0.04, 0.1}) {
    for (double sign : {-1.0, 1.0}) {
      for (int k = 0; k < 8; ++k) d.Add(FromZenithCosineAndAzimuth(horizon_mu + sign * offset, 2.0 * kPi * uniform(rng)));
    }
  }
  // The floats next to the horizon's cosine.
  float mu = static_cast<float>(horizon_mu);
  for (int k = 0; k < 8; ++k) mu = std::nextafter(mu, -1.0f);
  for (int k = 0; k < 16; ++k, mu = std::nextafter(mu, 1.0f)) {
    const glm::dvec3 v = FromZenithCosineAndAzimuth(mu, 2.0 * kPi * uniform(rng));
    d.x.push_back(static_cast<float>(v.x));
    d.y.push_back(static_cast<float>(v.y));
    d.z.push_back(mu);
  }
  return d;
}

struct Errors {
  double s = 0.0, t = 0.0;  // texels
};

// One observer, sun and table: compares the sampling positions and the radiance of the row
// lookup with the shared path, for the same float directions (promoted to double there). Adds
// the largest position errors to *errors.
void CompareWithSharedPath(const shared::Texture2D& table, double altitude_m, const glm::dvec3& sun_direction,
                           unsigned seed, Errors* errors) {
  const shared::AtmosphereParameters atmosphere = testing::EarthLike();
  const double r = atmosphere.bottom_radius + altitude_m;
  const double beta = shared::GetHorizonNadirAngle(atmosphere, r);
  const glm::dvec3 sun = glm::normalize(sun_direction);
  const SkyViewLookup lookup = MakeSkyViewLookup(table, beta, sun);
  const Directions d = TestDirections(shared::CosineOfHorizonZenith(atmosphere, r), sun, seed);
  const int n = d.size();
  std::vector<float> s(n), t(n), radiance(3 * static_cast<std::size_t>(n));
  GetSkyViewTexelCoordinatesRow(lookup, d.x.data(), d.y.data(), d.z.data(), n, s.data(), t.data());
  LookupSkyViewRow(lookup, d.x.data(), d.y.data(), d.z.data(), n, radiance.data());

  double gradient, largest;
  TableBounds(table, &gradient, &largest);
  // Bilinear filtering moves by at most `gradient` per texel along each axis; the float blend
  // adds a few ulps of the largest value.
  const double radiance_tolerance = gradient * (kTexelToleranceS + kTexelToleranceT) + 1e-6 * largest;
  const shared::ivec2 size = shared::textureSize(table, 0);
  for (int i = 0; i < n; ++i) {
    const shared::vec3 view(d.x[i], d.y[i], d.z[i]);
    const double azimuth = shared::GetAzimuthFromSun(view, sun);
    const shared::vec2 uv = shared::GetSkyViewTextureUvFromBeta(size, beta, view.z, azimuth);
    const shared::vec3 expected = shared::vec3(shared::texture(table, uv));
    double ds = s[i] - (uv.x * size.x - 0.5);
    ds -= size.x * std::round(ds / size.x);  // the wrap
    const double dt = t[i] - (uv.y * size.y - 0.5);
    // A direction on the horizon to within float rounding may land on either half's edge row
    // (height/2 - 1 for the sky, height/2 for the ground): both hold the ray along the horizon in a
    // real table (a made-up table may differ there, so such ties are not compared further).
    const double sky_edge = size.y / 2 - 1;
    const bool horizon_tie = std::fabs(std::fabs(dt) - 1.0) < kTexelToleranceT &&
                             std::min(t[i], float(uv.y * size.y - 0.5)) > sky_edge - kTexelToleranceT &&
                             std::max(t[i], float(uv.y * size.y - 0.5)) < sky_edge + 1.0 + kTexelToleranceT;
    if (horizon_tie) continue;
    errors->s = std::max(errors->s, std::fabs(ds));
    errors->t = std::max(errors->t, std::fabs(dt));
    ASSERT_LE(std::fabs(ds), kTexelToleranceS) << "direction " << i << " (" << view.x << ", " << view.y << ", "
                                              << view.z << "), altitude " << altitude_m << " m, s " << s[i]
                                              << " expected " << uv.x * size.x - 0.5 << " size " << size.x;
    ASSERT_LE(std::fabs(dt), kTexelToleranceT) << "direction " << i << " (" << view.x << ", " << view.y << ", "
                                              << view.z << "), altitude " << altitude_m << " m";
    ASSERT_GE(s[i], 0.0f);
    ASSERT_LE(s[i], float(size.x));
    ASSERT_GE(t[i], 0.0f);
    ASSERT_LE(t[i], float(size.y - 1));
    for (int c = 0; c < 3; ++c) {
      const double dl = std::fabs(radiance[3 * i + c] - expected[c]);
      ASSERT_LE(dl, radiance_tolerance) << "direction " << i << " (" << view.x << ", " << view.y << ", " << view.z
                                        << "), altitude " << altitude_m << " m, channel " << c;
    }
  }
}

const double kAltitudesM[] = {0.0, 10.0, 1000.0, 50e3, 100e3};

std::vector<glm::dvec3> TestSuns() {
  const double elevation = 30.0 * kPi / 180.0;
  return {
      {0.0, 0.0, 1.0},                                          // at the zenith: atan2(0, 0)
      {0.0, -std::cos(elevation), std::sin(elevation)},         // south, 30 degrees up
      {0.6, 0.3, 0.2},                                          // anywhere
      {-0.3, 0.8, -0.1},                                        // below the horizon
      {1e-9, 0.0, 1.0},                                         // next to the zenith
  };
}

TEST(SkyViewLookup, SmoothTableMatchesSharedPath) {
  unsigned seed = 1;
  Errors errors;
  for (const glm::ivec2 size : {glm::ivec2(192, 108), glm::ivec2(37, 22)}) {
    const shared::Texture2D table = SmoothTable(size.x, size.y, seed);
    for (double altitude : kAltitudesM) {
      for (const glm::dvec3& sun : TestSuns()) CompareWithSharedPath(table, altitude, sun, ++seed, &errors);
    }
  }
  std::printf("largest position errors: %.2e texel in x, %.2e texel in y\n", errors.s, errors.t);
}

TEST(SkyViewLookup, SharpTableMatchesSharedPath) {
  unsigned seed = 100;
  Errors errors;
  for (const glm::ivec2 size : {glm::ivec2(192, 108), glm::ivec2(2, 2)}) {
    const shared::Texture2D table = SharpTable(size.x, size.y);
    for (double altitude : kAltitudesM) {
      for (const glm::dvec3& sun : TestSuns()) CompareWithSharedPath(table, altitude, sun, ++seed, &errors);
    }
  }
  std::printf("largest position errors: %.2e texel in x, %.2e texel in y\n", errors.s, errors.t);
}

// Any input, also non-finite, reads inside the table; a row of any length is filled.
TEST(SkyViewLookup, AnyInputReadsInsideTheTable) {
  const shared::Texture2D table = SmoothTable(16, 8, 7);
  const SkyViewLookup lookup = MakeSkyViewLookup(table, 1.0, glm::dvec3(0.0, 0.6, 0.8));
  const float inf = std::numeric_limits<float>::infinity();
  const float nan = std::numeric_limits<float>::quiet_NaN();
  const std::vector<float> x = {nan, inf, -inf, 0.0f, 2.0f, 0.0f, 1e30f};
  const std::vector<float> y = {0.0f, 0.0f, nan, -inf, 0.0f, 0.0f, -1e30f};
  const std::vector<float> z = {0.0f, nan, 0.0f, inf, -5.0f, 0.0f, 0.0f};
  std::vector<float> out(3 * x.size(), -1.0f);
  LookupSkyViewRow(lookup, x.data(), y.data(), z.data(), static_cast<int>(x.size()), out.data());
  for (float v : out) EXPECT_TRUE(std::isfinite(v) && v > 0.0f) << v;
  LookupSkyViewRow(lookup, x.data(), y.data(), z.data(), 0, nullptr);
}

}  // namespace
}  // namespace atmo::cpu
