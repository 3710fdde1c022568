#include "physics/shared_parameters.h"

#include <algorithm>
#include <cmath>

#include "atmo/error.h"

namespace atmo {
namespace {

shared::DensityProfileLayer ToSharedLayer(const DensityLayer& layer, double unit) {
  // Altitudes scale with the unit; exp_scale and linear_term are per length.
  return shared::DensityProfileLayer{layer.width_m / unit, layer.exp_term, layer.exp_scale_per_m * unit,
                                     layer.linear_term_per_m * unit, layer.constant_term};
}

shared::DensityProfile ToSharedProfile(const DensityProfile& profile, double unit) {
  shared::DensityProfile result;
  result.layers[0] = ToSharedLayer(profile.lower, unit);
  result.layers[1] = ToSharedLayer(profile.upper, unit);
  return result;
}

// Per-length coefficients of channels [first, first + 3), in the target unit.
glm::dvec3 Batch(const std::vector<double>& values, std::size_t first, double scale) {
  glm::dvec3 v;
  for (int i = 0; i < 3; ++i) {
    const std::size_t c = std::min(first + i, values.size() - 1);
    v[i] = values[c] * scale;
  }
  return v;
}

// The log density of the shared table, floored at kDensityTableLogZero.
double TableLogDensity(double density) {
  return density > 0.0 ? std::max(std::log(density), shared::kDensityTableLogZero) : shared::kDensityTableLogZero;
}

// Fills the density table of `a` (density_table_enabled, _top, density_table) from the profiles
// of `p`: enabled when at least one medium is tabulated, every medium then sampled at the table's
// knots; `unit` as for ToSharedParameters.
void SetDensityTable(const AtmosphereParameters& p, double unit, shared::AtmosphereParameters& a) {
  // Water vapour's density lives only in the table (w).
  a.density_table_enabled = p.rayleigh.density.tabulated() || p.mie.density.tabulated() ||
                                    p.ozone.density.tabulated() || p.water_vapor.present()
                                ? 1
                                : 0;
  // A half-space has no thickness; its table (a constant profile, if any) is then read at 0 only.
  const double thickness_m = p.top_radius_m > p.ground_radius_m ? p.top_radius_m - p.ground_radius_m : unit;
  a.density_table_top = thickness_m / unit;
  for (int i = 0; i < shared::kDensityTableSize; ++i) {
    if (!a.density_table_enabled) {
      a.density_table[i] = shared::vec4(0.0);
      continue;
    }
    // Every medium through the table (a layer profile too), so that one lookup serves all four.
    const double x = static_cast<double>(i) / (shared::kDensityTableSize - 1);
    const double altitude_m = thickness_m * x * x;
    a.density_table[i] = shared::vec4(TableLogDensity(p.rayleigh.density.Evaluate(altitude_m)),
                                      TableLogDensity(p.mie.density.Evaluate(altitude_m)),
                                      TableLogDensity(p.ozone.density.Evaluate(altitude_m)),
                                      p.water_vapor.present() ? TableLogDensity(p.water_vapor.density.Evaluate(altitude_m))
                                                              : shared::kDensityTableLogZero);
  }
}

}  // namespace

shared::vec3 BatchValues(std::span<const double> values, std::size_t batch) {
  if (values.empty()) throw Error("BatchValues needs at least one channel");
  return Batch(std::vector<double>(values.begin(), values.end()), 3 * batch, 1.0);
}

int ToSharedPhase(PhaseFunction phase) {
  switch (phase) {
    case PhaseFunction::kIsotropic: return shared::kPhaseIsotropic;
    case PhaseFunction::kRayleigh: return shared::kPhaseRayleigh;
    case PhaseFunction::kModifiedRayleigh: return shared::kPhaseModifiedRayleigh;
    case PhaseFunction::kCornetteShanks: return shared::kPhaseCornetteShanks;
    case PhaseFunction::kHenyeyGreenstein: return shared::kPhaseHenyeyGreenstein;
  }
  return shared::kPhaseIsotropic;
}

shared::AtmosphereParameters ToSharedParameters(const AtmosphereParameters& p, std::size_t batch,
                                                double unit) {
  for (double s : p.ozone.scattering_per_m) {
    if (s != 0.0) throw Error("ozone.scattering_per_m must be 0: the ozone layer only absorbs in this model");
  }
  const std::size_t first = 3 * batch;
  shared::AtmosphereParameters a;
  a.bottom_radius = p.ground_radius_m / unit;
  a.top_radius = p.top_radius_m / unit;
  a.rayleigh_density = ToSharedProfile(p.rayleigh.density, unit);
  a.rayleigh_scattering = Batch(p.rayleigh.scattering_per_m, first, unit);
  a.rayleigh_extinction = a.rayleigh_scattering + Batch(p.rayleigh.absorption_per_m, first, unit);
  a.rayleigh_phase = ToSharedPhase(p.rayleigh.phase);
  a.mie_density = ToSharedProfile(p.mie.density, unit);
  a.mie_scattering = Batch(p.mie.scattering_per_m, first, unit);
  a.mie_extinction = a.mie_scattering + Batch(p.mie.absorption_per_m, first, unit);
  a.mie_phase = ToSharedPhase(p.mie.phase);
  a.mie_g = p.mie.phase_g;
  a.absorption_density = ToSharedProfile(p.ozone.density, unit);
  a.absorption_extinction = Batch(p.ozone.absorption_per_m, first, unit);
  a.water_vapor_extinction =
      p.water_vapor.present() ? Batch(p.water_vapor.absorption_per_m, first, unit) : shared::vec3(0.0);
  a.ground_albedo = Batch(p.ground_albedo, first, 1.0);
  a.sun_angular_radius = p.sun_angular_radius_rad;
  // The sun's limb darkening is evaluated from each channel's wavelength (sun.glsl), and its
  // centre radiance, an integral over the disc, once here.
  a.wavelength = Batch(p.wavelengths_nm, first, 1.0);
  a.sun_limb_darkening = p.sun_limb_darkening ? 1 : 0;
  for (int i = 0; i < 3; ++i) {
    a.sun_centre_radiance[i] =
        shared::GetSunDiscCentreRadiance(a.wavelength[i], a.sun_angular_radius, p.sun_limb_darkening);
  }
  SetDensityTable(p, unit, a);
  return a;
}

}  // namespace atmo
