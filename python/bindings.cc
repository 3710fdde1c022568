// atmo._atmo: the compiled half of the Python module `atmo` (docs/python.md).
//
// The pure-Python package (python/atmo/__init__.py) broadcasts the NumPy arguments and calls
// these functions with flat, contiguous float64 arrays. Everything here calls the library the way
// the command line does, so that the numbers agree with `atmo sample` and `atmo render`:
//   - parameters from a preset, a JSON file or a JSON text (LoadParameters of apps/atmo/common.cc),
//     --spectral N through atmo::MakeSpectral, model options as the KEY=VALUE strings of --option;
//   - samples as apps/atmo/sample_command.cc computes them: points grouped by (altitude, sun
//     zenith), one SkyView per group, SkyView::RadianceEstimate and SkyView::Transmittance per point,
//     in double precision, the same unit conversions;
//   - frames as apps/atmo/render_command.cc renders them: RenderViewFolded into linear sRGB for
//     luminance, RenderView per channel otherwise, RenderProgressive for Monte Carlo models.
// The work runs with the GIL released, on oneTBB's threads. atmo::Error becomes ValueError with
// the library's one-line message.
#include <pybind11/numpy.h>
#include <pybind11/pybind11.h>
#include <pybind11/stl.h>

#include <chrono>
#include <cmath>
#include <filesystem>
#include <cstdint>
#include <cstring>
#include <limits>
#include <list>
#include <memory>
#include <mutex>
#include <numbers>
#include <optional>
#include <string>
#include <unordered_map>
#include <vector>

#include <oneapi/tbb/blocked_range.h>
#include <oneapi/tbb/global_control.h>
#include <oneapi/tbb/parallel_for.h>

#include "atmo/hillaire_tables.h"
#include "io/hillaire_table_file.h"  // ValidateHillaireExportView (python/CMakeLists.txt adds src/atmo)
#include "atmo/elek.h"
#include "atmo/cubemap.h"
#include "atmo/ibl.h"
#include "atmo/illuminance.h"
#include "atmo/moon.h"
#include "atmo/night_sky.h"
#include "atmo/stars.h"
#include "atmo/sun_position.h"
#include "atmo/engine_target.h"
#include "atmo/colour.h"
#include "atmo/cubemap.h"
#include "atmo/aerosol.h"
#include "atmo/error.h"
#include "atmo/memory.h"
#include "atmo/image.h"
#include "atmo/model.h"
#include "atmo/parameters.h"
#include "atmo/render.h"
#include "atmo/spectrum.h"
#include "atmo/table_cache.h"
#include "cpu/camera.h"
#include "shared/shared.h"

namespace py = pybind11;

namespace atmo::python {
namespace {

using Array = py::array_t<double, py::array::c_style | py::array::forcecast>;
using FloatArray = py::array_t<float, py::array::c_style | py::array::forcecast>;

// "[2, 1]" for the multi-index of flat index `flat` in an array of `shape`.
std::string IndexText(std::size_t flat, const std::vector<std::size_t>& shape) {
  std::vector<std::size_t> index(shape.size());
  for (std::size_t d = shape.size(); d-- > 0;) {
    const std::size_t extent = shape[d] == 0 ? 1 : shape[d];
    index[d] = flat % extent;
    flat /= extent;
  }
  std::string text = "[";
  for (std::size_t d = 0; d < index.size(); ++d) text += (d > 0 ? ", " : "") + std::to_string(index[d]);
  return text + "]";
}

std::string FormatNumber(double value) {
  char text[64];
  std::snprintf(text, sizeof text, "%.10g", value);
  return text;
}

// The checks of `atmo sample` on one point (apps/atmo/grid.cc CheckPoint): finite values, an
// altitude within kMaxAltitude_m, zenith angles in [0, 180] degrees.
void CheckPoint(double altitude_m, double sun_zenith_deg, double view_zenith_deg, double azimuth_deg,
                const std::string& where) {
  const std::pair<const char*, double> values[] = {{"altitude_m", altitude_m},
                                                   {"sun_zenith_deg", sun_zenith_deg},
                                                   {"view_zenith_deg", view_zenith_deg},
                                                   {"azimuth_deg", azimuth_deg}};
  for (const auto& [name, value] : values) {
    if (!std::isfinite(value)) throw Error(where + name + " is not a finite number");
  }
  if (!(std::fabs(altitude_m) <= kMaxAltitude_m)) {
    throw Error(where + "altitude_m " + FormatNumber(altitude_m) + " is outside [-1e+11, 1e+11] m");
  }
  for (const auto& [name, value] : {values[1], values[2]}) {
    if (value < 0.0 || value > 180.0) throw Error(where + name + " " + FormatNumber(value) + " is outside [0, 180]");
  }
}

// A model and the parameters it was made from.
class PyModel {
 public:
  // Exactly one source of parameters: a preset name, a JSON file or a JSON text (the Python layer
  // turns a dict into JSON text). spectral 0 and no wavelengths: as they are.
  PyModel(const std::string& name, const std::optional<std::string>& preset, const std::optional<std::string>& config_path,
          const std::optional<std::string>& config_json, int spectral, const std::vector<double>& wavelengths,
          const ModelOptions& options, const AerosolRequest& aerosol)
      : options_(options) {
    py::gil_scoped_release release;
    if (config_json) {
      parameters_ = FromJson(*config_json);
    } else if (config_path) {
      parameters_ = LoadParametersFile(*config_path);
    } else {
      parameters_ = Preset(preset.value_or("earth"));
    }
    if (spectral != 0) parameters_ = MakeSpectral(parameters_, spectral);
    if (!wavelengths.empty()) parameters_ = MakeSpectral(parameters_, wavelengths);
    ApplyAerosolRequest(parameters_, aerosol);  // after spectral, as the CLI's knobs
    model_ = CreateModel(name, parameters_, options_);
  }

  const Model& model() const { return *model_; }
  const AtmosphereParameters& parameters() const { return parameters_; }

  // The model's view for an observer altitude and a sun zenith (the sun at compass azimuth 0),
  // kept for the next calls: a view builds per-view tables (hillaire's sky-view tables, a few
  // ms), which repeated queries from one observer need not pay again. The last kViewCacheSize
  // views are kept; safe to call from several threads.
  std::shared_ptr<const SkyView> View(double altitude_m, double sun_zenith_deg) const {
    const std::pair<double, double> key(altitude_m, sun_zenith_deg);
    {
      std::lock_guard<std::mutex> lock(views_mutex_);
      for (auto it = views_.begin(); it != views_.end(); ++it) {
        if (std::memcmp(&it->first, &key, sizeof key) == 0) {
          views_.splice(views_.begin(), views_, it);  // most recently used first
          return views_.front().second;
        }
      }
    }
    std::shared_ptr<const SkyView> view =
        model_->View(altitude_m, DirectionFromZenithAzimuth(glm::radians(sun_zenith_deg), 0.0));
    std::lock_guard<std::mutex> lock(views_mutex_);
    views_.emplace_front(key, view);
    if (views_.size() > kViewCacheSize) views_.pop_back();
    return view;
  }

  // The model for a Monte Carlo frame in physical units: its images multiply the radiance by the
  // model's own solar_irradiance (RenderProgressive), so that is 1 there, as `atmo render` makes it.
  const Model& UnitIrradianceModel() const {
    std::lock_guard<std::mutex> lock(unit_irradiance_mutex_);
    if (!unit_irradiance_model_) {
      AtmosphereParameters ones = parameters_;
      ones.solar_irradiance.assign(ones.channel_count(), 1.0);
      unit_irradiance_model_ = CreateModel(model_->name(), ones, options_);
    }
    return *unit_irradiance_model_;
  }

 private:
  AtmosphereParameters parameters_;
  ModelOptions options_;
  std::unique_ptr<Model> model_;
  mutable std::mutex unit_irradiance_mutex_;
  mutable std::unique_ptr<Model> unit_irradiance_model_;
  static constexpr std::size_t kViewCacheSize = 8;
  mutable std::mutex views_mutex_;
  mutable std::list<std::pair<std::pair<double, double>, std::shared_ptr<const SkyView>>> views_;
};

// The points of a sample that share an altitude and a sun zenith: one SkyView.
struct PointGroup {
  double altitude_m = 0.0;
  double sun_zenith_deg = 0.0;
  std::vector<std::size_t> indices;
};

std::vector<PointGroup> GroupPoints(const double* altitude_m, const double* sun_zenith_deg, std::size_t n) {
  std::vector<PointGroup> groups;
  // Keys by bit pattern (the values are finite; -0 and +0 land in two groups of equal views).
  struct KeyHash {
    std::size_t operator()(const std::pair<std::uint64_t, std::uint64_t>& k) const {
      return std::hash<std::uint64_t>()(k.first * 0x9E3779B97F4A7C15ull ^ k.second);
    }
  };
  std::unordered_map<std::pair<std::uint64_t, std::uint64_t>, std::size_t, KeyHash> group_of;
  std::pair<std::uint64_t, std::uint64_t> last_key{};
  std::size_t last_group = std::numeric_limits<std::size_t>::max();
  for (std::size_t i = 0; i < n; ++i) {
    std::pair<std::uint64_t, std::uint64_t> key;
    std::memcpy(&key.first, &altitude_m[i], sizeof(double));
    std::memcpy(&key.second, &sun_zenith_deg[i], sizeof(double));
    if (last_group == std::numeric_limits<std::size_t>::max() || key != last_key) {  // runs are common
      const auto [found, inserted] = group_of.emplace(key, groups.size());
      if (inserted) groups.push_back({altitude_m[i], sun_zenith_deg[i], {}});
      last_key = key;
      last_group = found->second;
    }
    groups[last_group].indices.push_back(i);
  }
  return groups;
}

// Per point and channel: radiance, transmittance and the standard error of the radiance, in the
// unit of `atmo sample --unit`, into outputs of n x (channels) doubles (one "channel" for
// luminance: cd/m^2 and the luminous transmittance, apps/atmo/sample_command.cc). `shape` is the
// points' array shape, for error messages. Runs on oneTBB's threads; call it without the GIL.
void EvaluateSample(const PyModel& self, const double* alt, const double* sz, const double* vz, const double* az,
                    std::size_t n, RadianceUnit unit, const std::vector<std::size_t>& shape, double* out_radiance,
                    double* out_transmittance, double* out_error) {
  const AtmosphereParameters& parameters = self.parameters();
  const std::size_t nc = parameters.channel_count();
  for (std::size_t i = 0; i < n; ++i) {
    if (!(std::isfinite(alt[i]) && std::isfinite(sz[i]) && std::isfinite(vz[i]) && std::isfinite(az[i]) &&
          std::fabs(alt[i]) <= kMaxAltitude_m && sz[i] >= 0.0 && sz[i] <= 180.0 && vz[i] >= 0.0 && vz[i] <= 180.0)) {
      CheckPoint(alt[i], sz[i], vz[i], az[i], "sample " + IndexText(i, shape) + ": ");
    }
  }
  const SpectralConversion convert(parameters.wavelengths_nm);
  const std::size_t out_channels = SampleChannels(unit, nc);
  const std::vector<PointGroup> groups = GroupPoints(alt, sz, n);
  // Groups in parallel (each builds its view's tables), and each group's points in parallel.
  oneapi::tbb::parallel_for(std::size_t{0}, groups.size(), [&](std::size_t g) {
    const PointGroup& group = groups[g];
    const std::shared_ptr<const SkyView> sky = self.View(group.altitude_m, group.sun_zenith_deg);
    oneapi::tbb::parallel_for(
        oneapi::tbb::blocked_range<std::size_t>(0, group.indices.size(), 256),
        [&](const oneapi::tbb::blocked_range<std::size_t>& range) {
          std::vector<double> l(nc), t(nc), e(nc);
          for (std::size_t k = range.begin(); k < range.end(); ++k) {
            const std::size_t i = group.indices[k];
            const glm::dvec3 view = DirectionFromZenithAzimuth(glm::radians(vz[i]), glm::radians(az[i]));
            std::fill(e.begin(), e.end(), 0.0);
            sky->RadianceEstimate(view, l, e);
            sky->Transmittance(view, t);
            const std::size_t at = i * out_channels;
            ConvertSample(convert, unit, l, t, e, std::span<double>(out_radiance + at, out_channels),
                          std::span<double>(out_transmittance + at, out_channels),
                          std::span<double>(out_error + at, out_channels));
          }
        });
  });
}

py::tuple Sample(const PyModel& self, Array altitude_m, Array sun_zenith_deg, Array view_zenith_deg, Array azimuth_deg,
                 const std::string& unit_name, const std::vector<std::size_t>& shape) {
  const std::size_t n = static_cast<std::size_t>(altitude_m.size());
  for (const Array* a : {&sun_zenith_deg, &view_zenith_deg, &azimuth_deg}) {
    if (static_cast<std::size_t>(a->size()) != n) throw Error("sample: the four arrays must have one size");
  }
  const RadianceUnit unit = ParseRadianceUnit(unit_name);
  const std::size_t out_channels = unit == RadianceUnit::kLuminance ? 1 : self.parameters().channel_count();
  Array radiance({n, out_channels});
  Array transmittance({n, out_channels});
  Array standard_error({n, out_channels});
  const double* alt = altitude_m.data();
  const double* sz = sun_zenith_deg.data();
  const double* vz = view_zenith_deg.data();
  const double* az = azimuth_deg.data();
  double* out_radiance = radiance.mutable_data();
  double* out_transmittance = transmittance.mutable_data();
  double* out_error = standard_error.mutable_data();
  {
    py::gil_scoped_release release;
    EvaluateSample(self, alt, sz, vz, az, n, unit, shape, out_radiance, out_transmittance, out_error);
  }
  return py::make_tuple(radiance, transmittance, standard_error);
}

// The benchmark's C++ side of `sample` (python/bench_sample.py): seconds of the best of `repeats`
// runs of EvaluateSample on the four arrays (of one size) into fresh C++ outputs, the work of
// Model.sample without its Python layer and NumPy arrays.
double TimeSample(const PyModel& self, Array altitude_m, Array sun_zenith_deg, Array view_zenith_deg,
                  Array azimuth_deg, int repeats) {
  const std::size_t n = static_cast<std::size_t>(altitude_m.size());
  for (const Array* a : {&sun_zenith_deg, &view_zenith_deg, &azimuth_deg}) {
    if (static_cast<std::size_t>(a->size()) != n) throw Error("the four arrays must have one size");
  }
  const std::size_t nc = self.parameters().channel_count();
  py::gil_scoped_release release;
  double best = std::numeric_limits<double>::infinity();
  for (int r = 0; r < std::max(repeats, 1); ++r) {
    const auto start = std::chrono::steady_clock::now();
    std::vector<double> radiance(n * nc), transmittance(n * nc), standard_error(n * nc);
    EvaluateSample(self, altitude_m.data(), sun_zenith_deg.data(), view_zenith_deg.data(), azimuth_deg.data(), n,
                   RadianceUnit::kRelative, {n}, radiance.data(), transmittance.data(), standard_error.data());
    best = std::min(best, std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count());
  }
  return best;
}

// The view directions of a camera's pixel centres (H x W x 3, local frame x east, y north, z up),
// as the renderer forms them; 0 where the camera sees nothing (outside a fisheye's circle).
Array CameraDirections(const std::string& kind, int width, int height, double fov_deg, double yaw_deg, double pitch_deg) {
  Camera camera;
  camera.kind = ParseCameraKind(kind);
  camera.width = width;
  camera.height = height;
  camera.fov_deg = fov_deg;
  camera.yaw_deg = yaw_deg;
  camera.pitch_deg = pitch_deg;
  ValidateCamera(camera);
  Array out({static_cast<std::size_t>(height), static_cast<std::size_t>(width), std::size_t{3}});
  double* data = out.mutable_data();
  const shared::CameraParameters shared_camera = ToSharedCamera(camera);
  std::vector<glm::dvec3> row(static_cast<std::size_t>(width));
  for (int y = 0; y < height; ++y) {
    if (shared_camera.kind == shared::kCameraPerspective) {
      PerspectiveRowDirections(shared_camera, y, row);
    } else {
      for (int x = 0; x < width; ++x) {
        shared::vec3 direction;
        const bool seen = shared::GetCameraRayDirection(shared_camera, shared::vec2(x + 0.5, y + 0.5), direction);
        row[x] = seen ? glm::dvec3(direction) : glm::dvec3(0.0);
      }
    }
    for (int x = 0; x < width; ++x) {
      for (int k = 0; k < 3; ++k) data[(static_cast<std::size_t>(y) * width + x) * 3 + k] = row[x][k];
    }
  }
  return out;
}

// SkyView::RadianceBatch on directions (N x 3, unit or 0) for one observer and sun: float32 N x C.
FloatArray RadianceBatch(const PyModel& self, double altitude_m, double sun_zenith_deg, Array directions,
                         bool sun_disc, bool ground) {
  if (directions.ndim() != 2 || directions.shape(1) != 3) throw Error("radiance_batch: directions must be N x 3");
  CheckPoint(altitude_m, sun_zenith_deg, 0.0, 0.0, "radiance_batch: ");
  const std::size_t n = static_cast<std::size_t>(directions.shape(0));
  const std::size_t nc = self.parameters().channel_count();
  FloatArray out({n, nc});
  const glm::dvec3* views = reinterpret_cast<const glm::dvec3*>(directions.data());
  static_assert(sizeof(glm::dvec3) == 3 * sizeof(double));
  float* data = out.mutable_data();
  {
    py::gil_scoped_release release;
    const std::shared_ptr<const SkyView> sky = self.View(altitude_m, sun_zenith_deg);
    const RadianceTerms terms{sun_disc, ground};
    // Chunks of directions in parallel, as a frame's rows are.
    oneapi::tbb::parallel_for(oneapi::tbb::blocked_range<std::size_t>(0, n, 4096),
                              [&](const oneapi::tbb::blocked_range<std::size_t>& range) {
                                sky->RadianceBatch(std::span<const glm::dvec3>(views + range.begin(), range.size()),
                                                   terms, std::span<float>(data + range.begin() * nc, range.size() * nc));
                              });
  }
  return out;
}

// The benchmark's C++ side (python/bench_sample.py): seconds of the best of `repeats` runs of
// SkyView::RadianceBatch over `directions` (N x 3) in chunks on oneTBB's threads, as a frame
// uses it, for one observer and sun; the view's tables are made before the clock starts. With
// `parallel` false: one call on the calling thread.
double TimeRadianceBatch(const PyModel& self, double altitude_m, double sun_zenith_deg, Array directions, int repeats,
                         bool parallel) {
  if (directions.ndim() != 2 || directions.shape(1) != 3) throw Error("directions must be N x 3");
  const std::size_t n = static_cast<std::size_t>(directions.shape(0));
  const std::size_t nc = self.parameters().channel_count();
  const glm::dvec3* views = reinterpret_cast<const glm::dvec3*>(directions.data());
  py::gil_scoped_release release;
  const std::shared_ptr<const SkyView> sky = self.View(altitude_m, sun_zenith_deg);
  std::vector<float> out(n * nc);
  const RadianceTerms terms{false, false};
  double best = std::numeric_limits<double>::infinity();
  for (int r = 0; r < std::max(repeats, 1); ++r) {
    const auto start = std::chrono::steady_clock::now();
    if (parallel) {
      oneapi::tbb::parallel_for(oneapi::tbb::blocked_range<std::size_t>(0, n, 4096),
                                [&](const oneapi::tbb::blocked_range<std::size_t>& range) {
                                  sky->RadianceBatch(std::span<const glm::dvec3>(views + range.begin(), range.size()),
                                                     terms, std::span<float>(out.data() + range.begin() * nc,
                                                                             range.size() * nc));
                                });
    } else {
      sky->RadianceBatch(std::span<const glm::dvec3>(views, n), terms, out);
    }
    best = std::min(best, std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count());
  }
  return best;
}

// An Image as an H x W x C float32 array (copied).
FloatArray ToArray(const Image& image) {
  FloatArray out({static_cast<std::size_t>(image.height), static_cast<std::size_t>(image.width),
                  static_cast<std::size_t>(image.channels)});
  std::memcpy(out.mutable_data(), image.pixels.data(), image.pixels.size() * sizeof(float));
  return out;
}

py::object AlphaOf(const Image& image) {
  if (image.alpha.empty()) return py::none();
  FloatArray alpha({static_cast<std::size_t>(image.height), static_cast<std::size_t>(image.width)});
  std::memcpy(alpha.mutable_data(), image.alpha.data(), image.alpha.size() * sizeof(float));
  return alpha;
}

std::string ColourSpaceName(ColourSpace space) {
  switch (space) {
    case ColourSpace::kLinearSrgb: return "linear_srgb";
    case ColourSpace::kCieXyz: return "xyz";
    case ColourSpace::kUnspecified: break;
  }
  return "";
}

ColourSpace ParseColourSpace(const std::string& name) {
  if (name.empty()) return ColourSpace::kUnspecified;
  if (name == "linear_srgb") return ColourSpace::kLinearSrgb;
  if (name == "xyz") return ColourSpace::kCieXyz;
  throw Error("unknown colour space '" + name + "' (use linear_srgb, xyz or none)");
}

// CIE XYZ of a linear sRGB image, per pixel (as `atmo render --xyz`).
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

struct RenderRequest {
  std::string camera = "perspective";
  int width = 1280;
  int height = 720;
  double fov_deg = 90.0;
  double yaw_deg = 0.0;
  double pitch_deg = 10.0;
  double altitude_m = 0.0;
  double sun_elevation_deg = 10.0;
  double sun_azimuth_deg = 180.0;
  bool sun_disc = true;
  bool ground = true;
  std::string unit = "luminance";
  bool xyz = false;
  std::uint64_t spp = 0;  // Monte Carlo models; 0: their samples option
  bool night_sky = true;  // the night sky's own light (include/atmo/night_sky.h)
  // A moon by hand (include/atmo/moon.h): NaN elevation for none; the azimuth defaults to opposite
  // the sun, as on the command line.
  double moon_elevation_deg = std::numeric_limits<double>::quiet_NaN();
  double moon_azimuth_deg = std::numeric_limits<double>::quiet_NaN();
  double moon_phase_deg = std::numeric_limits<double>::quiet_NaN();
  double moon_distance_km = kMoonReferenceDistanceKm;  // the moon_position of a date gives its own
};

// The moon of a Python call and its own view of the model (RadianceTerms::moon), or none.
struct PyMoon {
  std::optional<Moon> moon;
  std::unique_ptr<SkyView> sky;
};

PyMoon MakeMoon(const Model& model, double altitude_m, double sun_elevation_deg, double sun_azimuth_deg,
                double moon_elevation_deg, double moon_azimuth_deg, double moon_phase_deg, double moon_distance_km) {
  PyMoon result;
  if (std::isnan(moon_elevation_deg) && std::isnan(moon_phase_deg) && std::isnan(moon_azimuth_deg)) return result;
  if (!std::isfinite(moon_elevation_deg) || !std::isfinite(moon_phase_deg)) {
    throw Error("a moon needs a finite moon_elevation_deg and moon_phase_deg (moon_azimuth_deg: default opposite the sun)");
  }
  if (moon_elevation_deg < -90.0 || moon_elevation_deg > 90.0) {
    throw Error("moon_elevation_deg must be in [-90, 90] (got " + std::to_string(moon_elevation_deg) + ")");
  }
  const double azimuth = std::isnan(moon_azimuth_deg) ? std::fmod(sun_azimuth_deg + 180.0, 360.0) : moon_azimuth_deg;
  if (!std::isfinite(azimuth)) throw Error("moon_azimuth_deg must be finite");
  const glm::dvec3 direction = SunDirection(moon_elevation_deg, azimuth);
  result.moon.emplace(direction, moon_phase_deg, moon_distance_km, model.parameters().wavelengths_nm,
                      SunDirection(sun_elevation_deg, sun_azimuth_deg));
  result.sky = model.View(altitude_m, direction);
  return result;
}

// Debian's stellarium-data's stars when installed (include/atmo/stars.h), else none.
const StarCatalogue* InstalledStars() {
  std::error_code error;
  if (!std::filesystem::is_directory(StarCatalogue::DefaultFolder(), error)) return nullptr;
  return &StarCatalogue::Default();
}

// One frame as `atmo render` makes it on the CPU backend. Returns (image H x W x C, alpha H x W or
// None, channel names, colour space, standard error H x W x C or None).
py::tuple RenderFrame(const PyModel& self, const RenderRequest& request) {
  const RadianceUnit unit = ParseRadianceUnit(request.unit);
  if (request.xyz && unit != RadianceUnit::kLuminance) throw Error("xyz needs unit luminance");
  const AtmosphereParameters& parameters = self.parameters();
  const bool cubemap = request.camera == "cubemap";
  Image image;
  Image standard_error;
  {
    py::gil_scoped_release release;
    if (!std::isfinite(request.altitude_m)) throw Error("altitude must be a finite number");
    const SpectralConversion convert(parameters.wavelengths_nm);
    const std::vector<glm::vec3> srgb_weights = ColourWeights(convert, ImageColour::kLinearSrgb);
    const std::vector<double> ones(parameters.channel_count(), 1.0);
    // The models answer per unit solar irradiance: a relative frame multiplies by the preset's
    // solar_irradiance, physical units bring in the solar spectrum through the conversion.
    const std::vector<double>& irradiance = unit == RadianceUnit::kRelative ? parameters.solar_irradiance : ones;
    RadianceTerms terms{request.sun_disc, request.ground};
    // The night sky's own light, as `atmo render` adds it (default ecliptic).
    std::optional<NightSky> night;
    if (request.night_sky && std::isfinite(request.altitude_m) && std::isfinite(request.sun_elevation_deg) &&
        std::isfinite(request.sun_azimuth_deg)) {
      const glm::dvec3 sun = SunDirection(request.sun_elevation_deg, request.sun_azimuth_deg);
      terms.night_sky = &night.emplace(parameters, std::max(request.altitude_m, 0.0), sun);
      // The stars, as `atmo render` adds them, when Debian's stellarium-data is installed.
      if (const StarCatalogue* stars = InstalledStars(); stars != nullptr) {
        night->SetStars(*stars, CelestialFrame::FromSun(sun));
      }
    }
    const ImageColour colour = unit == RadianceUnit::kRadiance ? ImageColour::kSpectral
                               : request.xyz                   ? ImageColour::kXyz
                                                               : ImageColour::kLinearSrgb;
    const Model& model = self.model();
    const PyMoon moon = MakeMoon(model, request.altitude_m, request.sun_elevation_deg, request.sun_azimuth_deg,
                                 request.moon_elevation_deg, request.moon_azimuth_deg, request.moon_phase_deg,
                                 request.moon_distance_km);
    if (moon.moon) {
      terms.moon = &*moon.moon;
      terms.moon_sky = moon.sky.get();
    }
    if (cubemap) {
      if (IsMonteCarlo(model)) throw Error("camera cubemap needs a deterministic model, not " + std::string(model.name()));
      if (request.width < 1 || request.width > kMaxImageSide) {
        throw Error("cubemap face size must be in 1.." + std::to_string(kMaxImageSide) + " (got " +
                    std::to_string(request.width) + ")");
      }
      const std::unique_ptr<SkyView> sky =
          model.View(request.altitude_m, SunDirection(request.sun_elevation_deg, request.sun_azimuth_deg));
      Cubemap cube = unit == RadianceUnit::kLuminance ? RenderCubemapFolded(*sky, request.width, terms, srgb_weights)
                                                      : RenderCubemap(*sky, request.width, terms, irradiance);
      image = CubemapExrImage(cube);
      if (unit == RadianceUnit::kLuminance) {
        image.colour_space = ColourSpace::kLinearSrgb;
        if (request.xyz) image = LinearSrgbImageToXyz(image);
      } else if (unit == RadianceUnit::kRadiance) {
        const EnvMap envmap = image.envmap;
        image = ConvertImage(image, convert, ImageColour::kSpectral);
        image.envmap = envmap;
      }
    } else {
      RenderSettings settings;
      settings.camera.kind = ParseCameraKind(request.camera);
      settings.camera.width = request.width;
      settings.camera.height = request.height;
      settings.camera.fov_deg = request.fov_deg;
      settings.camera.yaw_deg = request.yaw_deg;
      settings.camera.pitch_deg = request.pitch_deg;
      settings.altitude_m = request.altitude_m;
      settings.sun_elevation_deg = request.sun_elevation_deg;
      settings.sun_azimuth_deg = request.sun_azimuth_deg;
      settings.terms = terms;
      ValidateCamera(settings.camera);
      if (!std::isfinite(settings.sun_elevation_deg) || !std::isfinite(settings.sun_azimuth_deg)) {
        throw Error("the sun elevation and azimuth must be finite");
      }
      if (IsMonteCarlo(model)) {
        // Progressive, as `atmo render` renders it; in physical units from the model of unit
        // solar irradiance, then converted.
        ProgressiveSettings progressive;
        progressive.samples_per_pixel = request.spp;
        const Model& source = unit == RadianceUnit::kRelative ? model : self.UnitIrradianceModel();
        const ProgressiveImage result = RenderProgressive(source, settings, progressive);
        image = result.radiance;
        standard_error = result.standard_error;
        if (unit != RadianceUnit::kRelative) {
          image = ConvertImage(image, convert, colour);
          standard_error = ConvertStandardError(standard_error, convert, colour);
        }
      } else {
        if (request.spp != 0) {
          throw Error("spp is the number of Monte Carlo paths per pixel of model reference; model '" +
                      std::string(model.name()) + "' is deterministic and takes no spp");
        }
        const std::unique_ptr<SkyView> sky =
            model.View(settings.altitude_m, SunDirection(settings.sun_elevation_deg, settings.sun_azimuth_deg));
        if (unit == RadianceUnit::kLuminance) {
          image = RenderViewFolded(*sky, settings.camera, settings.terms, srgb_weights);
          image.colour_space = ColourSpace::kLinearSrgb;
          if (request.xyz) image = LinearSrgbImageToXyz(image);
        } else {
          image = RenderView(*sky, settings.camera, settings.terms, irradiance);
          if (unit == RadianceUnit::kRadiance) {
            const EnvMap envmap = image.envmap;
            image = ConvertImage(image, convert, ImageColour::kSpectral);
            image.envmap = envmap;
          }
        }
      }
    }
  }
  std::vector<std::string> names = image.channel_names;
  if (names.empty()) {
    for (int c = 0; c < image.channels; ++c) {
      names.push_back(image.channels == 3 ? std::string(1, "RGB"[c]) : "C" + std::to_string(c));
    }
  }
  const std::string envmap = image.envmap == EnvMap::kLatLong ? "latlong" : image.envmap == EnvMap::kCube ? "cube" : "";
  return py::make_tuple(ToArray(image), AlphaOf(image), names, ColourSpaceName(image.colour_space), envmap,
                        standard_error.width > 0 ? py::object(ToArray(standard_error)) : py::none());
}

// An H x W x C float32 array (C >= 1) with optional H x W alpha as an Image.
Image FromArray(const FloatArray& array, const std::optional<FloatArray>& alpha) {
  if (array.ndim() != 3 && array.ndim() != 2) throw Error("an image must be an H x W x C (or H x W) array");
  Image image;
  image.height = static_cast<int>(array.shape(0));
  image.width = static_cast<int>(array.shape(1));
  image.channels = array.ndim() == 3 ? static_cast<int>(array.shape(2)) : 1;
  if (image.width < 1 || image.height < 1 || image.channels < 1) throw Error("an image needs at least one pixel and one channel");
  image.pixels.assign(array.data(), array.data() + array.size());
  if (alpha) {
    if (alpha->ndim() != 2 || alpha->shape(0) != image.height || alpha->shape(1) != image.width) {
      throw Error("alpha must be an H x W array of the image's size");
    }
    image.alpha.assign(alpha->data(), alpha->data() + alpha->size());
  }
  return image;
}

// A cube map array in OpenEXR's layout (6 N x N x C, as Model.render(camera="cubemap") returns
// it) as a Cubemap; and back.
Cubemap CubeFromArray(const FloatArray& array) {
  Image image = FromArray(array, std::nullopt);
  image.colour_space = ColourSpace::kLinearSrgb;
  return CubemapFromExrImage(image);
}
FloatArray CubeToArray(const Cubemap& cube) { return ToArray(CubemapExrImage(cube)); }

void WriteKtx2Array(const std::string& path, const std::vector<FloatArray>& levels, bool mips, bool float32) {
  if (levels.empty()) throw Error("write_ktx2 needs a cube map (or its levels)");
  if (mips && levels.size() != 1) throw Error("write_ktx2: mips=True makes the chain from one cube map; got levels");
  std::vector<Cubemap> chain;
  for (const FloatArray& level : levels) chain.push_back(CubeFromArray(level));
  py::gil_scoped_release release;
  while (mips && chain.back().face_size > 1) chain.push_back(DownsampleCubemap(chain.back()));
  WriteKtx2(path, chain, float32, std::string("atmo ") + ATMO_VERSION + " (Python)");
}

py::dict SphericalHarmonicsOf(const FloatArray& array, const std::string& frame) {
  if (frame != "enu" && frame != "y_up") throw Error("frame must be 'enu' or 'y_up' (got '" + frame + "')");
  const Cubemap cube = CubeFromArray(array);
  if (cube.channels() != 3) throw Error("spherical_harmonics needs a 3-channel cube map");
  SphericalHarmonics sh;
  {
    py::gil_scoped_release release;
    sh = ProjectSphericalHarmonics(cube, frame == "enu" ? ShFrame::kEnu : ShFrame::kCube);
  }
  const std::array<glm::dvec3, 9> irradiance = ShIrradianceCoefficients(sh);
  py::array_t<double> radiance_out({9, 3}), irradiance_out({9, 3});
  auto r = radiance_out.mutable_unchecked<2>();
  auto e = irradiance_out.mutable_unchecked<2>();
  for (int i = 0; i < 9; ++i) {
    for (int c = 0; c < 3; ++c) {
      r(i, c) = sh.radiance[i][c];
      e(i, c) = irradiance[i][c];
    }
  }
  py::dict d;
  d["frame"] = frame;
  d["radiance"] = radiance_out;
  d["irradiance"] = irradiance_out;
  return d;
}

FloatArray IrradianceCubemapArray(const FloatArray& array, int size, int source_size) {
  const Cubemap cube = CubeFromArray(array);
  Cubemap out;
  {
    py::gil_scoped_release release;
    out = IrradianceCubemap(cube, size, source_size);
  }
  return CubeToArray(out);
}

std::vector<FloatArray> SpecularCubemapArrays(const FloatArray& array, int levels, int samples) {
  const Cubemap cube = CubeFromArray(array);
  SpecularSettings settings;
  settings.levels = levels;
  settings.samples = samples;
  std::vector<Cubemap> chain;
  {
    py::gil_scoped_release release;
    chain = PrefilterSpecular(cube, settings);
  }
  std::vector<FloatArray> out;
  for (const Cubemap& level : chain) out.push_back(CubeToArray(level));
  return out;
}

// `atmo precompute`: the tables of elek (its 4D scattering table and transmittance) or hillaire
// (its six tables for one observer and sun, with atmo precompute's default camera and aerial
// volume) written as NAME.json and NAME*.exr/.raw; the paths written.
std::vector<std::string> ExportTables(const PyModel& self, const std::string& name, double altitude_m,
                                      double sun_elevation_deg, double sun_azimuth_deg) {
  if (name.empty() || name.back() == '/') throw Error("export_tables needs the tables' NAME (NAME.json, ...)");
  std::vector<std::string> written;
  py::gil_scoped_release release;
  const std::string model = std::string(self.model().name());
  if (model == "elek") {
    const ElekTableFiles files = ExportElekTable(self.model(), name);
    for (const auto& path : {files.exr, files.raw, files.transmittance_exr, files.transmittance_raw, files.json}) {
      written.push_back(path.string());
    }
    return written;
  }
  if (model != "hillaire") {
    throw Error("export_tables writes the tables of models elek and hillaire; model " + model + " has none");
  }
  HillaireExportView view;
  view.altitude_m = altitude_m;
  view.sun_elevation_deg = sun_elevation_deg;
  view.sun_azimuth_deg = sun_azimuth_deg;
  view.camera.kind = CameraKind::kPerspective;  // atmo precompute's defaults
  view.camera.width = 1280;
  view.camera.height = 720;
  view.camera.fov_deg = 90.0;
  view.camera.yaw_deg = sun_azimuth_deg;
  view.camera.pitch_deg = 10.0;
  ValidateHillaireExportView(self.parameters(), view);
  const HillaireTableFiles files = ExportHillaireTables(ComputeHillaireTables(self.model(), view), name);
  for (const auto& path : files.all()) written.push_back(path.string());
  return written;
}

void WriteExrArray(const std::string& path, const FloatArray& array, const std::optional<FloatArray>& alpha,
                   const std::vector<std::string>& channel_names, const std::string& colour_space,
                   const std::string& envmap, const ImageMetadata& metadata) {
  Image image = FromArray(array, alpha);
  image.channel_names = channel_names;
  image.colour_space = ParseColourSpace(colour_space);
  if (envmap == "latlong") {
    image.envmap = EnvMap::kLatLong;
  } else if (envmap == "cube") {
    image.envmap = EnvMap::kCube;
  } else if (!envmap.empty()) {
    throw Error("unknown envmap '" + envmap + "' (use latlong, cube or none)");
  }
  py::gil_scoped_release release;
  WriteExr(path, image, metadata);
}

py::tuple ReadExrArray(const std::string& path) {
  ImageMetadata metadata;
  Image image;
  {
    py::gil_scoped_release release;
    image = ReadExr(path, &metadata);
  }
  py::dict attributes;
  for (const auto& [key, value] : metadata) attributes[py::str(key)] = value;
  return py::make_tuple(ToArray(image), AlphaOf(image), image.channel_names, attributes);
}

void WritePngArray(const std::string& path, const FloatArray& array, const std::optional<FloatArray>& alpha,
                   std::optional<double> exposure, std::optional<double> ev100, const std::string& tonemap,
                   std::optional<double> gamma, bool per_channel, bool dither, int bits, const std::string& metering) {
  Image image = FromArray(array, alpha);
  if (image.channels != 3) throw Error("write_png needs an image of 3 channels (linear sRGB), got " + std::to_string(image.channels));
  if (exposure && ev100) throw Error("give exposure or ev100, not both");
  if (bits != 8 && bits != 16) throw Error("bits must be 8 or 16 (got " + std::to_string(bits) + ")");
  ToneMapping mapping;
  mapping.op = ParseToneMapper(tonemap);
  const Metering meter = ParseMetering(metering);
  if (gamma) {
    if (!(*gamma > 0.0) || !std::isfinite(*gamma)) throw Error("gamma must be a positive number");
    mapping.transfer = DisplayTransfer::kGamma;
    mapping.gamma = *gamma;
  }
  mapping.per_channel = per_channel;
  mapping.dither = dither;
  mapping.bit_depth = bits;
  py::gil_scoped_release release;
  if (exposure) {
    if (!std::isfinite(*exposure) || *exposure < 0.0) throw Error("exposure must be a finite number >= 0");
    mapping.exposure = *exposure;
  } else {
    // The `atmo render` default for colour images: auto-exposure (docs/display.md).
    mapping.exposure = ExposureFromEv100(ev100 ? *ev100 : AutoExposureEv100(image, meter));
  }
  WritePng(path, image, mapping);
}

// `atmo --threads N`: at most N worker threads for everything that follows; 0 lifts the limit.
void SetThreads(int threads) {
  static std::unique_ptr<oneapi::tbb::global_control> limit;
  if (threads < 0 || threads > 1024) throw Error("threads must be in 0..1024 (got " + std::to_string(threads) + ")");
  limit.reset();
  if (threads > 0) {
    limit = std::make_unique<oneapi::tbb::global_control>(oneapi::tbb::global_control::max_allowed_parallelism,
                                                          static_cast<std::size_t>(threads));
  }
}

}  // namespace
}  // namespace atmo::python

namespace atmo::python {
void AddDaylightBindings(py::module_& m);  // daylight_bindings.cc
}  // namespace atmo::python

PYBIND11_MODULE(_atmo, m) {
  using namespace atmo;
  using namespace atmo::python;
  m.doc() = "atmo's compiled bindings; use the package `atmo` (docs/python.md)";
  py::register_exception_translator([](std::exception_ptr p) {
    try {
      if (p) std::rethrow_exception(p);
    } catch (const atmo::Error& error) {
      PyErr_SetString(PyExc_ValueError, error.what());
    }
  });

  py::class_<PyModel>(m, "Model")
      .def(py::init([](const std::string& name, const std::optional<std::string>& preset,
                       const std::optional<std::string>& config_path, const std::optional<std::string>& config_json,
                       int spectral, const ModelOptions& options, const std::optional<std::string>& aerosol,
                       std::optional<double> aod, std::optional<double> angstrom, std::optional<double> visibility,
                       std::optional<double> turbidity, const std::vector<double>& wavelengths,
                       const std::optional<std::string>& aerosol_phase) {
             AerosolRequest request;
             request.type = aerosol;
             request.phase = aerosol_phase;
             request.aod_550 = aod;
             request.angstrom_exponent = angstrom;
             request.visibility_km = visibility;
             request.linke_turbidity = turbidity;
             return std::make_unique<PyModel>(name, preset, config_path, config_json, spectral, wavelengths, options,
                                              request);
           }),
           py::arg("name"), py::arg("preset"), py::arg("config_path"), py::arg("config_json"), py::arg("spectral"),
           py::arg("options"), py::arg("aerosol") = py::none(), py::arg("aod") = py::none(),
           py::arg("angstrom") = py::none(), py::arg("visibility") = py::none(), py::arg("turbidity") = py::none(),
           py::arg("wavelengths") = std::vector<double>{}, py::arg("aerosol_phase") = py::none())
      .def_property_readonly("name", [](const PyModel& s) { return std::string(s.model().name()); })
      .def_property_readonly("preset", [](const PyModel& s) { return s.parameters().name; })
      .def_property_readonly("channel_count", [](const PyModel& s) { return s.parameters().channel_count(); })
      .def_property_readonly("wavelengths_nm", [](const PyModel& s) { return s.parameters().wavelengths_nm; })
      .def_property_readonly("solar_irradiance", [](const PyModel& s) { return s.parameters().solar_irradiance; })
      .def_property_readonly("solar_spectral_irradiance",
                             [](const PyModel& s) { return SpectralConversion(s.parameters().wavelengths_nm).solar_irradiance(); })
      .def_property_readonly("exposure", [](const PyModel& s) { return s.parameters().exposure; })
      .def_property_readonly("observer_altitude_m", [](const PyModel& s) { return s.parameters().observer_altitude_m; })
      .def_property_readonly("top_altitude_m",
                             [](const PyModel& s) { return s.parameters().top_radius_m - s.parameters().ground_radius_m; })
      .def_property_readonly("monte_carlo", [](const PyModel& s) { return IsMonteCarlo(s.model()); })
      .def_property_readonly("parameter_hash", [](const PyModel& s) { return ParameterHashHex(s.parameters()); })
      .def("parameters_json", [](const PyModel& s) { return ToJson(s.parameters()); })
      .def("export_tables", &ExportTables, py::arg("name"), py::arg("altitude_m"), py::arg("sun_elevation_deg"),
           py::arg("sun_azimuth_deg"))
      .def(
          "illuminance",
          [](const PyModel& self, double altitude_m, double sun_elevation_deg, bool night_sky, double moon_elevation_deg,
             double moon_azimuth_deg, double moon_phase_deg, double moon_distance_km) {
            Illuminance e;
            {
              py::gil_scoped_release release;
              // As `atmo illuminance`: the solar spectrum comes in by colour, the model at irradiance 1.
              const Model& model = self.UnitIrradianceModel();
              const glm::dvec3 sun = SunDirection(sun_elevation_deg, 0.0);
              const std::unique_ptr<SkyView> sky = model.View(altitude_m, sun);
              // The night sky's own light in its own column and in the global, as the command.
              NightSky night(model.parameters(), std::max(altitude_m, 0.0), sun);
              if (const StarCatalogue* stars = InstalledStars(); stars != nullptr && night_sky) {
                night.SetStars(*stars, CelestialFrame::FromSun(sun));
              }
              IlluminanceSettings settings;
              if (night_sky) settings.night_sky = &night;
              const PyMoon moon = MakeMoon(model, altitude_m, sun_elevation_deg, 0.0, moon_elevation_deg,
                                           moon_azimuth_deg, moon_phase_deg, moon_distance_km);
              if (moon.moon) {
                settings.moon = &*moon.moon;
                settings.moon_sky = moon.sky.get();
              }
              e = ComputeIlluminance(*sky, model.parameters(), settings);
            }
            py::dict d;
            d["direct_normal_lux"] = e.direct_normal_lux;
            d["direct_horizontal_lux"] = e.direct_horizontal_lux;
            d["diffuse_horizontal_lux"] = e.diffuse_horizontal_lux;
            d["global_horizontal_lux"] = e.global_horizontal_lux;
            d["direct_normal_w_m2"] = e.direct_normal_w_m2;
            d["diffuse_horizontal_w_m2"] = e.diffuse_horizontal_w_m2;
            d["night_sky_horizontal_lux"] = e.night_sky_horizontal_lux;
            d["night_sky_horizontal_w_m2"] = e.night_sky_horizontal_w_m2;
            d["moon_direct_horizontal_lux"] = e.moon_direct_horizontal_lux;
            d["moon_diffuse_horizontal_lux"] = e.moon_diffuse_horizontal_lux;
            return d;
          },
          py::arg("altitude_m"), py::arg("sun_elevation_deg"), py::arg("night_sky"), py::arg("moon_elevation_deg"),
          py::arg("moon_azimuth_deg"), py::arg("moon_phase_deg"), py::arg("moon_distance_km"))
      .def("sample", &Sample, py::arg("altitude_m"), py::arg("sun_zenith_deg"), py::arg("view_zenith_deg"),
           py::arg("azimuth_deg"), py::arg("unit"), py::arg("shape"))
      .def("radiance_batch", &RadianceBatch, py::arg("altitude_m"), py::arg("sun_zenith_deg"), py::arg("directions"),
           py::arg("sun_disc"), py::arg("ground"))
      .def("time_sample", &TimeSample, py::arg("altitude_m"), py::arg("sun_zenith_deg"), py::arg("view_zenith_deg"),
           py::arg("azimuth_deg"), py::arg("repeats"))
      .def("time_radiance_batch", &TimeRadianceBatch, py::arg("altitude_m"), py::arg("sun_zenith_deg"),
           py::arg("directions"), py::arg("repeats"), py::arg("parallel"))
      .def(
          "render",
          [](const PyModel& self, const std::string& camera, int width, int height, double fov_deg, double yaw_deg,
             double pitch_deg, double altitude_m, double sun_elevation_deg, double sun_azimuth_deg, bool sun_disc,
             bool ground, const std::string& unit, bool xyz, std::uint64_t spp, bool night_sky,
             double moon_elevation_deg, double moon_azimuth_deg, double moon_phase_deg, double moon_distance_km) {
            RenderRequest request{camera,   width,    height, fov_deg, yaw_deg, pitch_deg, altitude_m, sun_elevation_deg,
                                  sun_azimuth_deg, sun_disc, ground, unit,    xyz,     spp,     night_sky,
                                  moon_elevation_deg, moon_azimuth_deg, moon_phase_deg, moon_distance_km};
            return RenderFrame(self, request);
          },
          py::arg("camera"), py::arg("width"), py::arg("height"), py::arg("fov_deg"), py::arg("yaw_deg"),
          py::arg("pitch_deg"), py::arg("altitude_m"), py::arg("sun_elevation_deg"), py::arg("sun_azimuth_deg"),
          py::arg("sun_disc"), py::arg("ground"), py::arg("unit"), py::arg("xyz"), py::arg("spp"),
          py::arg("night_sky"), py::arg("moon_elevation_deg"), py::arg("moon_azimuth_deg"), py::arg("moon_phase_deg"),
          py::arg("moon_distance_km"));

  m.def("camera_directions", &CameraDirections, py::arg("camera"), py::arg("width"), py::arg("height"),
        py::arg("fov_deg"), py::arg("yaw_deg"), py::arg("pitch_deg"));
  m.def("sun_direction", [](double elevation_deg, double azimuth_deg) {
    const glm::dvec3 d = SunDirection(elevation_deg, azimuth_deg);
    return std::vector<double>{d.x, d.y, d.z};
  });
  m.def("write_exr", &WriteExrArray, py::arg("path"), py::arg("image"), py::arg("alpha"), py::arg("channel_names"),
        py::arg("colour_space"), py::arg("envmap"), py::arg("metadata"));
  m.def("read_exr", &ReadExrArray, py::arg("path"));
  m.def("write_png", &WritePngArray, py::arg("path"), py::arg("image"), py::arg("alpha"), py::arg("exposure"),
        py::arg("ev100"), py::arg("tonemap"), py::arg("gamma"), py::arg("per_channel"), py::arg("dither"),
        py::arg("bits"), py::arg("metering"));
  m.def("auto_exposure_ev100", [](const FloatArray& image, const std::optional<FloatArray>& alpha,
                                  const std::string& metering) {
    return AutoExposureEv100(FromArray(image, alpha), ParseMetering(metering));
  }, py::arg("image"), py::arg("alpha") = py::none(), py::arg("metering") = "adaptive");
  m.def("exposure_from_ev100", &ExposureFromEv100);
  m.def("write_hdr", [](const std::string& path, const FloatArray& image) {
    const Image converted = FromArray(image, std::nullopt);
    py::gil_scoped_release release;
    WriteRadianceHdr(path, converted);
  }, py::arg("path"), py::arg("image"));
  m.def("cube_faces_for_three", [](const FloatArray& cube) {
    const Cubemap three = CubeTextureForThree(CubeFromArray(cube));
    std::vector<FloatArray> faces;
    for (const Image& face : three.faces) faces.push_back(ToArray(face));
    return faces;
  }, py::arg("cube"));
  m.def("write_ktx2", &WriteKtx2Array, py::arg("path"), py::arg("levels"), py::arg("mips"), py::arg("float32"));
  m.def("spherical_harmonics", &SphericalHarmonicsOf, py::arg("cube"), py::arg("frame"));
  m.def("irradiance_cubemap", &IrradianceCubemapArray, py::arg("cube"), py::arg("size"), py::arg("source_size"));
  m.def("specular_cubemaps", &SpecularCubemapArrays, py::arg("cube"), py::arg("levels"), py::arg("samples"));
  m.def("engine_targets", [] {
    py::list targets;
    for (const EngineTarget& t : EngineTargets()) {
      py::dict d;
      d["name"] = t.name;
      d["program"] = t.program;
      d["equirect_centre_azimuth_deg"] = t.equirect_centre_azimuth_deg;
      d["world"] = t.world;
      d["recipe"] = t.recipe;
      d["source"] = t.source;
      targets.append(d);
    }
    return targets;
  });
  m.def(
      "sun_position",
      [](const std::string& date, double latitude_deg, double longitude_deg, bool refraction, double height_m) {
        SunPositionOptions options;
        options.refraction = refraction;
        options.observer_height_m = height_m;
        const double julian_day = ParseIsoDateTime(date);
        const SunPosition p = ComputeSunPosition(julian_day, latitude_deg, longitude_deg, options);
        py::dict d;
        d["elevation_deg"] = p.elevation_deg;
        d["geometric_elevation_deg"] = p.geometric_elevation_deg;
        d["azimuth_deg"] = p.azimuth_deg;
        d["right_ascension_deg"] = p.right_ascension_deg;
        d["declination_deg"] = p.declination_deg;
        d["distance_au"] = p.distance_au;
        d["julian_day_utc"] = julian_day;
        return d;
      },
      py::arg("date"), py::arg("latitude_deg"), py::arg("longitude_deg"), py::arg("refraction"), py::arg("height_m"));
  m.def(
      "moon_position",
      [](const std::string& date, double latitude_deg, double longitude_deg) {
        const double julian_day = ParseIsoDateTime(date);
        const MoonPosition p = ComputeMoonPosition(julian_day, latitude_deg, longitude_deg);
        py::dict d;
        d["elevation_deg"] = p.elevation_deg;
        d["azimuth_deg"] = p.azimuth_deg;
        d["phase_angle_deg"] = p.phase_angle_deg;
        d["distance_km"] = p.distance_km;
        d["julian_day_utc"] = julian_day;
        return d;
      },
      py::arg("date"), py::arg("latitude_deg"), py::arg("longitude_deg"));
  m.def("set_threads", &SetThreads, py::arg("threads"));
  m.def(
      "set_table_cache",
      [](const std::optional<std::string>& folder, std::uint64_t max_bytes) {
        // None keeps nothing new; the tables shipped with atmo are read either way.
        if (folder && folder->empty()) throw Error("table cache: the folder is empty (None keeps nothing)");
        if (max_bytes == 0) throw Error("table cache: max_bytes must be positive");
        SetTableCache(TableCache{folder ? *folder : std::string(), max_bytes, ShippedTableFolders()});
      },
      py::arg("folder"), py::arg("max_bytes"));
  m.def("table_cache", []() -> std::optional<std::string> {
    const std::optional<TableCache> cache = GetTableCache();
    if (!cache || cache->folder.empty()) return std::nullopt;
    return cache->folder.string();
  });
  m.def("default_table_cache", []() -> std::optional<std::string> {
    const TableCache cache = DefaultTableCache();
    if (cache.folder.empty()) return std::nullopt;
    return cache.folder.string();
  });
  AddDaylightBindings(m);
  m.def("model_names", &ModelNames);
  m.def("preset_names", &PresetNames);
  m.def("aerosol_types", &AerosolTypeNames);
  m.def("set_max_memory", [](const std::string& size) { SetMemoryLimitBytes(size.empty() ? 0 : ParseByteSize(size)); });
  m.def("max_memory", [] { return MemoryLimitBytes(); });
  m.def("preset_json", [](const std::string& name) { return ToJson(Preset(name)); });
  m.attr("version") = ATMO_VERSION;
}
