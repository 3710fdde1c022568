// Atmosphere parameters: the physical description of a sky, its presets, validation and JSON.
//
// To use it:
//   atmo::AtmosphereParameters p = atmo::Preset("earth");   // or LoadParametersFile("my.json")
//   p.ground_albedo = {0.1, 0.1, 0.1};
//   atmo::Validate(p);                                        // throws atmo::Error, one line
//   std::string json = atmo::ToJson(p);                       // FromJson(json) gives p back
//
// Units: lengths in metres, coefficients per metre, angles in radians (docs/design.md §2). For the
// half-space geometry of the `simple` preset, lengths are in the preset's own length unit and
// coefficients per that unit. Every per-channel vector has one value per wavelength.
#pragma once

#include <cstdint>
#include <filesystem>
#include <string>
#include <string_view>
#include <vector>

namespace atmo {

enum class PhaseFunction {
  kIsotropic,         // 1 / (4 pi)
  kRayleigh,          // 3/(16 pi) (1 + nu^2)
  kModifiedRayleigh,  // Atmosphere Plus: (1.4 + 0.5 nu^2), normalised
  kCornetteShanks,    // Cornette-Shanks with asymmetry g
  kHenyeyGreenstein,  // Henyey-Greenstein with asymmetry g
  kTabulated,         // Medium::phase_table (the Mie medium only)
};

// One sample of a tabulated phase function: its value (any positive scale; atmo normalises the
// table to 1 over the sphere) at a scattering angle.
struct PhaseSample {
  double angle_deg = 0.0;
  double value = 0.0;

  bool operator==(const PhaseSample&) const = default;
};

enum class Geometry {
  kSpherical,  // a planet of radius ground_radius_m with an atmosphere up to top_radius_m
  kHalfSpace,  // the `simple` model's homogeneous half-space below a boundary plane
};

// exp_term * exp(exp_scale_per_m * h) + linear_term_per_m * h + constant_term, clamped to [0, 1],
// at altitude h (after Bruneton 2017).
struct DensityLayer {
  double width_m = 0.0;  // thickness; ignored for the upper layer
  double exp_term = 0.0;
  double exp_scale_per_m = 0.0;
  double linear_term_per_m = 0.0;
  double constant_term = 0.0;

  bool operator==(const DensityLayer&) const = default;
};

// One knot of a tabulated density profile.
struct DensityKnot {
  double altitude_m = 0.0;
  double density = 0.0;  // in [0, 1]

  bool operator==(const DensityKnot&) const = default;
};

// Either two layers (`lower` applies below altitude lower.width_m, `upper` above it), or, when
// `table` is not empty, a tabulated profile: knots at strictly increasing altitudes, exponential
// in altitude between two positive knots and linear where one of them is 0, held at the end knots'
// values outside them (docs/parameters.md, "Tabulated profiles"). The layers are then unused.
struct DensityProfile {
  DensityLayer lower;
  DensityLayer upper;
  std::vector<DensityKnot> table;

  bool tabulated() const { return !table.empty(); }
  // Density at altitude h in metres, in [0, 1].
  double Evaluate(double altitude_m) const;
  // A tabulated profile through the given knots (checked by Validate, not here).
  static DensityProfile Tabulated(std::vector<DensityKnot> knots);
  // A single exponential layer exp(-h / scale_height_m).
  static DensityProfile Exponential(double scale_height_m);
  // A tent: 0 at bottom_m, 1 at peak_m, 0 at top_m (the ozone layer of Bruneton 2017).
  static DensityProfile Tent(double bottom_m, double peak_m, double top_m);
  // Density 1 everywhere.
  static DensityProfile Constant();

  bool operator==(const DensityProfile&) const = default;
};

// One constituent of the atmosphere. A medium whose coefficients are all zero is absent.
struct Medium {
  std::vector<double> scattering_per_m;  // per channel, at density 1
  std::vector<double> absorption_per_m;  // per channel, at density 1
  DensityProfile density;
  PhaseFunction phase = PhaseFunction::kIsotropic;
  double phase_g = 0.0;  // asymmetry, for Cornette-Shanks and Henyey-Greenstein; |g| < 1
  // For kTabulated: samples at strictly increasing angles from 0 to 180 degrees, values > 0,
  // interpolated linearly in angle in the logarithm of the value (docs/parameters.md, "Phase
  // functions"). phase_g then only describes the table (its asymmetry; the viewer's slider).
  std::vector<PhaseSample> phase_table;

  bool present() const;
  double extinction_per_m(std::size_t channel) const {
    return scattering_per_m[channel] + absorption_per_m[channel];
  }
  bool operator==(const Medium&) const = default;
};

// The light of the night sky that no model scatters from the sun: the airglow of the upper
// atmosphere and the zodiacal light (src/atmo/physics/night_sky.cc, docs/night.md). It is added
// to images, cube maps and illuminance by the renderers (atmo::NightSky), attenuated by the
// atmosphere in front of it; the scattering tables do not depend on it.
struct NightSkySettings {
  bool enabled = true;
  // Airglow: a shell of uniform emission centred at `airglow_altitude_m`, `airglow_thickness_m`
  // thick, whose zenith brightness seen from outside the atmosphere is `airglow_scale` times the
  // ESO sky model's (Noll et al. 2012, 130 sfu of solar radio flux).
  double airglow_scale = 1.0;
  double airglow_altitude_m = 92e3;
  double airglow_thickness_m = 16e3;
  // Zodiacal light: `zodiacal_scale` times Leinert et al. 1998's Table 17.
  double zodiacal_scale = 1.0;
  // Integrated starlight (the stars too faint to draw, and the diffuse galactic light):
  // `starlight_scale` times Leinert et al. 1998's Table 35 (Pioneer 10), less the catalogue stars
  // drawn one by one (docs/night.md).
  double starlight_scale = 1.0;

  bool operator==(const NightSkySettings&) const = default;
};

struct AtmosphereParameters {
  std::string name = "custom";  // the preset it came from, or "custom"
  Geometry geometry = Geometry::kSpherical;
  double ground_radius_m = 6360e3;
  double top_radius_m = 6460e3;
  std::vector<double> wavelengths_nm;  // one per channel, > 0
  Medium rayleigh;
  Medium mie;
  Medium ozone;
  // Water vapour: absorbing only, with its own profile (docs/parameters.md, "Gases"). Absent, with
  // empty vectors, in every preset that predates it; when present its vectors have one value per
  // channel like the other media's.
  Medium water_vapor;
  std::vector<double> ground_albedo;  // per channel, in [0, 1]
  double sun_angular_radius_rad = 0.004675;
  // The sun disc's limb darkening: Neckel and Labs 1994's per-wavelength centre-to-limb law
  // (src/atmo/shared/sun.glsl); false: a uniform disc. Either way the disc's irradiance is 1.
  bool sun_limb_darkening = true;
  // Per channel: the solar irradiance that rendered images multiply the model's radiance (per
  // unit irradiance) by. 1 gives images in sr^-1 per unit solar irradiance.
  std::vector<double> solar_irradiance;
  // Display defaults that come with a preset: tone-mapping exposure and the observer altitude.
  double exposure = 10.0;
  double observer_altitude_m = 0.0;
  // The night sky's own light (spherical geometry only; ignored by a half-space).
  NightSkySettings night_sky;

  std::size_t channel_count() const { return wavelengths_nm.size(); }
  bool operator==(const AtmosphereParameters&) const = default;
};

// The largest observer altitude (and layer width, and |length| of the half-space), in metres:
// 1e11 m (0.7 au). Commands check their --altitude against it too (docs/parameters.md).
inline constexpr double kMaxAltitude_m = 1e11;

// Throws atmo::Error naming the first invalid value: a non-finite number, a negative radius or
// coefficient, top <= ground, |g| >= 1, an albedo outside [0, 1], zero channels, a per-channel
// vector of the wrong length, a non-positive wavelength or sun radius, and every value outside
// the physical bounds of docs/parameters.md (radii in [1 m, 1e10 m], coefficients <= 1e3 per m,
// ...), which keep the numerics finite in double and in float.
void Validate(const AtmosphereParameters& parameters);

// Presets of docs/design.md §3: "earth", "atmosphere-plus", "simple". Throws atmo::Error for an
// unknown name, listing the known ones.
AtmosphereParameters Preset(std::string_view name);
std::vector<std::string> PresetNames();

// JSON with the keys of docs/parameters.md. ToJson output is accepted back by FromJson.
// FromJson starts from the preset named by the "preset" key when there is one (else from "earth")
// and overrides what the document holds; it throws atmo::Error on malformed JSON, unknown keys,
// wrong types, and values that fail Validate.
std::string ToJson(const AtmosphereParameters& parameters);
AtmosphereParameters FromJson(std::string_view json_text);
AtmosphereParameters LoadParametersFile(const std::filesystem::path& path);

// A stable 64-bit hash (FNV-1a over the canonical JSON, name excluded) of the parameters,
// written into outputs.
std::uint64_t ParameterHash(const AtmosphereParameters& parameters);
std::string ParameterHashHex(const AtmosphereParameters& parameters);

std::string_view ToString(PhaseFunction phase);
std::string_view ToString(Geometry geometry);

}  // namespace atmo
