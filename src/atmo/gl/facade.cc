// The public entry points of the GL backend (include/atmo/gl/hillaire_gl.h, elek_gl.h): model
// options by name, parsed as CreateModel parses them, on top of the backend's own classes.
#include <utility>

#include "gl/elek_gl.h"
#include "gl/hillaire_gl.h"

namespace atmo::gl {
namespace {

// CreateModel accepts "seed" for every model and the deterministic ones ignore it; so do these.
ModelOptions WithoutSeed(ModelOptions options) {
  options.erase("seed");
  return options;
}

}  // namespace

Image RenderHillaire(const Context& context, const AtmosphereParameters& parameters, const ModelOptions& options,
                     const RenderSettings& render, PassTimings* timings) {
  return RenderHillaireGl(context, parameters, HillaireSettings::FromOptions(WithoutSeed(options)), render, timings);
}

HillaireSampler::HillaireSampler(const Context& context, const AtmosphereParameters& parameters,
                                 const ModelOptions& options, PassTimings* timings)
    : sky_(std::make_unique<HillaireGl>(context, parameters, HillaireSettings::FromOptions(WithoutSeed(options)))) {
  sky_->Precompute(timings);
}

HillaireSampler::~HillaireSampler() = default;
HillaireSampler::HillaireSampler(HillaireSampler&&) noexcept = default;
HillaireSampler& HillaireSampler::operator=(HillaireSampler&&) noexcept = default;

std::size_t HillaireSampler::channel_count() const { return sky_->channel_count(); }

void HillaireSampler::SetView(double altitude_m, const glm::dvec3& sun_direction, PassTimings* timings) {
  sky_->SetView(altitude_m, sun_direction, /*ground=*/false, timings);
}

void HillaireSampler::Sample(std::span<const glm::dvec3> views, std::vector<double>& radiance,
                             std::vector<double>& transmittance, PassTimings* timings) {
  sky_->Sample(views, radiance, transmittance, timings);
}

std::unique_ptr<Model> CreateElekModel(const Context& context, const AtmosphereParameters& parameters,
                                       const ModelOptions& options, PassTimings* timings) {
  auto model = std::make_unique<ElekModel>(parameters, ElekSettings::FromOptions(WithoutSeed(options)));
  PrecomputeElekGl(context, *model, timings);
  return model;
}

Image RenderElek(const Context& context, const AtmosphereParameters& parameters, const ModelOptions& options,
                 const RenderSettings& render, PassTimings* timings) {
  return RenderElekGl(context, parameters, ElekSettings::FromOptions(WithoutSeed(options)), render, timings);
}

}  // namespace atmo::gl
