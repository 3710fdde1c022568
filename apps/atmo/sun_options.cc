// The sun from --date for the subcommands, and the render time-lapse (sun_options.h).
#include "sun_options.h"

#include <sys/stat.h>
#include <sys/wait.h>
#include <unistd.h>

#include <chrono>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <filesystem>

#include "atmo/error.h"
#include "atmo/image.h"
#include "commands.h"
#include "progress_bar.h"

namespace atmo::cli {

namespace {

namespace fs = std::filesystem;

// The full path of an executable `program` on PATH; empty when there is none.
std::string FindOnPath(const std::string& program) {
  const char* path = std::getenv("PATH");
  if (path == nullptr) return {};
  std::string folders = path;
  std::size_t start = 0;
  while (start <= folders.size()) {
    const std::size_t end = std::min(folders.find(':', start), folders.size());
    const std::string folder = folders.substr(start, end - start);
    const std::string candidate = (folder.empty() ? "." : folder) + "/" + program;
    struct stat info {};
    if (::stat(candidate.c_str(), &info) == 0 && S_ISREG(info.st_mode) && ::access(candidate.c_str(), X_OK) == 0) {
      return candidate;
    }
    start = end + 1;
  }
  return {};
}

// Runs `arguments` (the program's full path first) and waits; returns its exit status, -1 when it
// could not run or was killed.
int RunProgram(const std::vector<std::string>& arguments) {
  std::vector<char*> argv;
  for (const std::string& argument : arguments) argv.push_back(const_cast<char*>(argument.c_str()));
  argv.push_back(nullptr);
  std::fflush(stdout);
  std::fflush(stderr);
  const pid_t child = ::fork();
  if (child < 0) return -1;
  if (child == 0) {
    ::execv(argv[0], argv.data());
    ::_exit(127);
  }
  int status = 0;
  while (::waitpid(child, &status, 0) < 0) {
  }
  return WIFEXITED(status) ? WEXITSTATUS(status) : -1;
}

// A frame path's parts: what goes before the number, the number's digits, what goes after.
struct FrameName {
  std::string before;
  int digits = 4;
  std::string after;
};

FrameName SplitFramePath(const std::string& path, std::size_t frame_count) {
  FrameName name;
  for (std::size_t last = frame_count > 0 ? frame_count - 1 : 0; last >= 10000; last /= 10) ++name.digits;
  // The extension: from the last '.' of the file name, unless the name starts with it (".hidden").
  const std::size_t slash = path.rfind('/');
  const std::size_t name_start = slash == std::string::npos ? 0 : slash + 1;
  const std::size_t dot = path.rfind('.');
  const bool has_extension = dot != std::string::npos && dot > name_start;
  name.before = (has_extension ? path.substr(0, dot) : path) + "_";
  name.after = has_extension ? path.substr(dot) : "";
  return name;
}

// The printf-style pattern ffmpeg reads the frames with: the number as %0Nd, literal % doubled.
std::string FramePattern(const std::string& png_path, std::size_t frame_count) {
  const FrameName name = SplitFramePath(png_path, frame_count);
  const auto escape = [](const std::string& text) {
    std::string escaped;
    for (const char c : text) escaped += c == '%' ? std::string("%%") : std::string(1, c);
    return escaped;
  };
  return escape(name.before) + Format("%%0%dd", name.digits) + escape(name.after);
}

}  // namespace

SunAtInstant SunAt(const SunOptions& sun, double julian_day_utc) {
  if (!sun.latitude_deg || !sun.longitude_deg) throw Error("--date needs --latitude and --longitude");
  SunPositionOptions options;
  options.refraction = sun.refraction;
  SunAtInstant at;
  at.julian_day_utc = julian_day_utc;
  at.date_utc = FormatIsoDateTimeUtc(julian_day_utc);
  at.position = ComputeSunPosition(julian_day_utc, *sun.latitude_deg, *sun.longitude_deg, options);
  return at;
}

SunAtInstant SunAtDate(const SunOptions& sun) { return SunAt(sun, ParseIsoDateTime(sun.date)); }

std::optional<MoonPosition> ResolveMoon(const MoonOptions& moon, const SunOptions& sun, double sun_azimuth_deg,
                                        const std::optional<double>& julian_day_utc) {
  if (moon.no_moon) return std::nullopt;
  const bool by_hand = moon.elevation_deg || moon.azimuth_deg || moon.phase_deg;
  if (by_hand) {
    if (!moon.elevation_deg || !moon.phase_deg) {
      throw Error("a moon by hand needs --moon-elevation and --moon-phase (--moon-azimuth: default opposite the sun)");
    }
    MoonPosition place;
    place.elevation_deg = *moon.elevation_deg;
    place.azimuth_deg = moon.azimuth_deg.value_or(std::fmod(sun_azimuth_deg + 180.0, 360.0));
    place.phase_angle_deg = *moon.phase_deg;
    return place;
  }
  if (julian_day_utc && sun.latitude_deg && sun.longitude_deg) {
    return ComputeMoonPosition(*julian_day_utc, *sun.latitude_deg, *sun.longitude_deg);
  }
  return std::nullopt;
}

std::vector<std::pair<std::string, std::string>> SunMetadata(const SunOptions& sun, const SunAtInstant& at) {
  return {
      {"atmo:date", at.date_utc},
      {"atmo:latitudeDeg", Format("%.10g", sun.latitude_deg.value_or(0.0))},
      {"atmo:longitudeDeg", Format("%.10g", sun.longitude_deg.value_or(0.0))},
      {"atmo:refraction", sun.refraction ? "on" : "off"},
  };
}

std::string FramePath(const std::string& path, std::size_t frame, std::size_t frame_count) {
  if (path.empty()) return path;
  const FrameName name = SplitFramePath(path, frame_count);
  return name.before + Format("%0*zu", name.digits, frame) + name.after;
}

std::vector<double> TimeLapseInstants(const SunOptions& sun, const std::string& png_path) {
  const double start = ParseIsoDateTime(sun.date);
  const double end = ParseIsoDateTime(sun.until);
  const double step_s = ParseDurationS(sun.step);
  if (end < start) throw Error("--until " + sun.until + " is before --date " + sun.date);
  // Counted in seconds, with a microsecond of slack so that an --until on a step is included.
  const double frames = std::floor((end - start) * 86400.0 / step_s + 1e-6) + 1.0;
  if (frames > static_cast<double>(kMaxTimeLapseFrames)) {
    throw Error(Format("the time-lapse from --date to --until every %s has %.0f frames, more than %zu: use a longer --step",
                       sun.step.c_str(), frames, kMaxTimeLapseFrames));
  }
  if (!sun.mp4_path.empty()) {
    if (png_path.empty()) throw Error("--mp4 is made from the PNG frames: give --png");
    if (FindOnPath("ffmpeg").empty()) throw Error("--mp4 needs ffmpeg on PATH, and there is none");
    CheckOutputWritable(sun.mp4_path);
  }
  std::vector<double> instants;
  for (std::size_t i = 0; i < static_cast<std::size_t>(frames); ++i) instants.push_back(start + i * step_s / 86400.0);
  return instants;
}

int RunTimeLapse(const SunOptions& sun, const std::string& exr_path, const std::string& png_path,
                 const std::string& description,
                 const std::function<void(std::size_t frame, const SunAtInstant& sun, const std::string& exr,
                                          const std::string& png)>& render_frame) {
  const std::vector<double> instants = TimeLapseInstants(sun, png_path);
  const std::size_t count = instants.size();
  const auto start = std::chrono::steady_clock::now();
  ProgressBar progress("time-lapse");
  SunAtInstant first, last;
  for (std::size_t frame = 0; frame < count; ++frame) {
    progress.Update(static_cast<double>(frame), static_cast<double>(count));
    const SunAtInstant at = SunAt(sun, instants[frame]);
    render_frame(frame, at, FramePath(exr_path, frame, count), FramePath(png_path, frame, count));
    if (frame == 0) first = at;
    last = at;
  }
  progress.Update(static_cast<double>(count), static_cast<double>(count));
  progress.Finish();

  if (!sun.mp4_path.empty()) {
    const std::string ffmpeg = FindOnPath("ffmpeg");
    if (ffmpeg.empty()) throw Error("--mp4 needs ffmpeg on PATH, and there is none");
    // H.264 in yuv420p, the form players accept, needs even sides: pad odd ones by a pixel.
    WriteFileAtomically(sun.mp4_path, [&](const fs::path& temporary) {
      const int status = RunProgram({ffmpeg, "-nostdin", "-loglevel", "error", "-y", "-framerate",
                                     Format("%.10g", sun.fps), "-start_number", "0", "-i",
                                     FramePattern(png_path, count), "-vf", "pad=ceil(iw/2)*2:ceil(ih/2)*2",
                                     "-c:v", "libx264", "-pix_fmt", "yuv420p", "-f", "mp4", temporary.string()});
      if (status != 0) throw Error(Format("ffmpeg failed (exit status %d)", status));
    });
  }

  const double seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
  std::string files;
  for (const std::string& path : {exr_path, png_path}) {
    if (path.empty()) continue;
    files += (files.empty() ? "" : ", ") + FramePath(path, 0, count);
    if (count > 1) files += " .. " + FramePath(path, count - 1, count);
  }
  if (!sun.mp4_path.empty()) files += (files.empty() ? "" : ", ") + sun.mp4_path;
  std::printf("wrote %zu frames %s(%s, sun elevation %.2f to %.2f deg, %s to %s) in %.1f s\n", count,
              files.empty() ? "without files " : (files + " ").c_str(), description.c_str(),
              first.position.elevation_deg, last.position.elevation_deg, first.date_utc.c_str(),
              last.date_utc.c_str(), seconds);
  return 0;
}

}  // namespace atmo::cli
