// The subcommands of the `atmo` program, one function each, behind plain option structs.
//
// main.cc owns the command-line parsing (CLI11 lives in that one file only) and fills these
// structs; each Run* function calls the library and reports. Every Run* function throws
// atmo::Error with a one-line message for anything the user got wrong, and returns the exit code.
#pragma once

#include <cstdint>
#include <filesystem>
#include <memory>
#include <optional>
#include <string>
#include <vector>

#include "atmo/aerosol.h"
#include "atmo/colour.h"
#include "atmo/cubemap.h"
#include "atmo/engine_target.h"
#include "atmo/table_cache.h"
#include "atmo/image.h"
#include "atmo/model.h"
#include "atmo/parameters.h"
#include "atmo/render.h"
#include "atmo/timing.h"
#include "sun_options.h"
#ifdef ATMO_HAVE_GL
#include "gl/context.h"
#include "models/elek_model.h"
#include "models/hillaire_model.h"
#include "models/source4d_model.h"
#endif

namespace atmo::cli {

// The flags every subcommand takes (docs/design.md §4).
struct CommonOptions {
  std::string model = "hillaire";
  std::string preset = "earth";
  // Whether --model and --preset were given (the daylighting commands default to source4d on
  // us-standard).
  bool model_given = false;
  bool preset_given = false;
  std::string config;  // a JSON parameters file; when set, `preset` is not used
  std::string backend = "cpu";
  int threads = 0;  // 0: oneTBB's default
  std::string max_memory;  // --max-memory SIZE (atmo::ParseByteSize); empty: half the machine's memory
  std::string table_cache;  // --table-cache FOLDER|off; empty: atmo::DefaultTableCache()
  // --source4d-tables gpu|cpu|auto: on --backend gl, where source4d's tables come from
  // (Source4dTablesFromCpu); `atmo bench` always times the GPU's build.
  std::string source4d_tables = "auto";
  // Accepted for every model. Deterministic models ignore it; a Monte Carlo model will receive it
  // (see CreateModelFor).
  std::uint64_t seed = 0;
  bool seed_given = false;
  std::vector<std::string> options;  // KEY=VALUE strings for atmo::ModelOptions
  // --spectral N: resample the parameters to N wavelengths over 360..830 nm (atmo::MakeSpectral);
  // 0: as they are.
  int spectral = 0;
  // --wavelengths W...: resample to these wavelengths instead (the other form of MakeSpectral).
  std::vector<double> wavelengths;
  // --aerosol, --aod, --angstrom, --visibility, --turbidity (atmo::ApplyAerosolRequest), applied
  // after --spectral.
  AerosolRequest aerosol;
};

// The parameters named by --preset or --config, made spectral by --spectral. Throws atmo::Error.
AtmosphereParameters LoadParameters(const CommonOptions& common);
// Parses KEY=VALUE strings; throws atmo::Error for a malformed or repeated one.
ModelOptions ParseModelOptions(const std::vector<std::string>& options);
// Throws atmo::Error for a backend this build does not have, or gl for a command without a gl path
// (`command_has_gl` false) or a model other than hillaire, elek and source4d.
void CheckBackend(const CommonOptions& common, bool command_has_gl = false);
#ifdef ATMO_HAVE_GL
// The --option settings of models hillaire, elek and source4d (the "seed" option dropped, as on
// the CPU).
HillaireSettings GlHillaireSettings(const CommonOptions& common);
ElekSettings GlElekSettings(const CommonOptions& common);
Source4dModelSettings GlSource4dSettings(const CommonOptions& common);
// Whether source4d's tables on the gl backend are the CPU's (computed on the CPU or read from the
// table cache or the shipped tables, then uploaded): --source4d-tables cpu, or auto on a software
// GL such as llvmpipe, where the GPU's passes run on the same cores ~30x slower than the CPU's
// build and the cache cannot serve them. gpu, or auto on a hardware GPU: built there.
bool Source4dTablesFromCpu(const CommonOptions& common, const gl::Context& context);
// Renders model hillaire, elek or source4d on the gl backend (--option settings as for the CPU
// model), each pass's GPU time into `timings`: every table and the frame are GPU passes, except
// source4d's where Source4dTablesFromCpu (then its tables' upload, source4d_gl_upload, and the
// frame). With `gpu_tables`, source4d's tables are built on the GPU whatever the flag says (bench).
Image RenderOnGl(const gl::Context& context, const CommonOptions& common, const AtmosphereParameters& parameters,
                 const RenderSettings& settings, PassTimings* timings = nullptr, bool gpu_tables = false);
#endif
// Creates (and so precomputes) the model named by --model with the --option settings. With
// --backend gl, models elek and source4d compute their tables on the GPU (gl::PrecomputeElekGl,
// gl::PrecomputeSource4dGl) and answer from them (source4d: unless Source4dTablesFromCpu, then
// the CPU's model as on --backend cpu); other models throw atmo::Error there.
std::unique_ptr<Model> CreateModelFor(const CommonOptions& common, const AtmosphereParameters& parameters);
// atmo::DefaultTableCache(), its folder replaced by --table-cache's (a folder; off: none, the
// shipped tables are still read). Throws atmo::Error for a path that exists and is not a folder.
TableCache TableCacheFor(const CommonOptions& common);
// Fails fast, before heavy work, when `path` cannot be written: its folder is missing or not
// writable, or the path is a folder.
void CheckOutputWritable(const std::filesystem::path& path);

// Refuses, in one line, an output whose extension is not the one of its format (`--png x.jpg`
// wrote PNG data): `extension` such as ".png", compared without regard to case. Empty paths pass.
void CheckExtension(const std::string& flag, const std::filesystem::path& path, const std::string& extension);

// A flag and the path it names, e.g. {"--grid", "in.csv"}.
struct NamedPath {
  std::string flag;
  std::filesystem::path path;
};
// Refuses, in one line and before any work, an output that names the same file as an input (the
// --config, the tables of --table, and `inputs`) or as another output: they were silently
// overwritten. Empty paths are skipped; existing files are compared by identity (links included).
void CheckOutputsApart(const CommonOptions& common, std::vector<NamedPath> inputs,
                       const std::vector<NamedPath>& outputs);

// A --seed or seed=N: a decimal integer in [0, 2^64 - 1], digits only (no sign, no spaces).
std::optional<std::uint64_t> ParseSeed(const std::string& text);
// printf-style formatting into a std::string.
std::string Format(const char* format, ...) __attribute__((format(printf, 1, 2)));

struct RenderCommand {
  std::string camera = "perspective";
  int width = 1280;
  int height = 720;
  double fov_deg = 90.0;
  std::optional<double> yaw_deg;
  std::string target;  // --target: an equirect in a program's convention (empty: none)
  std::string output_name;  // -o NAME as given (exr_path and png_path hold what it means)  // default: the sun azimuth (look towards the sun)
  double pitch_deg = 10.0;
  double sun_elevation_deg = 10.0;
  double sun_azimuth_deg = 180.0;
  std::optional<double> altitude_m;  // default: parameters.observer_altitude_m
  // Display (docs/display.md): a linear exposure multiplier, or EV100, or auto-exposure (the
  // default for physical units; a relative 3-channel render defaults to parameters.exposure).
  std::optional<double> exposure;
  std::optional<double> ev100;
  bool auto_exposure = false;
  std::string metering = "adaptive";  // how auto-exposure places the average (atmo::Metering)
  // Empty: agx, except exp for a relative 3-channel render or with --per-channel (the seeds' look).
  std::string tonemap;
  std::optional<double> gamma;  // given: the bare gamma transfer instead of sRGB
  bool per_channel = false;     // the curve per channel (the seed's look) instead of on luminance
  bool no_dither = false;
  int png_bits = 8;
  bool no_sun_disc = false;
  std::optional<double> sun_size_deg;  // the sun's angular diameter; default: 2 x sun_angular_radius_rad
  bool no_ground = false;
  bool no_night_glow = false;  // leave the airglow and zodiacal light out (NightSkySettings::enabled)
  MoonOptions moon;            // --moon-*, --no-moon
  bool no_stars = false;       // leave the stars out
  bool night_vision = false;   // the PNG as the eye sees in the dark (include/atmo/night_vision.h)
  std::string star_catalogue;  // a folder of Stellarium star files; empty: Debian's stellarium-data if installed
  std::string exr_path = "sky.exr";  // empty: no EXR
  std::string png_path = "sky.png";  // empty: no PNG
  // Monte Carlo paths per pixel (model reference only; default: its `samples` option).
  std::optional<std::uint64_t> spp;
  // What the EXR holds (atmo/colour.h): luminance (linear sRGB, Y in cd/m^2; XYZ with --xyz),
  // radiance (W m^-2 sr^-1 nm^-1 per wavelength) or relative (the model's channels x
  // solar_irradiance, as before physical units).
  std::string unit = "luminance";
  bool xyz = false;
  // --date etc.: the sun from a date and place instead of the two angles above; --until: a time-lapse.
  SunOptions sun;
  // --camera cubemap (docs/environment.md): the face size, and the outputs beyond --exr / --png
  // (which hold the six faces stacked vertically, OpenEXR's cube-map layout). Empty: none.
  int face_size = 256;
  std::string ktx2_path;        // KTX 2.0 cubemap (RGBA16F; RGBA32F with ktx2_float32)
  bool ktx2_float32 = false;    // every KTX2 output in RGBA32F
  bool mips = false;            // the KTX2 cubemap with its box-filtered mip chain down to 1 texel
  std::string sh_path;          // L2 spherical harmonics, JSON
  std::string irradiance_path;  // diffuse irradiance cube map: OpenEXR cube for *.exr, else KTX2
  int irradiance_size = 32;
  std::string specular_path;    // GGX-prefiltered specular mip chain, KTX2
  // Six Radiance HDR faces NAME_px.hdr, NAME_nx.hdr, ... NAME_nz.hdr (three.js's names and order), in
  // the cube frame's GL convention, or as three's CubeTexture wants them with --target three.
  std::string hdr_faces;
  int specular_levels = 6;
  int specular_samples = 32;
};
int RunRender(const CommonOptions& common, const RenderCommand& command);

// What `atmo render` makes of its flags before it renders: the atmosphere, the unit, the frame's
// settings (camera, observer, sun, terms) and the PNG's tone mapping. atmo-viewer (apps/viewer)
// plans its frames and screenshots with the same function, so that the same flags mean the same.
struct RenderPlan {
  AtmosphereParameters parameters;        // --preset / --config, --spectral, --sun-size
  AtmosphereParameters model_parameters;  // parameters, with solar_irradiance 1 in physical units
  RadianceUnit unit = RadianceUnit::kLuminance;
  RenderSettings settings;
  std::optional<SunAtInstant> dated_sun;  // --date
  bool cubemap = false;                   // --camera cubemap (settings.camera then perspective)
  const EngineTarget* target = nullptr;   // --target (include/atmo/engine_target.h)
  ToneMapping mapping;                    // the PNG's, before its exposure
};
// Throws atmo::Error for what RunRender rejects in these flags.
RenderPlan PlanRender(const CommonOptions& common, const RenderCommand& command);
// The star catalogue of a render (atmo render, atmo-viewer): --star-catalogue (atmo::Error if it
// cannot be read), else Debian's stellarium-data when installed; null with --no-stars, for a
// half-space, or (with a warning) when no catalogue is installed.
const StarCatalogue* LoadStarsFor(const RenderCommand& command, const AtmosphereParameters& parameters);

// The EXR and PNG outputs of `atmo render`: the image converted to the EXR's unit, the metadata
// table of docs/cli.md#atmo-render, the PNG's exposure (--exposure, --ev, auto or the preset's).
// `plan` and `command` must outlive it. Write takes the model's image per channel (relative
// radiance x model_parameters.solar_irradiance) or already linear sRGB (colour_space kLinearSrgb),
// and a Monte Carlo model's standard errors (or null); empty paths are skipped; it returns the
// paths written. Throws atmo::Error.
class RenderOutputs {
 public:
  RenderOutputs(const CommonOptions& common, const RenderCommand& command, const RenderPlan& plan,
                const std::string& model_name);
  void SetMetadata(const std::string& key, const std::string& value);  // adds or replaces
  std::vector<std::string> Write(const std::string& exr_path, const std::string& png_path, const Image& image,
                                 const Image* standard_error, double render_ms);
  double write_s() const { return write_s_; }  // seconds spent in Write so far

 private:
  const RenderCommand& command_;
  const RenderPlan& plan_;
  SpectralConversion convert_;
  ImageColour exr_colour_ = ImageColour::kLinearSrgb;
  bool legacy_png_ = false;
  ImageMetadata metadata_;
  double write_s_ = 0.0;
};
// cubemap_command.cc: whether --ktx2, --sh, --irradiance or --specular asks for output, and
// writing them from the cube (3 channels; linear sRGB when `luminance`), appending the paths.
bool WantsEnvironmentOutputs(const RenderCommand& command);
// The six files of --hdr-faces NAME: NAME_px.hdr, NAME_nx.hdr, ..., NAME_nz.hdr (none for "").
std::vector<std::string> HdrFacePaths(const std::string& name);
void WriteEnvironmentOutputs(const RenderCommand& command, const Cubemap& cube, const std::string& unit_description,
                             bool luminance, std::vector<std::string>& written);

struct SampleCommand {
  std::string grid_path;  // a CSV grid; empty: the single configuration below
  std::string out_path;   // empty: stdout
  std::optional<double> altitude_m;
  std::optional<double> sun_zenith_deg;
  std::optional<double> view_zenith_deg;
  std::optional<double> azimuth_deg;
  // relative (docs/design.md §4: sr^-1 per unit solar irradiance), radiance (W m^-2 sr^-1 nm^-1 per
  // wavelength row) or luminance (one row per point: luminance_cd_m2, stderr).
  std::string unit = "relative";
  bool night_sky = false;  // add the night sky's own light to the radiance (include/atmo/night_sky.h)
  SunOptions sun;  // --date: the sun zenith of the single query from a date and place
  // A moon (--moon-elevation, --moon-azimuth relative to the sun's azimuth, which sample puts at
  // 0, --moon-phase; or --date's): its light as the model scatters it, added to the radiance.
  MoonOptions moon;
};
int RunSample(const CommonOptions& common, const SampleCommand& command);

// `atmo compare`: --model (M) against --against (R) on a grid; see compare_command.cc.
struct CompareCommand {
  std::string against = "reference";
  std::vector<std::string> against_options;  // KEY=VALUE for the reference model
  // A file of `atmo sample` (default unit): R and its standard errors read from it, on its
  // configurations, instead of a model (excludes --against, --against-option, --grid, --image).
  std::string against_samples;
  std::string grid = "standard";  // "standard", "twilight", "space" or an IN.csv path (as `atmo sample`)
  // Rows with R <= floor x the largest R of their sky (altitude, sun zenith, channel) are left
  // out of the relative statistics.
  double floor = 1e-4;
  std::string csv_path;    // empty: none
  std::string json_path;      // empty: none
  std::string markdown_path;  // empty: none
  std::string image_path;     // empty: none
  double image_altitude_m = 0.0;
  double image_sun_zenith_deg = 60.0;
  double image_range_percent = 10.0;  // colour scale: -range .. +range
  int image_size = 256;               // pixels per fisheye
};
int RunCompare(const CommonOptions& common, const CompareCommand& command);

struct PresetsCommand {
  std::string dump;  // a preset name to print as JSON; empty: list the presets
};
int RunPresets(const CommonOptions& common, const PresetsCommand& command);

struct BenchCommand {
  int repeat = 10;
  bool quick = false;  // repeat 3 times
  int width = 1920;
  int height = 1080;
  SunOptions sun;  // --date: the frame's sun from a date and place (default: 30 degrees high, south)
  // --work-group-forms on|off|auto: GL's gl::Context::work_group_forms (auto: the context's own).
  std::string work_group_forms = "auto";
};
int RunBench(const CommonOptions& common, const BenchCommand& command);

// `atmo precompute`: computes the model's tables and exports them (model elek: NAME.exr, NAME.raw,
// NAME_transmittance.exr/.raw, NAME.json, include/atmo/elek.h; model hillaire: NAME_<table>.exr/.raw
// for six tables and NAME.json, include/atmo/hillaire_tables.h and docs/tables.md).
struct PrecomputeCommand {
  std::string out;  // NAME, without extension
  // Model hillaire: the observer and sun of the sky-view and aerial-perspective tables, and the
  // camera and size of the aerial-perspective volume (render's flags and defaults).
  std::optional<double> altitude_m;  // default: parameters.observer_altitude_m
  double sun_elevation_deg = 10.0;
  double sun_azimuth_deg = 180.0;
  SunOptions sun;  // --date: the sun from a date and place
  int width = 1280;
  int height = 720;
  double fov_deg = 90.0;
  std::optional<double> yaw_deg;  // default: the sun azimuth
  double pitch_deg = 10.0;
  std::string aerial_size = "32x32x32";
  double aerial_distance_m = 32000.0;
};
int RunPrecompute(const CommonOptions& common, const PrecomputeCommand& command);

// `atmo illuminance`: sun and sky illuminance on a horizontal plane, one CSV row per elevation.
struct IlluminanceCommand {
  std::vector<double> sun_elevations_deg = {30.0};
  std::optional<double> altitude_m;  // default: parameters.observer_altitude_m
  bool no_night_glow = false;        // leave the night sky's own light out
  SunOptions sun;                    // --date: one row for the sun and moon of that instant and place
  MoonOptions moon;                  // --moon-*, --no-moon
  bool no_stars = false;             // leave the stars out of the night sky's column
};
int RunIlluminance(const CommonOptions& common, const IlluminanceCommand& command);

// `atmo irradiance`: the sun's and sky's light on planes (atmo::ComputeIrradiance), one CSV row per
// sun and plane (or per sun, plane and wavelength with --per-wavelength).
struct IrradianceCommand {
  std::vector<double> sun_elevations_deg = {30.0};
  double sun_azimuth_deg = 180.0;
  std::optional<double> altitude_m;  // default: parameters.observer_altitude_m
  SunOptions sun;                    // --date: one row per plane for the sun of that instant and place
  // TILT:AZIMUTH in degrees, or "sun" (a plane facing the sun). Default: horizontal and facing the
  // sun (GHI, DHI and DNI).
  std::vector<std::string> planes = {"0:180", "sun"};
  double circumsolar_deg = 2.5;
  bool spectral = false;  // W m^-2 nm^-1 per wavelength instead of lux and W m^-2
  std::string out_path;   // empty: standard output
};
int RunIrradiance(const CommonOptions& common, const IrradianceCommand& command);
// `atmo calibrate`: the clear sky (aerosol optical depth and albedo) that reproduces a measured
// direct-normal and diffuse-horizontal illuminance (atmo::CalibrateClearSky), as a config file.
struct CalibrateCommand {
  std::optional<double> sun_elevation_deg;
  double sun_azimuth_deg = 180.0;
  SunOptions sun;  // --date: the sun (and its distance) of that instant and place
  std::optional<double> altitude_m;
  double direct_normal_lux = 0.0;
  double diffuse_horizontal_lux = 0.0;
  double circumsolar_deg = 2.5;
  double tolerance_percent = 0.5;
  std::string out_path;  // the calibrated parameters, JSON (atmo render --config)
};
int RunCalibrate(const CommonOptions& common, const CalibrateCommand& command);
// `atmo annual`: a weather file's hours as calibrated skies (atmo::AnnualSkies, atmo::RunAnnual):
// parts in --out-dir, merged into sky.mtx, hours.csv and irradiance.csv once every hour is done.
struct AnnualCommand {
  std::string epw_path;
  std::string out_dir;
  std::vector<std::string> planes;  // TILT:AZIMUTH or sun, besides the horizontal and the sun-facing
  int subdivision = 1;              // Reinhart MF
  int patch_samples = 2;
  double circumsolar_deg = 2.5;
  std::string hours;  // A:B, file hours [A, B); empty: all
  std::string shard;  // I/N; empty: 0/1
  bool no_sun_in_matrix = false;
  int sky_maps = 0;  // > 0: maps/sky_HHHH.hdr of this size and sky_HHHH.rad per hour with light
  bool per_wavelength = false;  // also irradiance_spectral.csv
  std::optional<double> latitude_deg;   // must agree with the file's
  std::optional<double> longitude_deg;
};
int RunAnnual(const CommonOptions& common, const AnnualCommand& command);

}  // namespace atmo::cli
