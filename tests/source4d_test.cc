// Model source4d (docs/models/source4d.md): its quadrature, its two gathering paths, its single
// scattering against the reference's deterministic quadrature, its sky and ground irradiance
// against the reference path tracer, and its stability.

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <memory>
#include <string>
#include <vector>

#include <gtest/gtest.h>

#include "atmo/error.h"
#include "atmo/model.h"
#include "atmo/parameters.h"
#include "atmo/render.h"
#include "atmo/spectrum.h"
#include "cpu/path_tracer.h"
#include "cpu/source4d_tables.h"
#include "models/source4d_model.h"
#include "physics/shared_parameters.h"
#include "shared/shared.h"

namespace atmo {
namespace {

constexpr double kPi = 3.14159265358979323846;

glm::dvec3 Direction(double zenith_deg, double azimuth_deg) {
  return DirectionFromZenithAzimuth(glm::radians(zenith_deg), glm::radians(azimuth_deg));
}

std::unique_ptr<Source4dModel> MakeSource4d(const AtmosphereParameters& p, const ModelOptions& options = {}) {
  auto model = CreateModel("source4d", p, options);
  return std::unique_ptr<Source4dModel>(static_cast<Source4dModel*>(model.release()));
}

// The phase functions' first moment <nu> = integral of p(nu) nu over the sphere, by a fine
// 1D quadrature: what the quadrature matrix must give for the incident field L(w) = w.z.
double FirstMoment(const shared::AtmosphereParameters& a, bool mie) {
  constexpr int n = 200000;
  double sum = 0.0;
  for (int i = 0; i < n; ++i) {
    const double nu = -1.0 + (i + 0.5) * 2.0 / n;
    sum += (mie ? shared::GetMiePhase(a, nu) : shared::GetRayleighPhase(a, nu)) * nu;
  }
  return sum * 2.0 * kPi * 2.0 / n;
}

TEST(Source4dQuadrature, ReproducesThePhaseFunctionsFirstMomentAndTheCosineIntegral) {
  const shared::AtmosphereParameters a = ToSharedParameters(Preset("earth"), 0);
  const cpu::Source4dSettings s;
  const cpu::Source4dQuadrature q = cpu::ComputeSource4dQuadrature(a, s);
  ASSERT_EQ(q.out_count, s.mu_size * s.phi_size);
  ASSERT_EQ(q.in_count, s.gather_zeniths * s.gather_azimuths);
  std::vector<double> cosine(q.in_count);
  for (int ab = 0; ab < q.in_count; ++ab) cosine[ab] = std::cos(kPi * (ab / s.gather_azimuths) / (s.gather_zeniths - 1));
  const double rayleigh = FirstMoment(a, false);
  const double mie = FirstMoment(a, true);
  EXPECT_NEAR(rayleigh, 0.0, 1e-9);
  EXPECT_GT(mie, 0.5);  // the forward peak
  for (int cd = 0; cd < q.out_count; ++cd) {
    const double mu = std::cos(kPi * (cd / s.phi_size) / (s.mu_size - 1));
    double g_r = 0.0, g_m = 0.0, sum_r = 0.0, sum_m = 0.0;
    for (int ab = 0; ab < q.in_count; ++ab) {
      g_r += q.rayleigh[cd * q.in_count + ab] * cosine[ab];
      g_m += q.mie[cd * q.in_count + ab] * cosine[ab];
      sum_r += q.rayleigh[cd * q.in_count + ab];
      sum_m += q.mie[cd * q.in_count + ab];
    }
    // Funk-Hecke: integral of p(v.w) (w.z) dw = <nu> (v.z).
    EXPECT_NEAR(g_r, rayleigh * mu, 2e-3) << cd;
    EXPECT_NEAR(g_m, mie * mu, 3e-3) << cd;
    EXPECT_NEAR(sum_r, 1.0, 1e-5);
    EXPECT_NEAR(sum_m, 1.0, 1e-5);
  }
  // The ground's weights: integral of cos over the upper hemisphere is pi, of cos^2 is 2 pi / 3.
  double e_1 = 0.0, e_cos = 0.0;
  for (int ab = 0; ab < q.in_count; ++ab) {
    e_1 += q.irradiance[ab];
    e_cos += q.irradiance[ab] * cosine[ab];
    if (cosine[ab] < -1e-12) {
      EXPECT_EQ(q.irradiance[ab], 0.0);
    }
  }
  EXPECT_NEAR(e_1, kPi, 1e-9);
  EXPECT_NEAR(e_cos, 2.0 * kPi / 3.0, 2e-3);
}

// The Rayleigh matrix's rank-5 form (the products use it) equals the matrix to float rounding,
// for Rayleigh's phase function, the modified Rayleigh one and the isotropic one.
TEST(Source4dQuadrature, RayleighMatrixIsItsRankFiveProduct) {
  const cpu::Source4dSettings s;
  for (PhaseFunction phase : {PhaseFunction::kRayleigh, PhaseFunction::kModifiedRayleigh, PhaseFunction::kIsotropic}) {
    AtmosphereParameters p = Preset("earth");
    p.rayleigh.phase = phase;
    const cpu::Source4dQuadrature q = cpu::ComputeSource4dQuadrature(ToSharedParameters(p, 0), s);
    ASSERT_EQ(q.rayleigh_out.size(), static_cast<std::size_t>(q.out_count) * cpu::kSource4dRayleighRank);
    ASSERT_EQ(q.rayleigh_in.size(), static_cast<std::size_t>(q.in_count) * cpu::kSource4dRayleighRank);
    double largest_difference = 0.0;  // relative to each row's largest weight
    for (int cd = 0; cd < q.out_count; ++cd) {
      float row_max = 0.0f;
      for (int ab = 0; ab < q.in_count; ++ab) row_max = std::max(row_max, q.rayleigh[cd * q.in_count + ab]);
      for (int ab = 0; ab < q.in_count; ++ab) {
        double product = 0.0;
        for (int t = 0; t < cpu::kSource4dRayleighRank; ++t) {
          product += double(q.rayleigh_out[cd * cpu::kSource4dRayleighRank + t]) * q.rayleigh_in[t * q.in_count + ab];
        }
        const double difference = std::fabs(product - q.rayleigh[cd * q.in_count + ab]) / row_max;
        largest_difference = std::max(largest_difference, difference);
      }
    }
    EXPECT_LT(largest_difference, 1e-5) << static_cast<int>(phase);
  }
}

// The gathering paths that do the sun-independent work once per ray give the general march's
// values: order 1 (single scattering; the pairs with a shadow edge on the ray take the general
// march, the others share the ray's steps) and order 2 (the table's lookups, per step one 2D slice
// of both tables, float exp and float sums), with sun zeniths from 0 to 120 degrees.
TEST(Source4dTables, SharedGeometryGatherEqualsThePerRayMarch) {
  AtmosphereParameters p = Preset("earth");
  p.ground_albedo = {0.3, 0.3, 0.3};
  const shared::AtmosphereParameters a = ToSharedParameters(p, 0);
  cpu::Source4dSettings s;
  s.r_size = 6;
  s.mu_size = 8;
  s.mu_s_size = 10;
  s.phi_size = 4;
  s.gather_zeniths = 9;
  s.gather_azimuths = 5;
  s.orders = 3;
  cpu::Source4dTables tables;
  cpu::ComputeSource4dTables(a, s, tables);
  for (int order : {1, 2}) {
    const std::vector<float> general = cpu::GatherSource4dOrder(a, s, tables, order, false);
    const std::vector<float> shared_geometry = cpu::GatherSource4dOrder(a, s, tables, order, true);
    ASSERT_EQ(general.size(), shared_geometry.size());
    double largest = 0.0;
    for (float v : general) largest = std::max(largest, double(v));
    ASSERT_GT(largest, 0.0);
    // Order 1 computes its coordinates in double as the general march does; orders >= 2 compute
    // the sun's row and azimuth in float (measured: 1.1e-4 at worst on this coarse grid, where ln G
    // changes fastest between its 10 sun-zenith rows).
    const double tolerance = order == 1 ? 1e-5 : 2e-4;
    for (std::size_t k = 0; k < general.size(); ++k) {
      EXPECT_NEAR(shared_geometry[k], general[k], tolerance * std::abs(general[k]) + 1e-9 * largest)
          << "order " << order << ", value " << k;
    }
  }
}

// The sun-zenith axis's knots (60, 84, 104 degrees) lie on rows for every table size, so that the
// lookups' linear interpolation between two rows is linear in the sun zenith; and the mapping runs
// monotonically from 0 (sun at the zenith) to 1 (120 degrees) and back.
TEST(Source4dTables, SunZenithKnotsLieOnRows) {
  for (int rows : {8, 11, 16, 21, 47, 48, 64, 100, 512}) {
    for (double knot : {shared::kSource4dSunKnot1, shared::kSource4dSunKnot2, shared::kSource4dSunKnot3}) {
      const double row = shared::GetSource4dSunRow(rows, std::cos(knot)) - 0.5;
      EXPECT_NEAR(row, std::round(row), 1e-4) << rows << " rows, knot " << glm::degrees(knot);
      EXPECT_NEAR(shared::GetSource4dSunZenithFromUnit(std::round(row) / (rows - 1), rows), knot, 1e-12);
    }
    EXPECT_NEAR(shared::GetSource4dUnitFromSunZenith(0.0, rows), 0.0, 1e-12);
    EXPECT_NEAR(shared::GetSource4dUnitFromSunZenith(shared::kSource4dMaxSunZenith, rows), 1.0, 1e-12);
    double last = -1.0;
    for (int j = 0; j < rows; ++j) {
      const double theta = shared::GetSource4dSunZenithFromUnit(double(j) / (rows - 1), rows);
      EXPECT_GT(theta, last) << rows << " rows, row " << j;
      EXPECT_NEAR(shared::GetSource4dUnitFromSunZenith(theta, rows), double(j) / (rows - 1), 1e-12);
      last = theta;
    }
  }
}

// The zenith sky between the table's rows, against a table of four times as many rows (the
// defaults otherwise): looking up from the ground at sun 58-62, 82-86 and 102-106 degrees (the knots), where
// the zenith sky falls by a decade per 2 degrees at 104. A knot between two rows made the
// interpolation cross the kink and the zenith sky 12 % low at 104 degrees with the default 48 rows;
// on rows, the largest difference is 1.6 % (blue, 104-106 degrees, rows 1.6 degrees apart).
TEST(Source4dModel, SunZenithInterpolationIsSmoothAcrossTheKnots) {
  const AtmosphereParameters p = Preset("earth");
  const ModelOptions common = {{"sky_view", "off"}};
  ModelOptions coarse_options = common, fine_options = common;
  coarse_options["table"] = "16x24x48x8";  // the default
  fine_options["table"] = "16x24x192x8";
  const auto coarse = MakeSource4d(p, coarse_options);
  const auto fine = MakeSource4d(p, fine_options);
  const glm::dvec3 up(0.0, 0.0, 1.0);
  double worst = 0.0;
  for (double centre : {60.0, 84.0, 104.0}) {
    for (double sun = centre - 2.0; sun <= centre + 2.0 + 1e-9; sun += 0.25) {
      std::vector<double> a(3), b(3);
      coarse->View(0.0, Direction(sun, 0.0))->Radiance(up, a);
      fine->View(0.0, Direction(sun, 0.0))->Radiance(up, b);
      for (int k = 0; k < 3; ++k) {
        ASSERT_GT(b[k], 0.0);
        worst = std::max(worst, std::abs(a[k] / b[k] - 1.0));
        EXPECT_NEAR(a[k], b[k], 0.03 * b[k]) << "sun " << sun << ", channel " << k;
      }
    }
  }
  std::printf("source4d: 48 against 192 sun-zenith rows, zenith sky at the knots: max |diff| %.2g\n", worst);
}

// Where the per-view march's 64 steps are short: a grazing ray from 10 km in deep twilight
// (sun 95 degrees, view 92) whose lit part lies beyond the ray's lowest point, 6 km up: the
// quadrature errs by up to 1.2 % in blue there with 64 steps, 0.14 % with 256 (docs/models/source4d.md).
TEST(Source4dModel, GrazingTwilightSingleScatteringConvergesWithSteps) {
  const AtmosphereParameters p = Preset("earth");
  const cpu::PathTracer tracer(p);
  const glm::dvec3 sun = Direction(95.0, 0.0);
  const glm::dvec3 view = Direction(92.0, 0.0);
  std::vector<double> expected(3), coarse(3), fine(3);
  tracer.SingleScattering(tracer.ObserverPosition(10e3), view, sun, 1e-6, expected);
  MakeSource4d(p, {{"orders", "1"}})->View(10e3, sun)->Radiance(view, coarse);
  MakeSource4d(p, {{"orders", "1"}, {"samples", "256"}})->View(10e3, sun)->Radiance(view, fine);
  for (int k = 0; k < 3; ++k) {
    EXPECT_NEAR(coarse[k], expected[k], 1.5e-2 * expected[k]) << k;
    EXPECT_NEAR(fine[k], expected[k], 2e-3 * expected[k]) << k;
    EXPECT_LT(std::abs(fine[k] - expected[k]), std::abs(coarse[k] - expected[k]) + 1e-3 * expected[k]) << k;
  }
}

// Single scattering alone (orders=1) against the reference's deterministic quadrature (adaptive
// Gauss-Legendre with the planet shadow's edges as breakpoints, no table): with the sun up, at
// the horizon, in twilight with the shadow's edge on the ray, from 10 km and from 500 km.
TEST(Source4dModel, SingleScatteringMatchesTheReferenceQuadrature) {
  const AtmosphereParameters p = Preset("earth");
  const auto model = MakeSource4d(p, {{"orders", "1"}});
  const cpu::PathTracer tracer(p);
  struct Case {
    double altitude_m, sun_zenith, view_zenith, azimuth;
  };
  for (const Case& c : {Case{0, 45, 60, 90}, Case{0, 30, 0, 0}, Case{0, 85, 89, 0}, Case{0, 85, 89, 180},
                        Case{0, 94, 80, 0}, Case{0, 96, 60, 0}, Case{0, 96, 89.5, 30}, Case{10e3, 60, 120, 90},
                        Case{10e3, 94, 80, 0}, Case{500e3, 60, 110, 0}, Case{500e3, 80, 111, 10}}) {
    const glm::dvec3 sun = Direction(c.sun_zenith, 0.0);
    const glm::dvec3 view = Direction(c.view_zenith, c.azimuth);
    std::vector<double> expected(3), actual(3);
    tracer.SingleScattering(tracer.ObserverPosition(c.altitude_m), view, sun, 1e-6, expected);
    model->View(c.altitude_m, sun)->Radiance(view, actual);
    for (int k = 0; k < 3; ++k) {
      ASSERT_GT(expected[k], 0.0) << c.altitude_m << " " << c.sun_zenith << " " << c.view_zenith;
      EXPECT_NEAR(actual[k], expected[k], 3e-3 * expected[k])
          << c.altitude_m << " m, sun " << c.sun_zenith << ", view " << c.view_zenith << "/" << c.azimuth
          << ", channel " << k;
    }
  }
}

// All orders against the reference path tracer (2^17 paths, standard errors 0.3-0.6 %).
TEST(Source4dModel, RadianceMatchesThePathTracer) {
  AtmosphereParameters p = Preset("earth");
  p.ground_albedo = {0.3, 0.3, 0.3};
  const auto model = MakeSource4d(p);
  const cpu::PathTracer tracer(p);
  struct Case {
    double altitude_m, sun_zenith, view_zenith, azimuth;
  };
  for (const Case& c : {Case{0, 45, 30, 90}, Case{0, 70, 88, 180}, Case{0, 80, 75, 0}, Case{5e3, 60, 120, 90}}) {
    const glm::dvec3 sun = Direction(c.sun_zenith, 0.0);
    cpu::TraceQuery query;
    query.origin = tracer.ObserverPosition(c.altitude_m);
    query.sun = sun;
    query.view = Direction(c.view_zenith, c.azimuth);
    const cpu::PathTally tally = tracer.Trace(query, 11, 0, 1 << 17);
    std::vector<double> actual(3);
    model->View(c.altitude_m, sun)->Radiance(query.view, actual);
    for (int k = 0; k < 3; ++k) {
      const cpu::Estimate e = tally.Get(k, 0);
      EXPECT_NEAR(actual[k], e.mean, 4.0 * e.standard_error + 5e-3 * e.mean)
          << c.altitude_m << " m, sun " << c.sun_zenith << ", view " << c.view_zenith << "/" << c.azimuth
          << ", channel " << k << ": z " << (actual[k] - e.mean) / e.standard_error;
    }
  }
}

// The ground's irradiance table (every order of the sky's light)
// against the reference's flux estimator on the ground (cosine-weighted directions, 4e5 paths).
TEST(Source4dModel, GroundSkyIrradianceMatchesTheReferenceFlux) {
  AtmosphereParameters p = Preset("earth");
  p.ground_albedo = {0.3, 0.3, 0.3};
  const auto model = MakeSource4d(p);
  const cpu::PathTracer tracer(p);
  const Source4dModel::Batch& batch = model->batches()[0];
  for (double sun_zenith : {30.0, 75.0}) {
    const glm::dvec3 sun = Direction(sun_zenith, 0.0);
    const cpu::PathTally tally = tracer.DiffuseIrradiance(tracer.ObserverPosition(0.0), {0.0, 0.0, 1.0}, sun, 5, 400000);
    const glm::dvec3 sky = shared::GetSource4dGroundIrradiance(batch.tables.ground_irradiance, sun.z);
    for (int k = 0; k < 3; ++k) {
      const cpu::Estimate e = tally.Get(k, 0);
      EXPECT_NEAR(sky[k], e.mean, 3.0 * e.standard_error + 1e-2 * e.mean)
          << "sun " << sun_zenith << ", channel " << k;
    }
  }
}

// A hazy atmosphere (Mie x 10) and a white ground: finite, positive radiance everywhere, the sun
// from up to twilight, and ground radiance only below the horizon.
TEST(Source4dModel, HazyAtmosphereAndWhiteGroundStayFiniteAndPositive) {
  AtmosphereParameters p = Preset("earth");
  for (double& s : p.mie.scattering_per_m) s *= 10.0;
  for (double& s : p.mie.absorption_per_m) s *= 10.0;
  p.ground_albedo = {1.0, 1.0, 1.0};
  const auto model = MakeSource4d(p, {{"table", "6x8x10x4"}, {"gather", "13x5"}});
  for (double altitude : {0.0, 2e3, 50e3, 400e3}) {
    for (double sun_zenith : {20.0, 88.0, 100.0}) {
      const auto sky = model->View(altitude, Direction(sun_zenith, 0.0));
      for (double view_zenith : {0.0, 60.0, 89.9, 90.0, 95.0, 150.0, 180.0}) {
        for (double azimuth : {0.0, 90.0, 180.0}) {
          std::vector<double> l(3), g(3);
          const glm::dvec3 view = Direction(view_zenith, azimuth);
          sky->Radiance(view, l);
          sky->GroundRadiance(view, g);
          for (int k = 0; k < 3; ++k) {
            EXPECT_TRUE(std::isfinite(l[k]) && l[k] >= 0.0) << altitude << " " << sun_zenith << " " << view_zenith;
            EXPECT_TRUE(std::isfinite(g[k]) && g[k] >= 0.0);
            if (view_zenith < 90.0 && altitude < 100e3 && sun_zenith < 90.0) {
              EXPECT_GT(l[k], 0.0);
            }
          }
          if (view_zenith <= 90.0 && altitude == 0.0) {
            EXPECT_EQ(g[0], 0.0);
          }
        }
      }
    }
  }
}

// The sky-view table (sky_view=on: every query reads it) against the march of every direction
// (off): the table's resolution and mapping, at the ground, at 10 km and at the top, sun up and in
// twilight. Images (RadianceBatch with the ground) read the table and agree with the march plus
// the lit ground; the mirrored half of the columns mirrors the sky.
TEST(Source4dModel, SkyViewTableMatchesTheMarch) {
  const AtmosphereParameters p = Preset("earth");
  const auto on = MakeSource4d(p, {{"table", "8x12x16x6"}, {"gather", "17x5"}, {"sky_view", "on"}});
  const auto off = MakeSource4d(p, {{"table", "8x12x16x6"}, {"gather", "17x5"}, {"sky_view", "off"}});
  on->Precompute();
  off->Precompute();
  for (double altitude : {0.0, 10e3, 99e3}) {
    std::vector<double> errors;
    for (double sun_zenith : {40.0, 93.0}) {
      const glm::dvec3 sun = Direction(sun_zenith, 0.0);
      const auto table = on->View(altitude, sun);
      const auto march = off->View(altitude, sun);
      std::vector<glm::dvec3> views;
      for (double view_zenith : {3.0, 30.0, 60.0, 80.0, 87.0, 89.5, 91.0, 100.0, 130.0, 170.0}) {
        for (double azimuth : {10.0, 70.0, 135.0, 200.0, 300.0}) views.push_back(Direction(view_zenith, azimuth));
      }
      std::vector<float> batch(3 * views.size());
      table->RadianceBatch(views, RadianceTerms{/*sun_disc=*/false, /*ground=*/true}, batch);
      for (std::size_t i = 0; i < views.size(); ++i) {
        std::vector<double> t(3), m(3), g(3), mirrored(3);
        table->Radiance(views[i], t);
        march->Radiance(views[i], m);
        march->GroundRadiance(views[i], g);
        table->Radiance(glm::dvec3(-views[i].x, views[i].y, views[i].z), mirrored);  // the sun at x = 0
        for (int k = 0; k < 3; ++k) {
          EXPECT_NEAR(mirrored[k], t[k], 1e-5 * t[k]) << altitude << " " << sun_zenith << " " << i;
          if (!(m[k] > 1e-9)) continue;  // the black sky above 99 km in twilight
          errors.push_back(std::fabs(t[k] / m[k] - 1.0));
          // The image path (float lookups, the lit ground from the table): measured up to 1.1 % in
          // the air (10 km, sun 93 degrees, view 87), 4.6 % at 99 km.
          EXPECT_NEAR(batch[3 * i + k], m[k] + g[k], (altitude < 50e3 ? 0.02 : 0.1) * (m[k] + g[k]))
              << altitude << " " << sun_zenith << " " << i;
        }
      }
    }
    ASSERT_GT(errors.size(), 150u);  // from the ground, the views below the horizontal see nothing
    std::sort(errors.begin(), errors.end());
    const double median = errors[errors.size() / 2];
    const double p95 = errors[errors.size() * 95 / 100];
    // Measured: median 0.01-0.03 %, p95 0.1-0.2 % in the air; 1 km below the top, the views just
    // above the horizontal (their path through the air grows fastest with the angle there) err by
    // 4-5 %, the p95.
    EXPECT_LT(median, 1e-3) << altitude << " m, p95 " << p95;
    EXPECT_LT(p95, altitude < 50e3 ? 5e-3 : 0.08) << altitude << " m, median " << median;
  }
}

// The sky-view table's texels are marched when a lookup first needs them: a perspective view
// marches a small part of the table, and its image is the same, bit for bit, as that of a
// view whose whole table was marched first (by an equirectangular image), for every channel
// (two batches) and folded into colour.
TEST(Source4dModel, SkyViewMarchesOnlyTheTexelsAnImageReads) {
  const AtmosphereParameters p = MakeSpectral(Preset("earth"), 6);
  const auto model = MakeSource4d(p, {{"table", "8x12x16x6"}, {"gather", "17x5"}, {"orders", "3"}});
  model->Precompute();
  const glm::dvec3 sun = Direction(80.0, 30.0);
  Camera perspective;
  perspective.kind = CameraKind::kPerspective;
  // Pixels 5 degrees apart, several texels: no pixel's taps are marched for another pixel.
  perspective.width = 12;
  perspective.height = 7;
  perspective.fov_deg = 60.0;
  perspective.yaw_deg = 100.0;  // not towards the sun: no pixel mirrors another
  perspective.pitch_deg = 10.0;
  const RadianceTerms terms{/*sun_disc=*/false, /*ground=*/true};
  const std::vector<double> irradiance(p.channel_count(), 1.0);
  std::vector<glm::vec3> weights;
  for (std::size_t c = 0; c < p.channel_count(); ++c) weights.emplace_back(0.1f * (c + 1), 0.2f, 1.0f / (c + 1));

  const auto lazy = model->View(1000.0, sun);
  const Image lazy_image = RenderView(*lazy, perspective, terms, irradiance);
  const Image lazy_folded = RenderViewFolded(*lazy, perspective, terms, weights);
  const std::size_t marched = Source4dModel::SkyViewTexelsMarched(*lazy);

  // The direction of every texel's centre, which marches the whole table.
  const auto whole = model->View(1000.0, sun);
  const shared::ivec2 size(384, 216);
  const double sun_azimuth = std::atan2(sun.y, sun.x);
  std::vector<glm::dvec3> centres;
  for (int y = 0; y < size.y; ++y) {
    for (int x = 0; x < size.x; ++x) {
      double mu = 0.0;
      double azimuth = 0.0;
      shared::GetViewAnglesFromSkyViewTextureUv(model->batches()[0].atmosphere, size, p.ground_radius_m + 1000.0,
                                                shared::vec2((x + 0.5) / size.x, (y + 0.5) / size.y), mu, azimuth);
      const double sin_theta = std::sqrt(std::max(1.0 - mu * mu, 0.0));
      centres.emplace_back(sin_theta * std::cos(sun_azimuth + azimuth), sin_theta * std::sin(sun_azimuth + azimuth), mu);
    }
  }
  std::vector<float> discarded(centres.size() * p.channel_count());
  whole->RadianceBatch(centres, terms, discarded);
  const std::size_t all = Source4dModel::SkyViewTexelsMarched(*whole);
  const Image whole_image = RenderView(*whole, perspective, terms, irradiance);
  const Image whole_folded = RenderViewFolded(*whole, perspective, terms, weights);

  // 384 x 216 texels, columns 0 .. 192 marched (the others are their mirror images).
  EXPECT_EQ(all, 193u * 216u);
  EXPECT_EQ(Source4dModel::SkyViewTexelsMarched(*whole), all);
  EXPECT_GT(marched, 0u);
  EXPECT_LT(marched, all / 20) << "84 pixels need at most 84 x 9 texels";
  ASSERT_EQ(lazy_image.pixels.size(), whole_image.pixels.size());
  EXPECT_TRUE(lazy_image.pixels == whole_image.pixels);
  EXPECT_TRUE(lazy_folded.pixels == whole_folded.pixels);
  // The folded image is the per-channel one folded (float lookups of the folded table against
  // double lookups of each channel's).
  for (std::size_t i = 0; i < lazy_folded.pixels.size() / 3; ++i) {
    glm::dvec3 folded(0.0);
    for (std::size_t c = 0; c < p.channel_count(); ++c) {
      folded += glm::dvec3(weights[c]) * static_cast<double>(lazy_image.pixels[i * p.channel_count() + c]);
    }
    for (int k = 0; k < 3; ++k) EXPECT_NEAR(lazy_folded.pixels[3 * i + k], folded[k], 1e-4 * folded[k] + 1e-12) << i;
  }
}

TEST(Source4dModel, RefusesBadOptions) {
  const AtmosphereParameters p = Preset("earth");
  EXPECT_THROW(CreateModel("source4d", p, {{"table", "8x8x8"}}), Error);
  EXPECT_THROW(CreateModel("source4d", p, {{"table", "8x8x8x1"}}), Error);
  EXPECT_THROW(CreateModel("source4d", p, {{"table", "8x8x7x8"}}), Error);  // fewer sun-zenith rows than pieces
  EXPECT_THROW(CreateModel("source4d", p, {{"gather", "2x9"}}), Error);
  EXPECT_THROW(CreateModel("source4d", p, {{"orders", "0"}}), Error);
  EXPECT_THROW(CreateModel("source4d", p, {{"tail", "maybe"}}), Error);
  EXPECT_THROW(CreateModel("source4d", p, {{"colour", "red"}}), Error);
  EXPECT_THROW(CreateModel("source4d", p, {{"table", "512x8x512x8"}, {"gather", "512x3"}}), Error);  // 2^27 rays
  EXPECT_THROW(CreateModel("source4d", Preset("simple")), Error);
  try {
    CreateModel("source4d", p, {{"gather", "49xA"}});
    FAIL();
  } catch (const Error& e) {
    EXPECT_NE(std::string(e.what()).find("gather=49xA"), std::string::npos) << e.what();
  }
}

}  // namespace
}  // namespace atmo
