// Model `simple` (seed "Simple Atmosphere"): the closed form of src/atmo/shared/simple.glsl against
// numerical integration of its own single-scattering integral, its symmetries and limits, and the
// model built on it (preset `simple`, errors).
#include <algorithm>
#include <cmath>
#include <functional>
#include <random>
#include <string>
#include <vector>

#include <glm/gtc/matrix_transform.hpp>
#include <gtest/gtest.h>

#include "atmo/error.h"
#include "atmo/model.h"
#include "atmo/parameters.h"
#include "shared/shared.h"

namespace atmo {
namespace {

using shared::vec3;

constexpr int kRed = 0;
constexpr int kGreen = 1;
constexpr int kBlue = 2;
constexpr double kPi = 3.14159265358979323846;

// The seed's configuration: sigma = (0.1, 0.3, 0.7) per unit length, no absorption, isotropic.
const vec3 kSeedSigma(0.1, 0.3, 0.7);
vec3 IsotropicBeta(const vec3& sigma_s) { return sigma_s / (4.0 * kPi); }

// A unit vector from its polar angle to `u` and an azimuth about it, in the frame (e1, e2, u).
struct Frame {
  vec3 e1, e2, u;
  vec3 Direction(double zenith_deg, double azimuth_deg) const {
    const double t = glm::radians(zenith_deg);
    const double a = glm::radians(azimuth_deg);
    return std::sin(t) * std::cos(a) * e1 + std::sin(t) * std::sin(a) * e2 + std::cos(t) * u;
  }
};

// A frame with an up vector that is not a coordinate axis, so that the tests exercise the seed's
// general u.
Frame TiltedFrame() {
  const vec3 u = glm::normalize(vec3(0.3, -0.5, 0.8));
  const vec3 e1 = glm::normalize(glm::cross(u, vec3(1.0, 0.0, 0.0)));
  return {e1, glm::cross(u, e1), u};
}

// Reference single scattering for one channel, straight from the seed's integral
//   int beta exp(-sigma (l(q(tau), s) + (tau - tau_in))) dtau over the part of the ray in the medium,
// q(tau) = p + tau d, by globally adaptive Gauss-Legendre quadrature. Written independently of
// simple.glsl: only the geometry of the half-space <u, q> < 0 is used.

// The n-point Gauss-Legendre rule on [-1, 1], nodes by Newton's method on P_n.
struct GaussRule {
  std::vector<double> nodes, weights;
  explicit GaussRule(int n) {
    for (int i = 0; i < n; ++i) {
      double x = std::cos(kPi * (i + 0.75) / (n + 0.5));
      double derivative = 0.0;
      for (int iteration = 0; iteration < 100; ++iteration) {
        double p0 = 1.0, p1 = x;  // P_0, P_1, then the recurrence up to P_n
        for (int k = 2; k <= n; ++k) {
          const double p2 = ((2.0 * k - 1.0) * x * p1 - (k - 1.0) * p0) / k;
          p0 = p1;
          p1 = p2;
        }
        derivative = n * (x * p1 - p0) / (x * x - 1.0);
        const double step = p1 / derivative;
        x -= step;
        if (std::abs(step) < 1e-16) break;
      }
      nodes.push_back(x);
      weights.push_back(2.0 / ((1.0 - x * x) * derivative * derivative));
    }
  }
  double Apply(const std::function<double(double)>& f, double a, double b) const {
    double sum = 0.0;
    for (std::size_t i = 0; i < nodes.size(); ++i) sum += weights[i] * f(0.5 * (a + b) + 0.5 * (b - a) * nodes[i]);
    return 0.5 * (b - a) * sum;
  }
};

// Bisects the interval with the largest error estimate (the rule on it vs on its halves) until the
// estimated total error is below relative_tolerance of the total, or a budget of intervals is spent.
double Integrate(const std::function<double(double)>& f, double a, double b, double relative_tolerance) {
  static const GaussRule rule(10);
  struct Piece {
    double a, b, value, error;
  };
  auto make = [&](double lo, double hi) {
    const double whole = rule.Apply(f, lo, hi);
    const double mid = 0.5 * (lo + hi);
    const double halves = rule.Apply(f, lo, mid) + rule.Apply(f, mid, hi);
    return Piece{lo, hi, halves, std::abs(halves - whole)};
  };
  std::vector<Piece> pieces;
  constexpr int kStart = 16;
  for (int i = 0; i < kStart; ++i) pieces.push_back(make(a + (b - a) * i / kStart, a + (b - a) * (i + 1) / kStart));
  for (int round = 0; round < 20000; ++round) {
    double total = 0.0, error = 0.0;
    std::size_t worst = 0;
    for (std::size_t i = 0; i < pieces.size(); ++i) {
      total += pieces[i].value;
      error += pieces[i].error;
      if (pieces[i].error > pieces[worst].error) worst = i;
    }
    if (error <= relative_tolerance * std::abs(total)) return total;
    const Piece split = pieces[worst];
    const double mid = 0.5 * (split.a + split.b);
    pieces[worst] = make(split.a, mid);
    pieces.push_back(make(mid, split.b));
  }
  ADD_FAILURE() << "quadrature did not converge";
  return 0.0;
}

double QuadratureRadiance(const vec3& u, const vec3& p, const vec3& d, const vec3& s, double sigma_t, double beta) {
  const double mu = glm::dot(u, d), mu_s = glm::dot(u, s), height = glm::dot(u, p);
  if (mu_s <= 0.0) return 0.0;  // no sunlight below the plane
  double tau_in = 0.0;
  if (height > 0.0) {
    if (mu >= 0.0) return 0.0;
    tau_in = height / -mu;
  }
  // Out of the medium at the plane, or earlier where the light that still comes back is below
  // exp(-40) of the total: the integrand falls at least as fast as exp(-sigma (tau - tau_in)).
  const double cutoff = tau_in + 40.0 / sigma_t;
  const double tau_out = mu > 0.0 ? std::min(-height / mu, cutoff) : cutoff;
  auto integrand = [&](double tau) {
    const vec3 q = p + tau * d;
    const double sun_path = std::max(-glm::dot(u, q), 0.0) / mu_s;
    return beta * std::exp(-sigma_t * (sun_path + (tau - tau_in)));
  };
  return Integrate(integrand, tau_in, tau_out, 1e-12);
}

// Closed form vs QuadratureRadiance: the quadrature stops at an estimated 1e-12 relative error
// (its tail cut-off adds exp(-40) = 4e-18); the closed form is exact up to rounding and the series
// of G below x = 0.01 (< 1.4e-13). 1e-11 leaves room for both, and still catches the series
// truncated one term earlier (8e-11).
constexpr double kQuadratureTolerance = 1e-11;

// The closed form with the model's conventions, for tests that give u explicitly.
vec3 ClosedForm(const vec3& u, const vec3& p, const vec3& d, const vec3& s, const vec3& sigma_t, const vec3& beta) {
  return shared::ComputeSimpleScatteredRadiance(u, p, d, s, sigma_t, beta);
}

// --- The closed form against its integral -----------------------------------------------------

TEST(SimpleClosedForm, MatchesQuadratureOfItsIntegral) {
  const Frame frame = TiltedFrame();
  // Absorption in two channels: extinction in every transmittance, scattering only where light
  // scatters; beta stands for any phase function value (constant along the ray).
  const vec3 sigma_t = kSeedSigma + vec3(0.0, 0.05, 0.2);
  const vec3 beta = IsotropicBeta(kSeedSigma) * 1.7;
  int cases = 0;
  for (double height : {-0.3, -2.0, -1e-3, 0.0, 0.5}) {
    const vec3 p = height * frame.u + 0.7 * frame.e1 - 0.2 * frame.e2;  // any point at that height
    for (double sun_zenith : {0.0, 30.0, 60.0, 85.0, 89.5}) {
      const vec3 s = frame.Direction(sun_zenith, 40.0);
      // View zeniths below the sun's give f < 0, equal ones f = 0 (at the sun's azimuth), those
      // past 90 degrees look down (infinite path).
      for (double view_zenith : {0.0, 10.0, 29.0, 45.0, 60.0, 80.0, 89.0, 90.0, 91.0, 120.0, 180.0}) {
        // A ray along the plane from on or above it is ill-posed: <u, d> = +-6e-17 from rounding
        // decides whether and (from above) how far away, up to 1e16, it enters the medium.
        if (height >= 0.0 && view_zenith == 90.0) continue;
        for (double azimuth : {40.0, 130.0, 220.0}) {
          const vec3 d = frame.Direction(view_zenith, azimuth);
          const vec3 closed = ClosedForm(frame.u, p, d, s, sigma_t, beta);
          for (int c = 0; c < 3; ++c) {
            const double reference = QuadratureRadiance(frame.u, p, d, s, sigma_t[c], beta[c]);
            EXPECT_NEAR(closed[c], reference, kQuadratureTolerance * reference + 1e-15)
                << "height " << height << " sun zenith " << sun_zenith << " view zenith " << view_zenith
                << " azimuth " << azimuth << " channel " << c;
            ++cases;
          }
        }
      }
    }
  }
  EXPECT_EQ(cases, (5 * 11 - 2) * 5 * 3 * 3);
}

TEST(SimpleClosedForm, FNearZeroIsTheLimitNotADivisionByZero) {
  // f = 1 - <u,d>/<u,s> within 1e-6 of 0 on either side, and exactly 0: looking along a
  // direction as steep as the sun's. The limit is beta L exp(-sigma_t L), L = l(p, d) = l(p, s).
  const Frame frame = TiltedFrame();
  const vec3 p = -0.3 * frame.u;
  const vec3 s = frame.Direction(50.0, 0.0);
  const double mu_s = glm::dot(frame.u, s);
  const vec3 beta = IsotropicBeta(kSeedSigma);
  for (double f : {-1e-6, -1e-9, 0.0, 1e-9, 1e-6}) {
    const double mu = (1.0 - f) * mu_s;
    const vec3 d = frame.Direction(glm::degrees(std::acos(mu)), 120.0);
    const vec3 closed = ClosedForm(frame.u, p, d, s, kSeedSigma, beta);
    const double length = 0.3 / mu;
    for (int c = 0; c < 3; ++c) {
      ASSERT_TRUE(std::isfinite(closed[c]));
      const double limit = beta[c] * length * std::exp(-kSeedSigma[c] * length);
      // |f| <= 1e-6 moves the result by about sigma L |f| / 2 relative: below 1e-6.
      EXPECT_NEAR(closed[c], limit, 1e-6 * limit) << "f " << f;
      const double reference = QuadratureRadiance(frame.u, p, d, s, kSeedSigma[c], beta[c]);
      EXPECT_NEAR(closed[c], reference, kQuadratureTolerance * reference) << "f " << f;
    }
  }
}

TEST(SimpleClosedForm, InvariantUnderARotationOfTheWholeConfiguration) {
  std::mt19937_64 rng(7);
  std::uniform_real_distribution<double> uniform(-1.0, 1.0);
  auto random_unit = [&] {
    vec3 v;
    do v = vec3(uniform(rng), uniform(rng), uniform(rng));
    while (glm::length(v) < 0.1 || glm::length(v) > 1.0);
    return glm::normalize(v);
  };
  const vec3 sigma_t = kSeedSigma + vec3(0.02);
  const vec3 beta = IsotropicBeta(kSeedSigma);
  for (int i = 0; i < 200; ++i) {
    const vec3 u(0.0, 0.0, 1.0);
    const vec3 p(uniform(rng), uniform(rng), 2.0 * uniform(rng) - 0.5);  // mostly inside, some above
    const vec3 d = random_unit();
    const vec3 s = random_unit();
    // A random rotation: axis and angle.
    const glm::dmat3 rotation = glm::dmat3(glm::rotate(glm::dmat4(1.0), 3.0 * uniform(rng), random_unit()));
    const vec3 a = ClosedForm(u, p, d, s, sigma_t, beta);
    const vec3 b = ClosedForm(rotation * u, rotation * p, rotation * d, rotation * s, sigma_t, beta);
    const vec3 ta = shared::GetSimpleViewTransmittance(u, p, d, sigma_t);
    const vec3 tb = shared::GetSimpleViewTransmittance(rotation * u, rotation * p, rotation * d, sigma_t);
    for (int c = 0; c < 3; ++c) {
      // The rotated dot products differ by rounding (~1e-16); near-grazing rays amplify that
      // through 1/<u,d>, hence 1e-9 rather than machine precision.
      EXPECT_NEAR(a[c], b[c], 1e-9 * a[c] + 1e-15) << "case " << i;
      EXPECT_NEAR(ta[c], tb[c], 1e-9) << "case " << i;
    }
  }
}

TEST(SimpleClosedForm, VanishesLinearlyAsTheMediumThinsOnAFinitePath) {
  // Looking up, I = beta L (1 + O(sigma L)): halving sigma (and beta with it) halves I in the limit.
  const vec3 u(0.0, 0.0, 1.0);
  const vec3 p(0.0, 0.0, -0.3);
  const vec3 s = glm::normalize(vec3(0.0, 1.0, 1.0));
  for (const vec3& d : {vec3(0.0, 0.0, 1.0), glm::normalize(vec3(1.0, 0.0, 0.2)), glm::normalize(vec3(0.0, 1.0, 3.0))}) {
    const double length = 0.3 / d.z;
    for (double scale : {1e-3, 1e-6, 1e-9}) {
      const vec3 sigma = scale * kSeedSigma;
      const vec3 radiance = ClosedForm(u, p, d, s, sigma, IsotropicBeta(sigma));
      for (int c = 0; c < 3; ++c) {
        const double thin = IsotropicBeta(sigma)[c] * length;  // the optically thin limit
        // The first correction is of relative size sigma (L + l(p, s)) < 2 sigma max(L, 0.43).
        EXPECT_NEAR(radiance[c], thin, 2.0 * sigma[c] * std::max(length, 0.43) * thin) << "scale " << scale;
      }
    }
  }
}

TEST(SimpleClosedForm, LookingDownIsIndependentOfTheDensity) {
  // An infinite path sees I = (beta / sigma_t) T(l(p, s)) / f: as the medium thins this tends to
  // (beta / sigma_t) / f, not 0: the half-space is infinitely thick. Observer on the plane, so
  // that l(p, s) = 0 and the value is exact at every scale.
  const vec3 u(0.0, 0.0, 1.0);
  const vec3 p(0.0, 0.0, 0.0);
  const vec3 s = glm::normalize(vec3(0.0, 1.0, 1.0));
  const vec3 d = glm::normalize(vec3(1.0, 0.0, -2.0));
  const double f = 1.0 - d.z / s.z;
  for (double scale : {1.0, 1e-3, 1e-9}) {
    const vec3 sigma = scale * kSeedSigma;
    const vec3 radiance = ClosedForm(u, p, d, s, sigma, IsotropicBeta(sigma));
    // Rounding only.
    for (int c = 0; c < 3; ++c) EXPECT_NEAR(radiance[c], 1.0 / (4.0 * kPi * f), 1e-14) << "scale " << scale;
  }
}

TEST(SimpleClosedForm, NoLightWithTheSunBelowThePlane) {
  const Frame frame = TiltedFrame();
  // (Not 90 degrees: cos(pi / 2) is 6e-17 in floating point, a sun just above the plane.)
  for (double sun_zenith : {90.001, 90.5, 120.0, 180.0}) {
    const vec3 s = frame.Direction(sun_zenith, 10.0);
    for (double view_zenith : {0.0, 45.0, 90.0, 135.0, 180.0}) {
      for (double height : {-0.3, 0.2}) {
        const vec3 radiance = ClosedForm(frame.u, height * frame.u, frame.Direction(view_zenith, 100.0), s,
                                         kSeedSigma, IsotropicBeta(kSeedSigma));
        EXPECT_EQ(radiance, vec3(0.0)) << "sun zenith " << sun_zenith << " view zenith " << view_zenith;
      }
    }
  }
  // A sun exactly in the plane: l(p, s) is infinite, no light either.
  for (const vec3& d : {vec3(0, 0, 1), vec3(0, 0, -1), vec3(1, 0, 0)}) {
    EXPECT_EQ(ClosedForm(vec3(0, 0, 1), vec3(0, 0, -0.3), d, vec3(0, 1, 0), kSeedSigma, IsotropicBeta(kSeedSigma)),
              vec3(0.0));
  }
}

TEST(SimpleClosedForm, ObserverAboveThePlaneSeesWhatAnObserverOnItSees) {
  // Vacuum above the plane: looking down from height h equals looking down from the entry point;
  // looking up sees nothing.
  const Frame frame = TiltedFrame();
  const vec3 s = frame.Direction(30.0, 0.0);
  const vec3 beta = IsotropicBeta(kSeedSigma);
  for (double view_zenith : {95.0, 135.0, 180.0}) {
    const vec3 d = frame.Direction(view_zenith, 70.0);
    const vec3 above = 5.0 * frame.u;
    const vec3 entry = above + (5.0 / -glm::dot(frame.u, d)) * d;
    const vec3 a = ClosedForm(frame.u, above, d, s, kSeedSigma, beta);
    const vec3 b = ClosedForm(frame.u, entry, d, s, kSeedSigma, beta);
    for (int c = 0; c < 3; ++c) EXPECT_NEAR(a[c], b[c], 1e-12 * b[c]);
  }
  EXPECT_EQ(ClosedForm(frame.u, 5.0 * frame.u, frame.Direction(60.0, 0.0), s, kSeedSigma, beta), vec3(0.0));
  EXPECT_EQ(ClosedForm(frame.u, 5.0 * frame.u, frame.Direction(90.0, 0.0), s, kSeedSigma, beta), vec3(0.0));
}

TEST(SimpleClosedForm, ContinuousAcrossTheHorizon) {
  // Just above the horizon the finite path is very long and f -> 1; just below it is infinite:
  // both tend to (beta / sigma_t) T(l(p, s)).
  const vec3 u(0.0, 0.0, 1.0);
  const vec3 p(0.0, 0.0, -0.3);
  const vec3 s = glm::normalize(vec3(0.0, 1.0, 1.0));
  const vec3 beta = IsotropicBeta(kSeedSigma);
  const vec3 up = ClosedForm(u, p, glm::normalize(vec3(1.0, 0.0, 1e-7)), s, kSeedSigma, beta);
  const vec3 flat = ClosedForm(u, p, vec3(1.0, 0.0, 0.0), s, kSeedSigma, beta);
  const vec3 down = ClosedForm(u, p, glm::normalize(vec3(1.0, 0.0, -1e-7)), s, kSeedSigma, beta);
  for (int c = 0; c < 3; ++c) {
    const double limit = std::exp(-kSeedSigma[c] * 0.3 / s.z) / (4.0 * kPi);
    // Above: the path is 3e6 long, so its end contributes exp(-3e5) = 0; f differs from 1 by
    // 1.4e-7. Below: f = 1 + 1.4e-7. Both within 1e-6 of the limit.
    EXPECT_NEAR(up[c], limit, 1e-6 * limit);
    EXPECT_NEAR(flat[c], limit, 1e-14);
    EXPECT_NEAR(down[c], limit, 1e-6 * limit);
  }
}

TEST(SimpleClosedForm, SegmentsAddUp) {
  // L(p) = L_segment(p, t) + T(t) L(p + t d): the segment integral and the whole ray agree, in
  // every branch (finite path, infinite path, from above the plane).
  const Frame frame = TiltedFrame();
  const vec3 sigma_t = kSeedSigma + vec3(0.01, 0.0, 0.1);
  const vec3 beta = IsotropicBeta(kSeedSigma);
  const vec3 s = frame.Direction(55.0, 0.0);
  for (double height : {-0.3, 0.4}) {
    for (double view_zenith : {20.0, 55.0, 80.0, 100.0, 170.0}) {
      const vec3 p = height * frame.u;
      const vec3 d = frame.Direction(view_zenith, 30.0);
      const vec3 whole = ClosedForm(frame.u, p, d, s, sigma_t, beta);
      for (double t : {0.05, 0.2, 0.7, 3.0}) {
        vec3 transmittance;
        const vec3 near =
            shared::ComputeSimpleScatteringAlongSegment(frame.u, p, d, s, sigma_t, beta, t, transmittance);
        const vec3 far = ClosedForm(frame.u, p + t * d, d, s, sigma_t, beta);
        for (int c = 0; c < 3; ++c) {
          // Rounding only.
          EXPECT_NEAR(near[c] + transmittance[c] * far[c], whole[c], 1e-12 * whole[c] + 1e-16)
              << "height " << height << " view zenith " << view_zenith << " t " << t;
        }
      }
    }
  }
}

TEST(SimpleClosedForm, TransmittanceAlongTheViewRay) {
  const Frame frame = TiltedFrame();
  const vec3 inside = -0.3 * frame.u;
  for (double view_zenith : {0.0, 30.0, 80.0}) {
    const vec3 t = shared::GetSimpleViewTransmittance(frame.u, inside, frame.Direction(view_zenith, 5.0), kSeedSigma);
    const double length = 0.3 / std::cos(glm::radians(view_zenith));
    for (int c = 0; c < 3; ++c) EXPECT_NEAR(t[c], std::exp(-kSeedSigma[c] * length), 1e-14);
  }
  // Infinite paths (the contract's "0 where the ray meets the ground"), inside and from above.
  for (double view_zenith : {90.0, 120.0, 180.0}) {
    EXPECT_EQ(shared::GetSimpleViewTransmittance(frame.u, inside, frame.Direction(view_zenith, 5.0), kSeedSigma),
              vec3(0.0));
    EXPECT_EQ(shared::GetSimpleViewTransmittance(frame.u, 2.0 * frame.u, frame.Direction(view_zenith + 0.5, 5.0),
                                                 kSeedSigma),
              vec3(0.0));
  }
  // Rays that never meet the medium, and a ray from the plane straight out.
  EXPECT_EQ(shared::GetSimpleViewTransmittance(frame.u, 2.0 * frame.u, frame.Direction(60.0, 5.0), kSeedSigma),
            vec3(1.0));
  EXPECT_EQ(shared::GetSimpleViewTransmittance(frame.u, vec3(0.0), frame.Direction(60.0, 5.0), kSeedSigma),
            vec3(1.0));
}

// --- The model on preset `simple` --------------------------------------------------------------

class SimplePreset : public ::testing::Test {
 protected:
  static void SetUpTestSuite() { model_ = CreateModel("simple", Preset("simple")).release(); }
  static void TearDownTestSuite() { delete model_; }
  static Model* model_;

  static std::vector<double> Query(void (SkyView::*query)(const glm::dvec3&, std::span<double>) const,
                                   const SkyView& sky, const glm::dvec3& view) {
    std::vector<double> out(sky.channel_count());
    (sky.*query)(view, out);
    return out;
  }
  static std::vector<double> Radiance(const SkyView& sky, double zenith_deg, double azimuth_deg) {
    return Query(&SkyView::Radiance, sky, DirectionFromZenithAzimuth(glm::radians(zenith_deg), glm::radians(azimuth_deg)));
  }
  static glm::dvec3 Sun(double zenith_deg) { return DirectionFromZenithAzimuth(glm::radians(zenith_deg), 0.0); }
};
Model* SimplePreset::model_ = nullptr;

TEST_F(SimplePreset, IsTheSeedsConfiguration) {
  const AtmosphereParameters& p = model_->parameters();
  EXPECT_EQ(p.observer_altitude_m, -0.3);
  EXPECT_EQ(model_->name(), "simple");
  // The model through its interface equals the closed form with u = z and p = (0, 0, -0.3).
  const auto sky = model_->View(p.observer_altitude_m, Sun(40.0));
  const glm::dvec3 d = DirectionFromZenithAzimuth(glm::radians(70.0), glm::radians(25.0));
  const auto radiance = Query(&SkyView::Radiance, *sky, d);
  const vec3 closed = ClosedForm(vec3(0, 0, 1), vec3(0, 0, -0.3), d, Sun(40.0), kSeedSigma, IsotropicBeta(kSeedSigma));
  for (int c = 0; c < 3; ++c) EXPECT_DOUBLE_EQ(radiance[c], closed[c]);
}

TEST_F(SimplePreset, ZenithIsBlueAndTheHorizonAWhiteBand) {
  // What the closed form gives for the seed's sky (sun 45 degrees high), per channel:
  //   zenith:  beta L exp(-sigma min(L, l_s)) G(..), L = 0.3: thin, so proportional to sigma: blue;
  //   horizon: the path is long and f -> 1, so I -> (1 / 4 pi) T(l(p, s)): close to 1 / (4 pi) in
  //            every channel (white), and brighter than the zenith.
  const auto sky = model_->View(-0.3, Sun(45.0));
  const auto zenith = Radiance(*sky, 0.0, 90.0);
  const auto horizon = Radiance(*sky, 89.999, 90.0);
  EXPECT_GT(zenith[kBlue], zenith[kGreen]);
  EXPECT_GT(zenith[kGreen], zenith[kRed]);
  EXPECT_GT(zenith[kBlue] / zenith[kRed], 3.0 * horizon[kBlue] / horizon[kRed]);
  const double sun_path = 0.3 / std::cos(glm::radians(45.0));
  for (int c = 0; c < 3; ++c) {
    EXPECT_GT(horizon[c], zenith[c]);
    // 0.001 degrees above the horizon the path is 1.7e4 long (its far end contributes nothing) and
    // f = 1 - 2.5e-5: the limit within 1e-4.
    const double limit = std::exp(-kSeedSigma[c] * sun_path) / (4.0 * kPi);
    EXPECT_NEAR(horizon[c], limit, 1e-4 * limit);
  }
}

TEST_F(SimplePreset, FiniteAndNonNegativeEverywhere) {
  std::mt19937_64 rng(11);
  std::uniform_real_distribution<double> uniform(-1.0, 1.0);
  for (int i = 0; i < 50; ++i) {
    const glm::dvec3 sun = glm::normalize(glm::dvec3(uniform(rng), uniform(rng), uniform(rng)));
    const double altitude = i % 5 == 0 ? 0.0 : (i % 5 == 1 ? 0.5 : -0.3);
    const auto sky = model_->View(altitude, sun);
    for (int j = 0; j < 200; ++j) {
      glm::dvec3 d(uniform(rng), uniform(rng), uniform(rng));
      if (glm::length(d) < 1e-3) continue;
      d = glm::normalize(d);
      for (auto query : {&SkyView::Radiance, &SkyView::Transmittance, &SkyView::SunDiscRadiance}) {
        for (double v : Query(query, *sky, d)) {
          ASSERT_TRUE(std::isfinite(v) && v >= 0.0) << "sun " << sun.x << "," << sun.y << "," << sun.z;
        }
      }
    }
    // Exactly along the plane, straight up and down, and at the sun.
    for (const glm::dvec3& d : {glm::dvec3(1, 0, 0), glm::dvec3(0, 0, 1), glm::dvec3(0, 0, -1), sun}) {
      for (double v : Query(&SkyView::Radiance, *sky, d)) ASSERT_TRUE(std::isfinite(v) && v >= 0.0);
    }
  }
}

TEST_F(SimplePreset, SunDiscIsTheAttenuatedUnitIrradianceDisc) {
  const double alpha = model_->parameters().sun_angular_radius_rad;
  // The limb-darkened disc of unit irradiance (shared/sun.glsl): centre radiance L_c = 1 / (solid
  // angle x the disc's mean limb darkening), so L_c x solid angle x mean = 1.
  std::vector<double> solid_angle(3);
  for (int c = 0; c < 3; ++c) {
    solid_angle[c] = 2.0 * kPi * (1.0 - std::cos(alpha)) *
                     shared::GetSunDiscMeanLimbDarkening(model_->parameters().wavelengths_nm[c], alpha, true);
  }
  const auto sky = model_->View(-0.3, Sun(30.0));
  const auto disc = Query(&SkyView::SunDiscRadiance, *sky, Sun(30.0));
  const auto transmittance = Query(&SkyView::Transmittance, *sky, Sun(30.0));
  const auto edge_in = Query(&SkyView::SunDiscRadiance, *sky,
                             DirectionFromZenithAzimuth(glm::radians(30.0) + 0.99 * alpha, 0.0));
  const auto edge_out = Query(&SkyView::SunDiscRadiance, *sky,
                              DirectionFromZenithAzimuth(glm::radians(30.0) + 1.01 * alpha, 0.0));
  for (int c = 0; c < 3; ++c) {
    // Solid angle times radiance is the irradiance 1, attenuated by T(l(p, s)) = exp(-sigma 0.3 / cos 30).
    EXPECT_NEAR(disc[c] * solid_angle[c], transmittance[c], 1e-9);
    EXPECT_NEAR(transmittance[c], std::exp(-kSeedSigma[c] * 0.3 / std::cos(glm::radians(30.0))), 1e-14);
    // At 0.99 alpha the limb darkening at mu = sqrt(1 - 0.99^2) (the view transmittance barely changes).
    const double f = shared::GetSunLimbDarkening(model_->parameters().wavelengths_nm[c], std::sqrt(1.0 - 0.99 * 0.99));
    EXPECT_NEAR(edge_in[c], f * disc[c], 2e-3 * disc[c]);
    EXPECT_EQ(edge_out[c], 0.0);
  }
  // From above the plane the disc is unattenuated; a sun below the plane seen from inside is not seen.
  const auto above = model_->View(1.0, Sun(30.0));
  const auto unattenuated = Query(&SkyView::SunDiscRadiance, *above, Sun(30.0));
  for (int c = 0; c < 3; ++c) EXPECT_NEAR(unattenuated[c] * solid_angle[c], 1.0, 1e-9);
  const auto night = model_->View(-0.3, Sun(120.0));
  for (double v : Query(&SkyView::SunDiscRadiance, *night, Sun(120.0))) EXPECT_EQ(v, 0.0);
}

TEST_F(SimplePreset, SegmentOfTheWholeRayIsTheRadiance) {
  const auto sky = model_->View(-0.3, Sun(60.0));
  const glm::dvec3 d = DirectionFromZenithAzimuth(glm::radians(50.0), glm::radians(20.0));
  std::vector<double> radiance(3), transmittance(3);
  sky->ScatteringAlongSegment(d, 10.0, radiance, transmittance);  // past the boundary at 0.47
  const auto whole = Query(&SkyView::Radiance, *sky, d);
  const auto t = Query(&SkyView::Transmittance, *sky, d);
  for (int c = 0; c < 3; ++c) {
    EXPECT_NEAR(radiance[c], whole[c], 1e-15);
    EXPECT_NEAR(transmittance[c], t[c], 1e-15);
  }
}

// --- Other media, channels and errors ---------------------------------------------------------

TEST(SimpleModel, UsesEachMediumsPhaseFunctionAndAbsorption) {
  AtmosphereParameters p = Preset("simple");
  p.rayleigh.phase = PhaseFunction::kRayleigh;
  p.mie.scattering_per_m = {0.05, 0.05, 0.05};
  p.mie.absorption_per_m = {0.01, 0.01, 0.01};
  p.mie.phase = PhaseFunction::kHenyeyGreenstein;
  p.mie.phase_g = 0.7;
  p.ozone.absorption_per_m = {0.02, 0.04, 0.0};
  const auto model = CreateModel("simple", p);
  const glm::dvec3 sun = DirectionFromZenithAzimuth(glm::radians(50.0), 0.0);
  const auto sky = model->View(-0.3, sun);
  const glm::dvec3 d = DirectionFromZenithAzimuth(glm::radians(30.0), glm::radians(60.0));
  std::vector<double> radiance(3);
  sky->Radiance(d, radiance);
  const double nu = glm::dot(d, sun);
  const double rayleigh = 3.0 / (16.0 * kPi) * (1.0 + nu * nu);
  const double hg = (1.0 - 0.49) / (4.0 * kPi * std::pow(1.0 + 0.49 - 1.4 * nu, 1.5));
  for (int c = 0; c < 3; ++c) {
    const double sigma_t = p.rayleigh.scattering_per_m[c] + 0.06 + p.ozone.absorption_per_m[c];
    const double beta = p.rayleigh.scattering_per_m[c] * rayleigh + 0.05 * hg;
    const double reference =
        QuadratureRadiance(vec3(0, 0, 1), vec3(0, 0, -0.3), d, sun, sigma_t, beta);
    EXPECT_NEAR(radiance[c], reference, kQuadratureTolerance * reference);
  }
}

TEST(SimpleModel, AnyNumberOfChannels) {
  AtmosphereParameters p = Preset("simple");
  p.wavelengths_nm = {700.0, 600.0, 500.0, 400.0};
  p.rayleigh.scattering_per_m = {0.1, 0.2, 0.4, 0.8};
  p.rayleigh.absorption_per_m = {0.0, 0.0, 0.0, 0.0};
  for (Medium* m : {&p.mie, &p.ozone}) {
    m->scattering_per_m = {0.0, 0.0, 0.0, 0.0};
    m->absorption_per_m = {0.0, 0.0, 0.0, 0.0};
  }
  p.ground_albedo = {0.0, 0.0, 0.0, 0.0};
  p.solar_irradiance = {1.0, 1.0, 1.0, 1.0};
  const auto model = CreateModel("simple", p);
  const glm::dvec3 sun = DirectionFromZenithAzimuth(glm::radians(40.0), 0.0);
  const auto sky = model->View(-0.3, sun);
  std::vector<double> radiance(4);
  sky->Radiance(glm::dvec3(0, 0, 1), radiance);
  for (int c = 0; c < 4; ++c) {
    const double sigma = p.rayleigh.scattering_per_m[c];
    const double reference = QuadratureRadiance(vec3(0, 0, 1), vec3(0, 0, -0.3), vec3(0, 0, 1), sun, sigma,
                                                sigma / (4.0 * kPi));
    EXPECT_NEAR(radiance[c], reference, kQuadratureTolerance * reference) << "channel " << c;
  }
}

TEST(SimpleModel, RejectsWhatItCannotHandle) {
  auto message = [](const std::function<void()>& f) {
    try {
      f();
    } catch (const Error& e) {
      return std::string(e.what());
    }
    return std::string("no error");
  };
  // A spherical preset: the message names it and points to hillaire.
  const std::string spherical = message([] { CreateModel("simple", Preset("earth")); });
  EXPECT_NE(spherical.find("earth"), std::string::npos) << spherical;
  EXPECT_NE(spherical.find("hillaire"), std::string::npos) << spherical;
  // Options: none but the common seed.
  EXPECT_NO_THROW(CreateModel("simple", Preset("simple"), {{"seed", "42"}}));
  const std::string option = message([] { CreateModel("simple", Preset("simple"), {{"samples", "8"}}); });
  EXPECT_NE(option.find("samples"), std::string::npos) << option;
  EXPECT_NE(option.find("seed"), std::string::npos) << option;
  // A density that varies inside the half-space.
  AtmosphereParameters varying = Preset("simple");
  varying.rayleigh.density.lower.linear_term_per_m = 0.1;
  varying.rayleigh.density.lower.constant_term = 0.5;
  EXPECT_THROW(CreateModel("simple", varying), Error);
  // Views.
  const auto model = CreateModel("simple", Preset("simple"));
  EXPECT_THROW(model->View(std::nan(""), glm::dvec3(0, 0, 1)), Error);
  EXPECT_THROW(model->View(-0.3, glm::dvec3(0.0)), Error);
  EXPECT_NO_THROW(model->View(2.0, glm::dvec3(0, 0, 1)));  // above the plane is allowed
}

TEST(SimpleModel, IsListed) {
  const std::vector<std::string> names = ModelNames();
  EXPECT_NE(std::find(names.begin(), names.end(), "simple"), names.end());
}

}  // namespace
}  // namespace atmo
