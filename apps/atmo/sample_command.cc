// `atmo sample`: the machine-readable model query of DESIGN.md §4.
//
//   IN.csv : altitude_m,sun_zenith_deg,view_zenith_deg,azimuth_deg          (header line first)
//   OUT.csv: altitude_m,sun_zenith_deg,view_zenith_deg,azimuth_deg,wavelength_nm,radiance,
//            transmittance,stderr
//
// One output row per input row and channel, channels in the order of parameters.wavelengths_nm.
// Angles are in degrees; the sun lies at compass azimuth 0 and the view at `azimuth_deg`, so the
// azimuth is the one between the horizontal projections of the view and sun directions.
#include <cmath>
#include <cstdio>
#include <fstream>
#include <map>
#include <string_view>
#include <utility>

#include <glm/glm.hpp>

#include "atmo/error.h"
#include "atmo/image.h"
#include "commands.h"
#include "grid.h"
#include "progress_bar.h"

namespace atmo::cli {

namespace {

constexpr const char* kOutputHeader =
    "altitude_m,sun_zenith_deg,view_zenith_deg,azimuth_deg,wavelength_nm,radiance,transmittance,stderr";

// What one query gives per channel.
struct SampleResult {
  std::vector<double> radiance;
  std::vector<double> transmittance;
  // Standard error of `radiance`: 0 for deterministic models.
  std::vector<double> standard_error;
};

SampleResult Query(const SkyView& sky, const glm::dvec3& view) {
  const std::size_t channels = sky.channel_count();
  SampleResult result{std::vector<double>(channels), std::vector<double>(channels),
                      std::vector<double>(channels, 0.0)};
  sky.RadianceEstimate(view, result.radiance, result.standard_error);
  sky.Transmittance(view, result.transmittance);
  return result;
}

// Evaluates every point, building one SkyView per distinct (altitude, sun zenith) pair, and
// returns the whole CSV text.
std::string EvaluatePoints(const Model& model, const std::vector<SamplePoint>& points) {
  const std::vector<double>& wavelengths_nm = model.parameters().wavelengths_nm;
  std::map<std::pair<double, double>, std::unique_ptr<SkyView>> views;
  std::string csv = std::string(kOutputHeader) + "\n";
  ProgressBar progress("sample");
  for (const SamplePoint& point : points) {
    progress.Update(static_cast<double>(&point - points.data()), static_cast<double>(points.size()));
    const std::string where = point.location.empty() ? "" : point.location + ": ";
    const std::pair<double, double> key(point.altitude_m, point.sun_zenith_deg);
    auto found = views.find(key);
    if (found == views.end()) {
      const glm::dvec3 sun = DirectionFromZenithAzimuth(glm::radians(point.sun_zenith_deg), 0.0);
      try {
        found = views.emplace(key, model.View(point.altitude_m, sun)).first;
      } catch (const Error& error) {
        throw Error(where + error.what());
      }
    }
    const glm::dvec3 view =
        DirectionFromZenithAzimuth(glm::radians(point.view_zenith_deg), glm::radians(point.azimuth_deg));
    const SampleResult result = Query(*found->second, view);
    const std::string inputs = Format("%.10g,%.10g,%.10g,%.10g,", point.altitude_m, point.sun_zenith_deg,
                                      point.view_zenith_deg, point.azimuth_deg);
    for (std::size_t c = 0; c < wavelengths_nm.size(); ++c) {
      csv += inputs;
      csv += Format("%.10g,%.9e,%.9e,%.9e\n", wavelengths_nm[c], result.radiance[c], result.transmittance[c],
                    result.standard_error[c]);
    }
  }
  return csv;
}

}  // namespace

int RunSample(const CommonOptions& common, const SampleCommand& command) {
  CheckBackend(common);
  const AtmosphereParameters parameters = LoadParameters(common);

  std::vector<SamplePoint> points;
  if (!command.grid_path.empty()) {
    points = ReadGrid(command.grid_path);
  } else {
    if (!command.altitude_m || !command.sun_zenith_deg || !command.view_zenith_deg || !command.azimuth_deg) {
      throw Error("give --grid IN.csv, or all of --altitude, --sun-zenith, --view-zenith and --azimuth");
    }
    SamplePoint point{*command.altitude_m, *command.sun_zenith_deg, *command.view_zenith_deg,
                      *command.azimuth_deg, ""};
    CheckPoint(point, "");
    points.push_back(point);
  }
  if (!command.out_path.empty()) CheckOutputWritable(command.out_path);

  const std::unique_ptr<Model> model = CreateModelFor(common, parameters);
  const std::string csv = EvaluatePoints(*model, points);

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
