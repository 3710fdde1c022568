#include "cpu/path_tracer.h"

#include <atomic>
#include <cstring>
#include <functional>
#include <limits>
#include <mutex>

#include <oneapi/tbb/blocked_range.h>
#include <oneapi/tbb/parallel_for.h>
#include <oneapi/tbb/task_arena.h>

#include "atmo/error.h"
#include "physics/shared_parameters.h"

namespace atmo::cpu {
namespace {

constexpr double kPi = 3.14159265358979323846;
constexpr double kInfinity = std::numeric_limits<double>::infinity();
// Paths per block of the parallel loop; blocks are reduced in index order.
constexpr std::uint64_t kBlockPaths = 128;
// Absolute tolerance on optical depths (unitless) of the adaptive Simpson quadrature: its error
// in a transmittance T is <= T * 1e-10, far below any Monte Carlo noise.
constexpr double kOpticalDepthTolerance = 1e-10;
// Bounds on the loops that depend on the data (docs/reliability.md). The adaptive quadrature
// stops refining a panel at depth 30 or once one integral has spent its evaluations, and never
// asks for less than the rounding error of the panel's own value (a grazing ray over a large
// planet has density samples whose noise is above 1e-10 / 2^k: depth 40 meant 2^40 evaluations,
// the audit's hang of > 100 s). Tracking loops stop after kMaxTrackingSteps tentative
// collisions (the expected count is the majorant's optical depth, < 100 for any real sky) and
// ratio tracking as soon as the transmittance is 0 (with an extinction of 1e300 it reached 0 in
// a few steps and then looped for ever).
constexpr int kMaxQuadratureDepth = 30;
constexpr int kMaxQuadratureEvaluations = 1 << 16;
constexpr double kQuadratureRelativeFloor = 1e-14;
constexpr std::uint64_t kMaxTrackingSteps = std::uint64_t{1} << 24;
// Ratio tracking's running transmittance below which Russian roulette decides (RatioTracking).
constexpr double kRouletteTransmittance = 1e-3;
// The proxy table of SunDensityProxy: 32 radii x 64 zenith cosines in Bruneton's mapping
// (shared/transmittance.glsl), each entry by the trapezoidal rule with 40 intervals about the
// ray's lowest point (the shared quadrature's substitution, which errs by <= 2.5e-3 in
// transmittance there). It steers importance sampling only, so its error costs variance, not bias.
constexpr int kSunProxyR = 32;
constexpr int kSunProxyMu = 64;
constexpr int kSunProxyIntervals = 40;
// Nodes of the piecewise-exponential proposal of SegmentSunlight: 16 intervals about the
// segment's lowest point (t = t_low + x |x|, x uniform), plus the shadow's edges.
constexpr int kSegmentIntervals = 16;
// The proposal is never below this fraction of its largest node value on the lit part, so a
// proxy that is wrong by a large factor somewhere still has a bounded weight there.
constexpr double kProposalFloor = 1e-4;
// Asymmetry of the lobe about the sun that shadow guiding mixes into the phase sampling: by the
// Henyey-Greenstein CDF 75 % of its directions lie within 37 deg of the sun and 90 % within
// 66 deg, which covers where a shadowed vertex finds lit air in twilight (towards the sun,
// 5-20 deg above its direction).
constexpr double kGuideG = 0.8;
// The horizon lobe of shadow guiding, in the local frame of the vertex x (up = x / |x|): azimuth
// about the sun's azimuth and elevation about e0 = -acos((R_ground + h / 2) / |x|) (the ray that
// grazes half the vertex's altitude h), each a two-sided exponential of the given scale truncated
// to its range. In deep twilight (sun 100-108 deg) a vertex near the ground finds lit air only
// along near-horizontal rays towards the sun's azimuth that travel 500-1500 km and cross the
// terminator above 20-60 km (docs/models/reference.md): a band a few degrees high and some tens of
// degrees wide, which the lobe about the sun (whose axis is 10-18 deg below the horizontal there)
// reaches with a few per cent of its draws.
constexpr double kHorizonAzimuthScale = 0.35;   // rad
constexpr double kHorizonElevationScale = 0.035;  // rad
// Rate of the residual-ratio-tracking walks, as a fraction of the largest node extinction (plus 2
// collisions per walk): see ResidualSunTransmittance.
constexpr double kResidualRate = 0.25;
// view_collisions=guided: the share of the view ray's collisions drawn from the guide's importance
// proposal; the rest from delta tracking's density (a defensive mixture, GuidedViewCollision).
constexpr double kGuidedCollisionShare = 0.5;
// Importance splitting: at most this many copies at one vertex, and this many walks per path.
constexpr int kMaxCopies = 8;
constexpr int kMaxWalks = 32;
// The radiance-proxy guide table (PathTracer::GuideTable, docs/models/reference.md). Positions: the
// altitudes below, as fractions of the atmosphere's thickness (dense near the ground, where most
// shadowed vertices are and where the local horizon's dip changes fastest: 0.5 deg per node up to
// 3 km), times kGuideSunNodes sun zenith angles from 90 deg to 90 deg + 3 acos(R_ground / R_top)
// (earth: 90-120 deg in 1.9 deg steps; beyond it no lit air is in sight). Directions, in the local
// frame: elevation cells of 0.75 deg from -8 to +13 deg (the local horizon's dip is 0-6 deg
// for vertices up to 40 km, and the lit air seen from deep shadow lies a few degrees above the
// ground's horizon) and coarser ones outside; azimuth about the sun's azimuth, |phi| in [0, pi],
// with edges pi (k / 16)^2 (0.7 deg wide at phi = 0, 22 deg at pi). Each direction cell's proxy is
// the first-order radiance along its centre direction (RayRadianceProxy), plus with guide_orders
// >= 2 the light of the next orders along it (RayNextOrderProxy, from the previous order's integral
// over directions).
constexpr int kGuideAltitudes = 15;
constexpr double kGuideAltitudeFractions[kGuideAltitudes] = {0.0,  0.005, 0.015, 0.03, 0.05, 0.08, 0.12, 0.17,
                                                             0.23, 0.30,  0.38,  0.48, 0.62, 0.8,  1.0};
constexpr int kGuideSunNodes = 17;
constexpr int kGuidePhi = 16;
constexpr double kGuideFineLow = -8.0, kGuideFineHigh = 13.0, kGuideFineStep = 0.75;  // deg
constexpr double kGuideCoarseBelow[] = {-90.0, -60.0, -40.0, -28.0, -20.0, -15.0, -12.0, -10.0};
constexpr double kGuideCoarseAbove[] = {14.5, 16.5, 19.0, 23.0, 29.0, 37.0, 50.0, 68.0, 90.0};
// Each position's direction sampler is (1 - kGuideFloor) the proxy times solid angle, normalised,
// plus kGuideFloor uniform in solid angle: no cell is ever 0, so a cell whose centre misses a
// thin band of lit air still draws it, at a bounded weight.
constexpr double kGuideFloor = 0.02;

// splitmix64's finaliser (Steele, Lea, Flood 2014): a bijective 64-bit mix.
std::uint64_t Mix64(std::uint64_t z) {
  z = (z ^ (z >> 30)) * 0xBF58476D1CE4E5B9ull;
  z = (z ^ (z >> 27)) * 0x94D049BB133111EBull;
  return z ^ (z >> 31);
}

std::uint64_t HashDoubles(std::uint64_t h, std::initializer_list<double> values) {
  for (double v : values) {
    std::uint64_t bits;
    std::memcpy(&bits, &v, sizeof bits);
    h = Mix64(h ^ bits) + 0x9E3779B97F4A7C15ull;
  }
  return h;
}

std::uint64_t QueryKey(const TraceQuery& q) {
  return HashDoubles(q.ground_only ? 0x6A0Dull : q.include_first_ground_hit ? 0x5EEDull : 0x0ull,
                     {q.origin.x, q.origin.y, q.origin.z, q.sun.x, q.sun.y, q.sun.z, q.view.x, q.view.y, q.view.z});
}

// The stream of one path of one channel.
std::uint64_t StreamSeed(std::uint64_t seed, std::uint64_t key, std::uint64_t path, std::uint64_t channel) {
  return Mix64(Mix64(Mix64(seed ^ 0xA7305EEDull) ^ key) ^ (path * 0x100000001B3ull + channel));
}

// An orthonormal basis around a unit vector n (Duff et al. 2017, "Building an orthonormal basis,
// revisited"), and the direction with cosine `mu` to n and azimuth `phi` about it.
glm::dvec3 DirectionAbout(const glm::dvec3& n, double mu, double phi) {
  const double sign = std::copysign(1.0, n.z);
  const double a = -1.0 / (sign + n.z);
  const double b = n.x * n.y * a;
  const glm::dvec3 t1(1.0 + sign * n.x * n.x * a, sign * b, -sign * n.x);
  const glm::dvec3 t2(b, sign + n.y * n.y * a, -n.y);
  const double sin_theta = std::sqrt(std::max(0.0, 1.0 - mu * mu));
  return glm::normalize(mu * n + sin_theta * (std::cos(phi) * t1 + std::sin(phi) * t2));
}

// A two-sided exponential density exp(-|x - centre| / scale) truncated to [lo, hi] (lo <= centre
// <= hi): a sample from a uniform u, and the normalised density.
double SampleTruncatedLaplace(double centre, double scale, double lo, double hi, double u) {
  const double left = -std::expm1(-(centre - lo) / scale);
  const double right = -std::expm1(-(hi - centre) / scale);
  const double s = u * (left + right);
  const double x = s < left ? centre + scale * std::log1p(-s) : centre - scale * std::log1p(-(s - left));
  return std::clamp(x, lo, hi);
}
double TruncatedLaplacePdf(double centre, double scale, double lo, double hi, double x) {
  if (x < lo || x > hi) return 0.0;
  const double mass = -std::expm1(-(centre - lo) / scale) - std::expm1(-(hi - centre) / scale);
  return std::exp(-std::abs(x - centre) / scale) / (scale * mass);
}

// 8-point Gauss-Legendre rule on [-1, 1] (Abramowitz & Stegun table 25.4), nodes ascending.
constexpr double kGaussNodes[8] = {-0.9602898564975363, -0.7966664774136267, -0.5255324099163290,
                                   -0.1834346424956498, 0.1834346424956498,  0.5255324099163290,
                                   0.7966664774136267,  0.9602898564975363};
constexpr double kGaussWeights[8] = {0.1012285362903763, 0.2223810344533745, 0.3137066458778873,
                                     0.3626837833783620, 0.3626837833783620, 0.3137066458778873,
                                     0.2223810344533745, 0.1012285362903763};

}  // namespace

// splitmix64 (Steele, Lea, Flood 2014): a counter with a strong output mix, so any seed gives an
// independent-looking stream; uniform doubles in [0, 1) with 53 random bits.
class PathTracer::Rng {
 public:
  explicit Rng(std::uint64_t seed) : state_(seed) {}
  double Uniform() {
    state_ += 0x9E3779B97F4A7C15ull;
    return static_cast<double>(Mix64(state_) >> 11) * 0x1.0p-53;
  }

 private:
  std::uint64_t state_;
};

void PathTally::Add(std::size_t index, double x) {
  const double x2 = x * x;
  sum[index] += x;
  sum_sq[index] += x2;
  sum_cube[index] += x2 * x;
  sum_quad[index] += x2 * x2;
}

void PathTally::Reset() {
  paths = 0;
  for (std::vector<double>* v : {&sum, &sum_sq, &sum_cube, &sum_quad}) std::fill(v->begin(), v->end(), 0.0);
}

void PathTally::Merge(const PathTally& other) {
  paths += other.paths;
  for (std::size_t i = 0; i < sum.size(); ++i) {
    sum[i] += other.sum[i];
    sum_sq[i] += other.sum_sq[i];
    sum_cube[i] += other.sum_cube[i];
    sum_quad[i] += other.sum_quad[i];
  }
}

Estimate PathTally::Get(std::size_t channel, int slot) const {
  Estimate e;
  if (paths == 0) return e;
  const std::size_t i = channel * kTallySlots + static_cast<std::size_t>(slot);
  const double n = static_cast<double>(paths);
  e.mean = sum[i] / n;
  if (paths > 1) {
    const double m = e.mean;
    const double central_2 = std::max(0.0, sum_sq[i] - n * m * m);
    e.standard_error = std::sqrt(central_2 / (n - 1.0) / n);
    // The central fourth-power sum from the raw ones; rounding can only make it slightly negative
    // when the values hardly spread, where the VOV is ~0 anyway.
    const double central_4 = sum_quad[i] - 4.0 * m * sum_cube[i] + 6.0 * m * m * sum_sq[i] - 3.0 * n * m * m * m * m;
    if (central_2 > 0.0) {
      e.variance_of_variance = std::clamp(central_4 / (central_2 * central_2) - 1.0 / n, 0.0, 1.0);
    }
  }
  return e;
}

TabulatedPhaseSampler::TabulatedPhaseSampler(const shared::AtmosphereParameters& atmosphere) {
  constexpr int kN = shared::kPhaseTableSize;
  for (int i = 0; i < kN; ++i) logs_[i] = atmosphere.mie_phase_table[i / 4][i % 4];
  const std::size_t pieces = static_cast<std::size_t>(kN - 1) * kPiecesPerKnot;
  bound_.resize(pieces);
  cumulative_.resize(pieces);
  constexpr double kM = kN - 1;
  const double pi = std::numbers::pi;
  double total = 0.0;
  for (std::size_t j = 0; j < pieces; ++j) {
    const double u0 = static_cast<double>(j) / kPiecesPerKnot;
    const double u1 = static_cast<double>(j + 1) / kPiecesPerKnot;
    const int i = static_cast<int>(j / kPiecesPerKnot);
    const double f0 = static_cast<double>(j % kPiecesPerKnot) / kPiecesPerKnot;
    const double f1 = f0 + 1.0 / kPiecesPerKnot;
    // exp of a linear function: its largest value is at an end of the piece.
    const double phase = std::exp(std::max(logs_[i] + f0 * (logs_[i + 1] - logs_[i]),
                                           logs_[i] + f1 * (logs_[i + 1] - logs_[i])));
    const double theta0 = pi * (u0 / kM) * (u0 / kM);
    const double theta1 = pi * (u1 / kM) * (u1 / kM);
    const double sine = theta0 <= 0.5 * pi && theta1 >= 0.5 * pi ? 1.0
                                                                 : std::max(std::sin(theta0), std::sin(theta1));
    // 1e-12 relative: the rounding of the density at the piece's ends cannot exceed the bound.
    bound_[j] = phase * 2.0 * pi * sine * (2.0 * pi * u1 / (kM * kM)) * (1.0 + 1e-12);
    total += bound_[j] * (u1 - u0);
    cumulative_[j] = total;
  }
}

double TabulatedPhaseSampler::Density(double u) const {
  const int i = std::min(static_cast<int>(u), shared::kPhaseTableSize - 2);
  return std::exp(logs_[i] + (u - i) * (logs_[i + 1] - logs_[i])) * shared::GetPhaseTableSolidAnglePerKnot(u);
}

PathTracer::PathTracer(const AtmosphereParameters& parameters, const PathTracerSettings& settings)
    : settings_(settings) {
  Validate(parameters);
  half_space_ = parameters.geometry == Geometry::kHalfSpace;
  atmosphere_ = ToSharedParameters(parameters, 0);
  rayleigh_phase_ = atmosphere_.rayleigh_phase;
  mie_phase_ = atmosphere_.mie_phase;
  rayleigh_g_ = parameters.rayleigh.phase_g;
  mie_g_ = parameters.mie.phase_g;
  if (mie_phase_ == shared::kPhaseTabulated) tabulated_phase_ = TabulatedPhaseSampler(atmosphere_);
  max_extinction_ = glm::dvec4(0.0);
  for (std::size_t c = 0; c < parameters.channel_count(); ++c) {
    Channel ch;
    ch.rayleigh_scattering = parameters.rayleigh.scattering_per_m[c];
    ch.rayleigh_extinction = parameters.rayleigh.extinction_per_m(c);
    ch.mie_scattering = parameters.mie.scattering_per_m[c];
    ch.mie_extinction = parameters.mie.extinction_per_m(c);
    ch.ozone_extinction = parameters.ozone.extinction_per_m(c);
    ch.water_vapor_extinction = parameters.water_vapor.present() ? parameters.water_vapor.extinction_per_m(c) : 0.0;
    // Densities are clamped to [0, 1] (shared/medium.glsl), so this bounds sigma_t everywhere.
    ch.majorant = ch.rayleigh_extinction + ch.mie_extinction + ch.ozone_extinction + ch.water_vapor_extinction;
    ch.albedo = half_space_ ? 0.0 : parameters.ground_albedo[c];
    channels_.push_back(ch);
    max_extinction_ = glm::max(max_extinction_,
                               glm::dvec4(ch.rayleigh_extinction, ch.mie_extinction, ch.ozone_extinction,
                                                          ch.water_vapor_extinction));
  }
  // The half-space is homogeneous: the media at the density of altitude 0.
  half_space_densities_ = shared::GetDensities(atmosphere_, atmosphere_.bottom_radius);
  if (half_space_) {
    for (Channel& ch : channels_) ch.majorant = OpticalDepth(ch, half_space_densities_);
  }
  if (atmosphere_.density_table_enabled) {
    table_maximum_above_.resize(shared::kDensityTableSize);
    glm::dvec4 maximum(0.0);
    for (int i = shared::kDensityTableSize - 1; i >= 0; --i) {
      const glm::dvec4& knot = atmosphere_.density_table[i];
      // The margin covers the rounding of exp(mix(...)) between knots.
      maximum = glm::max(maximum, glm::exp(knot) * (1.0 + 1e-12));
      table_maximum_above_[i] = maximum;
    }
  }
  // Altitudes where a profile may have a kink: layer boundaries, and where a linear layer meets
  // the clamp at 0 or 1 (the ozone tent); with a density table, its knots (the densities'
  // slopes change there: without the breakpoints the adaptive quadrature spent its whole budget of
  // evaluations on them).
  const double thickness = atmosphere_.top_radius - atmosphere_.bottom_radius;
  if (atmosphere_.density_table_enabled) {
    constexpr int kLast = shared::kDensityTableSize - 1;
    for (int i = 1; i < kLast; ++i) kink_altitudes_.push_back(atmosphere_.density_table_top * i * i / (kLast * kLast));
  }
  for (const shared::DensityProfile* profile :
       {&atmosphere_.rayleigh_density, &atmosphere_.mie_density, &atmosphere_.absorption_density}) {
    if (atmosphere_.density_table_enabled) break;
    kink_altitudes_.push_back(profile->layers[0].width);
    for (const shared::DensityProfileLayer& layer : profile->layers) {
      if (layer.exp_term == 0.0 && layer.linear_term != 0.0) {
        kink_altitudes_.push_back(-layer.constant_term / layer.linear_term);
        kink_altitudes_.push_back((1.0 - layer.constant_term) / layer.linear_term);
      }
    }
  }
  std::erase_if(kink_altitudes_, [&](double h) { return !(h > 0.0 && h < thickness); });
  if (settings_.segment_samples < 1) throw Error("the segment estimate needs at least 1 sample per segment");
  if (!(settings_.shadow_guiding >= 0.0 && settings_.shadow_guiding < 1.0)) {
    throw Error("the shadow guiding probability must be in [0, 1)");
  }
  if (!(settings_.horizon_lobe >= 0.0 && settings_.horizon_lobe <= 1.0)) {
    throw Error("the horizon lobe fraction must be in [0, 1]");
  }
  if (settings_.shadow_splits < 1) throw Error("shadow splitting needs at least 1 direction");
  if (!(settings_.table_fraction >= 0.0 && settings_.table_fraction <= 1.0)) {
    throw Error("the guide table's fraction of the guided draws must be in [0, 1]");
  }
  guide_ = std::make_shared<GuideTable>();
  // The sun-ray proxy table serves the segment estimate and the guide table (which shadow guiding
  // by the table and the guided view collisions use with any next-event estimation).
  if (!half_space_ && (settings_.next_event != NextEventEstimation::kVertex ||
                       (settings_.guiding == ShadowGuiding::kTable && settings_.shadow_guiding > 0.0 &&
                        (settings_.table_fraction > 0.0 || settings_.view_collisions == ViewCollisions::kGuided)))) {
    // Bruneton's mapping: x_r = rho / H, x_mu = (d - d_min) / (d_max - d_min), both in [0, 1].
    const double rg = atmosphere_.bottom_radius;
    const double h_top = std::sqrt((atmosphere_.top_radius - rg) * (atmosphere_.top_radius + rg));
    sun_proxy_.resize(static_cast<std::size_t>(kSunProxyR) * kSunProxyMu);
    for (int i = 0; i < kSunProxyR; ++i) {
      const double rho = h_top * i / (kSunProxyR - 1);
      const double r = std::sqrt(rho * rho + rg * rg);
      const double d_min = atmosphere_.top_radius - r;
      const double d_max = rho + h_top;
      for (int j = 0; j < kSunProxyMu; ++j) {
        const double d = d_min + (d_max - d_min) * j / (kSunProxyMu - 1);
        // Law of cosines on (centre, point, exit point): top^2 = r^2 + d^2 + 2 r mu d.
        const double mu = d == 0.0 ? 1.0 : shared::ClampCosine((h_top * h_top - rho * rho - d * d) / (2.0 * r * d));
        sun_proxy_[static_cast<std::size_t>(i) * kSunProxyMu + j] = DensityIntegralToTop(r, mu);
      }
    }
  }
}

glm::dvec3 PathTracer::ObserverPosition(double altitude_m) const {
  return glm::dvec3(0.0, 0.0, half_space_ ? altitude_m : atmosphere_.bottom_radius + altitude_m);
}

glm::dvec4 PathTracer::Densities(const glm::dvec3& p) const {
  return half_space_ ? half_space_densities_ : shared::GetDensities(atmosphere_, glm::length(p));
}

namespace {

// The largest density of one layer over altitudes [a, b]. exp_term exp(exp_scale h) and
// linear_term h are each monotone, and so is their sum when both vary the same way; clamping to
// [0, 1] keeps monotonicity, so the maximum is at an end. Otherwise 1 (the clamp) bounds it.
double LayerMaximum(const shared::DensityProfileLayer& layer, double a, double b) {
  if (layer.exp_term * layer.exp_scale * layer.linear_term < 0.0) return 1.0;
  return std::max(shared::GetLayerDensity(layer, a), shared::GetLayerDensity(layer, b));
}

double ProfileMaximumAbove(const shared::DensityProfile& profile, double h, double top) {
  const double width = profile.layers[0].width;
  double m = h < width ? LayerMaximum(profile.layers[0], h, width) : 0.0;
  return std::max(m, LayerMaximum(profile.layers[1], std::max(h, width), std::max(top, width)));
}

}  // namespace

glm::dvec4 PathTracer::MaxDensities(const glm::dvec3& p, const glm::dvec3& d, double length) const {
  // Lowest point of the segment: its perigee when inside, else the nearer end.
  const double b = glm::dot(p, d);
  double r_min;
  if (-b > 0.0 && -b < length) {
    r_min = glm::length(glm::cross(p, d));
  } else {
    r_min = std::min(glm::length(p), glm::length(p + std::min(length, 1e300) * d));
  }
  const double top = atmosphere_.top_radius - atmosphere_.bottom_radius;
  const double h = std::max(r_min - atmosphere_.bottom_radius, 0.0);
  if (atmosphere_.density_table_enabled) {
    const double u = shared::GetDensityTableCoord(atmosphere_, h);
    const int i = std::clamp(static_cast<int>(u), 0, shared::kDensityTableSize - 1);
    return table_maximum_above_[static_cast<std::size_t>(i)];
  }
  // Water vapour exists only in the table: its density is 0 here.
  return glm::dvec4(ProfileMaximumAbove(atmosphere_.rayleigh_density, h, top),
                    ProfileMaximumAbove(atmosphere_.mie_density, h, top),
                    ProfileMaximumAbove(atmosphere_.absorption_density, h, top), 0.0);
}

void PathTracer::Segment(const glm::dvec3& p, const glm::dvec3& d, double& length, bool& ground) const {
  if (half_space_) {
    ground = false;
    length = d.z > 0.0 ? std::max(-p.z, 0.0) / d.z : kInfinity;
    return;
  }
  const double r = glm::length(p);
  const double mu = shared::ClampCosine(glm::dot(p, d) / r);
  ground = shared::RayIntersectsGround(atmosphere_, r, mu);
  length = shared::DistanceToNearestAtmosphereBoundary(atmosphere_, r, mu, ground);
}

bool PathTracer::EnterAtmosphere(glm::dvec3& p, const glm::dvec3& d) const {
  if (half_space_) {
    if (p.z <= 0.0) return true;
    if (d.z >= 0.0) return false;
    p += (-p.z / d.z) * d;
    p.z = 0.0;
    return true;
  }
  const double r = glm::length(p);
  if (r <= atmosphere_.top_radius) return true;
  const double t = shared::DistanceToAtmosphereEntry(atmosphere_, r, glm::dot(p, d) / r);
  if (t < 0.0) return false;
  p = glm::normalize(p + t * d) * atmosphere_.top_radius;
  return true;
}

// Ratio tracking (Novak et al. 2014): the product of (1 - sigma_t / sigma_bar) over the
// tentative collisions of a majorant process along the sun ray has expectation exp(-tau).
// The half-space is homogeneous, so there the closed form is exact.
double PathTracer::SunTransmittance(const glm::dvec3& p, const glm::dvec3& sun, const Channel& c, Rng& rng) const {
  double length;
  bool ground;
  Segment(p, sun, length, ground);
  if (ground || length == kInfinity) return 0.0;
  if (half_space_) return std::exp(-c.majorant * length);
  return RatioTracking(p, sun, length, c, rng);
}

double PathTracer::RatioTracking(const glm::dvec3& p, const glm::dvec3& d, double length, const Channel& c,
                                 Rng& rng) const {
  const double majorant = Majorant(c, p, d, length);
  if (majorant <= 0.0) return 1.0;
  double transmittance = 1.0;
  double t = 0.0;
  for (std::uint64_t step = 0; step < kMaxTrackingSteps; ++step) {
    t -= std::log1p(-rng.Uniform()) / majorant;
    if (!(t < length)) return transmittance;
    transmittance *= 1.0 - OpticalDepth(c, Densities(p + t * d)) / majorant;
    // Every later factor is in [0, 1]: once 0 (or NaN), it stays so.
    if (!(transmittance > 0.0)) return 0.0;
    // Russian roulette on a small running product: below kRouletteTransmittance the walk goes on
    // with probability 1/2 and twice the weight, so its expectation is unchanged (no bias) and a
    // shadow ray through an optically thick medium (an optical depth of 10^4 cost 10^4 steps and
    // ~0.2 s per path) stops after a few more steps.
    if (transmittance < kRouletteTransmittance) {
      if (rng.Uniform() < 0.5) return 0.0;
      transmittance *= 2.0;
    }
  }
  return transmittance;  // an optical depth above ~1.7e7: the rest of the product is negligible
}

// Residual ratio tracking (Novak et al. 2014) against a control extinction sigma_c that is
// piecewise linear between 17 nodes along the sun ray (placed about its lowest point, as in
// DensityIntegralToTop): T = exp(-tau_c) E[prod (1 - (sigma - sigma_c)(t_i) / rate)] over a Poisson
// process of constant rate, unbiased for any rate > 0 (the factors may leave [0, 1]). tau_c is the
// trapezoidal rule on the nodes, exactly; the residual is a few per cent of sigma, so the product
// stays near 1 where plain ratio tracking of a grazing ray (optical depth 10 and more in deep
// twilight) multiplies tens of factors near 0 and is right only on average over rare walks.
// rate = (2 + kResidualRate * max sigma_node * length) / length: 2 tentative collisions plus a
// quarter of the majorant's, with factors 1 -+ 4 |sigma_r| / sigma_max (a rate of the full
// majorant gave the same twilight standard errors at more cost, sun 104-108 deg, 262144 paths).
double PathTracer::ResidualSunTransmittance(const glm::dvec3& x, const glm::dvec3& sun, const Channel& c,
                                            Rng& rng) const {
  double length;
  bool ground;
  Segment(x, sun, length, ground);
  if (ground || !(length < kInfinity)) return 0.0;
  if (!(length > 0.0)) return 1.0;
  constexpr int kIntervals = 16;
  std::array<double, kIntervals + 1> ts, sigma;
  const double t_low = std::clamp(-glm::dot(x, sun), 0.0, length);
  const double x_0 = -std::sqrt(t_low);
  const double x_1 = std::sqrt(length - t_low);
  double tau_c = 0.0, sigma_max = 0.0;
  for (int i = 0; i <= kIntervals; ++i) {
    const double u = x_0 + (x_1 - x_0) * i / kIntervals;
    ts[i] = i == 0 ? 0.0 : i == kIntervals ? length : std::clamp(t_low + u * std::abs(u), ts[i - 1], length);
    sigma[i] = OpticalDepth(c, Densities(x + ts[i] * sun));
    sigma_max = std::max(sigma_max, sigma[i]);
    if (i > 0) tau_c += 0.5 * (sigma[i - 1] + sigma[i]) * (ts[i] - ts[i - 1]);
  }
  const double rate = (2.0 + kResidualRate * sigma_max * length) / length;
  double product = 1.0;
  double t = 0.0;
  int piece = 0;
  for (std::uint64_t step = 0; step < kMaxTrackingSteps; ++step) {
    t -= std::log1p(-rng.Uniform()) / rate;
    if (!(t < length)) break;
    while (piece + 1 < kIntervals && ts[piece + 1] <= t) ++piece;
    const double width = ts[piece + 1] - ts[piece];
    const double f = width > 0.0 ? (t - ts[piece]) / width : 0.0;
    const double control = sigma[piece] + f * (sigma[piece + 1] - sigma[piece]);
    product *= 1.0 - (OpticalDepth(c, Densities(x + t * sun)) - control) / rate;
  }
  return std::exp(-tau_c) * product;
}

double PathTracer::GlowAlong(const GlowSource& glow, const glm::dvec3& p, const glm::dvec3& d, const Channel& c,
                             Rng& rng) const {
  const std::size_t channel = static_cast<std::size_t>(&c - channels_.data());
  if (channel >= glow.emission.size() || !(glow.emission[channel] > 0.0)) return 0.0;
  double length;
  bool ground;
  Segment(p, d, length, ground);
  const double end = ground ? length : kInfinity;  // past the atmosphere's top the ray goes on to space
  // Where the ray is inside a sphere of radius R: t in [-b - q, -b + q], b = p.d, q^2 = b^2 - |p|^2 + R^2.
  const double b = glm::dot(p, d);
  const double pp = glm::dot(p, p);
  const auto chord = [&](double radius, double& t0, double& t1) {
    const double q2 = b * b - pp + radius * radius;
    if (!(q2 > 0.0)) return false;
    const double q = std::sqrt(q2);
    t0 = -b - q;
    t1 = -b + q;
    return true;
  };
  double out0, out1;
  if (!chord(glow.outer_radius, out0, out1)) return 0.0;
  // The parts inside the outer sphere and outside the inner one, cut to [0, end].
  std::array<std::array<double, 2>, 2> parts{};
  int count = 0;
  double in0, in1;
  if (chord(glow.inner_radius, in0, in1) && in0 < out1 && in1 > out0) {
    parts[count++] = {out0, in0};
    parts[count++] = {in1, out1};
  } else {
    parts[count++] = {out0, out1};
  }
  double sum = 0.0;
  for (int i = 0; i < count; ++i) {
    const double a = std::max(parts[i][0], 0.0);
    const double z = std::min(parts[i][1], end);
    if (!(z > a)) continue;
    sum += (z - a) * RatioTracking(p, d, std::min(a, length), c, rng);
  }
  return glow.emission[channel] * sum;
}

bool PathTracer::InShadow(const glm::dvec3& x, const glm::dvec3& sun) const {
  const double along = glm::dot(x, sun);
  const glm::dvec3 x_perp = x - along * sun;
  return along < 0.0 && glm::dot(x_perp, x_perp) < atmosphere_.bottom_radius * atmosphere_.bottom_radius;
}

void PathTracer::ShadowInterval(const glm::dvec3& p, const glm::dvec3& d, double length, const glm::dvec3& sun,
                                double& shadow_begin, double& shadow_end) const {
  shadow_begin = 0.0;
  shadow_end = length;
  // Inside the cylinder: |p_perp + t d_perp|^2 < R^2, i.e. a t^2 + 2 b t + c < 0.
  const glm::dvec3 p_perp = p - glm::dot(p, sun) * sun;
  const glm::dvec3 d_perp = d - glm::dot(d, sun) * sun;
  const double a = glm::dot(d_perp, d_perp);
  const double b = glm::dot(p_perp, d_perp);
  const double c = glm::dot(p_perp, p_perp) - atmosphere_.bottom_radius * atmosphere_.bottom_radius;
  if (a > 0.0) {
    const double discriminant = b * b - a * c;
    if (!(discriminant > 0.0)) {
      shadow_end = -1.0;
      return;
    }
    // Roots without cancellation: q = -(b + sign(b) sqrt(D)); q / a and c / q.
    const double q = -(b + std::copysign(std::sqrt(discriminant), b));
    const double t1 = q / a;
    const double t2 = q != 0.0 ? c / q : -t1;
    shadow_begin = std::max(shadow_begin, std::min(t1, t2));
    shadow_end = std::min(shadow_end, std::max(t1, t2));
  } else if (!(c < 0.0)) {
    shadow_end = -1.0;
    return;
  }
  // Behind the planet: dot(p + t d, sun) < 0.
  const double ps = glm::dot(p, sun);
  const double ds = glm::dot(d, sun);
  if (ds > 0.0) {
    shadow_end = std::min(shadow_end, -ps / ds);
  } else if (ds < 0.0) {
    shadow_begin = std::max(shadow_begin, -ps / ds);
  } else if (!(ps < 0.0)) {
    shadow_end = -1.0;
  }
}

glm::dvec4 PathTracer::DensityIntegralToTop(double r, double mu) const {
  const double d = shared::DistanceToTopAtmosphereBoundary(atmosphere_, r, mu);
  const double t_low = std::clamp(-r * mu, 0.0, d);
  const double x_0 = -std::sqrt(t_low);
  const double dx = (std::sqrt(d - t_low) - x_0) / kSunProxyIntervals;
  glm::dvec4 sum(0.0);
  for (int i = 0; i <= kSunProxyIntervals; ++i) {
    const double x = x_0 + i * dx;
    const double t = t_low + x * std::abs(x);
    const double r_i = std::sqrt(std::max(t * t + 2.0 * r * mu * t + r * r, 0.0));
    const double w = (i == 0 || i == kSunProxyIntervals) ? 0.5 : 1.0;
    sum += shared::GetDensities(atmosphere_, r_i) * (w * 2.0 * std::abs(x));
  }
  return sum * dx;
}

glm::dvec4 PathTracer::SunDensityProxy(const glm::dvec3& x, const glm::dvec3& sun) const {
  const double rg = atmosphere_.bottom_radius;
  const double rt = atmosphere_.top_radius;
  const double r = std::clamp(glm::length(x), rg, rt);
  const double mu = shared::ClampCosine(glm::dot(x, sun) / r);
  const double h_top = std::sqrt((rt - rg) * (rt + rg));
  const double rho = std::sqrt(std::max((r - rg) * (r + rg), 0.0));
  const double d = shared::DistanceToTopAtmosphereBoundary(atmosphere_, r, mu);
  const double d_min = rt - r;
  const double d_max = rho + h_top;
  const double u_mu = std::clamp(d_max > d_min ? (d - d_min) / (d_max - d_min) : 0.0, 0.0, 1.0) * (kSunProxyMu - 1);
  const double u_r = std::clamp(rho / h_top, 0.0, 1.0) * (kSunProxyR - 1);
  const int i = std::min(static_cast<int>(u_r), kSunProxyR - 2);
  const int j = std::min(static_cast<int>(u_mu), kSunProxyMu - 2);
  const double fr = u_r - i;
  const double fm = u_mu - j;
  const auto at = [&](int a, int b) { return sun_proxy_[static_cast<std::size_t>(a) * kSunProxyMu + b]; };
  return (1.0 - fr) * ((1.0 - fm) * at(i, j) + fm * at(i, j + 1)) + fr * ((1.0 - fm) * at(i + 1, j) + fm * at(i + 1, j + 1));
}

// The segment estimate (docs/models/reference.md, "Next-event estimation on segments"). The
// integrand f(t) = T(p, x_t) s(x_t) T_sun(x_t), s = sum_media sigma_s p(nu), is 0 in the planet's
// shadow. Proposal: node values g_i = s(x_i) exp(-tau_view(t_i) - tau_sun(x_i)) with tau_view by
// the trapezoidal rule over the nodes and tau_sun from the proxy table, interpolated
// exponentially between nodes (a density that falls exponentially along the segment is then
// followed exactly) on the lit pieces only, floored at kProposalFloor of the largest. K points
// are drawn stratified in the proposal's CDF (one per 1/K of its mass); each scores
// T(p, x_j) s(x_j) T_sun(x_j) / (K pdf(t_j)) with both transmittances by ratio tracking (the view
// one by a single walk along the segment, read at every t_j), so the estimate is unbiased
// wherever the proposal is positive, i.e. on the whole lit part.
int PathTracer::SegmentNodes(const glm::dvec3& p, const glm::dvec3& d, double length, double shadow_begin,
                             double shadow_end, double* ts) const {
  int n = 0;
  const double t_low = std::clamp(-glm::dot(p, d), 0.0, length);
  const double x_0 = -std::sqrt(t_low);
  const double x_1 = std::sqrt(length - t_low);
  for (int i = 0; i <= kSegmentIntervals; ++i) {
    const double x = x_0 + (x_1 - x_0) * i / kSegmentIntervals;
    ts[n++] = i == 0 ? 0.0 : i == kSegmentIntervals ? length : std::clamp(t_low + x * std::abs(x), 0.0, length);
  }
  if (shadow_begin < shadow_end) {
    for (double t : {shadow_begin, shadow_end}) {
      if (t > 0.0 && t < length) ts[n++] = t;
    }
    std::sort(ts, ts + n);
  }
  return n;
}

// The deterministic part of a segment estimate: its nodes, the proposal's pieces and the control
// of its view transmittance. It is the same for every path along one segment, so the view ray's
// is made once per query (ViewRayPlan) and each path only draws from it.
struct PathTracer::SegmentPlan {
  bool empty = true;  // the estimate is 0 (no scattering on the segment's lit part)
  double rayleigh = 0.0, mie = 0.0;  // sigma_s p(nu) per medium at density 1
  int n = 0;                         // nodes
  int first_lit = -1, last_lit = -1;
  double total = 0.0;  // the proposal's mass
  std::array<double, kSegmentIntervals + 3> ts, sigma_node, tau_node;
  std::array<double, kSegmentIntervals + 3> g;         // the proposal at node i, floored
  std::array<double, kSegmentIntervals + 3> mass{};    // of piece i, [i, i + 1]
  std::array<double, kSegmentIntervals + 3> rate{};    // ln(g_b / g_a) / width
  std::array<double, kSegmentIntervals + 3> below{};   // mass of the pieces before piece i
};

void PathTracer::PlanSegmentSunlight(const glm::dvec3& p, const glm::dvec3& d, double length, const glm::dvec3& sun,
                                     const Channel& c, SegmentPlan& plan) const {
  plan.empty = true;
  if (!(length > 0.0)) return;
  const double nu = glm::dot(d, sun);
  const double rayleigh = c.rayleigh_scattering * shared::EvaluatePhaseFunction(rayleigh_phase_, rayleigh_g_, nu);
  const double mie = c.mie_scattering * shared::GetMiePhase(atmosphere_, nu);
  if (!(rayleigh + mie > 0.0)) return;
  plan.rayleigh = rayleigh;
  plan.mie = mie;
  double shadow_begin, shadow_end;
  ShadowInterval(p, d, length, sun, shadow_begin, shadow_end);
  const bool shadow = shadow_begin < shadow_end;
  if (shadow && shadow_begin <= 0.0 && shadow_end >= length) return;

  // Nodes.
  auto& ts = plan.ts;
  const int n = plan.n = SegmentNodes(p, d, length, shadow_begin, shadow_end, ts.data());

  // Node values and the proposal's pieces.
  auto& g = plan.g;
  double tau_view = 0.0;
  double sigma_previous = 0.0;
  double g_max = 0.0;
  for (int i = 0; i < n; ++i) {
    const glm::dvec3 x = p + ts[i] * d;
    const glm::dvec4 densities = Densities(x);
    const double sigma = OpticalDepth(c, densities);
    if (i > 0) tau_view += 0.5 * (sigma_previous + sigma) * (ts[i] - ts[i - 1]);
    sigma_previous = sigma;
    plan.sigma_node[i] = sigma;
    plan.tau_node[i] = tau_view;
    const double scattering = rayleigh * densities.x + mie * densities.y;
    g[i] = scattering * std::exp(-tau_view - OpticalDepth(c, SunDensityProxy(x, sun)));
  }
  const auto lit_piece = [&](int i) {
    const double mid = 0.5 * (ts[i] + ts[i + 1]);
    return ts[i + 1] > ts[i] && !(shadow && mid > shadow_begin && mid < shadow_end);
  };
  for (int i = 0; i + 1 < n; ++i) {
    if (lit_piece(i)) g_max = std::max({g_max, g[i], g[i + 1]});
  }
  // g_max = 0: no scattering on the lit part, or exp(-tau) below the smallest double there.
  if (!(g_max > 0.0)) return;
  double total = 0.0;
  int first_lit = -1, last_lit = -1;
  for (int i = 0; i + 1 < n; ++i) {
    plan.below[i] = total;
    if (!lit_piece(i)) continue;
    g[i] = std::max(g[i], kProposalFloor * g_max);
    const double gb = std::max(g[i + 1], kProposalFloor * g_max);
    const double width = ts[i + 1] - ts[i];
    const double log_ratio = std::log(gb / g[i]);
    plan.rate[i] = log_ratio / width;
    plan.mass[i] = std::abs(log_ratio) < 1e-9 ? g[i] * width : g[i] * width * std::expm1(log_ratio) / log_ratio;
    total += plan.mass[i];
    if (plan.mass[i] > 0.0) {
      if (first_lit < 0) first_lit = i;
      last_lit = i;
    }
  }
  if (!(total > 0.0) || first_lit < 0) return;
  plan.total = total;
  plan.first_lit = first_lit;
  plan.last_lit = last_lit;
  plan.empty = false;
}

double PathTracer::SegmentSunlight(const glm::dvec3& p, const glm::dvec3& d, double length, const glm::dvec3& sun,
                                   const Channel& c, Rng& rng) const {
  SegmentPlan plan;
  PlanSegmentSunlight(p, d, length, sun, c, plan);
  return SegmentSunlight(plan, p, d, sun, c, rng);
}

double PathTracer::SegmentSunlight(const SegmentPlan& plan, const glm::dvec3& p, const glm::dvec3& d,
                                   const glm::dvec3& sun, const Channel& c, Rng& rng) const {
  if (plan.empty) return 0.0;
  const auto& ts = plan.ts;
  const auto& g = plan.g;
  const auto& mass = plan.mass;
  const auto& rate = plan.rate;
  const auto& below = plan.below;
  const double total = plan.total;

  // Stratified points in the proposal's CDF; their order along the segment is that of u.
  const int k = settings_.segment_samples;
  std::array<double, 64> t_sample, weight_sample;
  std::vector<double> heap_t, heap_w;
  double* tj = t_sample.data();
  double* wj = weight_sample.data();
  if (k > 64) {
    heap_t.resize(k);
    heap_w.resize(k);
    tj = heap_t.data();
    wj = heap_w.data();
  }
  int piece = plan.first_lit;
  for (int j = 0; j < k; ++j) {
    const double u = (j + rng.Uniform()) / k * total;
    // The first piece with mass whose end is above u (the last one if rounding put u at the end).
    while (piece < plan.last_lit && (mass[piece] == 0.0 || below[piece] + mass[piece] <= u)) ++piece;
    const double width = ts[piece + 1] - ts[piece];
    const double v = std::clamp((u - below[piece]) / mass[piece], 0.0, 1.0);
    double s;
    if (std::abs(rate[piece] * width) < 1e-9) {
      s = v * width;
    } else {
      s = std::log1p(v * std::expm1(rate[piece] * width)) / rate[piece];
    }
    s = std::clamp(s, 0.0, width);
    tj[j] = ts[piece] + s;
    const double pdf = g[piece] * std::exp(rate[piece] * s) / total;
    wj[j] = 1.0 / (k * pdf);
  }

  std::array<double, 64> transmittance_small;
  std::vector<double> transmittance_big;
  double* transmittance = transmittance_small.data();
  if (k > 64) {
    transmittance_big.resize(k);
    transmittance = transmittance_big.data();
  }
  ResidualViewTransmittances(p, d, ts.data(), plan.sigma_node.data(), plan.tau_node.data(), plan.n, tj, k, c, rng,
                             transmittance);
  double estimate = 0.0;
  for (int j = 0; j < k; ++j) {
    const glm::dvec3 x = p + tj[j] * d;
    const glm::dvec4 densities = Densities(x);
    const double s = plan.rayleigh * densities.x + plan.mie * densities.y;
    if (s > 0.0) estimate += wj[j] * transmittance[j] * s * ResidualSunTransmittance(x, sun, c, rng);
  }
  return estimate;
}

// One residual-ratio-tracking walk along [0, t_k] against the control that is linear between
// the nodes (as in ResidualSunTransmittance): T(p, x_j) = exp(-tau_c(t_j)) times the running
// product at t_j, unbiased for every j.
void PathTracer::ResidualViewTransmittances(const glm::dvec3& p, const glm::dvec3& d, const double* ts,
                                            const double* sigma_node, const double* tau_node, int n, const double* t,
                                            int k, const Channel& c, Rng& rng, double* out) const {
  const double t_last = t[k - 1];
  double sigma_max = 0.0;
  for (int i = 0; i < n; ++i) sigma_max = std::max(sigma_max, sigma_node[i]);
  const double walk_rate = t_last > 0.0 ? (2.0 + kResidualRate * sigma_max * t_last) / t_last : 1.0;
  // The control at t and its integral from 0 to t, with `node` the piece that holds t.
  int node = 0;
  const auto control = [&](double at, double& tau_c) {
    while (node + 2 < n && ts[node + 1] <= at) ++node;
    const double width = ts[node + 1] - ts[node];
    const double f = width > 0.0 ? std::clamp((at - ts[node]) / width, 0.0, 1.0) : 0.0;
    const double sigma_c = sigma_node[node] + f * (sigma_node[node + 1] - sigma_node[node]);
    tau_c = tau_node[node] + 0.5 * (sigma_node[node] + sigma_c) * (at - ts[node]);
    return sigma_c;
  };
  double product = 1.0;
  double t_next = -std::log1p(-rng.Uniform()) / walk_rate;
  std::uint64_t steps = 0;
  for (int j = 0; j < k; ++j) {
    double tau_c;
    while (t_next < t[j] && steps < kMaxTrackingSteps) {
      ++steps;
      const double sigma_c = control(t_next, tau_c);
      product *= 1.0 - (OpticalDepth(c, Densities(p + t_next * d)) - sigma_c) / walk_rate;
      t_next -= std::log1p(-rng.Uniform()) / walk_rate;
    }
    node = 0;
    control(t[j], tau_c);
    out[j] = std::exp(-tau_c) * product;
  }
}

// The deterministic part of GuidedViewCollision: the two proposals on the segment's nodes.
struct PathTracer::CollisionPlan {
  static constexpr int kNodes = kSegmentIntervals + 1;
  bool valid = false;  // false: the proposal has no mass (no collision)
  std::array<double, kNodes> ts, sigma_node, tau_node;
  // [0] sigma_t exp(-tau) I (the guide's), [1] sigma_t exp(-tau) (delta tracking's density,
  // defensive); at the nodes, each floored at kProposalFloor of its largest node value.
  std::array<std::array<double, kNodes>, 2> g;
  std::array<std::array<double, kNodes - 1>, 2> mass{}, rate{};
  std::array<double, 2> total{};
};

// One view ray's plan per channel, made once per query (PathTracer::Trace).
struct PathTracer::ViewRayPlan {
  bool segment_planned = false;
  SegmentPlan segment;
  bool collision_planned = false;
  CollisionPlan collision;
};

void PathTracer::PlanGuidedViewCollision(const glm::dvec3& p, const glm::dvec3& d, double length,
                                         const glm::dvec3& sun, const Channel& c, std::size_t channel,
                                         CollisionPlan& plan) const {
  const GuideTable& table = Guide();
  constexpr int n = CollisionPlan::kNodes;
  auto& ts = plan.ts;
  auto& g = plan.g;
  plan.valid = false;
  SegmentNodes(p, d, length, 0.0, 0.0, ts.data());
  double tau = 0.0;
  std::array<double, 2> g_max{};
  for (int i = 0; i < n; ++i) {
    const glm::dvec3 y = p + ts[i] * d;
    const double sigma = OpticalDepth(c, Densities(y));
    if (i > 0) tau += 0.5 * (plan.sigma_node[i - 1] + sigma) * (ts[i] - ts[i - 1]);
    plan.sigma_node[i] = sigma;
    plan.tau_node[i] = tau;
    g[1][i] = sigma * std::exp(-tau);
    g[0][i] = g[1][i] * GuideImportance(table, LocateGuide(table, y, sun), channel);
    for (int a = 0; a < 2; ++a) g_max[a] = std::max(g_max[a], g[a][i]);
  }
  if (!(g_max[1] > 0.0)) return;
  if (!(g_max[0] > 0.0)) g[0] = g[1], g_max[0] = g_max[1];
  for (int a = 0; a < 2; ++a) {
    for (int i = 0; i + 1 < n; ++i) {
      const double ga = std::max(g[a][i], kProposalFloor * g_max[a]);
      const double gb = std::max(g[a][i + 1], kProposalFloor * g_max[a]);
      g[a][i] = ga;
      const double width = ts[i + 1] - ts[i];
      const double log_ratio = std::log(gb / ga);
      plan.rate[a][i] = width > 0.0 ? log_ratio / width : 0.0;
      plan.mass[a][i] = std::abs(log_ratio) < 1e-9 ? ga * width : ga * width * std::expm1(log_ratio) / log_ratio;
      plan.total[a] += plan.mass[a][i];
    }
    if (!(plan.total[a] > 0.0)) return;
  }
  plan.valid = true;
}

// The view ray's collision drawn by importance (view_collisions=guided, docs/models/reference.md):
// from a proposal that follows sigma_t(t) exp(-tau(t)) I(x_t), I the guide table's importance (the
// light a point of the shadow sees, orders 1 and 2), piecewise exponential between 17 nodes about
// the ray's lowest point and floored at kProposalFloor of its largest node value, mixed with a
// proposal of delta tracking's own density T sigma_t (kGuidedCollisionShare). `factor` = T(p, x_t)
// / q(t), q the mixture's pdf and T by residual ratio tracking: times sigma_t(x_t) (the caller's,
// at the collision) the collision's expected weight is that of delta tracking at every t. Returns false
// where the proposal has no mass (no extinction on the segment). The proposal is the plan's
// (PlanGuidedViewCollision), made once per query.
bool PathTracer::GuidedViewCollision(const CollisionPlan& plan, const glm::dvec3& p, const glm::dvec3& d,
                                     const Channel& c, Rng& rng, double& t, double& factor) const {
  if (!plan.valid) return false;
  constexpr int n = CollisionPlan::kNodes;
  const auto& ts = plan.ts;
  const auto& g = plan.g;
  const auto& mass = plan.mass;
  const auto& rate = plan.rate;
  const auto& total = plan.total;
  // A component (kGuidedCollisionShare the guide's), a piece by its mass, a point in it.
  const int a = rng.Uniform() < kGuidedCollisionShare ? 0 : 1;
  double u = rng.Uniform() * total[a];
  int piece = 0;
  while (piece + 1 < n - 1 && (mass[a][piece] == 0.0 || u >= mass[a][piece])) u -= mass[a][piece++];
  while (piece > 0 && !(mass[a][piece] > 0.0)) u = mass[a][--piece];  // rounding ran past the last mass
  if (!(mass[a][piece] > 0.0)) return false;
  const double width = ts[piece + 1] - ts[piece];
  const double v = std::clamp(u / mass[a][piece], 0.0, 1.0);
  const double r = rate[a][piece];
  double s = std::abs(r * width) < 1e-9 ? v * width : std::log1p(v * std::expm1(r * width)) / r;
  s = std::clamp(s, 0.0, width);
  t = ts[piece] + s;
  // The mixture's pdf at t (both components share the pieces).
  const double pdf = kGuidedCollisionShare * g[0][piece] * std::exp(rate[0][piece] * s) / total[0] +
                     (1.0 - kGuidedCollisionShare) * g[1][piece] * std::exp(rate[1][piece] * s) / total[1];
  double transmittance;
  ResidualViewTransmittances(p, d, ts.data(), plan.sigma_node.data(), plan.tau_node.data(), n, &t, 1, c, rng,
                             &transmittance);
  factor = transmittance / pdf;
  return true;
}

void PathTracer::HorizonFrame(const glm::dvec3& x, const glm::dvec3& sun, glm::dvec3& up, glm::dvec3& towards,
                              glm::dvec3& across, double& e0) const {
  const double r = glm::length(x);
  up = x / r;
  towards = sun - glm::dot(sun, up) * up;
  if (glm::dot(towards, towards) < 1e-24) towards = DirectionAbout(up, 0.0, 0.0);
  towards = glm::normalize(towards);
  across = glm::cross(up, towards);
  const double rg = atmosphere_.bottom_radius;
  e0 = -std::acos(std::clamp((rg + 0.5 * std::max(r - rg, 0.0)) / r, -1.0, 1.0));
}

// The importance of a shadowed vertex for importance splitting: the proxy of the segment
// estimate (the integrand of SegmentSunlight with an isotropic phase function, both optical depths
// by the trapezoidal rule on 17 nodes and the sun's from the proxy table) along the horizon lobe's
// axis, the direction in which a deep-twilight vertex sees the most lit air. It only decides how
// many copies a path is split into, never a weight's expectation.
double PathTracer::ImportanceProxy(const glm::dvec3& x, const glm::dvec3& sun, const Channel& c) const {
  glm::dvec3 up, towards, across;
  double e0;
  HorizonFrame(x, sun, up, towards, across, e0);
  const glm::dvec3 a = glm::normalize(std::cos(e0) * towards + std::sin(e0) * up);
  double length;
  bool ground;
  Segment(x, a, length, ground);
  if (!(length > 0.0 && length < kInfinity)) return 0.0;
  double shadow_begin, shadow_end;
  ShadowInterval(x, a, length, sun, shadow_begin, shadow_end);
  std::array<double, kSegmentIntervals + 1> ts;
  SegmentNodes(x, a, length, 0.0, 0.0, ts.data());
  double tau = 0.0, sigma_previous = 0.0, g_previous = 0.0, t_previous = 0.0, integral = 0.0;
  for (int i = 0; i <= kSegmentIntervals; ++i) {
    const double t = ts[i];
    const glm::dvec3 y = x + t * a;
    const glm::dvec4 densities = Densities(y);
    const double sigma = OpticalDepth(c, densities);
    if (i > 0) tau += 0.5 * (sigma_previous + sigma) * (t - t_previous);
    const bool lit = !(shadow_begin < shadow_end && t > shadow_begin && t < shadow_end);
    const double g = lit ? (c.rayleigh_scattering * densities.x + c.mie_scattering * densities.y) *
                               std::exp(-tau - OpticalDepth(c, SunDensityProxy(y, sun)))
                         : 0.0;
    if (i > 0) integral += 0.5 * (g_previous + g) * (t - t_previous);
    sigma_previous = sigma;
    g_previous = g;
    t_previous = t;
  }
  return integral;
}

// The radiance-proxy guide table (docs/models/reference.md, "Radiance-proxy guiding"). The
// first-order radiance that reaches a vertex x from direction w, L1(x, w) = sum_m p_m(w.sun)
// integral T sigma_s,m T_sun dt, depends on (|x|, x.sun / |x|, x.w / |x|, the azimuth of w about x
// from the sun's azimuth) only, and is even in that azimuth: one table serves every query of the
// tracer. Per channel and table position, a piecewise-constant density in solid angle over the
// direction cells; a vertex's sampler is the bilinear mixture of its four neighbouring positions'
// (a deterministic function of x, so the mixture pdf of a direction drawn by any technique is
// the same function of it).
struct PathTracer::GuideTable {
  std::once_flag once;
  std::atomic<bool> built{false};
  std::vector<double> altitudes;  // m, kGuideAltitudes
  double sun_step = 0.0;          // rad between sun zenith angle nodes, from pi / 2
  std::vector<double> mu_edges;   // cosines to the local zenith, ascending from -1 to 1
  std::vector<double> phi_edges;  // |azimuth| from the sun's, ascending from 0 to pi
  int cells = 0;                  // (mu_edges.size() - 1) * kGuidePhi
  // [(channel * positions + position) * (cells + 1) + k]: the CDF over cells k = mu * kGuidePhi +
  // phi (0 first, 1 last), and per (channel, position) the proxy's integral over the sphere.
  std::vector<double> cdf;
  std::vector<double> integral;
  std::size_t positions() const { return altitudes.size() * kGuideSunNodes; }
};

void PathTracer::RayRadianceProxy(const glm::dvec3& x, const glm::dvec3& w, const glm::dvec3& sun, double* out) const {
  const std::size_t channels = channels_.size();
  for (std::size_t c = 0; c < channels; ++c) out[c] = 0.0;
  double length;
  bool ground;
  Segment(x, w, length, ground);
  if (!(length > 0.0 && length < kInfinity)) return;
  double shadow_begin, shadow_end;
  ShadowInterval(x, w, length, sun, shadow_begin, shadow_end);
  const bool shadow = shadow_begin < shadow_end;
  if (shadow && shadow_begin <= 0.0 && shadow_end >= length) return;
  std::array<double, kSegmentIntervals + 3> ts;
  const int n = SegmentNodes(x, w, length, shadow_begin, shadow_end, ts.data());
  const double nu = glm::dot(w, sun);
  const double p_rayleigh = shared::EvaluatePhaseFunction(rayleigh_phase_, rayleigh_g_, nu);
  const double p_mie = shared::GetMiePhase(atmosphere_, nu);
  // Per channel: optical depth so far, the previous node's extinction and integrand.
  std::array<double, 16> tau_small{}, sigma_small{}, g_small{};
  std::vector<double> tau_big, sigma_big, g_big;
  double* tau = tau_small.data();
  double* sigma_previous = sigma_small.data();
  double* g_previous = g_small.data();
  if (channels > tau_small.size()) {
    tau_big.assign(channels, 0.0), sigma_big.assign(channels, 0.0), g_big.assign(channels, 0.0);
    tau = tau_big.data(), sigma_previous = sigma_big.data(), g_previous = g_big.data();
  }
  for (int i = 0; i < n; ++i) {
    const glm::dvec3 y = x + ts[i] * w;
    const glm::dvec4 densities = Densities(y);
    const bool lit_before = i > 0 && !(shadow && 0.5 * (ts[i - 1] + ts[i]) > shadow_begin &&
                                       0.5 * (ts[i - 1] + ts[i]) < shadow_end);
    const bool lit_after = i + 1 < n && !(shadow && 0.5 * (ts[i] + ts[i + 1]) > shadow_begin &&
                                          0.5 * (ts[i] + ts[i + 1]) < shadow_end);
    const bool needed = lit_before || lit_after;
    const glm::dvec4 sun_densities = needed ? SunDensityProxy(y, sun) : glm::dvec4(0.0);
    for (std::size_t c = 0; c < channels; ++c) {
      const Channel& ch = channels_[c];
      const double sigma = OpticalDepth(ch, densities);
      if (i > 0) tau[c] += 0.5 * (sigma_previous[c] + sigma) * (ts[i] - ts[i - 1]);
      sigma_previous[c] = sigma;
      const double g = needed ? (ch.rayleigh_scattering * p_rayleigh * densities.x +
                                 ch.mie_scattering * p_mie * densities.y) *
                                    std::exp(-tau[c] - OpticalDepth(ch, sun_densities))
                              : 0.0;
      if (lit_before) out[c] += 0.5 * (g_previous[c] + g) * (ts[i] - ts[i - 1]);
      g_previous[c] = g;
    }
  }
}

void PathTracer::RayNextOrderProxy(const GuideTable& table, const std::vector<double>& previous, const glm::dvec3& x,
                                   const glm::dvec3& w, const glm::dvec3& sun, double* out) const {
  const std::size_t channels = channels_.size();
  for (std::size_t c = 0; c < channels; ++c) out[c] = 0.0;
  double length;
  bool ground;
  Segment(x, w, length, ground);
  if (!(length > 0.0 && length < kInfinity)) return;
  std::array<double, kSegmentIntervals + 1> ts;
  SegmentNodes(x, w, length, 0.0, 0.0, ts.data());
  const std::size_t positions = table.positions();
  std::vector<double> tau(channels, 0.0), sigma_previous(channels, 0.0), g_previous(channels, 0.0);
  double t_previous = 0.0;
  for (int i = 0; i <= kSegmentIntervals; ++i) {
    const double t = ts[i];
    const glm::dvec3 y = x + t * w;
    const glm::dvec4 densities = Densities(y);
    const GuidePosition at = LocateGuide(table, y, sun);
    for (std::size_t c = 0; c < channels; ++c) {
      const Channel& ch = channels_[c];
      const double sigma = OpticalDepth(ch, densities);
      if (i > 0) tau[c] += 0.5 * (sigma_previous[c] + sigma) * (t - t_previous);
      sigma_previous[c] = sigma;
      double radiance = 0.0;
      for (int n = 0; n < 4; ++n) radiance += at.weight[n] * previous[c * positions + static_cast<std::size_t>(at.index[n])];
      const double g = (ch.rayleigh_scattering * densities.x + ch.mie_scattering * densities.y) *
                       std::exp(-tau[c]) * radiance / (4.0 * kPi);
      if (i > 0) out[c] += 0.5 * (g_previous[c] + g) * (t - t_previous);
      g_previous[c] = g;
    }
    t_previous = t;
  }
}

void PathTracer::BuildGuideTable(GuideTable& table) const {
  const double rg = atmosphere_.bottom_radius;
  const double rt = atmosphere_.top_radius;
  const double thickness = rt - rg;
  for (double f : kGuideAltitudeFractions) table.altitudes.push_back(f * thickness);
  table.sun_step = 3.0 * std::acos(std::clamp(rg / rt, -1.0, 1.0)) / (kGuideSunNodes - 1);
  std::vector<double> elevations(std::begin(kGuideCoarseBelow), std::end(kGuideCoarseBelow));
  for (double e = kGuideFineLow; e <= kGuideFineHigh + 1e-9; e += kGuideFineStep) elevations.push_back(e);
  elevations.insert(elevations.end(), std::begin(kGuideCoarseAbove), std::end(kGuideCoarseAbove));
  for (double e : elevations) table.mu_edges.push_back(std::sin(e * kPi / 180.0));
  table.mu_edges.front() = -1.0;
  table.mu_edges.back() = 1.0;
  for (int k = 0; k <= kGuidePhi; ++k) table.phi_edges.push_back(kPi * (k * k) / (kGuidePhi * kGuidePhi));
  const int n_mu = static_cast<int>(table.mu_edges.size()) - 1;
  table.cells = n_mu * kGuidePhi;
  const std::size_t channels = channels_.size();
  const std::size_t positions = table.positions();
  const std::size_t cells = static_cast<std::size_t>(table.cells);
  const std::size_t stride = cells + 1;
  table.cdf.assign(channels * positions * stride, 0.0);
  table.integral.assign(channels * positions, 0.0);
  std::vector<double> solid_angle(cells);
  for (int m = 0; m < n_mu; ++m) {
    for (int f = 0; f < kGuidePhi; ++f) {
      solid_angle[m * kGuidePhi + f] =
          (table.mu_edges[m + 1] - table.mu_edges[m]) * (table.phi_edges[f + 1] - table.phi_edges[f]);
    }
  }
  // The position and the cell centre directions of each table entry.
  const auto position_of = [&](std::size_t position, glm::dvec3& x, glm::dvec3& sun) {
    const std::size_t ih = position / kGuideSunNodes;
    const int is = static_cast<int>(position % kGuideSunNodes);
    x = glm::dvec3(0.0, 0.0, rg + table.altitudes[ih]);
    const double theta = 0.5 * kPi + is * table.sun_step;
    sun = glm::dvec3(std::sin(theta), 0.0, std::cos(theta));
  };
  const auto direction_of = [&](std::size_t k) {
    const int m = static_cast<int>(k) / kGuidePhi;
    const int f = static_cast<int>(k) % kGuidePhi;
    const double mu = 0.5 * (table.mu_edges[m] + table.mu_edges[m + 1]);
    const double sin_mu = std::sqrt(std::max(0.0, 1.0 - mu * mu));
    const double phi = 0.5 * (table.phi_edges[f] + table.phi_edges[f + 1]);
    return glm::dvec3(sin_mu * std::cos(phi), sin_mu * std::sin(phi), mu);
  };
  // value[(position * cells + k) * channels + c]: the sum of the orders so far; order[...]: the
  // last order alone, and its integral over directions per (channel, position).
  std::vector<double> value(positions * cells * channels), order(positions * cells * channels);
  std::vector<double> order_integral(channels * positions);
  const auto integrate = [&](const std::vector<double>& v, std::vector<double>& out) {
    for (std::size_t position = 0; position < positions; ++position) {
      for (std::size_t c = 0; c < channels; ++c) {
        double total = 0.0;
        for (std::size_t k = 0; k < cells; ++k) total += v[(position * cells + k) * channels + c] * solid_angle[k];
        out[c * positions + position] = 2.0 * total;  // both signs of the azimuth
      }
    }
  };
  // Positions in parallel (each independent, so the table does not depend on the thread count),
  // isolated: a thread waiting here must not pick up a path of the caller's loop, which could ask
  // for this table again.
  const auto for_positions = [&](const std::function<void(std::size_t)>& body) {
    oneapi::tbb::this_task_arena::isolate([&] {
      oneapi::tbb::parallel_for(std::size_t{0}, positions, body);
    });
  };
  for_positions([&](std::size_t position) {
    glm::dvec3 x, sun;
    position_of(position, x, sun);
    for (std::size_t k = 0; k < cells; ++k) {
      RayRadianceProxy(x, direction_of(k), sun, &order[(position * cells + k) * channels]);
    }
  });
  value = order;
  for (int n = 2; n <= settings_.guide_orders; ++n) {
    integrate(order, order_integral);
    std::vector<double> next(order.size());
    for_positions([&](std::size_t position) {
      glm::dvec3 x, sun;
      position_of(position, x, sun);
      for (std::size_t k = 0; k < cells; ++k) {
        RayNextOrderProxy(table, order_integral, x, direction_of(k), sun, &next[(position * cells + k) * channels]);
      }
    });
    order = std::move(next);
    for (std::size_t i = 0; i < value.size(); ++i) value[i] += order[i];
  }
  integrate(value, table.integral);
  for (std::size_t position = 0; position < positions; ++position) {
    for (std::size_t c = 0; c < channels; ++c) {
      const double total = 0.5 * table.integral[c * positions + position];
      double* cdf = &table.cdf[(c * positions + position) * stride];
      double sum = 0.0;
      cdf[0] = 0.0;
      for (std::size_t k = 0; k < cells; ++k) {
        const double proxy = total > 0.0 ? value[(position * cells + k) * channels + c] * solid_angle[k] / total : 0.0;
        const double floor = solid_angle[k] / (2.0 * kPi);  // one side of the sphere: 2 pi
        sum += total > 0.0 ? (1.0 - kGuideFloor) * proxy + kGuideFloor * floor : floor;
        cdf[k + 1] = sum;
      }
      for (std::size_t k = 1; k <= cells; ++k) cdf[k] /= sum;
      cdf[cells] = 1.0;
    }
  }
}

const PathTracer::GuideTable& PathTracer::Guide() const {
  std::call_once(guide_->once, [this] {
    BuildGuideTable(*guide_);
    guide_->built = true;
  });
  return *guide_;
}

bool PathTracer::GuideTableBuilt() const { return guide_->built; }

void PathTracer::GuideTableEdges(std::vector<double>& mu_edges, std::vector<double>& phi_edges) const {
  const GuideTable& table = Guide();
  mu_edges = table.mu_edges;
  phi_edges = table.phi_edges;
}

PathTracer::GuidePosition PathTracer::LocateGuide(const GuideTable& table, const glm::dvec3& x,
                                                  const glm::dvec3& sun) const {
  GuidePosition at;
  const double r = glm::length(x);
  at.up = x / r;
  at.towards = sun - glm::dot(sun, at.up) * at.up;
  if (glm::dot(at.towards, at.towards) < 1e-24) at.towards = DirectionAbout(at.up, 0.0, 0.0);
  at.towards = glm::normalize(at.towards);
  at.across = glm::cross(at.up, at.towards);
  const double h = r - atmosphere_.bottom_radius;
  const int n_h = static_cast<int>(table.altitudes.size());
  int ih = 0;
  while (ih + 2 < n_h && table.altitudes[ih + 1] <= h) ++ih;
  const double fh = std::clamp((h - table.altitudes[ih]) / (table.altitudes[ih + 1] - table.altitudes[ih]), 0.0, 1.0);
  const double theta = std::acos(std::clamp(glm::dot(at.up, sun), -1.0, 1.0));
  const double u = std::clamp((theta - 0.5 * kPi) / table.sun_step, 0.0, static_cast<double>(kGuideSunNodes - 1));
  const int is = std::min(static_cast<int>(u), kGuideSunNodes - 2);
  const double fs = u - is;
  for (int a = 0; a < 2; ++a) {
    for (int b = 0; b < 2; ++b) {
      at.index[2 * a + b] = (ih + a) * kGuideSunNodes + is + b;
      at.weight[2 * a + b] = (a ? fh : 1.0 - fh) * (b ? fs : 1.0 - fs);
    }
  }
  return at;
}

glm::dvec3 PathTracer::SampleGuide(const GuideTable& table, const GuidePosition& at, std::size_t channel,
                                   Rng& rng) const {
  // A neighbouring position by its bilinear weight, a cell by its CDF, then uniform in solid
  // angle in the cell (uniform in mu and phi), the azimuth's sign at random.
  double u = rng.Uniform();
  int n = 0;
  while (n < 3 && !(u < at.weight[n])) u -= at.weight[n++];
  while (n > 0 && !(at.weight[n] > 0.0)) --n;
  const std::size_t stride = static_cast<std::size_t>(table.cells) + 1;
  const double* cdf = &table.cdf[(channel * table.positions() + static_cast<std::size_t>(at.index[n])) * stride];
  const double v = rng.Uniform();
  int k = static_cast<int>(std::upper_bound(cdf, cdf + stride, v) - cdf) - 1;
  k = std::clamp(k, 0, table.cells - 1);
  const int m = k / kGuidePhi;
  const int f = k % kGuidePhi;
  const double mu = table.mu_edges[m] + rng.Uniform() * (table.mu_edges[m + 1] - table.mu_edges[m]);
  double phi = table.phi_edges[f] + rng.Uniform() * (table.phi_edges[f + 1] - table.phi_edges[f]);
  if (rng.Uniform() < 0.5) phi = -phi;
  const double sin_mu = std::sqrt(std::max(0.0, 1.0 - mu * mu));
  return glm::normalize(mu * at.up + sin_mu * (std::cos(phi) * at.towards + std::sin(phi) * at.across));
}

double PathTracer::GuidePdf(const GuideTable& table, const GuidePosition& at, std::size_t channel,
                            const glm::dvec3& w) const {
  const double mu = std::clamp(glm::dot(w, at.up), -1.0, 1.0);
  const double phi = std::atan2(std::abs(glm::dot(w, at.across)), glm::dot(w, at.towards));
  const int n_mu = static_cast<int>(table.mu_edges.size()) - 1;
  const int m = std::clamp(
      static_cast<int>(std::upper_bound(table.mu_edges.begin(), table.mu_edges.end(), mu) - table.mu_edges.begin()) - 1,
      0, n_mu - 1);
  const int f = std::clamp(static_cast<int>(std::upper_bound(table.phi_edges.begin(), table.phi_edges.end(), phi) -
                                            table.phi_edges.begin()) -
                               1,
                           0, kGuidePhi - 1);
  const int k = m * kGuidePhi + f;
  const double solid_angle =
      2.0 * (table.mu_edges[m + 1] - table.mu_edges[m]) * (table.phi_edges[f + 1] - table.phi_edges[f]);
  const std::size_t stride = static_cast<std::size_t>(table.cells) + 1;
  double probability = 0.0;
  for (int n = 0; n < 4; ++n) {
    if (!(at.weight[n] > 0.0)) continue;
    const double* cdf = &table.cdf[(channel * table.positions() + static_cast<std::size_t>(at.index[n])) * stride];
    probability += at.weight[n] * (cdf[k + 1] - cdf[k]);
  }
  return probability / solid_angle;
}

double PathTracer::GuideImportance(const GuideTable& table, const GuidePosition& at, std::size_t channel) const {
  double importance = 0.0;
  for (int n = 0; n < 4; ++n) {
    importance += at.weight[n] * table.integral[channel * table.positions() + static_cast<std::size_t>(at.index[n])];
  }
  return importance;
}

glm::dvec3 PathTracer::SampleGuideTable(const glm::dvec3& x, const glm::dvec3& sun, std::size_t channel,
                                        std::uint64_t seed) const {
  const GuideTable& table = Guide();
  Rng rng(Mix64(seed ^ 0x7AB1Eull));
  return SampleGuide(table, LocateGuide(table, x, sun), channel, rng);
}

double PathTracer::GuideTablePdf(const glm::dvec3& x, const glm::dvec3& sun, const glm::dvec3& w,
                                 std::size_t channel) const {
  const GuideTable& table = Guide();
  return GuidePdf(table, LocateGuide(table, x, sun), channel, w);
}

double PathTracer::GuideTableImportance(const glm::dvec3& x, const glm::dvec3& sun, std::size_t channel) const {
  const GuideTable& table = Guide();
  return GuideImportance(table, LocateGuide(table, x, sun), channel);
}

glm::dvec3 PathTracer::GuidedDirection(const glm::dvec3& x, const glm::dvec3& d, const glm::dvec3& sun, int kind,
                                       double g, std::size_t channel, Rng& rng, double& mis_weight) const {
  // One-sample MIS of the phase function (1 - guide), the table's sampler (guiding=table: the
  // fraction table_fraction of guide) and the lobes (the rest of guide, split by horizon_lobe).
  const double guide = settings_.shadow_guiding;
  const double table_share = settings_.guiding == ShadowGuiding::kTable ? guide * settings_.table_fraction : 0.0;
  const double lobes = guide - table_share;
  const double horizon = lobes * settings_.horizon_lobe;
  const double sun_lobe = lobes - horizon;
  glm::dvec3 up, towards, across;
  double e0;
  HorizonFrame(x, sun, up, towards, across, e0);
  constexpr double kHalfPi = 0.5 * kPi;
  const GuideTable* table = table_share > 0.0 ? &Guide() : nullptr;
  GuidePosition at{};
  if (table) at = LocateGuide(*table, x, sun);

  glm::dvec3 next;
  const double u = rng.Uniform();
  if (table && u >= 1.0 - table_share) {
    next = SampleGuide(*table, at, channel, rng);
  } else if (u < sun_lobe) {
    const double mu = SamplePhaseCosine(shared::kPhaseHenyeyGreenstein, kGuideG, [&] { return rng.Uniform(); });
    next = DirectionAbout(sun, mu, 2.0 * kPi * rng.Uniform());
  } else if (u < lobes) {
    const double azimuth = SampleTruncatedLaplace(0.0, kHorizonAzimuthScale, -kPi, kPi, rng.Uniform());
    const double elevation = SampleTruncatedLaplace(e0, kHorizonElevationScale, -kHalfPi, kHalfPi, rng.Uniform());
    next = glm::normalize(std::cos(elevation) * (std::cos(azimuth) * towards + std::sin(azimuth) * across) +
                          std::sin(elevation) * up);
  } else {
    const double nu = SampleMediumPhaseCosine(kind, g, [&] { return rng.Uniform(); });
    next = DirectionAbout(d, nu, 2.0 * kPi * rng.Uniform());
  }
  const double phase = shared::GetMediumPhase(atmosphere_, kind, g, glm::dot(d, next));
  double mixture = (1.0 - guide) * phase;
  if (table) mixture += table_share * GuidePdf(*table, at, channel, next);
  if (sun_lobe > 0.0) {
    mixture += sun_lobe * shared::EvaluatePhaseFunction(shared::kPhaseHenyeyGreenstein, kGuideG, glm::dot(sun, next));
  }
  if (horizon > 0.0) {
    // Solid-angle density: p(azimuth) p(elevation) / cos(elevation).
    const double sin_elevation = std::clamp(glm::dot(next, up), -1.0, 1.0);
    const double cos_elevation = std::sqrt(std::max(0.0, 1.0 - sin_elevation * sin_elevation));
    if (cos_elevation > 1e-12) {
      const double azimuth = std::atan2(glm::dot(next, across), glm::dot(next, towards));
      const double elevation = std::asin(sin_elevation);
      mixture += horizon * TruncatedLaplacePdf(0.0, kHorizonAzimuthScale, -kPi, kPi, azimuth) *
                 TruncatedLaplacePdf(e0, kHorizonElevationScale, -kHalfPi, kHalfPi, elevation) / cos_elevation;
    }
  }
  mis_weight = mixture > 0.0 ? phase / mixture : 0.0;
  return next;
}

glm::dvec3 PathTracer::SampleShadowDirection(const glm::dvec3& x, const glm::dvec3& d, const glm::dvec3& sun, bool mie,
                                             std::uint64_t seed, double& weight, std::size_t channel) const {
  Rng rng(Mix64(seed ^ 0x5D1Eull));
  return GuidedDirection(x, d, sun, mie ? mie_phase_ : rayleigh_phase_, mie ? mie_g_ : rayleigh_g_, channel, rng,
                         weight);
}

void PathTracer::TracePath(const TraceQuery& query, const Channel& c, const ViewRayPlan& view_plan, Rng& rng,
                           std::array<double, kOrderBins>& orders) const {
  glm::dvec3 entry = query.origin;
  if (!EnterAtmosphere(entry, query.view)) return;
  const std::size_t channel = static_cast<std::size_t>(&c - channels_.data());
  // A glow query scores the shell's light at each vertex and uses none of the sun's estimates,
  // guiding or splitting (TraceQuery::glow).
  const GlowSource* glow = query.glow;
  // Importance splitting (settings_.importance_splitting): the walks that copies of the path
  // still have to trace, and the weight times importance at the path's first shadowed vertex,
  // which later shadowed vertices split towards (docs/models/reference.md).
  struct Walk {
    glm::dvec3 p, d;
    double weight;
    int order;
    double target;  // the weight a walk is split down to; roulette is relative to min(target, 1)
    bool been_shadowed;
  };
  std::array<Walk, kMaxWalks> pending;
  int pending_count = 0;
  int walks = 1;
  double reference_importance = 0.0;
  // Shadow splitting happens once per path; the continued direction's segment estimate is one of
  // the N and carries 1/N of the weight (segment_scale).
  bool split = false;
  const auto walk = [&](const Walk& start) {
    glm::dvec3 p = start.p;
    glm::dvec3 d = start.d;
    double weight = start.weight;
    int order = start.order;  // scattering events (and ground reflections) so far
    double target = start.target;
    const auto add = [&](double value) { orders[std::min(order, kOrderBins) - 1] += value; };
    double segment_scale = 1.0;
    // Whether a segment of this walk has started in the shadow: nee=auto then takes the segment
    // estimate on the rest of it (a guided path that reached lit air has vertex estimates there
    // that are rare and large: the forward peak towards the sun).
    bool been_shadowed = start.been_shadowed;
    while (true) {
      double length;
      bool ground;
      Segment(p, d, length, ground);
      const bool end_scores = ground && c.albedo > 0.0 &&
                              (order > 0 || query.include_first_ground_hit || query.ground_only);
      // Ground term only: cross the view segment to the ground, weighted by its transmittance.
      const bool cross_to_ground = query.ground_only && order == 0;
      if (cross_to_ground) {
        if (!end_scores) return;
        weight *= RatioTracking(p, d, length, c, rng);
      }

      // Next-event estimation on the segment: the expected vertex estimate of the next collision,
      // scored in that collision's order bin; the vertex itself then takes none.
      // The view ray (order 0: the path's first segment) takes both from its plan (PlanViewRay).
      bool segment_nee = false;
      if (glow != nullptr) {
        segment_nee = false;
      } else if (order == 0) {
        segment_nee = view_plan.segment_planned;
        if (segment_nee) orders[0] += weight * SegmentSunlight(view_plan.segment, p, d, query.sun, c, rng);
      } else if (!half_space_ && length < kInfinity && settings_.next_event != NextEventEstimation::kVertex) {
        segment_nee = settings_.next_event == NextEventEstimation::kSegment || been_shadowed;
        if (!segment_nee) segment_nee = been_shadowed = InShadow(p, query.sun);
        if (segment_nee) {
          orders[std::min(order + 1, kOrderBins) - 1] +=
              segment_scale * weight * SegmentSunlight(p, d, length, query.sun, c, rng);
        }
      }
      segment_scale = 1.0;

      // Delta tracking against the segment's majorant, the first tentative collision forced into
      // the segment where allowed; or, on a view ray that starts in the planet's shadow and whose
      // end scores nothing, the collision drawn by the guide table's importance.
      bool collided = false;
      glm::dvec4 densities(0.0);
      const bool guided_collision =
          glow != nullptr ? false
          : order == 0    ? view_plan.collision_planned
                          : settings_.shadow_collisions == ShadowCollisions::kGuided &&
                           settings_.guiding == ShadowGuiding::kTable && settings_.shadow_guiding > 0.0 &&
                           !half_space_ && !end_scores && length < kInfinity && InShadow(p, query.sun);
      const double majorant = cross_to_ground || guided_collision ? 0.0 : Majorant(c, p, d, length);
      if (guided_collision) {
        double t, factor;
        CollisionPlan own;
        if (order > 0) PlanGuidedViewCollision(p, d, length, query.sun, c, channel, own);
        if (!GuidedViewCollision(order == 0 ? view_plan.collision : own, p, d, c, rng, t, factor)) return;
        p += t * d;
        densities = Densities(p);
        weight *= factor * OpticalDepth(c, densities);
        collided = weight > 0.0;
        if (!collided) return;
      } else if (majorant > 0.0) {
        const bool force = settings_.forced_collisions && !end_scores && length < kInfinity;
        double t = 0.0;
        bool first = true;
        for (std::uint64_t step = 0; step < kMaxTrackingSteps; ++step) {
          if (first && force) {
            const double p_collide = -std::expm1(-majorant * length);
            weight *= p_collide;
            t -= std::log1p(-rng.Uniform() * p_collide) / majorant;
          } else {
            t -= std::log1p(-rng.Uniform()) / majorant;
          }
          first = false;
          if (!(t < length)) break;
          const glm::dvec3 x = p + t * d;
          densities = Densities(x);
          if (rng.Uniform() * majorant < OpticalDepth(c, densities)) {
            p = x;
            collided = true;
            break;
          }
        }
      }

      if (collided) {
        const double rayleigh = c.rayleigh_scattering * densities.x;
        const double mie = c.mie_scattering * densities.y;
        weight *= (rayleigh + mie) / OpticalDepth(c, densities);
        if (weight <= 0.0) return;
        ++order;
        const bool is_mie = rng.Uniform() * (rayleigh + mie) < mie;
        const int kind = is_mie ? mie_phase_ : rayleigh_phase_;
        const double g = is_mie ? mie_g_ : rayleigh_g_;
        const double sun_transmittance =
            segment_nee || glow != nullptr ? 0.0 : SunTransmittance(p, query.sun, c, rng);
        if (sun_transmittance != 0.0) {
          add(weight * shared::GetMediumPhase(atmosphere_, kind, g, glm::dot(d, query.sun)) * sun_transmittance);
        }
        const bool shadowed = glow == nullptr && !half_space_ && InShadow(p, query.sun);
        // Splitting at the path's first shadowed vertex, where the next segment's estimate is taken
        // (nee=auto or segment): N directions from the same distribution; directions 1..N-1 score
        // their segment estimates now, each with 1/N of the weight, in the next collision's bin,
        // and direction 0 goes on with the full weight, its segment estimate scaled by 1/N. The
        // mean of N unbiased estimates of the next segment's expected vertex estimate is one, and
        // the continued path is a draw of the unsplit one (docs/models/reference.md).
        const int splits = settings_.shadow_splits;
        const bool do_split = shadowed && !split && splits > 1 && settings_.next_event != NextEventEstimation::kVertex;
        if (do_split) split = true;
        const auto draw = [&](double& direction_weight) {
          if (shadowed && settings_.shadow_guiding > 0.0) {
            return GuidedDirection(p, d, query.sun, kind, g, channel, rng, direction_weight);
          }
          direction_weight = 1.0;
          const double nu = SampleMediumPhaseCosine(kind, g, [&] { return rng.Uniform(); });
          return DirectionAbout(d, nu, 2.0 * kPi * rng.Uniform());
        };
        if (do_split) {
          const double share = 1.0 / splits;
          for (int i = 1; i < splits; ++i) {
            double w_i;
            const glm::dvec3 d_i = draw(w_i);
            if (!(w_i > 0.0)) continue;
            double length_i;
            bool ground_i;
            Segment(p, d_i, length_i, ground_i);
            if (length_i < kInfinity) {
              orders[std::min(order + 1, kOrderBins) - 1] +=
                  share * weight * w_i * SegmentSunlight(p, d_i, length_i, query.sun, c, rng);
            }
          }
          segment_scale = share;
        }
        // Importance splitting at the later shadowed vertices: a path whose weight times the
        // vertex's importance is n >= 2 times that at its first shadowed vertex goes on as n copies
        // of 1/n of the weight, each with its own direction (a sum of n unbiased continuations over
        // n); at most kMaxCopies at a vertex and kMaxWalks per path.
        // A lit vertex of a path that has been in the shadow is weighed by its own importance too
        // (the table's, large where the sun shines): against the last shadowed vertex's target, the
        // roulette lifted the small weight of a rare lit vertex to that target, one path then
        // carrying several per cent of an estimate (docs/models/reference.md).
        if (glow == nullptr && settings_.importance_splitting && (shadowed || reference_importance > 0.0) &&
            settings_.next_event != NextEventEstimation::kVertex) {
          const double importance = settings_.guiding == ShadowGuiding::kTable
                                        ? GuideImportance(Guide(), LocateGuide(Guide(), p, query.sun), channel)
                                        : ImportanceProxy(p, query.sun, c);
          if (importance > 0.0) {
            if (!(reference_importance > 0.0)) reference_importance = weight * importance;
            target = reference_importance / importance;
            const double ratio = std::min(weight / target, static_cast<double>(kMaxCopies));
            const int n = std::min(static_cast<int>(ratio), kMaxWalks - walks + 1);
            if (n >= 2) {
              weight /= n;
              for (int i = 1; i < n; ++i) {
                double w_i;
                const glm::dvec3 d_i = draw(w_i);
                ++walks;
                if (w_i > 0.0) pending[pending_count++] = Walk{p, d_i, weight * w_i, order, target, true};
              }
            }
          }
        }
        if (shadowed && settings_.shadow_guiding > 0.0) {
          double w;
          d = draw(w);
          weight *= w;
          if (!(weight > 0.0)) return;
        } else {
          const double nu = SampleMediumPhaseCosine(kind, g, [&] { return rng.Uniform(); });
          d = DirectionAbout(d, nu, 2.0 * kPi * rng.Uniform());
        }
        // The glow arriving along the new direction, scattered here (phase-sampled: the weight
        // is the estimate's).
        if (glow != nullptr) add(weight * GlowAlong(*glow, p, d, c, rng));
      } else if (end_scores) {
        const glm::dvec3 n = glm::normalize(p + length * d);
        p = n * atmosphere_.bottom_radius;
        ++order;
        const double cos_sun = glm::dot(n, query.sun);
        if (cos_sun > 0.0 && glow == nullptr) {
          add(weight * c.albedo / kPi * cos_sun * SunTransmittance(p, query.sun, c, rng));
        }
        weight *= c.albedo;
        if (weight <= 0.0) return;
        // Cosine-weighted: the Lambertian BRDF times cos over this pdf is the albedo.
        d = DirectionAbout(n, std::sqrt(rng.Uniform()), 2.0 * kPi * rng.Uniform());
        if (glow != nullptr) add(weight * GlowAlong(*glow, p, d, c, rng));
      } else {
        return;  // escaped, or the view ray's own ground hit
      }

      if (order >= settings_.roulette_start_order) {
        const double survival = std::min(weight / std::min(target, 1.0), 0.95);
        if (!(rng.Uniform() < survival)) return;
        weight /= survival;
      }
    }
  };
  walk(Walk{entry, query.view, 1.0, 0, kInfinity, false});
  while (pending_count > 0) {
    --pending_count;
    walk(pending[pending_count]);
  }
}

// The view ray's deterministic parts, as TracePath's first segment makes them: the same inputs
// in the same order, so a path drawn from the plan is the path drawn without it, bit for bit.
void PathTracer::PlanViewRay(const TraceQuery& query, const Channel& c, ViewRayPlan& plan) const {
  glm::dvec3 entry = query.origin;
  if (!EnterAtmosphere(entry, query.view)) return;
  const std::size_t channel = static_cast<std::size_t>(&c - channels_.data());
  double length;
  bool ground;
  Segment(entry, query.view, length, ground);
  const bool end_scores = ground && c.albedo > 0.0 && (query.include_first_ground_hit || query.ground_only);
  const bool cross_to_ground = query.ground_only;
  if (!half_space_ && !cross_to_ground && length < kInfinity && settings_.next_event != NextEventEstimation::kVertex) {
    PlanSegmentSunlight(entry, query.view, length, query.sun, c, plan.segment);
    plan.segment_planned = true;
  }
  if (settings_.view_collisions == ViewCollisions::kGuided && settings_.guiding == ShadowGuiding::kTable &&
      settings_.shadow_guiding > 0.0 && !half_space_ && !cross_to_ground && !end_scores && length < kInfinity &&
      InShadow(entry, query.sun)) {
    PlanGuidedViewCollision(entry, query.view, length, query.sun, c, channel, plan.collision);
    plan.collision_planned = true;
  }
}

std::vector<PathTracer::ViewRayPlan> PathTracer::PlanViewRays(const TraceQuery& query) const {
  std::vector<ViewRayPlan> plans(channels_.size());
  for (std::size_t c = 0; c < channels_.size(); ++c) PlanViewRay(query, channels_[c], plans[c]);
  return plans;
}

void PathTracer::TraceSerial(const TraceQuery& query, std::uint64_t seed, std::uint64_t first, std::uint64_t count,
                             PathTally& tally) const {
  TraceSerial(query, PlanViewRays(query), seed, first, count, tally);
}

void PathTracer::TraceSerial(const TraceQuery& query, const std::vector<ViewRayPlan>& plans, std::uint64_t seed,
                             std::uint64_t first, std::uint64_t count, PathTally& tally) const {
  const std::uint64_t key = QueryKey(query);
  for (std::uint64_t i = first; i < first + count; ++i) {
    for (std::size_t c = 0; c < channels_.size(); ++c) {
      Rng rng(StreamSeed(seed, key, i, c));
      std::array<double, kOrderBins> orders{};
      TracePath(query, channels_[c], plans[c], rng, orders);
      double total = 0.0;
      for (int k = 0; k < kOrderBins; ++k) {
        tally.Add(c * kTallySlots + 1 + static_cast<std::size_t>(k), orders[k]);
        total += orders[k];
      }
      tally.Add(c * kTallySlots, total);
    }
  }
  tally.paths += count;
}

namespace {

// Runs trace_block(first, count, tally) over fixed blocks in parallel and merges them in order.
PathTally TraceBlocks(std::size_t channels, std::uint64_t first, std::uint64_t count,
                      const std::function<void(std::uint64_t, std::uint64_t, PathTally&)>& trace_block) {
  const std::uint64_t blocks = (count + kBlockPaths - 1) / kBlockPaths;
  // Blocks are traced in parallel a group at a time and merged in block order, as one pass over
  // all of them would be: the result is the same, and the tallies in memory stay under ~64 MB
  // (2^40 paths were 2^33 tallies at once, a std::bad_alloc).
  const std::uint64_t tally_bytes = 4 * sizeof(double) * kTallySlots * std::max<std::size_t>(channels, 1);
  const std::uint64_t group_blocks = std::max<std::uint64_t>(64, (std::uint64_t{64} << 20) / tally_bytes);
  PathTally total(channels);
  std::vector<PathTally> tallies;
  for (std::uint64_t group = 0; group < blocks; group += group_blocks) {
    const std::uint64_t n = std::min(group_blocks, blocks - group);
    tallies.assign(n, PathTally(channels));
    oneapi::tbb::parallel_for(oneapi::tbb::blocked_range<std::uint64_t>(0, n, 1),
                              [&](const oneapi::tbb::blocked_range<std::uint64_t>& range) {
                                for (std::uint64_t i = range.begin(); i < range.end(); ++i) {
                                  const std::uint64_t start = (group + i) * kBlockPaths;
                                  trace_block(first + start, std::min(kBlockPaths, count - start), tallies[i]);
                                }
                              });
    for (const PathTally& t : tallies) total.Merge(t);
  }
  return total;
}

}  // namespace

PathTally PathTracer::Trace(const TraceQuery& query, std::uint64_t seed, std::uint64_t first,
                            std::uint64_t count) const {
  const std::vector<ViewRayPlan> plans = PlanViewRays(query);
  return TraceBlocks(channels_.size(), first, count, [&](std::uint64_t start, std::uint64_t n, PathTally& tally) {
    TraceSerial(query, plans, seed, start, n, tally);
  });
}

PathTally PathTracer::TopOutgoingRadiance(const glm::dvec3& sun, std::uint64_t seed, std::uint64_t count) const {
  if (half_space_) throw Error("the flux estimator needs a spherical atmosphere");
  constexpr std::uint64_t kKey = 0xF10A7ull;
  return TraceBlocks(channels_.size(), 0, count, [&](std::uint64_t start, std::uint64_t n, PathTally& tally) {
    for (std::uint64_t i = start; i < start + n; ++i) {
      // The point and direction from their own stream (channel index = channel count).
      Rng geometry(StreamSeed(seed, kKey, i, channels_.size()));
      const double z = 1.0 - 2.0 * geometry.Uniform();
      const double phi = 2.0 * kPi * geometry.Uniform();
      const double s = std::sqrt(std::max(0.0, 1.0 - z * z));
      const glm::dvec3 normal(s * std::cos(phi), s * std::sin(phi), z);
      TraceQuery query;
      query.origin = normal * atmosphere_.top_radius;
      query.sun = sun;
      query.view = -DirectionAbout(normal, std::sqrt(geometry.Uniform()), 2.0 * kPi * geometry.Uniform());
      query.include_first_ground_hit = true;
      for (std::size_t c = 0; c < channels_.size(); ++c) {
        Rng rng(StreamSeed(seed, kKey, i, c));
        std::array<double, kOrderBins> orders{};
        ViewRayPlan plan;
        PlanViewRay(query, channels_[c], plan);
        TracePath(query, channels_[c], plan, rng, orders);
        double total = 0.0;
        for (double v : orders) total += v;
        tally.Add(c * kTallySlots, total);
      }
    }
    tally.paths += n;
  });
}

PathTally PathTracer::DiffuseIrradiance(const glm::dvec3& origin, const glm::dvec3& normal, const glm::dvec3& sun,
                                        std::uint64_t seed, std::uint64_t count) const {
  constexpr std::uint64_t kKey = 0xE1AAull;
  return TraceBlocks(channels_.size(), 0, count, [&](std::uint64_t start, std::uint64_t n, PathTally& tally) {
    for (std::uint64_t i = start; i < start + n; ++i) {
      Rng geometry(StreamSeed(seed, kKey, i, channels_.size()));
      TraceQuery query;
      query.origin = origin;
      query.sun = sun;
      // pdf cos / pi: the estimate of E is pi L per path.
      query.view = DirectionAbout(normal, std::sqrt(geometry.Uniform()), 2.0 * kPi * geometry.Uniform());
      for (std::size_t c = 0; c < channels_.size(); ++c) {
        Rng rng(StreamSeed(seed, kKey, i, c));
        std::array<double, kOrderBins> orders{};
        ViewRayPlan plan;
        PlanViewRay(query, channels_[c], plan);
        TracePath(query, channels_[c], plan, rng, orders);
        for (int k = 0; k < kOrderBins; ++k) {
          tally.Add(c * kTallySlots + 1 + k, kPi * orders[k]);
        }
        double total = 0.0;
        for (double v : orders) total += kPi * v;
        tally.Add(c * kTallySlots, total);
      }
    }
    tally.paths += n;
  });
}

// ---------------------------------------------------------------------------------------------
// Quadratures.

void PathTracer::AddBreakpoints(const glm::dvec3& p, const glm::dvec3& d, double t0, double t1,
                                std::vector<double>& ts) const {
  if (half_space_) return;
  const auto add = [&](double t) {
    if (t > t0 && t < t1) ts.push_back(t);
  };
  const double b = glm::dot(p, d);
  add(-b);  // the lowest point of the ray
  const double r = glm::length(p);
  for (double h : kink_altitudes_) {
    const double radius = atmosphere_.bottom_radius + h;
    const double c = (r - radius) * (r + radius);
    const double discriminant = b * b - c;
    if (discriminant < 0.0) continue;
    // Roots of t^2 + 2 b t + c = 0 without cancellation: q = -(b + sign(b) sqrt(D)), q and c / q.
    const double q = -(b + std::copysign(std::sqrt(discriminant), b));
    add(q);
    if (q != 0.0) add(c / q);
  }
}

glm::dvec4 PathTracer::DensityIntegral(const glm::dvec3& p, const glm::dvec3& d, double t0, double t1) const {
  if (!(t1 > t0)) return glm::dvec4(0.0);
  if (half_space_) return half_space_densities_ * (t1 - t0);
  std::vector<double> ts = {t0, t1};
  AddBreakpoints(p, d, t0, t1, ts);
  std::sort(ts.begin(), ts.end());
  const auto f = [&](double t) { return shared::GetDensities(atmosphere_, glm::length(p + t * d)); };
  // Adaptive Simpson; the error of a panel is measured as an optical depth (weights: the largest
  // extinction of each medium), and the Richardson term is added to the result.
  int evaluations = 0;  // of f by adapt, for this integral
  std::function<glm::dvec4(double, double, const glm::dvec4&, const glm::dvec4&, const glm::dvec4&,
                           const glm::dvec4&, double, int)>
      adapt = [&](double a, double b, const glm::dvec4& fa, const glm::dvec4& fm, const glm::dvec4& fb,
                  const glm::dvec4& whole, double eps, int depth) -> glm::dvec4 {
    const double m = 0.5 * (a + b);
    const glm::dvec4 flm = f(0.5 * (a + m));
    const glm::dvec4 frm = f(0.5 * (m + b));
    const glm::dvec4 left = (m - a) / 6.0 * (fa + 4.0 * flm + fm);
    const glm::dvec4 right = (b - m) / 6.0 * (fm + 4.0 * frm + fb);
    evaluations += 2;
    const glm::dvec4 delta = left + right - whole;
    const double error = glm::dot(glm::abs(delta), max_extinction_);
    const double rounding = kQuadratureRelativeFloor * glm::dot(glm::abs(left + right), max_extinction_);
    if (depth <= 0 || evaluations >= kMaxQuadratureEvaluations || error <= 15.0 * std::max(eps, rounding)) {
      return left + right + delta / 15.0;
    }
    return adapt(a, m, fa, flm, fm, left, 0.5 * eps, depth - 1) + adapt(m, b, fm, frm, fb, right, 0.5 * eps, depth - 1);
  };
  glm::dvec4 total(0.0);
  // Panels per piece, so that no feature hides between the first samples; a ray cut by many
  // breakpoints (a density table's knots) is sampled closely enough by them.
  const int panels = ts.size() > 9 ? 1 : 4;
  for (std::size_t i = 0; i + 1 < ts.size(); ++i) {
    const double h = (ts[i + 1] - ts[i]) / panels;
    if (!(h > 0.0)) continue;
    for (int k = 0; k < panels; ++k) {
      const double a = ts[i] + k * h;
      const double b = k + 1 == panels ? ts[i + 1] : a + h;
      const glm::dvec4 fa = f(a), fm = f(0.5 * (a + b)), fb = f(b);
      total += adapt(a, b, fa, fm, fb, (b - a) / 6.0 * (fa + 4.0 * fm + fb), kOpticalDepthTolerance,
                     kMaxQuadratureDepth);
    }
  }
  return total;
}

void PathTracer::Transmittance(const glm::dvec3& origin, const glm::dvec3& view, std::span<double> out) const {
  glm::dvec3 p = origin;
  if (!EnterAtmosphere(p, view)) {
    std::fill(out.begin(), out.end(), 1.0);
    return;
  }
  double length;
  bool ground;
  Segment(p, view, length, ground);
  if (ground || length == kInfinity) {
    std::fill(out.begin(), out.end(), 0.0);
    return;
  }
  const glm::dvec4 densities = DensityIntegral(p, view, 0.0, length);
  for (std::size_t c = 0; c < channels_.size(); ++c) out[c] = std::exp(-OpticalDepth(channels_[c], densities));
}

void PathTracer::SingleScattering(const glm::dvec3& origin, const glm::dvec3& view, const glm::dvec3& sun,
                                  double rel_tolerance, std::span<double> out) const {
  std::fill(out.begin(), out.end(), 0.0);
  glm::dvec3 p = origin;
  if (!EnterAtmosphere(p, view)) return;
  double length;
  bool ground;
  Segment(p, view, length, ground);
  if (length == kInfinity) {
    // A half-space seen downwards: stop where every channel's transmittance is below e^-60.
    double smallest = kInfinity;
    for (const Channel& c : channels_) {
      if (c.majorant > 0.0) smallest = std::min(smallest, c.majorant);
    }
    if (smallest == kInfinity) return;
    length = 60.0 / smallest;
  }
  std::vector<double> breaks = {0.0, length};
  AddBreakpoints(p, view, 0.0, length, breaks);
  if (!half_space_) {
    // Edges of the planet's shadow: the cylinder of radius R_ground about the axis through the
    // planet centre along the sun, on the side away from the sun.
    const glm::dvec3 p_perp = p - glm::dot(p, sun) * sun;
    const glm::dvec3 v_perp = view - glm::dot(view, sun) * sun;
    const double a = glm::dot(v_perp, v_perp);
    const double b = glm::dot(p_perp, v_perp);
    const double c = glm::dot(p_perp, p_perp) - atmosphere_.bottom_radius * atmosphere_.bottom_radius;
    const double discriminant = b * b - a * c;
    if (a > 0.0 && discriminant >= 0.0) {
      for (double t : {(-b - std::sqrt(discriminant)) / a, (-b + std::sqrt(discriminant)) / a}) {
        if (t > 0.0 && t < length) breaks.push_back(t);
      }
    }
  }
  std::sort(breaks.begin(), breaks.end());

  const double nu = glm::dot(view, sun);
  const double rayleigh_phase = shared::EvaluatePhaseFunction(rayleigh_phase_, rayleigh_g_, nu);
  const double mie_phase = shared::GetMiePhase(atmosphere_, nu);
  const std::size_t n = channels_.size();

  const auto integrate = [&](int panels) {
    std::vector<double> result(n, 0.0);
    double t_previous = 0.0;
    glm::dvec4 view_densities(0.0);  // density integrals from p to t_previous
    for (std::size_t i = 0; i + 1 < breaks.size(); ++i) {
      const double h = (breaks[i + 1] - breaks[i]) / panels;
      if (!(h > 0.0)) continue;
      for (int k = 0; k < panels; ++k) {
        const double a = breaks[i] + k * h;
        for (int j = 0; j < 8; ++j) {
          const double t = a + 0.5 * h * (1.0 + kGaussNodes[j]);
          const double w = 0.5 * h * kGaussWeights[j];
          view_densities += DensityIntegral(p, view, t_previous, t);
          t_previous = t;
          const glm::dvec3 x = p + t * view;
          double sun_length;
          bool sun_ground;
          Segment(x, sun, sun_length, sun_ground);
          if (sun_ground || sun_length == kInfinity) continue;
          const glm::dvec4 sun_densities = DensityIntegral(x, sun, 0.0, sun_length);
          const glm::dvec4 densities = Densities(x);
          for (std::size_t c = 0; c < n; ++c) {
            const Channel& ch = channels_[c];
            const double scattering = ch.rayleigh_scattering * densities.x * rayleigh_phase +
                                      ch.mie_scattering * densities.y * mie_phase;
            result[c] += w * scattering *
                         std::exp(-OpticalDepth(ch, view_densities) - OpticalDepth(ch, sun_densities));
          }
        }
      }
    }
    return result;
  };

  std::vector<double> previous = integrate(2);
  for (int panels = 4; panels <= 4096; panels *= 2) {
    const std::vector<double> current = integrate(panels);
    double change = 0.0;
    for (std::size_t c = 0; c < n; ++c) {
      if (current[c] != 0.0) change = std::max(change, std::abs(current[c] - previous[c]) / std::abs(current[c]));
    }
    previous = current;
    if (change <= rel_tolerance) break;
  }
  std::copy(previous.begin(), previous.end(), out.begin());
}

std::vector<double> PathTracer::DirectTransmittedPower() const {
  if (half_space_) throw Error("the direct transmitted power needs a spherical atmosphere");
  const double rg = atmosphere_.bottom_radius;
  const double rt = atmosphere_.top_radius;
  std::vector<double> power(channels_.size(), 0.0);
  std::vector<double> transmittance(channels_.size());
  constexpr int kPanels = 200;
  const double h = (rt - rg) / kPanels;
  for (int k = 0; k < kPanels; ++k) {
    for (int j = 0; j < 8; ++j) {
      const double b = rg + (k + 0.5 * (1.0 + kGaussNodes[j])) * h;
      const double w = 0.5 * h * kGaussWeights[j];
      // Enter the top sphere at impact parameter b, travelling along +z.
      const glm::dvec3 entry(b, 0.0, -std::sqrt((rt - b) * (rt + b)));
      Transmittance(entry, glm::dvec3(0.0, 0.0, 1.0), transmittance);
      for (std::size_t c = 0; c < power.size(); ++c) power[c] += w * 2.0 * kPi * b * transmittance[c];
    }
  }
  return power;
}

}  // namespace atmo::cpu
