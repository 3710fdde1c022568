#include "physics/shared_parameters.h"

#include <algorithm>
#include <array>
#include <cmath>
#include <numbers>

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

// The logarithm of a tabulated phase function's samples at an angle: linear in the angle between
// samples (the public table's interpolation, docs/parameters.md).
double SampledLogPhase(const std::vector<PhaseSample>& table, double angle_deg) {
  const auto upper = std::upper_bound(table.begin(), table.end(), angle_deg,
                                      [](double a, const PhaseSample& s) { return a < s.angle_deg; });
  if (upper == table.begin()) return std::log(table.front().value);
  if (upper == table.end()) return std::log(table.back().value);
  const PhaseSample& a = *(upper - 1);
  const PhaseSample& b = *upper;
  const double f = (angle_deg - a.angle_deg) / (b.angle_deg - a.angle_deg);
  return std::log(a.value) + f * (std::log(b.value) - std::log(a.value));
}

// Fills mie_phase_table of `a` for a tabulated Mie phase function: the samples' log phase at the
// shared knots (angle pi (i / (N - 1))^2), shifted so that the shared interpolant (linear in the
// knot coordinate) integrates to exactly 1 over the sphere. The integral: over each knot interval,
// exp(l(u)) times shared::GetPhaseTableSolidAnglePerKnot(u), by 16-point Gauss-Legendre in u (the
// integrand is smooth there), the whole within 1e-12.
void SetPhaseTable(const Medium& mie, shared::AtmosphereParameters& a) {
  constexpr int kN = shared::kPhaseTableSize;
  constexpr double kM = kN - 1;
  std::array<double, kN> logs{};
  a.mie_phase_peak_cap = 0.0;
  a.mie_phase_peak_mass = 0.0;
  if (mie.phase != PhaseFunction::kTabulated) {
    for (int i = 0; i < kN / 4; ++i) a.mie_phase_table[i] = shared::vec4(0.0);
    return;
  }
  for (int i = 0; i < kN; ++i) logs[i] = SampledLogPhase(mie.phase_table, 180.0 * (i / kM) * (i / kM));
  // 16-point Gauss-Legendre nodes and weights on [-1, 1] (the positive half).
  static constexpr double kX[8] = {0.0950125098376374, 0.2816035507792589, 0.4580167776572274, 0.6178762444026438,
                                   0.7554044083550030, 0.8656312023878318, 0.9445750230732326, 0.9894009349916499};
  static constexpr double kW[8] = {0.1894506104550685, 0.1826034150449236, 0.1691565193950025, 0.1495959888165767,
                                   0.1246289712555339, 0.0951585116824928, 0.0622535239386479, 0.0271524594117541};
  const double pi = std::numbers::pi;
  double integral = 0.0;
  for (int i = 0; i + 1 < kN; ++i) {
    for (int k = 0; k < 16; ++k) {
      const double x = (k < 8 ? -kX[7 - k] : kX[k - 8]);
      const double w = (k < 8 ? kW[7 - k] : kW[k - 8]);
      const double t = 0.5 * (x + 1.0);  // in [0, 1]
      integral += 0.5 * w * std::exp(logs[i] + t * (logs[i + 1] - logs[i])) *
                  shared::GetPhaseTableSolidAnglePerKnot(i + t);
    }
  }
  const double shift = std::log(integral);
  for (int i = 0; i < kN; ++i) a.mie_phase_table[i / 4][i % 4] = logs[i] - shift;
  // The forward peak for source4d's gathering: the excess over the value at kPhasePeakAngle inside
  // it, by the midpoint rule on 2000 steps of the angle (the interpolant is smooth there).
  a.mie_phase_peak_cap = shared::GetMiePhase(a, std::cos(shared::kPhasePeakAngle));
  double mass = 0.0;
  constexpr int kSteps = 2000;
  for (int k = 0; k < kSteps; ++k) {
    const double theta = shared::kPhasePeakAngle * (k + 0.5) / kSteps;
    mass += std::max(shared::GetMiePhase(a, std::cos(theta)) - a.mie_phase_peak_cap, 0.0) * 2.0 * pi *
            std::sin(theta) * (shared::kPhasePeakAngle / kSteps);
  }
  a.mie_phase_peak_mass = mass;
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
    case PhaseFunction::kTabulated: return shared::kPhaseTabulated;
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
  SetPhaseTable(p.mie, a);
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
