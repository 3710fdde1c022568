// Sky-view table lookups for a row of view directions, in float, vectorised.
//
// Per direction v (unit, local frame x = east, y = north, z = up) the result is that of the
// shared double-precision path
//   texture(sky_view, GetSkyViewTextureUvFromBeta(textureSize(sky_view, 0), beta, v.z,
//                                                 GetAzimuthFromSun(v, sun)))
// with the same latitude mapping and the same GL_LINEAR sampling (repeat in x, clamp to edge in y),
// to within a few 1e-5 texels of the sampling position: acos and atan2 are float polynomials
// accurate to float rounding (see sky_view_lookup.cc). The arithmetic runs on structure-of-arrays
// chunks without branches, so that the compiler vectorises it; then the four texels of each
// direction are fetched and blended.
//
// To use it: build a SkyViewLookup once per view and table with MakeSkyViewLookup, then call
// LookupSkyViewRow on rows of directions (any count; thread-safe, the lookup is read-only).
#pragma once

#include <span>
#include <vector>

#include <glm/glm.hpp>

#include "atmo/model.h"
#include "shared/glsl_cpp.h"

namespace atmo::cpu {

// The per-view constants of the lookup. Made by MakeSkyViewLookup; the fields are its business.
struct SkyViewLookup {
  // A copy of the table, `width` x `height` texels, row-major, padded to RGBA so that a texel is
  // one 16-byte load. Sampled as GL_LINEAR with GL_REPEAT in x and clamp to edge in y (the
  // sky-view sampler).
  std::vector<glm::vec4> texels;
  int width = 0;
  int height = 0;

  // Azimuth from the sun: the sun direction's horizontal components, and the table's texels per
  // radian of azimuth, width / (2 pi).
  float sun_x = 0.0f;
  float sun_y = 0.0f;
  float texels_per_radian = 0.0f;

  // Latitude. beta is the horizon-nadir angle (shared::GetHorizonNadirAngle), theta_h = pi - beta
  // the zenith angle of the horizon, d = acos(mu) - theta_h the view zenith angle past the
  // horizon (rad). With a = |mu| and g(a) = acos(a): d = g(a) - theta_h for mu >= 0 and
  // d = beta - g(a) for mu < 0.
  float horizon_zenith_rad = 0.0f;      // theta_h
  float horizon_nadir_angle_rad = 0.0f;         // beta
  float inverse_horizon_zenith = 0.0f;  // 1 / theta_h
  float inverse_horizon_dip = 0.0f;     // 1 / beta (the horizon-nadir angle)
  // Near the horizon (|a - horizon_a| < near_horizon_window), where the mapping has a square
  // root singularity and d must be accurate to far better than a float ulp of pi, d is formed
  // from constants computed in double and a Taylor polynomial of g about horizon_a:
  //   d = above_offset + G(a - horizon_a)  (mu >= 0),   d = below_offset - G(a - horizon_a)  (mu < 0),
  // with G(delta) = g(horizon_a + delta) - g(horizon_a) = sum_k taylor[k - 1] delta^k, k = 1..5.
  float horizon_a = 0.0f;
  float near_horizon_window = 0.0f;
  float above_offset = 0.0f;  // g(horizon_a) - theta_h
  float below_offset = 0.0f;  // beta - g(horizon_a)
  float taylor[5] = {};
};

// The lookup of `sky_view` (a table made for one observer and a sun at azimuth 0, as
// HillaireModel::ComputeSkyViewLut makes it) for the horizon-nadir angle `horizon_nadir_angle_rad`
// (shared::GetHorizonNadirAngle(atmosphere, r)) and the sun direction `sun_direction` (the local
// frame, normalised). Copies the table (for 192 x 108 texels, ~0.3 MiB).
SkyViewLookup MakeSkyViewLookup(const shared::Texture2D& sky_view, double horizon_nadir_angle_rad,
                                const glm::dvec3& sun_direction);

// Writes the table's radiance for the `count` directions (x[i], y[i], z[i]) to out[3 i + c],
// c = 0, 1, 2. Directions should be unit vectors; any finite or non-finite input gives an
// in-bounds lookup (z is clamped to [-1, 1], a NaN azimuth reads as the sun's).
void LookupSkyViewRow(const SkyViewLookup& lookup, const float* x, const float* y, const float* z, int count,
                      float* out);

// LookupSkyViewRow over any number of double-precision directions: three values per direction
// into out[3 i + c].
void LookupSkyViewDirections(const SkyViewLookup& lookup, std::span<const glm::dvec3> views, std::span<float> out);

// An image row from sky-view tables (one per batch of three channels, as `sky` was made with;
// `lookup` their float copy where there is one batch): out[i * channels + c] the tables' radiance
// of direction i (LookupSkyViewDirections for three channels, shared::texture per direction
// otherwise), 0 where a camera sees nothing (the direction (0, 0, 0)), and with `sun_disc`
// sky.SunDiscRadiance added inside the disc. What the models that read sky-view tables
// (hillaire, source4d) give for SkyView::RadianceBatch.
void LookupSkyViewBatch(const SkyView& sky, const SkyViewLookup& lookup, const std::vector<shared::Texture2D>& tables,
                        double horizon_nadir_angle_rad, bool sun_disc, std::span<const glm::dvec3> views,
                        std::span<float> out);

// The folded image row of the models that read sky-view tables (SkyView::RadianceBatchFolded):
// `folded`, a table folded into three values with `weights` (one per channel), looked up for
// `views` into out[3 i + k], 0 where a camera sees nothing, and with `sun_disc`
// sky.SunDiscRadiance folded with `weights` added inside the disc.
void LookupFoldedSkyViewBatch(const SkyView& sky, const SkyViewLookup& folded, std::span<const glm::vec3> weights,
                              bool sun_disc, std::span<const glm::dvec3> views, std::span<float> out);

// The sampling positions of LookupSkyViewRow, for tests: texel coordinates s = u * width - 0.5
// and t = v * height - 0.5 (texel i's centre at i), s[i] in [0, width] after the wrap in x,
// t[i] in [0, height - 1].
void GetSkyViewTexelCoordinatesRow(const SkyViewLookup& lookup, const float* x, const float* y, const float* z,
                                   int count, float* s, float* t);

}  // namespace atmo::cpu
