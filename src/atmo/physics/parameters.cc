// Atmosphere parameters: density profiles, validation, hashing and enum names.
//
// Validation reports the first invalid value it meets as one line that names the JSON key path of
// docs/parameters.md (`rayleigh.scattering_per_m[1]`, `mie.density.upper.exp_term`, ...), so that a
// user who edited a config file can find the value to fix.
#include "atmo/parameters.h"

#include <algorithm>
#include <charconv>
#include <cmath>
#include <cstdio>
#include <numbers>
#include <string>
#include <utility>

#include "atmo/error.h"
#include "printable.h"
#include "physics/density_interpolation.h"

namespace atmo {
namespace {

// The most channels a parameter set may have: spectral rendering samples the visible range at
// 1 nm (about 400 channels); 4096 leaves room and still bounds per-channel allocations.
constexpr std::size_t kMaxChannelCount = 4096;

// Physical bounds (docs/parameters.md, docs/reliability.md). They keep every intermediate of the
// shared code finite and meaningful in double on the CPU and in float (lengths in km) on the GPU:
// - radii in [1 m, 1e10 m]: r^2 stays far from overflow (1e20 m^2; 1e14 km^2 in float) and from
//   underflow (the audit's 1e154 m and 1e-200 m radii turned r^2 into inf / 0 and NaN into an
//   index); 1e10 m is 14 solar radii, 1 m a boulder.
// - a thickness top - ground in [1e-5, 10] x ground: float keeps > 100 distinct radii across the
//   atmosphere (its epsilon is 6e-8), and no known atmosphere reaches 10 planet radii.
// - lengths and altitudes up to 1e11 m (0.7 au): far enough to see any allowed planet as a dot.
// - coefficients up to 1e3 per m: optical depths stay <= 1e14 over the longest allowed path
//   (exp underflows to 0 well before); the audit's 1e300 overflowed to inf and NaN.
// - density terms up to 1e6 in magnitude (per m for the rates, i.e. scale heights >= 1 um):
//   the linear and constant parts stay finite at every allowed altitude, so an exponential that
//   overflows is +-inf alone and the [0, 1] clamp holds (opposite-signed infinities made NaN).
constexpr double kMinRadius_m = 1.0;
constexpr double kMaxRadius_m = 1e10;
constexpr double kMinRelativeThickness = 1e-5;
constexpr double kMaxRelativeThickness = 10.0;
constexpr double kMaxLength_m = kMaxAltitude_m;
constexpr double kMaxCoefficient_per_m = 1e3;
constexpr double kMaxDensityTerm = 1e6;
constexpr double kMinWavelength_nm = 1.0;
constexpr double kMaxWavelength_nm = 1e5;
// |g| <= 0.999: the peak (1 + g) / (1 - g)^2 / (4 pi) stays below 2e5 and 1 - g keeps three
// significant digits in float.
constexpr double kMaxPhaseG = 0.999;
// Below 1e-6 rad the disc's centre radiance 1 / (pi sin^2(alpha / 2)) passes 1e12.
constexpr double kMinSunRadius_rad = 1e-6;
constexpr double kMaxIrradiance = 1e10;
constexpr double kMinExposure = 1e-10;
constexpr double kMaxExposure = 1e10;

// A bound of a range, in the shortest form (1e+10 rather than 10000000000).
std::string FormatBound(double value) {
  char buffer[32];
  const auto result = std::to_chars(buffer, buffer + sizeof buffer, value);
  return std::string(buffer, result.ptr);
}

std::string Indexed(const std::string& key, std::size_t index) {
  return key + "[" + std::to_string(index) + "]";
}

[[noreturn]] void Fail(const std::string& message) { throw Error(message); }

void CheckFinite(const std::string& key, double value) {
  if (!std::isfinite(value)) Fail(key + " must be finite (got " + FormatNumber(value) + ")");
}

void CheckChannelCount(const std::string& key, const std::vector<double>& values,
                       std::size_t channel_count) {
  if (values.size() == channel_count) return;
  Fail(key + " has " + std::to_string(values.size()) +
       (values.size() == 1 ? " value" : " values") + " but there " +
       (channel_count == 1 ? "is 1 channel" : "are " + std::to_string(channel_count) + " channels"));
}

// `value` in [lo, hi] (NaN fails): "KEY must be in [LO, HI] UNIT (got VALUE)".
void CheckRange(const std::string& key, double value, double lo, double hi, const std::string& unit) {
  if (value >= lo && value <= hi) return;
  Fail(key + " must be in [" + FormatBound(lo) + ", " + FormatBound(hi) + "]" +
       (unit.empty() ? "" : " " + unit) + " (got " + FormatNumber(value) + ")");
}

// Every value in [lo, hi], one per channel.
void CheckRangePerChannel(const std::string& key, const std::vector<double>& values,
                          std::size_t channel_count, double lo, double hi, const std::string& unit) {
  CheckChannelCount(key, values, channel_count);
  for (std::size_t i = 0; i < values.size(); ++i) CheckRange(Indexed(key, i), values[i], lo, hi, unit);
}

void ValidateLayer(const std::string& key, const DensityLayer& layer) {
  CheckRange(key + ".width_m", layer.width_m, 0.0, kMaxLength_m, "m");
  CheckRange(key + ".exp_term", layer.exp_term, -kMaxDensityTerm, kMaxDensityTerm, "");
  CheckRange(key + ".exp_scale_per_m", layer.exp_scale_per_m, -kMaxDensityTerm, kMaxDensityTerm, "per m");
  CheckRange(key + ".linear_term_per_m", layer.linear_term_per_m, -kMaxDensityTerm, kMaxDensityTerm, "per m");
  CheckRange(key + ".constant_term", layer.constant_term, -kMaxDensityTerm, kMaxDensityTerm, "");
}

// The most knots of a tabulated profile: a profile at 1 m steps through a 100 km atmosphere.
constexpr std::size_t kMaxTableKnots = 100000;

// Knots at strictly increasing finite altitudes within +-kMaxLength_m, densities in [0, 1].
void ValidateTable(const std::string& key, const std::vector<DensityKnot>& table) {
  if (table.size() < 2) Fail(key + " needs at least 2 knots (got " + std::to_string(table.size()) + ")");
  if (table.size() > kMaxTableKnots) {
    Fail(key + " has " + std::to_string(table.size()) + " knots, more than the " + std::to_string(kMaxTableKnots) +
         " allowed");
  }
  for (std::size_t i = 0; i < table.size(); ++i) {
    const std::string knot = Indexed(key, i);
    CheckRange(knot + ".altitude_m", table[i].altitude_m, -kMaxLength_m, kMaxLength_m, "m");
    CheckRange(knot + ".density", table[i].density, 0.0, 1.0, "");
    if (i > 0 && !(table[i].altitude_m > table[i - 1].altitude_m)) {
      Fail(key + " altitudes must increase strictly: knot " + std::to_string(i) + " is at " +
           FormatNumber(table[i].altitude_m) + " m after " + FormatNumber(table[i - 1].altitude_m) + " m");
    }
  }
}

// A tabulated phase function: the Mie medium only (the shared code carries one table), samples
// from 0 to 180 degrees at strictly increasing angles, values positive and finite.
void ValidatePhaseTable(const std::string& key, const Medium& medium) {
  const std::vector<PhaseSample>& table = medium.phase_table;
  if (medium.phase != PhaseFunction::kTabulated) {
    if (!table.empty()) Fail(key + ".phase_table is only read with phase_function \"tabulated\"");
    return;
  }
  if (key != "mie") Fail(key + ".phase_function \"tabulated\" is only supported for the mie medium");
  const std::string name = key + ".phase_table";
  if (table.size() < 2) Fail(name + " needs at least 2 samples (got " + std::to_string(table.size()) + ")");
  if (table.size() > kMaxTableKnots) {
    Fail(name + " has " + std::to_string(table.size()) + " samples, more than the " +
         std::to_string(kMaxTableKnots) + " allowed");
  }
  for (std::size_t i = 0; i < table.size(); ++i) {
    const std::string sample = Indexed(name, i);
    CheckRange(sample + ".angle_deg", table[i].angle_deg, 0.0, 180.0, "degrees");
    if (!(table[i].value > 0.0 && table[i].value <= 1e12)) {  // also NaN
      Fail(sample + ".value must be in (0, 1e12] (got " + FormatNumber(table[i].value) + ")");
    }
    if (i > 0 && !(table[i].angle_deg > table[i - 1].angle_deg)) {
      Fail(name + " angles must increase strictly: sample " + std::to_string(i) + " is at " +
           FormatNumber(table[i].angle_deg) + " degrees after " + FormatNumber(table[i - 1].angle_deg));
    }
  }
  if (table.front().angle_deg != 0.0 || table.back().angle_deg != 180.0) {
    Fail(name + " must run from 0 to 180 degrees (got " + FormatNumber(table.front().angle_deg) + " to " +
         FormatNumber(table.back().angle_deg) + ")");
  }
}

void ValidateMedium(const std::string& key, const Medium& medium, std::size_t channel_count) {
  CheckRangePerChannel(key + ".scattering_per_m", medium.scattering_per_m, channel_count, 0.0,
                       kMaxCoefficient_per_m, "per m");
  CheckRangePerChannel(key + ".absorption_per_m", medium.absorption_per_m, channel_count, 0.0,
                       kMaxCoefficient_per_m, "per m");
  if (!(std::fabs(medium.phase_g) < 1.0)) {  // also NaN
    Fail(key + ".phase_g must satisfy |g| < 1 (got " + FormatNumber(medium.phase_g) + ")");
  }
  CheckRange(key + ".phase_g", medium.phase_g, -kMaxPhaseG, kMaxPhaseG, "");
  ValidatePhaseTable(key, medium);
  if (medium.density.tabulated()) {
    ValidateTable(key + ".density.table", medium.density.table);
  } else {
    ValidateLayer(key + ".density.lower", medium.density.lower);
    ValidateLayer(key + ".density.upper", medium.density.upper);
  }
}

}  // namespace

// Bruneton 2017's layer: exp_term e^{exp_scale h} + linear_term h + constant_term, clamped to [0, 1].
// A zero exp_term skips the exponential so that exp_scale may be anything without overflow.
// A tabulated profile: exponential between two positive knots (linear in log density), linear
// where one is 0, the end values outside.
double DensityProfile::Evaluate(double altitude_m) const {
  if (tabulated()) {
    if (!(altitude_m > table.front().altitude_m)) return table.front().density;
    if (altitude_m >= table.back().altitude_m) return table.back().density;
    const auto upper_knot = std::upper_bound(table.begin(), table.end(), altitude_m,
                                             [](double h, const DensityKnot& k) { return h < k.altitude_m; });
    const DensityKnot& b = *upper_knot;
    const DensityKnot& a = *(upper_knot - 1);
    const double f = (altitude_m - a.altitude_m) / (b.altitude_m - a.altitude_m);
    return std::clamp(InterpolateDensity(a.density, b.density, f), 0.0, 1.0);
  }
  const DensityLayer& layer = altitude_m < lower.width_m ? lower : upper;
  const double exponential =
      layer.exp_term == 0.0 ? 0.0 : layer.exp_term * std::exp(layer.exp_scale_per_m * altitude_m);
  const double density = exponential + layer.linear_term_per_m * altitude_m + layer.constant_term;
  return std::clamp(density, 0.0, 1.0);
}

// Both layers hold exp(-h / H) (the lower one is zero wide), so that altitudes below 0, such as
// an observer inside a half-space, still get the exponential clamped to 1 rather than 0.
DensityProfile DensityProfile::Exponential(double scale_height_m) {
  DensityLayer layer;
  layer.exp_term = 1.0;
  layer.exp_scale_per_m = -1.0 / scale_height_m;
  return DensityProfile{layer, layer, {}};
}

// Lower layer (h < peak): rises linearly from 0 at bottom to 1 at peak; upper layer falls from 1
// at peak to 0 at top; the clamp keeps it 0 outside [bottom, top].
DensityProfile DensityProfile::Tent(double bottom_m, double peak_m, double top_m) {
  if (!(bottom_m < peak_m && peak_m < top_m)) {
    Fail("a density tent needs bottom < peak < top (got " + FormatNumber(bottom_m) + ", " +
         FormatNumber(peak_m) + ", " + FormatNumber(top_m) + ")");
  }
  DensityProfile profile;
  profile.lower.width_m = peak_m;
  profile.lower.linear_term_per_m = 1.0 / (peak_m - bottom_m);
  profile.lower.constant_term = -bottom_m / (peak_m - bottom_m);
  profile.upper.linear_term_per_m = -1.0 / (top_m - peak_m);
  profile.upper.constant_term = top_m / (top_m - peak_m);
  return profile;
}

DensityProfile DensityProfile::Tabulated(std::vector<DensityKnot> knots) {
  DensityProfile profile;
  profile.table = std::move(knots);
  return profile;
}

DensityProfile DensityProfile::Constant() {
  DensityLayer layer;
  layer.constant_term = 1.0;
  return DensityProfile{layer, layer, {}};
}

bool Medium::present() const {
  for (double value : scattering_per_m) {
    if (value != 0.0) return true;
  }
  for (double value : absorption_per_m) {
    if (value != 0.0) return true;
  }
  return false;
}

void Validate(const AtmosphereParameters& p) {
  const std::size_t channel_count = p.channel_count();
  if (channel_count == 0) Fail("wavelengths_nm must have at least one channel");
  if (channel_count > kMaxChannelCount) {
    Fail("wavelengths_nm has " + std::to_string(channel_count) + " channels, more than the " +
         std::to_string(kMaxChannelCount) + " allowed");
  }
  for (std::size_t i = 0; i < channel_count; ++i) {
    CheckRange(Indexed("wavelengths_nm", i), p.wavelengths_nm[i], kMinWavelength_nm, kMaxWavelength_nm, "nm");
  }

  CheckFinite("ground_radius_m", p.ground_radius_m);
  CheckFinite("top_radius_m", p.top_radius_m);
  if (p.geometry == Geometry::kSpherical) {
    CheckRange("ground_radius_m", p.ground_radius_m, kMinRadius_m, kMaxRadius_m, "m");
    if (p.top_radius_m <= p.ground_radius_m) {
      Fail("top_radius_m (" + FormatNumber(p.top_radius_m) +
           ") must be greater than ground_radius_m (" + FormatNumber(p.ground_radius_m) + ")");
    }
    // The thickness, relative to the planet: the range is given in metres for this planet.
    const double thickness = p.top_radius_m - p.ground_radius_m;
    const double relative = thickness / p.ground_radius_m;
    if (!(relative >= kMinRelativeThickness && relative <= kMaxRelativeThickness)) {
      char range[64];
      std::snprintf(range, sizeof range, "[%.6g, %.6g]", kMinRelativeThickness * p.ground_radius_m,
                    kMaxRelativeThickness * p.ground_radius_m);
      Fail("top_radius_m - ground_radius_m must be in [1e-05, 10] x ground_radius_m = " + std::string(range) +
           " m (got " + FormatNumber(thickness) + ")");
    }
  } else {
    // Unused by the half-space, but still bounded: they travel into the shared code.
    CheckRange("ground_radius_m", p.ground_radius_m, -kMaxLength_m, kMaxLength_m, "m");
    CheckRange("top_radius_m", p.top_radius_m, -kMaxLength_m, kMaxLength_m, "m");
  }

  ValidateMedium("rayleigh", p.rayleigh, channel_count);
  ValidateMedium("mie", p.mie, channel_count);
  ValidateMedium("ozone", p.ozone, channel_count);
  // Water vapour is optional: empty vectors mean none.
  if (!p.water_vapor.scattering_per_m.empty() || !p.water_vapor.absorption_per_m.empty()) {
    ValidateMedium("water_vapor", p.water_vapor, channel_count);
    for (std::size_t i = 0; i < channel_count; ++i) {
      if (p.water_vapor.scattering_per_m[i] != 0.0) {
        Fail(Indexed("water_vapor.scattering_per_m", i) + " must be 0: water vapour only absorbs in this model");
      }
    }
  }

  CheckChannelCount("ground_albedo", p.ground_albedo, channel_count);
  for (std::size_t i = 0; i < channel_count; ++i) {
    const double albedo = p.ground_albedo[i];
    if (!(albedo >= 0.0 && albedo <= 1.0)) {  // also rejects NaN
      Fail(Indexed("ground_albedo", i) + " must be in [0, 1] (got " + FormatNumber(albedo) + ")");
    }
  }

  const double sun_radius = p.sun_angular_radius_rad;
  if (!(sun_radius >= kMinSunRadius_rad && sun_radius < std::numbers::pi / 2.0)) {
    Fail("sun_angular_radius_rad must be in [1e-06, pi/2) (got " + FormatNumber(sun_radius) + ")");
  }

  CheckRangePerChannel("solar_irradiance", p.solar_irradiance, channel_count, 0.0, kMaxIrradiance, "");

  CheckRange("exposure", p.exposure, kMinExposure, kMaxExposure, "");

  CheckFinite("observer_altitude_m", p.observer_altitude_m);
  if (p.geometry == Geometry::kSpherical && p.observer_altitude_m < 0.0) {
    Fail("observer_altitude_m must be >= 0 for spherical geometry (got " +
         FormatNumber(p.observer_altitude_m) + ")");
  }
  CheckRange("observer_altitude_m", p.observer_altitude_m, -kMaxLength_m, kMaxLength_m, "m");

  const NightSkySettings& night = p.night_sky;
  CheckRange("night_sky.airglow_scale", night.airglow_scale, 0.0, 1e3, "");
  CheckRange("night_sky.zodiacal_scale", night.zodiacal_scale, 0.0, 1e3, "");
  CheckRange("night_sky.starlight_scale", night.starlight_scale, 0.0, 1e3, "");
  CheckRange("night_sky.airglow_thickness_m", night.airglow_thickness_m, 1.0, 1e6, "m");
  CheckRange("night_sky.airglow_altitude_m", night.airglow_altitude_m, 0.0, kMaxLength_m, "m");
  if (!(night.airglow_altitude_m - 0.5 * night.airglow_thickness_m >= 0.0)) {
    Fail("night_sky: the airglow layer must lie above the ground (airglow_altitude_m >= airglow_thickness_m / 2)");
  }
}

// FNV-1a, 64 bit (Fowler, Noll, Vo): offset basis 14695981039346656037, prime 1099511628211,
// over the bytes of the canonical JSON, which holds every value exactly.
std::uint64_t ParameterHash(const AtmosphereParameters& parameters) {
  // The physics only: the same atmosphere hashes the same whatever it is named, so that tables
  // computed for a preset serve an identical "custom" config.
  AtmosphereParameters unnamed = parameters;
  unnamed.name = "custom";
  // The night sky's light is added to images, not to the tables: it does not change the hash.
  unnamed.night_sky = NightSkySettings{};
  std::uint64_t hash = 14695981039346656037ull;
  for (const char c : ToJson(unnamed)) {
    hash ^= static_cast<unsigned char>(c);
    hash *= 1099511628211ull;
  }
  return hash;
}

std::string ParameterHashHex(const AtmosphereParameters& parameters) {
  char buffer[17];
  std::snprintf(buffer, sizeof buffer, "%016llx",
                static_cast<unsigned long long>(ParameterHash(parameters)));
  return buffer;
}

std::string_view ToString(PhaseFunction phase) {
  switch (phase) {
    case PhaseFunction::kIsotropic: return "isotropic";
    case PhaseFunction::kRayleigh: return "rayleigh";
    case PhaseFunction::kModifiedRayleigh: return "modified_rayleigh";
    case PhaseFunction::kCornetteShanks: return "cornette_shanks";
    case PhaseFunction::kHenyeyGreenstein: return "henyey_greenstein";
    case PhaseFunction::kTabulated: return "tabulated";
  }
  return "unknown";
}

std::string_view ToString(Geometry geometry) {
  switch (geometry) {
    case Geometry::kSpherical: return "spherical";
    case Geometry::kHalfSpace: return "half_space";
  }
  return "unknown";
}

}  // namespace atmo
