#include "models/reference_model.h"

#include <chrono>
#include <cmath>
#include <cstdlib>
#include <string>

#include "atmo/error.h"
#include "models/model_options.h"
#include "shared/shared.h"

namespace atmo {
namespace {

std::uint64_t ParseCount(const std::string& key, const std::string& value, std::uint64_t lo, std::uint64_t hi) {
  char* end = nullptr;
  const unsigned long long v = std::strtoull(value.c_str(), &end, 10);
  if (value.empty() || value.find_first_not_of("0123456789") != std::string::npos || *end != '\0' || v < lo ||
      v > hi) {
    throw Error("option " + key + "=" + value + ": expected an integer in [" + std::to_string(lo) + ", " +
                std::to_string(hi) + "]");
  }
  return v;
}

}  // namespace

ReferenceSettings ReferenceSettings::FromOptions(const ModelOptions& options) {
  constexpr std::uint64_t kMaxPaths = std::uint64_t{1} << 40;
  ReferenceSettings s;
  bool max_given = false;
  for (const auto& [key, value] : options) {
    if (key == "samples") {
      s.samples = ParseCount(key, value, 2, kMaxPaths);
    } else if (key == "target_rel_error") {
      s.target_rel_error = ParseDoubleOption(key, value, 0.0, 1.0);
    } else if (key == "max_samples") {
      s.max_samples = ParseCount(key, value, 2, kMaxPaths);
      max_given = true;
    } else if (key == "max_vov") {
      s.max_vov = ParseDoubleOption(key, value, 1e-6, 1.0);
    } else if (key == "estimator") {
      if (value == "path") s.estimator = Estimator::kPath;
      else if (value == "single_quadrature") s.estimator = Estimator::kSingleQuadrature;
      else throw Error("option estimator=" + value + ": expected path or single_quadrature");
    } else if (key == "forced_collisions") {
      if (value != "on" && value != "off") throw Error("option forced_collisions=" + value + ": expected on or off");
      s.forced_collisions = value == "on";
    } else if (key == "nee") {
      if (value == "auto") s.next_event = cpu::NextEventEstimation::kAuto;
      else if (value == "segment") s.next_event = cpu::NextEventEstimation::kSegment;
      else if (value == "vertex") s.next_event = cpu::NextEventEstimation::kVertex;
      else throw Error("option nee=" + value + ": expected auto, segment or vertex");
    } else if (key == "nee_samples") {
      s.nee_samples = static_cast<int>(ParseCount(key, value, 1, 64));
    } else if (key == "shadow_guiding") {
      s.shadow_guiding = ParseDoubleOption(key, value, 0.0, 0.95);
    } else if (key == "horizon_lobe") {
      s.horizon_lobe = ParseDoubleOption(key, value, 0.0, 1.0);
    } else if (key == "shadow_splits") {
      s.shadow_splits = static_cast<int>(ParseCount(key, value, 1, 64));
    } else if (key == "importance_splitting") {
      if (value != "on" && value != "off") throw Error("option importance_splitting=" + value + ": expected on or off");
      s.importance_splitting = value == "on";
    } else if (key == "guiding") {
      if (value == "table") s.guiding = cpu::ShadowGuiding::kTable;
      else if (value == "lobes") s.guiding = cpu::ShadowGuiding::kLobes;
      else throw Error("option guiding=" + value + ": expected table or lobes");
    } else if (key == "table_fraction") {
      s.table_fraction = ParseDoubleOption(key, value, 0.0, 1.0);
    } else if (key == "guide_orders") {
      s.guide_orders = static_cast<int>(ParseCount(key, value, 1, 4));
    } else if (key == "view_collisions") {
      if (value == "guided") s.view_collisions = cpu::ViewCollisions::kGuided;
      else if (value == "tracked") s.view_collisions = cpu::ViewCollisions::kTracked;
      else throw Error("option view_collisions=" + value + ": expected guided or tracked");
    } else if (key == "shadow_collisions") {
      if (value == "guided") s.shadow_collisions = cpu::ShadowCollisions::kGuided;
      else if (value == "tracked") s.shadow_collisions = cpu::ShadowCollisions::kTracked;
      else throw Error("option shadow_collisions=" + value + ": expected guided or tracked");
    } else if (key == "quadrature_tolerance") {
      s.quadrature_tolerance = ParseDoubleOption(key, value, 1e-12, 0.1);
    } else if (key == "seed") {
      s.seed = ParseCount(key, value, 0, ~std::uint64_t{0});
    } else {
      throw Error("unknown option '" + key + "' for model reference (known: samples, target_rel_error, "
                  "max_samples, max_vov, estimator, forced_collisions, nee, nee_samples, shadow_guiding, horizon_lobe, "
                  "shadow_splits, importance_splitting, guiding, table_fraction, guide_orders, view_collisions, shadow_collisions, "
                  "quadrature_tolerance, seed)");
    }
  }
  if (!max_given) s.max_samples = std::max(s.max_samples, s.samples);
  if (s.max_samples < s.samples) {
    throw Error("option max_samples=" + std::to_string(s.max_samples) + " is below samples=" +
                std::to_string(s.samples));
  }
  return s;
}

ReferenceModel::ReferenceModel(const AtmosphereParameters& parameters, const ReferenceSettings& settings)
    : Model(parameters),
      settings_(settings),
      tracer_(parameters, cpu::PathTracerSettings{settings.forced_collisions, 3, settings.next_event, settings.nee_samples,
                                      settings.shadow_guiding, settings.horizon_lobe, settings.shadow_splits,
                                      settings.importance_splitting, settings.guiding,
                                      settings.table_fraction, settings.guide_orders, settings.view_collisions,
                                      settings.shadow_collisions}) {}

std::unique_ptr<SkyView> ReferenceModel::View(double altitude_m, const glm::dvec3& sun_direction) const {
  if (!std::isfinite(altitude_m) || (parameters().geometry == Geometry::kSpherical && altitude_m < 0.0)) {
    throw Error("altitude_m must be finite (and >= 0 above a planet) for model reference (got " +
                std::to_string(altitude_m) + ")");
  }
  CheckDirection(sun_direction, "the sun direction");
  return std::make_unique<ReferenceSkyView>(*this, altitude_m, glm::normalize(sun_direction));
}

ReferenceSkyView::ReferenceSkyView(const ReferenceModel& model, double altitude_m, const glm::dvec3& sun)
    : SkyView(altitude_m, sun, model.channel_count(), model.parameters().sun_angular_radius_rad),
      model_(model),
      origin_(model.tracer().ObserverPosition(altitude_m)) {}

cpu::TraceQuery ReferenceSkyView::Query(const glm::dvec3& view) const {
  CheckDirection(view, "the view direction");
  cpu::TraceQuery query;
  query.origin = origin_;
  query.sun = sun_direction();
  query.view = glm::normalize(view);
  return query;
}

namespace {

OrderEstimate ToOrderEstimate(const cpu::PathTally& tally, std::size_t channels) {
  OrderEstimate e;
  e.paths = tally.paths;
  for (std::size_t c = 0; c < channels; ++c) {
    e.total.push_back(tally.Get(c, 0));
    std::array<cpu::Estimate, cpu::kOrderBins> orders;
    for (int k = 0; k < cpu::kOrderBins; ++k) orders[k] = tally.Get(c, 1 + k);
    e.orders.push_back(orders);
  }
  return e;
}

// The doubling's stopping test: in every channel the relative standard error at most `target`
// and a standard error that is itself trustworthy, i.e. not set by a few paths: the relative
// variance of the variance at most `max_vov` (MCNP's statistical check, bound 0.1). In deep
// twilight one path in 10^5 can carry several per cent of an estimate; until such paths are
// either absent or many, the sample variance is low by luck and the VOV says so.
bool Converged(const cpu::PathTally& tally, std::size_t channels, double target, double max_vov) {
  for (std::size_t c = 0; c < channels; ++c) {
    const cpu::Estimate e = tally.Get(c, 0);
    if (e.standard_error > target * std::abs(e.mean)) return false;
    if (e.variance_of_variance > max_vov) return false;
  }
  return true;
}

}  // namespace

OrderEstimate ReferenceSkyView::EstimateByOrder(const glm::dvec3& view, std::uint64_t paths) const {
  const cpu::TraceQuery query = Query(view);
  return ToOrderEstimate(model_.tracer().Trace(query, model_.settings().seed, 0, paths), channel_count());
}

OrderEstimate ReferenceSkyView::EstimateByOrder(const glm::dvec3& view) const {
  const ReferenceSettings& s = model_.settings();
  const cpu::TraceQuery query = Query(view);
  cpu::PathTally tally = model_.tracer().Trace(query, s.seed, 0, s.samples);
  // Doubling: paths [n, 2n) are added to [0, n), so the result is that of the first 2n paths.
  while (s.target_rel_error > 0.0 && tally.paths < s.max_samples &&
         !Converged(tally, channel_count(), s.target_rel_error, s.max_vov)) {
    const std::uint64_t more = std::min(tally.paths, s.max_samples - tally.paths);
    tally.Merge(model_.tracer().Trace(query, s.seed, tally.paths, more));
  }
  return ToOrderEstimate(tally, channel_count());
}

void ReferenceSkyView::SingleScatteringQuadrature(const glm::dvec3& view, std::span<double> out) const {
  const cpu::TraceQuery query = Query(view);
  model_.tracer().SingleScattering(query.origin, query.view, query.sun, model_.settings().quadrature_tolerance, out);
}

void ReferenceSkyView::RadianceEstimate(const glm::dvec3& view, std::span<double> radiance,
                                        std::span<double> standard_error) const {
  if (model_.settings().estimator == ReferenceSettings::Estimator::kSingleQuadrature) {
    SingleScatteringQuadrature(view, radiance);
    std::fill(standard_error.begin(), standard_error.end(), 0.0);
    return;
  }
  const OrderEstimate e = EstimateByOrder(view);
  for (std::size_t c = 0; c < channel_count(); ++c) {
    radiance[c] = e.total[c].mean;
    standard_error[c] = e.total[c].standard_error;
  }
}

void ReferenceSkyView::Radiance(const glm::dvec3& view, std::span<double> out) const {
  std::vector<double> standard_error(channel_count());
  RadianceEstimate(view, out, standard_error);
}

void ReferenceSkyView::GroundRadianceEstimate(const glm::dvec3& view, std::span<double> radiance,
                                              std::span<double> standard_error) const {
  cpu::TraceQuery query = Query(view);
  query.ground_only = true;
  const cpu::PathTally tally = model_.tracer().Trace(query, model_.settings().seed, 0, model_.settings().samples);
  for (std::size_t c = 0; c < channel_count(); ++c) {
    const cpu::Estimate e = tally.Get(c, 0);
    radiance[c] = e.mean;
    standard_error[c] = e.standard_error;
  }
}

void ReferenceSkyView::GroundRadiance(const glm::dvec3& view, std::span<double> out) const {
  std::vector<double> standard_error(channel_count());
  GroundRadianceEstimate(view, out, standard_error);
}

void ReferenceSkyView::AddPaths(const glm::dvec3& view, bool ground, std::uint64_t first, std::uint64_t count,
                                cpu::PathTally& tally) const {
  cpu::TraceQuery query = Query(view);
  query.include_first_ground_hit = ground;
  model_.tracer().TraceSerial(query, model_.settings().seed, first, count, tally);
}

void ReferenceSkyView::AddGlowPaths(const glm::dvec3& view, bool ground, const cpu::GlowSource& glow,
                                    std::uint64_t first, std::uint64_t count, cpu::PathTally& tally) const {
  cpu::TraceQuery query = Query(view);
  query.include_first_ground_hit = ground;
  query.glow = &glow;
  model_.tracer().TraceSerial(query, model_.settings().seed, first, count, tally);
}

void ReferenceSkyView::Transmittance(const glm::dvec3& view, std::span<double> out) const {
  const cpu::TraceQuery query = Query(view);
  model_.tracer().Transmittance(query.origin, query.view, out);
}

void ReferenceSkyView::SunDiscRadiance(const glm::dvec3& view, std::span<double> out) const {
  // The limb-darkened disc of unit irradiance (shared/sun.glsl), attenuated along the view.
  const AtmosphereParameters& p = model_.parameters();
  const glm::dvec3 v = glm::normalize(view);
  const double mu = shared::GetSunDiscSurfaceCosine(glm::dot(v, sun_direction()), p.sun_angular_radius_rad);
  if (mu < 0.0) {
    std::fill(out.begin(), out.end(), 0.0);
    return;
  }
  Transmittance(v, out);
  for (std::size_t c = 0; c < out.size(); ++c) {
    const double wavelength_nm = p.wavelengths_nm[c];
    out[c] *= shared::GetSunDiscCentreRadiance(wavelength_nm, p.sun_angular_radius_rad, p.sun_limb_darkening) *
              (p.sun_limb_darkening ? shared::GetSunLimbDarkening(wavelength_nm, mu) : 1.0);
  }
}

}  // namespace atmo
