// The flags shared by the `atmo` programs (cli_flags.h).
#include "cli_flags.h"

#include <cctype>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <filesystem>

#include "atmo/engine_target.h"
#include "atmo/model.h"
#include "atmo/parameters.h"
#include "atmo/render.h"

namespace atmo::cli {

void PrintWarning(const std::string& message) { std::fprintf(stderr, "atmo: warning: %s\n", message.c_str()); }

// Rejects "nan", "inf" and anything that is not a number (CLI11 would accept nan and inf).
const CLI::Validator kFinite = CLI::Validator(
    [](std::string& text) -> std::string {
      char* end = nullptr;
      const double value = std::strtod(text.c_str(), &end);
      if (text.empty() || end != text.c_str() + text.size()) return "'" + text + "' is not a number";
      if (!std::isfinite(value)) return "must be a finite number, got '" + text + "'";
      return {};
    },
    "FINITE", "FINITE");

// An integer, checked before a range so that `--width abc` says so (CLI11's Range said "not in range").
const CLI::Validator kInteger = CLI::Validator(
    [](std::string& text) -> std::string {
      char* end = nullptr;
      (void)std::strtoll(text.c_str(), &end, 10);
      if (text.empty() || end != text.c_str() + text.size()) return "'" + text + "' is not an integer";
      return {};
    },
    "", "INTEGER");

// "a, b, c": the names a --help lists.
std::string JoinNames(const std::vector<std::string>& names) {
  std::string text;
  for (const std::string& name : names) text += (text.empty() ? "" : ", ") + name;
  return text;
}

const CLI::Validator kPositive = CLI::Validator(
    [](std::string& text) -> std::string {
      char* end = nullptr;
      const double value = std::strtod(text.c_str(), &end);
      if (!(value > 0.0)) return "must be positive, got '" + text + "'";
      return {};
    },
    "POSITIVE", "POSITIVE");

// [min, max] for a floating-point value, printed with %g (CLI::Range prints "0.000000").
CLI::Validator RangeOf(double min, double max) {
  return CLI::Validator(
      [min, max](std::string& text) -> std::string {
        const double value = std::strtod(text.c_str(), nullptr);
        if (value >= min && value <= max) return {};
        return Format("%s is outside [%g, %g]", text.c_str(), min, max);
      },
      Format("[%g, %g]", min, max));
}

// (min, max), open: for the perspective field of view.
CLI::Validator OpenRangeOf(double min, double max) {
  return CLI::Validator(
      [min, max](std::string& text) -> std::string {
        const double value = std::strtod(text.c_str(), nullptr);
        if (value > min && value < max) return {};
        return Format("%s is outside (%g, %g)", text.c_str(), min, max);
      },
      Format("(%g, %g)", min, max));
}

// Adds a floating-point option that must be finite.
CLI::Option* AddNumber(CLI::App* app, const std::string& name, double& value, const std::string& help) {
  return app->add_option(name, value, help)->check(kFinite)->capture_default_str();
}

// An option whose default depends on other values: set only when given.
CLI::Option* AddOptionalNumber(CLI::App* app, const std::string& name, std::optional<double>& value,
                               const std::string& help) {
  return app
      ->add_option_function<double>(
          name, [&value](const double& v) { value = v; }, help)
      ->check(kFinite);
}

// Read as a signed integer: CLI11 converts "-4" to an unsigned type by wrapping it (the error
// then showed 18446744073709551612); a negative count now reaches the range check as given.
CLI::Option* AddPathCount(CLI::App* app, const std::string& name, std::optional<std::uint64_t>& value,
                          const std::string& help) {
  return app
      ->add_option_function<std::int64_t>(
          name, [&value](const std::int64_t& n) { value = static_cast<std::uint64_t>(n); }, help)
      ->check(kInteger);
}

void AddCommonOptions(CLI::App* app, CommonOptions& common) {
  app->add_option("--model", common.model, "sky model: " + JoinNames(atmo::ModelNames()))->capture_default_str();
  CLI::Option* preset =
      app->add_option("--preset", common.preset, "parameter preset: " + JoinNames(atmo::PresetNames()) +
                                                     " (`atmo presets` describes them)")
          ->capture_default_str();
  CLI::Option* config =
      app->add_option("--config", common.config, "parameters as a JSON file (instead of --preset)");
  preset->excludes(config);
  app->add_option("--backend", common.backend, "cpu, or gl (OpenGL compute: render, sample, precompute, bench of hillaire and elek; render, sample, bench of source4d)")
      ->check(CLI::IsMember({"cpu", "gl"}))
      ->capture_default_str();
  app->add_option("--threads", common.threads, "worker threads (default: all cores)")
      ->check(kInteger)
      ->check(CLI::Range(1, 1024));
  app->add_option("--max-memory", common.max_memory,
                  "refuse work whose tables and images would need more memory than SIZE (e.g. 4G, 512M; "
                  "default: half of this machine's memory; docs/reliability.md)");
  app->add_option("--source4d-tables", common.source4d_tables,
                  "with --backend gl, where source4d's tables come from: gpu (built there), cpu (the CPU's, from the "
                  "table cache or the shipped tables where they are, uploaded) or auto (cpu on a software GL such as "
                  "llvmpipe, gpu on a hardware GPU); bench always times the GPU's")
      ->check(CLI::IsMember({"gpu", "cpu", "auto"}))
      ->capture_default_str();
  app->add_option("--table-cache", common.table_cache,
                  "FOLDER where precomputed source4d and elek tables are kept for later runs, or off (default: "
                  "$ATMO_TABLE_CACHE, else $XDG_CACHE_HOME/atmo/tables, else ~/.cache/atmo/tables; docs/cli.md)");
  // Read as text: CLI11's unsigned conversion wrapped -1 to 2^64 - 1 and refused 20-digit seeds.
  app->add_option_function<std::string>(
         "--seed",
         [&common](const std::string& text) {
           common.seed = *ParseSeed(text);
           common.seed_given = true;
         },
         "random seed for Monte Carlo models, an integer in [0, 18446744073709551615] (deterministic models "
         "ignore it)")
      ->check(CLI::Validator(
          [](std::string& text) -> std::string {
            if (ParseSeed(text)) return {};
            return "'" + text + "' is not an integer in [0, 18446744073709551615]";
          },
          "SEED", "SEED"));
  app->add_option("--option", common.options,
                  "model setting KEY=VALUE (repeatable); the keys are in docs/models/MODEL.md#options, and an "
                  "unknown key's error lists the model's keys")
      ->expected(1)
      ->take_all();
  app->add_option("--spectral", common.spectral,
                  "resample the atmosphere to N wavelengths over 360-830 nm, each medium by its physics "
                  "(docs/spectral.md)")
      ->check(kInteger)
      ->check(CLI::Range(3, 256));
  app->add_option("--wavelengths", common.wavelengths,
                  "resample the atmosphere to these wavelengths in nm (increasing, within 360-830; each channel "
                  "stands for the band halfway to its neighbours), each medium by its physics (docs/spectral.md)")
      ->expected(1, 256)
      ->delimiter(',')
      ->excludes("--spectral");
  // The aerosol knobs (docs/aerosols.md); their values are checked by atmo::ApplyAerosolRequest,
  // whose one-line errors name the bounds.
  app->add_option_function<std::string>(
      "--aerosol", [&common](const std::string& v) { common.aerosol.type = v; },
      "aerosol type (OPAC): " + JoinNames(atmo::AerosolTypeNames()) + "; replaces the preset's Mie medium");
  app->add_option_function<double>(
      "--aod", [&common](const double& v) { common.aerosol.aod_550 = v; },
      "aerosol optical depth at 550 nm, in [0, 10] [default: the type's typical]");
  app->add_option_function<double>(
      "--angstrom", [&common](const double& v) { common.aerosol.angstrom_exponent = v; },
      "Angstrom exponent in [-1, 4]: tau(lambda) = aod (lambda / 550 nm)^-alpha [default: the type's spectrum]");
  app->add_option_function<double>(
      "--visibility", [&common](const double& v) { common.aerosol.visibility_km = v; },
      "meteorological visibility in km (Koschmieder): sets the aerosol optical depth");
  app->add_option_function<double>(
      "--turbidity", [&common](const double& v) { common.aerosol.linke_turbidity = v; },
      "Linke turbidity factor (air mass 2, Ineichen 2008): sets the aerosol optical depth");
  app->add_option_function<std::string>(
      "--aerosol-phase", [&common](const std::string& v) { common.aerosol.phase = v; },
      "the aerosol's phase function: opac (OPAC's own, tabulated) or henyey-greenstein (its asymmetry g) "
      "[default: opac]");
}

// --date, --latitude, --longitude, --refraction (sun_options.h): the sun from a date and a place.
// A date needs a place and a place a date. Returns the --date option, for the caller's excludes.
CLI::Option* AddSunOptions(CLI::App* app, SunOptions& sun) {
  CLI::Option* date = app->add_option(
      "--date", sun.date,
      "ISO 8601 date-time with a zone (2026-06-21T12:00+02:00, 2026-06-21T10:00Z): the sun of that instant "
      "at --latitude, --longitude");
  CLI::Option* latitude = AddOptionalNumber(app, "--latitude", sun.latitude_deg,
                                            "observer latitude in degrees, north positive (with --date)")
                              ->check(RangeOf(-90.0, 90.0));
  CLI::Option* longitude = AddOptionalNumber(app, "--longitude", sun.longitude_deg,
                                             "observer longitude in degrees, east positive (with --date)")
                               ->check(RangeOf(-180.0, 180.0));
  CLI::Option* refraction = app->add_flag(
      "--refraction", sun.refraction,
      "the apparent (refracted, 1010 mbar, 10 C) sun elevation instead of the geometric one (with --date)");
  for (CLI::Option* option : {latitude, longitude, refraction}) option->needs(date);
  date->needs(latitude)->needs(longitude);
  return date;
}

void AddMoonOptions(CLI::App* app, MoonOptions& moon, CLI::Option* date) {
  CLI::Option* elevation = AddOptionalNumber(app, "--moon-elevation", moon.elevation_deg,
                                             "a moon by hand: its elevation in degrees, [-90, 90] (with --moon-phase)")
                               ->check(RangeOf(-90.0, 90.0));
  CLI::Option* azimuth = AddOptionalNumber(app, "--moon-azimuth", moon.azimuth_deg,
                                           "its compass azimuth in degrees [default: opposite the sun]")
                             ->check(RangeOf(-360.0, 360.0));
  CLI::Option* phase = AddOptionalNumber(app, "--moon-phase", moon.phase_deg,
                                         "its phase angle in degrees, [0, 180]: 0 full, 90 quarter, 180 new")
                           ->check(RangeOf(0.0, 180.0));
  CLI::Option* none = app->add_flag("--no-moon", moon.no_moon, "leave the moon of --date out");
  for (CLI::Option* option : {elevation, azimuth, phase}) {
    if (date != nullptr) option->excludes(date);
    option->excludes(none);
  }
}

void AddRenderFlags(CLI::App* app, RenderCommand& render, RenderFlags& flags) {
  app->add_option("--camera", render.camera, "perspective, fisheye, equirect or cubemap")
      ->check(CLI::IsMember({"perspective", "fisheye", "equirect", "cubemap"}))
      ->capture_default_str();
  const std::string side_help = " in pixels";
  app->add_option("--width", render.width, "image width" + side_help)
      ->check(kInteger)
      ->check(CLI::Range(1, kMaxImageSide))
      ->capture_default_str();
  app->add_option("--height", render.height, "image height" + side_help)
      ->check(kInteger)
      ->check(CLI::Range(1, kMaxImageSide))
      ->capture_default_str();
  AddNumber(app, "--fov", render.fov_deg, "horizontal field of view in degrees (perspective)")
      ->check(OpenRangeOf(0.0, 180.0));
  AddOptionalNumber(app, "--yaw", render.yaw_deg,
                    "compass azimuth of the view centre (fisheye: of the image's top) in degrees "
                    "[default: the sun's; fisheye: 0, north up]");
  app->add_option("--target", render.target,
                  "write the equirect as this program reads it, fixed in the world: " + atmo::EngineTargetNames() +
                      " (docs/environment.md)");
  AddNumber(app, "--pitch", render.pitch_deg, "elevation of the view in degrees")
      ->check(RangeOf(-90.0, 90.0));
  AddNumber(app, "--sun-elevation", render.sun_elevation_deg, "sun elevation in degrees")
      ->check(RangeOf(-90.0, 90.0));
  AddNumber(app, "--sun-azimuth", render.sun_azimuth_deg, "sun compass azimuth in degrees");
  AddOptionalNumber(app, "--altitude", render.altitude_m,
                    "observer altitude in metres [default: the preset's]")
      ->check(RangeOf(-kMaxAltitude_m, kMaxAltitude_m));
  CLI::Option* exposure = AddOptionalNumber(app, "--exposure", render.exposure,
                                            "linear exposure multiplier of the PNG (docs/display.md) [default: "
                                            "auto-exposure; a relative 3-channel render: the preset's]")
                              ->check(RangeOf(kMinExposure, kMaxExposure));
  // EV100 within [-32, 32]: exposures 1/(1.2 2^EV) in [1.9e-10, 3.6e9], inside the exposure bounds.
  CLI::Option* ev = AddOptionalNumber(app, "--ev", render.ev100,
                                      "exposure as EV100 in [-32, 32] (photographic; 1/(1.2 2^EV) on cd/m^2), "
                                      "e.g. 15 for sunny noon, 9 for sunset, 4 for civil twilight")
                        ->check(RangeOf(-kMaxEv100, kMaxEv100))
                        ->excludes(exposure);
  app->add_flag("--auto-exposure", render.auto_exposure,
                       "EV100 from the image's log-average luminance (the default for physical units)")
      ->excludes(exposure)
      ->excludes(ev);
  app->add_option("--metering", render.metering,
                  "how auto-exposure places the average: adaptive (a noon sky bright, twilight darker, "
                  "as the eye adapts) or camera (every sky a mid grey)")
      ->check(CLI::IsMember({"adaptive", "camera"}))
      ->capture_default_str();
  app->add_option("--tonemap", render.tonemap,
                  "agx (highlights roll off to white), or exp, aces, none on the luminance with hue kept "
                  "[default: agx; exp for a relative 3-channel render or with --per-channel]")
      ->check(CLI::IsMember({"agx", "exp", "aces", "none"}));
  app->add_option_function<double>(
                "--gamma", [&render](const double& g) { render.gamma = g; },
                "a bare display gamma instead of the sRGB transfer function (the seed's curve: 2.2)")
      ->check(kFinite)
      ->check(RangeOf(0.1, 10.0));
  app->add_flag("--per-channel", render.per_channel,
                       "tone-map each channel apart (the seed's look) instead of the luminance");
  app->add_flag("--no-dither", render.no_dither, "8-bit PNG without dithering (shows contour bands)");
  app->add_option("--png-bits", render.png_bits, "PNG bits per sample: 8 or 16")
      ->check(CLI::IsMember({8, 16}))
      ->capture_default_str();
  app->add_flag("--no-sun-disc", render.no_sun_disc, "leave the sun disc out");
  AddOptionalNumber(app, "--sun-size", render.sun_size_deg,
                    "angular diameter of the sun disc in degrees, in (0, 20] [default: the preset's]");
  app->add_flag("--no-ground", render.no_ground,
                       "leave the light reflected by the ground out (rays that meet it show only the air in front)");
  app->add_flag("--no-night-glow", render.no_night_glow,
                "leave the night sky's own light out: airglow, zodiacal light, integrated starlight (docs/night.md)");
  CLI::Option* exr_flag =
      app->add_option("--exr", render.exr_path, "linear EXR output, F.exr (empty: none)")->capture_default_str();
  CLI::Option* png_flag = app->add_option("--png", render.png_path, "tone-mapped PNG output, F.png (empty: none)")
                              ->capture_default_str();
    app
      ->add_option("-o,--output", flags.output,
                   "NAME: write NAME.exr and NAME.png; NAME.exr or NAME.png: only that file (instead of --exr, --png)")
      ->excludes(exr_flag)
      ->excludes(png_flag);
  app->add_flag("--no-exr", flags.no_exr, "write no EXR (the same as --exr \"\")")->excludes(exr_flag);
  app->add_flag("--no-png", flags.no_png, "write no PNG (the same as --png \"\")")->excludes(png_flag);
  app->add_option("--unit", render.unit,
                         "what the EXR holds: luminance (linear sRGB, cd/m^2), radiance (W m^-2 sr^-1 nm^-1 per "
                         "wavelength) or relative (per unit solar irradiance x solar_irradiance)")
      ->check(CLI::IsMember({"luminance", "radiance", "relative"}))
      ->capture_default_str();
  app->add_flag("--xyz", render.xyz, "with --unit luminance: CIE 1931 XYZ channels instead of linear sRGB");
  AddPathCount(app, "--spp,--samples", render.spp,
               "Monte Carlo paths per pixel, rendered progressively in passes of 4, 8, 16, ... "
               "(model reference only; --samples is the same flag, as in `atmo sample`) [default: its samples option]")
      ->check(CLI::Range(std::int64_t{2}, std::int64_t{1} << 40));

  // The sun from a date (sun_options.h) instead of --sun-elevation and --sun-azimuth, and the time-lapse.
  // --camera cubemap and its environment outputs (docs/environment.md).
  app->add_option("--face-size", render.face_size, "cubemap face size in texels")
      ->check(CLI::Range(1, kMaxImageSide))
      ->capture_default_str();
  app->add_option("--ktx2", render.ktx2_path, "cubemap: KTX 2.0 cubemap output (RGBA16F)");
  app->add_flag("--ktx2-float", render.ktx2_float32, "cubemap: KTX2 outputs in RGBA32F instead of RGBA16F");
  app->add_flag("--mips", render.mips, "cubemap: the --ktx2 file with its box-filtered mip chain");
  app->add_option("--sh", render.sh_path, "cubemap: L2 spherical harmonics of the radiance, JSON");
  app->add_option("--irradiance", render.irradiance_path,
                         "cubemap: diffuse irradiance cube map (OpenEXR cube for *.exr, else KTX2)");
  app->add_option("--irradiance-size", render.irradiance_size, "cubemap: irradiance face size")
      ->check(CLI::Range(1, 1024))
      ->capture_default_str();
  app->add_option("--specular", render.specular_path, "cubemap: GGX-prefiltered specular mip chain, KTX2");
  app->add_option("--hdr-faces", render.hdr_faces,
                  "cubemap: six Radiance HDR faces NAME_px.hdr .. NAME_nz.hdr (with --target three: for three.js's "
                  "HDRCubeTextureLoader)");
  app->add_option("--specular-levels", render.specular_levels,
                         "cubemap: specular levels (roughness = level / (levels - 1))")
      ->check(CLI::Range(1, 15))
      ->capture_default_str();
  app->add_option("--specular-samples", render.specular_samples, "cubemap: GGX samples per specular texel")
      ->check(CLI::Range(1, 4096))
      ->capture_default_str();
  CLI::Option* render_date = AddSunOptions(app, render.sun);
  render_date->excludes(app->get_option("--sun-elevation"))->excludes(app->get_option("--sun-azimuth"));
  AddMoonOptions(app, render.moon, render_date);
  CLI::Option* no_stars = app->add_flag("--no-stars", render.no_stars, "leave the stars out (docs/night.md)");
  app->add_flag("--night-vision", render.night_vision,
                "the PNG as the eye sees in the dark: mesopic and scotopic vision (CIE 191), colour fading to blue-grey "
                "(docs/night.md); the EXR stays physical");
  app->add_option("--star-catalogue", render.star_catalogue,
                  "folder of Stellarium 0.22 star files (stars_0_0v0_8.cat, stars_1_0v0_8.cat) [default: Debian's "
                  "stellarium-data, /usr/share/stellarium/stars/default, when installed]")
      ->excludes(no_stars);
  CLI::Option* until = app->add_option(
      "--until", render.sun.until, "time-lapse: frames from --date every --step up to this ISO 8601 date-time");
  CLI::Option* step = app->add_option("--step", render.sun.step, "time-lapse step: 10min, 30s, 1h30min, 2d");
  CLI::Option* mp4 = app->add_option(
      "--mp4", render.sun.mp4_path, "time-lapse: also assemble the PNG frames into this H.264 MP4 (needs ffmpeg on PATH)");
  AddNumber(app, "--fps", render.sun.fps, "frames per second of the --mp4")->check(RangeOf(0.1, 1000.0))->needs(mp4);
  until->needs(render_date)->needs(step);
  step->needs(until);
  mp4->needs(until);
}

void FinishRenderFlags(CLI::App* app, RenderCommand& render, const RenderFlags& flags, bool png_only_warnings) {
  render.output_name = flags.output;
  if (!flags.output.empty()) {
    std::string extension = std::filesystem::path(flags.output).extension().string();
    for (char& c : extension) c = static_cast<char>(std::tolower(static_cast<unsigned char>(c)));
    render.exr_path = extension == ".png" ? std::string() : extension == ".exr" ? flags.output : flags.output + ".exr";
    render.png_path = extension == ".exr" ? std::string() : extension == ".png" ? flags.output : flags.output + ".png";
  }
  if (flags.no_exr) render.exr_path.clear();
  if (flags.no_png) render.png_path.clear();
  // --target writes an equirect: the camera unless --camera says otherwise (PlanRender refuses
  // another), 2048 x 1024 unless the size is given.
  if (!render.target.empty() && app->get_option("--camera")->count() == 0) render.camera = "equirect";
  if (!render.target.empty() && app->get_option("--width")->count() == 0 && app->get_option("--height")->count() == 0) {
    render.width = 2048;
    render.height = 1024;
  }
  // Flags that the chosen camera or outputs do not use: said, not silently ignored.
  if (render.camera != "perspective") {
    for (const char* flag : {"--fov", "--pitch"}) {
      if (app->get_option(flag)->count() > 0) {
        PrintWarning(std::string(flag) + " applies to the perspective camera only");
      }
    }
  }
  if (png_only_warnings && render.png_path.empty()) {
    for (const char* flag : {"--exposure", "--ev", "--auto-exposure", "--metering", "--tonemap", "--gamma",
                             "--per-channel", "--no-dither", "--png-bits"}) {
      if (app->get_option(flag)->count() > 0) PrintWarning(std::string(flag) + " applies to the PNG only");
    }
  }
}

}  // namespace atmo::cli
