// Reading and checking IN.csv grids (grid.h), shared by `atmo sample` and `atmo compare`.
#include "grid.h"

#include <charconv>
#include <cmath>
#include <cstdio>
#include <fstream>
#include <iostream>
#include <sstream>
#include <string_view>
#include <utility>

#include "atmo/error.h"
#include "atmo/image.h"
#include "atmo/parameters.h"

namespace atmo::cli {

namespace {

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

std::vector<SamplePoint> ParseGrid(std::string_view text, const std::string& path) {
  if (const std::size_t nul = text.find('\0'); nul != std::string::npos) {
    throw Error(path + ": a NUL byte at byte " + std::to_string(nul + 1) + "; a grid is CSV text");
  }

  std::vector<SamplePoint> points;
  bool header_seen = false;
  int line_number = 0;
  std::size_t start = 0;
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

}  // namespace atmo::cli
