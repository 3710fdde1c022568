#include "models/simple_model.h"

#include <algorithm>
#include <cmath>
#include <string>

#include "atmo/error.h"
#include "physics/shared_parameters.h"

namespace atmo {
namespace {

// The closed form's up vector u in the local frame (x east, y north, z up).
const shared::vec3 kUp(0.0, 0.0, 1.0);

// The density of a medium inside the half-space (altitudes < 0), which the closed form needs
// constant. The profile is a clamped exponential plus a linear term (DensityProfile), so it is
// checked at depths spread over 18 decades rather than proved constant; the presets' profiles
// are constant there (`simple`: 1; `earth`'s exponentials clamp to 1 below 0, its ozone tent to 0).
double ConstantDensityBelowPlane(const DensityProfile& profile, const char* medium) {
  const double density = profile.Evaluate(-1e-6);
  for (double depth = 1e-5; depth <= 1e12; depth *= 10.0) {
    const double d = profile.Evaluate(-depth);
    if (d != density) {
      throw Error(std::string("model simple needs a constant density in the half-space; ") + medium +
                  ".density varies there (" + std::to_string(density) + " at altitude -1e-06, " +
                  std::to_string(d) + " at altitude " + std::to_string(-depth) + ")");
    }
  }
  return density;
}

// Channels [first, first + 3) of a per-channel vector, repeating the last channel past the end.
shared::vec3 BatchOf(const std::vector<double>& values, std::size_t first) {
  shared::vec3 v;
  for (int i = 0; i < 3; ++i) v[i] = values[std::min(first + i, values.size() - 1)];
  return v;
}

void CheckDirection(const glm::dvec3& v, const char* what) {
  if (!std::isfinite(v.x) || !std::isfinite(v.y) || !std::isfinite(v.z) || glm::length(v) == 0.0) {
    throw Error(std::string(what) + " must be a finite, non-zero direction");
  }
}

}  // namespace

SimpleModel::SimpleModel(const AtmosphereParameters& parameters, const ModelOptions& options)
    : Model(parameters) {
  if (!options.empty()) {
    throw Error("unknown option '" + options.begin()->first +
                "' for model simple (it has no options; the common option is seed)");
  }
  Validate(parameters);
  if (parameters.geometry != Geometry::kHalfSpace) {
    throw Error("model simple needs the half-space geometry (preset simple); preset '" + parameters.name +
                "' is spherical: use model hillaire for it");
  }
  const std::pair<const Medium*, const char*> media[] = {{&parameters.rayleigh, "rayleigh"},
                                                         {&parameters.mie, "mie"},
                                                         {&parameters.ozone, "ozone"},
                                                         {&parameters.water_vapor, "water_vapor"}};
  for (std::size_t b = 0; b < ChannelBatchCount(parameters.channel_count()); ++b) {
    Batch batch;
    batch.extinction = shared::vec3(0.0);
    batch.sun = ToSharedParameters(parameters, b);
    for (const auto& [medium, key] : media) {
      if (!medium->present()) continue;
      if (medium->phase == PhaseFunction::kTabulated) {
        throw Error(std::string("model simple takes the analytic phase functions only; ") + key +
                    ".phase_function is \"tabulated\": use model hillaire or source4d for it");
      }
      const double density = ConstantDensityBelowPlane(medium->density, key);
      const shared::vec3 scattering = density * BatchOf(medium->scattering_per_m, 3 * b);
      batch.extinction += scattering + density * BatchOf(medium->absorption_per_m, 3 * b);
      if (scattering != shared::vec3(0.0)) {
        batch.media.push_back({scattering, ToSharedPhase(medium->phase), medium->phase_g});
      }
    }
    batches_.push_back(std::move(batch));
  }
}

// The per-view state: the observer p = (0, 0, altitude) and the sun s; queries evaluate the closed
// form of simple.glsl with u = z.
class SimpleSkyView final : public SkyView {
 public:
  SimpleSkyView(const SimpleModel& model, double altitude_m, const glm::dvec3& sun)
      : SkyView(altitude_m, sun, model.channel_count(), model.parameters().sun_angular_radius_rad),
        model_(model),
        observer_(0.0, 0.0, altitude_m) {}

  void Radiance(const glm::dvec3& view, std::span<double> out) const override {
    ScatterBatches(model_.batches().size(), out, [&](std::size_t b) {
      const SimpleModel::Batch& batch = model_.batches()[b];
      return shared::ComputeSimpleScatteredRadiance(kUp, observer_, view, sun_direction(), batch.extinction,
                                                    InScattering(batch, view));
    });
  }

  void Transmittance(const glm::dvec3& view, std::span<double> out) const override {
    ScatterBatches(model_.batches().size(), out, [&](std::size_t b) {
      const SimpleModel::Batch& batch = model_.batches()[b];
      return shared::GetSimpleViewTransmittance(kUp, observer_, view, batch.extinction);
    });
  }

  void SunDiscRadiance(const glm::dvec3& view, std::span<double> out) const override {
    ScatterBatches(model_.batches().size(), out, [&](std::size_t b) {
      const SimpleModel::Batch& batch = model_.batches()[b];
      return shared::GetSimpleSunDiscRadiance(kUp, observer_, view, sun_direction(), batch.extinction, batch.sun);
    });
  }

  void ScatteringAlongSegment(const glm::dvec3& view, double distance_m, std::span<double> radiance,
                              std::span<double> transmittance) const override {
    const auto& batches = model_.batches();
    for (std::size_t b = 0; b < batches.size(); ++b) {
      shared::vec3 t;
      const shared::vec3 l = shared::ComputeSimpleScatteringAlongSegment(
          kUp, observer_, view, sun_direction(), batches[b].extinction, InScattering(batches[b], view),
          std::max(distance_m, 0.0), t);
      for (std::size_t c = 0; c < 3 && 3 * b + c < radiance.size(); ++c) {
        radiance[3 * b + c] = l[static_cast<int>(c)];
        transmittance[3 * b + c] = t[static_cast<int>(c)];
      }
    }
  }

 private:
  // beta(nu): the in-scattering coefficient per unit solid angle of all media along `view`.
  shared::vec3 InScattering(const SimpleModel::Batch& batch, const glm::dvec3& view) const {
    const double nu = std::clamp(glm::dot(view, sun_direction()), -1.0, 1.0);
    shared::vec3 beta(0.0);
    for (const SimpleModel::ScatteringMedium& m : batch.media) {
      beta += shared::GetSimpleMediumScattering(m.scattering, m.phase, m.phase_g, nu);
    }
    return beta;
  }

  const SimpleModel& model_;
  shared::vec3 observer_;  // p: the altitude is the signed height above the boundary plane
};

std::unique_ptr<SkyView> SimpleModel::View(double altitude_m, const glm::dvec3& sun_direction) const {
  if (!std::isfinite(altitude_m)) {
    throw Error("altitude_m must be finite for model simple (got " + std::to_string(altitude_m) + ")");
  }
  CheckDirection(sun_direction, "the sun direction");
  return std::make_unique<SimpleSkyView>(*this, altitude_m, glm::normalize(sun_direction));
}

}  // namespace atmo
