// Model hillaire on the GL backend (configuration gl_f32_rgb), for programs that link atmo::gl.
//
// To use it (a headless EGL context: a hardware GPU where the driver offers one, Mesa llvmpipe
// otherwise):
//   atmo::gl::Context context;
//   atmo::RenderSettings render;                       // camera, observer, sun (atmo/render.h)
//   render.camera = {atmo::CameraKind::kFisheye, 256, 256};
//   atmo::Image image = atmo::gl::RenderHillaire(context, atmo::Preset("earth"), {}, render);
// or, for the radiance and transmittance of single directions:
//   atmo::gl::HillaireSampler sky(context, atmo::Preset("earth"));   // the view-independent tables
//   sky.SetView(/*altitude_m=*/0.0, sun);                             // the observer's tables
//   sky.Sample(views, radiance, transmittance);
//
// `options` are those of atmo::CreateModel("hillaire", ...) (docs/models/hillaire.md#options;
// "seed" is accepted and ignored). Every pass runs on the GPU and the tables stay there between
// passes; results are what the CPU model gives, within float precision (docs/architecture.md).
// Errors are atmo::Error, one line: invalid options or parameters, what atmo::Render rejects.
// `timings` (may be null) receives each pass's GPU time.
#pragma once

#include <cstddef>
#include <memory>
#include <span>
#include <vector>

#include <glm/glm.hpp>

#include "atmo/gl/context.h"
#include "atmo/image.h"
#include "atmo/model.h"
#include "atmo/parameters.h"
#include "atmo/render.h"
#include "atmo/timing.h"

namespace atmo::gl {

class HillaireGl;  // the backend's passes (private)

// One frame of model hillaire: what atmo::Render(*CreateModel("hillaire", parameters, options),
// render) gives on the CPU, one channel per wavelength (alpha for a fisheye camera).
Image RenderHillaire(const Context& context, const AtmosphereParameters& parameters, const ModelOptions& options,
                     const RenderSettings& render, PassTimings* timings = nullptr);

// The radiance of single directions (what `atmo sample --backend gl` computes): the
// view-independent tables once, then per observer and sun its sky-view table, then any number of
// directions in one GPU pass. Keeps a reference to `context`, which must outlive it. Move-only.
class HillaireSampler {
 public:
  HillaireSampler(const Context& context, const AtmosphereParameters& parameters, const ModelOptions& options = {},
                  PassTimings* timings = nullptr);
  ~HillaireSampler();
  HillaireSampler(HillaireSampler&&) noexcept;
  HillaireSampler& operator=(HillaireSampler&&) noexcept;

  std::size_t channel_count() const;
  // The observer (altitude >= 0, metres) and the sun (unit, local frame: x east, y north, z up).
  void SetView(double altitude_m, const glm::dvec3& sun_direction, PassTimings* timings = nullptr);
  // Per unit direction: the scattered radiance per unit solar irradiance (sr^-1; no sun disc, no
  // ground light) and the transmittance to the top of the atmosphere (0 towards the ground), as
  // SkyView::Radiance and Transmittance; channel c of view i at [i * channel_count() + c].
  // Needs SetView.
  void Sample(std::span<const glm::dvec3> views, std::vector<double>& radiance, std::vector<double>& transmittance,
              PassTimings* timings = nullptr);

 private:
  std::unique_ptr<HillaireGl> sky_;
};

}  // namespace atmo::gl
