// The sun's place in the sky from a date, a time and a place on the Earth (libnova, after Meeus,
// *Astronomical Algorithms*, 2nd ed. 1998), and the ISO 8601 and duration text that gives them.
//
// To use it:
//   const double jd = atmo::ParseIsoDateTime("2026-06-21T12:00+02:00");   // UTC Julian day
//   const atmo::SunPosition sun = atmo::ComputeSunPosition(jd, 46.5, 7.9); // latitude, longitude (east +)
//   settings.sun_elevation_deg = sun.elevation_deg;
//   settings.sun_azimuth_deg = sun.azimuth_deg;                            // compass: 0 north, 90 east
//   const double step_s = atmo::ParseDurationS("1h30min");                 // 5400
//
// Time scales. Instants are UTC Julian days (days since -4712-01-01 12:00, Julian calendar before
// 1582-10-15 and Gregorian from then on, as ln_get_julian_day and Meeus ch. 7), treated as UT1: UTC
// never differs from UT1 by more than 0.9 s, in which the sun moves 0.004 degrees along its daily
// circle. The sun's ephemeris (VSOP87) wants Terrestrial Time: ComputeSunPosition adds Delta T =
// TT - UT for it (DeltaTSeconds), and uses UT for the sidereal time. libnova's own Delta T
// (ln_get_jde) follows the measured values only to 2000, then extrapolates too fast and jumps by
// 45 s in mid-2010 (128 s in 2020, when it was 69 s): DeltaTSeconds uses it before 2000 only. A
// minute of Delta T moves the sun 0.0007 degrees along the ecliptic.
//
// What comes from libnova: Delta T before 2000, the Earth's VSOP87 longitude and distance
// (ln_get_earth_helio_coords), the nutation (ln_get_nutation) and the parallax (ln_get_parallax).
// What does not, because libnova 0.16 gets it wrong by more than 0.01 degrees or by more than the
// rest: its Earth longitude is referred to the equinox of J2000, so it is precessed to the equinox
// of date (ln_get_solar_equ_coords is 0.36 degrees off in 2026); its latitude drifts by 45" a
// century, so the sun's comes from Meeus's VSOP87D terms; ln_get_solar_equ_coords has no
// aberration (20.5"); ln_get_hrz_from_equ uses the mean sidereal time and
// ln_get_apparent_sidereal_time drops a cos(obliquity) (0.0004 degrees). These few steps follow
// Meeus chs. 12, 13, 21 and 25 in sun_position.cc. Against the NREL SPA example and Meeus Example
// 25.b the result is within 0.00002 degrees (tests/sun_position_test.cc).
//
// Geometric and apparent. `geometric_elevation_deg` is the topocentric elevation of the sun's
// centre without the atmosphere: apparent geocentric place (nutation and aberration included),
// then the parallax of an observer on the ellipsoid (at most 8.8", 0.0024 degrees). With
// `refraction` set, `elevation_deg` adds the refraction of the air, the elevation one sees:
// Saemundsson's formula from the true elevation (Meeus eq. 16.4, as NREL's SPA, eq. 42), scaled
// by pressure / 1010 mbar and 283 K / temperature, applied while the sun's upper limb can be seen
// (geometric elevation >= -0.8333 degrees, SPA's rule); otherwise it equals the geometric one.
// (libnova's ln_get_refraction_adj is Bennett's eq. 16.3, which starts from the apparent
// elevation, so it is not used here.) A sky model's sun direction is the geometric one: the models
// trace straight rays, so refraction is off by default.
#pragma once

#include <string>
#include <string_view>

namespace atmo {

// Parses an ISO 8601 date and time with a zone: `YYYY-MM-DDTHH:MM[:SS[.fff...]]` followed by `Z`,
// `+HH:MM`, `+HHMM` or `+HH` (or `-`), e.g. `2026-06-21T12:00+02:00`, `2003-10-17T19:30:30Z`. A
// lower-case `t`/`z` and a space for the `T` are accepted. Returns the instant as a UTC Julian day.
// Throws a one-line atmo::Error naming the text for a missing zone, malformed text or a field out
// of range (month 1..12, the month's days, hour 0..23, minute 0..59, second [0, 60), zone at most
// 18 hours).
double ParseIsoDateTime(std::string_view text);

// The instant `julian_day_utc` as `YYYY-MM-DDTHH:MM:SS[.sss]Z` (milliseconds only when not whole
// seconds), rounded to the millisecond.
std::string FormatIsoDateTimeUtc(double julian_day_utc);

// Parses a duration as one or more NUMBER UNIT parts, units d, h, min, s (`10min`, `30s`, `1h`,
// `1h30min`, `2d`, `1.5h`); returns seconds, > 0. Throws a one-line atmo::Error naming the text for
// anything else (no unit, an unknown unit, a zero or non-finite total).
double ParseDurationS(std::string_view text);

// Delta T = TT - UT in seconds at `julian_day_utc`: libnova's table before 2000, Espenak and
// Meeus's polynomials (NASA/TP-2006-214141) after; 64.7 s in 2005, 71.6 s in 2020 (measured:
// 69.4 s). Past years are good to a fraction of a second, future ones are predictions. Throws
// atmo::Error for a non-finite day.
double DeltaTSeconds(double julian_day_utc);

// The Greenwich mean sidereal time in degrees, [0, 360), at `julian_day_utc` taken as UT1 (Meeus
// eq. 12.4). The star frame of include/atmo/stars.h uses it with mean places.
double GreenwichMeanSiderealTimeDeg(double julian_day_utc);

struct SunPositionOptions {
  // Adds the air's refraction to `elevation_deg` (see the header comment).
  bool refraction = false;
  // The air at the observer, for the refraction: Meeus's standard 1010 mbar and 10 C.
  double pressure_mbar = 1010.0;
  double temperature_c = 10.0;
  // Observer height above the ellipsoid, for the parallax.
  double observer_height_m = 0.0;
};

struct SunPosition {
  // Topocentric elevation of the sun's centre above the horizontal; apparent (refracted) when
  // options.refraction, otherwise equal to geometric_elevation_deg.
  double elevation_deg = 0.0;
  double geometric_elevation_deg = 0.0;
  // Compass azimuth: 0 = north, 90 = east, in [0, 360) (libnova's, from the south westward, + 180).
  double azimuth_deg = 0.0;
  // The apparent geocentric right ascension, in [0, 360), and declination (true equator and
  // equinox of date), without the parallax.
  double right_ascension_deg = 0.0;
  double declination_deg = 0.0;
  double distance_au = 0.0;  // Earth-sun distance
};

// The sun at `julian_day_utc` for an observer at `latitude_deg` in [-90, 90] (north positive) and
// `longitude_deg` in [-180, 360) (east positive; 180..360 wrap to the west). Throws atmo::Error for
// a non-finite instant, an instant outside the years 0000..9999 that ParseIsoDateTime reads,
// latitude or longitude out of range, or non-finite options. Safe to call from several threads
// (the libnova calls, which share caches, take turns).
SunPosition ComputeSunPosition(double julian_day_utc, double latitude_deg, double longitude_deg,
                               const SunPositionOptions& options = {});

}  // namespace atmo
