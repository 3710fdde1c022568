// Rendering model hillaire on the GL backend: configuration gl_f32_rgb (STYLE.md).
//
// Every table and the frame are GL compute passes (hillaire_gl.h) running the shared per-texel
// kernels in float, with the atmosphere in km: transmittance_lut, multiple_scattering_lut,
// ground_irradiance_lut and ground_view_lut (with terms.ground), sky_view_lut, frame_WxH. The
// frame looks the sky up in the sky-view table (with the lit ground added below the horizon when
// terms.ground) and adds the sun disc per pixel, as the CPU frame of HillaireModel does.
//
// To use it:
//   gl::Context context;                       // throws atmo::Error when no GL 4.5 context
//   PassTimings timings;
//   Image image = gl::RenderHillaireGl(context, Preset("earth"), HillaireSettings{}, settings, &timings);
// timings receives each pass's GPU time (GL_TIME_ELAPSED) under the names above.
//
// Throws atmo::Error (one line) for what atmo::Render rejects, for parameters without exactly 3
// channels, for an observer above the top of the atmosphere or sky_view=off (the per-pixel ray
// march is not on the GL backend yet).
#pragma once

#include "atmo/image.h"
#include "atmo/parameters.h"
#include "atmo/render.h"
#include "atmo/timing.h"
#include "gl/context.h"
#include "models/hillaire_model.h"

namespace atmo::gl {

Image RenderHillaireGl(const Context& context, const AtmosphereParameters& parameters,
                       const HillaireSettings& settings, const RenderSettings& render,
                       PassTimings* timings = nullptr);

}  // namespace atmo::gl
