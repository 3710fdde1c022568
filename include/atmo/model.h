// The model interface that every sky model implements (docs/design.md §1).
//
// To use it:
//   auto model = atmo::CreateModel("hillaire", atmo::Preset("earth"));   // precomputes its tables
//   glm::dvec3 sun = atmo::DirectionFromZenithAzimuth(glm::radians(60.0), 0.0);
//   auto sky = model->View(/*altitude_m=*/0.0, sun);                     // per-observer state
//   std::vector<double> L(model->channel_count());
//   sky->Radiance(atmo::DirectionFromZenithAzimuth(glm::radians(80.0), glm::radians(90.0)), L);
//
// Frame: the observer's local frame, x = east, y = north, z = up; directions are unit vectors.
// Units (docs/design.md §2): radiance per unit solar irradiance at the top of the atmosphere (sr^-1),
// per channel; transmittance unitless. Radiance excludes the sun disc and, for rays that meet the
// ground, the ground's own reflected light.
#pragma once

#include <chrono>
#include <limits>
#include <map>
#include <memory>
#include <mutex>
#include <span>
#include <string>
#include <string_view>
#include <vector>

#include <glm/glm.hpp>

#include "atmo/parameters.h"
#include "atmo/timing.h"

namespace atmo {

// Model settings as key=value strings (`--option key=value` on the command line); each model
// documents its keys and rejects unknown ones. One key is common to all: "seed" (an unsigned
// integer, from `--seed`), which stochastic models use and deterministic ones ignore.
using ModelOptions = std::map<std::string, std::string>;

// What RadianceBatch adds to the scattered radiance, for images.
class Moon;
class SkyView;
class NightSky;

struct RadianceTerms {
  bool sun_disc = true;  // the sun disc, attenuated by the view transmittance
  bool ground = true;    // the light the Lambertian ground reflects, attenuated (rays that meet it)
  // The night sky's own light (airglow, zodiacal light; include/atmo/night_sky.h), made for the
  // same parameters, altitude and sun. Like the sun disc it is added by the renderers (RenderView,
  // RenderViewFolded, the cube maps, the GL renderers), not by RadianceBatch. Not owned.
  const NightSky* night_sky = nullptr;
  // The moon (include/atmo/moon.h) and the model's view for a sun in the moon's direction, made for
  // the same altitude: the renderers add its disc (attenuated, with the phase) and its light as the
  // model scatters it (moon_sky's radiance times the moon's relative irradiance), with the lit
  // ground when `ground`. Both or neither; not owned.
  const Moon* moon = nullptr;
  const SkyView* moon_sky = nullptr;
};

// A model bound to one observer altitude and one sun direction: what a frame needs. Creating it
// may precompute per-view tables (the sky-view table of `hillaire`). Thread-safe for queries. It
// refers to the model's tables: the Model must outlive every SkyView made from it.
class SkyView {
 public:
  virtual ~SkyView() = default;

  // Scattered radiance towards the observer along `view`, all orders the model has; one value
  // per channel into `out` (size channel_count()).
  virtual void Radiance(const glm::dvec3& view, std::span<double> out) const = 0;
  // Radiance as above with the standard error of the estimate per channel: Monte Carlo models
  // fill both from the same samples; the default (deterministic models) calls Radiance and
  // writes 0 errors.
  virtual void RadianceEstimate(const glm::dvec3& view, std::span<double> radiance,
                                std::span<double> standard_error) const;
  // Transmittance along `view` to the top of the atmosphere; 0 where the ray meets the ground.
  virtual void Transmittance(const glm::dvec3& view, std::span<double> out) const = 0;
  // Radiance of the sun disc along `view` (0 off the disc), attenuated by the transmittance: the
  // disc of unit irradiance, limb darkened per channel (src/atmo/shared/sun.glsl).
  virtual void SunDiscRadiance(const glm::dvec3& view, std::span<double> out) const = 0;

  // Radiance reflected by the ground towards the observer along `view` (0 where the ray misses
  // the ground), attenuated by the atmosphere in front of it. The default has no ground: 0.
  virtual void GroundRadiance(const glm::dvec3& view, std::span<double> out) const;

  // Radiance plus the requested terms for many directions, written as floats with
  // channel_count() values per direction. The default loops over the single queries; models
  // override it with a faster path. Directions of length 0 are skipped (left at 0).
  virtual void RadianceBatch(std::span<const glm::dvec3> views, const RadianceTerms& terms, std::span<float> out) const;
  // RadianceBatch folded into three values per direction: out[3 i + k] = sum over channels c of
  // weights[c][k] L_c (for example the colour weights of atmo::ColourWeights, which give linear
  // sRGB). A spectral image costs about a 3-channel one this way when the model folds its tables
  // (hillaire folds its sky-view tables). weights has channel_count() entries. The default calls
  // RadianceBatch and folds.
  virtual void RadianceBatchFolded(std::span<const glm::dvec3> views, const RadianceTerms& terms,
                                   std::span<const glm::vec3> weights, std::span<float> out) const;

  // Aerial perspective: the radiance scattered towards the observer between it and the point at
  // `distance_m` along `view`, and the transmittance over that segment. Throws atmo::Error for a
  // model that does not provide it.
  virtual void ScatteringAlongSegment(const glm::dvec3& view, double distance_m, std::span<double> radiance,
                                      std::span<double> transmittance) const;

  double altitude_m() const { return altitude_m_; }
  const glm::dvec3& sun_direction() const { return sun_direction_; }
  std::size_t channel_count() const { return channel_count_; }
  // The angular radius of the sun disc that SunDiscRadiance draws (radians); NaN for a view that
  // was made without it (the renderers' disc pass then throws atmo::Error).
  double sun_angular_radius_rad() const { return sun_angular_radius_rad_; }

 protected:
  SkyView(double altitude_m, const glm::dvec3& sun_direction, std::size_t channel_count,
          double sun_angular_radius_rad = std::numeric_limits<double>::quiet_NaN())
      : altitude_m_(altitude_m),
        sun_direction_(sun_direction),
        channel_count_(channel_count),
        sun_angular_radius_rad_(sun_angular_radius_rad) {}

 private:
  double altitude_m_;
  glm::dvec3 sun_direction_;
  std::size_t channel_count_;
  double sun_angular_radius_rad_;
};

class Model {
 public:
  virtual ~Model() = default;

  virtual std::string_view name() const = 0;
  // (Re)computes the model's tables; CreateModel calls it once. Timed per pass in timings().
  virtual void Precompute() = 0;
  // State for one observer altitude (metres; negative below the boundary plane of a half-space)
  // and one sun direction (unit, towards the sun). Throws atmo::Error for a non-finite input.
  virtual std::unique_ptr<SkyView> View(double altitude_m, const glm::dvec3& sun_direction) const = 0;

  const AtmosphereParameters& parameters() const { return parameters_; }
  std::size_t channel_count() const { return parameters_.channel_count(); }
  // Per-pass times of Precompute() and of the per-view tables View() builds.
  const PassTimings& timings() const { return timings_; }
  // Seconds Precompute() is expected to take on the threads oneTBB may use, from the model's
  // table sizes and per-cell costs measured on this project's 2-core machine (docs/performance.md);
  // 0 for models whose precomputation is short whatever their options. An estimate, within a
  // factor of ~2, for announcing long work (SetProgressHandler), never for a decision.
  virtual double EstimatedPrecomputeSeconds() const { return 0.0; }

 protected:
  explicit Model(AtmosphereParameters parameters) : parameters_(std::move(parameters)) {}
  // Adds a pass time; safe to call from const methods and from several threads.
  void RecordPass(std::string_view pass, double ms) const;
  // The table cache (include/atmo/table_cache.h): a model whose tables are worth keeping writes
  // what Precompute() made as bytes and returns true; LoadTables reads them back instead of
  // Precompute() and returns false, leaving the model as it was, when they do not fit its
  // settings. The default keeps nothing.
  virtual bool SaveTables(std::vector<unsigned char>& bytes) const { return false; }
  virtual bool LoadTables(std::span<const unsigned char> bytes) { return false; }

 private:
  friend std::unique_ptr<Model> CreateModel(std::string_view, const AtmosphereParameters&, const ModelOptions&);
  AtmosphereParameters parameters_;
  mutable std::mutex timings_mutex_;
  mutable PassTimings timings_;
  // Set by CreateModel around a long Precompute: each pass's end is announced (SetProgressHandler).
  std::chrono::steady_clock::time_point progress_start_{};
  bool announce_passes_ = false;
};

// Creates and precomputes a model by name. Throws atmo::Error for an unknown model (listing the
// known ones), an unknown or invalid option, or parameters the model cannot handle.
std::unique_ptr<Model> CreateModel(std::string_view name, const AtmosphereParameters& parameters,
                                   const ModelOptions& options = {});
std::vector<std::string> ModelNames();

// Unit direction with the given zenith angle and compass azimuth (radians) in the local frame.
glm::dvec3 DirectionFromZenithAzimuth(double zenith_rad, double azimuth_rad);

}  // namespace atmo
