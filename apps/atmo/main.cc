// atmo: the command line of the atmo sky library (docs/design.md §4).
//
//   atmo render  [--camera perspective|fisheye|equirect] [--width W --height H] ... [-o NAME | --exr F --png F]
//   atmo sample  --model M [--preset P | --config F.json] (--grid IN.csv|- | --altitude --sun-zenith|--sun-elevation
//                --view-zenith --azimuth) [--out OUT.csv]
//   atmo compare --model M [--against R] [--against-option K=V] [--grid standard|twilight|space|IN.csv | --against-samples S.csv] [--csv F]
//                [--json F] [--image F.png [--altitude A --sun-zenith S --image-range PERCENT]]
//   atmo presets [--dump NAME]
//   atmo bench   [--repeat N | --quick] [--width W --height H]
//   atmo precompute --model elek --out NAME          (writes NAME.exr, NAME.raw, NAME.json, ...)
//   atmo precompute --model hillaire --out NAME      (writes NAME.json, NAME_<table>.exr, .raw)
//   atmo illuminance [--sun-elevation E ...] [--altitude A]   (lux on a horizontal plane, CSV)
//   atmo irradiance [--sun-elevation E ...] [--plane TILT:AZIMUTH|sun ...] [--spectral] [--out F.csv]
//   atmo annual --epw F.epw --out-dir DIR [--plane TILT:AZIMUTH ...] [--hours A:B] [--shard I/N]
//   atmo calibrate (--sun-elevation E | --date ...) --direct-normal-lux X --diffuse-horizontal-lux Y --out sky.json
// render, sample and bench also take --table NAME: load the elek table NAME instead of computing it.
// render, sample and bench also take --date ISO --latitude DEG --longitude DEG [--refraction]: the sun
// of that instant and place; render also --until ISO --step DURATION [--mp4 F]: a time-lapse.
// Shared by all but presets: --model, --preset, --config, --backend cpu|gl, --threads N, --seed N, --option K=V.
//
// This file only parses the command line (CLI11 lives here and in cli_flags.cc) and hands plain
// structs to the subcommands in commands.h. Errors: one line `atmo: error: ...` on stderr; exit 2
// for a command line that does not parse, 1 for anything else.
#include <algorithm>
#include <cctype>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <exception>
#include <filesystem>
#include <optional>
#include <string>
#include <vector>

#include <CLI/CLI.hpp>
#include <oneapi/tbb/global_control.h>

#include "atmo/error.h"
#include "atmo/interrupt.h"
#include "atmo/memory.h"
#include "atmo/render.h"
#include "atmo/timing.h"
#include "cli_flags.h"
#include "commands.h"

namespace {

using atmo::cli::AddCommonOptions;
using atmo::cli::AddNumber;
using atmo::cli::AddOptionalNumber;
using atmo::cli::AddPathCount;
using atmo::cli::AddMoonOptions;
using atmo::cli::AddSunOptions;
using atmo::cli::CommonOptions;
using atmo::cli::JoinNames;
using atmo::cli::kFinite;
using atmo::cli::kInteger;
using atmo::cli::kPositive;
using atmo::cli::OpenRangeOf;
using atmo::cli::RangeOf;

// Prints `atmo: error: <message>` as one line on stderr.
void PrintError(const std::string& message) {
  std::string line = message;
  for (char& c : line) {
    if (c == '\n' || c == '\r') c = ' ';
  }
  while (!line.empty() && line.back() == ' ') line.pop_back();
  std::fprintf(stderr, "atmo: error: %s\n", line.c_str());
}


// The default model and preset of render, sample, illuminance, irradiance, calibrate and annual:
// `source4d` on `us-standard` (docs/cli.md, "Common flags"). Their help says so.
constexpr const char* kAccurateModel = "source4d";
constexpr const char* kAccuratePreset = "us-standard";
void ShowAccurateDefaults(CLI::App* app) {
  app->get_option("--model")->default_str(kAccurateModel);
  app->get_option("--preset")->default_str(kAccuratePreset);
}

// Puts each flag of `app` into its help group (CLI11's default lumps them all under "Options").
void GroupFlags(CLI::App* app) {
  static const std::pair<const char*, const char*> kGroups[] = {
      {"--model", "Model and atmosphere"}, {"--preset", "Model and atmosphere"}, {"--config", "Model and atmosphere"},
      {"--option", "Model and atmosphere"}, {"--spectral", "Model and atmosphere"}, {"--wavelengths", "Model and atmosphere"}, {"--table", "Model and atmosphere"},
      {"--aerosol", "Model and atmosphere"}, {"--aod", "Model and atmosphere"}, {"--angstrom", "Model and atmosphere"},
      {"--visibility", "Model and atmosphere"}, {"--turbidity", "Model and atmosphere"},
      {"--aerosol-phase", "Model and atmosphere"},
      {"--backend", "Execution"}, {"--threads", "Execution"}, {"--max-memory", "Execution"}, {"--table-cache", "Execution"}, {"--source4d-tables", "Execution"}, {"--seed", "Execution"}, {"--spp", "Execution"},
      {"--samples", "Execution"}, {"--target-rel-error", "Execution"},
      {"--camera", "Camera"}, {"--width", "Camera"}, {"--height", "Camera"}, {"--fov", "Camera"},
      {"--yaw", "Camera"}, {"--target", "Camera"}, {"--pitch", "Camera"}, {"--altitude", "Observer and sun"},
      {"--sun-elevation", "Observer and sun"}, {"--sun-azimuth", "Observer and sun"},
      {"--sun-zenith", "Observer and sun"}, {"--view-zenith", "Observer and sun"}, {"--azimuth", "Observer and sun"},
      {"--date", "Observer and sun"}, {"--latitude", "Observer and sun"}, {"--longitude", "Observer and sun"},
      {"--refraction", "Observer and sun"}, {"--no-sun-disc", "Observer and sun"},
      {"--sun-size", "Observer and sun"}, {"--no-ground", "Observer and sun"},
      {"--exposure", "PNG display"}, {"--ev", "PNG display"}, {"--auto-exposure", "PNG display"},
      {"--tonemap", "PNG display"}, {"--metering", "PNG display"}, {"--gamma", "PNG display"},
      {"--per-channel", "PNG display"}, {"--no-dither", "PNG display"}, {"--png-bits", "PNG display"},
      {"--until", "Time-lapse"}, {"--step", "Time-lapse"}, {"--mp4", "Time-lapse"}, {"--fps", "Time-lapse"},
  };
  for (CLI::Option* option : app->get_options()) {
    if (option->get_lnames().empty() || option->check_lname("help")) continue;
    option->group("Outputs and inputs");
    for (const auto& [name, group] : kGroups) {
      if (option->check_lname(std::string(name).substr(2))) option->group(group);
    }
  }
}

using atmo::cli::PrintWarning;

// Levenshtein distance (insertions, deletions, substitutions), for "did you mean".
std::size_t EditDistance(const std::string& a, const std::string& b) {
  std::vector<std::size_t> row(b.size() + 1);
  for (std::size_t j = 0; j <= b.size(); ++j) row[j] = j;
  for (std::size_t i = 1; i <= a.size(); ++i) {
    std::size_t diagonal = row[0];
    row[0] = i;
    for (std::size_t j = 1; j <= b.size(); ++j) {
      const std::size_t above = row[j];
      row[j] = std::min({row[j] + 1, row[j - 1] + 1, diagonal + (a[i - 1] == b[j - 1] ? 0 : 1)});
      diagonal = above;
    }
  }
  return row[b.size()];
}

// The known word closest to `word` when it is close enough to be a typo (at most a third of its
// letters off); empty otherwise.
std::string Closest(const std::string& word, const std::vector<std::string>& known) {
  std::string best;
  std::size_t best_distance = std::max<std::size_t>(1, word.size() / 3) + 1;
  for (const std::string& candidate : known) {
    const std::size_t d = EditDistance(word, candidate);
    if (d < best_distance) {
      best_distance = d;
      best = candidate;
    }
  }
  return best;
}

// " (did you mean X?)" for the first command-line word that is neither a subcommand nor a flag of
// the command being parsed but is close to one; empty when there is none.
std::string DidYouMean(CLI::App& app, int argc, char** argv) {
  std::vector<std::string> subcommands;
  for (const CLI::App* sub : app.get_subcommands({})) subcommands.push_back(sub->get_name());
  const std::vector<CLI::App*> parsed = app.get_subcommands();
  const CLI::App* command = parsed.empty() ? &app : parsed.front();
  std::vector<std::string> flags;
  for (const CLI::Option* option : command->get_options()) {
    for (const std::string& name : option->get_lnames()) flags.push_back("--" + name);
  }
  for (int i = 1; i < argc; ++i) {
    std::string word = argv[i];
    word = word.substr(0, word.find('='));
    if (word.rfind("--", 0) == 0) {
      if (std::find(flags.begin(), flags.end(), word) != flags.end()) continue;
      const std::string near = Closest(word, flags);
      if (!near.empty()) return " (did you mean " + near + "?)";
    } else if (parsed.empty() && !word.empty() && word[0] != '-') {
      const std::string near = Closest(word, subcommands);
      if (!near.empty()) return " (did you mean " + near + "?)";
      return "";
    }
  }
  return "";
}

}  // namespace

int main(int argc, char** argv) {
  atmo::InstallInterruptHandlers("atmo");  // SIGINT/SIGTERM: no temporary file is left behind
  CLI::App app{"atmo: physically based sky rendering", "atmo"};
  app.set_version_flag("--version", std::string("atmo ") + ATMO_VERSION);
  app.require_subcommand(0, 1);

  CommonOptions common;

  atmo::cli::RenderCommand render;
  CLI::App* render_app = app.add_subcommand("render", "render a sky image (EXR + tone-mapped PNG)");
  AddCommonOptions(render_app, common);
  ShowAccurateDefaults(render_app);
  atmo::cli::RenderFlags render_flags;
  atmo::cli::AddRenderFlags(render_app, render, render_flags);
  const std::string side_help = " in pixels";

  atmo::cli::SampleCommand sample;
  CLI::App* sample_app = app.add_subcommand("sample", "query radiance and transmittance as CSV");
  AddCommonOptions(sample_app, common);
  ShowAccurateDefaults(sample_app);
  CLI::Option* grid = sample_app->add_option(
      "--grid", sample.grid_path, "CSV with header altitude_m,sun_zenith_deg,view_zenith_deg,azimuth_deg");
  sample_app->add_option("--out", sample.out_path, "output CSV (default: standard output)");
  sample_app->add_flag("--night-sky", sample.night_sky,
                       "add the night sky's own light (airglow, zodiacal light, integrated starlight; docs/night.md) to the radiance, as images show it");
  sample_app->add_option("--unit", sample.unit,
                         "relative (sr^-1 per unit solar irradiance), radiance (W m^-2 sr^-1 nm^-1) or luminance "
                         "(cd/m^2, one row per point)")
      ->check(CLI::IsMember({"relative", "radiance", "luminance"}))
      ->capture_default_str();
  CLI::Option* single[] = {
      AddOptionalNumber(sample_app, "--altitude", sample.altitude_m, "observer altitude in metres"),
      AddOptionalNumber(sample_app, "--sun-zenith", sample.sun_zenith_deg,
                        "sun zenith angle in degrees [0, 180]")
          ->check(RangeOf(0.0, 180.0)),
      AddOptionalNumber(sample_app, "--view-zenith", sample.view_zenith_deg,
                        "view zenith angle in degrees [0, 180]")
          ->check(RangeOf(0.0, 180.0)),
      AddOptionalNumber(sample_app, "--azimuth", sample.azimuth_deg,
                        "azimuth between view and sun in degrees (0: towards the sun)"),
  };
  for (CLI::Option* option : single) grid->excludes(option);
  // --date gives the single query's sun zenith (sun_options.h).
  CLI::Option* sample_date = AddSunOptions(sample_app, sample.sun)->excludes(grid)->excludes(single[1]);
  AddMoonOptions(sample_app, sample.moon, sample_date);
  // The render convention for the sun's height; the azimuth stays the one between view and sun (docs/design.md §4).
  std::optional<double> sample_sun_elevation;
  AddOptionalNumber(sample_app, "--sun-elevation", sample_sun_elevation,
                    "sun elevation in degrees [-90, 90], as in `atmo render`: the same as --sun-zenith 90-E "
                    "(--azimuth stays relative to the sun)")
      ->check(RangeOf(-90.0, 90.0))
      ->excludes(grid)
      ->excludes(single[1])
      ->excludes(sample_date);
  // Monte Carlo settings: they become the model options samples= and target_rel_error= (models
  // that take no such option reject them).
  std::optional<std::uint64_t> sample_paths;
  std::optional<double> target_rel_error;
  AddPathCount(sample_app, "--samples,--spp", sample_paths,
               "Monte Carlo paths per query (model reference; --spp is the same flag, as in `atmo render`)")
      ->check(CLI::Range(std::int64_t{2}, std::int64_t{1} << 40));
  AddOptionalNumber(sample_app, "--target-rel-error", target_rel_error,
                    "keep adding paths until standard error / radiance <= this (model reference)")
      ->check(RangeOf(0.0, 1.0));

  atmo::cli::CompareCommand compare;
  CLI::App* compare_app =
      app.add_subcommand("compare", "relative error of --model against a reference model on a grid");
  AddCommonOptions(compare_app, common);
  CLI::Option* against =
      compare_app->add_option("--against", compare.against, "the reference model")->capture_default_str();
  CLI::Option* against_option =
      compare_app
          ->add_option("--against-option", compare.against_options, "reference model setting KEY=VALUE (repeatable)")
          ->expected(1)
          ->take_all();
  CLI::Option* compare_grid =
      compare_app
          ->add_option("--grid", compare.grid,
                       "'standard', 'twilight' (sun 90-108), 'space' (observers 100-1000 km) or a CSV like "
                       "`atmo sample --grid`")
          ->capture_default_str();
  compare_app
      ->add_option("--against-samples", compare.against_samples,
                   "the reference read from an `atmo sample` CSV (its configurations are the grid)")
      ->excludes(against)
      ->excludes(against_option)
      ->excludes(compare_grid);
  AddNumber(compare_app, "--floor", compare.floor,
            "leave out rows whose reference is at most FLOOR x the largest of their sky")
      ->check(RangeOf(0.0, 1.0));
  compare_app->add_option("--csv", compare.csv_path, "per-row CSV output (one row per configuration and channel)");
  compare_app->add_option("--json", compare.json_path, "summary JSON output");
  compare_app->add_option("--markdown", compare.markdown_path, "the summary table as Markdown (docs/accuracy.md)");
  compare_app->add_option("--image", compare.image_path, "false-colour relative-error fisheye PNG");
  AddNumber(compare_app, "--altitude", compare.image_altitude_m, "observer altitude of the --image in metres")
      ->check(RangeOf(-atmo::kMaxAltitude_m, atmo::kMaxAltitude_m));
  AddNumber(compare_app, "--sun-zenith", compare.image_sun_zenith_deg, "sun zenith of the --image in degrees")
      ->check(RangeOf(0.0, 180.0));
  AddNumber(compare_app, "--image-range", compare.image_range_percent,
            "colour scale of the --image: -PERCENT .. +PERCENT relative error")
      ->check(kPositive);
  compare_app->add_option("--image-size", compare.image_size, "--image fisheye diameter in pixels")
      ->check(kInteger)
      ->check(CLI::Range(16, 4096))
      ->capture_default_str();

  atmo::cli::PresetsCommand presets;
  CLI::App* presets_app = app.add_subcommand("presets", "list the presets, or print one as JSON");
  presets_app->add_option("--dump", presets.dump, "print this preset as JSON (accepted back by --config)");

  atmo::cli::BenchCommand bench;
  CLI::App* bench_app = app.add_subcommand("bench", "time the precomputation passes and a frame");
  AddCommonOptions(bench_app, common);
  CLI::Option* repeat = bench_app->add_option("--repeat", bench.repeat, "repetitions")
                            ->check(kInteger)
                            ->check(CLI::Range(1, 100000))
                            ->capture_default_str();
  bench_app->add_flag("--quick", bench.quick, "3 repetitions")->excludes(repeat);
  bench_app->add_option("--width", bench.width, "frame width" + side_help)
      ->check(kInteger)
      ->check(CLI::Range(1, atmo::kMaxImageSide))
      ->capture_default_str();
  bench_app->add_option("--height", bench.height, "frame height" + side_help)
      ->check(kInteger)
      ->check(CLI::Range(1, atmo::kMaxImageSide))
      ->capture_default_str();
  AddSunOptions(bench_app, bench.sun);  // the frame's sun from a date (sun_options.h)
  bench_app->add_option("--work-group-forms", bench.work_group_forms,
                        "with --backend gl: hillaire's table passes split a texel's work over a work group (on) or "
                        "run a texel per invocation (off); auto: on for a hardware GPU, off on a software GL")
      ->check(CLI::IsMember({"on", "off", "auto"}))
      ->capture_default_str();

  atmo::cli::PrecomputeCommand precompute;
  CLI::App* precompute_app = app.add_subcommand(
      "precompute", "export the model's tables for engines (NAME.json + EXR and raw float; docs/tables.md)");
  AddCommonOptions(precompute_app, common);
  precompute_app->add_option("--out", precompute.out, "output NAME (without extension)")->required();
  // elek was the first model with an exportable table: still the default model here.
  precompute_app->get_option("--model")->default_str("elek")->description(
      "sky model whose tables are exported: elek (its scattering and transmittance tables) or hillaire "
      "(transmittance, multiple scattering, sky view, aerial perspective)");
  // Model hillaire's view-dependent tables: render's observer, sun and camera flags.
  const std::vector<CLI::Option*> hillaire_flags = {
      AddOptionalNumber(precompute_app, "--altitude", precompute.altitude_m,
                        "hillaire: observer altitude in metres of the sky-view and aerial tables [default: the "
                        "preset's]")
          ->check(RangeOf(-atmo::kMaxAltitude_m, atmo::kMaxAltitude_m)),
      AddNumber(precompute_app, "--sun-elevation", precompute.sun_elevation_deg, "hillaire: sun elevation in degrees")
          ->check(RangeOf(-90.0, 90.0)),
      AddNumber(precompute_app, "--sun-azimuth", precompute.sun_azimuth_deg, "hillaire: sun compass azimuth in degrees"),
      precompute_app->add_option("--width", precompute.width, "hillaire: aerial-perspective camera width in pixels")
          ->check(kInteger)
          ->check(CLI::Range(1, atmo::kMaxImageSide))
          ->capture_default_str(),
      precompute_app->add_option("--height", precompute.height, "hillaire: aerial-perspective camera height in pixels")
          ->check(kInteger)
          ->check(CLI::Range(1, atmo::kMaxImageSide))
          ->capture_default_str(),
      AddNumber(precompute_app, "--fov", precompute.fov_deg,
                "hillaire: aerial-perspective camera horizontal field of view in degrees")
          ->check(OpenRangeOf(0.0, 180.0)),
      AddOptionalNumber(precompute_app, "--yaw", precompute.yaw_deg,
                        "hillaire: aerial-perspective camera compass azimuth in degrees [default: the sun's]"),
      AddNumber(precompute_app, "--pitch", precompute.pitch_deg, "hillaire: aerial-perspective camera elevation in degrees")
          ->check(RangeOf(-90.0, 90.0)),
      precompute_app->add_option("--aerial-size", precompute.aerial_size,
                                 "hillaire: aerial-perspective froxels WxHxD, each in [1, 512]")
          ->capture_default_str(),
      // At most the altitude bound, at least 1 m: the manifest's max_distance_km stays a normal
      // float for an engine (1e300 m was accepted, which a float reads as inf).
      AddNumber(precompute_app, "--aerial-distance", precompute.aerial_distance_m,
                "hillaire: distance of the last aerial-perspective slice in metres, in [1, 1e11]")
          ->check(RangeOf(1.0, atmo::kMaxAltitude_m)),
      AddSunOptions(precompute_app, precompute.sun)};
  hillaire_flags.back()
      ->excludes(precompute_app->get_option("--sun-elevation"))
      ->excludes(precompute_app->get_option("--sun-azimuth"));

  atmo::cli::IlluminanceCommand illuminance;
  CLI::App* illuminance_app = app.add_subcommand(
      "illuminance", "sun and sky illuminance on a horizontal plane, in lux (CSV)");
  AddCommonOptions(illuminance_app, common);
  ShowAccurateDefaults(illuminance_app);
  illuminance_app
      ->add_option("--sun-elevation", illuminance.sun_elevations_deg,
                   "sun elevation(s) in degrees, e.g. --sun-elevation 10 30 60")
      ->check(kFinite)
      ->check(RangeOf(-90.0, 90.0))
      ->capture_default_str();
  AddOptionalNumber(illuminance_app, "--altitude", illuminance.altitude_m,
                    "observer altitude in metres [default: the preset's]")
      ->check(RangeOf(-atmo::kMaxAltitude_m, atmo::kMaxAltitude_m));
  CLI::Option* illuminance_date = AddSunOptions(illuminance_app, illuminance.sun);
  illuminance_date->excludes(illuminance_app->get_option("--sun-elevation"));
  AddMoonOptions(illuminance_app, illuminance.moon, illuminance_date);
  illuminance_app->add_flag("--no-stars", illuminance.no_stars,
                            "leave the stars (Debian's stellarium-data, when installed) out of night_sky_*");
  illuminance_app->add_flag("--no-night-glow", illuminance.no_night_glow,
                            "leave the airglow and zodiacal light out of night_sky_* and the global (the stars stay: "
                            "--no-stars)");

  atmo::cli::IrradianceCommand irradiance;
  CLI::App* irradiance_app = app.add_subcommand(
      "irradiance", "the sun's and sky's light on planes: direct, circumsolar, sky diffuse, ground-reflected (CSV)");
  AddCommonOptions(irradiance_app, common);
  ShowAccurateDefaults(irradiance_app);
  irradiance_app
      ->add_option("--sun-elevation", irradiance.sun_elevations_deg,
                   "sun elevation(s) in degrees, e.g. --sun-elevation 10 30 60")
      ->check(kFinite)
      ->check(RangeOf(-90.0, 90.0))
      ->capture_default_str();
  AddNumber(irradiance_app, "--sun-azimuth", irradiance.sun_azimuth_deg, "sun compass azimuth in degrees (0 north, 90 east)")
      ->capture_default_str();
  AddOptionalNumber(irradiance_app, "--altitude", irradiance.altitude_m,
                    "observer altitude in metres [default: the preset's]")
      ->check(RangeOf(-atmo::kMaxAltitude_m, atmo::kMaxAltitude_m));
  irradiance_app
      ->add_option("--plane", irradiance.planes,
                   "planes as TILT:AZIMUTH in degrees (tilt 0 faces up, 90 is vertical; azimuth the way the "
                   "plane faces, 0 north) or sun (facing the sun)")
      ->capture_default_str();
  AddNumber(irradiance_app, "--circumsolar", irradiance.circumsolar_deg,
            "half-angle in degrees of the circumsolar region around the sun (a pyrheliometer's 2.5)")
      ->check(RangeOf(0.0, 10.0))
      ->capture_default_str();
  irradiance_app->add_flag("--per-wavelength", irradiance.spectral,
                           "one row per wavelength in W m^-2 nm^-1 instead of lux and W m^-2 over 360-830 nm");
  irradiance_app->add_option("--out", irradiance.out_path, "write the CSV to this file instead of standard output");
  CLI::Option* irradiance_date = AddSunOptions(irradiance_app, irradiance.sun);
  irradiance_date->excludes(irradiance_app->get_option("--sun-elevation"))
      ->excludes(irradiance_app->get_option("--sun-azimuth"));

  atmo::cli::CalibrateCommand calibrate;
  CLI::App* calibrate_app = app.add_subcommand(
      "calibrate", "the clear sky (aerosol optical depth and albedo) of a measured direct and diffuse illuminance");
  AddCommonOptions(calibrate_app, common);
  ShowAccurateDefaults(calibrate_app);
  AddOptionalNumber(calibrate_app, "--sun-elevation", calibrate.sun_elevation_deg, "sun elevation in degrees")
      ->check(RangeOf(1.0, 90.0));
  AddNumber(calibrate_app, "--sun-azimuth", calibrate.sun_azimuth_deg, "sun compass azimuth in degrees")
      ->capture_default_str();
  AddOptionalNumber(calibrate_app, "--altitude", calibrate.altitude_m,
                    "the station's altitude in metres [default: the preset's]");
  AddNumber(calibrate_app, "--direct-normal-lux", calibrate.direct_normal_lux,
            "measured direct normal illuminance (a pyrheliometer's: the disc and 2.5 degrees around it)")
      ->required()
      ->check(RangeOf(0.0, 2e5));
  AddNumber(calibrate_app, "--diffuse-horizontal-lux", calibrate.diffuse_horizontal_lux,
            "measured diffuse horizontal illuminance (a shaded pyranometer's)")
      ->required()
      ->check(RangeOf(0.0, 2e5));
  AddNumber(calibrate_app, "--circumsolar", calibrate.circumsolar_deg,
            "half-angle in degrees of the pyrheliometer's view, whose aureole counts as direct")
      ->check(RangeOf(0.0, 10.0))
      ->capture_default_str();
  AddNumber(calibrate_app, "--tolerance", calibrate.tolerance_percent,
            "relative agreement asked of both illuminances, in percent")
      ->check(RangeOf(0.01, 10.0))
      ->capture_default_str();
  calibrate_app->add_option("--out", calibrate.out_path, "the calibrated parameters, JSON (atmo render --config)")
      ->required();
  CLI::Option* calibrate_date = AddSunOptions(calibrate_app, calibrate.sun);
  calibrate_date->excludes(calibrate_app->get_option("--sun-elevation"))
      ->excludes(calibrate_app->get_option("--sun-azimuth"));

  atmo::cli::AnnualCommand annual;
  CLI::App* annual_app = app.add_subcommand(
      "annual", "a weather file's hours as calibrated skies: Radiance sky matrix and irradiance per plane");
  AddCommonOptions(annual_app, common);
  ShowAccurateDefaults(annual_app);
  annual_app->add_option("--epw", annual.epw_path, "the EnergyPlus weather file (EPW)")->required();
  annual_app->add_option("--out-dir", annual.out_dir, "the run's folder: parts, run.json and, once complete, sky.mtx, "
                                                      "hours.csv, irradiance.csv")->required();
  annual_app->add_option("--plane", annual.planes,
                         "planes for irradiance.csv as TILT:AZIMUTH in degrees or sun, besides the horizontal and the "
                         "sun-facing plane");
  annual_app->add_option("--subdivision", annual.subdivision, "Reinhart's MF: 1 (145 patches), 2 (577), 4 (2305)")
      ->check(CLI::IsMember({1, 2, 4}))
      ->capture_default_str();
  annual_app->add_option("--patch-samples", annual.patch_samples, "sky samples per patch side")
      ->check(kInteger)
      ->check(CLI::Range(1, 16))
      ->capture_default_str();
  AddNumber(annual_app, "--circumsolar", annual.circumsolar_deg,
            "half-angle in degrees of the pyrheliometer's view, whose aureole counts as direct")
      ->check(RangeOf(0.0, 10.0))
      ->capture_default_str();
  annual_app->add_option("--hours", annual.hours, "only the file's hours A:B (from 0, B excluded)");
  annual_app->add_option("--shard", annual.shard, "only the whole days whose number modulo N is I (I/N), for job arrays");
  annual_app->add_option("--sky-maps", annual.sky_maps,
                         "also write each hour's sky as maps/sky_HHHH.hdr (an angular fisheye this many pixels a side) "
                         "and its Radiance scene maps/sky_HHHH.rad")
      ->check(kInteger)
      ->check(CLI::Range(16, 4096));
  annual_app->add_flag("--per-wavelength", annual.per_wavelength,
                       "also write irradiance_spectral.csv: every plane's irradiance per wavelength, W m^-2 nm^-1");
  annual_app->add_flag("--no-sun-in-matrix", annual.no_sun_in_matrix,
                       "leave the sun's direct light out of the matrix's patches (the sky alone)");
  AddOptionalNumber(annual_app, "--latitude", annual.latitude_deg, "check that the file is for this latitude (degrees)");
  AddOptionalNumber(annual_app, "--longitude", annual.longitude_deg, "check that the file is for this longitude (degrees east)");

  // --table NAME: the elek model's option table=NAME (load an exported table instead of computing).
  std::string table;
  for (CLI::App* table_app : {render_app, sample_app, bench_app}) {
    table_app->add_option("--table", table, "load the table NAME written by `atmo precompute` (model elek)");
  }

  const std::string models = JoinNames(atmo::ModelNames());
  const std::string preset_names = JoinNames(atmo::PresetNames());
  const std::string lists = "\n\nModels: " + models + " (docs/models/MODEL.md, options under #options).\nPresets: " +
                            preset_names + " (`atmo presets`).\nManual: docs/cli.md.";
  const std::pair<CLI::App*, std::string> footers[] = {
      {render_app, "Examples:\n  atmo render --camera fisheye --width 512 --height 512 -o allsky\n"
                   "  atmo render --model reference --spp 64 --width 160 --height 90 -o ref" + lists},
      {sample_app, "Examples:\n  atmo sample --altitude 0 --sun-zenith 60 --view-zenith 80 --azimuth 90\n"
                   "  atmo sample --grid grid.csv --out radiance.csv   (--grid -: standard input)" + lists},
      {compare_app, "Example:\n  atmo compare --model hillaire --option multiple_scattering_directions=2 --against "
                    "hillaire" + lists},
      {presets_app, "Examples:\n  atmo presets\n  atmo presets --dump earth > hazy.json" + lists},
      {bench_app, "Example:\n  atmo bench --quick --width 320 --height 180" + lists},
      {precompute_app, "Examples:\n  atmo precompute --preset atmosphere-plus --out ap_table   (elek: ap_table.exr, "
                       ".raw, .json, ap_table_transmittance.exr, .raw)\n"
                       "  atmo precompute --model hillaire --altitude 100 --sun-elevation 20 --out sky   (sky.json, "
                       "sky_<table>.exr, .raw)" + lists},
      {illuminance_app, "Example:\n  atmo illuminance --preset earth-spectral --sun-elevation 10 30 60" + lists},
      {irradiance_app, "Example (model source4d on us-standard unless given):\n  atmo irradiance --sun-elevation 40 "
                       "--plane 0:180 --plane 35:180 --plane 90:90 --plane sun" + lists},
      {annual_app, "Example (model source4d on us-standard unless given):\n  atmo annual --epw site.epw --out-dir "
                   "year --plane 30:180\n  atmo annual --epw site.epw --out-dir year --shard 3/16   (one job of an array)" +
                       lists},
      {calibrate_app, "Example (model source4d on us-standard unless given):\n  atmo calibrate --sun-elevation 45 "
                      "--direct-normal-lux 80000 --diffuse-horizontal-lux 14000 --out sky.json" + lists},
  };
  for (const auto& [sub, footer] : footers) {
    sub->footer(footer);
    GroupFlags(sub);
  }
  app.footer("Run `atmo SUBCOMMAND --help` for its flags and an example." + lists.substr(1));

  try {
    app.parse(argc, argv);
    if (sample_app->parsed() && sample.grid_path.empty()) {
      for (CLI::Option* option : single) {
        if (option->count() == 0 && !(option == single[1] && (!sample.sun.date.empty() || sample_sun_elevation))) {
          throw CLI::RequiredError(option->get_name() + " (or --grid)");
        }
      }
    }
  } catch (const CLI::Success& success) {
    return app.exit(success);  // --help, --version
  } catch (const CLI::ParseError& error) {
    PrintError(error.what() + DidYouMean(app, argc, argv));
    return 2;
  }

  if (app.get_subcommands().empty()) {
    std::fputs(app.help().c_str(), stderr);
    return 2;
  }
  if (sample_app->parsed() && sample_paths) common.options.push_back("samples=" + std::to_string(*sample_paths));
  if (sample_app->parsed() && target_rel_error) {
    common.options.push_back(atmo::cli::Format("target_rel_error=%.17g", *target_rel_error));
  }
  if (!table.empty()) common.options.push_back("table=" + table);
  if (sample_app->parsed() && sample_sun_elevation) sample.sun_zenith_deg = 90.0 - *sample_sun_elevation;
  if (precompute_app->parsed() && precompute_app->get_option("--model")->count() == 0) common.model = "elek";
  if (precompute_app->parsed() && common.model != "hillaire") {
    for (CLI::Option* option : hillaire_flags) {
      if (option->count() > 0) PrintWarning(option->get_name() + " applies to --model hillaire only");
    }
  }
  if (compare_app->parsed() && compare.image_path.empty()) {
    for (const char* flag : {"--altitude", "--sun-zenith", "--image-range", "--image-size"}) {
      if (compare_app->get_option(flag)->count() > 0) PrintWarning(std::string(flag) + " applies to the --image only");
    }
  }
  if (render_app->parsed()) atmo::cli::FinishRenderFlags(render_app, render, render_flags);
  for (CLI::App* sub : app.get_subcommands()) {
    const CLI::Option* model_flag = sub->get_option_no_throw("--model");
    const CLI::Option* preset_flag = sub->get_option_no_throw("--preset");
    common.model_given = model_flag != nullptr && model_flag->count() > 0;
    common.preset_given = preset_flag != nullptr && preset_flag->count() > 0;
  }

  try {
    std::optional<oneapi::tbb::global_control> thread_limit;
    if (common.threads > 0) {
      thread_limit.emplace(oneapi::tbb::global_control::max_allowed_parallelism,
                           static_cast<std::size_t>(common.threads));
    }
    if (!common.max_memory.empty()) atmo::SetMemoryLimitBytes(atmo::ParseByteSize(common.max_memory));
    atmo::SetTableCache(atmo::cli::TableCacheFor(common));
    // Long precomputations announce their estimate and passes (atmo::SetProgressHandler).
    atmo::SetProgressHandler([](const std::string& message) { std::fprintf(stderr, "atmo: %s\n", message.c_str()); });
    // render, sample and illuminance give the accurate model on the real sky unless told otherwise
    // (the daylighting commands do the same, daylight_commands.cc); bench, compare and precompute
    // keep hillaire (the real-time model) and elek on earth.
    if (render_app->parsed() || sample_app->parsed() || illuminance_app->parsed()) {
      if (!common.model_given) common.model = kAccurateModel;
      if (!common.preset_given && common.config.empty()) common.preset = kAccuratePreset;
    }
    if (render_app->parsed()) return atmo::cli::RunRender(common, render);
    if (sample_app->parsed()) return atmo::cli::RunSample(common, sample);
    if (compare_app->parsed()) return atmo::cli::RunCompare(common, compare);
    if (presets_app->parsed()) return atmo::cli::RunPresets(common, presets);
    if (bench_app->parsed()) return atmo::cli::RunBench(common, bench);
    if (precompute_app->parsed()) return atmo::cli::RunPrecompute(common, precompute);
    if (illuminance_app->parsed()) return atmo::cli::RunIlluminance(common, illuminance);
    if (irradiance_app->parsed()) return atmo::cli::RunIrradiance(common, irradiance);
    if (calibrate_app->parsed()) return atmo::cli::RunCalibrate(common, calibrate);
    if (annual_app->parsed()) return atmo::cli::RunAnnual(common, annual);
    return 2;
  } catch (const atmo::Error& error) {
    PrintError(error.what());
  } catch (const std::bad_alloc&) {
    // Sizes are checked against --max-memory before the large allocations; this is what the
    // machine refused below that limit.
    PrintError("out of memory: the machine refused an allocation below the --max-memory limit of " +
               atmo::FormatBytes(static_cast<double>(atmo::MemoryLimitBytes())) +
               " (lower --max-memory, or the sizes asked for)");
  } catch (const std::exception& error) {
    PrintError(error.what());
  }
  return 1;
}
