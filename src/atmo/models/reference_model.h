// Model `reference`: a Monte Carlo volumetric path tracer (cpu/path_tracer.h), the model every
// other model is judged by (docs/design.md §5). It uses no table: every query traces paths through
// the shared media and phase functions, and carries its standard error.
//
// Options (`--option key=value`; docs/models/reference.md):
//   samples=4096            paths per query and channel (`atmo sample --samples N`)
//   target_rel_error=0      > 0: double the paths until standard error / mean <= this for every
//                           channel (and max_vov holds), or until max_samples
//                           (`atmo sample --target-rel-error E`)
//   max_samples=16777216    cap of the doubling
//   max_vov=0.1             the doubling also goes on while a channel's relative variance of the
//                           variance (cpu::Estimate::variance_of_variance) is above this: its
//                           standard error is then set by a few paths (1: off)
//   estimator=path          path: all orders by path tracing; single_quadrature: single scattering
//                           only, by deterministic quadrature (standard error 0)
//   forced_collisions=on    force the first tentative collision of segments whose end scores 0
//   nee=auto                next-event estimation to the sun: vertex (at each collision), segment
//                           (the integral over each segment's lit part), auto (segment on the
//                           view ray, on segments that start in the planet's shadow and on the
//                           rest of such a path, vertex elsewhere)
//   nee_samples=2           stratified points per segment integral
//   shadow_guiding=0.5      at a vertex in the planet's shadow, the probability of drawing the
//                           new direction from the guide (MIS with the phase function)
//   horizon_lobe=0.5        the fraction of the lobes' draws from the lobe about the sun's
//                           azimuth just below the local horizontal (the rest: about the sun)
//   shadow_splits=1         directions drawn at a path's first shadowed vertex (splitting; 1: off)
//   importance_splitting=on split a path at its later shadowed vertices in proportion to a proxy
//                           of the lit air they see (off: no splitting)
//   guiding=table           where the guided draws come from: table (the tabulated first-order
//                           radiance proxy, whose integral is also the importance) or lobes
//                           (the sun and horizon lobes, importance along one axis)
//   table_fraction=0.5      with guiding=table: the fraction of the guided draws from the table
//                           (the rest from the lobes)
//   guide_orders=2          with guiding=table: the orders of the light the table holds, 1-4 (1:
//                           first-order light only; 2 adds the air lit by that light)
//   view_collisions=guided  guided: a view ray that starts in the planet's shadow draws its
//                           collision by the guide table's importance (with guiding=table);
//                           tracked: by delta tracking
//   shadow_collisions=guided guided: the segments that leave a shadowed vertex draw their
//                           collision as the guided view collision (end scoring nothing);
//                           tracked: by delta tracking
//   quadrature_tolerance=1e-6  relative tolerance of the single-scattering quadrature
//   seed=0                  the common seed (`--seed`)
// Observers may be above the top of the atmosphere (rays start where they enter it). Transmittance
// is computed by quadrature; the sun disc radiance is the limb-darkened disc of unit irradiance
// (shared/sun.glsl) times the transmittance.
// GroundRadiance is a Monte Carlo estimate too (`samples` paths that start with the view ray's
// first ground hit: the Lambertian ground lit by the attenuated sun and by the sky, all orders),
// so images through the generic renderer show the ground; RenderProgressive (atmo/render.h) traces
// radiance and ground in one path per sample instead (AddPaths).
#pragma once

#include <array>
#include <cstdint>
#include <memory>
#include <vector>

#include "atmo/model.h"
#include "cpu/path_tracer.h"

namespace atmo {

struct ReferenceSettings {
  enum class Estimator { kPath, kSingleQuadrature };

  std::uint64_t samples = 4096;
  double target_rel_error = 0.0;  // 0: a fixed number of samples
  std::uint64_t max_samples = std::uint64_t{1} << 24;
  double max_vov = 0.1;  // MCNP's bound on the variance of the variance for a trusted error
  Estimator estimator = Estimator::kPath;
  bool forced_collisions = true;
  cpu::NextEventEstimation next_event = cpu::NextEventEstimation::kAuto;
  int nee_samples = 2;
  double shadow_guiding = 0.5;
  double horizon_lobe = 0.5;
  int shadow_splits = 1;
  bool importance_splitting = true;
  cpu::ShadowGuiding guiding = cpu::ShadowGuiding::kTable;
  double table_fraction = 0.5;
  int guide_orders = 2;
  cpu::ViewCollisions view_collisions = cpu::ViewCollisions::kGuided;
  cpu::ShadowCollisions shadow_collisions = cpu::ShadowCollisions::kGuided;
  double quadrature_tolerance = 1e-6;
  std::uint64_t seed = 0;

  // Throws atmo::Error for an unknown key or a value out of range.
  static ReferenceSettings FromOptions(const ModelOptions& options);
};

// A radiance estimate split by scattering order, per channel.
struct OrderEstimate {
  std::uint64_t paths = 0;
  std::vector<cpu::Estimate> total;                                // all orders
  std::vector<std::array<cpu::Estimate, cpu::kOrderBins>> orders;  // orders 1, 2, 3, 4, >= 5
};

class ReferenceModel final : public Model {
 public:
  ReferenceModel(const AtmosphereParameters& parameters, const ReferenceSettings& settings);

  std::string_view name() const override { return "reference"; }
  void Precompute() override {}  // nothing to precompute
  std::unique_ptr<SkyView> View(double altitude_m, const glm::dvec3& sun_direction) const override;

  const ReferenceSettings& settings() const { return settings_; }
  const cpu::PathTracer& tracer() const { return tracer_; }

 private:
  ReferenceSettings settings_;
  cpu::PathTracer tracer_;
};

class ReferenceSkyView final : public SkyView {
 public:
  ReferenceSkyView(const ReferenceModel& model, double altitude_m, const glm::dvec3& sun);

  // Path tracing with the model's settings (samples, target_rel_error, max_samples).
  OrderEstimate EstimateByOrder(const glm::dvec3& view) const;
  // Exactly `paths` paths per channel (indices [0, paths)).
  OrderEstimate EstimateByOrder(const glm::dvec3& view, std::uint64_t paths) const;
  // Single scattering by deterministic quadrature (no tables).
  void SingleScatteringQuadrature(const glm::dvec3& view, std::span<double> out) const;

  void Radiance(const glm::dvec3& view, std::span<double> out) const override;
  void RadianceEstimate(const glm::dvec3& view, std::span<double> radiance,
                        std::span<double> standard_error) const override;
  void Transmittance(const glm::dvec3& view, std::span<double> out) const override;
  void SunDiscRadiance(const glm::dvec3& view, std::span<double> out) const override;
  // The light the ground reflects towards the observer at the view ray's first hit, attenuated
  // (0 for rays that miss the ground), from `samples` paths: mean and standard error per channel.
  void GroundRadianceEstimate(const glm::dvec3& view, std::span<double> radiance,
                              std::span<double> standard_error) const;
  void GroundRadiance(const glm::dvec3& view, std::span<double> out) const override;

  // For progressive rendering: adds paths [first, first + count) along `view` to `tally` (channel
  // count of the model), traced on the calling thread in path order. With `ground` each path also
  // scores the light reflected at the view ray's first ground hit, so its mean is Radiance +
  // GroundRadiance. A path's value depends only on (seed, view, ground, path index).
  void AddPaths(const glm::dvec3& view, bool ground, std::uint64_t first, std::uint64_t count,
                cpu::PathTally& tally) const;
  // The same for the light of `glow` scattered once or more (cpu::TraceQuery::glow): the night
  // glow's diffuse light, which the renderers' direct term (atmo::NightSky) leaves out.
  void AddGlowPaths(const glm::dvec3& view, bool ground, const cpu::GlowSource& glow, std::uint64_t first,
                    std::uint64_t count, cpu::PathTally& tally) const;

 private:
  cpu::TraceQuery Query(const glm::dvec3& view) const;

  const ReferenceModel& model_;
  glm::dvec3 origin_;
};

}  // namespace atmo
