// Aerosols as users know them: the OPAC aerosol types (Hess, Koepke and Schult 1998) with their
// spectral extinction, single-scattering albedo, asymmetry and vertical profile, and the knobs that
// set their amount: the optical depth at 550 nm, an Angstrom exponent, the Koschmieder visibility
// and the Linke turbidity.
//
// To use it:
//   atmo::AtmosphereParameters p = atmo::Preset("us-standard");
//   atmo::AerosolSettings haze;
//   haze.type = "continental-polluted";
//   haze.aod_550 = 0.4;
//   atmo::ApplyAerosol(p, haze);   // replaces p.mie
//
// The data (src/atmo/physics/data/aerosol_types.h) and how a type becomes atmo's one Mie medium
// are in docs/aerosols.md.
#pragma once

#include <limits>
#include <optional>
#include <string>
#include <string_view>
#include <vector>

#include "atmo/parameters.h"

namespace atmo {

// The names of the aerosol types, for --aerosol ("continental-clean", "continental-average", ...).
std::vector<std::string> AerosolTypeNames();
// One line describing a type; throws atmo::Error for an unknown name, listing the known ones.
std::string AerosolTypeDescription(std::string_view type);
// The type's optical depth at 550 nm with OPAC's default profile (mixing layer, free troposphere
// and stratospheric background): its "typical" amount.
double AerosolTypicalOpticalDepth(std::string_view type);

inline constexpr double kMaxAerosolOpticalDepth = 10.0;
inline constexpr double kMinAngstromExponent = -1.0;
inline constexpr double kMaxAngstromExponent = 4.0;

struct AerosolSettings {
  std::string type = "continental-average";
  // Extinction optical depth of the whole column at 550 nm, in [0, 10]; NaN: the type's typical
  // one. The amount changes the mixing layer, whose share OPAC varies; the free-tropospheric and
  // stratospheric background (tau 0.018) stays unless the total is smaller than it, when all
  // layers scale together.
  double aod_550 = std::numeric_limits<double>::quiet_NaN();
  // NaN: the type's own spectral extinction; else tau(lambda) = aod_550 (lambda / 550 nm)^-alpha
  // with alpha in [-1, 4] (the type's albedo and asymmetry stay).
  double angstrom_exponent = std::numeric_limits<double>::quiet_NaN();
  // The Mie medium's phase function: "opac", OPAC's own phase functions at 550 nm as a table, or
  // "henyey-greenstein" with the column's asymmetry at 550 nm (docs/aerosols.md, "Phase").
  std::string phase = "opac";
};

// The names of `AerosolSettings::phase` ("henyey-greenstein", "opac").
std::vector<std::string> AerosolPhaseNames();

// Throws atmo::Error with a one-line message for an unknown type or phase, an optical depth outside
// [0, 10] (or not finite), an Angstrom exponent outside [-1, 4].
void ValidateAerosol(const AerosolSettings& settings);

// Replaces the Mie medium of a spherical atmosphere by the aerosol: a tabulated profile (the
// type's layers, normalised to 1 at their densest) and, per channel, the column-weighted
// extinction and albedo of the layers at the channel's wavelength; a Henyey-Greenstein phase
// function with the column's scattering-weighted asymmetry at 550 nm. Throws atmo::Error for
// invalid settings or a half-space atmosphere.
void ApplyAerosol(AtmosphereParameters& parameters, const AerosolSettings& settings);

// The optical depth at 550 nm of the column whose extinction at the ground gives the
// meteorological visibility `visibility_km` by Koschmieder's law, V = 3.912 / beta_550, with
// beta the extinction of the aerosol and of the air (Rayleigh at the ground of `parameters`).
// Throws atmo::Error for V <= 0 or not finite, and for a V beyond the clean air's own limit.
double AerosolOpticalDepthFromVisibility(const AtmosphereParameters& parameters, std::string_view type,
                                         double visibility_km);

// The optical depth at 550 nm for a Linke turbidity factor T_L (air mass 2) by Ineichen 2008,
// "Conversion function between the Linke turbidity and the atmospheric water vapor and aerosol
// content" (Solar Energy 82): T_L = 3.91 e^{0.689 p0/p} tau_550 + 0.376 ln w + 2 + 0.54 p0/p -
// 0.5 (p0/p)^2 + 0.16 (p0/p)^3, with w the precipitable water in cm and p0/p = 1 at sea level.
// Throws atmo::Error when T_L is below that of an aerosol-free sky with this water.
double AerosolOpticalDepthFromLinkeTurbidity(double linke_turbidity, double precipitable_water_cm);

// What a user asks for (the CLI's --aerosol, --aod, --angstrom, --visibility and --turbidity, a
// config's "aerosol" object, Python's keywords): a type (default continental-average) and at most
// one amount (default the type's typical optical depth).
struct AerosolRequest {
  std::optional<std::string> type;
  std::optional<double> aod_550;
  std::optional<double> angstrom_exponent;
  std::optional<double> visibility_km;
  std::optional<double> linke_turbidity;
  std::optional<std::string> phase;
  bool empty() const {
    return !type && !aod_550 && !angstrom_exponent && !visibility_km && !linke_turbidity && !phase;
  }
};

// Resolves the request's amount and applies it (ApplyAerosol); nothing for an empty request. The
// Linke turbidity takes the precipitable water of the atmosphere's climatology when its name is
// one (atmo presets), else the US standard's 1.42 cm. Throws atmo::Error, naming the flags, for two
// amounts at once and for every invalid value.
void ApplyAerosolRequest(AtmosphereParameters& parameters, const AerosolRequest& request);

}  // namespace atmo
