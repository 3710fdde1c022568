// A Monte Carlo volumetric path tracer for the atmospheres of AtmosphereParameters: the engine of
// the `reference` model (models/reference_model.h), and deterministic quadratures of the same
// physics (transmittance, single scattering) to check it against.
//
// What it estimates: the radiance per unit solar irradiance at the top of the atmosphere that
// reaches a point along -view after one or more scatterings (a point sun, so the sun disc itself
// is never part of it), per channel. The media and phase functions are the shared definitions
// (shared/medium.glsl, shared/phase.glsl), so the tracer describes the same atmosphere as every
// model; it uses no table.
//
// The estimator, per channel (each channel traces its own path with its own majorant; there is no
// spectral sharing of paths, so each channel is an ordinary unbiased path-tracing estimator):
//   - free flights by delta tracking against the majorant sigma_bar = sum over media of their
//     extinction at density 1 (densities are clamped to [0, 1], so sigma_t <= sigma_bar everywhere);
//     a tentative collision is real with probability sigma_t / sigma_bar, and a real one scatters
//     with weight sigma_s / sigma_t (ozone and Mie absorption only lower the weight);
//   - optionally (on by default) the first tentative collision of a segment whose end contributes
//     nothing (escape to space, or the first hit of the view ray on the ground, which docs/design.md §4
//     leaves out) is forced into the segment: sampled from the truncated exponential, weight
//     1 - exp(-sigma_bar L). The event it removes (no tentative collision at all) scores 0, so the
//     expectation is unchanged; thin atmospheres then get a sample on every path;
//   - next-event estimation to the sun (PathTracerSettings::next_event), either at every real
//     scattering vertex: weight * phase(nu) * T_sun with nu = dot(path direction, sun), T_sun by
//     ratio tracking (unbiased), 0 when the sun ray meets the ground (planet shadow); or on the
//     segment before it (SegmentSunlight): the expectation of that vertex estimate, the integral
//     over the segment's lit part of T sigma_s p(nu) T_sun, estimated by stratified points from
//     a proposal that follows a proxy of the integrand, both transmittances by residual ratio
//     tracking, scored in the order bin of the vertex, which then takes no estimate of its own.
//     The default (kAuto) takes the segment estimate on the view ray (order 1: the forward
//     peak towards the sun makes vertex estimates there noisy) and on the segments that start in
//     the planet's shadow, where vertex estimates are mostly 0 and rarely large (twilight), and
//     on the rest of a path once one of its segments started there (its lit vertices are rare and
//     heavy), and the vertex estimate elsewhere (5-10x cheaper, and as good where every vertex is lit);
//   - at a vertex in the planet's shadow the new direction comes, with probability
//     shadow_guiding, from a guide instead of the phase function: by default (guiding kTable) half
//     of the guided draws (table_fraction) from the sampler of a table of the radiance the vertex
//     sees from each direction, orders 1 and 2 (guide_orders; built once per tracer on first use:
//     GuideTable), the
//     others (all of them with kLobes) from a Henyey-Greenstein lobe (g 0.8) about the sun, or
//     (fraction horizon_lobe of them) a lobe about the sun's azimuth just below the local
//     horizontal, where the lit air of a deep-twilight vertex lies;
//     weighted by phase / mixture pdf (one-sample MIS, weight <= 1 / (1 - shadow_guiding));
//   - splitting at the first vertex of a path in the shadow: shadow_splits directions, each with
//     its segment estimate at 1/N of the weight, one of them continued with the full weight;
//   - importance splitting at the later shadowed vertices (importance_splitting): a proxy of the
//     lit air a vertex sees (the table's integral over directions, or with kLobes ImportanceProxy
//     along one axis) times the path's weight, against the same product at
//     the path's first shadowed vertex, says into how many copies (of 1/n of the weight) the path
//     is split there, and Russian roulette is taken relative to that weight, so the rare paths
//     that climb to the bright air above the shadow no longer carry most of the estimate alone;
//   - the medium that scatters is Rayleigh or Mie with probability proportional to its scattering
//     coefficient at the point; the new direction is sampled exactly from its phase function;
//   - a Lambertian ground: next-event estimation albedo/pi * cos * T_sun and a cosine-weighted
//     bounce with weight albedo (not at the view ray's own first hit, unless asked for;
//     TraceQuery::ground_only scores that hit alone);
//   - unlimited orders; Russian roulette from order 3 on with survival min(weight, 0.95).
// Direction convention (docs/design.md §2): paths run from the observer outwards; at a vertex reached
// along direction d, light that arrives from direction d' (travelling along -d') and leaves along
// -d is scattered by the angle whose cosine is dot(-d', -d) = dot(d, d'). That cosine is the nu of
// the phase functions: for the sun, d' = sun and nu = dot(view, sun). So phase sampling draws
// cos(d, d') from p(nu): g > 0 keeps paths going forward, i.e. the peak is towards the sun.
//
// Randomness: every (seed, query, path index, channel) has its own splitmix64 stream, so results
// do not depend on the thread count; paths are traced in fixed blocks that are reduced in order.
#pragma once

#include <algorithm>
#include <array>
#include <cmath>
#include <cstdint>
#include <memory>
#include <numbers>
#include <span>
#include <vector>

#include <glm/glm.hpp>

#include "atmo/parameters.h"
#include "shared/shared.h"

namespace atmo::cpu {

// Contributions are kept separately for scattering orders 1, 2, 3, 4 and >= 5 (a ground
// reflection counts as one order, like a scattering in the air).
inline constexpr int kOrderBins = 5;
// Tally slots per channel: 0 = all orders, 1 + k = order bin k.
inline constexpr int kTallySlots = 1 + kOrderBins;

struct Estimate {
  double mean = 0.0;
  double standard_error = 0.0;  // of the mean, from the sample variance of the per-path values
  // The relative variance of the variance (MCNP's VOV, X-5 Monte Carlo Team 2003):
  // sum (x - mean)^4 / (sum (x - mean)^2)^2 - 1/n over the per-path values x, the squared
  // relative standard error of the estimated variance. It is about (kurtosis - 1) / n for a
  // well-behaved estimator and near 1 when one path carries most of the sample variance, i.e.
  // when the standard error itself is not yet to be trusted (deep twilight's heavy tails).
  double variance_of_variance = 0.0;
};

// Sums of per-path values and of their second, third and fourth powers, per channel and slot.
struct PathTally {
  std::uint64_t paths = 0;
  std::vector<double> sum;     // [channel * kTallySlots + slot]
  std::vector<double> sum_sq;  // same layout
  std::vector<double> sum_cube;
  std::vector<double> sum_quad;

  explicit PathTally(std::size_t channel_count = 0)
      : sum(channel_count * kTallySlots, 0.0),
        sum_sq(channel_count * kTallySlots, 0.0),
        sum_cube(channel_count * kTallySlots, 0.0),
        sum_quad(channel_count * kTallySlots, 0.0) {}
  void Add(std::size_t index, double x);  // one path's value into [index] of every sum
  void Reset();                           // no paths
  void Merge(const PathTally& other);
  Estimate Get(std::size_t channel, int slot) const;
};

// Where the next-event estimate to the sun is taken (see the file comment).
enum class NextEventEstimation {
  kVertex,   // at each real collision vertex
  kSegment,  // on every segment, as the integral over the lit part of the segment
  kAuto,     // kSegment on the view ray, on the segments that start in the planet's shadow and on
             // every later segment of such a path, kVertex on the others
};

// How the view ray's own collision is drawn (see PathTracer::GuidedViewCollision).
enum class ViewCollisions {
  kTracked,  // delta tracking, as every other segment
  kGuided,   // on a view ray that starts in the planet's shadow (with kTable guiding and
             // shadow_guiding > 0): by the guide table's importance along the ray
};

// How the collision on a segment that starts at a shadowed scattering vertex is drawn.
enum class ShadowCollisions {
  kTracked,  // delta tracking
  kGuided,   // as the guided view collision (with kTable guiding and shadow_guiding > 0), on the
             // segments whose end scores nothing
};

// What the guided draws at a shadowed vertex come from (see the file comment).
enum class ShadowGuiding {
  kLobes,  // the lobe about the sun and the horizon lobe (horizon_lobe); ImportanceProxy
  kTable,  // the tabulated first-order radiance proxy (GuideTable); its integral as importance
};

struct PathTracerSettings {
  bool forced_collisions = true;  // see the file comment
  int roulette_start_order = 3;   // Russian roulette after this many scattering events
  NextEventEstimation next_event = NextEventEstimation::kAuto;
  int segment_samples = 2;  // stratified points per segment integral, >= 1
  // At a scattering vertex in the planet's shadow, the probability of drawing the new direction
  // from a guiding lobe instead of the phase function (one-sample MIS); 0: off.
  double shadow_guiding = 0.5;
  // The fraction of those guided draws taken from the horizon lobe (about the sun's azimuth, just
  // below the local horizontal) rather than from the lobe about the sun, in [0, 1].
  double horizon_lobe = 0.5;
  // At the first scattering vertex of a path in the planet's shadow, the number of directions
  // drawn (splitting): each takes its segment estimate with 1/N of the weight, one goes on; >= 1.
  int shadow_splits = 1;
  // Importance splitting at the later shadowed vertices of a path (see TracePath).
  bool importance_splitting = true;
  // Where the guided draws (shadow_guiding) come from, and the importance of importance splitting.
  ShadowGuiding guiding = ShadowGuiding::kTable;
  // With kTable: the fraction of the guided draws from the table's sampler, the rest from the
  // lobes (split by horizon_lobe), in [0, 1].
  double table_fraction = 0.5;
  // With kTable: the scattering orders of the light the table's cells hold, 1 .. 4: 1 is the
  // first-order radiance proxy alone; each further order adds the light that the air along the
  // cell's direction scatters isotropically from the previous order's radiance (its integral over
  // directions, from the table itself), so that shadowed air lit only by other air counts too.
  int guide_orders = 2;
  ViewCollisions view_collisions = ViewCollisions::kGuided;
  ShadowCollisions shadow_collisions = ShadowCollisions::kGuided;
};

// One radiance query in the tracer's frame (see PathTracer::ObserverPosition).
// A shell of uniform, isotropic emission (the airglow of atmo::NightSky): what the paths of a
// glow query (TraceQuery::glow) score instead of the sun.
struct GlowSource {
  double inner_radius = 0.0;     // m, from the planet's centre
  double outer_radius = 0.0;     // m
  std::vector<double> emission;  // per channel: radiance per metre of path inside the shell
};

struct TraceQuery {
  glm::dvec3 origin;  // observer position
  glm::dvec3 sun;     // unit, towards the sun
  glm::dvec3 view;    // unit, from the observer outwards
  // Whether the view ray's own first hit on the ground reflects light (the flux estimator needs
  // it; radiance queries of docs/design.md §4 leave it out).
  bool include_first_ground_hit = false;
  // Whether to score only the light that the ground reflects at the view ray's first hit (the
  // ground term of images, SkyView::GroundRadiance): the view segment is not scattered in but
  // crossed with the weight of a ratio-tracking estimate of its transmittance, and paths whose
  // view ray misses the ground score 0. Implies include_first_ground_hit.
  bool ground_only = false;
  // A glow query: the paths score the light of this shell scattered once or more (the shell's own
  // light along the view ray, order 0, is left to the renderers, as the sun disc is), with no
  // estimate towards the sun and no sun-led guiding or splitting. At each scattering vertex and
  // ground reflection the path adds its weight times the shell's emission along the direction it
  // goes on in, attenuated (GlowAlong): a one-sample estimate of the in-scattered glow. Not owned.
  const GlowSource* glow = nullptr;
};

// Draws the cosine of the scattering angle from an atmosphere's tabulated Mie phase function
// (shared::TabulatedMiePhaseFunction) exactly: the density in the table's knot coordinate u,
// f(u) = p(theta(u)) 2 pi sin(theta) dtheta/du with theta = pi (u / M)^2, is bounded on each of
// kPiecesPerKnot pieces per knot interval (p is monotone between knots, sin(theta) and u are
// bounded by the piece's ends), a piece is drawn by its bound's mass and u uniformly in it, and u is
// kept with probability f(u) / bound (99.6 % of the draws are kept on us-standard's table).
class TabulatedPhaseSampler {
 public:
  TabulatedPhaseSampler() = default;
  explicit TabulatedPhaseSampler(const shared::AtmosphereParameters& atmosphere);
  // The phase function's density in u (per unit u, over the sphere).
  double Density(double u) const;
  template <typename Uniform>
  double Sample(Uniform&& uniform) const {
    while (true) {
      const double mass = uniform() * cumulative_.back();
      const std::size_t piece = static_cast<std::size_t>(
          std::upper_bound(cumulative_.begin(), cumulative_.end() - 1, mass) - cumulative_.begin());
      const double u = (static_cast<double>(piece) + uniform()) / kPiecesPerKnot;
      if (uniform() * bound_[piece] <= Density(u)) {
        const double t = u / (shared::kPhaseTableSize - 1);
        return std::cos(std::numbers::pi * t * t);
      }
    }
  }

 private:
  static constexpr int kPiecesPerKnot = 16;
  std::array<double, shared::kPhaseTableSize> logs_{};
  std::vector<double> bound_;       // the density's bound on each piece
  std::vector<double> cumulative_;  // the bound's mass up to the end of each piece
};

class PathTracer {
 public:
  // Throws atmo::Error for invalid parameters.
  PathTracer(const AtmosphereParameters& parameters, const PathTracerSettings& settings = {});

  std::size_t channel_count() const { return channels_.size(); }
  bool half_space() const { return half_space_; }
  // Frames: spherical, planet-centred with the observer on the +z axis, so the observer's local
  // frame (x east, y north, z up) is the global one; half-space: the boundary plane is z = 0 and
  // the medium fills z < 0 (homogeneous, at the density of altitude 0; no ground).
  glm::dvec3 ObserverPosition(double altitude_m) const;

  // Traces paths [first, first + count) of `query` in parallel over fixed blocks of paths and
  // reduces the blocks in order: the result depends on (seed, query, first, count) only.
  PathTally Trace(const TraceQuery& query, std::uint64_t seed, std::uint64_t first, std::uint64_t count) const;
  // The same paths on the calling thread, added to `tally`.
  void TraceSerial(const TraceQuery& query, std::uint64_t seed, std::uint64_t first, std::uint64_t count,
                   PathTally& tally) const;

  // Transmittance from `origin` along `view` to the top of the atmosphere by adaptive quadrature
  // of the optical depth (no table); 0 where the ray meets the ground (or, in a half-space, goes
  // down for ever); 1 for a ray that misses the atmosphere.
  void Transmittance(const glm::dvec3& origin, const glm::dvec3& view, std::span<double> out) const;
  // Single scattering by deterministic quadrature: composite 8-point Gauss-Legendre along the
  // view ray between breakpoints (density kinks, the ray's lowest point, the edges of the planet
  // shadow), panels doubled until the relative change is <= rel_tolerance; the optical depths of
  // the view and sun rays by adaptive Simpson quadrature.
  void SingleScattering(const glm::dvec3& origin, const glm::dvec3& view, const glm::dvec3& sun,
                        double rel_tolerance, std::span<double> out) const;

  // A flux estimator for energy checks: the radiance leaving the top of the atmosphere (ground
  // reflections included) averaged over points uniform on the top sphere and directions
  // cosine-weighted about the outward normal. Power out = 4 pi R_top^2 * pi * mean. Spherical
  // geometry only.
  PathTally TopOutgoingRadiance(const glm::dvec3& sun, std::uint64_t seed, std::uint64_t count) const;
  // A flux estimator for the sky's irradiance: E = integral of L(w) max(n.w, 0) dOmega at `origin`
  // (the scattered light only, as radiance queries score it: no direct sun, the view ray's own
  // ground hit left out) by directions cosine-weighted about the unit normal `normal`, each with
  // one path per channel; the tally's per-path values are pi L, so its mean is E per unit solar
  // irradiance with its standard error. On the ground facing up it is the diffuse horizontal
  // irradiance.
  PathTally DiffuseIrradiance(const glm::dvec3& origin, const glm::dvec3& normal, const glm::dvec3& sun,
                              std::uint64_t seed, std::uint64_t count) const;
  // The unscattered sunlight that crosses the atmosphere without meeting the ground, as a power
  // per unit irradiance (m^2): integral over impact parameters b in [R_ground, R_top] of
  // 2 pi b T(b) db, by quadrature.
  std::vector<double> DirectTransmittedPower() const;

  // The direction sampling of a scattering vertex at x in the planet's shadow (exposed for tests):
  // a direction from the mixture of shadow guiding for a path that reached x along d and
  // scatters off Rayleigh (mie false) or Mie, from the stream `seed`; `weight` is set to
  // phase / mixture pdf, so its mean over draws is 1 and weight * f(direction) is unbiased for
  // the phase-weighted mean of f.
  glm::dvec3 SampleShadowDirection(const glm::dvec3& x, const glm::dvec3& d, const glm::dvec3& sun, bool mie,
                                   std::uint64_t seed, double& weight, std::size_t channel = 0) const;
  // The radiance-proxy guiding table (exposed for tests; spherical geometry, built on first use):
  // a direction drawn from its sampler at x for channel `channel` from the stream `seed`, the
  // sampler's solid-angle pdf of any unit direction w, and the importance of x (the proxy's
  // integral over directions, interpolated between the table's positions).
  glm::dvec3 SampleGuideTable(const glm::dvec3& x, const glm::dvec3& sun, std::size_t channel,
                              std::uint64_t seed) const;
  double GuideTablePdf(const glm::dvec3& x, const glm::dvec3& sun, const glm::dvec3& w, std::size_t channel) const;
  double GuideTableImportance(const glm::dvec3& x, const glm::dvec3& sun, std::size_t channel) const;
  // The edges of its direction cells: cosines to the local zenith (ascending, -1 to 1) and |azimuth|
  // from the sun's (0 to pi); the pdf is constant on each cell and its mirror image.
  void GuideTableEdges(std::vector<double>& mu_edges, std::vector<double>& phi_edges) const;
  // Whether the guide table has been built (it is, only once a shadowed vertex needed it).
  bool GuideTableBuilt() const;

  // Phase-function sampling (exposed for tests): a cosine nu distributed with the normalised phase
  // function `kind` (shared::kPhase*) of asymmetry g, from two uniform numbers in [0, 1) and a
  // source of more for rejection.
  template <typename Uniform>
  static double SamplePhaseCosine(int kind, double g, Uniform&& uniform);
  // The same for this atmosphere's media: also the tabulated Mie phase function (shared::kPhaseTabulated).
  template <typename Uniform>
  double SampleMediumPhaseCosine(int kind, double g, Uniform&& uniform) const {
    return kind == shared::kPhaseTabulated ? tabulated_phase_.Sample(uniform) : SamplePhaseCosine(kind, g, uniform);
  }

 private:
  struct Channel {
    double rayleigh_scattering, rayleigh_extinction;
    double mie_scattering, mie_extinction;
    double ozone_extinction;
    double water_vapor_extinction;
    double majorant;
    double albedo;
  };
  struct Collision;
  class Rng;
  struct GuideTable;
  // The deterministic parts of a segment estimate and of the guided view collision, and the view
  // ray's of both per channel: the same for every path of a query, so made once (PlanViewRays).
  struct SegmentPlan;
  struct CollisionPlan;
  struct ViewRayPlan;
  // Where x falls in the guide table: the four neighbouring positions (altitude, sun zenith
  // angle) with their bilinear weights, and x's local frame (up, towards the sun's azimuth, across).
  struct GuidePosition {
    int index[4];
    double weight[4];
    glm::dvec3 up, towards, across;
  };

  glm::dvec4 Densities(const glm::dvec3& p) const;
  // Upper bounds of the three densities on the segment [p, p + length d]: the profiles' maxima
  // over the altitudes at or above the segment's lowest point.
  glm::dvec4 MaxDensities(const glm::dvec3& p, const glm::dvec3& d, double length) const;
  double Majorant(const Channel& c, const glm::dvec3& p, const glm::dvec3& d, double length) const {
    return half_space_ ? c.majorant : OpticalDepth(c, MaxDensities(p, d, length));
  }
  // Distance along d to where the ray leaves the atmosphere, and whether it ends on the ground.
  void Segment(const glm::dvec3& p, const glm::dvec3& d, double& length, bool& ground) const;
  // Moves an observer above the atmosphere to where `d` enters it; false when the ray misses it.
  bool EnterAtmosphere(glm::dvec3& p, const glm::dvec3& d) const;
  double SunTransmittance(const glm::dvec3& p, const glm::dvec3& sun, const Channel& c, Rng& rng) const;
  // Ratio-tracking estimate of the transmittance of the segment [p, p + length d] (finite length).
  double RatioTracking(const glm::dvec3& p, const glm::dvec3& d, double length, const Channel& c, Rng& rng) const;
  // The glow's radiance arriving at p from direction d (travelling along -d): the integral over the
  // ray's parts inside the shell of the emission times the transmittance from p (ratio tracking to
  // where the ray enters each part; the air inside the shell, above 80 km, is taken as clear: its
  // optical depth is below 1e-4), 0 past the ground.
  double GlowAlong(const GlowSource& glow, const glm::dvec3& p, const glm::dvec3& d, const Channel& c,
                   Rng& rng) const;
  // The part [shadow_begin, shadow_end] of the segment [p, p + length d] inside the planet's
  // shadow (the cylinder of radius R_ground about the sun axis, behind the planet: a convex set,
  // so one interval); empty (shadow_begin >= shadow_end) when the segment stays lit.
  // An unbiased estimate of the transmittance from x to the sun (0 in the planet's shadow) by
  // residual ratio tracking against a piecewise-linear control (spherical geometry).
  double ResidualSunTransmittance(const glm::dvec3& x, const glm::dvec3& sun, const Channel& c, Rng& rng) const;
  // Whether the sun ray from x meets the ground (x above it).
  bool InShadow(const glm::dvec3& x, const glm::dvec3& sun) const;
  void ShadowInterval(const glm::dvec3& p, const glm::dvec3& d, double length, const glm::dvec3& sun,
                      double& shadow_begin, double& shadow_end) const;
  // The segment estimate of next-event estimation (spherical geometry, finite length): an
  // unbiased estimate of integral_0^length T(p, x_t) sum_media sigma_s(x_t) p(nu) T_sun(x_t) dt,
  // x_t = p + t d, nu = dot(d, sun), i.e. the expected vertex estimate at the next collision.
  // The nodes of a segment's quadratures and proposals: kSegmentIntervals intervals about its lowest
  // point (t = t_low + x |x|, x uniform), plus the shadow's edges that fall inside (none when
  // shadow_begin >= shadow_end), ascending in ts (room for kSegmentIntervals + 1, + 3 with the
  // shadow's edges); returns the count.
  int SegmentNodes(const glm::dvec3& p, const glm::dvec3& d, double length, double shadow_begin, double shadow_end,
                   double* ts) const;
  // T(p, p + t_j d) for the ascending t[0 .. k), from one residual-ratio-tracking walk against the
  // control extinction linear between the n nodes ts (values sigma_node, integrals tau_node).
  void ResidualViewTransmittances(const glm::dvec3& p, const glm::dvec3& d, const double* ts, const double* sigma_node,
                                  const double* tau_node, int n, const double* t, int k, const Channel& c, Rng& rng,
                                  double* out) const;
  // The view ray's collision at t drawn by the guide table's importance, with the weight factor
  // T / pdf that, times sigma_t there, keeps its expectation (view_collisions=guided); false: no
  // collision. The proposal comes from PlanGuidedViewCollision on the same segment.
  void PlanGuidedViewCollision(const glm::dvec3& p, const glm::dvec3& d, double length, const glm::dvec3& sun,
                               const Channel& c, std::size_t channel, CollisionPlan& plan) const;
  bool GuidedViewCollision(const CollisionPlan& plan, const glm::dvec3& p, const glm::dvec3& d, const Channel& c,
                           Rng& rng, double& t, double& factor) const;
  double SegmentSunlight(const glm::dvec3& p, const glm::dvec3& d, double length, const glm::dvec3& sun,
                         const Channel& c, Rng& rng) const;
  // The same in two steps: the plan of the segment [p, p + length d], then one estimate from it.
  void PlanSegmentSunlight(const glm::dvec3& p, const glm::dvec3& d, double length, const glm::dvec3& sun,
                           const Channel& c, SegmentPlan& plan) const;
  double SegmentSunlight(const SegmentPlan& plan, const glm::dvec3& p, const glm::dvec3& d, const glm::dvec3& sun,
                         const Channel& c, Rng& rng) const;
  // The view ray's plan for channel c (segment estimate and guided collision, where TracePath's
  // first segment takes them), and for every channel.
  void PlanViewRay(const TraceQuery& query, const Channel& c, ViewRayPlan& plan) const;
  std::vector<ViewRayPlan> PlanViewRays(const TraceQuery& query) const;
  void TraceSerial(const TraceQuery& query, const std::vector<ViewRayPlan>& plans, std::uint64_t seed,
                   std::uint64_t first, std::uint64_t count, PathTally& tally) const;
  // Density integrals along the sun ray from x to the top, from a small table (importance
  // sampling of SegmentSunlight only: its errors change the variance, never the mean).
  glm::dvec4 SunDensityProxy(const glm::dvec3& x, const glm::dvec3& sun) const;
  // The same by the trapezoidal rule along (r, mu) (the table's entries).
  glm::dvec4 DensityIntegralToTop(double r, double mu) const;
  // The new direction at a scattering vertex x in the planet's shadow, reached along d, scattered
  // by the phase function (kind, g): drawn from the mixture of the phase function and the guiding
  // lobes; `mis_weight` is set to phase / mixture pdf (<= 1 / (1 - shadow_guiding)).
  glm::dvec3 GuidedDirection(const glm::dvec3& x, const glm::dvec3& d, const glm::dvec3& sun, int kind, double g,
                             std::size_t channel, Rng& rng, double& mis_weight) const;
  // The horizon lobe's frame at x: up, towards the sun's azimuth, across, and the axis elevation.
  void HorizonFrame(const glm::dvec3& x, const glm::dvec3& sun, glm::dvec3& up, glm::dvec3& towards,
                    glm::dvec3& across, double& e0) const;
  // A proxy of the light a shadowed vertex x can scatter (importance splitting only).
  double ImportanceProxy(const glm::dvec3& x, const glm::dvec3& sun, const Channel& c) const;
  // The guide table, built on the first call (thread-safe).
  const GuideTable& Guide() const;
  void BuildGuideTable(GuideTable& table) const;
  // The first-order radiance proxy seen from x along w, per channel (out[channel_count()]):
  // integral over the lit part of the segment of sum_m p_m(w.sun) sigma_s,m exp(-tau_view -
  // tau_sun), tau_view by the trapezoidal rule on SegmentSunlight's nodes, tau_sun from the proxy
  // table; 0 for a segment entirely in the shadow.
  void RayRadianceProxy(const glm::dvec3& x, const glm::dvec3& w, const glm::dvec3& sun, double* out) const;
  // The next order's proxy along x + t w, per channel: the integral of exp(-tau_view) sigma_s
  // times `previous` (per channel and table position: the previous order's radiance integrated
  // over directions) / 4 pi at each point, the trapezoidal rule on SegmentSunlight's nodes.
  void RayNextOrderProxy(const GuideTable& table, const std::vector<double>& previous, const glm::dvec3& x,
                         const glm::dvec3& w, const glm::dvec3& sun, double* out) const;
  GuidePosition LocateGuide(const GuideTable& table, const glm::dvec3& x, const glm::dvec3& sun) const;
  glm::dvec3 SampleGuide(const GuideTable& table, const GuidePosition& at, std::size_t channel, Rng& rng) const;
  double GuidePdf(const GuideTable& table, const GuidePosition& at, std::size_t channel, const glm::dvec3& w) const;
  double GuideImportance(const GuideTable& table, const GuidePosition& at, std::size_t channel) const;
  // One path of one channel, its view ray from `view_plan` (PlanViewRay of the same query and
  // channel); adds its contributions per order bin to `orders`.
  void TracePath(const TraceQuery& query, const Channel& c, const ViewRayPlan& view_plan, Rng& rng,
                 std::array<double, kOrderBins>& orders) const;
  // Integrals of the three densities along p + t d over [t0, t1].
  glm::dvec4 DensityIntegral(const glm::dvec3& p, const glm::dvec3& d, double t0, double t1) const;
  // Parameters t in (t0, t1) where p + t d crosses an altitude at which a density profile may
  // have a kink, and the ray's lowest point.
  void AddBreakpoints(const glm::dvec3& p, const glm::dvec3& d, double t0, double t1, std::vector<double>& t) const;
  double OpticalDepth(const Channel& c, const glm::dvec4& densities) const {
    return c.rayleigh_extinction * densities.x + c.mie_extinction * densities.y + c.ozone_extinction * densities.z +
           c.water_vapor_extinction * densities.w;
  }

  shared::AtmosphereParameters atmosphere_;  // profiles and radii (channels come from channels_)
  TabulatedPhaseSampler tabulated_phase_;     // the Mie phase function, when tabulated
  std::vector<Channel> channels_;
  int rayleigh_phase_, mie_phase_;
  double rayleigh_g_, mie_g_;
  bool half_space_;
  glm::dvec4 half_space_densities_;
  // With a density table: entry i holds the largest densities of knots i .. kDensityTableSize - 1,
  // which bound the (exponential between knots) densities above knot i.
  std::vector<glm::dvec4> table_maximum_above_;
  std::vector<double> kink_altitudes_;
  glm::dvec4 max_extinction_;  // per medium, over channels: weights of the quadrature error
  PathTracerSettings settings_;
  std::vector<glm::dvec4> sun_proxy_;  // [r index * kSunProxyMu + mu index], see SunDensityProxy
  // Built on first use by a shadowed vertex (Guide()); shared by copies of the tracer.
  std::shared_ptr<GuideTable> guide_;
};

// Depressed cubic x^3 + p x + q = 0 with p > 0 (one real root), by Cardano's formula in a form
// without cancellation for either sign of q.
inline double SolveDepressedCubic(double p, double q) {
  const double z = -0.5 * q;
  const double k = p / 3.0;
  const double a = std::cbrt(std::abs(z) + std::sqrt(z * z + k * k * k));
  const double root = a - k / a;
  return z < 0.0 ? -root : root;
}

template <typename Uniform>
double PathTracer::SamplePhaseCosine(int kind, double g, Uniform&& uniform) {
  const double u = uniform();
  switch (kind) {
    case shared::kPhaseRayleigh:
      // CDF (nu^3 + 3 nu + 4) / 8 = u: nu^3 + 3 nu + (4 - 8 u) = 0.
      return std::clamp(SolveDepressedCubic(3.0, 4.0 - 8.0 * u), -1.0, 1.0);
    case shared::kPhaseModifiedRayleigh:
      // CDF of 1.4 + 0.5 nu^2 over its integral 47/15: (1.4 nu + nu^3/6 + 1.4 + 1/6) / (47/15) = u,
      // times 6: nu^3 + 8.4 nu + (9.4 - 18.8 u) = 0.
      return std::clamp(SolveDepressedCubic(8.4, 9.4 - 18.8 * u), -1.0, 1.0);
    case shared::kPhaseHenyeyGreenstein:
    case shared::kPhaseCornetteShanks: {
      // Henyey-Greenstein by inversion of its CDF; below |g| = 1e-6 the phase function differs
      // from isotropic by < 3e-6 relative, and the inversion formula loses precision, so use 1 - 2u.
      // Cornette-Shanks = HG * 3 (1 + nu^2) / (2 (2 + g^2)) <= HG * 3 / (2 + g^2): rejection
      // against HG with acceptance (1 + nu^2) / 2 (mean acceptance (2 + g^2) / 3 >= 2/3).
      double v = u;
      while (true) {
        double nu;
        if (std::abs(g) < 1e-6) {
          nu = 1.0 - 2.0 * v;
        } else {
          const double s = (1.0 - g * g) / (1.0 - g + 2.0 * g * v);
          nu = std::clamp((1.0 + g * g - s * s) / (2.0 * g), -1.0, 1.0);
        }
        if (kind == shared::kPhaseHenyeyGreenstein || uniform() * 2.0 < 1.0 + nu * nu) return nu;
        v = uniform();
      }
    }
    default:
      return 1.0 - 2.0 * u;
  }
}

}  // namespace atmo::cpu
