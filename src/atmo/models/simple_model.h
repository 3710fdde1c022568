// Model `simple`: the seed "Simple Atmosphere" (Gijs Bellaard), single scattering in a homogeneous
// half-space, in closed form (src/atmo/shared/simple.glsl; docs/models/simple.md).
//
// It needs parameters with geometry half_space (preset `simple`). The media are summed per
// channel: extinction sigma_t = sum of (scattering + absorption) in every transmittance, and the
// in-scattering coefficient sum of scattering x phase function (each medium's own phase function
// at nu, constant along a ray). Each medium must have a constant density below the boundary plane
// (its density there scales its coefficients). `altitude_m` of View() is the observer's signed
// height above the boundary plane in the parameters' length unit (negative: inside the medium);
// the up vector of the closed form is the local frame's z axis.
//
// Options: none besides the common "seed", which it ignores (deterministic).
// No precomputation: every query evaluates the closed form. Any number of channels; they are
// evaluated three at a time.
#pragma once

#include <memory>
#include <vector>

#include "atmo/model.h"
#include "shared/shared.h"

namespace atmo {

class SimpleModel final : public Model {
 public:
  // Throws atmo::Error for an option (it has none), invalid parameters, a spherical geometry, or
  // a medium whose density varies below the boundary plane.
  SimpleModel(const AtmosphereParameters& parameters, const ModelOptions& options);

  std::string_view name() const override { return "simple"; }
  void Precompute() override {}
  std::unique_ptr<SkyView> View(double altitude_m, const glm::dvec3& sun_direction) const override;

  // One medium's coefficients for a batch of three channels, density included.
  struct ScatteringMedium {
    shared::vec3 scattering;  // per length unit
    int phase;                // shared::kPhase*
    double phase_g;
  };
  // The media of channels [3 b, 3 b + 3); a batch with fewer channels repeats its last one.
  struct Batch {
    shared::vec3 extinction;     // sigma_t: sum over media of scattering + absorption
    std::vector<ScatteringMedium> media;  // the scattering media (absent ones left out)
    shared::AtmosphereParameters sun;     // the sun disc's members (wavelengths, centre radiance)
  };
  const std::vector<Batch>& batches() const { return batches_; }

 private:
  std::vector<Batch> batches_;
};

}  // namespace atmo
