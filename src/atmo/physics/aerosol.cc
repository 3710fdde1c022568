// Aerosol types and their knobs (include/atmo/aerosol.h, docs/aerosols.md).
#include "atmo/aerosol.h"

#include <algorithm>
#include <cmath>
#include <span>
#include <string>

#include "atmo/error.h"
#include "atmo/standard_atmosphere.h"
#include "physics/density_interpolation.h"
#include "physics/data/aerosol_phase.h"
#include "physics/data/aerosol_types.h"
#include "printable.h"

namespace atmo {
namespace {

constexpr double kKoschmiederConstant = 3.912;  // -ln(0.02): the 2 % contrast threshold
// Half-widths of the ramps that replace OPAC's steps at the layer boundaries.
constexpr double kMixingLayerRamp_m = 250.0;
constexpr double kBackgroundRamp_m = 500.0;

const data::AerosolType& FindType(std::string_view name) {
  for (const data::AerosolType& type : data::kAerosolTypes) {
    if (name == type.name) return type;
  }
  std::string known;
  for (const data::AerosolType& type : data::kAerosolTypes) known += (known.empty() ? "" : ", ") + std::string(type.name);
  throw Error("unknown aerosol type '" + Printable(name) + "' (known: " + known + ")");
}

// A spectral table's values at a wavelength: linear between its points, held outside them.
data::AerosolSpectralPoint AtWavelength(std::span<const data::AerosolSpectralPoint> table, double wavelength_nm) {
  if (!(wavelength_nm > table.front().wavelength_nm)) return table.front();
  if (wavelength_nm >= table.back().wavelength_nm) return table.back();
  std::size_t k = 1;
  while (table[k].wavelength_nm < wavelength_nm) ++k;
  const data::AerosolSpectralPoint& a = table[k - 1];
  const data::AerosolSpectralPoint& b = table[k];
  const double f = (wavelength_nm - a.wavelength_nm) / (b.wavelength_nm - a.wavelength_nm);
  const auto lerp = [f](double x, double y) { return x + (y - x) * f; };
  return {wavelength_nm, lerp(a.extinction_relative_550, b.extinction_relative_550),
          lerp(a.single_scattering_albedo, b.single_scattering_albedo), lerp(a.asymmetry_g, b.asymmetry_g)};
}

// The layers of a type's column at 550 nm, scaled to an optical depth.
struct Layer {
  std::span<const data::AerosolSpectralPoint> spectrum;
  double bottom_m;
  double top_m;
  double scale_height_m;  // 0: constant
  double extinction_550_per_m;  // at altitude 0 for an exponential layer (OPAC's reference)
  double Extinction(double altitude_m) const {
    if (altitude_m < bottom_m || altitude_m >= top_m) return 0.0;  // [bottom, top)
    return scale_height_m > 0.0 ? extinction_550_per_m * std::exp(-altitude_m / scale_height_m) : extinction_550_per_m;
  }
  double OpticalDepth() const {
    if (!(top_m > bottom_m)) return 0.0;
    if (scale_height_m <= 0.0) return extinction_550_per_m * (top_m - bottom_m);
    return extinction_550_per_m * scale_height_m *
           (std::exp(-bottom_m / scale_height_m) - std::exp(-top_m / scale_height_m));
  }
};

const data::AerosolPhaseTable& PhaseTable(std::string_view name) {
  for (const data::AerosolPhaseTable& table : data::kAerosolPhaseTables) {
    if (name == table.name) return table;
  }
  throw Error("no phase function for aerosol '" + std::string(name) + "'");  // a data error, not the user's
}

// OPAC's column for a type (opac.cfg): the mixing layer from the ground to the type's top, the
// free troposphere from there to 12 km, the stratospheric background from 12 to 35 km.
std::vector<Layer> DefaultLayers(const data::AerosolType& type) {
  const data::AerosolBackgroundLayer& ft = data::kFreeTroposphere;
  const data::AerosolBackgroundLayer& st = data::kStratosphere;
  return {
      {{type.spectrum, static_cast<std::size_t>(type.spectrum_count)}, 0.0, type.layer_top_m, type.scale_height_m,
       type.extinction_550_per_m},
      {{ft.spectrum, static_cast<std::size_t>(ft.spectrum_count)}, type.layer_top_m, ft.top_m, ft.scale_height_m,
       ft.extinction_550_per_m},
      {{st.spectrum, static_cast<std::size_t>(st.spectrum_count)}, st.bottom_m, st.top_m, st.scale_height_m,
       st.extinction_550_per_m},
  };
}

// The layers scaled to a column optical depth: the mixing layer carries what exceeds the
// background; below the background every layer scales.
std::vector<Layer> ScaledLayers(const data::AerosolType& type, double aod_550) {
  std::vector<Layer> layers = DefaultLayers(type);
  const double background = layers[1].OpticalDepth() + layers[2].OpticalDepth();
  const double mixing = layers[0].OpticalDepth();
  if (aod_550 >= background) {
    layers[0].extinction_550_per_m *= mixing > 0.0 ? (aod_550 - background) / mixing : 0.0;
  } else {
    const double s = background > 0.0 ? aod_550 / background : 0.0;
    layers[0].extinction_550_per_m = 0.0;
    layers[1].extinction_550_per_m *= s;
    layers[2].extinction_550_per_m *= s;
  }
  return layers;
}

double TotalExtinction(const std::vector<Layer>& layers, double altitude_m) {
  double sum = 0.0;
  for (const Layer& l : layers) sum += l.Extinction(altitude_m);
  return sum;
}

// The normalised profile of a column's 550 nm extinction as tabulated knots: OPAC's layers end to
// end (exponential between knots, so exact inside a layer), with a ramp across each boundary
// instead of OPAC's step (a mixing layer's top is an entrainment zone a few hundred metres thick;
// a step would need every solver's quadrature to place a node on it). column_m is the profile's
// integral (m): the ramps move a little extinction across each boundary, so coefficients are
// scaled by it to keep the optical depth asked for. No knots for an empty column.
struct AerosolProfile {
  std::vector<DensityKnot> knots;
  double column_m = 0.0;
};

AerosolProfile BuildProfile(const std::vector<Layer>& layers, double top_m) {
  std::vector<double> altitudes = {0.0};
  for (const Layer& l : layers) {
    if (!(l.top_m > l.bottom_m)) continue;
    const double ramp = l.top_m <= 4000.0 ? kMixingLayerRamp_m : kBackgroundRamp_m;
    for (double h : {l.bottom_m - ramp, l.bottom_m + ramp, l.top_m - ramp, l.top_m + ramp}) {
      if (h > 0.0) altitudes.push_back(h);
    }
  }
  std::sort(altitudes.begin(), altitudes.end());
  altitudes.erase(std::unique(altitudes.begin(), altitudes.end()), altitudes.end());
  double peak = 0.0;
  for (double h : altitudes) peak = std::max(peak, TotalExtinction(layers, h));
  AerosolProfile profile;
  if (!(peak > 0.0)) return profile;
  for (double h : altitudes) profile.knots.push_back({h, std::min(TotalExtinction(layers, h) / peak, 1.0)});
  // The integral of DensityProfile::Evaluate's interpolation, knot to knot, and held to the top.
  for (std::size_t i = 0; i + 1 < profile.knots.size(); ++i) {
    const DensityKnot& a = profile.knots[i];
    const DensityKnot& b = profile.knots[i + 1];
    const double dz = std::min(b.altitude_m, top_m) - a.altitude_m;
    if (!(dz > 0.0)) break;
    const double f = dz / (b.altitude_m - a.altitude_m);  // the part below the top
    profile.column_m += IntegrateDensity(a.density, InterpolateDensity(a.density, b.density, f), dz);
  }
  if (profile.knots.back().altitude_m < top_m) {
    profile.column_m += profile.knots.back().density * (top_m - profile.knots.back().altitude_m);
  }
  return profile;
}

// The aerosol's 550 nm extinction at the ground for a column optical depth.
double GroundExtinction(const data::AerosolType& type, double aod, double top_m) {
  const AerosolProfile profile = BuildProfile(ScaledLayers(type, aod), top_m);
  return profile.knots.empty() ? 0.0 : aod * profile.knots.front().density / profile.column_m;
}

// The 550 nm Rayleigh extinction of an atmosphere at its ground, from the channel nearest 550 nm
// by the lambda^-4 law.
double RayleighExtinction550AtGround(const AtmosphereParameters& p) {
  std::size_t nearest = 0;
  for (std::size_t c = 1; c < p.channel_count(); ++c) {
    if (std::abs(p.wavelengths_nm[c] - 550.0) < std::abs(p.wavelengths_nm[nearest] - 550.0)) nearest = c;
  }
  const double ratio = p.wavelengths_nm[nearest] / 550.0;
  // Scattering only: it follows lambda^-4; the air's gas absorption (O2, O2-O2) is band-shaped and
  // negligible at 550 nm, but a channel's band may hold the 577 nm O2-O2 band.
  return p.rayleigh.scattering_per_m[nearest] * ratio * ratio * ratio * ratio * p.rayleigh.density.Evaluate(0.0);
}

std::string Format(double value) {
  char buffer[32];
  std::snprintf(buffer, sizeof buffer, "%g", value);
  return buffer;
}

}  // namespace

std::vector<std::string> AerosolTypeNames() {
  std::vector<std::string> names;
  for (const data::AerosolType& type : data::kAerosolTypes) names.emplace_back(type.name);
  return names;
}

std::vector<std::string> AerosolPhaseNames() { return {"henyey-greenstein", "opac"}; }

std::string AerosolTypeDescription(std::string_view type) { return FindType(type).description; }

double AerosolTypicalOpticalDepth(std::string_view type) {
  double sum = 0.0;
  for (const Layer& l : DefaultLayers(FindType(type))) sum += l.OpticalDepth();
  return sum;
}

void ValidateAerosol(const AerosolSettings& s) {
  FindType(s.type);
  const std::vector<std::string> phases = AerosolPhaseNames();
  if (std::find(phases.begin(), phases.end(), s.phase) == phases.end()) {
    throw Error("unknown aerosol phase '" + Printable(s.phase) + "' (known: henyey-greenstein, opac)");
  }
  if (!std::isnan(s.aod_550) && !(s.aod_550 >= 0.0 && s.aod_550 <= kMaxAerosolOpticalDepth)) {
    throw Error("aerosol optical depth " + Format(s.aod_550) + " at 550 nm is outside [0, 10]");
  }
  if (!std::isnan(s.angstrom_exponent) &&
      !(s.angstrom_exponent >= kMinAngstromExponent && s.angstrom_exponent <= kMaxAngstromExponent)) {
    throw Error("Angstrom exponent " + Format(s.angstrom_exponent) + " is outside [-1, 4]");
  }
}

void ApplyAerosol(AtmosphereParameters& p, const AerosolSettings& s) {
  ValidateAerosol(s);
  if (p.geometry != Geometry::kSpherical) throw Error("aerosols need a spherical atmosphere (not a half-space)");
  const data::AerosolType& type = FindType(s.type);
  const double aod = std::isnan(s.aod_550) ? AerosolTypicalOpticalDepth(s.type) : s.aod_550;
  const std::vector<Layer> layers = ScaledLayers(type, aod);
  const std::size_t n = p.channel_count();
  p.mie.scattering_per_m.assign(n, 0.0);
  p.mie.absorption_per_m.assign(n, 0.0);
  p.mie.phase = PhaseFunction::kHenyeyGreenstein;
  p.mie.phase_table.clear();

  const AerosolProfile profile = BuildProfile(layers, p.top_radius_m - p.ground_radius_m);
  if (profile.knots.empty()) {
    p.mie.density = DensityProfile::Exponential(1200.0);  // an absent medium; any profile
    p.mie.phase_g = 0.0;
    return;
  }
  p.mie.density = DensityProfile::Tabulated(profile.knots);
  const double profile_column_m = profile.column_m;

  // Column-weighted optical properties: every wavelength's column optical depth is exact.
  double scattering_550 = 0.0, scattering_g_550 = 0.0;
  std::vector<double> tau(layers.size());
  for (std::size_t l = 0; l < layers.size(); ++l) {
    tau[l] = layers[l].OpticalDepth();
    const data::AerosolSpectralPoint at = AtWavelength(layers[l].spectrum, 550.0);
    scattering_550 += tau[l] * at.single_scattering_albedo;
    scattering_g_550 += tau[l] * at.single_scattering_albedo * at.asymmetry_g;
  }
  const double total = tau[0] + tau[1] + tau[2];
  p.mie.phase_g = scattering_550 > 0.0 ? scattering_g_550 / scattering_550 : 0.0;
  if (scattering_550 > 0.0 && s.phase == "opac") {
    // The column's phase function at 550 nm: each layer's OPAC phase function (aerosol_phase.h)
    // weighted by its scattering optical depth; phase_g above is its asymmetry.
    const char* names[] = {type.name, data::kFreeTroposphere.name, data::kStratosphere.name};
    p.mie.phase = PhaseFunction::kTabulated;
    p.mie.phase_table.assign(data::kAerosolPhaseAngleCount, PhaseSample{});
    for (int k = 0; k < data::kAerosolPhaseAngleCount; ++k) p.mie.phase_table[k].angle_deg = data::kAerosolPhaseAnglesDeg[k];
    for (std::size_t l = 0; l < layers.size(); ++l) {
      const double weight = tau[l] * AtWavelength(layers[l].spectrum, 550.0).single_scattering_albedo / scattering_550;
      const data::AerosolPhaseTable& table = PhaseTable(names[l]);
      for (int k = 0; k < data::kAerosolPhaseAngleCount; ++k) p.mie.phase_table[k].value += weight * table.values[k];
    }
  }
  for (std::size_t c = 0; c < n; ++c) {
    const double lambda = p.wavelengths_nm[c];
    double extinction = 0.0, scattering = 0.0;  // column optical depths at lambda
    for (std::size_t l = 0; l < layers.size(); ++l) {
      const data::AerosolSpectralPoint at = AtWavelength(layers[l].spectrum, lambda);
      extinction += tau[l] * at.extinction_relative_550;
      scattering += tau[l] * at.extinction_relative_550 * at.single_scattering_albedo;
    }
    const double albedo = extinction > 0.0 ? scattering / extinction : 0.0;
    const double relative =
        std::isnan(s.angstrom_exponent) ? extinction / total : std::pow(lambda / 550.0, -s.angstrom_exponent);
    const double coefficient = aod * relative / profile_column_m;  // per m at density 1
    p.mie.scattering_per_m[c] = coefficient * albedo;
    p.mie.absorption_per_m[c] = coefficient - coefficient * albedo;
  }
}

double AerosolOpticalDepthFromVisibility(const AtmosphereParameters& p, std::string_view type_name,
                                         double visibility_km) {
  if (!(std::isfinite(visibility_km) && visibility_km > 0.0)) {
    throw Error("visibility " + Format(visibility_km) + " km must be positive and finite");
  }
  const data::AerosolType& type = FindType(type_name);
  const double air = RayleighExtinction550AtGround(p);
  const double limit_km = kKoschmiederConstant / air * 1e-3;
  const double aerosol = kKoschmiederConstant / (visibility_km * 1e3) - air;
  if (!(aerosol >= 0.0)) {
    throw Error("visibility " + Format(visibility_km) + " km is beyond the " + Format(std::round(limit_km)) +
                " km that the air alone allows");
  }
  // The ground extinction grows with the optical depth: bisection on [0, 10].
  const double top_m = p.top_radius_m - p.ground_radius_m;
  if (GroundExtinction(type, kMaxAerosolOpticalDepth, top_m) < aerosol) {
    throw Error("visibility " + Format(visibility_km) + " km gives an aerosol optical depth above the 10 allowed");
  }
  double lo = 0.0, hi = kMaxAerosolOpticalDepth;
  for (int i = 0; i < 60; ++i) {
    const double mid = 0.5 * (lo + hi);
    (GroundExtinction(type, mid, top_m) < aerosol ? lo : hi) = mid;
  }
  const double aod = 0.5 * (lo + hi);
  if (aod > kMaxAerosolOpticalDepth) {
    throw Error("visibility " + Format(visibility_km) + " km gives an aerosol optical depth of " + Format(aod) +
                ", above the 10 allowed");
  }
  return aod;
}

double AerosolOpticalDepthFromLinkeTurbidity(double linke_turbidity, double precipitable_water_cm) {
  if (!(std::isfinite(linke_turbidity) && linke_turbidity > 0.0 && linke_turbidity <= 20.0)) {
    throw Error("Linke turbidity " + Format(linke_turbidity) + " is outside (0, 20]");
  }
  if (!(std::isfinite(precipitable_water_cm) && precipitable_water_cm > 0.0)) {
    throw Error("precipitable water " + Format(precipitable_water_cm) + " cm must be positive");
  }
  const double pc = 1.0;  // p0 / p at sea level
  const double clean = 0.376 * std::log(precipitable_water_cm) + 2.0 + 0.54 * pc - 0.5 * pc * pc + 0.16 * pc * pc * pc;
  const double aod = (linke_turbidity - clean) / (3.91 * std::exp(0.689 * pc));
  if (aod < 0.0) {
    throw Error("Linke turbidity " + Format(linke_turbidity) + " is below the " + Format(clean) +
                " of an aerosol-free sky with " + Format(precipitable_water_cm) + " cm of water vapour");
  }
  if (aod > kMaxAerosolOpticalDepth) {
    throw Error("Linke turbidity " + Format(linke_turbidity) + " gives an aerosol optical depth above 10");
  }
  return aod;
}

void ApplyAerosolRequest(AtmosphereParameters& p, const AerosolRequest& r) {
  if (r.empty()) return;
  const int amounts = (r.aod_550 ? 1 : 0) + (r.visibility_km ? 1 : 0) + (r.linke_turbidity ? 1 : 0);
  if (amounts > 1) throw Error("give at most one of --aod, --visibility and --turbidity");
  AerosolSettings settings;
  if (r.type) settings.type = *r.type;
  FindType(settings.type);
  if (r.phase) settings.phase = *r.phase;
  if (r.angstrom_exponent) {
    if (std::isnan(*r.angstrom_exponent)) throw Error("Angstrom exponent nan is outside [-1, 4]");
    settings.angstrom_exponent = *r.angstrom_exponent;
  }
  if (r.aod_550) {
    if (std::isnan(*r.aod_550)) throw Error("aerosol optical depth nan at 550 nm is outside [0, 10]");
    settings.aod_550 = *r.aod_550;
  }
  if (r.visibility_km) settings.aod_550 = AerosolOpticalDepthFromVisibility(p, settings.type, *r.visibility_km);
  if (r.linke_turbidity) {
    Climatology climatology = Climatology::kUsStandard1976;
    for (Climatology c : AllClimatologies()) {
      if (p.name == ToString(c)) climatology = c;
    }
    // Water vapour column: molecules per m^2 to cm of liquid (18.015 g/mol, 1 g/cm^3).
    const double water_cm = ClimatologyColumns(climatology).water_per_m2 * 1e-4 * 18.015 / 6.02214076e23;
    settings.aod_550 = AerosolOpticalDepthFromLinkeTurbidity(*r.linke_turbidity, water_cm);
  }
  ApplyAerosol(p, settings);
}

}  // namespace atmo
