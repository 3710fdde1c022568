// Standard atmospheres (include/atmo/standard_atmosphere.h): the US Standard Atmosphere 1976 from
// its defining equations, and the AFGL 1986 climatologies from their published tables.
#include "atmo/standard_atmosphere.h"

#include <algorithm>
#include <array>
#include <cmath>
#include <span>
#include <string>

#include "atmo/error.h"
#include "atmo/spectrum.h"
#include "physics/gases.h"
#include "physics/density_interpolation.h"
#include "physics/data/afgl_profiles.h"
#include "printable.h"

namespace atmo {
namespace {

// The constants of the US Standard Atmosphere 1976 (NOAA-S/T 76-1562, table 2 and section 1.2).
constexpr double kEarthRadius_m = 6356766.0;      // r0, for geopotential altitude
constexpr double kG0 = 9.80665;                   // m s^-2 (and m^2 s^-2 per geopotential metre)
constexpr double kMolarMassAir = 28.9644;         // M0, kg / kmol
constexpr double kGasConstant = 8.31432e3;        // R*, J / (kmol K)
constexpr double kAvogadro = 6.022169e26;         // N_A, per kmol
constexpr double kSeaLevelPressure_pa = 101325.0;
constexpr double kMaxAltitude_m = 120e3;

// The seven layers below 86 km: base geopotential altitude (km') and lapse rate of the
// molecular-scale temperature (K per km'). The base temperatures follow from 288.15 K.
struct Layer {
  double base_km;
  double lapse_k_per_km;
};
constexpr std::array<Layer, 7> kLayers = {{{0.0, -6.5},
                                           {11.0, 0.0},
                                           {20.0, 1.0},
                                           {32.0, 2.8},
                                           {47.0, 0.0},
                                           {51.0, -2.8},
                                           {71.0, -2.0}}};
constexpr double kTopGeopotential_km = 84.8520;  // 86 km geometric
constexpr double kZ86_m = 86e3;
// M / M0 at 86 km (the standard's table 8); from 80 km it falls smoothly from 1, here linearly.
constexpr double kMolarMassRatio86 = 0.999579;

double GeopotentialKm(double altitude_m) { return kEarthRadius_m * altitude_m / (kEarthRadius_m + altitude_m) * 1e-3; }

// Pressure and molecular-scale temperature below 86 km (eqs. 33a and 33b).
void LowerAtmosphere(double h_km, double& pressure_pa, double& molecular_temperature_k) {
  double base_t = 288.15;
  double base_p = kSeaLevelPressure_pa;
  const double beta = kG0 * kMolarMassAir / kGasConstant;  // K per m'
  for (std::size_t i = 0; i < kLayers.size(); ++i) {
    const double top_km = i + 1 < kLayers.size() ? kLayers[i + 1].base_km : kTopGeopotential_km;
    const double lapse = kLayers[i].lapse_k_per_km * 1e-3;  // K per m'
    const double dh = (std::min(h_km, top_km) - kLayers[i].base_km) * 1e3;
    const double t = base_t + lapse * dh;
    const double p = lapse == 0.0 ? base_p * std::exp(-beta * dh / base_t) : base_p * std::pow(base_t / t, beta / lapse);
    if (h_km <= top_km || i + 1 == kLayers.size()) {
      pressure_pa = p;
      molecular_temperature_k = t;
      return;
    }
    base_t = t;
    base_p = p;
  }
}

// The kinetic temperature above 86 km (the standard's eqs. 25-29), geometric altitude in km.
double UpperTemperature(double z_km) {
  if (z_km <= 91.0) return 186.8673;
  if (z_km <= 110.0) {
    const double x = (z_km - 91.0) / -19.9429;
    return 263.1905 - 76.3232 * std::sqrt(std::max(1.0 - x * x, 0.0));
  }
  return 240.0 + 12.0 * (z_km - 110.0);
}

double Gravity(double altitude_m) {
  const double ratio = kEarthRadius_m / (kEarthRadius_m + altitude_m);
  return kG0 * ratio * ratio;
}

// Pressure above 86 km: hydrostatic at the 86 km molar mass, by Simpson's rule on d(ln p)/dz.
double UpperPressure(double altitude_m, double pressure_86_pa) {
  const double molar_mass = kMolarMassAir * kMolarMassRatio86;
  const auto rate = [&](double z) {
    return -Gravity(z) * molar_mass / (kGasConstant * UpperTemperature(z * 1e-3));
  };
  const int steps = std::max(2, 2 * static_cast<int>(std::ceil((altitude_m - kZ86_m) / 200.0)));
  const double dz = (altitude_m - kZ86_m) / steps;
  double sum = rate(kZ86_m) + rate(altitude_m);
  for (int i = 1; i < steps; ++i) sum += (i % 2 ? 4.0 : 2.0) * rate(kZ86_m + i * dz);
  return pressure_86_pa * std::exp(sum * dz / 3.0);
}

double NumberDensity(double pressure_pa, double temperature_k) {
  return kAvogadro * pressure_pa / (kGasConstant * temperature_k);
}

std::span<const data::AfglLevel> AfglTable(Climatology climatology) {
  switch (climatology) {
    case Climatology::kUsStandard1976: return data::kAfglUsStandard;
    case Climatology::kTropical: return data::kAfglTropical;
    case Climatology::kMidlatitudeSummer: return data::kAfglMidlatitudeSummer;
    case Climatology::kMidlatitudeWinter: return data::kAfglMidlatitudeWinter;
    case Climatology::kSubarcticSummer: return data::kAfglSubarcticSummer;
    case Climatology::kSubarcticWinter: return data::kAfglSubarcticWinter;
  }
  return data::kAfglUsStandard;
}

// A table's level at any altitude (held at the end levels outside it).
AtmosphereLevel InterpolateAfgl(std::span<const data::AfglLevel> table, double altitude_m) {
  const double z_km = altitude_m * 1e-3;
  auto upper = std::upper_bound(table.begin(), table.end(), z_km,
                                [](double z, const data::AfglLevel& l) { return z < l.altitude_km; });
  if (upper == table.end()) --upper;
  if (upper == table.begin()) ++upper;
  const data::AfglLevel& b = *upper;
  const data::AfglLevel& a = *(upper - 1);
  const double f = std::clamp((z_km - a.altitude_km) / (b.altitude_km - a.altitude_km), 0.0, 1.0);
  AtmosphereLevel level;
  level.altitude_m = altitude_m;
  level.pressure_pa = InterpolateDensity(a.pressure_hpa, b.pressure_hpa, f) * 100.0;
  level.temperature_k = a.temperature_k + (b.temperature_k - a.temperature_k) * f;
  level.air_per_m3 = InterpolateDensity(a.air_per_cm3, b.air_per_cm3, f) * 1e6;
  level.ozone_per_m3 = InterpolateDensity(a.ozone_per_cm3, b.ozone_per_cm3, f) * 1e6;
  level.water_per_m3 = InterpolateDensity(a.water_per_cm3, b.water_per_cm3, f) * 1e6;
  return level;
}

void CheckAltitude(double altitude_m) {
  if (!(altitude_m >= 0.0 && altitude_m <= kMaxAltitude_m)) {
    throw Error("standard atmosphere altitude " + std::to_string(altitude_m) + " m is outside [0, 120000] m");
  }
}

}  // namespace

AtmosphereLevel UsStandardAtmosphere1976(double altitude_m) {
  CheckAltitude(altitude_m);
  AtmosphereLevel level;
  level.altitude_m = altitude_m;
  if (altitude_m <= kZ86_m) {
    double molecular_temperature_k = 0.0;
    LowerAtmosphere(GeopotentialKm(altitude_m), level.pressure_pa, molecular_temperature_k);
    const double ratio = altitude_m <= 80e3 ? 1.0 : 1.0 + (kMolarMassRatio86 - 1.0) * (altitude_m - 80e3) / 6e3;
    level.temperature_k = molecular_temperature_k * ratio;
  } else {
    double p86 = 0.0, t86 = 0.0;
    LowerAtmosphere(kTopGeopotential_km, p86, t86);
    level.pressure_pa = UpperPressure(altitude_m, p86);
    level.temperature_k = UpperTemperature(altitude_m * 1e-3);
  }
  level.air_per_m3 = NumberDensity(level.pressure_pa, level.temperature_k);
  // Ozone and water vapour: the AFGL US standard table.
  const AtmosphereLevel afgl = InterpolateAfgl(data::kAfglUsStandard, altitude_m);
  level.ozone_per_m3 = afgl.ozone_per_m3;
  level.water_per_m3 = afgl.water_per_m3;
  return level;
}

std::string_view ToString(Climatology climatology) {
  switch (climatology) {
    case Climatology::kUsStandard1976: return "us-standard";
    case Climatology::kTropical: return "tropical";
    case Climatology::kMidlatitudeSummer: return "midlatitude-summer";
    case Climatology::kMidlatitudeWinter: return "midlatitude-winter";
    case Climatology::kSubarcticSummer: return "subarctic-summer";
    case Climatology::kSubarcticWinter: return "subarctic-winter";
  }
  return "unknown";
}

std::vector<Climatology> AllClimatologies() {
  return {Climatology::kUsStandard1976,    Climatology::kTropical,        Climatology::kMidlatitudeSummer,
          Climatology::kMidlatitudeWinter, Climatology::kSubarcticSummer, Climatology::kSubarcticWinter};
}

Climatology ParseClimatology(std::string_view name) {
  std::string known;
  for (Climatology c : AllClimatologies()) {
    if (name == ToString(c)) return c;
    known += (known.empty() ? "" : ", ") + std::string(ToString(c));
  }
  throw Error("unknown atmosphere '" + Printable(name) + "' (known: " + known + ")");
}

std::vector<AtmosphereLevel> ClimatologyLevels(Climatology climatology) {
  std::vector<AtmosphereLevel> levels;
  for (const data::AfglLevel& l : AfglTable(climatology)) {
    AtmosphereLevel level;
    level.altitude_m = l.altitude_km * 1e3;
    if (climatology == Climatology::kUsStandard1976) {
      const AtmosphereLevel computed = UsStandardAtmosphere1976(level.altitude_m);
      level.pressure_pa = computed.pressure_pa;
      level.temperature_k = computed.temperature_k;
      level.air_per_m3 = computed.air_per_m3;
    } else {
      level.pressure_pa = l.pressure_hpa * 100.0;
      level.temperature_k = l.temperature_k;
      level.air_per_m3 = l.air_per_cm3 * 1e6;
    }
    level.ozone_per_m3 = l.ozone_per_cm3 * 1e6;
    level.water_per_m3 = l.water_per_cm3 * 1e6;
    levels.push_back(level);
  }
  return levels;
}

AtmosphereLevel ClimatologyAt(Climatology climatology, double altitude_m) {
  CheckAltitude(altitude_m);
  if (climatology == Climatology::kUsStandard1976) return UsStandardAtmosphere1976(altitude_m);
  return InterpolateAfgl(AfglTable(climatology), altitude_m);
}

Columns ClimatologyColumns(Climatology climatology) {
  const std::vector<AtmosphereLevel> levels = ClimatologyLevels(climatology);
  Columns columns;
  for (std::size_t i = 0; i + 1 < levels.size(); ++i) {
    const double dz = levels[i + 1].altitude_m - levels[i].altitude_m;
    columns.air_per_m2 += IntegrateDensity(levels[i].air_per_m3, levels[i + 1].air_per_m3, dz);
    columns.ozone_per_m2 += IntegrateDensity(levels[i].ozone_per_m3, levels[i + 1].ozone_per_m3, dz);
    columns.water_per_m2 += IntegrateDensity(levels[i].water_per_m3, levels[i + 1].water_per_m3, dz);
  }
  return columns;
}

AtmosphereParameters StandardSky(const StandardSkySettings& s) {
  if (!(s.ground_albedo >= 0.0 && s.ground_albedo <= 1.0)) {
    throw Error("ground albedo " + std::to_string(s.ground_albedo) + " is outside [0, 1]");
  }
  SpectralEarthSettings spectral;
  spectral.wavelength_count = s.wavelength_count;
  spectral.co2_ppm = s.co2_ppm;
  spectral.ground_albedo = s.ground_albedo;
  AtmosphereParameters p = EarthSpectral(spectral);  // wavelengths, sun, display defaults
  p.name = std::string(ToString(s.climatology));
  p.ground_radius_m = 6371e3;
  p.top_radius_m = p.ground_radius_m + 100e3;
  p.sun_angular_radius_rad = 0.0046524;  // 959.63 arcsec at 1 au

  // The air: every 500 m, exponential between knots (the density of an isothermal layer).
  const double top_m = p.top_radius_m - p.ground_radius_m;
  const double ground_air = ClimatologyAt(s.climatology, 0.0).air_per_m3;
  std::vector<DensityKnot> air;
  for (int i = 0; i <= 200; ++i) {
    const double h = top_m * i / 200.0;
    air.push_back({h, ClimatologyAt(s.climatology, h).air_per_m3 / ground_air});
  }
  // Ozone at the climatology's own levels, normalised to its peak.
  const std::vector<AtmosphereLevel> levels = ClimatologyLevels(s.climatology);
  double ozone_peak = 0.0;
  for (const AtmosphereLevel& l : levels) ozone_peak = std::max(ozone_peak, l.ozone_per_m3);
  std::vector<DensityKnot> ozone;
  for (const AtmosphereLevel& l : levels) ozone.push_back({l.altitude_m, l.ozone_per_m3 / ozone_peak});

  p.rayleigh.density = DensityProfile::Tabulated(std::move(air));
  p.ozone.density = DensityProfile::Tabulated(std::move(ozone));
  for (std::size_t c = 0; c < p.channel_count(); ++c) {
    const double lambda = p.wavelengths_nm[c];
    p.rayleigh.scattering_per_m[c] = RayleighCrossSection(lambda, s.co2_ppm) * ground_air;
    p.rayleigh.absorption_per_m[c] = 0.0;
    p.ozone.scattering_per_m[c] = 0.0;
    p.ozone.absorption_per_m[c] = OzoneCrossSection(lambda) * ozone_peak;
  }
  if (s.gases) {
    // Water vapour at the climatology's levels, normalised to its peak (at the ground).
    double water_peak = 0.0;
    for (const AtmosphereLevel& l : levels) water_peak = std::max(water_peak, l.water_per_m3);
    std::vector<DensityKnot> water;
    for (const AtmosphereLevel& l : levels) {
      if (l.altitude_m <= top_m) water.push_back({l.altitude_m, l.water_per_m3 / water_peak});
    }
    p.water_vapor.density = DensityProfile::Tabulated(std::move(water));
    SetGasAbsorption(p, ground_air, water_peak);
  }
  ApplyAerosol(p, s.aerosol);
  Validate(p);
  return p;
}

}  // namespace atmo
