// `atmo sample`: the machine-readable model query of docs/design.md §4.
//
//   IN.csv : altitude_m,sun_zenith_deg,view_zenith_deg,azimuth_deg          (header line first)
//   OUT.csv: altitude_m,sun_zenith_deg,view_zenith_deg,azimuth_deg,wavelength_nm,radiance,
//            transmittance,stderr
//
// One output row per input row and channel, channels in the order of parameters.wavelengths_nm.
// `radiance` is the model's scattered light; with --night-sky it also holds the night sky's own
// light (airglow and zodiacal light, include/atmo/night_sky.h, default ecliptic), as images do;
// with a moon (--moon-elevation and --moon-phase, --moon-azimuth measured from the sun's; or the
// moon of --date) the moon's light as the model scatters it (its disc, as the sun's, is not in it).
// Angles are in degrees; the sun lies at compass azimuth 0 and the view at `azimuth_deg`, so the
// azimuth is the one between the horizontal projections of the view and sun directions.
//
// Points that share an altitude and a sun share one view. With --backend gl, model hillaire
// computes its tables and every point of a view on the GPU (one pass over the view's directions);
// models elek and source4d compute their tables on the GPU and answer from them.
#include <algorithm>
#include <cmath>
#include <cstdio>
#include <fstream>
#include <functional>
#include <map>
#include <optional>
#include <string_view>
#include <utility>

#include <glm/glm.hpp>

#include "atmo/colour.h"
#include "atmo/spectrum.h"
#include "atmo/error.h"
#include "atmo/image.h"
#include "atmo/moon.h"
#include "atmo/night_sky.h"
#include "commands.h"
#include "grid.h"
#include "progress_bar.h"
#ifdef ATMO_HAVE_GL
#include "gl/context.h"
#include "gl/hillaire_gl.h"
#endif

namespace atmo::cli {

namespace {

constexpr const char* kOutputHeader =
    "altitude_m,sun_zenith_deg,view_zenith_deg,azimuth_deg,wavelength_nm,radiance,transmittance,stderr";
// --unit luminance: one row per point. The transmittance is the luminous one, the sun's
// luminance-weighted transmittance: sum_c w_c T_c / sum_c w_c with w_c the luminance weights.
constexpr const char* kLuminanceHeader =
    "altitude_m,sun_zenith_deg,view_zenith_deg,azimuth_deg,luminance_cd_m2,luminous_transmittance,stderr";

// What one query gives per channel.
struct SampleResult {
  std::vector<double> radiance;
  std::vector<double> transmittance;
  // Standard error of `radiance`: 0 for deterministic models.
  std::vector<double> standard_error;
};

// The points that share an observer altitude and a sun (one view), in order of first appearance.
struct PointGroup {
  double altitude_m = 0.0;
  double sun_zenith_deg = 0.0;
  std::vector<std::size_t> indices;  // into the points
  std::vector<glm::dvec3> views;     // the points' view directions (unit, local frame)
};

std::vector<PointGroup> GroupPoints(const std::vector<SamplePoint>& points) {
  std::vector<PointGroup> groups;
  std::map<std::pair<double, double>, std::size_t> group_of;
  for (std::size_t i = 0; i < points.size(); ++i) {
    const std::pair<double, double> key(points[i].altitude_m, points[i].sun_zenith_deg);
    const auto [found, inserted] = group_of.emplace(key, groups.size());
    if (inserted) groups.push_back({key.first, key.second, {}, {}});
    groups[found->second].indices.push_back(i);
    groups[found->second].views.push_back(
        DirectionFromZenithAzimuth(glm::radians(points[i].view_zenith_deg), glm::radians(points[i].azimuth_deg)));
  }
  return groups;
}

glm::dvec3 SunOf(const PointGroup& group) { return DirectionFromZenithAzimuth(glm::radians(group.sun_zenith_deg), 0.0); }

// Evaluates one group's points into `results` (indexed like the points) for a source along `light`
// (the group's sun, or the moon: the models are linear in their source); throws atmo::Error.
using GroupEvaluator =
    std::function<void(const PointGroup& group, const glm::dvec3& light, std::vector<SampleResult>& results)>;

// The moon of the samples, in sample's frame (the sun at compass azimuth 0): its elevation, its
// azimuth from the sun's, its phase and distance.
struct SampleMoon {
  double elevation_deg = 0.0;
  double azimuth_from_sun_deg = 0.0;
  double phase_deg = 0.0;
  double distance_km = kMoonReferenceDistanceKm;
};

// Every point through `evaluate`, group by group, and the whole CSV text in the input order.
std::string EvaluatePoints(const AtmosphereParameters& parameters, const std::vector<SamplePoint>& points,
                           RadianceUnit unit, bool night_sky, const std::optional<SampleMoon>& moon,
                           const GroupEvaluator& evaluate) {
  const std::vector<double>& wavelengths_nm = parameters.wavelengths_nm;
  std::vector<SampleResult> results(points.size());
  ProgressBar progress("sample");
  std::size_t done = 0;
  for (const PointGroup& group : GroupPoints(points)) {
    progress.Update(static_cast<double>(done), static_cast<double>(points.size()));
    try {
      evaluate(group, SunOf(group), results);
      if (moon) {
        // The moonlit sky: the same model lit from the moon, times the moon's irradiance relative
        // to the sun's; standard errors in quadrature. No disc (sample has none of the sun's).
        const glm::dvec3 direction = SunDirection(moon->elevation_deg, moon->azimuth_from_sun_deg);
        const Moon lit(direction, moon->phase_deg, moon->distance_km, wavelengths_nm, SunOf(group));
        std::vector<SampleResult> moonlit(points.size());
        evaluate(group, direction, moonlit);
        for (std::size_t index : group.indices) {
          SampleResult& result = results[index];
          for (std::size_t c = 0; c < result.radiance.size(); ++c) {
            const double scale = lit.relative_irradiance()[c];
            result.radiance[c] += scale * moonlit[index].radiance[c];
            result.standard_error[c] = std::hypot(result.standard_error[c], scale * moonlit[index].standard_error[c]);
          }
        }
      }
      if (night_sky) {
        const NightSky night(parameters, std::max(group.altitude_m, 0.0), SunOf(group));
        std::vector<double> glow(wavelengths_nm.size());
        for (std::size_t k = 0; k < group.indices.size(); ++k) {
          night.Radiance(group.views[k], glow);
          std::vector<double>& radiance = results[group.indices[k]].radiance;
          for (std::size_t c = 0; c < glow.size(); ++c) radiance[c] += glow[c];
        }
      }
    } catch (const Error& error) {
      const std::string& where = points[group.indices.front()].location;
      throw Error((where.empty() ? "" : where + ": ") + error.what());
    }
    done += group.indices.size();
  }
  const SpectralConversion convert(wavelengths_nm);
  std::string csv = std::string(unit == RadianceUnit::kLuminance ? kLuminanceHeader : kOutputHeader) + "\n";
  const std::size_t out_channels = SampleChannels(unit, wavelengths_nm.size());
  std::vector<double> radiance(out_channels), transmittance(out_channels), error(out_channels);
  for (std::size_t i = 0; i < points.size(); ++i) {
    const SamplePoint& point = points[i];
    const SampleResult& result = results[i];
    const std::string inputs = Format("%.10g,%.10g,%.10g,%.10g,", point.altitude_m, point.sun_zenith_deg,
                                      point.view_zenith_deg, point.azimuth_deg);
    ConvertSample(convert, unit, result.radiance, result.transmittance, result.standard_error, radiance, transmittance,
                  error);
    if (unit == RadianceUnit::kLuminance) {
      csv += inputs + Format("%.9e,%.9e,%.9e\n", radiance[0], transmittance[0], error[0]);
      continue;
    }
    for (std::size_t c = 0; c < wavelengths_nm.size(); ++c) {
      csv += inputs;
      csv += Format("%.10g,%.9e,%.9e,%.9e\n", wavelengths_nm[c], radiance[c], transmittance[c], error[c]);
    }
  }
  return csv;
}

// A model's views (the CPU, or tables the gl backend computed), one query per point.
GroupEvaluator ModelEvaluator(const Model& model) {
  return [&model](const PointGroup& group, const glm::dvec3& light, std::vector<SampleResult>& results) {
    const std::unique_ptr<SkyView> sky = model.View(group.altitude_m, light);
    const std::size_t channels = sky->channel_count();
    for (std::size_t k = 0; k < group.indices.size(); ++k) {
      SampleResult& result = results[group.indices[k]];
      result = {std::vector<double>(channels), std::vector<double>(channels), std::vector<double>(channels, 0.0)};
      sky->RadianceEstimate(group.views[k], result.radiance, result.standard_error);
      sky->Transmittance(group.views[k], result.transmittance);
    }
  };
}

#ifdef ATMO_HAVE_GL
// Model hillaire on the gl backend: per group the view's tables and one GPU pass over its directions.
GroupEvaluator HillaireGlEvaluator(gl::HillaireGl& sky) {
  return [&sky](const PointGroup& group, const glm::dvec3& light, std::vector<SampleResult>& results) {
    sky.SetView(group.altitude_m, light, /*ground=*/false);
    std::vector<double> radiance, transmittance;  // channel_count values per view
    sky.Sample(group.views, radiance, transmittance);
    const std::size_t nc = sky.channel_count();
    for (std::size_t k = 0; k < group.indices.size(); ++k) {
      const auto channels = [&](const std::vector<double>& values) {
        return std::vector<double>(values.begin() + static_cast<std::ptrdiff_t>(nc * k),
                                   values.begin() + static_cast<std::ptrdiff_t>(nc * (k + 1)));
      };
      results[group.indices[k]] = {channels(radiance), channels(transmittance), std::vector<double>(nc, 0.0)};
    }
  };
}
#endif

}  // namespace

int RunSample(const CommonOptions& common, const SampleCommand& command) {
  CheckBackend(common, /*command_has_gl=*/true);
  CheckOutputsApart(common, {{"--grid", command.grid_path}}, {{"--out", command.out_path}});
  const AtmosphereParameters parameters = LoadParameters(common);
  const RadianceUnit unit = ParseRadianceUnit(command.unit);

  std::vector<SamplePoint> points;
  if (!command.grid_path.empty()) {
    if (HasDate(command.sun)) throw Error("--date sets the sun of the single query; a --grid gives each row's sun_zenith_deg");
    points = ReadGrid(command.grid_path);
  } else {
    // --date: the sun zenith (90 - elevation) of that instant and place (sun_options.h); the
    // azimuth stays the one between the view and the sun.
    std::optional<double> sun_zenith_deg = command.sun_zenith_deg;
    if (HasDate(command.sun)) sun_zenith_deg = 90.0 - SunAtDate(command.sun).position.elevation_deg;
    if (!command.altitude_m || !sun_zenith_deg || !command.view_zenith_deg || !command.azimuth_deg) {
      throw Error("give --grid IN.csv, or all of --altitude, --sun-zenith, --view-zenith and --azimuth");
    }
    SamplePoint point{*command.altitude_m, *sun_zenith_deg, *command.view_zenith_deg,
                      *command.azimuth_deg, ""};
    CheckPoint(point, "");
    points.push_back(point);
  }
  if (!command.out_path.empty()) CheckOutputWritable(command.out_path);
  CheckExtension("--out", command.out_path, ".csv");

  // The moon: by hand in sample's frame (the sun at azimuth 0), or the date's, its azimuth then
  // taken from the sun's.
  std::optional<SampleMoon> moon;
  {
    std::optional<double> julian_day;
    double sun_azimuth_deg = 0.0;
    if (HasDate(command.sun)) {
      const SunAtInstant sun = SunAtDate(command.sun);
      julian_day = sun.julian_day_utc;
      sun_azimuth_deg = sun.position.azimuth_deg;
    }
    if (const std::optional<MoonPosition> place = ResolveMoon(command.moon, command.sun, sun_azimuth_deg, julian_day)) {
      moon = SampleMoon{place->elevation_deg, place->azimuth_deg - sun_azimuth_deg, place->phase_angle_deg,
                        place->distance_km};
    }
  }

  std::string csv;
#ifdef ATMO_HAVE_GL
  if (common.backend == "gl" && common.model == "hillaire") {
    const gl::Context context;
    gl::HillaireGl sky(context, parameters, GlHillaireSettings(common));
    sky.Precompute();
    csv = EvaluatePoints(parameters, points, unit, command.night_sky, moon, HillaireGlEvaluator(sky));
  }
#endif
  if (csv.empty()) {
    const std::unique_ptr<Model> model = CreateModelFor(common, parameters);
    csv = EvaluatePoints(parameters, points, unit, command.night_sky, moon, ModelEvaluator(*model));
  }

  if (command.out_path.empty()) {
    if (std::fwrite(csv.data(), 1, csv.size(), stdout) != csv.size() || std::fflush(stdout) != 0) {
      throw Error("cannot write to standard output");
    }
    return 0;
  }
  WriteFileAtomically(command.out_path, [&](const std::filesystem::path& temporary) {
    std::ofstream out(temporary, std::ios::binary);
    out.write(csv.data(), static_cast<std::streamsize>(csv.size()));
    out.close();
    if (!out) throw Error("write failed");
  });
  return 0;
}

}  // namespace atmo::cli
