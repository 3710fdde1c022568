// The hillaire tables computed by OpenGL compute shaders (private to the GL backend).
//
// Each pass is a compute shader whose main() calls the shared per-texel kernel of
// src/atmo/shared with the texel centre, in float, and writes an rgba32f image that is read back
// into a shared::Texture2D (the layout of the CPU tables, so either backend's table feeds either
// backend's lookups). The atmosphere is uploaded member by member as the uniform struct
// `atmosphere` (program.h).
//
// To use it: with a gl::Context alive on this thread and km parameters
// (ToSharedParameters(p, batch, 1000)):
//   shared::Texture2D t = gl::ComputeTransmittanceTableGl(context, km, {256, 64}, 40);
// Table values do not depend on the length unit (transmittance is unitless; the multiple-scattering
// radiance integrates sigma_s dt), so GL and CPU tables are interchangeable.
#pragma once

#include "gl/context.h"
#include "shared/shared.h"

namespace atmo::gl {

// Wall-clock times of one GL pass; each phase ends with glFinish.
struct GlPassTiming {
  double compile_ms = 0.0;   // shader compile + link (llvmpipe JITs here and at the first dispatch)
  double dispatch_ms = 0.0;  // uniforms, dispatch, barrier, until the GPU is done
  double readback_ms = 0.0;  // glGetTexImage into the Texture2D
};

// The transmittance table, texel (x, y) = ComputeTransmittanceToTopAtmosphereBoundaryTexel(
// km_atmosphere, size, (x + 0.5, y + 0.5), sample_count) in float.
shared::Texture2D ComputeTransmittanceTableGl(const Context& context, const shared::AtmosphereParameters& km_atmosphere,
                                              shared::ivec2 size, int sample_count, GlPassTiming* timing = nullptr);

// The multiple-scattering table, texel (x, y) = ComputeMultiScatteringTexel(km_atmosphere,
// transmittance, size, (x + 0.5, y + 0.5), direction_count, sample_count, media_phase,
// ground_transfer) in float. `transmittance` (from either backend) is sampled with GL_LINEAR and
// clamp to edge, the rules shared::Texture2D follows; `ground_transfer` is unitless
// (shared::GetGroundTransfer, or 0).
shared::Texture2D ComputeMultipleScatteringTableGl(const Context& context,
                                                   const shared::AtmosphereParameters& km_atmosphere,
                                                   const shared::Texture2D& transmittance, shared::ivec2 size,
                                                   int direction_count, int sample_count, bool media_phase,
                                                   const shared::vec3& ground_transfer,
                                                   GlPassTiming* timing = nullptr);

}  // namespace atmo::gl
