// Model `hillaire`: "A Scalable and Production Ready Sky and Atmosphere Rendering Technique"
// (Hillaire 2020), as in the seed "Sky Atmosphere in XEngine".
//
// Tables (sizes and sample counts are options, `--option key=value`):
//   transmittance_lut=256x64          transmittance to the top, Bruneton's (r, mu) mapping
//   transmittance_samples=40          trapezoidal intervals per texel
//   multiple_scattering_lut=32x32     Psi_ms(mu_s, r), isotropic orders >= 2
//   multiple_scattering_directions=64 directions over the sphere (even: a Fibonacci lattice on the
//                                     half sphere and its mirror image), or 2 = the seed's up/down
//                                     variant
//   multiple_scattering_samples=20    ray-march steps per direction
//   multiple_scattering_orders=4     orders >= 2 gathered one by one (each from the previous
//                                     order's table) before the 1/(1 - f_ms) series; 1 = Hillaire
//                                     2020's series alone
//   multiple_scattering_gather_directions  directions of the gathered orders 2.. (default: those of
//                                     multiple_scattering_directions; fewer: faster)
//   multiple_scattering_phase=isotropic  the phase of the first scattering in the table: isotropic
//                                     (Hillaire 2020) or media (Rayleigh and Mie's own)
//   multiple_scattering_ground=on     on: the ground also reflects orders >= 2 in the 1/(1 - f_ms)
//                                     series (shared::GetGroundTransfer; halves hillaire's blue
//                                     deficit against the reference); off: Hillaire 2020 as published
//   sky_view_lut=192x108              per observer and sun: 360 degrees of azimuth x latitude with
//                                     the horizon-following non-linear mapping
//   sky_view_samples=30               ray-march steps per sky-view texel
//   ray_march_samples=30              steps of the per-pixel ray march
//   sky_view=auto|off                 auto: use the sky-view table inside the atmosphere and ray
//                                     march per pixel above it; off: always ray march per pixel
//   ground_irradiance_lut=32          sky irradiance of the ground vs sun zenith cosine (images)
//   ground_irradiance_directions=64   hemisphere directions per texel
//   ground_irradiance_samples=16      ray-march steps per direction
// The sun disc (SunDiscRadiance) is the limb-darkened disc of shared/sun.glsl attenuated by the
// view transmittance, at full resolution; images integrate it over the pixels (cpu/sun_disc.h).
// For images the ground is a Lambertian surface lit by the attenuated sun and the sky; each view
// keeps a copy of its sky-view table with that light added below the horizon.
// Channels are computed three at a time: a preset with N channels keeps ceil(N/3) sets of tables.
#pragma once

#include <memory>
#include <vector>

#include "atmo/model.h"
#include "shared/shared.h"

namespace atmo {

struct HillaireSettings {
  glm::ivec2 transmittance_lut{256, 64};
  int transmittance_samples = 40;
  glm::ivec2 multiple_scattering_lut{32, 32};
  int multiple_scattering_directions = 64;
  int multiple_scattering_samples = 20;
  bool multiple_scattering_media_phase = false;
  bool multiple_scattering_ground = true;
  int multiple_scattering_orders = 4;
  int multiple_scattering_gather_directions = 64;  // FromOptions: multiple_scattering_directions unless given
  glm::ivec2 sky_view_lut{192, 108};
  int sky_view_samples = 30;
  int ray_march_samples = 30;
  bool use_sky_view_lut = true;
  int ground_irradiance_lut = 32;
  int ground_irradiance_directions = 64;
  int ground_irradiance_samples = 16;

  // Throws atmo::Error for an unknown key or a value out of range.
  static HillaireSettings FromOptions(const ModelOptions& options);
};

class HillaireModel final : public Model {
 public:
  HillaireModel(const AtmosphereParameters& parameters, const HillaireSettings& settings);

  std::string_view name() const override { return "hillaire"; }
  void Precompute() override;
  std::unique_ptr<SkyView> View(double altitude_m, const glm::dvec3& sun_direction) const override;

  // The tables of one batch of three channels.
  struct Batch {
    shared::AtmosphereParameters atmosphere;
    shared::Texture2D transmittance;
    shared::Texture2D multiple_scattering;
    shared::Texture2D ground_irradiance;  // width x 1
  };
  const std::vector<Batch>& batches() const { return batches_; }
  const HillaireSettings& settings() const { return settings_; }
  // Builds the sky-view table of one batch for an observer radius and sun zenith cosine.
  shared::Texture2D ComputeSkyViewLut(const Batch& batch, double r, double mu_s) const;
  // Adds the ground's reflected light to a sky-view table of the same observer and sun.
  void AddGroundView(const Batch& batch, double r, double mu_s, shared::Texture2D& table) const;

 private:
  void ComputeMultipleScatteringLut(Batch& batch) const;
  void ComputeGroundIrradianceLut(Batch& batch) const;

  HillaireSettings settings_;
  std::vector<Batch> batches_;
  friend class HillaireSkyView;
};

}  // namespace atmo
