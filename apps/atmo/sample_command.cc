// `atmo sample`: the machine-readable model query of DESIGN.md §4.
//
//   IN.csv : altitude_m,sun_zenith_deg,view_zenith_deg,azimuth_deg          (header line first)
//   OUT.csv: altitude_m,sun_zenith_deg,view_zenith_deg,azimuth_deg,wavelength_nm,radiance,
//            transmittance,stderr
//
// One output row per input row and channel, channels in the order of parameters.wavelengths_nm.
// Angles are in degrees; the sun lies at compass azimuth 0 and the view at `azimuth_deg`, so the
// azimuth is the one between the horizontal projections of the view and sun directions.
#include <charconv>
#include <cmath>
#include <cstdio>
#include <fstream>
#include <map>
#include <sstream>
#include <string_view>
#include <utility>

#include <glm/glm.hpp>

#include "atmo/error.h"
#include "atmo/image.h"
#include "commands.h"

namespace atmo::cli {

namespace {

constexpr const char* kGridHeader = "altitude_m,sun_zenith_deg,view_zenith_deg,azimuth_deg";
constexpr const char* kOutputHeader =
    "altitude_m,sun_zenith_deg,view_zenith_deg,azimuth_deg,wavelength_nm,radiance,transmittance,stderr";

struct SamplePoint {
  double altitude_m = 0.0;
  double sun_zenith_deg = 0.0;
  double view_zenith_deg = 0.0;
  double azimuth_deg = 0.0;
  std::string location;  // "grid.csv:3" for error messages, or "" for the single configuration
};

std::string_view Trim(std::string_view text) {
  const auto is_space = [](char c) { return c == ' ' || c == '\t' || c == '\r' || c == '\n'; };
  while (!text.empty() && is_space(text.front())) text.remove_prefix(1);
  while (!text.empty() && is_space(text.back())) text.remove_suffix(1);
  return text;
}

std::vector<std::string_view> SplitCommas(std::string_view line) {
  std::vector<std::string_view> fields;
  std::size_t start = 0;
  while (true) {
    const std::size_t comma = line.find(',', start);
    fields.push_back(Trim(line.substr(start, comma == std::string_view::npos ? line.npos : comma - start)));
    if (comma == std::string_view::npos) break;
    start = comma + 1;
  }
  return fields;
}

// Checks the values of one point; `where` prefixes the message ("grid.csv:3: " or "").
void CheckPoint(const SamplePoint& point, const std::string& where) {
  const std::pair<const char*, double> values[] = {{"altitude_m", point.altitude_m},
                                                   {"sun_zenith_deg", point.sun_zenith_deg},
                                                   {"view_zenith_deg", point.view_zenith_deg},
                                                   {"azimuth_deg", point.azimuth_deg}};
  for (const auto& [name, value] : values) {
    if (!std::isfinite(value)) throw Error(where + name + " is not a finite number");
  }
  for (const auto& [name, value] : {values[1], values[2]}) {
    if (value < 0.0 || value > 180.0) {
      throw Error(where + name + " " + Format("%.10g", value) + " is outside [0, 180]");
    }
  }
}

// Reads and checks the whole grid before any model work, so a bad file fails fast.
std::vector<SamplePoint> ReadGrid(const std::string& path) {
  std::ifstream file(path, std::ios::binary);
  if (!file) throw Error("cannot read '" + path + "'");
  std::stringstream buffer;
  buffer << file.rdbuf();
  if (file.bad()) throw Error("cannot read '" + path + "'");
  const std::string text = buffer.str();

  std::vector<SamplePoint> points;
  bool header_seen = false;
  int line_number = 0;
  std::size_t start = 0;
  while (start < text.size()) {
    std::size_t end = text.find('\n', start);
    if (end == std::string::npos) end = text.size();
    const std::string_view line = Trim(std::string_view(text).substr(start, end - start));
    start = end + 1;
    ++line_number;
    if (line.empty()) continue;
    const std::string where = path + ":" + std::to_string(line_number) + ": ";

    if (!header_seen) {
      const std::vector<std::string_view> names = SplitCommas(line);
      const std::vector<std::string_view> expected = SplitCommas(kGridHeader);
      if (names != expected) {
        throw Error(where + "expected the header '" + kGridHeader + "', got '" + std::string(line) + "'");
      }
      header_seen = true;
      continue;
    }

    const std::vector<std::string_view> fields = SplitCommas(line);
    if (fields.size() != 4) throw Error(where + "expected 4 comma-separated numbers");
    double values[4];
    for (int i = 0; i < 4; ++i) {
      std::string_view field = fields[i];
      if (field.size() > 1 && field.front() == '+') field.remove_prefix(1);  // from_chars takes no '+'

      const char* last = field.data() + field.size();
      const auto [ptr, error] = std::from_chars(field.data(), last, values[i]);
      if (field.empty() || error != std::errc() || ptr != last) {
        if (error == std::errc::result_out_of_range && ptr == last) {
          throw Error(where + "'" + std::string(field) + "' is out of range");
        }
        throw Error(where + "expected 4 comma-separated numbers, got '" + std::string(field) + "'");
      }
    }
    SamplePoint point{values[0], values[1], values[2], values[3], path + ":" + std::to_string(line_number)};
    CheckPoint(point, where);
    points.push_back(std::move(point));
  }
  if (!header_seen) {
    throw Error(path + ": expected the header '" + std::string(kGridHeader) + "', got an empty file");
  }
  return points;
}

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
  for (const SamplePoint& point : points) {
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
