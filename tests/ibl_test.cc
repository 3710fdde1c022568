// Image-based lighting (atmo/ibl.h): the spherical harmonics, the irradiance cube map and the
// specular chain against constant skies (exact answers) and a clear sky's direct cosine-weighted
// integral, and the SH illuminance against atmo::ComputeIlluminance.
#include "atmo/ibl.h"

#include <cmath>
#include <cstdio>
#include <numbers>
#include <vector>

#include <gtest/gtest.h>

#include "atmo/colour.h"
#include "atmo/illuminance.h"
#include "atmo/image.h"
#include "atmo/parameters.h"
#include "cpu/path_tracer.h"

namespace atmo {
namespace {

constexpr double kPi = std::numbers::pi;

Cubemap ConstantCube(int n, const glm::dvec3& value) {
  Cubemap cube(n, 3);
  for (Image& face : cube.faces) {
    for (std::size_t p = 0; p < face.pixels.size(); p += 3) {
      face.pixels[p] = static_cast<float>(value.x);
      face.pixels[p + 1] = static_cast<float>(value.y);
      face.pixels[p + 2] = static_cast<float>(value.z);
    }
  }
  return cube;
}

double RelativeError(const glm::dvec3& a, const glm::dvec3& b) {
  return std::max({std::abs(a.x / b.x - 1.0), std::abs(a.y / b.y - 1.0), std::abs(a.z / b.z - 1.0)});
}

TEST(SphericalHarmonics, BasisIsOrthonormalOnTheCube) {
  // Texel-centre quadrature over a 64-texel cube: exact up to its O(h^2) error.
  const int n = 64;
  double gram[9][9] = {};
  for (int f = 0; f < kCubeFaceCount; ++f) {
    for (int j = 0; j < n; ++j) {
      for (int i = 0; i < n; ++i) {
        const auto y = ShBasis(CubeFaceDirection(static_cast<CubeFace>(f), (i + 0.5) / n, (j + 0.5) / n));
        const double w = CubeTexelSolidAngle(n, i, j);
        for (int a = 0; a < 9; ++a) {
          for (int b = 0; b < 9; ++b) gram[a][b] += y[a] * y[b] * w;
        }
      }
    }
  }
  for (int a = 0; a < 9; ++a) {
    for (int b = 0; b < 9; ++b) EXPECT_NEAR(gram[a][b], a == b ? 1.0 : 0.0, 2e-4) << a << " " << b;
  }
}

// A constant sky L: irradiance pi L on every normal, exactly (to rounding: the solid angles sum to
// 4 pi and the cube's symmetry cancels every other band), in both frames; the irradiance cube is
// pi L everywhere; the specular chain is L at every level and texel, so its mean is L.
TEST(ImageBasedLighting, ConstantSkyGivesPiLAndStaysConstant) {
  const glm::dvec3 l(1.5, 2.0, 0.25);
  const Cubemap cube = ConstantCube(32, l);
  for (const ShFrame frame : {ShFrame::kEnu, ShFrame::kCube}) {
    const SphericalHarmonics sh = ProjectSphericalHarmonics(cube, frame);
    EXPECT_LT(RelativeError(sh.radiance[0], 2.0 * std::sqrt(kPi) * l), 1e-7);  // float texels
    for (int k = 1; k < 9; ++k) EXPECT_LT(glm::length(sh.radiance[k]), 1e-6) << k;
    for (const glm::dvec3& normal : {glm::dvec3(0, 0, 1), glm::dvec3(1, 0, 0), glm::dvec3(0.3, -0.5, -0.8)}) {
      EXPECT_LT(RelativeError(ShIrradiance(sh, normal), kPi * l), 1e-6);
    }
  }
  EXPECT_LT(RelativeError(CubemapIrradiance(cube, {0.2, 0.9, -0.1}), kPi * l), 1e-6);
  const Cubemap irradiance = IrradianceCubemap(cube, 8);
  for (const Image& face : irradiance.faces) {
    for (std::size_t p = 0; p < face.pixels.size(); p += 3) {
      EXPECT_LT(RelativeError({face.pixels[p], face.pixels[p + 1], face.pixels[p + 2]}, kPi * l), 1e-5);
    }
  }
  const std::vector<Cubemap> specular = PrefilterSpecular(cube, {6, 32});
  ASSERT_EQ(specular.size(), 6u);
  for (std::size_t m = 0; m < specular.size(); ++m) {
    EXPECT_EQ(specular[m].face_size, 32 >> m);
    glm::dvec3 mean(0.0);
    double count = 0.0;
    for (const Image& face : specular[m].faces) {
      for (std::size_t p = 0; p < face.pixels.size(); p += 3) {
        const glm::dvec3 v(face.pixels[p], face.pixels[p + 1], face.pixels[p + 2]);
        EXPECT_LT(RelativeError(v, l), 1e-6) << "level " << m;
        mean += v;
        count += 1.0;
      }
    }
    EXPECT_LT(RelativeError(mean / count, l), 1e-6) << "level " << m;
  }
}

class ClearSky : public ::testing::Test {
 protected:
  static void SetUpTestSuite() {
    parameters_ = new AtmosphereParameters(Preset("earth"));
    model_ = CreateModel("hillaire", *parameters_).release();
    sky_ = model_->View(0.0, SunDirection(30.0, 150.0)).release();
    const SpectralConversion convert(parameters_->wavelengths_nm);
    weights_ = ColourWeights(convert, ImageColour::kLinearSrgb);
    // Linear sRGB in cd/m^2, as atmo render writes it, the disc left out (see below) and the lit
    // ground in (below the horizon; without it the radiance drops to 0 there).
    cube_ = new Cubemap(RenderCubemapFolded(*sky_, 128, RadianceTerms{false, true}, weights_));
  }
  static void TearDownTestSuite() {
    delete cube_;
    delete sky_;
    delete model_;
    delete parameters_;
  }
  static inline AtmosphereParameters* parameters_ = nullptr;
  static inline Model* model_ = nullptr;
  static inline SkyView* sky_ = nullptr;
  static inline Cubemap* cube_ = nullptr;
  static inline std::vector<glm::vec3> weights_;
};

// A sky that is a polynomial of degree 2 in the direction lies in the span of bands 0..2, so its L2
// irradiance is exact: L = 1 + 0.5 z + 0.3 x y + 0.8 z^2 (ENU) gives, facing up,
// E = pi + 0.5 (2 pi / 3) + 0 + 0.8 (pi / 2) = 1.7333 pi (to the cube's O(texel^2) quadrature).
TEST(SphericalHarmonics, IrradianceOfABandLimitedSkyIsExact) {
  const int n = 64;
  Cubemap cube(n, 3);
  for (int f = 0; f < kCubeFaceCount; ++f) {
    for (int j = 0; j < n; ++j) {
      for (int i = 0; i < n; ++i) {
        const glm::dvec3 d = EnuFromCube(CubeFaceDirection(static_cast<CubeFace>(f), (i + 0.5) / n, (j + 0.5) / n));
        const double l = 1.0 + 0.5 * d.z + 0.3 * d.x * d.y + 0.8 * d.z * d.z;
        for (int c = 0; c < 3; ++c) cube.faces[f].at(i, j, c) = static_cast<float>(l * (c + 1));
      }
    }
  }
  const glm::dvec3 e = ShIrradiance(ProjectSphericalHarmonics(cube), {0.0, 0.0, 1.0});
  const double exact = (1.0 + 1.0 / 3.0 + 0.4) * kPi;
  EXPECT_LT(RelativeError(e, glm::dvec3(exact, 2.0 * exact, 3.0 * exact)), 1e-4);
  // The direct integral agrees too (its error is the cube's quadrature).
  EXPECT_LT(RelativeError(CubemapIrradiance(cube, {0.0, 1.0, 0.0}), glm::dvec3(exact, 2.0 * exact, 3.0 * exact)), 1e-4);
}

// On a horizontal plane (normal up: ENU +z, cube +Y) the direct cosine-weighted integral of the
// rendered cube matches ComputeIlluminance's diffuse_horizontal_lux (its own hemisphere quadrature
// of the model) within 1 %, and the two SH frames agree to rounding. The L2 SH irradiance is NOT
// within 1 % of it: the sky brightens towards the horizon (here 1770 cd/m^2 at the zenith, 11700
// at the horizon, green), even-band structure above l = 2 that the clamped-cosine kernel still
// sees (A_4 = -pi/24), so L2 overestimates the horizontal irradiance by ~4.5 % in luminance
// (7 % in R). Bounded at 6 % here; a band-limited sky is exact (the test above). With the sun
// disc in the cube, L2 rings: that error is printed, not bounded.
TEST_F(ClearSky, ShIrradianceOnAHorizontalPlaneAgainstTheDirectIntegralAndComputeIlluminance) {
  const glm::dvec3 direct = CubemapIrradiance(*cube_, {0.0, 1.0, 0.0});
  const SphericalHarmonics enu = ProjectSphericalHarmonics(*cube_, ShFrame::kEnu);
  const SphericalHarmonics y_up = ProjectSphericalHarmonics(*cube_, ShFrame::kCube);
  const glm::dvec3 sh = ShIrradiance(enu, {0.0, 0.0, 1.0});
  EXPECT_LT(RelativeError(ShIrradiance(y_up, {0.0, 1.0, 0.0}), sh), 1e-9);
  const Illuminance reference = ComputeIlluminance(*sky_, *parameters_);
  const double direct_lux = Luminance(direct.x, direct.y, direct.z);
  const double lux = Luminance(sh.x, sh.y, sh.z);
  const double direct_error = direct_lux / reference.diffuse_horizontal_lux - 1.0;
  const double lux_error = lux / reference.diffuse_horizontal_lux - 1.0;
  std::printf("horizontal: direct integral %.1f lux, ComputeIlluminance %.1f lux (%+.3f %%); L2 SH %.1f lux (%+.3f %%)\n",
              direct_lux, reference.diffuse_horizontal_lux, 100.0 * direct_error, lux, 100.0 * lux_error);
  EXPECT_LT(std::abs(direct_error), 0.01);
  EXPECT_LT(std::abs(lux_error), 0.06);
  EXPECT_GT(lux_error, 0.0);  // the horizon band's l >= 4 part: an overestimate

  // Tilted planes: the L2 error grows away from the zenith (printed for the record).
  for (const glm::dvec3& n : {glm::dvec3(1, 0, 0), glm::dvec3(0, -1, 0), glm::dvec3(0.5, -0.5, 0.707)}) {
    const glm::dvec3 e = ShIrradiance(enu, n);
    std::printf("  normal (%.2f, %.2f, %.2f) ENU: SH vs direct %+.3f %%\n", n.x, n.y, n.z,
                100.0 * (Luminance(e.x, e.y, e.z) /
                             Luminance(CubemapIrradiance(*cube_, CubeFromEnu(glm::normalize(n))).x,
                                       CubemapIrradiance(*cube_, CubeFromEnu(glm::normalize(n))).y,
                                       CubemapIrradiance(*cube_, CubeFromEnu(glm::normalize(n))).z) -
                         1.0));
  }
  const Cubemap with_disc = RenderCubemapFolded(*sky_, 128, RadianceTerms{true, false}, weights_);
  const glm::dvec3 e_disc = ShIrradiance(ProjectSphericalHarmonics(with_disc), {0.0, 0.0, 1.0});
  const glm::dvec3 direct_disc = CubemapIrradiance(with_disc, {0.0, 1.0, 0.0});
  std::printf("with the sun disc: SH %.1f lux against the direct integral %.1f lux (%+.2f %%: L2 ringing)\n",
              Luminance(e_disc.x, e_disc.y, e_disc.z), Luminance(direct_disc.x, direct_disc.y, direct_disc.z),
              100.0 * (Luminance(e_disc.x, e_disc.y, e_disc.z) /
                           Luminance(direct_disc.x, direct_disc.y, direct_disc.z) -
                       1.0));
}

// The sky's irradiance on a horizontal plane against the reference path tracer's flux estimator
// (PathTracer::DiffuseIrradiance: cosine-weighted directions, pi L per path, 2 million paths,
// standard errors 0.3 % or less). hillaire's scattered radiance integrated over the upper
// hemisphere (the midpoint rule of ComputeIlluminance, 1 x 2 degrees; the cube's direct integral
// agrees with it to 0.005 % in luminance, the test above) is measured at -2.1 % of the reference in
// illuminance (the channels weighted by the solar irradiance and the luminance of their sRGB
// colour; 8144 against 8323 +- 12 lux), and per channel at +0.2 % (680 nm), -1.8 % (550 nm) and
// -4.1 % (440 nm): hillaire's multiple-scattering approximation is short in blue (docs/accuracy.md),
// so the 2 % the project asked for is missed by the model, not by the cube's integration. Bounded
// at 3 % in illuminance and 5 % per channel.
TEST_F(ClearSky, HorizontalIrradianceMatchesTheReferenceFlux) {
  // The vertex estimator: with the sun 30 deg high it is the cheaper one per path for this flux,
  // and these 2 000 000 paths are the ones the figures above were measured with.
  cpu::PathTracerSettings settings;
  settings.next_event = cpu::NextEventEstimation::kVertex;
  const cpu::PathTracer tracer(*parameters_, settings);
  const glm::dvec3 sun = SunDirection(30.0, 150.0);
  const cpu::PathTally tally = tracer.DiffuseIrradiance(tracer.ObserverPosition(0.0), {0.0, 0.0, 1.0}, sun, 7, 2000000);
  constexpr int kZenith = 90;
  constexpr int kAzimuth = 180;
  std::vector<double> hemisphere(3, 0.0);
  std::array<double, 3> l{};
  for (int i = 0; i < kZenith; ++i) {
    const double theta = (i + 0.5) * (kPi / 2.0) / kZenith;
    const double d_omega = std::sin(theta) * (kPi / 2.0 / kZenith) * (2.0 * kPi / kAzimuth);
    for (int j = 0; j < kAzimuth; ++j) {
      const double phi = (j + 0.5) * 2.0 * kPi / kAzimuth;
      sky_->Radiance(glm::dvec3(std::sin(theta) * std::cos(phi), std::sin(theta) * std::sin(phi), std::cos(theta)), l);
      for (int c = 0; c < 3; ++c) hemisphere[c] += l[c] * std::cos(theta) * d_omega;
    }
  }
  double lux = 0.0;
  double reference_lux = 0.0;
  double reference_lux_se2 = 0.0;
  for (int c = 0; c < 3; ++c) {
    const cpu::Estimate e = tally.Get(c, 0);
    std::printf("channel %d: hillaire %.5e, reference %.5e +- %.1e (%+.2f %%, %.1f standard errors)\n", c,
                hemisphere[c], e.mean, e.standard_error, 100.0 * (hemisphere[c] / e.mean - 1.0),
                (hemisphere[c] - e.mean) / e.standard_error);
    EXPECT_LT(e.standard_error / e.mean, 0.004);
    EXPECT_NEAR(hemisphere[c] / e.mean, 1.0, 0.05) << "channel " << c;
    const glm::vec3 w = weights_[c];
    const double k = parameters_->solar_irradiance[c] * Luminance(w.x, w.y, w.z);
    lux += k * hemisphere[c];
    reference_lux += k * e.mean;
    reference_lux_se2 += k * k * e.standard_error * e.standard_error;
  }
  std::printf("illuminance: hillaire %.1f lux, reference %.1f +- %.1f lux (%+.2f %%)\n", lux, reference_lux,
              std::sqrt(reference_lux_se2), 100.0 * (lux / reference_lux - 1.0));
  EXPECT_NEAR(lux / reference_lux, 1.0, 0.03);
}

// Where the L2 error of the horizontal irradiance comes from. For the normal n = up only the zonal
// harmonics Y_l0 = sqrt((2l + 1) / 4pi) P_l(z) see it, so the exact irradiance is the series
//   E(up) = sum over l of A_l L_l0 sqrt((2l + 1) / 4pi),  L_l0 = integral of L Y_l0 dOmega,
// with the clamped-cosine constants A_0 = pi, A_1 = 2pi/3, A_l = 0 for odd l > 1 and, for even
// l >= 2, A_l = 2pi (-1)^(l/2 - 1) / ((l + 2)(l - 1)) l! / (2^l ((l/2)!)^2) (Ramamoorthi & Hanrahan
// 2001, eq. 8). Truncated at l = 2 the series is the L2 SH irradiance (to rounding); carried on, it
// converges to the direct integral of the same cube (measured: +1.6 % at l = 4, +0.79 % at l = 6,
// +0.06 % at l = 16, 0.002 % at l = 40), so the harmonics are right and the +4.5 % of L2 is its
// truncation (the bands l >= 4).
TEST_F(ClearSky, ZonalSeriesOfTheHorizontalIrradianceConvergesToTheDirectIntegral) {
  constexpr int kMaxBand = 40;
  const int n = cube_->face_size;
  const std::vector<double> omega = CubeFaceSolidAngles(n);
  std::vector<glm::dvec3> zonal(kMaxBand + 1, glm::dvec3(0.0));  // L_l0 / sqrt((2l + 1) / 4pi)
  std::vector<double> legendre(kMaxBand + 1);
  for (int f = 0; f < kCubeFaceCount; ++f) {
    for (int j = 0; j < n; ++j) {
      for (int i = 0; i < n; ++i) {
        const double z = EnuFromCube(CubeFaceDirection(static_cast<CubeFace>(f), (i + 0.5) / n, (j + 0.5) / n)).z;
        legendre[0] = 1.0;
        legendre[1] = z;
        for (int l = 2; l <= kMaxBand; ++l) legendre[l] = ((2 * l - 1) * z * legendre[l - 1] - (l - 1) * legendre[l - 2]) / l;
        const float* p = &cube_->faces[f].pixels[(static_cast<std::size_t>(j) * n + i) * 3];
        const glm::dvec3 l_omega = glm::dvec3(p[0], p[1], p[2]) * omega[static_cast<std::size_t>(j) * n + i];
        for (int l = 0; l <= kMaxBand; ++l) zonal[l] += legendre[l] * l_omega;
      }
    }
  }
  const auto cosine_lobe = [](int l) {
    if (l == 0) return std::numbers::pi;
    if (l == 1) return 2.0 * std::numbers::pi / 3.0;
    if (l % 2 == 1) return 0.0;
    double ratio = 1.0;  // l! / (2^l ((l/2)!)^2), the central binomial coefficient over 2^l
    for (int k = 1; k <= l / 2; ++k) ratio *= (l / 2.0 + k) / (4.0 * k);
    return 2.0 * std::numbers::pi * ((l / 2) % 2 == 1 ? 1.0 : -1.0) / ((l + 2.0) * (l - 1.0)) * ratio;
  };
  ASSERT_NEAR(cosine_lobe(2), std::numbers::pi / 4.0, 1e-15);
  ASSERT_NEAR(cosine_lobe(4), -std::numbers::pi / 24.0, 1e-15);
  const glm::dvec3 direct = CubemapIrradiance(*cube_, {0.0, 1.0, 0.0});
  const double direct_lux = Luminance(direct.x, direct.y, direct.z);
  glm::dvec3 series(0.0);
  double error_at_6 = 0.0;
  for (int l = 0; l <= kMaxBand; ++l) {
    // A_l L_l0 Y_l0(up) = A_l (2l + 1) / (4 pi) x (the sum of L P_l dOmega).
    series += cosine_lobe(l) * (2.0 * l + 1.0) / (4.0 * std::numbers::pi) * zonal[l];
    const double error = Luminance(series.x, series.y, series.z) / direct_lux - 1.0;
    if (l == 2) {
      const glm::dvec3 sh = ShIrradiance(ProjectSphericalHarmonics(*cube_), {0.0, 0.0, 1.0});
      EXPECT_LT(RelativeError(series, sh), 1e-9);  // the series at l = 2 is the L2 SH irradiance
      EXPECT_GT(error, 0.03);                      // and it is the +4.5 % of the test above
    }
    if (l == 6) error_at_6 = error;
    if (l % 2 == 0 && l >= 2) std::printf("  zonal series to l = %2d: %+.3f %% against the direct integral\n", l, 100.0 * error);
  }
  EXPECT_LT(std::abs(error_at_6), 0.01);
  EXPECT_LT(std::abs(Luminance(series.x, series.y, series.z) / direct_lux - 1.0), 1e-4);
}

// The irradiance cube's value facing up (bilinear at the centre of +Y: the mean of its four
// central texels) is the direct integral within 1 %, as are texels elsewhere.
TEST_F(ClearSky, IrradianceCubeMatchesTheDirectIntegral) {
  const Cubemap irradiance = IrradianceCubemap(*cube_);
  const glm::dvec3 up = SampleCubemap(irradiance, {0.0, 1.0, 0.0});
  const glm::dvec3 direct = CubemapIrradiance(*cube_, {0.0, 1.0, 0.0});
  std::printf("irradiance cube facing up %.3f %.3f %.3f, direct %.3f %.3f %.3f (%.3f %%)\n", up.x, up.y, up.z,
              direct.x, direct.y, direct.z, 100.0 * RelativeError(up, direct));
  EXPECT_LT(RelativeError(up, direct), 0.01);
  double worst = 0.0;
  for (int f = 0; f < kCubeFaceCount; ++f) {
    for (const auto& [i, j] : std::vector<std::pair<int, int>>{{3, 5}, {16, 16}, {30, 1}}) {
      const glm::dvec3 n = CubeFaceDirection(static_cast<CubeFace>(f), (i + 0.5) / 32, (j + 0.5) / 32);
      const Image& face = irradiance.faces[f];
      const glm::dvec3 v(face.at(i, j, 0), face.at(i, j, 1), face.at(i, j, 2));
      worst = std::max(worst, RelativeError(v, CubemapIrradiance(*cube_, n)));
    }
  }
  std::printf("irradiance cube texels against the direct integral: worst %.3f %%\n", 100.0 * worst);
  EXPECT_LT(worst, 0.01);
}

// Roughness 0 is the radiance itself; at roughness 1 (alpha 1) the GGX lobe at N = V makes l
// uniform over the sphere, so the n.l-weighted mean is the cosine-weighted mean E(n) / pi. For a
// smooth sky (1 + Y, mean 1) that holds within 0.05 at 256 samples on every face centre (the
// filtered-importance-sampling lookups blur: -0.037 measured facing up, -0.004 at 4096 samples). On the clear sky, whose horizon band and
// aureole are narrow against 128 accepted samples, each texel of the last level is within 15 %
// of E(n) / pi (measured: up to +11 %).
TEST_F(ClearSky, SpecularChainIsTheRadianceAtRoughness0AndIrradianceOverPiAtRoughness1) {
  const std::vector<Cubemap> chain = PrefilterSpecular(*cube_, {6, 256});
  ASSERT_EQ(chain.size(), 6u);
  for (int f = 0; f < kCubeFaceCount; ++f) EXPECT_EQ(chain[0].faces[f].pixels, cube_->faces[f].pixels);
  const Cubemap& last = chain.back();
  double worst = 0.0;
  for (int f = 0; f < kCubeFaceCount; ++f) {
    for (int j = 0; j < last.face_size; ++j) {
      for (int i = 0; i < last.face_size; ++i) {
        const glm::dvec3 n = CubeFaceDirection(static_cast<CubeFace>(f), (i + 0.5) / last.face_size, (j + 0.5) / last.face_size);
        const glm::dvec3 e = CubemapIrradiance(*cube_, n) / kPi;
        const Image& face = last.faces[f];
        const glm::dvec3 v(face.at(i, j, 0), face.at(i, j, 1), face.at(i, j, 2));
        const double error = Luminance(v.x, v.y, v.z) / Luminance(e.x, e.y, e.z) - 1.0;
        if (std::abs(error) > std::abs(worst)) worst = error;
      }
    }
  }
  std::printf("roughness 1 against E(n) / pi over the last level: worst %+.2f %%\n", 100.0 * worst);
  EXPECT_LT(std::abs(worst), 0.15);
  Cubemap smooth(64, 3);
  for (int f = 0; f < kCubeFaceCount; ++f) {
    for (int j = 0; j < 64; ++j) {
      for (int i = 0; i < 64; ++i) {
        const glm::dvec3 d = CubeFaceDirection(static_cast<CubeFace>(f), (i + 0.5) / 64, (j + 0.5) / 64);
        for (int c = 0; c < 3; ++c) smooth.faces[f].at(i, j, c) = static_cast<float>(1.0 + d.y);
      }
    }
  }
  const std::vector<Cubemap> smooth_chain = PrefilterSpecular(smooth, {7, 256});
  const Cubemap& top = smooth_chain.back();
  for (int f = 0; f < kCubeFaceCount; ++f) {
    const glm::dvec3 n = CubeFaceDirection(static_cast<CubeFace>(f), 0.5, 0.5);
    const double error = top.faces[f].at(0, 0, 0) - CubemapIrradiance(smooth, n).x / kPi;
    std::printf("  smooth sky, face %d: roughness 1 minus E / pi = %+.4f (sky mean 1)\n", f, error);
    EXPECT_LT(std::abs(error), 0.05) << f;
  }
}

}  // namespace
}  // namespace atmo
