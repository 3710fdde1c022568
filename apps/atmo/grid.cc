// Reading and checking IN.csv grids (grid.h), shared by `atmo sample` and `atmo compare`.
#include "grid.h"

#include <charconv>
#include <cmath>
#include <cstdio>
#include <fstream>
#include <functional>
#include <iostream>
#include <map>
#include <sstream>
#include <string_view>
#include <tuple>
#include <utility>

#include "atmo/error.h"
#include "atmo/image.h"
#include "atmo/parameters.h"

namespace atmo::cli {

namespace {

// What an error quotes of an input line or field: at most 32 bytes, control characters escaped,
// "..." when cut. A grid given a file that is not a grid (`--grid /etc/passwd`) is named by its
// path and line number; its contents are not echoed beyond that excerpt.
std::string Excerpt(std::string_view text) {
  constexpr std::size_t kMax = 32;
  std::string out;
  for (std::size_t i = 0; i < text.size() && i < kMax; ++i) {
    const unsigned char c = static_cast<unsigned char>(text[i]);
    if (c < 0x20 || c == 0x7f) {
      char escaped[8];
      std::snprintf(escaped, sizeof escaped, "\\x%02x", c);
      out += escaped;
    } else {
      out += static_cast<char>(c);
    }
  }
  if (text.size() > kMax) out += "...";
  return out;
}

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

// "%.10g" of a value, for messages.
std::string Number(double value) {
  char text[32];
  std::snprintf(text, sizeof text, "%.10g", value);
  return text;
}

}  // namespace

void CheckPoint(const SamplePoint& point, const std::string& where) {
  const std::pair<const char*, double> values[] = {{"altitude_m", point.altitude_m},
                                                   {"sun_zenith_deg", point.sun_zenith_deg},
                                                   {"view_zenith_deg", point.view_zenith_deg},
                                                   {"azimuth_deg", point.azimuth_deg}};
  for (const auto& [name, value] : values) {
    if (!std::isfinite(value)) throw Error(where + name + " is not a finite number");
  }
  if (!(std::fabs(point.altitude_m) <= kMaxAltitude_m)) {
    throw Error(where + "altitude_m " + Number(point.altitude_m) + " is outside [-1e+11, 1e+11] m");
  }
  for (const auto& [name, value] : {values[1], values[2]}) {
    if (value < 0.0 || value > 180.0) {
      throw Error(where + name + " " + Number(value) + " is outside [0, 180]");
    }
  }
}

// "-": standard input, at most as many bytes as a grid file may have.
std::string ReadStandardInput() {
  std::string text;
  char buffer[65536];
  while (std::cin.read(buffer, sizeof buffer) || std::cin.gcount() > 0) {
    text.append(buffer, static_cast<std::size_t>(std::cin.gcount()));
    if (text.size() > kMaxInputFileBytes) {
      throw Error("the grid on standard input is larger than " + std::to_string(kMaxInputFileBytes >> 20) + " MiB");
    }
  }
  return text;
}

std::vector<SamplePoint> ReadGrid(const std::string& given_path) {
  // A regular file of at most 64 MiB: "cannot read 'PATH': is a directory" (a folder was "an
  // empty file"), a device or FIFO is refused (/dev/zero ended in std::bad_alloc). "-" reads
  // standard input, named "<stdin>" in messages.
  const bool from_stdin = given_path == "-";
  const std::string path = from_stdin ? "<stdin>" : given_path;
  return ParseGrid(from_stdin ? ReadStandardInput() : ReadFileBounded(path), path);
}

namespace {

// The rows of a CSV of numbers after its header line: `row(values, where, line_number)` for each
// non-empty line, `values` of size `columns`. Errors name the file and line.
void ParseNumberRows(std::string_view text, const std::string& path, const char* header, std::size_t columns,
                     const std::function<void(const std::vector<double>&, const std::string&, int)>& row) {
  if (const std::size_t nul = text.find('\0'); nul != std::string::npos) {
    throw Error(path + ": a NUL byte at byte " + std::to_string(nul + 1) + "; a grid is CSV text");
  }
  const std::string count = std::to_string(columns);
  bool header_seen = false;
  int line_number = 0;
  std::size_t start = 0;
  std::vector<double> values(columns);
  while (start < text.size()) {
    std::size_t end = text.find('\n', start);
    if (end == std::string::npos) end = text.size();
    const std::string_view line = Trim(text.substr(start, end - start));
    start = end + 1;
    ++line_number;
    if (line.empty()) continue;
    const std::string where = path + ":" + std::to_string(line_number) + ": ";

    if (!header_seen) {
      const std::vector<std::string_view> names = SplitCommas(line);
      const std::vector<std::string_view> expected = SplitCommas(header);
      if (names != expected) {
        throw Error(where + "expected the header '" + header + "', got '" + Excerpt(line) + "'");
      }
      header_seen = true;
      continue;
    }

    const std::vector<std::string_view> fields = SplitCommas(line);
    if (fields.size() != columns) throw Error(where + "expected " + count + " comma-separated numbers");
    for (std::size_t i = 0; i < columns; ++i) {
      std::string_view field = fields[i];
      if (field.size() > 1 && field.front() == '+') field.remove_prefix(1);  // from_chars takes no '+'

      const char* last = field.data() + field.size();
      const auto [ptr, error] = std::from_chars(field.data(), last, values[i]);
      if (field.empty() || error != std::errc() || ptr != last) {
        if (error == std::errc::result_out_of_range && ptr == last) {
          throw Error(where + "'" + Excerpt(field) + "' is out of range");
        }
        throw Error(where + "expected " + count + " comma-separated numbers, got '" + Excerpt(field) + "'");
      }
    }
    row(values, where, line_number);
  }
  if (!header_seen) {
    throw Error(path + ": expected the header '" + std::string(header) + "', got an empty file");
  }
}

std::string ReadInput(const std::string& given_path) {
  return given_path == "-" ? ReadStandardInput() : ReadFileBounded(given_path);
}

}  // namespace

std::vector<SamplePoint> ParseGrid(std::string_view text, const std::string& path) {
  std::vector<SamplePoint> points;
  ParseNumberRows(text, path, kGridHeader, 4, [&](const std::vector<double>& v, const std::string& where, int line) {
    SamplePoint point{v[0], v[1], v[2], v[3], path + ":" + std::to_string(line)};
    CheckPoint(point, where);
    points.push_back(std::move(point));
  });
  return points;
}

SampleTable ReadSamples(const std::string& given_path, const std::vector<double>& wavelengths_nm) {
  const std::string path = given_path == "-" ? "<stdin>" : given_path;
  return ParseSamples(ReadInput(given_path), path, wavelengths_nm);
}

SampleTable ParseSamples(std::string_view text, const std::string& path, const std::vector<double>& wavelengths_nm) {
  SampleTable table;
  const std::size_t channels = wavelengths_nm.size();
  std::size_t channel = 0;  // of the next row
  std::string first_where;  // of the configuration being read
  // Each configuration once: a repeated one counted twice in every statistic of `compare`.
  std::map<std::tuple<double, double, double, double>, int> seen;
  ParseNumberRows(text, path, kSamplesHeader, 8, [&](const std::vector<double>& v, const std::string& where, int line) {
    const SamplePoint point{v[0], v[1], v[2], v[3], path + ":" + std::to_string(line)};
    CheckPoint(point, where);
    if (channel == 0) {
      const auto [it, inserted] =
          seen.emplace(std::tuple{point.altitude_m, point.sun_zenith_deg, point.view_zenith_deg, point.azimuth_deg}, line);
      if (!inserted) {
        throw Error(where + "the configuration of line " + std::to_string(it->second) +
                    " again: each configuration once (merge repeated reference runs before comparing)");
      }
      table.points.push_back(point);
      first_where = where;
    } else {
      const SamplePoint& open = table.points.back();
      if (point.altitude_m != open.altitude_m || point.sun_zenith_deg != open.sun_zenith_deg ||
          point.view_zenith_deg != open.view_zenith_deg || point.azimuth_deg != open.azimuth_deg) {
        throw Error(where + "a new configuration after " + std::to_string(channel) + " of its " +
                    std::to_string(channels) + " channels (" + std::to_string(channels) +
                    " rows a configuration, one per wavelength)");
      }
    }
    if (!(std::fabs(v[4] - wavelengths_nm[channel]) <= 1e-6)) {
      throw Error(where + "wavelength_nm " + Number(v[4]) + " where the atmosphere's channel " +
                  std::to_string(channel + 1) + " is " + Number(wavelengths_nm[channel]) + " nm");
    }
    if (!(std::isfinite(v[5]) && v[5] >= 0.0)) {
      throw Error(where + "radiance " + Number(v[5]) + " is not finite and >= 0");
    }
    if (!(v[6] >= 0.0 && v[6] <= 1.0)) throw Error(where + "transmittance " + Number(v[6]) + " is outside [0, 1]");
    if (!(std::isfinite(v[7]) && v[7] >= 0.0)) {
      throw Error(where + "stderr " + Number(v[7]) + " is not finite and >= 0");
    }
    table.radiance.push_back(v[5]);
    table.transmittance.push_back(v[6]);
    table.standard_error.push_back(v[7]);
    channel = (channel + 1) % channels;
  });
  if (channel != 0) {
    throw Error(path + ": the last configuration has " + std::to_string(channel) + " of its " +
                std::to_string(channels) + " channels");
  }
  if (table.points.empty()) throw Error(path + ": no configurations after the header");
  return table;
}

}  // namespace atmo::cli
