// The presets of docs/design.md §3. Each value says where it comes from; coefficients are per metre
// (per the preset's own length unit for the half-space `simple`) at density 1.
#include <numbers>
#include <string>
#include <string_view>
#include <vector>

#include "atmo/error.h"
#include "printable.h"
#include "atmo/parameters.h"
#include "atmo/spectrum.h"
#include "atmo/standard_atmosphere.h"

namespace atmo {
namespace {

std::vector<double> PerChannel(double value, std::size_t channel_count) {
  return std::vector<double>(channel_count, value);
}

// Hillaire 2020 demo / Bruneton 2017, in metres.
AtmosphereParameters Earth() {
  AtmosphereParameters p;
  p.name = "earth";
  p.geometry = Geometry::kSpherical;
  p.ground_radius_m = 6360e3;
  p.top_radius_m = 6460e3;
  p.wavelengths_nm = {680.0, 550.0, 440.0};

  p.rayleigh.scattering_per_m = {5.802e-6, 13.558e-6, 33.100e-6};
  p.rayleigh.absorption_per_m = {0.0, 0.0, 0.0};
  p.rayleigh.density = DensityProfile::Exponential(8000.0);
  p.rayleigh.phase = PhaseFunction::kRayleigh;

  // Mie extinction 4.440e-6 /m of which 3.996e-6 /m scatters: absorption is the difference.
  p.mie.scattering_per_m = PerChannel(3.996e-6, 3);
  p.mie.absorption_per_m = PerChannel(0.444e-6, 3);
  p.mie.density = DensityProfile::Exponential(1200.0);
  p.mie.phase = PhaseFunction::kCornetteShanks;
  p.mie.phase_g = 0.8;

  // Ozone only absorbs; its density is a tent 0 at 10 km, 1 at 25 km, 0 at 40 km.
  p.ozone.scattering_per_m = {0.0, 0.0, 0.0};
  p.ozone.absorption_per_m = {0.650e-6, 1.881e-6, 0.085e-6};
  p.ozone.density = DensityProfile::Tent(10e3, 25e3, 40e3);
  p.ozone.phase = PhaseFunction::kIsotropic;

  p.ground_albedo = PerChannel(0.3, 3);
  p.sun_angular_radius_rad = 0.004675;
  p.solar_irradiance = PerChannel(1.0, 3);
  p.exposure = 10.0;
  p.observer_altitude_m = 0.0;
  return p;
}

// Seed 000 (Atmosphere Plus), in metres.
AtmosphereParameters AtmospherePlus() {
  AtmosphereParameters p;
  p.name = "atmosphere-plus";
  p.geometry = Geometry::kSpherical;
  p.ground_radius_m = 6371e3;
  p.top_radius_m = 6471e3;
  p.wavelengths_nm = {650.0, 510.0, 475.0};

  // The seed offers a "modified Rayleigh" phase; plain Rayleigh is the default here and
  // kModifiedRayleigh can be chosen by config.
  p.rayleigh.scattering_per_m = {6.55e-6, 1.73e-5, 2.30e-5};
  p.rayleigh.absorption_per_m = {0.0, 0.0, 0.0};
  p.rayleigh.density = DensityProfile::Exponential(8000.0);
  p.rayleigh.phase = PhaseFunction::kRayleigh;

  // Mie extinction = scattering / 0.9 (single-scattering albedo 0.9). The seed's g = -0.85 with
  // its "+2g cos" convention is g = +0.85 here (docs/design.md §2).
  constexpr double kMieScattering = 2e-6;
  constexpr double kMieExtinction = kMieScattering / 0.9;
  p.mie.scattering_per_m = PerChannel(kMieScattering, 3);
  p.mie.absorption_per_m = PerChannel(kMieExtinction - kMieScattering, 3);
  p.mie.density = DensityProfile::Exponential(1200.0);
  p.mie.phase = PhaseFunction::kCornetteShanks;
  p.mie.phase_g = 0.85;

  // No ozone: all coefficients zero, so the medium is absent.
  p.ozone.scattering_per_m = {0.0, 0.0, 0.0};
  p.ozone.absorption_per_m = {0.0, 0.0, 0.0};
  p.ozone.density = DensityProfile::Tent(10e3, 25e3, 40e3);
  p.ozone.phase = PhaseFunction::kIsotropic;

  p.ground_albedo = PerChannel(0.0, 3);
  p.sun_angular_radius_rad = 0.004675;
  p.solar_irradiance = {20.344770, 16.907042, 23.453083};  // the seed's sun intensity I_I
  p.exposure = 1.0;  // the seed tone-maps 1 - exp(-x) then gamma 2.2
  p.observer_altitude_m = 0.0;
  return p;
}

// Seed 002 (Simple Atmosphere): a homogeneous half-space, lengths in the seed's own unit. The seed
// names its channels only red, green, blue; we give them the wavelengths of `earth`.
AtmosphereParameters Simple() {
  AtmosphereParameters p;
  p.name = "simple";
  p.geometry = Geometry::kHalfSpace;
  p.ground_radius_m = 0.0;  // unused by the half-space
  p.top_radius_m = 0.0;     // unused by the half-space
  p.wavelengths_nm = {680.0, 550.0, 440.0};

  // The single medium; the seed's in-scattering has no phase function, i.e. isotropic.
  p.rayleigh.scattering_per_m = {0.1, 0.3, 0.7};
  p.rayleigh.absorption_per_m = {0.0, 0.0, 0.0};
  p.rayleigh.density = DensityProfile::Constant();
  p.rayleigh.phase = PhaseFunction::kIsotropic;

  for (Medium* absent : {&p.mie, &p.ozone}) {
    absent->scattering_per_m = {0.0, 0.0, 0.0};
    absent->absorption_per_m = {0.0, 0.0, 0.0};
    absent->density = DensityProfile::Constant();
    absent->phase = PhaseFunction::kIsotropic;
    absent->phase_g = 0.0;
  }

  p.ground_albedo = PerChannel(0.0, 3);
  p.sun_angular_radius_rad = 0.0045;
  p.solar_irradiance = PerChannel(1.0, 3);
  // The seed tone-maps 1 - exp(-L') with an unnormalised isotropic phase (1 instead of 1/(4 pi)):
  // exposure 4 pi applied to our radiance L = L' / (4 pi) gives the same image.
  p.exposure = 4.0 * std::numbers::pi;
  p.observer_altitude_m = -0.3;  // the seed's observer is 0.3 units inside the half-space
  return p;
}

}  // namespace

AtmosphereParameters Preset(std::string_view name) {
  if (name == "earth") return Earth();
  if (name == "earth-spectral") return EarthSpectral();
  if (name == "atmosphere-plus") return AtmospherePlus();
  if (name == "simple") return Simple();
  for (Climatology c : AllClimatologies()) {
    if (name == ToString(c)) return StandardSky(StandardSkySettings{.climatology = c});
  }
  std::string known;
  for (const std::string& preset : PresetNames()) {
    known += (known.empty() ? "" : ", ") + preset;
  }
  throw Error("unknown preset '" + Printable(name) + "' (known: " + known + ")");
}

std::vector<std::string> PresetNames() {
  std::vector<std::string> names = {"earth", "earth-spectral", "atmosphere-plus", "simple"};
  for (Climatology c : AllClimatologies()) names.emplace_back(ToString(c));
  return names;
}

}  // namespace atmo
