// Model `reference` (cpu/path_tracer.h): the Monte Carlo path tracer against closed forms, its own
// deterministic single-scattering quadrature and conservation laws; exact phase sampling;
// symmetry; determinism. Statistical checks use fixed seeds, so each test is deterministic; the
// tolerance "3 standard errors" would fail with probability ~0.3% per comparison for a random seed.
#include <algorithm>
#include <atomic>
#include <cmath>
#include <cstdio>
#include <random>
#include <string>
#include <vector>

#include <gtest/gtest.h>
#include <oneapi/tbb/global_control.h>

#include "atmo/aerosol.h"
#include "atmo/error.h"
#include "atmo/model.h"
#include "atmo/parameters.h"
#include "atmo/render.h"
#include "atmo/spectrum.h"
#include "cpu/path_tracer.h"
#include "models/reference_model.h"
#include "shared/shared.h"

namespace atmo {
namespace {

constexpr double kPi = 3.14159265358979323846;

glm::dvec3 Direction(double zenith_deg, double azimuth_deg) {
  return DirectionFromZenithAzimuth(glm::radians(zenith_deg), glm::radians(azimuth_deg));
}

std::unique_ptr<ReferenceModel> MakeReference(const AtmosphereParameters& p, ModelOptions options = {}) {
  auto model = CreateModel("reference", p, options);
  return std::unique_ptr<ReferenceModel>(static_cast<ReferenceModel*>(model.release()));
}

const ReferenceSkyView& AsReference(const SkyView& sky) { return static_cast<const ReferenceSkyView&>(sky); }

// Whether |a - b| <= k * standard error.
::testing::AssertionResult WithinErrors(double a, double b, double standard_error, double k = 3.0) {
  if (std::abs(a - b) <= k * standard_error) return ::testing::AssertionSuccess();
  return ::testing::AssertionFailure() << a << " vs " << b << ": difference " << std::abs(a - b) << " = "
                                       << std::abs(a - b) / standard_error << " standard errors (" << standard_error
                                       << ")";
}

// ---------------------------------------------------------------------------------------------
// Phase sampling: chi-square test of the sampled cosines against the pdf.

// Upper quantile of the chi-square distribution with k degrees of freedom (Wilson-Hilferty;
// accurate to ~1% for k >= 30), for the standard normal quantile z.
double ChiSquareQuantile(int k, double z) {
  const double a = 2.0 / (9.0 * k);
  return k * std::pow(1.0 - a + z * std::sqrt(a), 3.0);
}

struct PhaseCase {
  int kind;
  double g;
  const char* name;
};

TEST(ReferencePhaseSampling, CosinesFollowThePhaseFunction) {
  // 64 bins in nu, 400000 samples, significance 0.001 (z = 3.09): the test fails for a correct
  // sampler with probability 0.1% per case (and for this fixed seed, never).
  constexpr int kBins = 64;
  constexpr int kSamples = 400000;
  const double threshold = ChiSquareQuantile(kBins - 1, 3.090232);
  const PhaseCase cases[] = {{shared::kPhaseIsotropic, 0.0, "isotropic"},
                             {shared::kPhaseRayleigh, 0.0, "rayleigh"},
                             {shared::kPhaseModifiedRayleigh, 0.0, "modified rayleigh"},
                             {shared::kPhaseHenyeyGreenstein, 0.7, "HG g=0.7"},
                             {shared::kPhaseHenyeyGreenstein, -0.4, "HG g=-0.4"},
                             {shared::kPhaseCornetteShanks, 0.8, "CS g=0.8"},
                             {shared::kPhaseCornetteShanks, -0.3, "CS g=-0.3"}};
  for (const PhaseCase& c : cases) {
    std::mt19937_64 engine(1234);
    std::uniform_real_distribution<double> uniform(0.0, 1.0);
    std::vector<double> counts(kBins, 0.0);
    double mean_nu = 0.0;
    for (int i = 0; i < kSamples; ++i) {
      const double nu = cpu::PathTracer::SamplePhaseCosine(c.kind, c.g, [&] { return uniform(engine); });
      ASSERT_GE(nu, -1.0);
      ASSERT_LE(nu, 1.0);
      counts[std::min(kBins - 1, static_cast<int>((nu + 1.0) / 2.0 * kBins))] += 1.0;
      mean_nu += nu / kSamples;
    }
    // Expected counts: 2 pi times the integral of the pdf over each bin (Simpson, 64 intervals).
    double chi_square = 0.0;
    for (int b = 0; b < kBins; ++b) {
      const double lo = -1.0 + 2.0 * b / kBins;
      const double h = 2.0 / kBins / 64.0;
      double integral = 0.0;
      for (int j = 0; j < 64; ++j) {
        const double x = lo + j * h;
        integral += h / 6.0 *
                    (shared::EvaluatePhaseFunction(c.kind, c.g, x) +
                     4.0 * shared::EvaluatePhaseFunction(c.kind, c.g, x + 0.5 * h) +
                     shared::EvaluatePhaseFunction(c.kind, c.g, x + h));
      }
      const double expected = 2.0 * kPi * integral * kSamples;
      chi_square += (counts[b] - expected) * (counts[b] - expected) / expected;
    }
    EXPECT_LT(chi_square, threshold) << c.name;
    // The sign convention: for Henyey-Greenstein the mean cosine is g (forward for g > 0).
    if (c.kind == shared::kPhaseHenyeyGreenstein) {
      EXPECT_NEAR(mean_nu, c.g, 0.01) << c.name;
    }
  }
}

TEST(ReferencePhaseSampling, CubicInversionIsExact) {
  for (double u : {0.0, 0.1, 0.37, 0.5, 0.81, 1.0}) {
    const double nu = cpu::PathTracer::SamplePhaseCosine(shared::kPhaseRayleigh, 0.0, [&] { return u; });
    EXPECT_NEAR((nu * nu * nu + 3.0 * nu + 4.0) / 8.0, u, 1e-14);
  }
}

// ---------------------------------------------------------------------------------------------
// Transmittance and single scattering by quadrature.

TEST(ReferenceQuadrature, VerticalTransmittanceMatchesClosedForm) {
  AtmosphereParameters p = Preset("earth");
  p.mie.scattering_per_m = p.mie.absorption_per_m = p.ozone.absorption_per_m = {0.0, 0.0, 0.0};
  cpu::PathTracer tracer(p);
  std::vector<double> t(3);
  tracer.Transmittance(tracer.ObserverPosition(0.0), glm::dvec3(0, 0, 1), t);
  const double column = 8000.0 * (1.0 - std::exp(-100e3 / 8000.0));  // integral of exp(-h/H) over 0..100 km
  for (int c = 0; c < 3; ++c) {
    EXPECT_NEAR(t[c], std::exp(-p.rayleigh.scattering_per_m[c] * column), 1e-12);
  }
}

TEST(ReferenceQuadrature, SingleScatteringConvergesFarBelowTheNoise) {
  auto model = MakeReference(Preset("earth"));
  const cpu::PathTracer& tracer = model->tracer();
  const glm::dvec3 origin = tracer.ObserverPosition(0.0);
  for (const auto& [sun_zenith, view_zenith] : {std::pair{45.0, 60.0}, {85.0, 89.0}, {96.0, 80.0}}) {
    std::vector<double> coarse(3), fine(3);
    tracer.SingleScattering(origin, Direction(view_zenith, 90.0), Direction(sun_zenith, 0.0), 1e-4, coarse);
    tracer.SingleScattering(origin, Direction(view_zenith, 90.0), Direction(sun_zenith, 0.0), 1e-9, fine);
    for (int c = 0; c < 3; ++c) EXPECT_NEAR(coarse[c], fine[c], 2e-4 * fine[c]) << sun_zenith << " " << view_zenith;
  }
}

// ---------------------------------------------------------------------------------------------
// Monte Carlo against closed forms and quadrature.

struct Configuration {
  double altitude_m, sun_zenith_deg, view_zenith_deg, azimuth_deg;
};

TEST(ReferencePathTracer, FirstOrderMatchesSingleScatteringQuadrature) {
  AtmosphereParameters hg = Preset("earth");
  hg.mie.phase = PhaseFunction::kHenyeyGreenstein;
  hg.mie.phase_g = 0.6;
  AtmosphereParameters plus = Preset("atmosphere-plus");
  plus.rayleigh.phase = PhaseFunction::kModifiedRayleigh;
  AtmosphereParameters hazy = Preset("us-standard");
  ApplyAerosol(hazy, {"continental-polluted", 0.6});
  const std::vector<std::pair<AtmosphereParameters, std::vector<Configuration>>> cases = {
      {Preset("earth"),
       {{0.0, 45.0, 60.0, 90.0}, {0.0, 80.0, 88.0, 10.0}, {2000.0, 30.0, 120.0, 150.0}, {5000.0, 94.0, 85.0, 0.0},
        {40e3, 60.0, 20.0, 45.0}, {300e3, 30.0, 110.0, 30.0}}},
      {hg, {{1000.0, 50.0, 70.0, 20.0}}},
      {plus, {{0.0, 70.0, 75.0, 40.0}}},
      // The real-sky media: tabulated air, ozone and OPAC aerosol layers, and a tau 0.6 haze.
      {MakeSpectral(Preset("us-standard"), 3), {{0.0, 80.0, 88.0, 10.0}, {2635.0, 60.0, 0.0, 0.0}}},
      {MakeSpectral(hazy, 3), {{1800.0, 40.0, 95.0, 120.0}}},
  };
  for (const auto& [parameters, configurations] : cases) {
    auto model = MakeReference(parameters, {{"seed", "1"}});
    for (const Configuration& q : configurations) {
      const auto sky = model->View(q.altitude_m, Direction(q.sun_zenith_deg, 0.0));
      const glm::dvec3 view = Direction(q.view_zenith_deg, q.azimuth_deg);
      const OrderEstimate mc = AsReference(*sky).EstimateByOrder(view, 16384);
      std::vector<double> quadrature(3);
      AsReference(*sky).SingleScatteringQuadrature(view, quadrature);
      for (int c = 0; c < 3; ++c) {
        EXPECT_GT(quadrature[c], 0.0);
        EXPECT_TRUE(WithinErrors(mc.orders[c][0].mean, quadrature[c], mc.orders[c][0].standard_error))
            << parameters.name << " altitude " << q.altitude_m << " sun " << q.sun_zenith_deg << " view "
            << q.view_zenith_deg << " azimuth " << q.azimuth_deg << " channel " << c;
      }
    }
  }
}

TEST(ReferencePathTracer, HalfSpaceFirstOrderMatchesTheSimpleAtmosphereClosedForm) {
  // Seed 002 (Simple Atmosphere): homogeneous half-space z < 0, sigma_s = sigma_t = sigma,
  // isotropic phase 1/(4 pi), observer at depth 0.3. With l(p, x) = -<u,p>/<u,x> for <u,x> > 0
  // (infinite otherwise) and f = 1 - d_z / s_z, single scattering is
  //   I = sigma/(4 pi) T(l(p,s)) int_0^{l(p,d)} exp(-sigma f tau) dtau
  //     = 1/(4 pi) exp(-sigma l(p,s)) (1/f) (1 - exp(-sigma f l(p,d))).
  const AtmosphereParameters p = Preset("simple");
  auto model = MakeReference(p, {{"seed", "3"}});
  const double depth = 0.3;
  for (const auto& [sun_zenith, view_zenith, azimuth] :
       {std::tuple{30.0, 70.0, 90.0}, {60.0, 20.0, 180.0}, {75.0, 120.0, 0.0}, {10.0, 170.0, 45.0}}) {
    const glm::dvec3 sun = Direction(sun_zenith, 0.0);
    const glm::dvec3 view = Direction(view_zenith, azimuth);
    const auto sky = model->View(-depth, sun);
    const OrderEstimate mc = AsReference(*sky).EstimateByOrder(view, 16384);
    std::vector<double> quadrature(3);
    AsReference(*sky).SingleScatteringQuadrature(view, quadrature);
    const double f = 1.0 - view.z / sun.z;
    for (int c = 0; c < 3; ++c) {
      const double sigma = p.rayleigh.scattering_per_m[c];
      const double integral = view.z > 0.0 ? (1.0 - std::exp(-sigma * f * depth / view.z)) / f : 1.0 / f;
      const double closed = std::exp(-sigma * depth / sun.z) * integral / (4.0 * kPi);
      EXPECT_NEAR(quadrature[c], closed, 1e-6 * closed) << sun_zenith << " " << view_zenith << " channel " << c;
      EXPECT_TRUE(WithinErrors(mc.orders[c][0].mean, closed, mc.orders[c][0].standard_error))
          << sun_zenith << " " << view_zenith << " channel " << c;
      EXPECT_GT(mc.orders[c][1].mean, 0.0);  // the half-space scatters more than once
    }
  }
}

TEST(ReferencePathTracer, OpticallyThinLimitIsSingleScattering) {
  // All coefficients x1e-3 and x1e-2 (no ground reflection, whose order 2 is not of higher order
  // in the optical depth): order 1 is the quadrature, and order 2 / order 1 scales with the
  // coefficients, i.e. drops tenfold from x1e-2 to x1e-3.
  const auto scaled = [](double k) {
    AtmosphereParameters p = Preset("earth");
    for (Medium* m : {&p.rayleigh, &p.mie, &p.ozone}) {
      for (double& v : m->scattering_per_m) v *= k;
      for (double& v : m->absorption_per_m) v *= k;
    }
    p.ground_albedo = {0.0, 0.0, 0.0};
    return p;
  };
  double ratio[2][3];
  int i = 0;
  for (double k : {1e-2, 1e-3}) {
    auto model = MakeReference(scaled(k), {{"seed", "11"}});
    const auto sky = model->View(0.0, Direction(50.0, 0.0));
    const glm::dvec3 view = Direction(70.0, 60.0);
    const OrderEstimate mc = AsReference(*sky).EstimateByOrder(view, 65536);
    std::vector<double> quadrature(3);
    AsReference(*sky).SingleScatteringQuadrature(view, quadrature);
    for (int c = 0; c < 3; ++c) {
      EXPECT_TRUE(WithinErrors(mc.orders[c][0].mean, quadrature[c], mc.orders[c][0].standard_error)) << k;
      EXPECT_GT(mc.orders[c][1].mean, 5.0 * mc.orders[c][1].standard_error) << "order 2 resolved, x" << k;
      ratio[i][c] = mc.orders[c][1].mean / mc.orders[c][0].mean;
      EXPECT_GT(ratio[i][c], 1e-2 * k) << k;
      EXPECT_LT(ratio[i][c], 1.0 * k) << k;
      std::printf("x%g channel %d: order 2 / order 1 = %.3e\n", k, c, ratio[i][c]);
    }
    ++i;
  }
  for (int c = 0; c < 3; ++c) EXPECT_NEAR(ratio[1][c] / ratio[0][c], 0.1, 0.03) << c;
}

TEST(ReferencePathTracer, ForcedCollisionsDoNotChangeTheExpectation) {
  const AtmosphereParameters p = Preset("earth");
  auto forced = MakeReference(p, {{"seed", "5"}});
  auto analog = MakeReference(p, {{"seed", "6"}, {"forced_collisions", "off"}});
  for (const Configuration& q : {Configuration{0.0, 60.0, 75.0, 30.0}, Configuration{20e3, 92.0, 95.0, 0.0}}) {
    const auto a = forced->View(q.altitude_m, Direction(q.sun_zenith_deg, 0.0));
    const auto b = analog->View(q.altitude_m, Direction(q.sun_zenith_deg, 0.0));
    const glm::dvec3 view = Direction(q.view_zenith_deg, q.azimuth_deg);
    const OrderEstimate ea = AsReference(*a).EstimateByOrder(view, 16384);
    const OrderEstimate eb = AsReference(*b).EstimateByOrder(view, 16384);
    for (int c = 0; c < 3; ++c) {
      const double se = std::hypot(ea.total[c].standard_error, eb.total[c].standard_error);
      EXPECT_TRUE(WithinErrors(ea.total[c].mean, eb.total[c].mean, se)) << q.sun_zenith_deg << " channel " << c;
    }
  }
}

TEST(ReferencePathTracer, ConservesEnergyWithAWhiteGroundAndNoAbsorption) {
  // Power in: pi R_top^2 (unit irradiance on the atmosphere's cross-section). Power out: the
  // scattered and reflected light leaving the top, 4 pi R_top^2 * pi * <L_out> (flux estimator of
  // the tracer, all orders, ground reflections included), plus the unscattered sunlight that
  // crosses the atmosphere without meeting the ground (quadrature). Nothing is absorbed.
  AtmosphereParameters p = Preset("earth");
  p.mie.absorption_per_m = {0.0, 0.0, 0.0};
  p.ozone.absorption_per_m = {0.0, 0.0, 0.0};
  p.ground_albedo = {1.0, 1.0, 1.0};
  cpu::PathTracer tracer(p);
  const cpu::PathTally tally = tracer.TopOutgoingRadiance(Direction(0.0, 0.0), 17, 500000);
  const std::vector<double> direct = tracer.DirectTransmittedPower();
  const double area = 4.0 * kPi * p.top_radius_m * p.top_radius_m * kPi;
  const double incoming = kPi * p.top_radius_m * p.top_radius_m;
  for (int c = 0; c < 3; ++c) {
    const cpu::Estimate e = tally.Get(c, 0);
    const double out = (area * e.mean + direct[c]) / incoming;
    const double se = area * e.standard_error / incoming;
    std::printf("channel %d: power out / power in = %.5f +- %.5f (direct %.4f)\n", c, out, se, direct[c] / incoming);
    EXPECT_NEAR(out, 1.0, 0.01) << c;
    EXPECT_TRUE(WithinErrors(out, 1.0, se)) << c;
    EXPECT_LT(se, 0.0035) << c;  // so that the 1% check above is a 3-standard-error test
  }
}

// ---------------------------------------------------------------------------------------------
// Symmetry, determinism, options, model interface.

TEST(ReferencePathTracer, AzimuthMirrorSymmetry) {
  auto model = MakeReference(Preset("earth"), {{"seed", "9"}});
  const auto sky = model->View(0.0, Direction(70.0, 0.0));
  for (double azimuth : {40.0, 110.0}) {
    const OrderEstimate a = AsReference(*sky).EstimateByOrder(Direction(75.0, azimuth), 16384);
    const OrderEstimate b = AsReference(*sky).EstimateByOrder(Direction(75.0, -azimuth), 16384);
    for (int c = 0; c < 3; ++c) {
      EXPECT_NE(a.total[c].mean, b.total[c].mean);  // independent streams
      EXPECT_TRUE(WithinErrors(a.total[c].mean, b.total[c].mean,
                               std::hypot(a.total[c].standard_error, b.total[c].standard_error)))
          << azimuth << " channel " << c;
    }
  }
}

TEST(ReferencePathTracer, DeterministicForASeedAndAnyThreadCount) {
  const AtmosphereParameters p = Preset("earth");
  const glm::dvec3 view = Direction(80.0, 30.0);
  const auto run = [&](int threads, const char* seed) {
    oneapi::tbb::global_control limit(oneapi::tbb::global_control::max_allowed_parallelism, threads);
    auto model = MakeReference(p, {{"seed", seed}, {"samples", "3000"}});
    const auto sky = model->View(0.0, Direction(60.0, 0.0));
    std::vector<double> l(3), se(3);
    sky->RadianceEstimate(view, l, se);
    l.insert(l.end(), se.begin(), se.end());
    return l;
  };
  const std::vector<double> one = run(1, "42");
  EXPECT_EQ(one, run(2, "42"));
  EXPECT_EQ(one, run(2, "42"));
  const std::vector<double> other = run(2, "43");
  for (int c = 0; c < 3; ++c) EXPECT_NE(one[c], other[c]);
}

TEST(ReferenceModel, TargetRelativeErrorIsReached) {
  auto model = MakeReference(Preset("earth"), {{"samples", "1024"}, {"target_rel_error", "0.02"}});
  const auto sky = model->View(0.0, Direction(45.0, 0.0));
  const OrderEstimate e = AsReference(*sky).EstimateByOrder(Direction(60.0, 90.0));
  EXPECT_GT(e.paths, 1024u);
  for (int c = 0; c < 3; ++c) EXPECT_LE(e.total[c].standard_error, 0.02 * e.total[c].mean);
}

// The tally's variance of the variance from its power sums = the two-pass definition
// sum (x - m)^4 / (sum (x - m)^2)^2 - 1/n, after merging; ~ (kurtosis - 1) / n for a light-tailed
// sample, and near 1 once one value carries the variance.
TEST(ReferenceModel, TallyVarianceOfVarianceIsTheTwoPassValue) {
  std::vector<double> values;
  std::uint64_t state = 12345;
  for (int i = 0; i < 4000; ++i) {
    state = state * 6364136223846793005ull + 1442695040888963407ull;
    const double u = static_cast<double>(state >> 11) * 0x1.0p-53;
    values.push_back(1e-6 * (2.0 + std::log(1.0 - u)));  // shifted exponential, scale 1e-6
  }
  const auto two_pass = [](const std::vector<double>& x) {
    double m = 0.0;
    for (double v : x) m += v;
    m /= static_cast<double>(x.size());
    double s2 = 0.0, s4 = 0.0;
    for (double v : x) {
      s2 += (v - m) * (v - m);
      s4 += (v - m) * (v - m) * (v - m) * (v - m);
    }
    return s4 / (s2 * s2) - 1.0 / static_cast<double>(x.size());
  };
  const auto tally_of = [](const std::vector<double>& x) {
    cpu::PathTally a(1), b(1);
    for (std::size_t i = 0; i < x.size(); ++i) (i % 3 == 0 ? a : b).Add(0, x[i]);
    a.paths = (x.size() + 2) / 3;
    b.paths = x.size() - a.paths;
    a.Merge(b);
    return a.Get(0, 0);
  };
  const cpu::Estimate light = tally_of(values);
  EXPECT_NEAR(light.variance_of_variance, two_pass(values), 1e-9);
  // Exponential: kurtosis 9, so VOV ~ 8 / n.
  EXPECT_NEAR(light.variance_of_variance * 4000.0, 8.0, 3.0);
  values[17] = 1e-2;  // one path 10^4 times the others
  const cpu::Estimate heavy = tally_of(values);
  EXPECT_NEAR(heavy.variance_of_variance, two_pass(values), 1e-9);
  EXPECT_GT(heavy.variance_of_variance, 0.9);
}

// The doubling goes on while the standard error is set by a few paths: with a target the
// estimator meets at once (100 %), max_vov=1 stops at the first count and the default (0.1) only
// where the VOV is at most 0.1 in every channel. In deep twilight (ground, sun 104 deg,
// horizontal view away from the sun) 2048 paths have VOVs of 0.27-0.96, so it runs more paths.
TEST(ReferenceModel, TargetRelativeErrorWaitsForATrustworthyError) {
  const auto run = [](const char* max_vov) {
    auto model = MakeReference(Preset("earth"), {{"samples", "2048"}, {"target_rel_error", "1"},
                                                 {"max_vov", max_vov}, {"max_samples", "65536"}});
    const auto sky = model->View(0.0, Direction(104.0, 0.0));
    return AsReference(*sky).EstimateByOrder(Direction(90.0, 180.0));
  };
  const OrderEstimate off = run("1");
  EXPECT_EQ(off.paths, 2048u);
  const OrderEstimate on = run("0.1");
  EXPECT_GT(on.paths, off.paths);
  if (on.paths < 65536u) {
    for (int c = 0; c < 3; ++c) EXPECT_LE(on.total[c].variance_of_variance, 0.1) << "channel " << c;
  }
}

TEST(ReferenceModel, OptionsAndInputsAreChecked) {
  const AtmosphereParameters p = Preset("earth");
  EXPECT_THROW(CreateModel("reference", p, {{"samples", "0"}}), Error);
  EXPECT_THROW(CreateModel("reference", p, {{"estimator", "magic"}}), Error);
  EXPECT_THROW(CreateModel("reference", p, {{"target_rel_error", "-1"}}), Error);
  EXPECT_THROW(CreateModel("reference", p, {{"max_vov", "0"}}), Error);
  EXPECT_THROW(CreateModel("reference", p, {{"max_vov", "2"}}), Error);
  EXPECT_THROW(CreateModel("reference", p, {{"samples", "100"}, {"max_samples", "10"}}), Error);
  EXPECT_THROW(CreateModel("reference", p, {{"frobnicate", "1"}}), Error);
  auto model = CreateModel("reference", p);
  EXPECT_THROW(model->View(-1.0, Direction(0.0, 0.0)), Error);
  EXPECT_THROW(model->View(0.0, glm::dvec3(0.0)), Error);
}

TEST(ReferenceModel, InterfaceQueries) {
  auto model = MakeReference(Preset("earth"), {{"samples", "256"}});
  const auto sky = model->View(1000.0, Direction(40.0, 0.0));
  std::vector<double> l(3), se(3), t(3);
  // A ray into the ground: transmittance 0, radiance of the air in front of it > 0.
  sky->RadianceEstimate(Direction(120.0, 0.0), l, se);
  sky->Transmittance(Direction(120.0, 0.0), t);
  for (int c = 0; c < 3; ++c) {
    EXPECT_GT(l[c], 0.0);
    EXPECT_GT(se[c], 0.0);
    EXPECT_EQ(t[c], 0.0);
  }
  // The sun disc: at its centre the transmittance times the limb-darkened disc's centre radiance
  // (shared/sun.glsl: irradiance 1), 0 off the disc.
  sky->SunDiscRadiance(Direction(40.0, 0.0), l);
  sky->Transmittance(Direction(40.0, 0.0), t);
  const AtmosphereParameters& p = model->parameters();
  for (int c = 0; c < 3; ++c) {
    const double centre = shared::GetSunDiscCentreRadiance(p.wavelengths_nm[c], p.sun_angular_radius_rad, true);
    EXPECT_NEAR(l[c], t[c] * centre, 1e-9 * l[c]);
  }
  sky->SunDiscRadiance(Direction(50.0, 0.0), l);
  for (int c = 0; c < 3; ++c) EXPECT_EQ(l[c], 0.0);
  // Above the atmosphere: a ray that misses it sees nothing and is not attenuated.
  const auto space = model->View(500e3, Direction(40.0, 0.0));
  space->RadianceEstimate(Direction(10.0, 0.0), l, se);
  space->Transmittance(Direction(10.0, 0.0), t);
  for (int c = 0; c < 3; ++c) {
    EXPECT_EQ(l[c], 0.0);
    EXPECT_EQ(t[c], 1.0);
  }
}

// ---------------------------------------------------------------------------------------------
// The ground term (GroundRadiance, AddPaths with the first ground hit) and progressive rendering.

TEST(ReferenceGround, FirstOrderIsTheSunlitLambertianGround) {
  // Order 1 of the ground-only estimator is the ground's reflection of direct sunlight:
  // albedo / pi * mu_s * T_sun * T_view, with both transmittances by quadrature. T_view (ground
  // point to observer) is T(ground -> top along -view) / T(observer -> top along -view).
  const AtmosphereParameters p = Preset("earth");
  const cpu::PathTracer tracer(p);
  cpu::TraceQuery query;
  query.origin = tracer.ObserverPosition(1000.0);
  query.sun = Direction(50.0, 0.0);
  query.ground_only = true;
  for (const glm::dvec3& view : {Direction(120.0, 30.0), Direction(95.0, 150.0)}) {
    query.view = view;
    const cpu::PathTally tally = tracer.Trace(query, 1, 0, 16384);
    const double b = glm::dot(query.origin, view);
    const double c = glm::dot(query.origin, query.origin) - p.ground_radius_m * p.ground_radius_m;
    const glm::dvec3 x = query.origin + (-b - std::sqrt(b * b - c)) * view;
    const double mu_s = glm::dot(glm::normalize(x), query.sun);
    std::vector<double> t_sun(3), t_ground_up(3), t_observer_up(3);
    tracer.Transmittance(x, query.sun, t_sun);
    tracer.Transmittance(x, -view, t_ground_up);
    tracer.Transmittance(query.origin, -view, t_observer_up);
    for (int ch = 0; ch < 3; ++ch) {
      const double expected = p.ground_albedo[ch] / kPi * mu_s * t_sun[ch] * t_ground_up[ch] / t_observer_up[ch];
      const cpu::Estimate first = tally.Get(ch, 1);
      EXPECT_GT(first.mean, 0.0);
      EXPECT_TRUE(WithinErrors(first.mean, expected, first.standard_error)) << "channel " << ch;
      EXPECT_GT(tally.Get(ch, 2).mean, 0.0);  // sky light reflected by the ground
    }
  }
}

TEST(ReferenceGround, GroundRadianceIsThePartOfTheFirstGroundHit) {
  // Paths that include the view ray's first ground hit estimate Radiance + GroundRadiance; the
  // three estimates use independent streams, so their errors add in quadrature.
  constexpr std::uint64_t kPaths = 8192;
  auto model = MakeReference(Preset("earth"), {{"samples", std::to_string(kPaths)}, {"seed", "3"}});
  const auto sky = model->View(1000.0, Direction(50.0, 0.0));
  const ReferenceSkyView& ref = AsReference(*sky);
  for (const glm::dvec3& view : {Direction(100.0, 0.0), Direction(130.0, 120.0)}) {
    std::vector<double> air(3), air_se(3), ground(3), ground_se(3);
    ref.RadianceEstimate(view, air, air_se);
    ref.GroundRadianceEstimate(view, ground, ground_se);
    cpu::PathTally both(3);
    ref.AddPaths(view, /*ground=*/true, 0, kPaths, both);
    for (std::size_t c = 0; c < 3; ++c) {
      EXPECT_GT(ground[c], 0.0);
      const cpu::Estimate e = both.Get(c, 0);
      EXPECT_TRUE(WithinErrors(e.mean, air[c] + ground[c],
                               std::sqrt(e.standard_error * e.standard_error + air_se[c] * air_se[c] +
                                         ground_se[c] * ground_se[c])))
          << "channel " << c;
    }
  }
  // A ray that misses the ground has no ground term.
  std::vector<double> up(3);
  ref.GroundRadiance(Direction(60.0, 0.0), up);
  for (double v : up) EXPECT_EQ(v, 0.0);
}

TEST(ReferenceRender, GenericRendererShowsTheGround) {
  // Render() adds GroundRadiance to Radiance; the air part uses the same paths with or without
  // the ground, so below the horizon the difference is exactly the (positive) ground term.
  auto model = MakeReference(Preset("earth"), {{"samples", "64"}, {"seed", "1"}});
  RenderSettings s;
  s.camera = {CameraKind::kEquirect, 8, 4};
  s.sun_elevation_deg = 30.0;
  s.terms.sun_disc = false;
  const Image with_ground = Render(*model, s);
  s.terms.ground = false;
  const Image without = Render(*model, s);
  for (int y = 0; y < 4; ++y) {
    for (int x = 0; x < 8; ++x) {
      for (int c = 0; c < 3; ++c) {
        if (y < 2) EXPECT_EQ(with_ground.at(x, y, c), without.at(x, y, c));  // sky
        else EXPECT_GT(with_ground.at(x, y, c), without.at(x, y, c));        // ground
      }
    }
  }
}

ProgressiveImage RenderSmallProgressive(const char* seed, int threads, std::vector<std::uint64_t>* passes = nullptr) {
  oneapi::tbb::global_control limit(oneapi::tbb::global_control::max_allowed_parallelism, threads);
  auto model = MakeReference(Preset("earth"), {{"seed", seed}});
  RenderSettings s;
  s.camera = {CameraKind::kEquirect, 16, 8};
  s.sun_elevation_deg = 30.0;
  ProgressiveSettings p;
  p.samples_per_pixel = 16;
  if (passes != nullptr) p.on_pass = [&](const ProgressiveImage& pass) { passes->push_back(pass.samples_per_pixel); };
  return RenderProgressive(*model, s, p);
}

TEST(ReferenceRender, ProgressivePassesAreTheSameForAnyThreadCount) {
  std::vector<std::uint64_t> passes;
  const ProgressiveImage one = RenderSmallProgressive("42", 1, &passes);
  EXPECT_EQ(passes, (std::vector<std::uint64_t>{4, 8, 16}));
  EXPECT_EQ(one.samples_per_pixel, 16u);
  EXPECT_EQ(one.pass, 3);
  const ProgressiveImage two = RenderSmallProgressive("42", 2);
  EXPECT_EQ(one.radiance.pixels, two.radiance.pixels);
  EXPECT_EQ(one.standard_error.pixels, two.standard_error.pixels);
  const ProgressiveImage other = RenderSmallProgressive("43", 2);
  EXPECT_NE(one.radiance.pixels, other.radiance.pixels);
  for (float se : one.standard_error.pixels) EXPECT_TRUE(std::isfinite(se) && se >= 0.0f);

  const Image exr = WithStandardErrorChannels(one);
  ASSERT_EQ(exr.channels, 6);
  EXPECT_EQ(exr.at(5, 6, exr.ChannelIndex("G")), one.radiance.at(5, 6, 1));
  EXPECT_EQ(exr.at(5, 6, exr.ChannelIndex("stderr.B")), one.standard_error.at(5, 6, 2));
}

// A cancelled render (a viewer restarting) stops and returns the last complete pass: here the
// flag is set from the first pass's callback, so the result is that pass, not the total.
TEST(ReferenceRender, CancelledProgressiveRenderKeepsTheLastCompletePass) {
  RenderSettings s;
  s.camera = {CameraKind::kEquirect, 8, 4};
  auto model = MakeReference(Preset("earth"), {{"samples", "64"}});
  std::atomic<bool> cancel{false};
  ProgressiveSettings p;
  p.cancel = &cancel;
  int passes = 0;
  p.on_pass = [&](const ProgressiveImage&) {
    ++passes;
    cancel = true;
  };
  const ProgressiveImage image = RenderProgressive(*model, s, p);
  EXPECT_EQ(passes, 1);
  EXPECT_EQ(image.samples_per_pixel, 4u);
  EXPECT_EQ(image.radiance.width, 8);
  cancel = true;  // before the first pass: nothing
  EXPECT_EQ(RenderProgressive(*model, s, p).radiance.width, 0);
}

TEST(ReferenceRender, ProgressiveRenderingChecksItsInputs) {
  RenderSettings s;
  s.camera = {CameraKind::kEquirect, 4, 2};
  ProgressiveSettings p;
  const auto simple = CreateModel("simple", Preset("simple"));
  EXPECT_FALSE(IsMonteCarlo(*simple));
  EXPECT_THROW(RenderProgressive(*simple, s, p), Error);
  auto model = MakeReference(Preset("earth"), {{"samples", "8"}});
  EXPECT_TRUE(IsMonteCarlo(*model));
  p.samples_per_pixel = 1;
  EXPECT_THROW(RenderProgressive(*model, s, p), Error);
  p.samples_per_pixel = 0;  // the model's samples: 8, in passes of 4 and 8
  EXPECT_EQ(RenderProgressive(*model, s, p).samples_per_pixel, 8u);
  p.first_pass_samples = 1;
  EXPECT_THROW(RenderProgressive(*model, s, p), Error);
}

}  // namespace
}  // namespace atmo
