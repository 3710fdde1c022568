// EnergyPlus weather files (include/atmo/weather.h).
#include "atmo/weather.h"

#include <charconv>
#include <cmath>
#include <cstdio>
#include <fstream>
#include <limits>
#include <string_view>

#include "atmo/error.h"
#include "atmo/sun_position.h"
#include "printable.h"

namespace atmo {

namespace {

constexpr double kNaN = std::numeric_limits<double>::quiet_NaN();

std::string_view Trim(std::string_view s) {
  while (!s.empty() && (s.front() == ' ' || s.front() == '\t')) s.remove_prefix(1);
  while (!s.empty() && (s.back() == ' ' || s.back() == '\t' || s.back() == '\r')) s.remove_suffix(1);
  return s;
}

class LineError {
 public:
  LineError(const std::filesystem::path& path, int line) : path_(path), line_(line) {}
  [[noreturn]] void operator()(const std::string& what) const {
    throw Error(Printable(path_.string()) + ":" + std::to_string(line_) + ": " + what);
  }

 private:
  const std::filesystem::path& path_;
  int line_;
};

double Number(std::string_view text, const char* name, const LineError& fail) {
  const std::string_view t = Trim(text);
  double value = 0.0;
  const auto [end, ec] = std::from_chars(t.data(), t.data() + t.size(), value);
  if (t.empty() || ec != std::errc() || end != t.data() + t.size() || !std::isfinite(value)) {
    fail(std::string(name) + " is not a number: '" + Printable(std::string(t)) + "'");
  }
  return value;
}

int Integer(std::string_view text, const char* name, const LineError& fail) {
  const double v = Number(text, name, fail);
  if (v != std::floor(v) || std::abs(v) > 1e6) fail(std::string(name) + " is not an integer: " + FormatNumber(v));
  return static_cast<int>(v);
}

// A value with a missing code: NaN for the code (or above it), else within [low, high].
double Measured(std::string_view text, const char* name, double missing_code, double low, double high,
                const LineError& fail) {
  const double v = Number(text, name, fail);
  if (v >= missing_code) return kNaN;
  if (v < low || v > high) {
    fail(std::string(name) + " " + FormatNumber(v) + " is outside [" + FormatNumber(low) + ", " + FormatNumber(high) + "]");
  }
  return v;
}

bool IsLeap(int year) { return (year % 4 == 0 && year % 100 != 0) || year % 400 == 0; }

}  // namespace

WeatherFile ReadEpw(const std::filesystem::path& path) {
  std::ifstream in(path, std::ios::binary);
  if (!in) throw Error("cannot read the weather file " + Printable(path.string()));
  WeatherFile file;
  file.path = path;
  std::string text;
  int line_number = 0;
  bool in_data = false;
  while (std::getline(in, text)) {
    ++line_number;
    const LineError fail(path, line_number);
    const std::string_view line = Trim(text);
    if (line_number == 1) {
      const std::vector<std::string_view> f = SplitCommas(line);
      if (f.size() < 10 || Trim(f[0]) != "LOCATION") {
        fail("not an EPW file: the first line must be LOCATION,city,state,country,source,WMO,latitude,longitude,"
             "time zone,elevation");
      }
      WeatherLocation& l = file.location;
      l.city = std::string(Trim(f[1]));
      l.region = std::string(Trim(f[2]));
      l.country = std::string(Trim(f[3]));
      l.source = std::string(Trim(f[4]));
      l.wmo = std::string(Trim(f[5]));
      l.latitude_deg = Number(f[6], "the latitude", fail);
      l.longitude_deg = Number(f[7], "the longitude", fail);
      l.time_zone_h = Number(f[8], "the time zone", fail);
      l.elevation_m = Number(f[9], "the elevation", fail);
      if (std::abs(l.latitude_deg) > 90.0) fail("the latitude " + FormatNumber(l.latitude_deg) + " is outside [-90, 90]");
      if (std::abs(l.longitude_deg) > 180.0) fail("the longitude " + FormatNumber(l.longitude_deg) + " is outside [-180, 180]");
      if (std::abs(l.time_zone_h) > 14.0) fail("the time zone " + FormatNumber(l.time_zone_h) + " h is outside [-14, 14]");
      if (l.elevation_m < -500.0 || l.elevation_m > 9000.0) {
        fail("the elevation " + FormatNumber(l.elevation_m) + " m is outside [-500, 9000]");
      }
      continue;
    }
    if (!in_data) {
      if (line.rfind("DATA PERIODS", 0) == 0) in_data = true;
      if (line_number > 8 && !in_data) fail("no DATA PERIODS line in the EPW header");
      continue;
    }
    if (line.empty()) continue;
    const std::vector<std::string_view> f = SplitCommas(line);
    if (f.size() < 19) {
      fail("an EPW row needs at least 19 fields (up to the diffuse horizontal illuminance), got " +
           std::to_string(f.size()));
    }
    WeatherHour h;
    h.line = line_number;
    h.year = Integer(f[0], "the year", fail);
    h.month = Integer(f[1], "the month", fail);
    h.day = Integer(f[2], "the day", fail);
    h.hour = Integer(f[3], "the hour", fail);
    static constexpr int kDays[] = {31, 29, 31, 30, 31, 30, 31, 31, 30, 31, 30, 31};
    if (h.month < 1 || h.month > 12) fail("the month " + std::to_string(h.month) + " does not exist");
    if (h.day < 1 || h.day > kDays[h.month - 1] || (h.month == 2 && h.day == 29 && !IsLeap(h.year))) {
      fail("the date " + std::to_string(h.year) + "-" + std::to_string(h.month) + "-" + std::to_string(h.day) +
           " does not exist");
    }
    if (h.hour < 1 || h.hour > 24) fail("the hour " + std::to_string(h.hour) + " is outside 1..24");
    h.pressure_pa = Measured(f[9], "the pressure (Pa)", 999999.0, 30000.0, 120000.0, fail);
    h.global_horizontal_w_m2 = Measured(f[13], "the global horizontal irradiance", 9999.0, 0.0, 1500.0, fail);
    h.direct_normal_w_m2 = Measured(f[14], "the direct normal irradiance", 9999.0, 0.0, 1500.0, fail);
    h.diffuse_horizontal_w_m2 = Measured(f[15], "the diffuse horizontal irradiance", 9999.0, 0.0, 1500.0, fail);
    h.global_horizontal_lux = Measured(f[16], "the global horizontal illuminance", 999999.0, 0.0, 200000.0, fail);
    h.direct_normal_lux = Measured(f[17], "the direct normal illuminance", 999999.0, 0.0, 200000.0, fail);
    h.diffuse_horizontal_lux = Measured(f[18], "the diffuse horizontal illuminance", 999999.0, 0.0, 200000.0, fail);
    h.precipitable_water_mm = f.size() > 28 ? Measured(f[28], "the precipitable water (mm)", 999.0, 0.0, 200.0, fail) : kNaN;
    h.albedo = f.size() > 32 && !Trim(f[32]).empty() ? Measured(f[32], "the albedo", 999.0, 0.0, 1.0, fail) : kNaN;
    file.hours.push_back(h);
  }
  if (line_number == 0) throw Error(Printable(path.string()) + ": empty file, not an EPW");
  if (file.hours.empty()) throw Error(Printable(path.string()) + ": no hourly rows after the header");
  return file;
}

double MidHourJulianDayUtc(const WeatherLocation& location, const WeatherHour& hour) {
  // Local standard time (h - 1):30 as an ISO date with the zone's offset.
  const double zone_minutes = std::round(location.time_zone_h * 60.0);
  const int offset = static_cast<int>(std::abs(zone_minutes));
  char text[64];
  std::snprintf(text, sizeof text, "%04d-%02d-%02dT%02d:30:00%c%02d:%02d", hour.year, hour.month, hour.day,
                hour.hour - 1, zone_minutes < 0.0 ? '-' : '+', offset / 60, offset % 60);
  return ParseIsoDateTime(text);
}

}  // namespace atmo
