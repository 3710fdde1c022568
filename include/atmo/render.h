// Rendering a model through a camera into an HDR image, on the CPU (oneTBB).
//
// To use it:
//   atmo::RenderSettings s;
//   s.camera = {atmo::CameraKind::kFisheye, 512, 512};
//   s.sun_elevation_deg = 10.0;
//   atmo::Image img = atmo::Render(*model, s);   // linear; radiance x solar_irradiance per channel
#pragma once

#include <atomic>
#include <cstdint>
#include <functional>
#include <span>
#include <string>
#include <string_view>

#include <glm/glm.hpp>

#include "atmo/image.h"
#include "atmo/model.h"
#include "atmo/night_sky.h"

namespace atmo {

enum class CameraKind {
  kPerspective,  // pinhole: horizontal field of view, yaw (compass azimuth) and pitch (elevation)
  kFisheye,      // all-sky equidistant: zenith at the centre, horizon on the circle, north up, east left
  kEquirect,     // full-sphere lat-long environment map: azimuth across (yaw at the centre), +90..-90 down
};

struct Camera {
  CameraKind kind = CameraKind::kPerspective;
  int width = 1920;
  int height = 1080;
  double fov_deg = 90.0;    // horizontal field of view (perspective)
  double yaw_deg = 0.0;     // compass azimuth of the view centre (0 = north, 90 = east)
  double pitch_deg = 0.0;   // elevation of the view centre (perspective)
};

struct RenderSettings {
  Camera camera;
  double altitude_m = 0.0;
  double sun_elevation_deg = 30.0;
  double sun_azimuth_deg = 180.0;  // compass azimuth of the sun
  RadianceTerms terms;             // sun disc and lit ground on by default
};

// Largest accepted image side, to reject absurd resolutions before allocating.
constexpr int kMaxImageSide = 16384;

// One image channel per model channel (per wavelength: 3 for the RGB presets, N for a spectral
// atmosphere; atmo::ConvertImage in atmo/colour.h turns them into colour and physical units).
// Throws atmo::Error for invalid settings (non-finite angles, a resolution outside
// [1, kMaxImageSide], a field of view outside (0, 180)). The night sky of the model's parameters
// (NightSkySettings, with the default ecliptic) is added unless settings.terms.night_sky gives one.
Image Render(const Model& model, const RenderSettings& settings);

// Renders a prepared view (its per-view tables already built) through a camera: the frame pass
// alone. Radiance is multiplied per channel by `solar_irradiance` (one value per channel). With
// terms.sun_disc the disc is not sampled at pixel centres but integrated over each pixel by its
// own pass (src/atmo/cpu/sun_disc.h), so that its energy in the image is the transmitted
// irradiance at any resolution and it is round. Same errors as Render for the camera;
// `solar_irradiance` has one value per channel of the view.
// `progress`, when given, is called as rows complete with (rows done, rows in the image), the last
// call with both equal; at most one call runs at a time (it may come from any worker thread, and a
// row that finds a call running skips its own), so a slow callback never stalls the frame.
using RowProgress = std::function<void(int rows_done, int rows_total)>;
Image RenderView(const SkyView& sky, const Camera& camera, const RadianceTerms& terms,
                 std::span<const double> solar_irradiance, const RowProgress& progress = {});
// The same into `image`, whose pixel storage is reused when its size and channel count are the
// frame's (a render loop's target: no allocation, zero fill or page faults per frame).
void RenderView(const SkyView& sky, const Camera& camera, const RadianceTerms& terms,
                std::span<const double> solar_irradiance, Image& image, const RowProgress& progress = {});

// Adds a night sky's per-pixel pass (NightSky::Scaled or NightSky::Fold, as many outputs as the
// image has channels) to an image rendered through `camera`: what RenderView does with
// RadianceTerms::night_sky, for images made elsewhere (the GL renderers after read-back). Throws
// atmo::Error for a size or channel mismatch.
void AddNightSky(const NightSky::Folded& night, const Camera& camera, Image& image);
// Only the stars of such a pass (NightSky::SetStars): each shared among the 2 x 2 pixels around it.
void AddStars(const NightSky::Folded& night, const Camera& camera, Image& image);
// The moon for images made elsewhere (the GL renderers), what RenderView does with
// RadianceTerms::moon: `moonlit` is the same renderer's image through `camera` with the sun put in
// the moon's direction, without the sun disc and the night sky (in the units of `image`: per
// unit solar irradiance times `solar_irradiance`); it is added times the moon's irradiance
// relative to the sun's, and then the moon's disc, integrated over the pixels and attenuated by
// `night`'s transmittance (the one the stars get). Throws atmo::Error for a size or channel
// mismatch.
void AddMoonLight(const Moon& moon, const Image& moonlit, const NightSky& night, const Camera& camera,
                  std::span<const double> solar_irradiance, Image& image);
// Only the moon's disc of AddMoonLight (atmo-viewer adds the moonlit sky on the GPU).
void AddMoonDiscLight(const Moon& moon, const NightSky& night, const Camera& camera,
                      std::span<const double> solar_irradiance, Image& image);

// RenderView folded into three channels: pixel value k = sum over channels c of weights[c][k] L_c
// (SkyView::RadianceBatchFolded), the pixel-integrated sun disc folded the same way. With the
// colour weights of atmo::ColourWeights (atmo/colour.h) this is ConvertImage(RenderView(...)) at
// about the cost of a 3-channel frame, whatever the channel count. Throws as RenderView, and for
// `weights` without one entry per channel of the view.
Image RenderViewFolded(const SkyView& sky, const Camera& camera, const RadianceTerms& terms,
                       std::span<const glm::vec3> weights, const RowProgress& progress = {});
void RenderViewFolded(const SkyView& sky, const Camera& camera, const RadianceTerms& terms,
                      std::span<const glm::vec3> weights, Image& image, const RowProgress& progress = {});

// Progressive rendering of a Monte Carlo model (model `reference`): every pixel gets
// `samples_per_pixel` paths (per channel) in passes, the first of `first_pass_samples` paths and
// each later one doubling the total (4, 8, 16, ... up to the total). With terms.ground each path
// also scores the light reflected at the view ray's first ground hit, so pixels on the ground show
// it; the sun disc is deterministic (standard error 0), integrated over the pixels as in RenderView. Pixel (x, y) depends only on the model's
// seed, its view direction and the path count: the image is the same for any thread count, and
// its pass k is a prefix of the final estimate.
//
// To use it:
//   atmo::ProgressiveSettings p;
//   p.samples_per_pixel = 256;
//   p.on_pass = [](const atmo::ProgressiveImage& pass) { /* write or show pass.radiance */ };
//   atmo::ProgressiveImage img = atmo::RenderProgressive(*model, settings, p);
//   atmo::WriteExr("sky.exr", atmo::WithStandardErrorChannels(img));
struct ProgressiveImage {
  Image radiance;        // as Render: radiance x solar_irradiance, 3 channels (+ alpha for fisheye)
  Image standard_error;  // the standard error of each pixel's radiance, same unit, 3 channels
  std::uint64_t samples_per_pixel = 0;  // paths per pixel (per channel) so far
  int pass = 0;                         // 1 for the first pass
};

struct ProgressiveSettings {
  std::uint64_t samples_per_pixel = 0;  // the total; 0: the model's `samples` setting
  std::uint64_t first_pass_samples = 4;
  // After each pass, on the calling thread, with the image so far.
  std::function<void(const ProgressiveImage&)> on_pass;
  // Now and then during a pass: paths done and paths in all (pixels x samples_per_pixel); calls
  // never overlap, but may come from any thread.
  std::function<void(double done, double total)> on_progress;
  // When given and set (from any thread), the render stops within a row of each thread and
  // returns the estimate of the last complete pass (an empty image before the first): a viewer
  // restarting after a change.
  const std::atomic<bool>* cancel = nullptr;
};

// Whether `model` estimates radiance by Monte Carlo, so that RenderProgressive applies to it.
bool IsMonteCarlo(const Model& model);
// Throws atmo::Error for a model that is not Monte Carlo, a samples_per_pixel of 1 or a
// first_pass_samples below 2 (a standard error needs two paths), and what Render rejects.
ProgressiveImage RenderProgressive(const Model& model, const RenderSettings& settings,
                                   const ProgressiveSettings& progressive);
// The EXR form of a progressive image: channels R, G, B, R.stderr, G.stderr, B.stderr (the
// standard errors), the alpha of the radiance.
Image WithStandardErrorChannels(const ProgressiveImage& image);

// Unit direction towards the sun in the local frame from its elevation and compass azimuth.
glm::dvec3 SunDirection(double elevation_deg, double azimuth_deg);
CameraKind ParseCameraKind(std::string_view name);
std::string_view ToString(CameraKind kind);

}  // namespace atmo
