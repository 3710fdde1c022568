// Grids of query configurations, shared by `atmo sample` and `atmo compare` (docs/design.md §4):
//
//   IN.csv : altitude_m,sun_zenith_deg,view_zenith_deg,azimuth_deg          (header line first)
//
// Angles in degrees; the sun lies at compass azimuth 0 and the view at `azimuth_deg`, so the
// azimuth is the one between the horizontal projections of the view and sun directions.
#pragma once

#include <string>
#include <string_view>
#include <vector>

namespace atmo::cli {

inline constexpr const char* kGridHeader = "altitude_m,sun_zenith_deg,view_zenith_deg,azimuth_deg";

struct SamplePoint {
  double altitude_m = 0.0;
  double sun_zenith_deg = 0.0;
  double view_zenith_deg = 0.0;
  double azimuth_deg = 0.0;
  std::string location;  // "grid.csv:3" for error messages, or "" for the single configuration
};

// Checks the values of one point (finite, zenith angles in [0, 180]); `where` prefixes the
// message ("grid.csv:3: " or ""). Throws atmo::Error.
void CheckPoint(const SamplePoint& point, const std::string& where);

// Reads and checks a whole IN.csv grid before any model work, so a bad file fails fast; errors
// name the file and line. `path` "-" reads standard input. Throws atmo::Error.
std::vector<SamplePoint> ReadGrid(const std::string& path);

// The same for the text of a grid; `path` names it in messages. Throws atmo::Error.
std::vector<SamplePoint> ParseGrid(std::string_view text, const std::string& path);

// The output of `atmo sample` (its default unit), read back: one row per configuration and
// channel, the channels of a configuration on consecutive rows in the order of the atmosphere's
// wavelengths. `atmo compare --against-samples` takes its reference from such a file.
inline constexpr const char* kSamplesHeader =
    "altitude_m,sun_zenith_deg,view_zenith_deg,azimuth_deg,wavelength_nm,radiance,transmittance,stderr";

struct SampleTable {
  std::vector<SamplePoint> points;
  // [point * channels + channel]
  std::vector<double> radiance;
  std::vector<double> transmittance;
  std::vector<double> standard_error;
};

// Reads and checks a whole samples file (a regular file of at most 64 MiB, or "-" for standard
// input): the header, 8 numbers a row, every configuration with exactly the channels
// `wavelengths_nm` (to 1e-6 nm) in order, radiance and standard error finite and >= 0,
// transmittance in [0, 1]. Errors name the file and line. Throws atmo::Error.
SampleTable ReadSamples(const std::string& path, const std::vector<double>& wavelengths_nm);
SampleTable ParseSamples(std::string_view text, const std::string& path, const std::vector<double>& wavelengths_nm);

}  // namespace atmo::cli
