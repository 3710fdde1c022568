// Standard atmospheres: the air, ozone and water vapour of the US Standard Atmosphere 1976 and of
// the six AFGL 1986 climatologies, as profiles of pressure, temperature and number densities.
//
// To use it:
//   atmo::AtmosphereLevel l = atmo::UsStandardAtmosphere1976(11000.0);   // 22632 Pa, 216.65 K
//   auto levels = atmo::ClimatologyLevels(atmo::Climatology::kTropical);   // AFGL 1986, 0-120 km
//   double n = atmo::ClimatologyAt(atmo::Climatology::kTropical, 5000.0).air_per_m3;
//
// Sources (docs/validation.md): the US Standard Atmosphere 1976 (NOAA-S/T 76-1562) is computed
// from its defining equations below 86 km; the AFGL tables are Anderson et al. 1986,
// "AFGL Atmospheric Constituent Profiles (0-120 km)", AFGL-TR-86-0110, shipped in
// src/atmo/physics/data/afgl_profiles.h.
#pragma once

#include <string>
#include <string_view>
#include <vector>

#include "atmo/aerosol.h"
#include "atmo/parameters.h"

namespace atmo {

// One level of a standard atmosphere. Number densities are molecules per m^3.
struct AtmosphereLevel {
  double altitude_m = 0.0;  // geometric altitude above the ground
  double pressure_pa = 0.0;
  double temperature_k = 0.0;
  double air_per_m3 = 0.0;
  double ozone_per_m3 = 0.0;
  double water_per_m3 = 0.0;
};

// The US Standard Atmosphere 1976 at a geometric altitude in [0, 120 km]: below 86 km its seven
// layers of linear molecular-scale temperature in geopotential altitude, in hydrostatic
// equilibrium from 101325 Pa (the standard's eqs. 23, 33a and 33b); from 86 km its kinetic
// temperature (isothermal to 91 km, then the elliptical segment to 110 km and the linear one to
// 120 km), in hydrostatic equilibrium at the 86 km mean molar mass. Above 86 km the standard's
// diffusive separation is left out; it changes the density there by a few per cent, at under 1e-5
// of the ground's. Ozone and water vapour are those of the AFGL US standard table. Throws
// atmo::Error outside [0, 120 km].
AtmosphereLevel UsStandardAtmosphere1976(double altitude_m);

enum class Climatology {
  kUsStandard1976,      // computed from the standard's equations (UsStandardAtmosphere1976)
  kTropical,            // AFGL 1986, 15 N annual
  kMidlatitudeSummer,   // AFGL 1986, 45 N July
  kMidlatitudeWinter,   // AFGL 1986, 45 N January
  kSubarcticSummer,     // AFGL 1986, 60 N July
  kSubarcticWinter,     // AFGL 1986, 60 N January
};

// "us-standard", "tropical", "midlatitude-summer", "midlatitude-winter", "subarctic-summer",
// "subarctic-winter".
std::string_view ToString(Climatology climatology);
// Throws atmo::Error for an unknown name, listing the known ones.
Climatology ParseClimatology(std::string_view name);
std::vector<Climatology> AllClimatologies();

// The published levels of a climatology (AFGL 1986, 0-120 km; for kUsStandard1976 the AFGL US
// standard table's altitudes with the air computed by UsStandardAtmosphere1976).
std::vector<AtmosphereLevel> ClimatologyLevels(Climatology climatology);

// A climatology at any altitude in [0, 120 km]: pressure and number densities interpolated
// exponentially between levels (linearly where one is 0), temperature linearly.
AtmosphereLevel ClimatologyAt(Climatology climatology, double altitude_m);

// Column amounts from the ground to 120 km, molecules per m^2 (trapezoidal in log density between
// levels, i.e. exact for the exponential interpolation of ClimatologyAt).
struct Columns {
  double air_per_m2 = 0.0;
  double ozone_per_m2 = 0.0;
  double water_per_m2 = 0.0;
};
Columns ClimatologyColumns(Climatology climatology);

// A spectral sky on a standard atmosphere (the presets us-standard, tropical, ...): the air of the
// climatology with Rayleigh scattering from RayleighCrossSection, its ozone with OzoneCrossSection
// (233 K), both as tabulated profiles up to 100 km over a planet of the Earth's mean radius
// (6371 km), an OPAC aerosol, a grey Lambertian ground and the solar spectrum; with `gases`, the
// absorption of O2, O2-O2 and water vapour (include/atmo/gas_absorption.h), water vapour with the
// climatology's profile.
struct StandardSkySettings {
  Climatology climatology = Climatology::kUsStandard1976;
  bool gases = true;
  int wavelength_count = 15;
  AerosolSettings aerosol;        // continental-average at its typical tau_550 (0.13)
  double ground_albedo = 0.2;     // a typical land surface (grass, soil)
  double co2_ppm = 400.0;
};
AtmosphereParameters StandardSky(const StandardSkySettings& settings = {});

}  // namespace atmo
