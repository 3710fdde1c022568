// Tests of the GLSL/C++ common subset against closed forms: geometry, phase functions, table
// mappings and transmittance.
#include <cmath>
#include <cstdio>
#include <random>

#include <gtest/gtest.h>

#include "shared/shared.h"
#include "test_atmospheres.h"

namespace atmo::shared {
namespace {

using testing::EarthLike;
using testing::SmallHomogeneous;

// ---------------------------------------------------------------------------------------------
// Geometry

TEST(Geometry, VerticalRaysMatchClosedForm) {
  const AtmosphereParameters a = EarthLike();
  for (double altitude : {0.0, 1.0, 1000.0, 50e3, 99e3}) {
    const double r = a.bottom_radius + altitude;
    EXPECT_NEAR(DistanceToTopAtmosphereBoundary(a, r, 1.0), a.top_radius - r, 1e-6);
    EXPECT_NEAR(DistanceToTopAtmosphereBoundary(a, r, -1.0), a.top_radius + r, 1e-6);
    EXPECT_TRUE(RayIntersectsGround(a, r, -1.0));
    EXPECT_NEAR(DistanceToBottomAtmosphereBoundary(a, r, -1.0), altitude, 1e-6);
  }
}

TEST(Geometry, HorizontalRaysMatchClosedForm) {
  const AtmosphereParameters a = EarthLike();
  for (double altitude : {0.0, 1.0, 1000.0, 50e3}) {
    const double r = a.bottom_radius + altitude;
    // Pythagoras: the horizontal ray is tangent to the sphere of radius r.
    EXPECT_NEAR(DistanceToTopAtmosphereBoundary(a, r, 0.0), std::sqrt(a.top_radius * a.top_radius - r * r), 1e-6);
    EXPECT_FALSE(RayIntersectsGround(a, r, 0.0));
  }
}

TEST(Geometry, GrazingGroundDistanceIsAccurate) {
  // From 1 m above the ground, a ray just below the horizon meets the ground; the distance must
  // satisfy |x + t v| = R to a relative precision far beyond what the naive formula gives in float.
  const AtmosphereParameters a = EarthLike();
  const double r = a.bottom_radius + 1.0;
  const double mu_h = CosineOfHorizonZenith(a, r);
  for (double delta : {1e-9, 1e-7, 1e-5, 1e-3}) {
    const double mu = mu_h - delta;
    ASSERT_TRUE(RayIntersectsGround(a, r, mu));
    const double t = DistanceToBottomAtmosphereBoundary(a, r, mu);
    const double r_end = std::sqrt(t * t + 2.0 * r * mu * t + r * r);
    EXPECT_NEAR(r_end, a.bottom_radius, 1e-6) << "delta " << delta;
  }
  // Just above the horizon the ray misses the ground.
  EXPECT_FALSE(RayIntersectsGround(a, r, mu_h + 1e-9));
}

TEST(Geometry, HorizonDipsWithAltitude) {
  const AtmosphereParameters a = EarthLike();
  EXPECT_NEAR(CosineOfHorizonZenith(a, a.bottom_radius), 0.0, 1e-12);
  double previous = 0.0;
  for (double altitude : {1e3, 10e3, 100e3, 1000e3}) {
    const double mu_h = CosineOfHorizonZenith(a, a.bottom_radius + altitude);
    EXPECT_LT(mu_h, previous);
    previous = mu_h;
  }
}

TEST(Geometry, AtmosphereEntryFromSpace) {
  const AtmosphereParameters a = EarthLike();
  const double r = a.top_radius + 1000e3;
  EXPECT_NEAR(DistanceToAtmosphereEntry(a, r, -1.0), 1000e3, 1e-6);
  EXPECT_LT(DistanceToAtmosphereEntry(a, r, 0.0), 0.0);  // looking sideways misses
  EXPECT_LT(DistanceToAtmosphereEntry(a, r, 1.0), 0.0);  // looking up misses
}

// ---------------------------------------------------------------------------------------------
// Phase functions: each integrates to 1 over the sphere.

double IntegrateOverSphere(int kind, double g) {
  // Gauss-free midpoint rule in nu = cos(theta); the azimuth integral is 2 pi.
  const int n = 200000;
  double sum = 0.0;
  for (int i = 0; i < n; ++i) {
    const double nu = -1.0 + (i + 0.5) * 2.0 / n;
    sum += EvaluatePhaseFunction(kind, g, nu);
  }
  return sum * 2.0 / n * 2.0 * kPi;
}

TEST(PhaseFunction, EachIntegratesToOne) {
  EXPECT_NEAR(IntegrateOverSphere(kPhaseIsotropic, 0.0), 1.0, 1e-9);
  EXPECT_NEAR(IntegrateOverSphere(kPhaseRayleigh, 0.0), 1.0, 1e-9);
  EXPECT_NEAR(IntegrateOverSphere(kPhaseModifiedRayleigh, 0.0), 1.0, 1e-9);
  // Strongly peaked lobes need the fine grid; 1e-4 is the midpoint rule's error at g = 0.9.
  for (double g : {-0.7, 0.0, 0.5, 0.8, 0.9}) {
    EXPECT_NEAR(IntegrateOverSphere(kPhaseCornetteShanks, g), 1.0, 1e-4) << "g " << g;
    EXPECT_NEAR(IntegrateOverSphere(kPhaseHenyeyGreenstein, g), 1.0, 1e-4) << "g " << g;
  }
}

TEST(PhaseFunction, PositiveGPeaksTowardsTheSun) {
  EXPECT_GT(CornetteShanksPhaseFunction(0.8, 1.0), 100.0 * CornetteShanksPhaseFunction(0.8, -1.0));
  EXPECT_GT(HenyeyGreensteinPhaseFunction(0.8, 1.0), 100.0 * HenyeyGreensteinPhaseFunction(0.8, -1.0));
  EXPECT_NEAR(RayleighPhaseFunction(1.0), RayleighPhaseFunction(-1.0), 1e-15);
}

// ---------------------------------------------------------------------------------------------
// Table mappings: uv -> parameters -> uv round trips.

TEST(TransmittanceLut, UvRoundTrip) {
  const AtmosphereParameters a = EarthLike();
  const ivec2 size(256, 64);
  for (double u = 0.5 / 256; u < 1.0; u += 0.037) {
    for (double v = 0.5 / 64; v < 1.0; v += 0.041) {
      double r, mu;
      GetRMuFromTransmittanceTextureUv(a, size, vec2(u, v), r, mu);
      const vec2 uv = GetTransmittanceTextureUvFromRMu(a, size, r, mu);
      EXPECT_NEAR(uv.x, u, 1e-6);
      EXPECT_NEAR(uv.y, v, 1e-9);
    }
  }
}

TEST(TransmittanceLut, BoundsMapToTexelCentres) {
  const AtmosphereParameters a = EarthLike();
  const ivec2 size(256, 64);
  // Ground level looking at the horizon: first texel centre in u; straight up: last one... in x_mu
  // terms straight up is d = d_min, i.e. u = 0.5 / width.
  vec2 uv = GetTransmittanceTextureUvFromRMu(a, size, a.bottom_radius, 1.0);
  EXPECT_NEAR(uv.x, 0.5 / 256, 1e-12);
  EXPECT_NEAR(uv.y, 0.5 / 64, 1e-12);
  uv = GetTransmittanceTextureUvFromRMu(a, size, a.bottom_radius, 0.0);
  EXPECT_NEAR(uv.x, 1.0 - 0.5 / 256, 1e-9);
  uv = GetTransmittanceTextureUvFromRMu(a, size, a.top_radius, 1.0);
  EXPECT_NEAR(uv.y, 1.0 - 0.5 / 64, 1e-12);
}

TEST(MultipleScatteringLut, UvRoundTrip) {
  const AtmosphereParameters a = EarthLike();
  const ivec2 size(32, 32);
  for (double u = 0.5 / 32; u < 1.0; u += 0.05) {
    for (double v = 0.5 / 32; v < 1.0; v += 0.05) {
      double r, mu_s;
      GetRMuSFromMultiScatteringTextureUv(a, size, vec2(u, v), r, mu_s);
      const vec2 uv = GetMultiScatteringTextureUvFromRMuS(a, size, r, mu_s);
      EXPECT_NEAR(uv.x, u, 1e-12);
      EXPECT_NEAR(uv.y, v, 1e-12);
    }
  }
}

TEST(SkyViewLut, UvRoundTripAtSeveralAltitudes) {
  const AtmosphereParameters a = EarthLike();
  const ivec2 size(192, 108);
  for (double altitude : {0.0, 10.0, 1e3, 30e3, 99e3}) {
    const double r = a.bottom_radius + altitude;
    for (double u = 0.5 / 192; u < 1.0; u += 0.031) {
      for (double v = 0.5 / 108; v < 1.0; v += 0.029) {
        double mu, azimuth;
        GetViewAnglesFromSkyViewTextureUv(a, size, r, vec2(u, v), mu, azimuth);
        const vec2 uv = GetSkyViewTextureUvFromViewAngles(a, size, r, mu, azimuth);
        EXPECT_NEAR(uv.x, u, 1e-9);
        // Between the two halves' outer texel centres (|v - 0.5| < 0.5 / height) lies no direction:
        // the forward mapping never lands there.
        if (std::abs(v - 0.5) >= 0.5 / 108) {
          EXPECT_NEAR(uv.y, v, 1e-6) << "altitude " << altitude << " v " << v;
        }
      }
    }
  }
}

TEST(SkyViewLut, HorizonSplitsTheRowsAndFollowsTheDip) {
  const AtmosphereParameters a = EarthLike();
  const ivec2 size(192, 108);
  for (double altitude : {0.0, 100.0, 10e3, 80e3}) {
    const double r = a.bottom_radius + altitude;
    const double mu_h = CosineOfHorizonZenith(a, r);
    // The horizon is the last sky row's centre (a ray along it is a sky ray) and just below it
    // the first ground row's: filtering never blends the two halves.
    EXPECT_NEAR(GetSkyViewTextureUvFromViewAngles(a, size, r, mu_h + 1e-12, 0.0).y * size.y - 0.5, 53.0, 1e-3);
    EXPECT_NEAR(GetSkyViewTextureUvFromViewAngles(a, size, r, mu_h - 1e-12, 0.0).y * size.y - 0.5, 54.0, 1e-3);
    // Zenith at the top row's centre, nadir at the bottom row's.
    EXPECT_NEAR(GetSkyViewTextureUvFromViewAngles(a, size, r, 1.0, 0.0).y, 0.5 / 108, 1e-9);
    EXPECT_NEAR(GetSkyViewTextureUvFromViewAngles(a, size, r, -1.0, 0.0).y, 1.0 - 0.5 / 108, 1e-9);
  }
}

// ---------------------------------------------------------------------------------------------
// Transmittance

TEST(Transmittance, HomogeneousVerticalMatchesBeerLambert) {
  const AtmosphereParameters a = SmallHomogeneous();
  const vec3 t = ComputeTransmittanceToTopAtmosphereBoundary(a, a.bottom_radius, 1.0, 50);
  for (int c = 0; c < 3; ++c) EXPECT_NEAR(t[c], std::exp(-a.rayleigh_scattering[c] * 100.0), 1e-12);
}

TEST(Transmittance, QuadratureConverges) {
  // Over altitudes and zenith angles of Earth (rays that miss the ground), 40 intervals of the
  // quadratic substitution agree with 20000 to 2.5e-3 absolute (the ozone tent's kinks dominate),
  // and the error falls as intervals are added.
  const AtmosphereParameters a = EarthLike();
  double worst_40 = 0.0, worst_160 = 0.0;
  for (double altitude : {0.0, 1e3, 10e3, 30e3, 99e3}) {
    const double r = a.bottom_radius + altitude;
    for (double zenith = 0.0; zenith <= 180.0; zenith += 2.5) {
      const double mu = std::cos(glm::radians(zenith));
      if (RayIntersectsGround(a, r, mu)) continue;
      const vec3 fine = ComputeTransmittanceToTopAtmosphereBoundary(a, r, mu, 20000);
      const vec3 t40 = ComputeTransmittanceToTopAtmosphereBoundary(a, r, mu, 40);
      const vec3 t160 = ComputeTransmittanceToTopAtmosphereBoundary(a, r, mu, 160);
      for (int c = 0; c < 3; ++c) {
        worst_40 = std::max(worst_40, std::abs(t40[c] - fine[c]));
        worst_160 = std::max(worst_160, std::abs(t160[c] - fine[c]));
      }
    }
  }
  EXPECT_LT(worst_40, 2.5e-3);
  EXPECT_LT(worst_160, worst_40 / 4.0);
}

// Fills a transmittance table the way the CPU backend does.
Texture2D MakeTransmittanceTable(const AtmosphereParameters& a, ivec2 size, int samples) {
  Texture2D t(size.x, size.y);
  for (int y = 0; y < size.y; ++y) {
    for (int x = 0; x < size.x; ++x) {
      t.at(x, y) = glm::vec3(ComputeTransmittanceToTopAtmosphereBoundaryTexel(a, size, vec2(x + 0.5, y + 0.5), samples));
    }
  }
  return t;
}

TEST(TransmittanceLut, MatchesDirectQuadrature) {
  const AtmosphereParameters a = EarthLike();
  const Texture2D table = MakeTransmittanceTable(a, ivec2(256, 64), 40);
  std::mt19937 rng(7);
  std::uniform_real_distribution<double> unit(0.0, 1.0);
  double worst_interpolation = 0.0;
  double worst_total = 0.0;
  for (int i = 0; i < 2000; ++i) {
    const double r = a.bottom_radius + unit(rng) * (a.top_radius - a.bottom_radius);
    const double mu_h = CosineOfHorizonZenith(a, r);
    const double mu = mu_h + unit(rng) * (1.0 - mu_h);
    const vec3 same_quadrature = ComputeTransmittanceToTopAtmosphereBoundary(a, r, mu, 40);
    const vec3 fine_quadrature = ComputeTransmittanceToTopAtmosphereBoundary(a, r, mu, 4000);
    const vec3 looked_up = GetTransmittanceToTopAtmosphereBoundary(a, table, r, mu);
    for (int c = 0; c < 3; ++c) {
      // Absolute errors: near the horizon T is ~1e-4 and a relative error says little.
      worst_interpolation = std::max(worst_interpolation, std::abs(looked_up[c] - same_quadrature[c]));
      worst_total = std::max(worst_total, std::abs(looked_up[c] - fine_quadrature[c]));
    }
  }
  // Bilinear interpolation between 256x64 texels of Bruneton's mapping (float storage included)
  // errs most just above the horizon near the ground, where T changes fastest: 2.2e-3 measured.
  EXPECT_LT(worst_interpolation, 3e-3);
  // With the 40-interval quadrature's own error (<= 2.5e-3, Transmittance.QuadratureConverges),
  // which partly cancels the interpolation's here.
  EXPECT_LT(worst_total, 3e-3);
  std::printf("transmittance table: worst |error| %.2e from interpolation, %.2e in all\n", worst_interpolation,
              worst_total);
}

TEST(Transmittance, IsMultiplicativeAlongARay) {
  // T(a, c) = T(a, b) T(b, c): from the ground at 70 degrees zenith, split at 20 km and 60 km.
  const AtmosphereParameters a = EarthLike();
  const Texture2D table = MakeTransmittanceTable(a, ivec2(256, 64), 40);
  const double r = a.bottom_radius;
  const double mu = std::cos(glm::radians(70.0));
  const double d1 = 20e3, d2 = 60e3;
  const vec3 t_ab = GetTransmittance(a, table, r, mu, d1, false);
  const double r_b = std::sqrt(d1 * d1 + 2.0 * r * mu * d1 + r * r);
  const double mu_b = (r * mu + d1) / r_b;
  const vec3 t_bc = GetTransmittance(a, table, r_b, mu_b, d2 - d1, false);
  const vec3 t_ac = GetTransmittance(a, table, r, mu, d2, false);
  for (int c = 0; c < 3; ++c) EXPECT_NEAR(t_ab[c] * t_bc[c], t_ac[c], 2e-3 * t_ac[c]);
  // And the whole ray to the top is the product of its parts.
  const vec3 t_top = GetTransmittanceToTopAtmosphereBoundary(a, table, r, mu);
  const double r_c = std::sqrt(d2 * d2 + 2.0 * r * mu * d2 + r * r);
  const vec3 t_c_top = GetTransmittanceToTopAtmosphereBoundary(a, table, r_c, (r * mu + d2) / r_c);
  for (int c = 0; c < 3; ++c) EXPECT_NEAR(t_ac[c] * t_c_top[c], t_top[c], 2e-3 * t_top[c]);
}

TEST(Transmittance, IsSymmetric) {
  // T(a, b) = T(b, a): compute by quadrature in both directions on the homogeneous planet and
  // through the table on Earth for a downward ray reversed.
  const AtmosphereParameters a = EarthLike();
  const Texture2D table = MakeTransmittanceTable(a, ivec2(256, 64), 40);
  const double r = a.bottom_radius + 5e3;
  const double mu = std::cos(glm::radians(60.0));
  const double d = 30e3;
  const vec3 forward = GetTransmittance(a, table, r, mu, d, false);
  const double r_d = std::sqrt(d * d + 2.0 * r * mu * d + r * r);
  const double mu_d = (r * mu + d) / r_d;
  // From the far point looking back: direction cosine -mu_d; this ray meets the ground further on.
  const vec3 backward = GetTransmittance(a, table, r_d, -mu_d, d, RayIntersectsGround(a, r_d, -mu_d));
  for (int c = 0; c < 3; ++c) EXPECT_NEAR(forward[c], backward[c], 3e-3 * forward[c]);
}

}  // namespace
}  // namespace atmo::shared

// The CPU renderer's row form of the perspective camera equals the shared per-pixel kernel.
#include "cpu/camera.h"

namespace atmo {
namespace {

TEST(Camera, PerspectiveRowsEqualThePerPixelKernel) {
  for (const Camera& c : {Camera{CameraKind::kPerspective, 64, 36, 90.0, 180.0, 10.0},
                          Camera{CameraKind::kPerspective, 17, 40, 30.0, -45.0, -70.0}}) {
    const shared::CameraParameters camera = ToSharedCamera(c);
    std::vector<glm::dvec3> row(c.width);
    for (int y = 0; y < c.height; ++y) {
      PerspectiveRowDirections(camera, y, row);
      for (int x = 0; x < c.width; ++x) {
        shared::vec3 expected;
        ASSERT_TRUE(shared::GetCameraRayDirection(camera, shared::vec2(x + 0.5, y + 0.5), expected));
        EXPECT_NEAR(glm::length(row[x] - expected), 0.0, 1e-14);
      }
    }
  }
}

TEST(Camera, DirectionsFollowTheConventions) {
  // Perspective: the centre looks at (yaw, pitch); fisheye: zenith at the centre, north up, east
  // left, horizon on the circle; equirect: the centre column at yaw, the top row at the zenith.
  shared::vec3 d;
  const auto perspective = ToSharedCamera(Camera{CameraKind::kPerspective, 2, 2, 60.0, 90.0, 0.0});
  shared::GetCameraRayDirection(perspective, shared::vec2(1.0, 1.0), d);
  EXPECT_NEAR(glm::length(d - glm::dvec3(1.0, 0.0, 0.0)), 0.0, 1e-12);  // east
  const auto fisheye = ToSharedCamera(Camera{CameraKind::kFisheye, 100, 100, 90.0, 0.0, 0.0});
  shared::GetCameraRayDirection(fisheye, shared::vec2(50.0, 50.0), d);
  EXPECT_NEAR(d.z, 1.0, 1e-12);
  shared::GetCameraRayDirection(fisheye, shared::vec2(50.0, 0.0), d);  // top edge: north horizon
  EXPECT_NEAR(glm::length(d - glm::dvec3(0.0, 1.0, 0.0)), 0.0, 1e-12);
  shared::GetCameraRayDirection(fisheye, shared::vec2(0.0, 50.0), d);  // left edge: east horizon
  EXPECT_NEAR(glm::length(d - glm::dvec3(1.0, 0.0, 0.0)), 0.0, 1e-12);
  EXPECT_FALSE(shared::GetCameraRayDirection(fisheye, shared::vec2(1.0, 1.0), d));  // corner
  const auto equirect = ToSharedCamera(Camera{CameraKind::kEquirect, 360, 180, 90.0, 180.0, 0.0});
  shared::GetCameraRayDirection(equirect, shared::vec2(180.0, 90.0), d);
  EXPECT_NEAR(glm::length(d - glm::dvec3(0.0, -1.0, 0.0)), 0.0, 1e-12);  // south
  shared::GetCameraRayDirection(equirect, shared::vec2(10.0, 0.0), d);
  EXPECT_NEAR(d.z, 1.0, 1e-12);
}

}  // namespace
}  // namespace atmo
