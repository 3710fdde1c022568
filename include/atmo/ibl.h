// Image-based lighting from a sky cube map (atmo/cubemap.h): L2 spherical harmonics of the
// radiance, a diffuse irradiance cube map and a GGX-prefiltered specular mip chain in the
// split-sum convention (docs/environment.md).
//
// To use it:
//   atmo::Cubemap sky = atmo::RenderCubemapFolded(*view, 256, {}, weights);   // linear sRGB, cd/m^2
//   atmo::SphericalHarmonics sh = atmo::ProjectSphericalHarmonics(sky, atmo::ShFrame::kEnu);
//   glm::dvec3 e = atmo::ShIrradiance(sh, {0, 0, 1});      // on a horizontal plane: lux for luminance
//   atmo::Cubemap irradiance = atmo::IrradianceCubemap(sky);
//   std::vector<atmo::Cubemap> specular = atmo::PrefilterSpecular(sky);   // 6 levels
//
// Units: whatever the cube's channels are. With atmo render's default (linear sRGB whose luminance
// is in cd/m^2) the irradiance E = integral of L max(cos, 0) dOmega is in the same colour space,
// its luminance in lux (cd sr m^-2). The cube must have 3 channels.
#pragma once

#include <array>
#include <vector>

#include <glm/glm.hpp>

#include "atmo/cubemap.h"

namespace atmo {

// The frame the harmonics' directions (x, y, z) are in: atmo's ENU (x east, y north, z up; the
// zenith is z, as in Ramamoorthi & Hanrahan 2001), or the cube frame (X east, Y up, Z south; the
// zenith is Y, as engines evaluate them).
enum class ShFrame { kEnu, kCube };

// The real spherical harmonics of bands l = 0, 1, 2 at a unit direction (x, y, z), in the order
// (l, m) = (0,0), (1,-1), (1,0), (1,1), (2,-2), (2,-1), (2,0), (2,1), (2,2), orthonormal on the
// sphere, with the signs of Ramamoorthi & Hanrahan 2001 (eq. 3; no Condon-Shortley phase):
//   Y00 = 0.282095                         (1 / (2 sqrt(pi)))
//   Y1-1 = 0.488603 y, Y10 = 0.488603 z, Y11 = 0.488603 x          (sqrt(3 / (4 pi)))
//   Y2-2 = 1.092548 x y, Y2-1 = 1.092548 y z, Y21 = 1.092548 x z  (sqrt(15 / (4 pi)))
//   Y20 = 0.315392 (3 z^2 - 1)                                      (sqrt(5 / (16 pi)))
//   Y22 = 0.546274 (x^2 - y^2)                                      (sqrt(15 / (16 pi)))
std::array<double, 9> ShBasis(const glm::dvec3& direction);

// The clamped-cosine convolution constants A_l of Ramamoorthi & Hanrahan 2001 (eq. 8): pi,
// 2 pi / 3, pi / 4 for l = 0, 1, 2.
constexpr std::array<double, 3> kShCosineLobe = {3.14159265358979323846, 2.0 * 3.14159265358979323846 / 3.0,
                                                 3.14159265358979323846 / 4.0};

struct SphericalHarmonics {
  ShFrame frame = ShFrame::kEnu;
  // L_lm = integral of L(w) Y_lm(w) dOmega: coefficients of the RADIANCE, per channel, in the
  // cube's unit (radiance).
  std::array<glm::dvec3, 9> radiance{};
};

// Projects the cube's radiance onto the nine harmonics, summing L Y_lm dOmega over the texels with
// their exact solid angles (CubeTexelSolidAngle): a constant sky L gives L00 = 2 sqrt(pi) L and
// every other coefficient 0 to rounding (the cube's symmetry).
SphericalHarmonics ProjectSphericalHarmonics(const Cubemap& radiance, ShFrame frame = ShFrame::kEnu);
// The irradiance on a surface of unit normal `normal` (in the harmonics' frame):
// E(n) = sum over l, m of A_l L_lm Y_lm(n) (the L2 approximation of integral L max(n.w, 0) dOmega).
glm::dvec3 ShIrradiance(const SphericalHarmonics& sh, const glm::dvec3& normal);
// The irradiance coefficients E_lm = A_l L_lm (what many engines store instead).
std::array<glm::dvec3, 9> ShIrradianceCoefficients(const SphericalHarmonics& sh);

// The irradiance integral E(n) = integral of L max(n.w, 0) dOmega over the whole cube (n in the
// cube frame), by the texels: pi sum L c dOmega / sum c dOmega with c = max(n.w, 0) at the texel
// centres (the kernel's quadrature normalised to its exact integral pi; a constant sky gives
// pi L to rounding, and the error left is O(texel^2) in the radiance's variation).
glm::dvec3 CubemapIrradiance(const Cubemap& radiance, const glm::dvec3& normal_cube);

// The diffuse irradiance cube map: texel n holds E(n) = pi sum L c dOmega / sum c dOmega,
// c = max(n.w, 0), over the radiance box-filtered (solid-angle weighted, energy conserving) to
// `source_size` texels a face: CubemapIrradiance with the kernel's quadrature normalised to its
// exact integral pi.
// Divide by pi for the radiance a white Lambertian surface reflects. Throws atmo::Error for sizes
// below 1 or a cube without 3 channels.
Cubemap IrradianceCubemap(const Cubemap& radiance, int size = 32, int source_size = 32);

// The split-sum specular prefilter of Karis 2013 ("Real Shading in Unreal Engine 4") as glTF
// viewers use it: level m of `levels` has face size max(1, N >> m) and roughness
// r = m / (levels - 1) (GGX alpha = r^2), and holds, with N = V = R,
//   sum over k of L(l_k) (n.l_k) / sum over k of (n.l_k),
// l_k the reflections of K = max(8, round(samples r)) GGX half vectors (Hammersley points
// ((k + 1/2) / K, radical inverse of k)) with n.l_k > 0: narrower lobes take fewer. Each
// sample reads the radiance's mip pyramid (the solid-angle weighted box filter) at the
// filtered-importance-sampling level of Krivanek & Colbert 2008 (GPU Gems 3, ch. 20):
//   lod = 0.5 log2(Omega_s / Omega_p) + lod_bias (1),  Omega_s = 1 / (K pdf),  Omega_p = 4 pi / (6 N^2),
// pdf = D(h) / 4 the GGX pdf of l at N = V, bilinear within the face (clamped at its edges) and
// linear between levels. Level 0 (roughness 0) is the radiance itself. Throws atmo::Error for
// levels outside [1, log2(N) + 1], samples < 1 or a cube without 3 channels.
struct SpecularSettings {
  int levels = 6;
  int samples = 32;
  double lod_bias = 1.0;  // the "+ 1" above; -inf: every sample reads the full-resolution radiance
};
std::vector<Cubemap> PrefilterSpecular(const Cubemap& radiance, const SpecularSettings& settings = {});

// The cube's value along `direction` (cube frame), bilinear within the face, clamped at its edges.
glm::dvec3 SampleCubemap(const Cubemap& cube, const glm::dvec3& direction);

}  // namespace atmo
