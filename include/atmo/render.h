// Rendering a model through a camera into an HDR image, on the CPU (oneTBB).
//
// To use it:
//   atmo::RenderSettings s;
//   s.camera = {atmo::CameraKind::kFisheye, 512, 512};
//   s.sun_elevation_deg = 10.0;
//   atmo::Image img = atmo::Render(*model, s);   // linear; radiance x solar_irradiance per channel
#pragma once

#include <span>
#include <string>
#include <string_view>

#include <glm/glm.hpp>

#include "atmo/image.h"
#include "atmo/model.h"

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

// Throws atmo::Error for invalid settings (non-finite angles, a resolution outside
// [1, kMaxImageSide], a field of view outside (0, 180)) or a model whose channel count is not 3.
Image Render(const Model& model, const RenderSettings& settings);

// Renders a prepared view (its per-view tables already built) through a camera: the frame pass
// alone. Radiance is multiplied per channel by `solar_irradiance` (one value per channel). Same
// errors as Render for the camera; the view must have 3 channels.
Image RenderView(const SkyView& sky, const Camera& camera, const RadianceTerms& terms,
                 std::span<const double> solar_irradiance);

// Unit direction towards the sun in the local frame from its elevation and compass azimuth.
glm::dvec3 SunDirection(double elevation_deg, double azimuth_deg);
CameraKind ParseCameraKind(std::string_view name);
std::string_view ToString(CameraKind kind);

}  // namespace atmo
