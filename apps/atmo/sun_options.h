// The sun from a date and a place for `atmo render`, `sample` and `bench` (--date, --latitude,
// --longitude, --refraction; include/atmo/sun_position.h), and the time-lapse of `atmo render`
// (--until, --step, --mp4, --fps): the frames, their file names, the progress bar and the MP4.
//
// main.cc registers the flags (and which need or exclude which); the commands call these helpers.
#pragma once

#include <cstddef>
#include <functional>
#include <optional>
#include <string>
#include <utility>
#include <vector>

#include "atmo/moon.h"
#include "atmo/sun_position.h"

namespace atmo::cli {

struct SunOptions {
  std::string date;                     // ISO 8601 with a zone; empty: the sun comes from the angle flags
  std::optional<double> latitude_deg;   // north positive
  std::optional<double> longitude_deg;  // east positive
  bool refraction = false;              // the apparent (refracted) elevation instead of the geometric one
  // `atmo render` only: a time-lapse from `date` to `until` (inclusive when on a step) every `step`.
  std::string until;
  std::string step;
  std::string mp4_path;  // empty: no video
  double fps = 24.0;     // frames per second of the MP4
};

// The moon (include/atmo/moon.h) of `atmo render` and `atmo illuminance`: by hand with the three
// angle flags, or from --date (the ephemeris) unless --no-moon.
struct MoonOptions {
  std::optional<double> elevation_deg;
  std::optional<double> azimuth_deg;  // default: opposite the sun
  std::optional<double> phase_deg;    // phase angle: 0 full, 180 new
  bool no_moon = false;
};

// The moon's place for one sun: by hand (the angle flags), from the date of `dated` (the
// ephemeris, for --latitude and --longitude), or none (no flags and no date, or --no-moon).
// Throws atmo::Error for a moon flag without --moon-elevation and --moon-phase.
std::optional<MoonPosition> ResolveMoon(const MoonOptions& moon, const SunOptions& sun, double sun_azimuth_deg,
                                        const std::optional<double>& julian_day_utc);

// The most frames a time-lapse may have.
constexpr std::size_t kMaxTimeLapseFrames = 100000;

// The sun at one instant.
struct SunAtInstant {
  double julian_day_utc = 0.0;
  std::string date_utc;  // FormatIsoDateTimeUtc
  SunPosition position;
};

inline bool HasDate(const SunOptions& sun) { return !sun.date.empty(); }
inline bool IsTimeLapse(const SunOptions& sun) { return !sun.until.empty(); }

// The sun at `julian_day_utc` for the --latitude and --longitude (refracted with --refraction,
// at 1010 mbar and 10 C). Throws atmo::Error.
SunAtInstant SunAt(const SunOptions& sun, double julian_day_utc);
// The sun at --date. Throws atmo::Error for a bad date or place.
SunAtInstant SunAtDate(const SunOptions& sun);

// The EXR attributes of a sun from a date: atmo:date (UTC), atmo:latitudeDeg, atmo:longitudeDeg,
// atmo:refraction ("on" or "off").
std::vector<std::pair<std::string, std::string>> SunMetadata(const SunOptions& sun, const SunAtInstant& at);

// Frame `frame` of `frame_count` of an output path: the frame number, zero-padded to at least 4
// digits (more when the count needs them), joined with `_` before the file's extension, or at the
// end of a name without one: sky.png -> sky_0000.png, out/frames -> out/frames_0000. An empty path
// stays empty (no such output).
std::string FramePath(const std::string& path, std::size_t frame, std::size_t frame_count);

// A time-lapse's instants: --date, then every --step while not later than --until. Throws
// atmo::Error for a bad date or step, --until before --date, more than kMaxTimeLapseFrames frames,
// or an --mp4 that cannot be made (no PNG frames, no ffmpeg on PATH, an unwritable file): all
// before any work.
std::vector<double> TimeLapseInstants(const SunOptions& sun, const std::string& png_path);

// Renders a time-lapse: `render_frame(frame, sun, exr_path, png_path)` per instant with that
// frame's paths (FramePath; empty when not asked for), a progress bar on stderr when it is a
// terminal, then the MP4 (--mp4, with ffmpeg) from the PNG frames, and one summary line on
// stdout. Returns the exit code.
int RunTimeLapse(const SunOptions& sun, const std::string& exr_path, const std::string& png_path,
                 const std::string& description,
                 const std::function<void(std::size_t frame, const SunAtInstant& sun, const std::string& exr,
                                          const std::string& png)>& render_frame);

}  // namespace atmo::cli
