// Weather files: EnergyPlus EPW (the hourly files daylighting and energy tools read), for skies
// calibrated to each hour's measured light (docs/daylighting.md).
//
// To use it:
//   atmo::WeatherFile epw = atmo::ReadEpw("site.epw");
//   for (const atmo::WeatherHour& h : epw.hours) {
//     double jd = atmo::MidHourJulianDayUtc(epw.location, h);   // the sun at the hour's middle
//     ... h.direct_normal_lux, h.diffuse_horizontal_lux ...
//   }
//
// The EPW format (EnergyPlus "Auxiliary Programs", Weather Converter, "EnergyPlus Weather File
// (EPW) Data Dictionary"): eight header lines, the first `LOCATION,city,state,country,source,WMO,
// latitude,longitude,time zone,elevation` (north and east positive, the zone in hours from UTC,
// metres), then one comma-separated line per hour: year, month, day, hour (1-24, the hour ending
// then in local standard time), minute, data source flags, then the weather fields in the
// dictionary's order; this reader uses those named in WeatherHour. Missing values carry the
// dictionary's codes (9999 for irradiance, 999999 for illuminance) and are read as NaN.
#pragma once

#include <filesystem>
#include <string>
#include <vector>

namespace atmo {

struct WeatherLocation {
  std::string city;
  std::string region;
  std::string country;
  std::string source;
  std::string wmo;
  double latitude_deg = 0.0;   // north positive
  double longitude_deg = 0.0;  // east positive
  double time_zone_h = 0.0;    // local standard time minus UTC
  double elevation_m = 0.0;
};

struct WeatherHour {
  int line = 0;  // in the file, from 1
  int year = 0;
  int month = 0;
  int day = 0;
  int hour = 0;  // 1..24: the hour ending at this time
  // W m^-2 (the EPW's Wh m^-2 over the hour) and lux; NaN where the file has its missing code.
  double global_horizontal_w_m2 = 0.0;
  double direct_normal_w_m2 = 0.0;
  double diffuse_horizontal_w_m2 = 0.0;
  double global_horizontal_lux = 0.0;
  double direct_normal_lux = 0.0;
  double diffuse_horizontal_lux = 0.0;
  double pressure_pa = 0.0;
  double precipitable_water_mm = 0.0;  // NaN when missing
  double albedo = 0.0;                 // NaN when missing
};

struct WeatherFile {
  std::filesystem::path path;
  WeatherLocation location;
  std::vector<WeatherHour> hours;
};

// Reads an EPW file. Throws atmo::Error with one line `FILE:LINE: what` for a missing or unreadable
// file, a malformed header, a row with too few fields or a non-number where a number belongs, a
// date or hour that does not exist, and a value outside its physical range (irradiance outside
// [0, 1500] W m^-2, illuminance outside [0, 200000] lux, pressure outside [30000, 120000] Pa), the
// missing codes excepted.
WeatherFile ReadEpw(const std::filesystem::path& path);

// The Julian day (UTC) of the middle of the hour: hour h covers (h - 1, h] in local standard time.
double MidHourJulianDayUtc(const WeatherLocation& location, const WeatherHour& hour);

}  // namespace atmo
