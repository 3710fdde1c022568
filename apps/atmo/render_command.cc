// `atmo render`: one frame of a model through a camera, written as EXR (linear, with metadata)
// and PNG (tone-mapped).
//
// A Monte Carlo model (reference) renders progressively (RenderProgressive): --spp paths per
// pixel in passes of 4, 8, 16, ... paths, with a progress bar on stderr when it is a terminal;
// the outputs are rewritten (atomically) after every pass, so they always hold the latest pass,
// and the EXR has the per-pixel standard errors as channels stderr.R, stderr.G, stderr.B (the layer stderr).
#include <bit>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <numbers>
#include <optional>
#include <string>
#include <utility>

#include "atmo/colour.h"
#include "atmo/cubemap.h"
#include "atmo/error.h"
#include "atmo/image.h"
#include "atmo/memory.h"
#include "atmo/moon.h"
#include "atmo/night_sky.h"
#include "atmo/night_vision.h"
#include "atmo/render.h"
#include "atmo/stars.h"
#include "cli_flags.h"
#include "commands.h"
#include "models/reference_model.h"
#include "progress_bar.h"

namespace atmo::cli {

namespace {

// "v0, v1, v2" with %.10g per value.
std::string JoinValues(const std::vector<double>& values) {
  std::string text;
  for (std::size_t i = 0; i < values.size(); ++i) {
    if (i > 0) text += ", ";
    text += Format("%.10g", values[i]);
  }
  return text;
}

std::string JoinOptions(const std::vector<std::string>& options) {
  std::string text;
  for (const std::string& option : options) text += (text.empty() ? "" : " ") + option;
  return text;
}

// CIE XYZ of a linear sRGB image (per pixel, the inverse of the sRGB matrix).
Image LinearSrgbImageToXyz(const Image& rgb) {
  Image xyz = rgb;
  const std::size_t pixels = static_cast<std::size_t>(rgb.width) * rgb.height;
  for (std::size_t p = 0; p < pixels; ++p) {
    const glm::dvec3 v = LinearSrgbToXyz(glm::dvec3(rgb.pixels[3 * p], rgb.pixels[3 * p + 1], rgb.pixels[3 * p + 2]));
    for (int k = 0; k < 3; ++k) xyz.pixels[3 * p + k] = static_cast<float>(v[k]);
  }
  xyz.channel_names = {"X", "Y", "Z"};
  xyz.colour_space = ColourSpace::kCieXyz;
  return xyz;
}

std::string UnitDescription(RadianceUnit unit, bool xyz, const std::vector<double>& solar_irradiance) {
  switch (unit) {
    case RadianceUnit::kLuminance:
      return xyz ? "cd/m^2 (CIE 1931 XYZ, Y = luminance)" : "cd/m^2 (linear Rec.709/sRGB, D65; Y = luminance)";
    case RadianceUnit::kRadiance: return "W m^-2 sr^-1 nm^-1 (spectral radiance, one channel per wavelength)";
    case RadianceUnit::kRelative: break;
  }
  return "sr^-1 per unit solar irradiance, times solar_irradiance (" + JoinValues(solar_irradiance) + ")";
}

}  // namespace

// The star catalogue of a render: --star-catalogue (an error if it cannot be read), else Debian's
// stellarium-data when it is installed; none with --no-stars, for a half-space, or (with a warning)
// when no catalogue is installed.
const StarCatalogue* LoadStarsFor(const RenderCommand& command, const AtmosphereParameters& parameters) {
  if (command.no_stars || parameters.geometry != Geometry::kSpherical) return nullptr;
  if (!command.star_catalogue.empty()) {
    static std::optional<StarCatalogue> given;
    given = StarCatalogue::Load(command.star_catalogue);
    return &*given;
  }
  std::error_code error;
  if (!std::filesystem::is_directory(StarCatalogue::DefaultFolder(), error)) {
    PrintWarning("no stars: no catalogue at " + StarCatalogue::DefaultFolder().string() +
                 " (install Debian's stellarium-data, or give --star-catalogue; --no-stars silences this)");
    return nullptr;
  }
  return &StarCatalogue::Default();
}

RenderPlan PlanRender(const CommonOptions& common, const RenderCommand& command) {
  RenderPlan plan;
  plan.parameters = LoadParameters(common);
  AtmosphereParameters& parameters = plan.parameters;
  if (command.sun_size_deg) {
    const double d = *command.sun_size_deg;
    // The lower bound is sun_angular_radius_rad's 1e-6 rad (docs/parameters.md) as a diameter.
    if (!(d >= 1.2e-4 && d <= 20.0)) {
      throw Error("--sun-size must be in [0.00012, 20] degrees (got " + Format("%g", d) + ")");
    }
    parameters.sun_angular_radius_rad = 0.5 * d * std::numbers::pi / 180.0;
  }
  if (command.no_night_glow) parameters.night_sky.enabled = false;
  plan.unit = ParseRadianceUnit(command.unit);
  if (command.night_vision && plan.unit == RadianceUnit::kRelative) {
    throw Error("--night-vision needs physical units: --unit luminance or radiance");
  }
  if (command.xyz && plan.unit != RadianceUnit::kLuminance) throw Error("--xyz needs --unit luminance");
  // The models answer per unit solar irradiance; in physical units the colour conversion brings
  // in the solar spectrum, so the model's images are rendered with solar_irradiance 1.
  plan.model_parameters = parameters;
  if (plan.unit != RadianceUnit::kRelative) {
    plan.model_parameters.solar_irradiance.assign(parameters.channel_count(), 1.0);
  }

  RenderSettings& settings = plan.settings;
  // --camera cubemap: six 90-degree perspective faces (atmo/cubemap.h), rendered by RunRender.
  plan.cubemap = command.camera == "cubemap";
  settings.camera.kind = plan.cubemap ? CameraKind::kPerspective : ParseCameraKind(command.camera);
  settings.camera.width = command.width;
  settings.camera.height = command.height;
  settings.camera.fov_deg = command.fov_deg;
  // Perspective and equirect views centre on the sun by default; the all-sky fisheye keeps north up.
  settings.camera.yaw_deg =
      command.yaw_deg.value_or(settings.camera.kind == CameraKind::kFisheye ? 0.0 : command.sun_azimuth_deg);
  settings.camera.pitch_deg = command.pitch_deg;
  // --target: the program's orientation, fixed in the world (a given --yaw still turns it).
  if (!command.target.empty()) {
    plan.target = &FindEngineTarget(command.target);
    if (plan.cubemap) {
      // A cube map for a program: three.js's CubeTexture, as --hdr-faces (CubeTextureForThree).
      if (command.target != "three") {
        throw Error("--target " + command.target + " with --camera cubemap: cube maps are written for three only; "
                    "use --camera equirect");
      }
      if (command.hdr_faces.empty()) {
        throw Error("--target three --camera cubemap writes --hdr-faces NAME (six Radiance HDR faces for three's "
                    "HDRCubeTextureLoader)");
      }
    } else if (settings.camera.kind != CameraKind::kEquirect) {
      throw Error("--target " + command.target + " writes an equirect: add --camera equirect");
    }
    settings.camera.yaw_deg = command.yaw_deg.value_or(plan.target->equirect_centre_azimuth_deg);
  }
  settings.altitude_m = command.altitude_m.value_or(parameters.observer_altitude_m);
  settings.sun_elevation_deg = command.sun_elevation_deg;
  settings.sun_azimuth_deg = command.sun_azimuth_deg;
  // --date: the sun of that instant and place instead (sun_options.h); a time-lapse starts there.
  if (HasDate(command.sun)) {
    plan.dated_sun = SunAtDate(command.sun);
    settings.sun_elevation_deg = plan.dated_sun->position.elevation_deg;
    settings.sun_azimuth_deg = plan.dated_sun->position.azimuth_deg;
    if (!command.yaw_deg && settings.camera.kind != CameraKind::kFisheye) settings.camera.yaw_deg = settings.sun_azimuth_deg;
  }
  settings.terms.sun_disc = !command.no_sun_disc;
  settings.terms.ground = !command.no_ground;
  if (!std::isfinite(settings.altitude_m)) throw Error("--altitude must be a finite number");

  ToneMapping& mapping = plan.mapping;
  const bool seed_look = command.per_channel ||
                         (plan.unit == RadianceUnit::kRelative && plan.parameters.channel_count() == 3);
  mapping.op = !command.tonemap.empty() ? ParseToneMapper(command.tonemap)
               : seed_look              ? ToneMapper::kExponential
                                        : ToneMapper::kAgx;
  if (command.gamma) {
    mapping.transfer = DisplayTransfer::kGamma;
    mapping.gamma = *command.gamma;
  }
  mapping.per_channel = command.per_channel;
  mapping.dither = !command.no_dither;
  mapping.bit_depth = command.png_bits;
  return plan;
}

RenderOutputs::RenderOutputs(const CommonOptions& common, const RenderCommand& command, const RenderPlan& plan,
                             const std::string& model_name)
    : command_(command), plan_(plan), convert_(plan.parameters.wavelengths_nm) {
  const AtmosphereParameters& parameters = plan.parameters;
  const RenderSettings& settings = plan.settings;
  const RadianceUnit unit = plan.unit;
  exr_colour_ = unit == RadianceUnit::kRadiance ? ImageColour::kSpectral
                : command.xyz                   ? ImageColour::kXyz
                                                : ImageColour::kLinearSrgb;
  // The PNG shows colour: the legacy channels as they are for a relative 3-channel render (the
  // seed's look), else the converted linear sRGB.
  legacy_png_ = unit == RadianceUnit::kRelative && parameters.channel_count() == 3;
  metadata_ = {
      {"atmo:version", ATMO_VERSION},
      {"atmo:model", model_name},
      {"atmo:backend", common.backend},
      {"atmo:preset", parameters.name},
      {"atmo:parameterHash", ParameterHashHex(parameters)},
      {"atmo:unit", std::string(ToString(unit))},
      {"atmo:radianceUnit", UnitDescription(unit, command.xyz, parameters.solar_irradiance)},
      {"atmo:renderTimeMs", ""},
      {"atmo:camera", plan.cubemap ? std::string("cubemap") : std::string(ToString(settings.camera.kind))},
      {"atmo:sunElevationDeg", Format("%.10g", settings.sun_elevation_deg)},
      {"atmo:sunAzimuthDeg", Format("%.10g", settings.sun_azimuth_deg)},
      {"atmo:altitudeM", Format("%.10g", settings.altitude_m)},
      {"atmo:wavelengthsNm", JoinValues(parameters.wavelengths_nm)},
      {"atmo:cameraYawDeg", Format("%.10g", settings.camera.yaw_deg)},
      {"atmo:terms", std::string(settings.terms.sun_disc ? "sun_disc " : "") + (settings.terms.ground ? "ground" : "")},
      {"atmo:sunAngularDiameterDeg", Format("%.10g", 2.0 * parameters.sun_angular_radius_rad * 180.0 / std::numbers::pi)},
      {"atmo:modelOptions", JoinOptions(common.options)},
  };
  // Only what the camera uses: the field of view and pitch are the perspective camera's (a cube
  // map's faces are perspective cameras too, but their yaw, fov and pitch are fixed by the face).
  if (plan.cubemap) {
    std::erase_if(metadata_, [](const auto& entry) { return entry.first == "atmo:cameraYawDeg"; });
  }
  if (settings.camera.kind == CameraKind::kPerspective && !plan.cubemap) {
    SetMetadata("atmo:cameraFovDeg", Format("%.10g", settings.camera.fov_deg));
    SetMetadata("atmo:cameraPitchDeg", Format("%.10g", settings.camera.pitch_deg));
  }
  if (plan.dated_sun) {
    for (const auto& [key, value] : SunMetadata(command.sun, *plan.dated_sun)) SetMetadata(key, value);
  }
  if (plan.target != nullptr) {
    SetMetadata("atmo:target", plan.target->name);
    SetMetadata("atmo:targetWorld", plan.target->world);
  }
}

void RenderOutputs::SetMetadata(const std::string& key, const std::string& value) {
  for (auto& entry : metadata_) {
    if (entry.first == key) {
      entry.second = value;
      return;
    }
  }
  metadata_.emplace_back(key, value);
}

std::vector<std::string> RenderOutputs::Write(const std::string& exr_path, const std::string& png_path,
                                              const Image& image, const Image* standard_error, double render_ms) {
  const auto write_start = std::chrono::steady_clock::now();
  const RenderCommand& command = command_;
  const RadianceUnit unit = plan_.unit;
  const bool is_colour = image.colour_space == ColourSpace::kLinearSrgb;
  std::vector<std::string> written;
  // The PNG's display image and exposure first, so that the EXR records the exposure too.
  Image display;
  ToneMapping png_mapping = plan_.mapping;
  if (!png_path.empty()) {
    display = legacy_png_ || is_colour ? image : ConvertImage(image, convert_, ImageColour::kLinearSrgb);
    if (command.night_vision) {
      // The eye at night, before the exposure that adapts to what it sees (docs/night.md).
      const double m = ApplyNightVision(display, NightVision(plan_.parameters.wavelengths_nm));
      SetMetadata("atmo:nightVisionPhotopicFraction", Format("%.4g", m));
    }
    if (command.exposure) {
      png_mapping.exposure = *command.exposure;
    } else if (command.ev100) {
      png_mapping.exposure = ExposureFromEv100(*command.ev100);
    } else if (command.auto_exposure || !legacy_png_) {
      // Relative units have no level to adapt to: the camera meter places them.
      const Metering metering = legacy_png_ ? Metering::kCamera : ParseMetering(command.metering);
      png_mapping.exposure = ExposureFromEv100(AutoExposureEv100(display, metering));
    } else {
      png_mapping.exposure = plan_.parameters.exposure;
    }
    SetMetadata("atmo:pngExposure", Format("%.6g", png_mapping.exposure));
  }
  if (!exr_path.empty()) {
    SetMetadata("atmo:renderTimeMs", Format("%.3f", render_ms));
    Image exr_image = is_colour ? (command.xyz ? LinearSrgbImageToXyz(image) : image)
                      : unit == RadianceUnit::kRelative ? image
                                                        : ConvertImage(image, convert_, exr_colour_);
    // Equirects and cube maps carry OpenEXR's envmap attribute (docs/environment.md).
    exr_image.envmap = plan_.settings.camera.kind == CameraKind::kEquirect ? EnvMap::kLatLong : image.envmap;
    if (standard_error != nullptr) {
      ProgressiveImage with_error;
      with_error.radiance = exr_image;
      with_error.standard_error =
          unit == RadianceUnit::kRelative ? *standard_error : ConvertStandardError(*standard_error, convert_, exr_colour_);
      exr_image = WithStandardErrorChannels(with_error);
      exr_image.colour_space = with_error.radiance.colour_space;
    }
    WriteExr(exr_path, exr_image, metadata_);
    written.push_back(exr_path);
  }
  if (!png_path.empty()) {
    WritePng(png_path, display, png_mapping);
    written.push_back(png_path);
  }
  write_s_ += std::chrono::duration<double>(std::chrono::steady_clock::now() - write_start).count();
  return written;
}

int RunRender(const CommonOptions& common, const RenderCommand& command) {
  // The success line reports the whole time and its parts (precompute, view, frame, write).
  const auto command_start = std::chrono::steady_clock::now();
  const auto seconds_since = [](std::chrono::steady_clock::time_point t) {
    return std::chrono::duration<double>(std::chrono::steady_clock::now() - t).count();
  };
  double precompute_s = 0.0;
  double view_s = 0.0;
  double frame_s = 0.0;
  CheckBackend(common, /*command_has_gl=*/true);
  // Every file the command may write, apart from the inputs and from each other.
  std::vector<NamedPath> output_paths = {
      {"--exr", command.exr_path},         {"--png", command.png_path},      {"--mp4", command.sun.mp4_path},
      {"--ktx2", command.ktx2_path},       {"--sh", command.sh_path},        {"--irradiance", command.irradiance_path},
      {"--specular", command.specular_path}};
  for (const std::string& face : HdrFacePaths(command.hdr_faces)) output_paths.push_back({"--hdr-faces", face});
  CheckOutputsApart(common, {}, output_paths);
  const bool on_gl = common.backend == "gl";
  RenderPlan plan = PlanRender(common, command);
  const AtmosphereParameters& parameters = plan.parameters;
  const AtmosphereParameters& model_parameters = plan.model_parameters;
  const RadianceUnit unit = plan.unit;
  const RenderSettings& settings = plan.settings;
  const bool cubemap = plan.cubemap;
  const SpectralConversion convert(parameters.wavelengths_nm);
  if (cubemap) {
    if (on_gl) throw Error("--camera cubemap renders on the cpu backend only");
    if (IsTimeLapse(command.sun)) throw Error("--camera cubemap does not take --until (a time-lapse)");
    if (common.model == "reference") throw Error("--camera cubemap needs a deterministic model, not reference");
    if (command.face_size < 1 || command.face_size > kMaxImageSide) {
      throw Error("--face-size must be in 1.." + std::to_string(kMaxImageSide) + " (got " +
                  std::to_string(command.face_size) + ")");
    }
  } else if (WantsEnvironmentOutputs(command)) {
    throw Error("--ktx2, --sh, --irradiance, --specular and --hdr-faces need --camera cubemap");
  }

  // Fail fast, before precomputing anything, when an output cannot be written, so that a refused
  // command changes nothing on disk (the cube-map products were checked only when written, after
  // the EXR and PNG had replaced the old ones).
  for (const NamedPath& output : output_paths) {
    if (output.flag != "--mp4" && !output.path.empty()) CheckOutputWritable(output.path);
  }
  if (command.mips && command.ktx2_path.empty()) throw Error("--mips makes the --ktx2 file's mip chain; give --ktx2");
  if (!command.specular_path.empty()) {
    // PrefilterSpecular's bound on the levels, checked here rather than after the other files are
    // written (the sizes and samples are bounded by their flags).
    const int max_levels = std::bit_width(static_cast<unsigned>(command.face_size));
    if (command.specular_levels < 1 || command.specular_levels > max_levels) {
      throw Error("--specular-levels must be in 1.." + std::to_string(max_levels) + " for --face-size " +
                  std::to_string(command.face_size) + " (got " + std::to_string(command.specular_levels) + ")");
    }
  }
  // -o NAME.jpg would write NAME.jpg.exr and NAME.jpg.png: a name that ends in another image or
  // data format's extension is refused instead.
  {
    std::string extension = std::filesystem::path(command.output_name).extension().string();
    for (char& c : extension) c = static_cast<char>(std::tolower(static_cast<unsigned char>(c)));
    for (const char* foreign : {".jpg", ".jpeg", ".tif", ".tiff", ".hdr", ".pic", ".rgbe", ".bmp", ".gif", ".webp",
                                ".avif", ".heic", ".jxl", ".tga", ".pfm", ".ppm", ".dds", ".ktx", ".ktx2", ".json",
                                ".csv", ".txt", ".mp4"}) {
      if (extension == foreign) {
        throw Error("-o '" + command.output_name + "' ends in " + extension +
                    ", which atmo render does not write: give NAME (NAME.exr and NAME.png), NAME.exr or NAME.png");
      }
    }
  }
  CheckExtension("--exr", command.exr_path, ".exr");
  CheckExtension("--png", command.png_path, ".png");
  if (IsTimeLapse(command.sun)) {
    // --until, --step, --mp4; then every frame's files, which are the outputs: each writable and
    // none an input (a frame named like --config replaced it; a frame that could not be written
    // failed the series after the earlier frames had replaced their files).
    const std::size_t count = TimeLapseInstants(command.sun, command.png_path).size();
    for (std::size_t frame = 0; frame < count; ++frame) {
      for (const auto& [flag, path] : {std::pair<std::string, std::string>{"--exr", command.exr_path},
                                       std::pair<std::string, std::string>{"--png", command.png_path}}) {
        if (path.empty()) continue;
        const std::string frame_path = FramePath(path, frame, count);
        CheckOutputsApart(common, {}, {{flag + " frame " + std::to_string(frame), frame_path}});
        CheckOutputWritable(frame_path);
      }
    }
  }

  // --spp is the path count of a Monte Carlo model; deterministic models have nothing to sample.
  if (command.spp && common.model != "reference") {
    throw Error("--spp is the number of Monte Carlo paths per pixel of model reference; model '" + common.model +
                "' is deterministic and takes no --spp");
  }
  // The image buffers before any work: measured 36-37 bytes per pixel (the frame, its display
  // conversion and the writers' rows), whatever the channel count (docs/reliability.md, "Memory").
  const double pixels = cubemap ? 6.0 * command.face_size * static_cast<double>(command.face_size)
                             : static_cast<double>(command.width) * command.height;
  CheckMemory(cubemap ? Format("a cube map of %d-texel faces", command.face_size)
                   : Format("a %dx%d render", command.width, command.height),
              40.0 * pixels);
  // The moon's light renders through the model's second view (RadianceTerms::moon): a CPU
  // model's, the reference's progressive render (its own paths), or a second GL frame.
  // On the gl backend the GL passes compute the tables and the frame (RenderOnGl); no CPU model is made.
  const auto precompute_start = std::chrono::steady_clock::now();
  const std::unique_ptr<Model> model = on_gl ? nullptr : CreateModelFor(common, model_parameters);
  precompute_s = seconds_since(precompute_start);
  const std::string model_name = model != nullptr ? std::string(model->name()) : common.model;

  const auto start = std::chrono::steady_clock::now();
  const auto elapsed_ms = [&] {
    return std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - start).count();
  };
  RenderOutputs outputs(common, command, plan, model_name);
  const auto set_metadata = [&](const std::string& key, const std::string& value) { outputs.SetMetadata(key, value); };
  const auto write_to = [&](const std::string& exr_path, const std::string& png_path, const Image& image,
                            const Image* standard_error, double render_ms) {
    return outputs.Write(exr_path, png_path, image, standard_error, render_ms);
  };
  const auto write = [&](const Image& image, const Image* standard_error, double render_ms) {
    return write_to(command.exr_path, command.png_path, image, standard_error, render_ms);
  };
  // A frame of a deterministic CPU model. In luminance the channels are folded into linear sRGB
  // while the frame is rendered (RenderViewFolded): a spectral frame costs about a 3-channel one.
  const std::vector<glm::vec3> srgb_weights = ColourWeights(convert, ImageColour::kLinearSrgb);
  // The night sky of a frame (include/atmo/night_sky.h): the ecliptic of the date and place when
  // the sun comes from --date, else the default one.
  // The stars: the catalogue of --star-catalogue, else Debian's stellarium-data when installed
  // (left out with a warning when not); the sky placed by the date and place, or by the sun.
  const StarCatalogue* catalogue = LoadStarsFor(command, model_parameters);
  const auto night_sky_for = [&](const RenderSettings& frame, const std::optional<SunAtInstant>& dated) {
    const glm::dvec3 sun = SunDirection(frame.sun_elevation_deg, frame.sun_azimuth_deg);
    const glm::dvec3 pole = dated ? EclipticPoleDirection(dated->julian_day_utc, *command.sun.latitude_deg,
                                                          *command.sun.longitude_deg)
                                  : glm::dvec3(0.0);
    NightSky night(model_parameters, std::max(frame.altitude_m, 0.0), sun, pole);
    const CelestialFrame sky = dated ? CelestialFrame::FromDate(dated->julian_day_utc, *command.sun.latitude_deg,
                                                                *command.sun.longitude_deg)
                                     : CelestialFrame::FromSun(sun);
    if (catalogue != nullptr) {
      night.SetStars(*catalogue, sky);
    } else {
      night.SetFrame(sky);  // the Milky Way's starlight
    }
    return night;
  };
  // The moon of a frame (include/atmo/moon.h): by hand, or from the date; its own view of the model.
  struct FrameMoon {
    std::optional<Moon> moon;
    std::unique_ptr<SkyView> sky;
  };
  // The moon alone (no view of the model): its place and its disc's light; recorded in the EXR.
  const auto moon_place_for = [&](const RenderSettings& frame,
                                  const std::optional<SunAtInstant>& dated) -> std::optional<Moon> {
    const std::optional<MoonPosition> place =
        ResolveMoon(command.moon, command.sun, frame.sun_azimuth_deg,
                    dated ? std::optional<double>(dated->julian_day_utc) : std::nullopt);
    if (!place) return std::nullopt;
    set_metadata("atmo:moonElevationDeg", Format("%.10g", place->elevation_deg));
    set_metadata("atmo:moonAzimuthDeg", Format("%.10g", place->azimuth_deg));
    set_metadata("atmo:moonPhaseDeg", Format("%.10g", place->phase_angle_deg));
    return Moon(SunDirection(place->elevation_deg, place->azimuth_deg), place->phase_angle_deg, place->distance_km,
                model_parameters.wavelengths_nm, SunDirection(frame.sun_elevation_deg, frame.sun_azimuth_deg));
  };
  const auto moon_for = [&](const RenderSettings& frame, const std::optional<SunAtInstant>& dated) {
    FrameMoon result;
    result.moon = moon_place_for(frame, dated);
    if (result.moon) result.sky = model->View(frame.altitude_m, result.moon->direction());
    return result;
  };
#ifdef ATMO_HAVE_GL
  // A GL frame with its night sky and moon: the moonlit sky is a second GL frame with the sun put
  // in the moon's direction (the models are linear in their source), added on the host with the
  // moon's disc (AddMoonLight), as the night sky is (AddNightSky).
  const auto render_gl = [&](const gl::Context& context, const RenderSettings& frame,
                             const std::optional<SunAtInstant>& dated) {
    if (common.model == "source4d") {
      set_metadata("atmo:source4dTables", Source4dTablesFromCpu(common, context) ? "cpu" : "gpu");
    }
    Image image = RenderOnGl(context, common, model_parameters, frame);
    const NightSky night = night_sky_for(frame, dated);
    AddNightSky(night.Scaled(model_parameters.solar_irradiance), frame.camera, image);
    if (const std::optional<Moon> moon = moon_place_for(frame, dated)) {
      RenderSettings lit_by_moon = frame;
      const glm::dvec3& d = moon->direction();
      lit_by_moon.sun_elevation_deg = glm::degrees(std::asin(std::clamp(d.z, -1.0, 1.0)));
      lit_by_moon.sun_azimuth_deg = glm::degrees(std::atan2(d.x, d.y));
      lit_by_moon.terms.sun_disc = false;
      const Image moonlit = RenderOnGl(context, common, model_parameters, lit_by_moon);
      AddMoonLight(*moon, moonlit, night, frame.camera, model_parameters.solar_irradiance, image);
    }
    return image;
  };
#endif
  const auto render_cpu = [&](const RenderSettings& frame, const std::optional<SunAtInstant>& dated,
                              const RowProgress& progress = {}) {
    const auto view_start = std::chrono::steady_clock::now();
    const std::unique_ptr<SkyView> sky =
        model->View(frame.altitude_m, SunDirection(frame.sun_elevation_deg, frame.sun_azimuth_deg));
    const NightSky night = night_sky_for(frame, dated);
    const FrameMoon moon = moon_for(frame, dated);
    view_s += seconds_since(view_start);
    RadianceTerms terms = frame.terms;
    terms.night_sky = &night;
    if (moon.moon) {
      terms.moon = &*moon.moon;
      terms.moon_sky = moon.sky.get();
    }
    const auto frame_start = std::chrono::steady_clock::now();
    Image image;
    if (unit != RadianceUnit::kLuminance) {
      image = RenderView(*sky, frame.camera, terms, model_parameters.solar_irradiance, progress);
    } else {
      image = RenderViewFolded(*sky, frame.camera, terms, srgb_weights, progress);
      image.colour_space = ColourSpace::kLinearSrgb;
    }
    frame_s += seconds_since(frame_start);
    return image;
  };

  // --until: a time-lapse. The model and its tables do not depend on the sun: made once above, each
  // frame is a new view (model->View: its per-view tables) and its frame pass. On the gl backend
  // each frame runs every pass (RenderOnGl) in one context.
  if (IsTimeLapse(command.sun)) {
#ifdef ATMO_HAVE_GL
    const std::unique_ptr<gl::Context> context = on_gl ? std::make_unique<gl::Context>() : nullptr;
#endif
    const std::string description = Format("%dx%d %s, %s, %s", settings.camera.width, settings.camera.height,
                                           std::string(ToString(settings.camera.kind)).c_str(), model_name.c_str(),
                                           parameters.name.c_str());
    const auto render_frame = [&](std::size_t, const SunAtInstant& sun, const std::string& exr_path,
                                  const std::string& png_path) {
      RenderSettings frame = settings;
      frame.sun_elevation_deg = sun.position.elevation_deg;
      frame.sun_azimuth_deg = sun.position.azimuth_deg;
      for (const auto& [key, value] : SunMetadata(command.sun, sun)) set_metadata(key, value);
      set_metadata("atmo:sunElevationDeg", Format("%.10g", frame.sun_elevation_deg));
      set_metadata("atmo:sunAzimuthDeg", Format("%.10g", frame.sun_azimuth_deg));
      const auto frame_start = std::chrono::steady_clock::now();
      Image image;
      Image standard_error;  // of a Monte Carlo model's radiance
      const NightSky night = night_sky_for(frame, sun);
      if (model != nullptr && IsMonteCarlo(*model)) {
        ProgressiveSettings progressive;
        progressive.samples_per_pixel = command.spp.value_or(0);
        frame.terms.night_sky = &night;
        const FrameMoon moon = moon_for(frame, sun);
        if (moon.moon) {
          frame.terms.moon = &*moon.moon;
          frame.terms.moon_sky = moon.sky.get();
        }
        const ProgressiveImage result = RenderProgressive(*model, frame, progressive);
        set_metadata("atmo:standardErrorChannels", "stderr.NAME: the standard error of channel NAME (same unit), the EXR layer stderr");
        set_metadata("atmo:samplesPerPixel", std::to_string(result.samples_per_pixel));
        image = result.radiance;
        standard_error = result.standard_error;
      } else if (model != nullptr) {
        image = render_cpu(frame, sun);
      } else {
#ifdef ATMO_HAVE_GL
        image = render_gl(*context, frame, sun);
#endif
      }
      const double frame_ms =
          std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - frame_start).count();
      write_to(exr_path, png_path, image, standard_error.width > 0 ? &standard_error : nullptr, frame_ms);
    };
    return RunTimeLapse(command.sun, command.exr_path, command.png_path, description, render_frame);
  }

  std::vector<std::string> written;
  Image image;
  double render_ms = 0.0;
  if (cubemap) {
    // The six faces as render_cpu renders a frame (folded into linear sRGB in luminance); --exr
    // and --png get OpenEXR's layout of them, the other outputs the cube itself.
    const std::unique_ptr<SkyView> sky =
        model->View(settings.altitude_m, SunDirection(settings.sun_elevation_deg, settings.sun_azimuth_deg));
    const NightSky night = night_sky_for(settings, plan.dated_sun);
    const FrameMoon moon = moon_for(settings, plan.dated_sun);
    RadianceTerms terms = settings.terms;
    terms.night_sky = &night;
    if (moon.moon) {
      terms.moon = &*moon.moon;
      terms.moon_sky = moon.sky.get();
    }
    Cubemap cube = unit == RadianceUnit::kLuminance
                       ? RenderCubemapFolded(*sky, command.face_size, terms, srgb_weights)
                       : RenderCubemap(*sky, command.face_size, terms, model_parameters.solar_irradiance);
    if (unit == RadianceUnit::kLuminance) {
      for (Image& face : cube.faces) face.colour_space = ColourSpace::kLinearSrgb;
    }
    render_ms = elapsed_ms();
    set_metadata("atmo:cubeFaceSize", std::to_string(command.face_size));
    set_metadata("atmo:cubeFrame", "X east, Y up, Z south (docs/environment.md); faces +X -X +Y -Y +Z -Z");
    image = CubemapExrImage(cube);
    written = write(image, nullptr, render_ms);
    WriteEnvironmentOutputs(command, cube, UnitDescription(unit, /*xyz=*/false, parameters.solar_irradiance),
                            unit == RadianceUnit::kLuminance, written);
    std::string files;
    for (const std::string& path : written) files += (files.empty() ? "" : ", ") + path;
    std::printf("%s %s (%d-texel cubemap, %s, %s) in %.1f ms\n", written.empty() ? "rendered" : "wrote",
                written.empty() ? "without writing a file" : files.c_str(), command.face_size, model_name.c_str(),
                parameters.name.c_str(), render_ms);
    return 0;
  }
  if (model != nullptr && IsMonteCarlo(*model)) {
    ProgressiveSettings progressive;
    progressive.samples_per_pixel = command.spp.value_or(0);  // 0: the model's samples option
    set_metadata("atmo:standardErrorChannels", "stderr.NAME: the standard error of channel NAME (same unit), the EXR layer stderr");
    // The bar's label says the whole job: paths per pixel and in total (the bar adds the ETA).
    // Without --spp: the model's samples option.
    const std::uint64_t spp = progressive.samples_per_pixel > 0
                                  ? progressive.samples_per_pixel
                                  : ReferenceSettings::FromOptions(ParseModelOptions(common.options)).samples;
    const double paths = static_cast<double>(spp) * settings.camera.width * settings.camera.height;
    ProgressBar progress(Format("render %llu paths per pixel (%.3g paths in all)", static_cast<unsigned long long>(spp),
                                paths));
    progressive.on_progress = [&](double done, double total) { progress.Update(done, total); };
    progressive.on_pass = [&](const ProgressiveImage& pass) {
      set_metadata("atmo:samplesPerPixel", std::to_string(pass.samples_per_pixel));
      render_ms = elapsed_ms();
      written = write(pass.radiance, &pass.standard_error, render_ms);
    };
    const auto passes_start = std::chrono::steady_clock::now();
    const NightSky night = night_sky_for(settings, plan.dated_sun);
    RenderSettings with_night = settings;
    with_night.terms.night_sky = &night;
    const FrameMoon moon = moon_for(settings, plan.dated_sun);
    if (moon.moon) {
      with_night.terms.moon = &*moon.moon;
      with_night.terms.moon_sky = moon.sky.get();
    }
    image = RenderProgressive(*model, with_night, progressive).radiance;
    frame_s = seconds_since(passes_start) - outputs.write_s();
    progress.Finish();
  } else {
    // A long CPU frame (a per-pixel ray march, a large image) draws a bar over its rows.
    ProgressBar progress("render rows");
    const RowProgress rows = [&](int done, int total) { progress.Update(done, total); };
#ifdef ATMO_HAVE_GL
    if (on_gl) {
      const gl::Context context;
      const auto gl_start = std::chrono::steady_clock::now();
      image = render_gl(context, settings, plan.dated_sun);
      frame_s = seconds_since(gl_start);
    } else {
      image = render_cpu(settings, plan.dated_sun, rows);
    }
#else
    image = render_cpu(settings, plan.dated_sun, rows);
#endif
    progress.Finish();
    render_ms = 1e3 * (view_s + frame_s);
    written = write(image, nullptr, render_ms);
  }

  std::string files;
  for (const std::string& path : written) files += (files.empty() ? "" : ", ") + path;
  // The whole time and its parts; on the gl backend the tables are GPU passes of the frame's run.
  const std::string parts =
      on_gl ? Format("gl passes and read-back %.2f s, write %.2f s", frame_s, outputs.write_s())
            : Format("precompute %.2f s, view %.2f s, frame %.2f s, write %.2f s", precompute_s, view_s, frame_s, outputs.write_s());
  std::printf("%s %s (%dx%d %s, %s, %s) in %.2f s: %s\n", written.empty() ? "rendered" : "wrote",
              written.empty() ? "without writing a file" : files.c_str(), image.width, image.height,
              std::string(ToString(settings.camera.kind)).c_str(), model_name.c_str(), parameters.name.c_str(),
              seconds_since(command_start), parts.c_str());
  return 0;
}

}  // namespace atmo::cli
