// Model elek on the GL backend (configuration gl_f32_rgb), for programs that link atmo::gl.
//
// To use it (a headless EGL context, as atmo/gl/hillaire_gl.h):
//   atmo::gl::Context context;
//   auto model = atmo::gl::CreateElekModel(context, atmo::Preset("atmosphere-plus"));
//   auto sky = model->View(0.0, sun);      // an atmo::Model: the CPU lookups, on GL-computed tables
// or, with the tables never leaving the GPU:
//   atmo::Image image = atmo::gl::RenderElek(context, atmo::Preset("atmosphere-plus"), {}, render);
//
// `options` are those of atmo::CreateModel("elek", ...) (docs/models/elek.md; "seed" is accepted
// and ignored) except table=NAME, which loads a table instead of computing one: use
// CreateModel for that. Errors are atmo::Error, one line: invalid options or parameters, what
// atmo::Render rejects. `timings` (may be null) receives each pass's GPU time.
#pragma once

#include <memory>

#include "atmo/gl/context.h"
#include "atmo/image.h"
#include "atmo/model.h"
#include "atmo/parameters.h"
#include "atmo/render.h"
#include "atmo/timing.h"

namespace atmo::gl {

// A model elek whose tables are computed on the GPU and read back: what
// CreateModel("elek", parameters, options) gives, within float precision; atmo::ExportElekTable
// accepts it. The context is needed only during the call.
std::unique_ptr<Model> CreateElekModel(const Context& context, const AtmosphereParameters& parameters,
                                       const ModelOptions& options = {}, PassTimings* timings = nullptr);

// One frame of model elek with its tables on the GPU: what atmo::Render gives for
// CreateModel("elek", parameters, options), one channel per wavelength (alpha for a fisheye).
Image RenderElek(const Context& context, const AtmosphereParameters& parameters, const ModelOptions& options,
                 const RenderSettings& render, PassTimings* timings = nullptr);

}  // namespace atmo::gl
