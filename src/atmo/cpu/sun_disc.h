// The sun disc of an image, integrated over each pixel (private; used by RenderView,
// RenderProgressive and the GL renderers after read-back).
//
// A pixel's value is the mean radiance over its solid angle: (1 / Omega_pixel) int_pixel L dOmega.
// Sampling the disc at pixel centres instead gives energy that depends on where the centres fall
// (0 at 256 px across an equirect with the sun between centres, +75 % elsewhere at 1024 px) and a
// blocky disc. The pass integrates the disc over the pixels that can meet it: for pixel p,
//   int_p L dOmega = int_p L(x, y) J(x, y) dx dy ~= (1 / n) sum_i L(s_i) J(s_i),
// with J = dOmega / dA the camera's solid angle per square pixel (GetCameraSolidAngleDensity) and
// n stratified sub-pixel positions s_i (k x k strata, each jittered by a hash of pixel and
// stratum: fixed, independent of threads), and adds it divided by the pixel's exact solid angle
// (GetCameraPixelSolidAngle). Summed over the image, value x Omega_pixel is then the disc's
// energy up to the quadrature error, which the stratum size sets: k is chosen so that the strata
// are ~1/96 of the disc's diameter (k = ceil(96 / D), D the diameter in pixels, 4 <= k <= 1024):
// for the Sun's 0.53 degrees that is k = 253 at 256 px across an equirect, and the error of the
// area estimate is ~0.2 %. A disc larger than 16 pixels across is smooth inside: pixels whose
// every point is on it take 2 x 2 strata at their centres (the midpoint rule), those on its edge
// k x k jittered strata. A disc smaller than a pixel across is sampled instead of the pixels: 96 x
// 96 cells of equal solid angle over the disc, each adding its L dOmega to the pixel it falls in
// (the pixels' strata would cost up to 1024^2 samples a pixel there).
#pragma once

#include <functional>
#include <span>

#include <glm/glm.hpp>

#include "atmo/image.h"
#include "atmo/model.h"
#include "atmo/render.h"

namespace atmo {

// The disc's radiance along a unit view direction per channel (attenuated, per unit irradiance at
// the top of the atmosphere, 0 off the disc): SkyView::SunDiscRadiance or the GL host's own.
using SunDiscRadianceFunction = std::function<void(const glm::dvec3& view, std::span<double> out)>;

// Adds the disc of angular radius `sun_angular_radius_rad` around `sun_direction` (unit), through
// `camera`, integrated over each pixel and multiplied per channel by `solar_irradiance` (one value
// per channel), to `image` (as many channels, the camera's size). A fisheye pixel on the rim
// holds the part of the disc inside the circle, even where its centre is outside (alpha 0), so
// that no energy is lost.
void AddSunDisc(const Camera& camera, const glm::dvec3& sun_direction, double sun_angular_radius_rad,
                const SunDiscRadianceFunction& radiance, std::span<const double> solar_irradiance, Image& image);

// The same with the disc of a view (SkyView::SunDiscRadiance, sun_direction and
// sun_angular_radius_rad). Throws atmo::Error for a view without a sun angular radius.
void AddSunDisc(const SkyView& sky, const Camera& camera, std::span<const double> solar_irradiance, Image& image);
// The moon's disc of `terms` (terms.moon and terms.moon_sky) through `camera`: its radiance
// (Moon::DiscRadiance, with the phase) attenuated by moon_sky's transmittance, folded by `fold`
// (channels -> 3 outputs; the channels themselves when empty) and times `scale` per output, added
// as AddSunDisc adds the sun's (defined in cpu/render.cc).
void AddMoonDisc(const RadianceTerms& terms, const Camera& camera, std::span<const glm::vec3> fold,
                 std::span<const double> scale, Image& image);

}  // namespace atmo
