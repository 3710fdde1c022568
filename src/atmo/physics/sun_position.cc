// The sun's position from date and place (include/atmo/sun_position.h), through libnova.
#include "atmo/sun_position.h"

#include <algorithm>
#include <cctype>
#include <cmath>
#include <cstdio>
#include <mutex>
#include <numbers>
#include <string>

#include <libnova/dynamical_time.h>
#include <libnova/earth.h>
#include <libnova/julian_day.h>
#include <libnova/lunar.h>
#include <libnova/ln_types.h>
#include <libnova/nutation.h>
#include <libnova/parallax.h>

#include "atmo/error.h"
#include "atmo/moon.h"
#include "atmo/night_sky.h"

namespace atmo {

namespace {

constexpr double kSecondsPerDay = 86400.0;
constexpr double kDegToRad = M_PI / 180.0;
// Julian days of 0000-01-01T00:00Z (Julian calendar) and 10000-01-01T00:00Z: the years
// ParseIsoDateTime reads, and the span ComputeSunPosition accepts.
constexpr double kFirstJulianDay = 1721057.5;
constexpr double kEndJulianDay = 5373484.5;

// The calendar of ln_get_julian_day (Meeus ch. 7): Julian before 1582-10-15, Gregorian from then on.
bool IsLeapYear(int year) { return year % 4 == 0 && (year < 1582 || year % 100 != 0 || year % 400 == 0); }

int DaysInMonth(int year, int month) {
  static constexpr int kDays[] = {31, 28, 31, 30, 31, 30, 31, 31, 30, 31, 30, 31};
  return month == 2 && IsLeapYear(year) ? 29 : kDays[month - 1];
}

// A cursor over the text with the few reads ISO 8601 needs.
class Reader {
 public:
  explicit Reader(std::string_view text) : text_(text) {}
  bool done() const { return at_ == text_.size(); }
  char peek() const { return done() ? '\0' : text_[at_]; }
  bool Take(char c) {
    if (peek() != c) return false;
    ++at_;
    return true;
  }
  // Exactly `digits` decimal digits into `value`.
  bool Digits(int digits, int& value) {
    value = 0;
    for (int i = 0; i < digits; ++i) {
      if (!std::isdigit(static_cast<unsigned char>(peek()))) return false;
      value = value * 10 + (text_[at_++] - '0');
    }
    return true;
  }
  // One or more digits read as the fraction after a decimal point.
  bool Fraction(double& value) {
    value = 0.0;
    double scale = 0.1;
    const std::size_t start = at_;
    while (std::isdigit(static_cast<unsigned char>(peek()))) {
      value += scale * (text_[at_++] - '0');
      scale *= 0.1;
    }
    return at_ > start;
  }

 private:
  std::string_view text_;
  std::size_t at_ = 0;
};

// The angle in [0, 360).
double Wrap360(double deg) {
  const double wrapped = std::fmod(deg, 360.0);
  return wrapped < 0.0 ? wrapped + 360.0 : wrapped;
}

// Saemundsson's refraction (Meeus eq. 16.4; NREL SPA eq. 42) in degrees, for the true elevation
// `elevation_deg`: R = 1.02' / tan(h + 10.3 / (h + 5.11)) at 1010 mbar and 10 C, scaled by the
// density of the air, pressure / 1010 x 283 / (273 + temperature).
double RefractionDeg(double elevation_deg, double pressure_mbar, double temperature_c) {
  const double arcmin = 1.02 / std::tan(kDegToRad * (elevation_deg + 10.3 / (elevation_deg + 5.11)));
  return (pressure_mbar / 1010.0) * (283.0 / (273.0 + temperature_c)) * arcmin / 60.0;
}

// 'text', for error messages (appended piecewise: GCC 12 warns, wrongly, on "'" + std::string).
std::string Quoted(std::string_view text) {
  std::string quoted = "'";
  quoted.append(text);
  quoted += '\'';
  return quoted;
}

// Julian centuries of 36525 days from J2000.0 (JD 2451545.0).
double CenturiesSinceJ2000(double julian_day) { return (julian_day - 2451545.0) / 36525.0; }

// Precesses an ecliptic longitude from the ecliptic and equinox of J2000.0 to those of date
// `jde` (Meeus eqs. 21.5 with T = 0, and 21.7, for a point on the ecliptic: the latitude it
// gains, under 0.002" for the sun, does not enter).
double PrecessEclipticLongitudeFromJ2000Deg(double jde, double longitude_deg) {
  constexpr double kArcsec = kDegToRad / 3600.0;
  const double t = CenturiesSinceJ2000(jde);
  const double eta = (47.0029 * t - 0.03302 * t * t + 0.000060 * t * t * t) * kArcsec;
  const double pi = 174.876384 * kDegToRad + (-869.8089 * t + 0.03536 * t * t) * kArcsec;
  const double p = (5029.0966 * t + 1.11113 * t * t - 0.000006 * t * t * t) * kArcsec;
  const double lambda = kDegToRad * longitude_deg;
  const double a = std::cos(eta) * std::cos(pi - lambda);
  const double b = std::sin(pi - lambda);
  return Wrap360((p + pi - std::atan2(b, a)) / kDegToRad);
}

// The Earth's heliocentric longitude on the ecliptic and equinox of date, from libnova's
// `libnova_longitude_deg` (ln_get_earth_helio_coords at `jde`).
//
// libnova 0.16's Earth series are referred to the fixed ecliptic and equinox of J2000 (its L1
// series starts with VSOP87B's 6283.07584999 rad per millennium, not VSOP87D's 6283.31966747:
// the difference is the general precession, 5029" a century), yet ln_get_solar_equ_coords uses
// them as of date: 0.10 degrees off in 1992, 0.36 in 2026. Which frame this libnova uses is
// checked once, against Meeus Example 25.b (1992 October 13.0 TD, JDE 2448908.5: the sun's
// geometric longitude of date, FK5, is 199d54'26.18", so the Earth's is 19.907272 degrees), and
// the longitude precessed to the equinox of date when needed (Meeus ch. 21).
double EarthLongitudeOfDateDeg(double jde, double libnova_longitude_deg) {
  static const bool needs_precession = [] {
    constexpr double kMeeusJde = 2448908.5;
    constexpr double kMeeusLongitudeDeg = 199.0 + 54.0 / 60.0 + 26.18 / 3600.0 - 180.0;
    ln_helio_posn earth{};
    ln_get_earth_helio_coords(kMeeusJde, &earth);
    if (std::abs(earth.L - kMeeusLongitudeDeg) < 0.001) return false;
    if (std::abs(PrecessEclipticLongitudeFromJ2000Deg(kMeeusJde, earth.L) - kMeeusLongitudeDeg) < 0.001) return true;
    throw Error("libnova's Earth longitude disagrees with Meeus Example 25.b in either frame");
  }();
  return needs_precession ? PrecessEclipticLongitudeFromJ2000Deg(jde, libnova_longitude_deg) : libnova_longitude_deg;
}

// The sun's geocentric ecliptic latitude, -B of the Earth, from the VSOP87D terms of Meeus's
// Table 32.A (B0: 5 terms, B1: 2; good to a few 0.01"). libnova 0.16's latitude is not used: it
// drifts by 45" a century from VSOP87D's (the ecliptic's own precession, 47" a century), and
// the sun's latitude never exceeds 1.2".
double SunLatitudeDeg(double jde) {
  const double tau = (jde - 2451545.0) / 365250.0;  // Julian millennia
  const double b0 = 280.0 * std::cos(3.199 + 84334.662 * tau) + 102.0 * std::cos(5.422 + 5507.553 * tau) +
                    80.0 * std::cos(3.88 + 5223.69 * tau) + 44.0 * std::cos(3.70 + 2352.87 * tau) +
                    32.0 * std::cos(4.00 + 1577.34 * tau);
  const double b1 = 9.0 * std::cos(3.90 + 5507.55 * tau) + 6.0 * std::cos(1.73 + 5223.69 * tau);
  return -(b0 + b1 * tau) * 1e-8 / kDegToRad;
}

// The nutation at exactly `jde`. ln_get_nutation keeps the last one it computed and returns it
// again for any instant within a fraction of a day of it, so its answer depends on the call
// before (by up to 0.01", 3e-6 degrees); asking first for an instant days away makes it compute
// this one. The caller holds the libnova lock.
ln_nutation NutationAt(double jde) {
  ln_nutation nutation{};
  ln_get_nutation(jde + 10.0, &nutation);
  ln_get_nutation(jde, &nutation);
  return nutation;
}

// The Greenwich apparent sidereal time in degrees at `julian_day_utc` (UT): the mean (Meeus eq.
// 12.4) plus the equation of the equinoxes, delta psi cos(epsilon) (Meeus ch. 12). (libnova's
// ln_get_apparent_sidereal_time leaves out the cos(epsilon), 0.0003 degrees, and
// ln_get_hrz_from_equ uses the mean sidereal time.)
double ApparentSiderealTimeDeg(double julian_day_utc, const ln_nutation& nutation) {
  const double epsilon = kDegToRad * (nutation.ecliptic + nutation.obliquity);
  return Wrap360(GreenwichMeanSiderealTimeDeg(julian_day_utc) + nutation.longitude * std::cos(epsilon));
}

// libnova keeps its last Earth position and nutation in globals (caches without a lock): one
// caller at a time, and each result independent of the calls before (NutationAt).
std::mutex& LibnovaMutex() {
  static std::mutex mutex;
  return mutex;
}

// The checks of every ephemeris here: an instant in the years 0000..9999 and a place on the Earth.
void CheckInstantAndPlace(double julian_day_utc, double latitude_deg, double longitude_deg) {
  if (!std::isfinite(julian_day_utc) || julian_day_utc < kFirstJulianDay || julian_day_utc >= kEndJulianDay) {
    throw Error("the sun's position needs an instant in the years 0000..9999, got Julian day " +
                std::to_string(julian_day_utc));
  }
  if (!(latitude_deg >= -90.0 && latitude_deg <= 90.0)) {
    throw Error("latitude " + std::to_string(latitude_deg) + " is outside [-90, 90] degrees");
  }
  if (!(longitude_deg >= -180.0 && longitude_deg < 360.0)) {
    throw Error("longitude " + std::to_string(longitude_deg) + " is outside [-180, 360) degrees (east positive)");
  }
}

// libnova's observer: east-positive longitudes in -180..180 (the caller's 180..360 are -180..0).
ln_lnlat_posn Observer(double latitude_deg, double longitude_deg) {
  ln_lnlat_posn observer{};
  observer.lng = longitude_deg >= 180.0 ? longitude_deg - 360.0 : longitude_deg;
  observer.lat = latitude_deg;
  return observer;
}

// Topocentric place: the geocentric one shifted by the parallax of an observer on the ellipsoid
// (Meeus ch. 40) for a body `distance_au` away.
ln_equ_posn Topocentric(const ln_equ_posn& geocentric, double distance_au, const ln_lnlat_posn& observer,
                        double height_m, double julian_day_utc) {
  ln_equ_posn place = geocentric;
  ln_lnlat_posn where = observer;  // libnova takes non-const pointers
  ln_equ_posn parallax{};
  ln_get_parallax(&place, distance_au, &where, height_m, julian_day_utc, &parallax);
  return {geocentric.ra + parallax.ra, geocentric.dec + parallax.dec};
}

struct Horizontal {
  double sin_elevation;
  double elevation_deg;
  double azimuth_deg;  // compass: from the north towards the east
};

// Horizontal coordinates of a place of date from the local hour angle H = apparent sidereal time +
// longitude - ra (Meeus eqs. 13.5, 13.6); atan2 gives the azimuth from the south towards the west,
// + 180.
Horizontal ToHorizontal(const ln_equ_posn& place, const ln_lnlat_posn& observer, double julian_day_utc,
                        const ln_nutation& nutation) {
  const double hour_angle = kDegToRad * (ApparentSiderealTimeDeg(julian_day_utc, nutation) + observer.lng - place.ra);
  const double phi = kDegToRad * observer.lat, delta = kDegToRad * place.dec;
  Horizontal h;
  h.sin_elevation = std::sin(phi) * std::sin(delta) + std::cos(phi) * std::cos(delta) * std::cos(hour_angle);
  const double azimuth_from_south =
      std::atan2(std::sin(hour_angle), std::cos(hour_angle) * std::sin(phi) - std::tan(delta) * std::cos(phi));
  h.elevation_deg = std::asin(std::clamp(h.sin_elevation, -1.0, 1.0)) / kDegToRad;
  h.azimuth_deg = Wrap360(azimuth_from_south / kDegToRad + 180.0);
  return h;
}

}  // namespace

double GreenwichMeanSiderealTimeDeg(double julian_day_utc) {
  const double t = CenturiesSinceJ2000(julian_day_utc);
  return Wrap360(280.46061837 + 360.98564736629 * (julian_day_utc - 2451545.0) + 0.000387933 * t * t -
                 t * t * t / 38710000.0);
}

double DeltaTSeconds(double julian_day_utc) {
  if (!std::isfinite(julian_day_utc)) throw Error("Delta T needs a finite Julian day");
  const double year = 2000.0 + (julian_day_utc - 2451545.0) / 365.25;
  // Before 2000: libnova's table of measured values (ln_get_dynamical_time_diff, Meeus ch. 10, and
  // its long-term formulas before 1620). After 2000 libnova extrapolates, too fast, and jumps by 45 s
  // in mid-2010; there Espenak and Meeus's polynomials (Five Millennium Canon of Solar Eclipses,
  // NASA/TP-2006-214141, "Polynomial expressions for Delta T") take over, continuous with it.
  if (year < 2000.0) return ln_get_dynamical_time_diff(julian_day_utc);
  if (year < 2005.0) {
    const double t = year - 2000.0;
    return 63.86 + 0.3345 * t - 0.060374 * t * t + 0.0017275 * t * t * t + 0.000651814 * t * t * t * t +
           0.00002373599 * t * t * t * t * t;
  }
  if (year < 2050.0) {
    const double t = year - 2000.0;
    return 62.92 + 0.32217 * t + 0.005589 * t * t;
  }
  const double u = (year - 1820.0) / 100.0;
  if (year < 2150.0) return -20.0 + 32.0 * u * u - 0.5628 * (2150.0 - year);
  return -20.0 + 32.0 * u * u;
}

double ParseIsoDateTime(std::string_view text) {
  const std::string quoted = Quoted(text);
  const auto malformed = [&](const char* expected) {
    return Error("date " + quoted + " is not ISO 8601 " + expected +
                 " (expected e.g. 2026-06-21T12:00+02:00, 2026-06-21T10:00:00Z)");
  };
  Reader in(text);
  int year = 0, month = 0, day = 0, hour = 0, minute = 0, second = 0;
  double fraction = 0.0;
  if (!in.Digits(4, year) || !in.Take('-') || !in.Digits(2, month) || !in.Take('-') || !in.Digits(2, day)) {
    throw malformed("YYYY-MM-DD");
  }
  if (!(in.Take('T') || in.Take('t') || in.Take(' '))) throw malformed("date-time: a T and the time must follow the date");
  if (!in.Digits(2, hour) || !in.Take(':') || !in.Digits(2, minute)) throw malformed("time HH:MM");
  if (in.Take(':')) {
    if (!in.Digits(2, second)) throw malformed("seconds :SS");
    if ((in.Take('.') || in.Take(',')) && !in.Fraction(fraction)) throw malformed("fraction of a second");
  }
  int zone_minutes = 0;
  if (in.Take('Z') || in.Take('z')) {
  } else if (in.peek() == '+' || in.peek() == '-') {
    const int sign = in.Take('-') ? -1 : (in.Take('+'), 1);
    int zone_hour = 0, zone_minute = 0;
    if (!in.Digits(2, zone_hour)) throw malformed("zone +HH:MM");
    if (!in.done()) {
      in.Take(':');
      if (!in.Digits(2, zone_minute)) throw malformed("zone +HH:MM");
    }
    if (zone_hour > 18 || zone_minute > 59 || zone_hour * 60 + zone_minute > 18 * 60) {
      throw Error("date " + quoted + " has a zone offset outside -18:00..+18:00");
    }
    zone_minutes = sign * (zone_hour * 60 + zone_minute);
  } else if (in.done()) {
    throw Error("date " + quoted + " has no zone: add Z (UTC) or an offset such as +02:00");
  } else {
    throw malformed("date-time");
  }
  if (!in.done()) throw malformed("date-time: unexpected text after the zone");

  const auto out_of_range = [&](const char* field) { return Error("date " + quoted + " has " + field + " out of range"); };
  if (month < 1 || month > 12) throw out_of_range("the month");
  if (day < 1 || day > DaysInMonth(year, month)) throw out_of_range("the day");
  if (hour > 23) throw out_of_range("the hour");
  if (minute > 59) throw out_of_range("the minute");
  if (second > 59) throw out_of_range("the second");

  ln_date date{};
  date.years = year;
  date.months = month;
  date.days = day;
  date.hours = 0;
  date.minutes = 0;
  date.seconds = 0.0;
  // Midnight from libnova, the time of day added here in seconds: whole days are exact in a double.
  const double seconds_of_day = hour * 3600.0 + minute * 60.0 + second + fraction - zone_minutes * 60.0;
  return ln_get_julian_day(&date) + seconds_of_day / kSecondsPerDay;
}

std::string FormatIsoDateTimeUtc(double julian_day_utc) {
  if (!std::isfinite(julian_day_utc)) throw Error("cannot format a non-finite Julian day");
  // Split at midnight, then count milliseconds of the day, so that rounding carries into the date.
  const double midnight = std::floor(julian_day_utc - 0.5) + 0.5;
  long long ms = std::llround((julian_day_utc - midnight) * kSecondsPerDay * 1000.0);
  double day_start = midnight;
  if (ms >= 86400000LL) {
    ms -= 86400000LL;
    day_start += 1.0;
  }
  ln_date date{};
  ln_get_date(day_start + 0.25, &date);  // noon-side of midnight: no rounding at the boundary
  const int hour = static_cast<int>(ms / 3600000);
  const int minute = static_cast<int>(ms / 60000 % 60);
  const int second = static_cast<int>(ms / 1000 % 60);
  const int millisecond = static_cast<int>(ms % 1000);
  char text[64];
  if (millisecond == 0) {
    std::snprintf(text, sizeof text, "%04d-%02d-%02dT%02d:%02d:%02dZ", date.years, date.months, date.days, hour,
                  minute, second);
  } else {
    std::snprintf(text, sizeof text, "%04d-%02d-%02dT%02d:%02d:%02d.%03dZ", date.years, date.months, date.days, hour,
                  minute, second, millisecond);
  }
  return text;
}

double ParseDurationS(std::string_view text) {
  const std::string quoted = Quoted(text);
  const auto invalid = [&] {
    return Error("duration " + quoted + " is not NUMBER UNIT parts with units d, h, min, s (e.g. 10min, 1h30min, 2d)");
  };
  if (text.empty()) throw invalid();
  double total_s = 0.0;
  std::size_t at = 0;
  while (at < text.size()) {
    const std::size_t number_start = at;
    while (at < text.size() && (std::isdigit(static_cast<unsigned char>(text[at])) || text[at] == '.')) ++at;
    if (at == number_start) throw invalid();
    const std::string number(text.substr(number_start, at - number_start));
    char* end = nullptr;
    const double value = std::strtod(number.c_str(), &end);
    if (end != number.c_str() + number.size()) throw invalid();
    const std::size_t unit_start = at;
    while (at < text.size() && std::isalpha(static_cast<unsigned char>(text[at]))) ++at;
    const std::string_view unit = text.substr(unit_start, at - unit_start);
    double unit_s = 0.0;
    if (unit == "d") {
      unit_s = kSecondsPerDay;
    } else if (unit == "h") {
      unit_s = 3600.0;
    } else if (unit == "min") {
      unit_s = 60.0;
    } else if (unit == "s") {
      unit_s = 1.0;
    } else {
      throw invalid();
    }
    total_s += value * unit_s;
  }
  if (!(total_s > 0.0) || !std::isfinite(total_s)) throw Error("duration " + quoted + " must be positive and finite");
  return total_s;
}

SunPosition ComputeSunPosition(double julian_day_utc, double latitude_deg, double longitude_deg,
                               const SunPositionOptions& options) {
  CheckInstantAndPlace(julian_day_utc, latitude_deg, longitude_deg);
  if (!std::isfinite(options.pressure_mbar) || options.pressure_mbar < 0.0 || !std::isfinite(options.temperature_c) ||
      options.temperature_c <= -273.0 || !std::isfinite(options.observer_height_m)) {
    throw Error("the sun's position needs a finite pressure >= 0, temperature > -273 C and observer height");
  }

  const std::lock_guard<std::mutex> lock(LibnovaMutex());

  // The ephemeris runs on Terrestrial Time: JDE = JD(UT) + Delta T.
  const double jde = julian_day_utc + DeltaTSeconds(julian_day_utc) / kSecondsPerDay;
  ln_helio_posn earth{};
  ln_get_earth_helio_coords(jde, &earth);

  // The geometric sun, seen from the Earth's centre: the Earth's heliocentric longitude + 180
  // (libnova's, brought to the equinox of date, see EarthLongitudeOfDateDeg) and latitude (Meeus's
  // series, see SunLatitudeDeg).
  const double theta_deg = EarthLongitudeOfDateDeg(jde, earth.L) + 180.0;
  const double beta_deg = SunLatitudeDeg(jde);
  // Apparent: nutation in longitude, and the aberration of light -20.4898" / R (Meeus eq. 25.10).
  const ln_nutation nutation = NutationAt(jde);
  const double lambda_deg = theta_deg + nutation.longitude - 20.4898 / 3600.0 / earth.R;
  const double epsilon_deg = nutation.ecliptic + nutation.obliquity;  // the true obliquity
  // Ecliptic to equatorial (Meeus eqs. 13.3, 13.4).
  const double lambda = kDegToRad * lambda_deg, beta = kDegToRad * beta_deg, epsilon = kDegToRad * epsilon_deg;
  ln_equ_posn geocentric{};
  geocentric.ra = Wrap360(
      std::atan2(std::sin(lambda) * std::cos(epsilon) - std::tan(beta) * std::sin(epsilon), std::cos(lambda)) /
      kDegToRad);
  geocentric.dec =
      std::asin(std::sin(beta) * std::cos(epsilon) + std::cos(beta) * std::sin(epsilon) * std::sin(lambda)) /
      kDegToRad;

  // Topocentric (the solar parallax is at most 8.8"), then horizontal.
  const ln_lnlat_posn observer = Observer(latitude_deg, longitude_deg);
  const Horizontal horizontal =
      ToHorizontal(Topocentric(geocentric, earth.R, observer, options.observer_height_m, julian_day_utc), observer,
                   julian_day_utc, nutation);

  SunPosition sun;
  sun.geometric_elevation_deg = horizontal.elevation_deg;
  sun.elevation_deg = sun.geometric_elevation_deg;
  sun.azimuth_deg = horizontal.azimuth_deg;
  sun.right_ascension_deg = geocentric.ra;
  sun.declination_deg = geocentric.dec;
  sun.distance_au = earth.R;
  // The sun's upper limb is above the apparent horizon while its centre's true elevation is above
  // -(semi-diameter 0.26667 + horizon refraction 0.5667) degrees (SPA, eq. 43).
  if (options.refraction && sun.geometric_elevation_deg >= -(0.26667 + 0.5667)) {
    sun.elevation_deg += RefractionDeg(sun.geometric_elevation_deg, options.pressure_mbar, options.temperature_c);
  }
  return sun;
}

}  // namespace atmo

namespace atmo {

glm::dvec3 EclipticPoleDirection(double julian_day_utc, double latitude_deg, double longitude_deg) {
  CheckInstantAndPlace(julian_day_utc, latitude_deg, longitude_deg);
  const std::lock_guard<std::mutex> lock(LibnovaMutex());
  const double jde = julian_day_utc + DeltaTSeconds(julian_day_utc) / kSecondsPerDay;
  const ln_nutation nutation = NutationAt(jde);
  // The ecliptic's north pole is at right ascension 270 degrees and declination 90 - epsilon
  // (true equator and equinox of date), placed as the sun is.
  const double epsilon_deg = nutation.ecliptic + nutation.obliquity;
  const Horizontal h = ToHorizontal({270.0, 90.0 - epsilon_deg}, Observer(latitude_deg, longitude_deg),
                                    julian_day_utc, nutation);
  const double elevation = kDegToRad * h.elevation_deg, azimuth = kDegToRad * h.azimuth_deg;
  return glm::dvec3(std::sin(azimuth) * std::cos(elevation), std::cos(azimuth) * std::cos(elevation),
                    std::sin(elevation));
}

}  // namespace atmo

namespace atmo {

MoonPosition ComputeMoonPosition(double julian_day_utc, double latitude_deg, double longitude_deg) {
  CheckInstantAndPlace(julian_day_utc, latitude_deg, longitude_deg);
  const std::lock_guard<std::mutex> lock(LibnovaMutex());
  const double jde = julian_day_utc + DeltaTSeconds(julian_day_utc) / kSecondsPerDay;
  // Geocentric apparent place (ELP 2000-82, Meeus ch. 47; libnova's series take Terrestrial Time).
  ln_equ_posn geocentric{};
  ln_get_lunar_equ_coords(jde, &geocentric);
  MoonPosition moon;
  const double geocentric_km = ln_get_lunar_earth_dist(jde);
  moon.phase_angle_deg = ln_get_lunar_phase(jde);
  // Topocentric (the observer's parallax is up to a degree for the moon), then horizontal.
  const ln_lnlat_posn observer = Observer(latitude_deg, longitude_deg);
  const Horizontal h = ToHorizontal(Topocentric(geocentric, geocentric_km / 149597870.7, observer, 0.0, julian_day_utc),
                                    observer, julian_day_utc, NutationAt(jde));
  moon.elevation_deg = h.elevation_deg;
  moon.azimuth_deg = h.azimuth_deg;
  // From the observer: the geocentric distance less the observer's offset towards the moon
  // (Earth radius times the sine of the elevation, to first order).
  moon.distance_km = geocentric_km - 6371.0 * std::clamp(h.sin_elevation, -1.0, 1.0);
  return moon;
}

}  // namespace atmo
