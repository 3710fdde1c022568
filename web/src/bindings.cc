// atmo.wasm's JavaScript API (docs/web.md): the library's own C++ behind Embind, called the way the
// command line and the Python module call it, so that the numbers agree with `atmo sample` and
// `atmo render` (the same code, compiled for WebAssembly):
//   - parameters from a preset or a JSON text, spectral N through atmo::MakeSpectral, the aerosol
//     knobs through atmo::ApplyAerosolRequest, model options as KEY=VALUE pairs (--option);
//   - samples as apps/atmo/sample_command.cc computes them (SkyView::RadianceEstimate and
//     SkyView::Transmittance per point, in double precision, the same units);
//   - frames as apps/atmo/render_command.cc renders them (RenderViewFolded into linear sRGB for
//     luminance, RenderView per channel otherwise);
//   - the sky-view table that the page draws from (web/src/sky.frag.glsl through atmo_tables.glsl):
//     any model's radiance at the texel centres of model hillaire's sky-view mapping, folded to
//     linear sRGB, as the GL backend's frames are drawn from one.
// Every atmo::Error (and any other C++ exception) becomes a JavaScript Error with the library's
// one-line message; nothing aborts the module. web/src/atmo.js wraps this in the public API.
#include <emscripten/bind.h>
#include <emscripten/val.h>
#include <oneapi/tbb/task_arena.h>  // web/shim: the threads of the module's loops

#include <chrono>
#include <cmath>
#include <cstdint>
#include <exception>
#include <limits>
#include <memory>
#include <numbers>
#include <string>
#include <vector>

#include "atmo/aerosol.h"
#include "atmo/colour.h"
#include "atmo/cubemap.h"
#include "atmo/engine_target.h"
#include "atmo/error.h"
#include "atmo/image.h"
#include "atmo/model.h"
#include "atmo/parameters.h"
#include "atmo/render.h"
#include "atmo/spectrum.h"
#include "atmo/timing.h"
#include "atmo/sun_position.h"
#include "cpu/camera.h"
#include "physics/shared_parameters.h"
#include "shared/shared.h"

namespace atmo::web {
namespace {

using emscripten::val;

[[noreturn]] void ThrowJs(const std::string& message) {
  val::global("Error").new_(val(message)).throw_();
  std::abort();  // throw_ does not return
}

// Runs `f`, turning any C++ exception into a JavaScript Error with its message.
template <typename F>
auto Guard(F&& f) -> decltype(f()) {
  try {
    return f();
  } catch (const std::exception& error) {
    ThrowJs(error.what());
  }
}

double Milliseconds(std::chrono::steady_clock::time_point start) {
  return std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - start).count();
}

// A fresh JavaScript typed array holding a copy of `data`.
template <typename T>
val CopyToJs(const char* type, const T* data, std::size_t n) {
  return val::global(type).new_(val(emscripten::typed_memory_view(n, data)));
}
val ToFloat32Array(const std::vector<float>& v) { return CopyToJs("Float32Array", v.data(), v.size()); }
val ToFloat64Array(const std::vector<double>& v) { return CopyToJs("Float64Array", v.data(), v.size()); }

// A JavaScript array or typed array of numbers as doubles.
std::vector<double> ToDoubles(const val& array, const char* what) {
  if (array.isUndefined() || array.isNull()) return {};
  if (!array["length"].isNumber()) ThrowJs(std::string(what) + " must be an array of numbers");
  return emscripten::convertJSArrayToNumberVector<double>(array);
}

// Field `key` of a JavaScript object, or `fallback` when it is absent; a present field must be a
// number (NaN and infinities pass here and are refused by the library's own checks).
double Number(const val& object, const char* key, double fallback) {
  if (object.isUndefined() || object.isNull()) return fallback;
  const val v = object[key];
  if (v.isUndefined() || v.isNull()) return fallback;
  if (!v.isNumber()) ThrowJs(std::string(key) + " must be a number");
  return v.as<double>();
}
int Integer(const val& object, const char* key, int fallback) {
  const double v = Number(object, key, fallback);
  if (!(std::fabs(v) <= 1e9) || v != std::floor(v)) ThrowJs(std::string(key) + " must be an integer");
  return static_cast<int>(v);
}
bool Boolean(const val& object, const char* key, bool fallback) {
  if (object.isUndefined() || object.isNull()) return fallback;
  const val v = object[key];
  if (v.isUndefined() || v.isNull()) return fallback;
  if (!v.isTrue() && !v.isFalse()) ThrowJs(std::string(key) + " must be true or false");
  return v.isTrue();
}
std::string String(const val& object, const char* key, const std::string& fallback) {
  if (object.isUndefined() || object.isNull()) return fallback;
  const val v = object[key];
  if (v.isUndefined() || v.isNull()) return fallback;
  if (!v.isString()) ThrowJs(std::string(key) + " must be a string");
  return v.as<std::string>();
}
std::optional<double> OptionalNumber(const val& object, const char* key) {
  if (object.isUndefined() || object.isNull() || object[key].isUndefined() || object[key].isNull()) return std::nullopt;
  return Number(object, key, 0.0);
}

// The observer and sun of a request, checked as the command line checks them.
struct Observer {
  double altitude_m = 0.0;
  double sun_elevation_deg = 10.0;
  double sun_azimuth_deg = 180.0;
};
Observer ReadObserver(const val& request, const AtmosphereParameters& parameters) {
  Observer o;
  o.altitude_m = Number(request, "altitude", parameters.observer_altitude_m);
  o.sun_elevation_deg = Number(request, "sunElevation", o.sun_elevation_deg);
  o.sun_azimuth_deg = Number(request, "sunAzimuth", o.sun_azimuth_deg);
  if (!std::isfinite(o.altitude_m) || std::fabs(o.altitude_m) > kMaxAltitude_m) {
    throw Error("altitude must be a finite number of metres within +-1e11");
  }
  if (!std::isfinite(o.sun_elevation_deg) || o.sun_elevation_deg < -90.0 || o.sun_elevation_deg > 90.0) {
    throw Error("sunElevation must be in [-90, 90] degrees");
  }
  if (!std::isfinite(o.sun_azimuth_deg)) throw Error("sunAzimuth must be a finite number of degrees");
  return o;
}

class WebModel {
 public:
  // config: {preset | json, spectral, wavelengths, options: {KEY: VALUE}, aerosol, aod, angstrom,
  // visibility, turbidity}.
  WebModel(const std::string& name, const val& config) {
    Guard([&] {
      const std::string json = String(config, "json", "");
      parameters_ = json.empty() ? Preset(String(config, "preset", "earth")) : FromJson(json);
      const int spectral = Integer(config, "spectral", 0);
      if (spectral != 0) parameters_ = MakeSpectral(parameters_, spectral);
      if (!config.isUndefined() && !config.isNull()) {
        const std::vector<double> wavelengths = ToDoubles(config["wavelengths"], "wavelengths");
        if (!wavelengths.empty()) parameters_ = MakeSpectral(parameters_, wavelengths);
      }
      AerosolRequest aerosol;
      if (const std::string type = String(config, "aerosol", ""); !type.empty()) aerosol.type = type;
      aerosol.aod_550 = OptionalNumber(config, "aod");
      aerosol.angstrom_exponent = OptionalNumber(config, "angstrom");
      aerosol.visibility_km = OptionalNumber(config, "visibility");
      aerosol.linke_turbidity = OptionalNumber(config, "turbidity");
      ApplyAerosolRequest(parameters_, aerosol);
      if (!config.isUndefined() && !config.isNull() && !config["options"].isUndefined()) {
        const val options = config["options"];
        const val keys = val::global("Object").call<val>("keys", options);
        const int n = keys["length"].as<int>();
        for (int i = 0; i < n; ++i) {
          const std::string key = keys[i].as<std::string>();
          const val value = options[key];
          options_[key] = value.isString() ? value.as<std::string>() : value.call<std::string>("toString");
        }
      }
      if (name == "reference") {
        throw Error("model 'reference' is a Monte Carlo path tracer; the web build takes the deterministic models");
      }
      const auto start = std::chrono::steady_clock::now();
      model_ = CreateModel(name, parameters_, options_);
      precompute_ms_ = Milliseconds(start);
      return 0;
    });
  }

  std::string name() const { return std::string(model_->name()); }
  std::string preset() const { return parameters_.name; }
  int channelCount() const { return static_cast<int>(parameters_.channel_count()); }
  double precomputeMs() const { return precompute_ms_; }
  double topAltitude() const { return parameters_.top_radius_m - parameters_.ground_radius_m; }
  double groundRadius() const { return parameters_.ground_radius_m; }
  double sunAngularRadius() const { return parameters_.sun_angular_radius_rad; }
  std::string parametersJson() const { return ToJson(parameters_); }
  std::string parameterHash() const { return ParameterHashHex(parameters_); }
  // The model's precomputation passes as `atmo bench` names them: {pass: milliseconds}.
  val passTimes() const {
    val out = val::object();
    for (const PassTiming& pass : model_->timings().entries()) out.set(pass.name, pass.last_ms);
    return out;
  }
  val wavelengths() const { return ToFloat64Array(parameters_.wavelengths_nm); }
  val solarIrradiance() const { return ToFloat64Array(parameters_.solar_irradiance); }

  // Points as `atmo sample` takes them: four arrays of one length (altitude m, sun zenith deg,
  // view zenith deg, view azimuth from the sun deg); unit "relative", "radiance" or "luminance".
  // Returns {radiance, transmittance, standardError, channels}: Float64Arrays of n x channels.
  val sample(const val& altitude_m, const val& sun_zenith_deg, const val& view_zenith_deg, const val& azimuth_deg,
             const std::string& unit_name) const {
    return Guard([&] {
      const std::vector<double> alt = ToDoubles(altitude_m, "altitude");
      const std::vector<double> sz = ToDoubles(sun_zenith_deg, "sunZenith");
      const std::vector<double> vz = ToDoubles(view_zenith_deg, "viewZenith");
      const std::vector<double> az = ToDoubles(azimuth_deg, "azimuth");
      const std::size_t n = alt.size();
      if (sz.size() != n || vz.size() != n || az.size() != n) throw Error("sample: the four arrays must have one length");
      const RadianceUnit unit = ParseRadianceUnit(unit_name);
      const std::size_t nc = parameters_.channel_count();
      const std::size_t out_channels = SampleChannels(unit, nc);
      for (std::size_t i = 0; i < n; ++i) {
        const double values[] = {alt[i], sz[i], vz[i], az[i]};
        for (double v : values) {
          if (!std::isfinite(v)) throw Error("sample " + std::to_string(i) + ": a value is not a finite number");
        }
        if (std::fabs(alt[i]) > kMaxAltitude_m) throw Error("sample " + std::to_string(i) + ": altitude outside +-1e11 m");
        if (sz[i] < 0.0 || sz[i] > 180.0 || vz[i] < 0.0 || vz[i] > 180.0) {
          throw Error("sample " + std::to_string(i) + ": zenith angles must be in [0, 180]");
        }
      }
      const SpectralConversion convert(parameters_.wavelengths_nm);
      std::vector<double> radiance(n * out_channels), transmittance(n * out_channels), error(n * out_channels);
      std::vector<double> l(nc), t(nc), e(nc);
      std::unique_ptr<SkyView> sky;
      double view_altitude = std::numeric_limits<double>::quiet_NaN(), view_sun_zenith = 0.0;
      for (std::size_t i = 0; i < n; ++i) {
        if (!sky || alt[i] != view_altitude || sz[i] != view_sun_zenith) {  // one view per run of points
          sky = model_->View(alt[i], DirectionFromZenithAzimuth(sz[i] * std::numbers::pi / 180.0, 0.0));
          view_altitude = alt[i];
          view_sun_zenith = sz[i];
        }
        const glm::dvec3 view = DirectionFromZenithAzimuth(vz[i] * std::numbers::pi / 180.0, az[i] * std::numbers::pi / 180.0);
        std::fill(e.begin(), e.end(), 0.0);
        sky->RadianceEstimate(view, l, e);
        sky->Transmittance(view, t);
        const std::size_t at = i * out_channels;
        ConvertSample(convert, unit, l, t, e, std::span<double>(radiance).subspan(at, out_channels),
                      std::span<double>(transmittance).subspan(at, out_channels),
                      std::span<double>(error).subspan(at, out_channels));
      }
      val out = val::object();
      out.set("radiance", ToFloat64Array(radiance));
      out.set("transmittance", ToFloat64Array(transmittance));
      out.set("standardError", ToFloat64Array(error));
      out.set("channels", static_cast<int>(out_channels));
      return out;
    });
  }

  // One frame as `atmo render` renders it on the CPU backend (no night sky, stars or moon in the
  // web build yet). request: {camera, width, height, fov, yaw, pitch, altitude, sunElevation,
  // sunAzimuth, sunDisc, ground, unit}. Returns {width, height, channels, pixels (Float32Array,
  // rows from the top), alpha (Float32Array or null), ms}.
  val renderFrame(const val& request) const {
    return Guard([&] {
      const auto start = std::chrono::steady_clock::now();
      const Observer o = ReadObserver(request, parameters_);
      Camera camera;
      camera.kind = ParseCameraKind(String(request, "camera", "perspective"));
      camera.width = Integer(request, "width", 640);
      camera.height = Integer(request, "height", 360);
      camera.fov_deg = Number(request, "fov", 90.0);
      camera.yaw_deg = Number(request, "yaw", o.sun_azimuth_deg);
      camera.pitch_deg = Number(request, "pitch", 10.0);
      ValidateCamera(camera);
      const RadianceUnit unit = ParseRadianceUnit(String(request, "unit", "luminance"));
      const RadianceTerms terms{Boolean(request, "sunDisc", true), Boolean(request, "ground", true)};
      const std::unique_ptr<SkyView> sky = model_->View(o.altitude_m, SunDirection(o.sun_elevation_deg, o.sun_azimuth_deg));
      const SpectralConversion convert(parameters_.wavelengths_nm);
      Image image;
      if (unit == RadianceUnit::kLuminance) {
        image = RenderViewFolded(*sky, camera, terms, ColourWeights(convert, ImageColour::kLinearSrgb));
      } else {
        const std::vector<double> ones(parameters_.channel_count(), 1.0);
        image = RenderView(*sky, camera, terms, unit == RadianceUnit::kRelative ? parameters_.solar_irradiance : ones);
        if (unit == RadianceUnit::kRadiance) image = ConvertImage(image, convert, ImageColour::kSpectral);
      }
      val out = val::object();
      out.set("width", image.width);
      out.set("height", image.height);
      out.set("channels", image.channels);
      out.set("pixels", ToFloat32Array(image.pixels));
      out.set("alpha", image.alpha.empty() ? val::null() : ToFloat32Array(image.alpha));
      out.set("ms", Milliseconds(start));
      return out;
    });
  }

  // The sky-view table the page draws from: width x height texels of RGBA float (A = 1), texel
  // (x, y) the model's radiance in linear sRGB cd/m^2 (with the lit ground below the horizon, no
  // sun disc) along the direction of model hillaire's sky-view mapping at the texel's centre
  // (shared::GetViewAnglesFromSkyViewTextureUv, azimuth from the sun). request: {altitude,
  // sunElevation, width, height, ground}. Returns {width, height, texels, rKm, bottomRadiusKm,
  // topRadiusKm, horizonNadirAngle, sunDisc (linear sRGB cd/m^2 at the disc's centre, seen
  // through the air), sunAngularRadius, autoEv100 (an exposure for the sky), ms}.
  val skyView(const val& request) const {
    return Guard([&] {
      const auto start = std::chrono::steady_clock::now();
      const Observer o = ReadObserver(request, parameters_);
      const int width = Integer(request, "width", 192);
      const int height = Integer(request, "height", 108);
      if (width < 4 || width > 4096 || height < 4 || height > 4096 || height % 2 != 0) {
        throw Error("skyView: width and height must be in 4..4096, the height even");
      }
      const bool ground = Boolean(request, "ground", true);
      const glm::dvec3 sun = SunDirection(o.sun_elevation_deg, 0.0);  // the table is relative to the sun's azimuth
      const std::unique_ptr<SkyView> sky = model_->View(o.altitude_m, sun);
      const shared::AtmosphereParameters atmosphere = ToSharedParameters(parameters_, 0);
      const double r = parameters_.ground_radius_m + std::max(o.altitude_m, 0.0);
      double sx = sun.x, sy = sun.y;
      const double horizontal = std::hypot(sx, sy);
      if (horizontal > 0.0) {
        sx /= horizontal;
        sy /= horizontal;
      } else {
        sx = 0.0;
        sy = 1.0;
      }
      std::vector<glm::dvec3> directions(static_cast<std::size_t>(width) * height);
      for (int y = 0; y < height; ++y) {
        for (int x = 0; x < width; ++x) {
          double mu = 0.0, azimuth = 0.0;
          shared::GetViewAnglesFromSkyViewTextureUv(atmosphere, shared::ivec2(width, height), r,
                                                    shared::vec2((x + 0.5) / width, (y + 0.5) / height), mu, azimuth);
          // The direction whose GetAzimuthFromSun is `azimuth`: the sun's horizontal direction
          // turned by -azimuth (atan2(v x s, v . s) = azimuth).
          const double c = std::cos(azimuth), s = std::sin(azimuth);
          const double h = std::sqrt(std::max(0.0, 1.0 - mu * mu));
          directions[static_cast<std::size_t>(y) * width + x] = glm::dvec3(h * (c * sx + s * sy), h * (c * sy - s * sx), mu);
        }
      }
      const SpectralConversion convert(parameters_.wavelengths_nm);
      const std::vector<glm::vec3> weights = ColourWeights(convert, ImageColour::kLinearSrgb);
      std::vector<float> rgb(directions.size() * 3);
      sky->RadianceBatchFolded(directions, RadianceTerms{false, ground}, weights, rgb);
      std::vector<float> texels(directions.size() * 4);
      for (std::size_t i = 0; i < directions.size(); ++i) {
        for (int k = 0; k < 3; ++k) texels[4 * i + k] = rgb[3 * i + k];
        texels[4 * i + 3] = 1.0f;
      }
      // The sun disc's centre as the renderer draws it (SunDiscRadiance per channel, folded).
      std::vector<double> disc(parameters_.channel_count());
      sky->SunDiscRadiance(sun, disc);
      glm::dvec3 disc_rgb(0.0);
      for (std::size_t c = 0; c < disc.size(); ++c) disc_rgb += glm::dvec3(weights[c]) * disc[c];
      val out = val::object();
      out.set("width", width);
      out.set("height", height);
      out.set("texels", ToFloat32Array(texels));
      out.set("rKm", r / 1000.0);
      out.set("bottomRadiusKm", atmosphere.bottom_radius / 1000.0);
      out.set("topRadiusKm", atmosphere.top_radius / 1000.0);
      out.set("horizonNadirAngle", shared::GetHorizonNadirAngle(atmosphere, r));
      out.set("sunDisc", ToFloat64Array({disc_rgb.x, disc_rgb.y, disc_rgb.z}));
      out.set("sunAngularRadius", parameters_.sun_angular_radius_rad);
      // An exposure for the page: atmo's adaptive metering (MeteredEv100) of the mean log2
      // luminance of the table's sky rows (each row one band of view zenith angles).
      double log2_sum = 0.0;
      std::size_t count = 0;
      for (std::size_t i = 0; i < directions.size() / 2; ++i) {
        const double y = 0.2126 * rgb[3 * i] + 0.7152 * rgb[3 * i + 1] + 0.0722 * rgb[3 * i + 2];
        log2_sum += std::log2(std::max(y, 1e-9));
        ++count;
      }
      out.set("autoEv100", MeteredEv100(count > 0 ? log2_sum / count : 0.0));
      out.set("ms", Milliseconds(start));
      return out;
    });
  }

  // The six faces of a cube map in three.js's CubeTexture order and orientation
  // (CubeTextureForThree): {size, faces: [6 Float32Arrays of size x size x 3], ms}, linear sRGB
  // cd/m^2 with the sun disc (its energy kept per texel) and the lit ground.
  val cubeMap(const val& request) const {
    return Guard([&] {
      const auto start = std::chrono::steady_clock::now();
      const Cubemap cube = CubeTextureForThree(FoldedCube(request, 64, "cubeMap"));
      const int size = cube.face_size;
      val faces = val::array();
      for (const Image& face : cube.faces) faces.call<void>("push", ToFloat32Array(face.pixels));
      val out = val::object();
      out.set("size", size);
      out.set("faces", faces);
      out.set("ms", Milliseconds(start));
      return out;
    });
  }

  // The cube map as `atmo render --camera cubemap --ktx2 FILE [--mips] [--ktx2-float]` writes it
  // (the GL cube-map convention, linear sRGB cd/m^2, RGBA16F or RGBA32F): the file's bytes, as a
  // Uint8Array. request: {size, altitude, sunElevation, sunAzimuth, sunDisc, ground, mips, float32}.
  val ktx2(const val& request) const {
    return Guard([&] {
      std::vector<Cubemap> levels{FoldedCube(request, 256, "ktx2")};
      if (Boolean(request, "mips", false)) {
        while (levels.back().face_size > 1) levels.push_back(DownsampleCubemap(levels.back()));
      }
      const std::vector<std::uint8_t> bytes = EncodeKtx2(levels, Boolean(request, "float32", false), "atmo.wasm " ATMO_VERSION);
      return CopyToJs("Uint8Array", bytes.data(), bytes.size());
    });
  }

 private:
  // The view's cube map (atmo's cube-map convention) folded to linear sRGB cd/m^2, as
  // `atmo render --camera cubemap` renders it. request: {size (default `default_size`), altitude,
  // sunElevation, sunAzimuth, sunDisc, ground}; `what` names the call in errors.
  Cubemap FoldedCube(const val& request, int default_size, const char* what) const {
    const Observer o = ReadObserver(request, parameters_);
    const int size = Integer(request, "size", default_size);
    if (size < 1 || size > 2048) throw Error(std::string(what) + ": size must be in 1..2048");
    const RadianceTerms terms{Boolean(request, "sunDisc", true), Boolean(request, "ground", true)};
    const std::unique_ptr<SkyView> sky = model_->View(o.altitude_m, SunDirection(o.sun_elevation_deg, o.sun_azimuth_deg));
    const SpectralConversion convert(parameters_.wavelengths_nm);
    Cubemap cube = RenderCubemapFolded(*sky, size, terms, ColourWeights(convert, ImageColour::kLinearSrgb));
    for (Image& face : cube.faces) face.colour_space = ColourSpace::kLinearSrgb;
    return cube;
  }

  AtmosphereParameters parameters_;
  ModelOptions options_;
  std::unique_ptr<Model> model_;
  double precompute_ms_ = 0.0;
};

val Names(const std::vector<std::string>& names) {
  val out = val::array();
  for (const std::string& n : names) out.call<void>("push", val(n));
  return out;
}

// The sun from date and place (libnova, as `atmo render --date`): {elevation, azimuth} in degrees.
val SunFromDate(const std::string& iso_date, double latitude_deg, double longitude_deg) {
  return Guard([&] {
    const SunPosition p = ComputeSunPosition(ParseIsoDateTime(iso_date), latitude_deg, longitude_deg);
    val out = val::object();
    out.set("elevation", p.elevation_deg);
    out.set("azimuth", p.azimuth_deg);
    return out;
  });
}

std::string PresetJson(const std::string& name) {
  return Guard([&] { return ToJson(Preset(name)); });
}

}  // namespace
}  // namespace atmo::web

EMSCRIPTEN_BINDINGS(atmo) {
  using namespace atmo::web;
  emscripten::class_<WebModel>("Model")
      .constructor<std::string, emscripten::val>()
      .property("name", &WebModel::name)
      .property("preset", &WebModel::preset)
      .property("channelCount", &WebModel::channelCount)
      .property("precomputeMs", &WebModel::precomputeMs)
      .property("topAltitude", &WebModel::topAltitude)
      .property("groundRadius", &WebModel::groundRadius)
      .property("sunAngularRadius", &WebModel::sunAngularRadius)
      .property("parameterHash", &WebModel::parameterHash)
      .function("parametersJson", &WebModel::parametersJson)
      .function("passTimes", &WebModel::passTimes)
      .function("wavelengths", &WebModel::wavelengths)
      .function("solarIrradiance", &WebModel::solarIrradiance)
      .function("sample", &WebModel::sample)
      .function("renderFrame", &WebModel::renderFrame)
      .function("skyView", &WebModel::skyView)
      .function("cubeMap", &WebModel::cubeMap)
      .function("ktx2", &WebModel::ktx2);
  emscripten::function("modelNames", emscripten::optional_override([] { return Names(atmo::ModelNames()); }));
  emscripten::function("presetNames", emscripten::optional_override([] { return Names(atmo::PresetNames()); }));
  emscripten::function("presetJson", &PresetJson);
  emscripten::function("sunFromDate", &SunFromDate);
  emscripten::function("version", emscripten::optional_override([] { return std::string(ATMO_VERSION); }));
  // The threads the module's loops run on: 1 in atmo.wasm, min(cores, 8) in atmo_mt.wasm.
  emscripten::function("threads", emscripten::optional_override([] {
    return oneapi::tbb::this_task_arena::max_concurrency();
  }));
}
