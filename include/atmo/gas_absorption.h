// Absorption by the gases of the clear sky between 360 and 830 nm besides ozone: molecular oxygen
// (its A band at 760 nm, B band at 687 nm and gamma band at 628 nm), water vapour (its bands from
// 590 nm on, strongest at 720 and 820 nm) and the collision pairs O2-O2 (O4: 360, 380, 477, 577 and
// 630 nm). The data are computed line by line from published line and collision-induced absorption
// lists (src/atmo/physics/data/gas_absorption.h, docs/data/gas_absorption/) and kept as
// k-distributions per 1 nm: a band's mean transmittance is exact for any absorber amount, which
// matters because the lines saturate (the mean transmittance of a band is not exp(-mean optical
// depth)).
//
// To use it:
//   auto bands = atmo::ChannelBands(parameters.wavelengths_nm);
//   double t = atmo::GasBandTransmittance(atmo::Gas::kOxygen, bands[c], o2_column_per_m2, air_mass);
//   double sigma = atmo::GasEffectiveCrossSection(atmo::Gas::kWaterVapor, bands[c], h2o_column_per_m2);
//
// A renderer's channel carries one extinction coefficient, so atmo's media hold the Beer-equivalent
// cross-section of each channel's band at a reference air mass (docs/parameters.md, "Gases"): the
// band transmittance is then exact at that air mass and within a few per cent elsewhere
// (tests/gas_absorption_test.cc measures how far).
#pragma once

#include <span>
#include <vector>

namespace atmo {

enum class Gas {
  kOxygen,            // O2; amounts in molecules per m^2
  kWaterVapor,        // H2O; molecules per m^2
  kOxygenCollisions,  // O2-O2 collision-induced absorption; amounts in molecules^2 per m^5
};

// A wavelength interval in nm (vacuum), lower < upper.
struct WavelengthBand {
  double lower_nm = 0.0;
  double upper_nm = 0.0;
};

// The band each channel stands for: from halfway to the previous channel to halfway to the next;
// the first and last channels' bands are symmetric about them, and a single channel's is 10 nm
// wide. Wavelengths must be strictly increasing (throws atmo::Error otherwise).
std::vector<WavelengthBand> ChannelBands(std::span<const double> wavelengths_nm);

// The air mass at which GasEffectiveCrossSection is exact by default: 1.5, the reference air mass
// of ASTM G-173 and IEC 60904-3 (the sun 48.2 degrees from the zenith).
inline constexpr double kGasReferenceAirMass = 1.5;

// The mean transmittance over the band (uniform in wavelength) of a vertical column `amount` seen
// along `air_mass` (the slant amount is amount * air_mass). Outside 360-830 nm the gases do not
// absorb here (1). Throws atmo::Error for a negative or non-finite amount or air mass, or an
// empty band.
double GasBandTransmittance(Gas gas, WavelengthBand band, double amount, double air_mass);

// The Beer-equivalent cross-section of the band (m^2 per molecule; m^5 per molecule^2 for O4):
// -ln(GasBandTransmittance(amount * air_mass)) / (amount * air_mass), which tends to the band-mean
// cross-section as the amount tends to 0.
double GasEffectiveCrossSection(Gas gas, WavelengthBand band, double amount,
                                double air_mass = kGasReferenceAirMass);

// O2's share of the molecules of dry air (volume mixing ratio, US Standard Atmosphere 1976).
inline constexpr double kOxygenMixingRatio = 0.209476;

}  // namespace atmo
