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

#include "atmo/image.h"
#include "gl/context.h"
#include "shared/shared.h"

namespace atmo::gl {

// Wall-clock times of one GL pass; each phase ends with glFinish.
struct GlPassTiming {
  double compile_ms = 0.0;   // shader compile + link (llvmpipe JITs here and at the first dispatch)
  double dispatch_ms = 0.0;  // uniforms, dispatch, barrier, until the GPU is done
  double readback_ms = 0.0;  // glGetTexImage into the Texture2D (or Image)
  double gpu_ms = 0.0;       // the dispatch alone, measured on the GPU (GL_TIME_ELAPSED query);
                             // dispatch_ms where the query reports 0 (llvmpipe dispatches synchronously)
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

// The ground-irradiance table (width x 1), texel x = ComputeGroundIrradianceTexel(km_atmosphere,
// transmittance, multiple_scattering, width, x + 0.5, direction_count, sample_count) in float.
shared::Texture2D ComputeGroundIrradianceTableGl(const Context& context,
                                                 const shared::AtmosphereParameters& km_atmosphere,
                                                 const shared::Texture2D& transmittance,
                                                 const shared::Texture2D& multiple_scattering, int width,
                                                 int direction_count, int sample_count,
                                                 GlPassTiming* timing = nullptr);

// The sky-view table of an observer at radius `r_km` (inside the atmosphere) and a sun at zenith
// cosine `mu_s`: texel (x, y) = ComputeSkyViewTexel(km_atmosphere, transmittance,
// multiple_scattering, size, (x + 0.5, y + 0.5), r_km, mu_s, sample_count) in float. The height
// must be even (sky and ground halves); the result repeats in u (repeat_u), as the CPU table.
shared::Texture2D ComputeSkyViewTableGl(const Context& context, const shared::AtmosphereParameters& km_atmosphere,
                                        const shared::Texture2D& transmittance,
                                        const shared::Texture2D& multiple_scattering, shared::ivec2 size, double r_km,
                                        double mu_s, int sample_count, GlPassTiming* timing = nullptr);

// `sky_view` plus the lit ground below the horizon: texel (x, y) = sky_view(x, y) +
// ComputeGroundViewTexel(km_atmosphere, transmittance, ground_irradiance, size, (x + 0.5, y + 0.5),
// r_km, mu_s) (HillaireModel::AddGroundView on the CPU).
shared::Texture2D AddGroundViewGl(const Context& context, const shared::AtmosphereParameters& km_atmosphere,
                                  const shared::Texture2D& transmittance, const shared::Texture2D& ground_irradiance,
                                  const shared::Texture2D& sky_view, double r_km, double mu_s,
                                  GlPassTiming* timing = nullptr);

// The frame pass of configuration gl_f32_rgb: per pixel the camera ray (GetCameraRayDirection),
// the sky-view table looked up with GetSkyViewTextureUvFromBeta(horizon_nadir_angle) and
// GetAzimuthFromSun (GL_LINEAR, repeat in u, clamp in v), plus GetSunDiscRadiance at full
// resolution when `sun_disc`, times `solar_irradiance` per channel. Returns an RGB image, with
// alpha (0 outside the circle) for a fisheye camera, as atmo::RenderView.
Image RenderSkyViewFrameGl(const Context& context, const shared::AtmosphereParameters& km_atmosphere,
                           const shared::Texture2D& transmittance, const shared::Texture2D& sky_view,
                           const shared::CameraParameters& camera, double r_km, double horizon_nadir_angle,
                           const shared::vec3& sun_direction, bool sun_disc, const shared::vec3& solar_irradiance,
                           GlPassTiming* timing = nullptr);

}  // namespace atmo::gl
