// Sky-view table lookups for rows of view directions, in float (see sky_view_lookup.h).
//
// Each chunk of directions goes through short loops over structure-of-arrays buffers, written
// with selects instead of branches so that g++ -O3 vectorises them (check with
// -fopt-info-vec-optimized): the azimuth and the latitude give the texel coordinates (s, t), these
// give the four texels and the weights, and a last loop fetches and blends them (one 16-byte load
// per texel from the lookup's RGBA copy of the table where the target has SSE). Two defaults of g++
// stand in the way, and are worked around here rather than switched off for this file: std::sqrt
// does not vectorise while it may set errno (-fmath-errno), so the square roots of a chunk are
// taken in passes of their own (SqrtInPlace); and a conditional `c ? x - y : y` is not
// if-converted while float arithmetic may trap (-ftrapping-math), so the selects between computed
// floats are bitwise (Select).
//
// Precision. The shared path computes in double with exact acos and atan2; this one in float with
// polynomials: the azimuth (|a| <= pi) to a few 1e-7 rad, i.e. s to ~1e-5 texel for width 192;
// the view zenith angle past the horizon d = acos(mu) - theta_h to ~2e-7 rad. The latitude mapping
// y = 0.5 -+ 0.5 sqrt(|d| / c) has slope 0.25 / sqrt(|d| c), infinite at the horizon, so there d
// is formed differently: as a small double-precision offset plus a Taylor polynomial of acos about
// the horizon in a - a_h (exact in float), which makes it accurate relative to its own size.
// Outside that window (|a - a_h| >= 1/32) the slope is at most ~1.2, so t stays within ~2e-5 texel
// for height 108.
#include "cpu/sky_view_lookup.h"

#include <algorithm>
#include <bit>
#include <cmath>
#include <cstddef>
#include <cstdint>

#if defined(__SSE__)
#include <immintrin.h>
#endif

#include "shared/shared.h"

namespace atmo::cpu {
namespace {

// Directions per chunk: the buffers of a chunk (~6 KiB) stay in L1.
constexpr int kChunk = 128;

constexpr double kPi = 3.14159265358979323846;

// acos(a) ~ sqrt(1 - a) p(a) for a in [0, 1] with |error| <= 2e-8 rad (Abramowitz & Stegun
// 4.4.46), p of degree 7; coefficients lowest degree first.
constexpr float kAcosPolynomial[8] = {1.5707963050f, -0.2145988016f, 0.0889789874f,  -0.0501743046f,
                                      0.0308918810f, -0.0170881256f, 0.0066700901f, -0.0012624911f};

// atan(a) ~ a + a^3 q(a^2) for a in [0, 1], q of degree 8 fitted for the least maximum absolute
// error (Lawson's iteration on 2000 Chebyshev nodes): |error| <= 1.1e-9 rad, 1e-8 rad with the
// coefficients rounded to float. Coefficients lowest degree first.
constexpr float kAtanPolynomial[9] = {-3.333326286e-01f, 1.999761983e-01f,  -1.425546112e-01f,
                                      1.091026922e-01f,  -8.289734235e-02f, 5.612693173e-02f,
                                      -2.944611740e-02f, 1.002542757e-02f,  -1.602387973e-03f};

constexpr float kPiF = static_cast<float>(kPi);
constexpr float kHalfPiF = static_cast<float>(0.5 * kPi);

// c ? a : b, with both evaluated: a bitwise blend that the vectoriser turns into a vector select.
inline float Select(bool c, float a, float b) {
  const std::uint32_t mask = 0u - static_cast<std::uint32_t>(c);
  return std::bit_cast<float>((std::bit_cast<std::uint32_t>(a) & mask) | (std::bit_cast<std::uint32_t>(b) & ~mask));
}

// v[i] = sqrt(v[i]) for v[i] >= 0, eight at a time where the target has AVX.
void SqrtInPlace(float* v, int n) {
  int i = 0;
#if defined(__AVX__)
  for (; i + 8 <= n; i += 8) _mm256_storeu_ps(v + i, _mm256_sqrt_ps(_mm256_loadu_ps(v + i)));
#endif
  for (; i < n; ++i) v[i] = std::sqrt(v[i]);
}

// The texel coordinates of n <= kChunk directions: s = azimuth from the sun (signed, in
// [-pi, pi]) * width / (2 pi), not yet wrapped; t the row coordinate within the sky or ground half of
// GetSkyViewTextureUvFromBeta (the sampler's v * height - 0.5).
void ComputeTexelCoordinates(const SkyViewLookup& l, const float* x, const float* y, const float* z, int n, float* s,
                             float* t) {
  float root[kChunk];    // argument, then value, of the square roots
  float factor[kChunk];  // d = offset + sign * root * factor
  float offset[kChunk];
  float sign[kChunk];
  // The constants, in locals: the vectoriser does not hoist loads of them out of the loops.
  const float width = static_cast<float>(l.width);
  const float sun_x = l.sun_x;
  const float sun_y = l.sun_y;
  const float texels_per_radian = l.texels_per_radian;
  const float theta_h = l.horizon_zenith_rad;
  const float beta = l.horizon_nadir_angle_rad;
  const float inverse_theta_h = l.inverse_horizon_zenith;
  const float inverse_beta = l.inverse_horizon_dip;
  const float horizon_a = l.horizon_a;
  const float window = l.near_horizon_window;
  const float above_offset = l.above_offset;
  const float below_offset = l.below_offset;
  const float t1 = l.taylor[0], t2 = l.taylor[1], t3 = l.taylor[2], t4 = l.taylor[3], t5 = l.taylor[4];
  for (int i = 0; i < n; ++i) {
    // Azimuth: atan2(v x sun . up, v . sun) in the horizontal plane (GetAzimuthFromSun), reduced
    // to atan on [0, 1].
    const float cx = x[i] * sun_x + y[i] * sun_y;
    const float cy = x[i] * sun_y - y[i] * sun_x;
    const float ax = std::fabs(cx);
    const float ay = std::fabs(cy);
    const float largest = ax > ay ? ax : ay;
    const float smallest = ax > ay ? ay : ax;
    const float ratio = Select(largest > 0.0f, smallest / largest, 0.0f);  // atan2(0, 0) = 0
    const float ratio2 = ratio * ratio;
    float q = kAtanPolynomial[8];
    for (int k = 7; k >= 0; --k) q = q * ratio2 + kAtanPolynomial[k];
    float angle = ratio + ratio * ratio2 * q;
    angle = Select(ay > ax, kHalfPiF - angle, angle);
    // The signs as std::atan2 reads them, signed zeros included: atan2(+-0, -0) = +-pi.
    angle = Select(std::signbit(cx), kPiF - angle, angle);
    angle = Select(std::signbit(cy), -angle, angle);
    const float si = angle * texels_per_radian;
    s[i] = Select((si >= -width) & (si < width), si, 0.0f);  // |si| <= width / 2 but for rounding; NaN -> 0
  }
  // The zenith in a loop of its own: together, the two need more vector registers than there are.
  for (int i = 0; i < n; ++i) {
    // Zenith: a = |mu| clamped to 1 (NaN -> 1), g(a) = acos(a) = sqrt(1 - a) p(a).
    const float abs_mu = std::fabs(z[i]);
    const float a = Select(abs_mu < 1.0f, abs_mu, 1.0f);
    const bool below = z[i] < 0.0f;
    const float delta = a - horizon_a;
    const bool near_horizon = std::fabs(delta) < window;
    const float taylor = delta * (t1 + delta * (t2 + delta * (t3 + delta * (t4 + delta * t5))));
    float p = kAcosPolynomial[7];
    for (int k = 6; k >= 0; --k) p = p * a + kAcosPolynomial[k];
    // Far from the horizon: d = g - theta_h (mu >= 0) or beta - g (mu < 0), g = root * p;
    // near it the same with the offsets about a_h and g replaced by the Taylor polynomial G.
    root[i] = Select(near_horizon, 1.0f, 1.0f - a);
    factor[i] = Select(near_horizon, taylor, p);
    offset[i] = Select(below, Select(near_horizon, below_offset, beta), Select(near_horizon, above_offset, -theta_h));
    sign[i] = Select(below, -1.0f, 1.0f);
  }
  SqrtInPlace(root, n);
  for (int i = 0; i < n; ++i) {
    // Above the horizon (d <= 0, as in the shared mapping) the sky half's y = 1 - sqrt(-d / theta_h),
    // below it the ground half's y = sqrt(min(d / beta, 1)).
    const float d = offset[i] + sign[i] * (root[i] * factor[i]);
    const bool above = !(d > 0.0f);
    const float q = std::fabs(d) * Select(above, inverse_theta_h, inverse_beta);
    root[i] = Select(q < 1.0f, q, 1.0f);  // also NaN -> 1
    sign[i] = Select(above, -1.0f, 1.0f);
  }
  SqrtInPlace(root, n);
  // Each half of the rows maps its y onto its own texel centres: the sky half onto rows
  // 0 .. height/2 - 1 (t = y (height/2 - 1)), the ground half onto rows height/2 .. height - 1.
  const float last_row = static_cast<float>(l.height - 1);
  const float half_last = static_cast<float>(l.height / 2 - 1);
  const float ground_first = static_cast<float>(l.height / 2);
  for (int i = 0; i < n; ++i) {
    const float ti = Select(sign[i] < 0.0f, half_last - half_last * root[i], ground_first + half_last * root[i]);
    t[i] = Select(ti > 0.0f, Select(ti < last_row, ti, last_row), 0.0f);
  }
}

}  // namespace

SkyViewLookup MakeSkyViewLookup(const shared::Texture2D& sky_view, double horizon_nadir_angle_rad,
                                const glm::dvec3& sun_direction) {
  SkyViewLookup l;
  l.texels.reserve(sky_view.texels.size());
  for (const glm::vec3& texel : sky_view.texels) l.texels.emplace_back(texel, 0.0f);
  l.width = sky_view.width;
  l.height = sky_view.height;
  l.sun_x = static_cast<float>(sun_direction.x);
  l.sun_y = static_cast<float>(sun_direction.y);
  l.texels_per_radian = static_cast<float>(sky_view.width / (2.0 * kPi));

  const double beta = horizon_nadir_angle_rad;
  const double theta_h = kPi - beta;
  l.horizon_zenith_rad = static_cast<float>(theta_h);
  l.horizon_nadir_angle_rad = static_cast<float>(beta);
  l.inverse_horizon_zenith = static_cast<float>(1.0 / theta_h);
  l.inverse_horizon_dip = static_cast<float>(1.0 / beta);

  // The horizon is at mu = -cos(beta); a_h is its |mu| rounded to float, so that a - a_h is exact.
  const float a_h = static_cast<float>(std::clamp(std::cos(beta), 0.0, 1.0));
  const double a0 = a_h;
  l.horizon_a = a_h;
  // acos is analytic on (-1, 1): its Taylor series about a0 converges for |delta| < 1 - a0, and
  // within 1/16 of that radius 5 terms leave a relative error below 1e-6 (below 1e-7 for the
  // observers inside an Earth-like atmosphere, where a0 <= 0.18 and the window is 1/32).
  const double window = std::min(1.0 / 32.0, (1.0 - a0) / 16.0);
  l.near_horizon_window = static_cast<float>(window);
  if (window > 0.0) {
    // acos'(a) = -h(a), h = (1 - a^2)^(-1/2) solves (1 - a^2) h' = a h, which gives the Taylor
    // coefficients of h about a0: h_{k+1} = ((2k + 1) a0 h_k + k h_{k-1}) / ((k + 1)(1 - a0^2));
    // then acos(a0 + delta) - acos(a0) = -sum_k h_k delta^(k+1) / (k + 1).
    const double c = 1.0 - a0 * a0;
    double h_previous = 0.0;
    double h = 1.0 / std::sqrt(c);
    for (int k = 0; k < 5; ++k) {
      l.taylor[k] = static_cast<float>(-h / (k + 1));
      const double h_next = ((2 * k + 1) * a0 * h + k * h_previous) / ((k + 1) * c);
      h_previous = h;
      h = h_next;
    }
  }
  const double g0 = std::acos(a0);
  l.above_offset = static_cast<float>(g0 - theta_h);
  l.below_offset = static_cast<float>(beta - g0);
  return l;
}

void GetSkyViewTexelCoordinatesRow(const SkyViewLookup& lookup, const float* x, const float* y, const float* z,
                                   int count, float* s, float* t) {
  for (int begin = 0; begin < count; begin += kChunk) {
    const int n = std::min(kChunk, count - begin);
    ComputeTexelCoordinates(lookup, x + begin, y + begin, z + begin, n, s + begin, t + begin);
    const float width = static_cast<float>(lookup.width);
    for (int i = begin; i < begin + n; ++i) s[i] = Select(s[i] < 0.0f, s[i] + width, s[i]);
  }
}

void LookupSkyViewRow(const SkyViewLookup& lookup, const float* x, const float* y, const float* z, int count,
                      float* out) {
  const int width = lookup.width;
  const int height = lookup.height;
  const glm::vec4* texels = lookup.texels.data();
  float s[kChunk];
  float t[kChunk];
  int base[kChunk];    // index of texel (x0, y0)
  int step_x[kChunk];  // (x1, y) - (x0, y): 1, or 1 - width at the wrap
  int step_y[kChunk];  // (x, y1) - (x, y0): width, or 0 on the last row
  float wx[kChunk];
  float wy[kChunk];
  for (int begin = 0; begin < count; begin += kChunk) {
    const int n = std::min(kChunk, count - begin);
    ComputeTexelCoordinates(lookup, x + begin, y + begin, z + begin, n, s, t);
    // The GL_LINEAR taps: s in [-width / 2, width / 2] wraps, t in [0, height - 1] is clamped
    // only in that the last row's second row is itself (where wy = 0). floor(s) is formed from the
    // truncation: std::floor does not vectorise while float arithmetic may trap.
    for (int i = 0; i < n; ++i) {
      int x0 = static_cast<int>(s[i]);
      x0 -= static_cast<float>(x0) > s[i];
      const int y0 = static_cast<int>(t[i]);  // t >= 0
      wx[i] = s[i] - static_cast<float>(x0);
      wy[i] = t[i] - static_cast<float>(y0);
      x0 += x0 < 0 ? width : 0;
      base[i] = x0 + y0 * width;
      step_x[i] = x0 == width - 1 ? 1 - width : 1;
      step_y[i] = y0 < height - 1 ? width : 0;
    }
    float* o = out + 3 * static_cast<std::ptrdiff_t>(begin);
    for (int i = 0; i < n; ++i) {
      const glm::vec4* t00 = texels + base[i];
      const glm::vec4* t01 = t00 + step_y[i];
#if defined(__SSE__)
      const __m128 a = _mm_loadu_ps(&t00[0].x);
      const __m128 b = _mm_loadu_ps(&t00[step_x[i]].x);
      const __m128 c = _mm_loadu_ps(&t01[0].x);
      const __m128 d = _mm_loadu_ps(&t01[step_x[i]].x);
      const __m128 fx = _mm_set1_ps(wx[i]);
      const __m128 top = _mm_add_ps(a, _mm_mul_ps(_mm_sub_ps(b, a), fx));
      const __m128 bottom = _mm_add_ps(c, _mm_mul_ps(_mm_sub_ps(d, c), fx));
      const __m128 value = _mm_add_ps(top, _mm_mul_ps(_mm_sub_ps(bottom, top), _mm_set1_ps(wy[i])));
      if (begin + i + 1 < count) {
        _mm_storeu_ps(o + 3 * i, value);  // the fourth float is the next pixel's, written after
      } else {
        alignas(16) float last[4];
        _mm_store_ps(last, value);
        for (int k = 0; k < 3; ++k) o[3 * i + k] = last[k];
      }
#else
      const glm::vec4 top = t00[0] + (t00[step_x[i]] - t00[0]) * wx[i];
      const glm::vec4 bottom = t01[0] + (t01[step_x[i]] - t01[0]) * wx[i];
      const glm::vec4 value = top + (bottom - top) * wy[i];
      o[3 * i] = value.x;
      o[3 * i + 1] = value.y;
      o[3 * i + 2] = value.z;
#endif
    }
  }
}

void LookupSkyViewDirections(const SkyViewLookup& lookup, std::span<const glm::dvec3> views, std::span<float> out) {
  // Chunks in structure-of-arrays form, for the vectorised kernel.
  float x[kChunk], y[kChunk], z[kChunk];
  for (std::size_t first = 0; first < views.size(); first += kChunk) {
    const std::size_t count = std::min<std::size_t>(kChunk, views.size() - first);
    for (std::size_t i = 0; i < count; ++i) {
      x[i] = static_cast<float>(views[first + i].x);
      y[i] = static_cast<float>(views[first + i].y);
      z[i] = static_cast<float>(views[first + i].z);
    }
    LookupSkyViewRow(lookup, x, y, z, static_cast<int>(count), &out[3 * first]);
  }
}

void LookupSkyViewBatch(const SkyView& sky, const SkyViewLookup& lookup, const std::vector<shared::Texture2D>& tables,
                        double horizon_nadir_angle_rad, bool sun_disc, std::span<const glm::dvec3> views,
                        std::span<float> out) {
  const std::size_t n = sky.channel_count();
  const glm::dvec3 sun = sky.sun_direction();
  if (n == 3) {
    LookupSkyViewDirections(lookup, views, out);
  } else {
    const shared::ivec2 size(tables.front().width, tables.front().height);
    for (std::size_t i = 0; i < views.size(); ++i) {
      const double azimuth = shared::GetAzimuthFromSun(views[i], sun);
      const shared::vec2 uv = shared::GetSkyViewTextureUvFromBeta(size, horizon_nadir_angle_rad, views[i].z, azimuth);
      for (std::size_t b = 0; b < tables.size(); ++b) {
        const glm::vec3 l = glm::vec3(shared::texture(tables[b], uv));
        for (std::size_t c = 0; c < 3 && 3 * b + c < n; ++c) out[i * n + 3 * b + c] = l[static_cast<int>(c)];
      }
    }
  }
  const double cos_sun = std::cos(sky.sun_angular_radius_rad());
  std::vector<double> disc(n);
  for (std::size_t i = 0; i < views.size(); ++i) {
    const glm::dvec3& view = views[i];
    if (view.x == 0.0 && view.y == 0.0 && view.z == 0.0) {  // nothing seen (outside a fisheye)
      for (std::size_t c = 0; c < n; ++c) out[i * n + c] = 0.0f;
      continue;
    }
    if (sun_disc && glm::dot(view, sun) >= cos_sun) {
      sky.SunDiscRadiance(view, disc);
      for (std::size_t c = 0; c < n; ++c) out[i * n + c] += static_cast<float>(disc[c]);
    }
  }
}

void LookupFoldedSkyViewBatch(const SkyView& sky, const SkyViewLookup& folded, std::span<const glm::vec3> weights,
                              bool sun_disc, std::span<const glm::dvec3> views, std::span<float> out) {
  LookupSkyViewDirections(folded, views, out);
  const std::size_t n = sky.channel_count();
  const glm::dvec3 sun = sky.sun_direction();
  const double cos_sun = std::cos(sky.sun_angular_radius_rad());
  std::vector<double> disc(n);
  for (std::size_t i = 0; i < views.size(); ++i) {
    const glm::dvec3& view = views[i];
    if (view.x == 0.0 && view.y == 0.0 && view.z == 0.0) {  // nothing seen (outside a fisheye)
      for (int k = 0; k < 3; ++k) out[3 * i + k] = 0.0f;
      continue;
    }
    if (sun_disc && glm::dot(view, sun) >= cos_sun) {
      sky.SunDiscRadiance(view, disc);
      for (std::size_t c = 0; c < n; ++c) {
        for (int k = 0; k < 3; ++k) out[3 * i + k] += weights[c][k] * static_cast<float>(disc[c]);
      }
    }
  }
}

}  // namespace atmo::cpu
