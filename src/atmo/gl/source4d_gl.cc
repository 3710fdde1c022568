#include "gl/source4d_gl.h"

#include <chrono>
#include <cmath>
#include <string>
#include <vector>

#include "atmo/error.h"
#include "cpu/camera.h"
#include "gl/hillaire_gl.h"
#include "gl/program.h"
#include "physics/shared_parameters.h"

namespace atmo::gl {
namespace {

// The view ray of each pixel marched through the tables (GetSource4dRadiance: single scattering
// exactly, orders >= 2 from ln G, the lit ground from the transmittance and the ground
// irradiance), and the disc per pixel for interactive use.
constexpr const char* kSource4dFrameMain = R"glsl(
layout(local_size_x = 8, local_size_y = 8) in;
layout(rgba32f, binding = 0) uniform writeonly image2D output_image;
uniform AtmosphereParameters atmosphere;
uniform sampler2D transmittance_texture;
uniform sampler3D rayleigh_texture;
uniform sampler3D mie_texture;
uniform sampler2D irradiance_texture;
uniform int mu_s_size;
uniform int sample_count;
uniform CameraParameters camera;
uniform float r;             // km
uniform vec3 sun_direction;  // unit, local frame (x east, y north, z up)
uniform bool ground;
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
    float mu = ClampCosine(direction.z);
    float nu = ClampCosine(dot(direction, sun_direction));
    vec3 ground_radiance;
    radiance = GetSource4dRadiance(atmosphere, transmittance_texture, rayleigh_texture, mie_texture,
        irradiance_texture, mu_s_size, r, mu, ClampCosine(sun_direction.z), nu, sample_count, ground_radiance);
    if (ground) radiance += ground_radiance;
    if (sun_disc) radiance += GetSunDiscRadiance(atmosphere, transmittance_texture, r, mu, nu);
  }
  imageStore(output_image, pixel, vec4(radiance * solar_irradiance, seen ? 1.0 : 0.0));
}
)glsl";

const ComputeProgram& Source4dFrameProgram(const Context& context, double* compile_ms = nullptr) {
  return context.Program({"definitions.glsl", "geometry.glsl", "medium.glsl", "phase.glsl", "transmittance.glsl",
                          "multiple_scattering.glsl", "sun.glsl", "sky.glsl", "camera.glsl", "source4d.glsl"},
                         kSource4dFrameMain, "source4d frame", compile_ms);
}

}  // namespace

Source4dTablesGl UploadSource4dTables(const cpu::Source4dTables& tables) {
  if (tables.mu_s_size < 2 || tables.rayleigh.depth == 0) {
    throw Error("GL source4d: the model's tables are not computed (Precompute first)");
  }
  Source4dTablesGl gl;
  gl.transmittance = GpuTexture::Upload(tables.transmittance);
  gl.rayleigh = GpuTexture::Upload(tables.rayleigh);
  gl.mie = GpuTexture::Upload(tables.mie);
  gl.ground_irradiance = GpuTexture::Upload(tables.ground_irradiance);
  gl.mu_s_size = tables.mu_s_size;
  return gl;
}

void RunSource4dFramePass(const Context& context, const shared::AtmosphereParameters& km_atmosphere,
                          const Source4dTablesGl& tables, int samples, const shared::CameraParameters& camera,
                          double r_km, const glm::dvec3& sun_direction, bool ground, bool sun_disc,
                          const shared::vec3& solar_irradiance, const GpuTexture& out) {
  context.MakeCurrent();
  const ComputeProgram& program = Source4dFrameProgram(context);
  SetAtmosphereUniforms(program, "atmosphere", km_atmosphere);
  SetCameraUniforms(program, "camera", camera);
  program.SetInt("mu_s_size", tables.mu_s_size);
  program.SetInt("sample_count", samples);
  program.SetFloat("r", r_km);
  program.SetVec3("sun_direction", glm::normalize(sun_direction));
  program.SetInt("ground", ground ? 1 : 0);
  program.SetInt("sun_disc", sun_disc ? 1 : 0);
  program.SetVec3("solar_irradiance", solar_irradiance);
  BindSamplers(program, {{"transmittance_texture", &tables.transmittance},
                         {"rayleigh_texture", &tables.rayleigh},
                         {"mie_texture", &tables.mie},
                         {"irradiance_texture", &tables.ground_irradiance}});
  out.BindImage(0);
  DispatchCompute2D(program, out.size2());
  CheckGlError("source4d frame");
}

Image RenderSource4dGl(const Context& context, const Source4dModel& model, const RenderSettings& render,
                       PassTimings* timings) {
  ValidateCamera(render.camera);
  for (const double value : {render.altitude_m, render.sun_elevation_deg, render.sun_azimuth_deg}) {
    if (!std::isfinite(value)) throw Error("altitude and sun angles must be finite");
  }
  const glm::dvec3 sun = glm::normalize(SunDirection(render.sun_elevation_deg, render.sun_azimuth_deg));
  model.View(render.altitude_m, sun);  // what the CPU rejects (altitude < 0)
  const AtmosphereParameters& parameters = model.parameters();
  context.MakeCurrent();
  double compile_ms = 0.0;
  Source4dFrameProgram(context, &compile_ms);  // compiled before any pass is timed
  if (timings != nullptr) timings->Add("source4d_gl_compile", compile_ms);

  const shared::CameraParameters camera = ToSharedCamera(render.camera);
  const std::size_t nc = parameters.channel_count();
  const std::size_t n = static_cast<std::size_t>(camera.width) * camera.height;
  Image image(camera.width, camera.height, static_cast<int>(nc));
  const bool has_alpha = camera.kind == shared::kCameraFisheye;
  if (has_alpha) image.alpha.assign(n, 0.0f);
  const GpuTexture frame = GpuTexture::Make2D({camera.width, camera.height});
  const double r_km = (parameters.ground_radius_m + render.altitude_m) / 1000.0;
  std::vector<shared::Texture2D> transmittance;  // per batch, for the host's sun disc
  for (std::size_t b = 0; b < model.batches().size(); ++b) {
    const cpu::Source4dTables& cpu_tables = model.batches()[b].tables;
    const auto upload_start = std::chrono::steady_clock::now();
    const Source4dTablesGl tables = UploadSource4dTables(cpu_tables);
    if (timings != nullptr) {
      timings->Add("source4d_gl_upload",
                   std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - upload_start).count());
    }
    {
      GpuPassTimer timer(timings);
      RunSource4dFramePass(context, ToSharedParameters(parameters, b, 1000.0), tables, model.settings().samples,
                           camera, r_km, sun, render.terms.ground, /*sun_disc=*/false,
                           BatchValues(parameters.solar_irradiance, b), frame);
      timer.Stop("frame_" + std::to_string(camera.width) + "x" + std::to_string(camera.height));
    }
    const std::vector<float> rgba = frame.DownloadRgba();
    for (std::size_t i = 0; i < n; ++i) {
      for (std::size_t c = 0; c < 3 && 3 * b + c < nc; ++c) image.pixels[nc * i + 3 * b + c] = rgba[4 * i + c];
      if (has_alpha && b == 0) image.alpha[i] = rgba[4 * i + 3];
    }
    if (render.terms.sun_disc) transmittance.push_back(cpu_tables.transmittance);
  }
  if (render.terms.sun_disc) AddSunDiscOnHost(parameters, transmittance, render, image);
  return image;
}

}  // namespace atmo::gl
