// The command-line flags of `atmo` that more than one program parses (CLI11, private to the apps).
//
// apps/atmo/main.cc and apps/viewer/main.cc both call these, so that `atmo render` and
// `atmo-viewer` read the same flags with the same checks, defaults and meanings. CLI11 is heavy
// (about 10 s per translation unit): only cli_flags.cc and the two mains include it.
//
// To use it:
//   CLI::App app{"..."};
//   atmo::cli::AddCommonOptions(&app, common);
//   atmo::cli::RenderFlags flags;
//   atmo::cli::AddRenderFlags(&app, render, flags);
//   CLI11_PARSE(app, argc, argv);
//   atmo::cli::FinishRenderFlags(&app, render, flags);   // -o NAME, --no-exr, warnings
#pragma once

#include <cstdint>
#include <optional>
#include <string>
#include <vector>

#include <CLI/CLI.hpp>

#include "commands.h"

namespace atmo::cli {

// Rejects "nan", "inf" and anything that is not a number (CLI11 would accept nan and inf).
extern const CLI::Validator kFinite;
// An integer, checked before a range so that `--width abc` says so.
extern const CLI::Validator kInteger;
// A number > 0.
extern const CLI::Validator kPositive;
// [min, max] for a floating-point value, printed with %g (CLI::Range prints "0.000000").
CLI::Validator RangeOf(double min, double max);
// (min, max), open: for the perspective field of view.
CLI::Validator OpenRangeOf(double min, double max);
// "a, b, c": the names a --help lists.
std::string JoinNames(const std::vector<std::string>& names);
// A floating-point option that must be finite.
CLI::Option* AddNumber(CLI::App* app, const std::string& name, double& value, const std::string& help);
// An option whose default depends on other values: set only when given.
CLI::Option* AddOptionalNumber(CLI::App* app, const std::string& name, std::optional<double>& value,
                               const std::string& help);
// A count of Monte Carlo paths (--spp, --samples): an integer, read as signed so that a negative
// one is shown as given; the caller adds its range (which must exclude the negatives).
CLI::Option* AddPathCount(CLI::App* app, const std::string& name, std::optional<std::uint64_t>& value,
                          const std::string& help);
// The PNG's --exposure range (the config's `exposure`: [1e-10, 1e10]) and --ev's, [-32, 32] (its
// exposures 1/(1.2 2^EV) stay inside the first).
inline constexpr double kMinExposure = 1e-10;
inline constexpr double kMaxExposure = 1e10;
inline constexpr double kMaxEv100 = 32.0;
// Prints `atmo: warning: <message>` as one line on stderr.
void PrintWarning(const std::string& message);

// --model, --preset, --config, --backend, --threads, --seed, --option, --spectral.
void AddCommonOptions(CLI::App* app, CommonOptions& common);
// --date, --latitude, --longitude, --refraction (sun_options.h): the sun from a date and a place.
// A date needs a place and a place a date. Returns the --date option, for the caller's excludes.
CLI::Option* AddSunOptions(CLI::App* app, SunOptions& sun);

// --moon-elevation, --moon-azimuth, --moon-phase, --no-moon (sun_options.h, MoonOptions): the angle
// flags exclude `date` (the moon then comes from the date, unless --no-moon).
void AddMoonOptions(CLI::App* app, MoonOptions& moon, CLI::Option* date);

// The flags of `atmo render` that do not land in RenderCommand directly.
struct RenderFlags {
  std::string output;  // -o NAME
  bool no_exr = false;
  bool no_png = false;
};
// Every flag of `atmo render` but the common ones and --table: camera, observer and sun, display,
// outputs, unit, --spp, cube map, date and time-lapse (docs/cli.md#atmo-render).
void AddRenderFlags(CLI::App* app, RenderCommand& render, RenderFlags& flags);
// After parsing: -o NAME into the EXR and PNG paths, --no-exr, --no-png, and a warning on stderr
// ("atmo: warning: ...") for each flag that the chosen camera or outputs do not use (the display
// flags without a PNG only where `png_only_warnings`).
void FinishRenderFlags(CLI::App* app, RenderCommand& render, const RenderFlags& flags, bool png_only_warnings = true);

}  // namespace atmo::cli
