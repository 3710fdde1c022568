// The gases of include/atmo/gas_absorption.h put into an atmosphere's media (internal): O2 and
// O2-O2 into the air's absorption, water vapour into its own medium (docs/parameters.md, "Gases").
#pragma once

#include "atmo/parameters.h"

namespace atmo {

// Sets p.rayleigh.absorption_per_m to O2's and O2-O2's Beer-equivalent absorption per channel for
// air of number density ground_air_per_m3 at density 1 along p.rayleigh.density, and, when
// water_peak_per_m3 > 0, p.water_vapor's absorption for that number density at density 1 along
// p.water_vapor.density (which the caller sets). O2-O2 absorbs in proportion to the square of the
// air's density but is given the air's profile with the same vertical optical depth (the medium has
// one profile); its vertical optical depth is at most 0.01 in 360-830 nm.
void SetGasAbsorption(AtmosphereParameters& p, double ground_air_per_m3, double water_peak_per_m3);

// The inverse for a spherical atmosphere whose gases SetGasAbsorption set: the air's number density
// at density 1 from the Rayleigh scattering (RayleighCrossSection at 400 ppm CO2) and the water
// vapour's from its strongest channel. MakeSpectral uses them to put the gases on new channels.
struct GasAmounts {
  double ground_air_per_m3 = 0.0;
  double water_peak_per_m3 = 0.0;
};
GasAmounts InferGasAmounts(const AtmosphereParameters& p);

}  // namespace atmo
