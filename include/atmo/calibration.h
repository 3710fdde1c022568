// Calibration of a clear sky to a measured hour: the aerosol that makes a model reproduce the
// direct-normal and diffuse-horizontal illuminance a weather station measured.
//
// To use it:
//   atmo::DaylightMeasurement m{/*direct_normal_lux=*/78000.0, /*diffuse_horizontal_lux=*/14500.0};
//   atmo::CalibrationSettings s;          // model source4d, aerosol continental-average
//   atmo::CalibrationResult r = atmo::CalibrateClearSky(atmo::Preset("us-standard"), 0.0,
//                                                       atmo::SunDirection(45.0, 180.0), m, s);
//   if (r.status == atmo::CalibrationStatus::kClear) { /* r.parameters reproduce m */ }
//
// What two measurements determine (docs/daylighting.md): the direct light fixes the aerosol's
// extinction, its optical depth at 550 nm (tau_550), with the spectral shape of the aerosol type;
// the diffuse light then fixes how much of that extinction scatters rather than absorbs, the
// single-scattering albedo at 550 nm (omega_550), shifted by the same amount at every wavelength
// (each channel's albedo clamped to [0, 1]). The type's profile and asymmetry, the air, the gases
// and the ground's albedo stay as the parameters have them.
//
// The measurements are taken as the instruments give them: the direct normal from a pyrheliometer,
// which sees the sun's disc and the aureole within its field of view (circumsolar_half_angle_deg,
// 2.5 degrees by WMO), and the diffuse horizontal from a shaded pyranometer, which sees the rest of
// the sky (include/atmo/irradiance.h's components).
#pragma once

#include <string>

#include <glm/glm.hpp>

#include "atmo/model.h"
#include "atmo/parameters.h"

namespace atmo {

struct DaylightMeasurement {
  double direct_normal_lux = 0.0;
  double diffuse_horizontal_lux = 0.0;
};

struct CalibrationSettings {
  std::string model = "source4d";
  ModelOptions options;
  // The aerosol type whose optical depth and albedo are fitted (include/atmo/aerosol.h).
  std::string aerosol_type = "continental-average";
  // The instruments' split between direct and diffuse (include/atmo/irradiance.h).
  double circumsolar_half_angle_deg = 2.5;
  // The range searched for omega_550.
  double min_single_scattering_albedo = 0.5;
  double max_single_scattering_albedo = 1.0;
  // Relative agreement asked of both illuminances.
  double tolerance = 0.005;
  // 1 / d^2 for an Earth-sun distance d in au (SunPosition::distance_au); 1 at 1 au.
  double sun_scale = 1.0;
  // The largest number of models built (each a full precomputation) before giving up.
  int max_model_builds = 12;
};

enum class CalibrationStatus {
  kClear,              // both measurements reproduced within the tolerance
  kTooMuchDiffuse,     // more diffuse light than any clear sky with this direct light gives: clouds
  kTooLittleDiffuse,   // less diffuse light than the most absorbing aerosol of the range gives
  kTooMuchDirect,      // more direct light than an atmosphere without aerosol transmits
  kTooLittleDirect,    // less direct light than tau_550 = 10 transmits: clouds or fog
  kNotConverged,       // max_model_builds reached
};

std::string_view ToString(CalibrationStatus status);

struct CalibrationResult {
  CalibrationStatus status = CalibrationStatus::kNotConverged;
  // The calibrated atmosphere (for a status other than kClear, the closest one found: the
  // optical depth and the albedo at the end of their range that was reached).
  AtmosphereParameters parameters;
  double aod_550 = 0.0;
  double single_scattering_albedo_550 = 0.0;
  // What the calibrated model gives, as the instruments would measure it.
  double direct_normal_lux = 0.0;
  double diffuse_horizontal_lux = 0.0;
  int model_builds = 0;
  std::string message;  // one line: what was found, or why the measurements cannot be met
};

// The aerosol of `base` (spherical, with a Mie medium or not) is replaced by the fitted one. The
// sun must be at least 1 degree above the horizon. Throws atmo::Error for invalid settings, a
// negative or non-finite measurement, a half-space atmosphere or a sun too low; a measurement no
// clear sky gives is not an error but a status.
CalibrationResult CalibrateClearSky(const AtmosphereParameters& base, double altitude_m, const glm::dvec3& sun,
                                    const DaylightMeasurement& measured, const CalibrationSettings& settings = {});

// The aerosol of `base` replaced by `type` at optical depth `aod_550`: the type's OPAC column at
// its typical optical depth (ApplyAerosol) with every Mie coefficient scaled by aod_550 / typical,
// so that the profile's shape stays and the optical depth of any path is linear in aod_550; its
// single-scattering albedo shifted so that it is `single_scattering_albedo_550` at 550 nm (NaN:
// the type's own). Throws atmo::Error for invalid values.
AtmosphereParameters WithAerosol(const AtmosphereParameters& base, const std::string& type, double aod_550,
                                 double single_scattering_albedo_550);
// The sun's transmitted light at a station as a function of the aerosol optical depth (WithAerosol):
// the slant optical depths of the air and gases and of the aerosol at the type's typical amount,
// each by a 1000-step quadrature, then exact for any optical depth.
class DirectLight {
 public:
  // sun_scale: 1 / d^2 (au). Throws atmo::Error as WithAerosol does.
  DirectLight(const AtmosphereParameters& base, const std::string& type, double altitude_m, const glm::dvec3& sun,
              double sun_scale = 1.0);
  // Per channel, per unit solar irradiance, times sun_scale.
  std::vector<double> DirectNormal(double aod_550) const;
  double Lux(double aod_550) const;
  // The optical depth in [0, kMaxAerosolOpticalDepth] whose direct light is `lux` (the bound
  // reached when none is).
  double OpticalDepthFor(double lux) const;

 private:
  std::vector<double> air_;      // transmittance without aerosol
  std::vector<double> aerosol_;  // the aerosol's slant optical depth per unit aod_550
  std::vector<double> weights_;  // lux per unit relative irradiance, per channel
  double sun_scale_ = 1.0;
};

// The options the daylighting computations give a model: source4d marches every direction
// (sky_view=off) unless `options` choose, because its sky-view table costs about 0.6 s per sun on
// two cores while the few thousand directions of an irradiance integral cost a tenth of that.
ModelOptions DaylightModelOptions(const std::string& model, ModelOptions options);

// The single-scattering albedo of the parameters' Mie medium at 550 nm (interpolated linearly in
// wavelength between the channels around it; the nearest channel outside their range).
double MieSingleScatteringAlbedo550(const AtmosphereParameters& parameters);

}  // namespace atmo
