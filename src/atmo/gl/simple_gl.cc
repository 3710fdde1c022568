#include "gl/simple_gl.h"

#include <string>

#include "atmo/error.h"
#include "gl/program.h"

namespace atmo::gl {

namespace {

// beta(nu) = sum over the media of sigma_s,m p_m(nu) (SimpleSkyView::InScattering), then the
// whole view ray's radiance; the disc per pixel for interactive use.
constexpr const char* kSimpleFrameMain = R"glsl(
layout(local_size_x = 8, local_size_y = 8) in;
layout(rgba32f, binding = 0) uniform writeonly image2D output_image;
uniform AtmosphereParameters sun_parameters;  // the sun disc's members
uniform CameraParameters camera;
uniform vec3 observer;
uniform vec3 sun_direction;
uniform vec3 extinction;
uniform int medium_count;
uniform vec3 medium_scattering[3];
uniform int medium_phase[3];
uniform float medium_g[3];
uniform bool sun_disc;
uniform vec3 solar_irradiance;

void main() {
  ivec2 size = imageSize(output_image);
  ivec2 pixel = ivec2(gl_GlobalInvocationID.xy);
  if (any(greaterThanEqual(pixel, size))) return;
  vec3 direction;
  bool seen = GetCameraRayDirection(camera, vec2(pixel) + vec2(0.5), direction);
  vec3 radiance = vec3(0.0);
  if (seen) {
    const vec3 up = vec3(0.0, 0.0, 1.0);
    float nu = clamp(dot(direction, sun_direction), -1.0, 1.0);
    vec3 beta = vec3(0.0);
    for (int m = 0; m < medium_count; ++m) {
      beta += GetSimpleMediumScattering(medium_scattering[m], medium_phase[m], medium_g[m], nu);
    }
    radiance = ComputeSimpleScatteredRadiance(up, observer, direction, sun_direction, extinction, beta);
    if (sun_disc) {
      radiance += GetSimpleSunDiscRadiance(up, observer, direction, sun_direction, extinction, sun_parameters);
    }
  }
  imageStore(output_image, pixel, vec4(radiance * solar_irradiance, seen ? 1.0 : 0.0));
}
)glsl";

}  // namespace

void RunSimpleFramePass(const Context& context, const SimpleModel::Batch& batch, double altitude_m,
                        const glm::dvec3& sun_direction, const shared::CameraParameters& camera, bool sun_disc,
                        const shared::vec3& solar_irradiance, const GpuTexture& out) {
  if (batch.media.size() > 3) throw Error("GL simple: at most 3 scattering media");
  context.MakeCurrent();
  const ComputeProgram& program =
      context.Program({"definitions.glsl", "geometry.glsl", "medium.glsl", "phase.glsl", "transmittance.glsl",
                       "multiple_scattering.glsl", "sun.glsl", "sky.glsl", "camera.glsl", "simple.glsl"},
                      kSimpleFrameMain, "simple frame");
  SetAtmosphereUniforms(program, "sun_parameters", batch.sun);
  SetCameraUniforms(program, "camera", camera);
  program.SetVec3("observer", shared::vec3(0.0, 0.0, altitude_m));
  program.SetVec3("sun_direction", glm::normalize(sun_direction));
  program.SetVec3("extinction", batch.extinction);
  program.SetInt("medium_count", static_cast<int>(batch.media.size()));
  for (std::size_t m = 0; m < batch.media.size(); ++m) {
    const std::string index = "[" + std::to_string(m) + "]";
    program.SetVec3("medium_scattering" + index, batch.media[m].scattering);
    program.SetInt("medium_phase" + index, batch.media[m].phase);
    program.SetFloat("medium_g" + index, batch.media[m].phase_g);
  }
  program.SetInt("sun_disc", sun_disc ? 1 : 0);
  program.SetVec3("solar_irradiance", solar_irradiance);
  out.BindImage(0);
  DispatchCompute2D(program, out.size2());
  CheckGlError("simple frame");
}

}  // namespace atmo::gl
