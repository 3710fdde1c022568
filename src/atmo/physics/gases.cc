#include "physics/gases.h"

#include <algorithm>
#include <cmath>

#include "atmo/error.h"
#include "atmo/gas_absorption.h"
#include "atmo/spectrum.h"

namespace atmo {
namespace {

// The integrals of a profile's density and squared density from the ground to `top_m` (metres),
// by Simpson's rule on 20 m steps (profiles change over kilometres; tables are exponential
// between knots).
struct ProfileIntegrals {
  double density_m = 0.0;
  double squared_m = 0.0;
};

ProfileIntegrals Integrate(const DensityProfile& profile, double top_m) {
  const int steps = std::max(2, 2 * static_cast<int>(std::ceil(top_m / 40.0)));
  const double h = top_m / steps;
  ProfileIntegrals sum;
  for (int i = 0; i <= steps; ++i) {
    const double w = (i == 0 || i == steps) ? 1.0 : (i % 2 == 1 ? 4.0 : 2.0);
    const double d = profile.Evaluate(i * h);
    sum.density_m += w * d;
    sum.squared_m += w * d * d;
  }
  sum.density_m *= h / 3.0;
  sum.squared_m *= h / 3.0;
  return sum;
}

double Thickness(const AtmosphereParameters& p) { return p.top_radius_m - p.ground_radius_m; }

}  // namespace

void SetGasAbsorption(AtmosphereParameters& p, double ground_air_per_m3, double water_peak_per_m3) {
  if (p.geometry != Geometry::kSpherical) throw Error("gas absorption needs a spherical atmosphere");
  const std::vector<WavelengthBand> bands = ChannelBands(p.wavelengths_nm);
  const std::size_t n = p.channel_count();
  const ProfileIntegrals air = Integrate(p.rayleigh.density, Thickness(p));
  const double o2_per_m3 = kOxygenMixingRatio * ground_air_per_m3;
  const double o2_column = o2_per_m3 * air.density_m;
  const double pair_column = o2_per_m3 * o2_per_m3 * air.squared_m;
  p.rayleigh.absorption_per_m.assign(n, 0.0);
  for (std::size_t c = 0; c < n; ++c) {
    const double o2 = GasEffectiveCrossSection(Gas::kOxygen, bands[c], o2_column) * o2_per_m3;
    const double pairs_tau = GasEffectiveCrossSection(Gas::kOxygenCollisions, bands[c], pair_column) * pair_column;
    p.rayleigh.absorption_per_m[c] = o2 + (air.density_m > 0.0 ? pairs_tau / air.density_m : 0.0);
  }
  // Without water vapour, a medium that was never given stays so (empty vectors).
  if (!(water_peak_per_m3 > 0.0) && p.water_vapor.absorption_per_m.empty()) return;
  p.water_vapor.scattering_per_m.assign(n, 0.0);
  p.water_vapor.absorption_per_m.assign(n, 0.0);
  if (!(water_peak_per_m3 > 0.0)) return;
  const double water_column = water_peak_per_m3 * Integrate(p.water_vapor.density, Thickness(p)).density_m;
  for (std::size_t c = 0; c < n; ++c) {
    p.water_vapor.absorption_per_m[c] =
        GasEffectiveCrossSection(Gas::kWaterVapor, bands[c], water_column) * water_peak_per_m3;
  }
}

GasAmounts InferGasAmounts(const AtmosphereParameters& p) {
  GasAmounts amounts;
  // The air: the least-squares scale of the Rayleigh cross-section to the scattering.
  double num = 0.0, den = 0.0;
  for (std::size_t c = 0; c < p.channel_count(); ++c) {
    const double sigma = RayleighCrossSection(p.wavelengths_nm[c], 400.0);
    num += sigma * p.rayleigh.scattering_per_m[c];
    den += sigma * sigma;
  }
  amounts.ground_air_per_m3 = den > 0.0 ? num / den : 0.0;
  if (!p.water_vapor.present()) return amounts;
  // Water vapour: the number density whose Beer-equivalent absorption gives the strongest
  // channel's coefficient (monotone in the amount: bisection on its logarithm).
  const std::vector<double>& a = p.water_vapor.absorption_per_m;
  const std::size_t c = static_cast<std::size_t>(std::max_element(a.begin(), a.end()) - a.begin());
  const WavelengthBand band = ChannelBands(p.wavelengths_nm)[c];
  const double profile_m = Integrate(p.water_vapor.density, Thickness(p)).density_m;
  const auto coefficient = [&](double peak) {
    return GasEffectiveCrossSection(Gas::kWaterVapor, band, peak * profile_m) * peak;
  };
  double lo = 1e10, hi = 1e30;  // molecules per m^3 (the real peak is ~1e23)
  if (!(coefficient(hi) > a[c]) || !(coefficient(lo) < a[c])) {
    throw Error("water_vapor's absorption is outside what water vapour can give at " +
                std::to_string(p.wavelengths_nm[c]) + " nm: it cannot be put on new wavelengths");
  }
  for (int i = 0; i < 100; ++i) {
    const double mid = std::sqrt(lo * hi);
    (coefficient(mid) < a[c] ? lo : hi) = mid;
  }
  amounts.water_peak_per_m3 = std::sqrt(lo * hi);
  return amounts;
}

}  // namespace atmo
