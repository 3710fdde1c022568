// Annual skies: one sky per hour of a weather file, calibrated to that hour's measured light, with
// the irradiance on planes and the patch radiances of a Radiance sky matrix (docs/daylighting.md).
//
// To use it:
//   atmo::AnnualSkies year(atmo::Preset("us-standard"), atmo::ReadEpw("site.epw"), {});
//   std::vector<std::size_t> hours = {4000, 4001, 4002};          // indices into the file's hours
//   std::vector<atmo::HourSky> skies = year.Compute(hours);
//
// Each hour (include/atmo/calibration.h for the clear-sky calibration):
// - night: the sun's centre below the horizon at the middle of the hour and no diffuse light;
// - missing: the file lacks the hour's direct-normal or diffuse-horizontal illuminance;
// - low-sun: the sun below min_sun_elevation_deg but diffuse light measured: a CIE standard
//   overcast sky (CIE S 011, sky 1) of the measured diffuse illuminance, the direct light dropped;
// - clear: the aerosol optical depth fixed by the direct light (its circumsolar share counted as a
//   pyrheliometer counts it) and the albedo by the diffuse light;
// - cloudy: more diffuse light than the clear sky of that optical depth gives even with albedo 1:
//   that clear sky (albedo 1) plus a CIE overcast sky carrying the rest of the diffuse light;
// - overcast: less direct light than the largest optical depth of the table transmits: that clear
//   sky scaled by the measured share of its direct light (clear_fraction) plus a CIE overcast sky
//   carrying the rest of the diffuse light;
// - dim: less diffuse light than the most absorbing aerosol of the range gives: that sky, its
//   diffuse light above the measurement (reported).
// The overcast part has the solar spectrum (clouds scatter nearly neutrally).
//
// Speed (the lever of a year of skies): the model is built once per node of a table of aerosol
// optical depths x albedos (aod_nodes x albedo_nodes), and each hour's sky is the bilinear blend of
// the four nodes around its calibrated values, evaluated for that hour's sun; the direct light is
// exact for the hour's optical depth. Hours are computed in order of their optical depth, so that
// at most the nodes of two neighbouring optical depths are held. docs/daylighting.md gives the
// blend's measured error against the sky built for the exact values.
#pragma once

#include <cstddef>
#include <filesystem>
#include <functional>
#include <memory>
#include <span>
#include <string>
#include <vector>

#include "atmo/image.h"
#include "atmo/irradiance.h"
#include "atmo/model.h"
#include "atmo/parameters.h"
#include "atmo/sky_patches.h"
#include "atmo/weather.h"

namespace atmo {

struct AnnualSettings {
  std::string model = "source4d";
  ModelOptions options;  // DaylightModelOptions is applied to them
  std::string aerosol_type = "continental-average";
  // Planes whose irradiance is reported (HourSky::planes), after the horizontal and the plane
  // facing the sun, which are always computed.
  std::vector<Plane> planes;
  int sky_subdivision = 1;  // Reinhart's MF: 1 (145 patches), 2 (577), 4 (2305)
  int patch_samples = 2;    // per patch side (include/atmo/irradiance.h)
  double circumsolar_half_angle_deg = 2.5;
  std::vector<double> aod_nodes = {0.0, 0.05, 0.1, 0.15, 0.2, 0.3, 0.4, 0.55, 0.75, 1.0, 1.4, 2.0};
  std::vector<double> albedo_nodes = {0.7, 1.0};
  double min_single_scattering_albedo = 0.5;  // below: status dim
  double min_sun_elevation_deg = 1.0;
  bool sun_in_matrix = true;  // add the sun's direct light to the patch that holds it (as gendaymtx does)
  // > 0: each hour with light also gets HourSky::sky_map, this many pixels a side (at most 4096).
  int sky_map_size = 0;
  // Also irradiance_spectral.csv (RunAnnual): every plane's irradiance per channel, W m^-2 nm^-1.
  bool per_wavelength = false;
};

enum class HourStatus { kNight, kMissing, kLowSun, kClear, kCloudy, kOvercast, kDim };
std::string_view ToString(HourStatus status);

struct HourSky {
  std::size_t hour = 0;  // index into WeatherFile::hours
  HourStatus status = HourStatus::kNight;
  double julian_day_utc = 0.0;
  double sun_elevation_deg = 0.0;
  double sun_azimuth_deg = 0.0;
  double sun_scale = 1.0;  // 1 / d^2
  // The clear part (NaN without one), its share and the overcast part's diffuse horizontal lux.
  double aod_550 = 0.0;
  double single_scattering_albedo_550 = 0.0;
  double clear_fraction = 0.0;
  double overcast_lux = 0.0;
  // What the sky gives as the instruments measure it, in lux.
  double direct_normal_lux = 0.0;
  double diffuse_horizontal_lux = 0.0;
  // Per channel, per unit solar irradiance times sun_scale: the horizontal, the plane facing the
  // sun, then AnnualSettings::planes.
  std::vector<IrradianceComponents> planes;
  // Per channel: the ground (Lambertian, lit by the global horizontal), then each sky patch's mean
  // radiance, the sun included when sun_in_matrix; channel_count() values each. Empty at night.
  std::vector<double> patch_radiance;
  // The overcast part's zenith radiance, per unit solar irradiance at every channel (0 without one).
  double overcast_zenith = 0.0;
  // With AnnualSettings::sky_map_size: the sky above the horizon as an angular fisheye (the zenith
  // at the centre, the horizon on the inscribed circle, north up and east right as seen from
  // above; 0 outside), in Radiance RGB radiance (include/atmo/colour.h), the sun disc left out
  // (the scene description makes it a source), its aureole kept.
  Image sky_map;
};

// The direction of a sky map's pixel (x, y) of `size` (rows from the top), and whether it lies in
// the circle.
bool SkyMapDirection(int x, int y, int size, glm::dvec3& direction);

class AnnualSkies {
 public:
  // Throws atmo::Error for invalid settings (nodes not increasing or outside their ranges, an
  // unknown model or type) or parameters the model cannot take.
  AnnualSkies(AtmosphereParameters base, WeatherFile weather, AnnualSettings settings);
  ~AnnualSkies();

  const WeatherFile& weather() const { return weather_; }
  const AnnualSettings& settings() const { return settings_; }
  const AtmosphereParameters& base() const { return base_; }
  const SkyPatches& patches() const { return patches_; }
  std::size_t channel_count() const { return base_.channel_count(); }
  // The models built so far (each a full precomputation).
  int models_built() const { return models_built_; }

  // The skies of the given hours (indices into weather().hours), in the order given. `progress`,
  // when set, is called after each hour with the number done; `batch`, when set, with each group
  // of finished hours as soon as it is finished (the hours that need no model first, then those of
  // each optical-depth bracket, at most 256 at a time), so that a caller can keep them; the skies
  // returned then hold only their scalars (no planes, patches or map), so that a year's memory
  // stays that of a few hundred hours.
  std::vector<HourSky> Compute(std::span<const std::size_t> hours,
                               const std::function<void(std::size_t done)>& progress = {},
                               const std::function<void(std::span<const HourSky>)>& batch = {});

 private:
  struct Node;
  const Model& NodeModel(std::size_t aod_index, std::size_t albedo_index);
  void Release(std::size_t below_aod_index);

  AtmosphereParameters base_;
  WeatherFile weather_;
  AnnualSettings settings_;
  SkyPatches patches_;
  std::vector<std::unique_ptr<Model>> nodes_;  // aod index x albedo index
  int models_built_ = 0;
};

// A year (or part of one) run into a folder, resumable and split into shards (docs/daylighting.md):
// the hours selected (`first_hour`..`end_hour` of the file, then every whole day whose number
// modulo `shards` is `shard`) are computed, each group of finished hours written at once as
// out_dir/parts/part-FIRST-LAST-COUNT.txt (atomically), and hours already in a part are skipped.
// out_dir/run.json records the settings, the parameters and the weather file; a folder holding
// another run is refused. When every hour of the file has a part, MergeAnnual writes the outputs.
struct AnnualRun {
  std::filesystem::path out_dir;
  std::size_t first_hour = 0;
  std::size_t end_hour = static_cast<std::size_t>(-1);  // past the last; clamped to the file
  int shard = 0;
  int shards = 1;
};

struct AnnualRunReport {
  std::size_t selected = 0;      // hours of this run's selection
  std::size_t already_done = 0;  // of them, found in parts
  std::size_t computed = 0;
  std::size_t file_done = 0;     // hours of the whole file in parts, after this run
  int models_built = 0;
  bool merged = false;  // the outputs were written
};

// Throws atmo::Error for a shard outside [0, shards), an empty selection, an out_dir that cannot
// be made or written, or that holds another run.
AnnualRunReport RunAnnual(AnnualSkies& skies, const AnnualRun& run,
                          const std::function<void(const std::string& message)>& progress = {});

// With sky maps (AnnualSettings::sky_map_size), each hour with light also gets
// out_dir/maps/sky_HHHH.hdr (its map, HHHH the file's hour from 0) and sky_HHHH.rad (the scene:
// the sun as a `light` source of 0.533 degrees, the map on a `glow` sky through
// out_dir/maps/atmo_sky.cal, the ground a uniform `glow` of albedo x global / pi), written before
// the part that marks the hour done.
//
// Writes out_dir/sky.mtx (Radiance's sky matrix: the ground then the patches, one column per hour
// of the file, Radiance RGB), hours.csv (each hour's sun, status and calibration) and
// irradiance.csv (each daylight hour's components per plane) from the parts, atomically, when
// every hour of the file has one; returns whether it did.
bool MergeAnnual(const AnnualSkies& skies, const std::filesystem::path& out_dir);

}  // namespace atmo
