// Model simple on the GL backend (configuration gl_f32_rgb), private to the backend: the frame
// pass evaluates the closed form of src/atmo/shared/simple.glsl per pixel in float, as
// SimpleModel's SkyView does in double on the CPU. The model has no tables, so a frame is one
// pass per batch of three channels.
//
// To use it (a gl::Context alive on this thread):
//   const SimpleModel model(Preset("simple"), {});
//   GpuTexture frame = GpuTexture::Make2D({camera.width, camera.height});
//   for (std::size_t b = 0; b < model.batches().size(); ++b)
//     gl::RunSimpleFramePass(context, model.batches()[b], altitude_m, sun, camera, false, irradiance_b, frame);
#pragma once

#include <glm/glm.hpp>

#include "gl/context.h"
#include "gl/resources.h"
#include "models/simple_model.h"
#include "shared/shared.h"

namespace atmo::gl {

// Per pixel of `out` (rgba32f, the camera's size): the camera ray (GetCameraRayDirection),
// ComputeSimpleScatteredRadiance of batch `batch` for the observer (0, 0, altitude_m) (metres,
// the signed height above the boundary plane) and the unit `sun_direction`, plus
// GetSimpleSunDiscRadiance where `sun_disc`, times `solar_irradiance`; alpha 0 outside a
// fisheye's circle. Throws atmo::Error for a batch with more than 3 scattering media.
void RunSimpleFramePass(const Context& context, const SimpleModel::Batch& batch, double altitude_m,
                        const glm::dvec3& sun_direction, const shared::CameraParameters& camera, bool sun_disc,
                        const shared::vec3& solar_irradiance, const GpuTexture& out);

}  // namespace atmo::gl
