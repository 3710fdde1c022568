// Spectra: the published tables atmo ships (CIE 1931 observer, the solar spectrum at the top of
// the atmosphere, ozone cross-sections), Rayleigh scattering from first principles, and spectral
// atmospheres built from them.
//
// To use it:
//   double e = atmo::SolarSpectralIrradiance(550.0);          // W m^-2 nm^-1 at 1 au
//   atmo::AtmosphereParameters p = atmo::EarthSpectral();      // preset earth-spectral
//   atmo::AtmosphereParameters q = atmo::MakeSpectral(atmo::Preset("earth"), 16);  // any preset
//
// Wavelengths are in nanometres. Every spectral quantity is defined on [360, 830] nm (the range of
// the CIE 1931 tables) and is 0 (colour-matching functions) or held at its end value (the others)
// outside it. Sources and units are in src/atmo/physics/data/spectral_tables.h and docs/spectral.md.
#pragma once

#include <span>
#include <vector>

#include <glm/glm.hpp>

#include "atmo/parameters.h"

namespace atmo {

inline constexpr double kSpectrumMinNm = 360.0;
inline constexpr double kSpectrumMaxNm = 830.0;
// Luminous efficacy of radiation at 555 nm, lm/W: luminance = 683 * integral of y-bar L d(lambda).
inline constexpr double kMaxLuminousEfficacy = 683.0;

// Luminous efficacy of scotopic (rod) vision at its 507 nm peak, lm/W: 683 / V'(555 nm) = 683 / 0.402.
inline constexpr double kMaxScotopicEfficacy = 1700.0;

// The CIE 1951 scotopic luminous efficiency V'(lambda) at `wavelength_nm`, linear between the 5 nm
// entries of src/atmo/physics/data/scotopic_table.h, 0 outside 380..780 nm.
double ScotopicEfficiency(double wavelength_nm);

// CIE 1931 2-degree colour-matching functions (x-bar, y-bar, z-bar) at `wavelength_nm`, linear
// between the 5 nm entries, 0 outside [360, 830] nm.
glm::dvec3 CieColourMatching(double wavelength_nm);

// Solar spectral irradiance at the top of the atmosphere, at 1 au, in W m^-2 nm^-1 (ASTM G-173
// extraterrestrial spectrum in 10 nm bins, linear between bin centres).
double SolarSpectralIrradiance(double wavelength_nm);

// Ozone absorption cross-section in m^2 per molecule (Serdyuchenko et al. 2014, 233 K, 10 nm
// bins, linear between bin centres).
double OzoneCrossSection(double wavelength_nm);

// Rayleigh scattering cross-section of dry air in m^2 per molecule, from first principles after
// Bodhaine et al. 1999: the refractive index of Peck & Reeder 1972 corrected to `co2_ppm` of CO2,
// and the King factor of Bates 1984 for N2, O2, Ar and CO2.
double RayleighCrossSection(double wavelength_nm, double co2_ppm = 360.0);
// Molecules per m^3 of air at 288.15 K and 1013.25 hPa (Bodhaine et al. 1999, after the ideal gas
// law): the density of the Rayleigh profile at altitude 0.
inline constexpr double kAirNumberDensityAtSeaLevel = 2.546899e25;
// Molecules per m^2 in one Dobson unit (a 10 um layer of ozone at 273.15 K and 1013.25 hPa).
inline constexpr double kDobsonUnitPerM2 = 2.6867e20;

// The wavelengths of an N-channel spectral atmosphere: N points spaced evenly over [360, 830] nm,
// the ends included (N >= 2), so that the piecewise-linear spectrum they define covers the range.
std::vector<double> SpectralWavelengths(int count);

// The knobs of the physically built Earth atmosphere (preset earth-spectral).
struct SpectralEarthSettings {
  int wavelength_count = 15;  // measured: docs/spectral.md
  double co2_ppm = 360.0;
  double ozone_column_du = 300.0;  // total ozone, Dobson units (300 DU: a mid-latitude average)
  // Aerosols: extinction optical depth at 550 nm (the turbidity knob) and Angstrom exponent alpha:
  // tau(lambda) = tau_550 (lambda / 550 nm)^-alpha; the profile is exponential with the earth
  // preset's 1.2 km scale height, so extinction at the ground = tau / 1200 m. The default 0.05 is a
  // clean continental day (Koschmieder visibility about 70 km at 550 nm); the earth preset's Mie
  // (4.44e-6 m^-1) is tau = 0.00533 with alpha = 0.
  double aerosol_optical_depth_550 = 0.05;
  double angstrom_exponent = 1.3;
  double aerosol_single_scattering_albedo = 0.9;
  double ground_albedo = 0.3;
};

// The Earth of preset `earth` (geometry, profiles, phase functions, sun) with every coefficient
// computed per wavelength from physics: Rayleigh from RayleighCrossSection, ozone from
// OzoneCrossSection and the column, aerosols from the Angstrom law. solar_irradiance holds the
// solar spectrum at each wavelength (W m^-2 nm^-1). Throws atmo::Error for invalid settings.
AtmosphereParameters EarthSpectral(const SpectralEarthSettings& settings = {});

// Any atmosphere resampled to `count` wavelengths over [360, 830] nm (SpectralWavelengths), each
// coefficient continued by the physics of its medium, fitted to the values it has:
//   rayleigh: k * RayleighCrossSection(lambda), k the least-squares fit in log space;
//   ozone:    k * OzoneCrossSection(lambda), likewise;
//   mie:      an Angstrom law a * lambda^-alpha fitted to extinction, the single-scattering albedo
//             interpolated linearly in wavelength;
//   ground albedo: linear in wavelength between the given channels, held beyond them;
//   solar_irradiance: SolarSpectralIrradiance.
// A half-space atmosphere (preset simple) has no physical medium: its coefficients follow the
// Angstrom fit for every medium. Throws atmo::Error for count outside [3, 256].
AtmosphereParameters MakeSpectral(const AtmosphereParameters& parameters, int count);
// The same at the given wavelengths: 1 to 256, increasing, within [360, 830] nm (throws
// atmo::Error naming the first that is not). Each channel stands for the band halfway to its
// neighbours (ChannelBands, include/atmo/gas_absorption.h), which the gases' absorption averages.
AtmosphereParameters MakeSpectral(const AtmosphereParameters& parameters, std::span<const double> wavelengths_nm);

}  // namespace atmo
