#include "gl/night_gl.h"

#include <algorithm>
#include <array>
#include <memory>
#include <string>
#include <string_view>

#include <epoxy/gl.h>

#include "atmo/error.h"
#include "atmo/gl/context.h"
#include "gl/program.h"
#include "gl/shader_sources.h"

namespace atmo::gl {
namespace {

// The glow: NightSky::Folded::Add per pixel of one frame texture.
constexpr const char* kGlowMain = R"glsl(
layout(local_size_x = 8, local_size_y = 8) in;
layout(rgba32f, binding = 0) uniform image2D frame;
layout(std430, binding = 1) readonly buffer Airglow { vec4 airglow[]; };
layout(std430, binding = 2) readonly buffer Transmitted { vec4 transmitted[]; };
layout(std430, binding = 3) readonly buffer ZodiacalGrid { float zodiacal_grid[]; };
layout(std430, binding = 4) readonly buffer StarlightGrid { float starlight_grid[]; };
uniform CameraParameters camera;
uniform vec3 ecliptic_pole;
uniform vec3 sun_direction;
uniform bool zodiacal;
uniform float zodiacal_scale;
uniform bool starlight;
const int kAngles = 4097;
const int kSinBeta = 129;
const int kCosElongation = 513;
const int kStarlightSide = 65;

// NightSky's zodiacal grid at |sin(beta)| and cos(elongation), bilinearly.
float ZodiacalValue(float abs_sin_beta, float cos_elongation) {
  float x = min(abs_sin_beta, 1.0) * float(kSinBeta - 1);
  float y = (clamp(cos_elongation, -1.0, 1.0) + 1.0) * (0.5 * float(kCosElongation - 1));
  int i = min(int(x), kSinBeta - 2);
  int j = min(int(y), kCosElongation - 2);
  float fx = x - float(i);
  float fy = y - float(j);
  int at = i * kCosElongation + j;
  return (1.0 - fx) * ((1.0 - fy) * zodiacal_grid[at] + fy * zodiacal_grid[at + 1]) +
         fx * ((1.0 - fy) * zodiacal_grid[at + kCosElongation] + fy * zodiacal_grid[at + kCosElongation + 1]);
}

// NightSky's hemi-octahedral starlight grids along v, bilinearly (StarlightGridValue).
float StarlightValue(vec3 v) {
  float n = abs(v.x) + abs(v.y) + abs(v.z);
  if (!(n > 0.0)) return 0.0;
  float u = v.x / n;
  float w = v.y / n;
  float x = clamp(u + w + 1.0, 0.0, 2.0) * (0.5 * float(kStarlightSide - 1));
  float y = clamp(u - w + 1.0, 0.0, 2.0) * (0.5 * float(kStarlightSide - 1));
  int i = min(int(x), kStarlightSide - 2);
  int j = min(int(y), kStarlightSide - 2);
  float fx = x - float(i);
  float fy = y - float(j);
  int at = (v.z < 0.0 ? kStarlightSide * kStarlightSide : 0) + j * kStarlightSide + i;
  return (1.0 - fy) * ((1.0 - fx) * starlight_grid[at] + fx * starlight_grid[at + 1]) +
         fy * ((1.0 - fx) * starlight_grid[at + kStarlightSide] + fx * starlight_grid[at + kStarlightSide + 1]);
}

void main() {
  ivec2 size = imageSize(frame);
  ivec2 pixel = ivec2(gl_GlobalInvocationID.xy);
  if (any(greaterThanEqual(pixel, size))) return;
  vec3 v;
  if (!GetCameraRayDirection(camera, vec2(pixel) + vec2(0.5), v)) return;
  float x = (clamp(v.z, -1.0, 1.0) + 1.0) * (0.5 * float(kAngles - 1));
  int a = min(int(x), kAngles - 2);
  float f = x - float(a);
  float z = zodiacal ? zodiacal_scale * ZodiacalValue(abs(dot(ecliptic_pole, v)), dot(sun_direction, v)) : 0.0;
  if (starlight) z += StarlightValue(v);
  vec3 add = (1.0 - f) * (airglow[a].rgb + z * transmitted[a].rgb) + f * (airglow[a + 1].rgb + z * transmitted[a + 1].rgb);
  vec4 value = imageLoad(frame, pixel);
  imageStore(frame, pixel, vec4(value.rgb + add, value.a));
}
)glsl";

// The stars, first each star's places: vertex 4 s + k is star s's share in pixel k of the 2 x 2
// around it (AddStars): the pixel's centre in clip space and the share over the pixel's solid
// angle (0: nothing drawn). One invocation per star, so that the projection runs once per star.
constexpr const char* kStarPlacesMain = R"glsl(
layout(local_size_x = 64) in;
layout(std430, binding = 0) readonly buffer Directions { vec4 directions[]; };
layout(std430, binding = 2) writeonly buffer Places { vec4 places[]; };
uniform CameraParameters camera;
uniform int star_count;

bool Seen(ivec2 pixel) {
  if (pixel.x < 0 || pixel.y < 0 || pixel.x >= camera.width || pixel.y >= camera.height) return false;
  vec3 unused;
  return GetCameraRayDirection(camera, vec2(pixel) + vec2(0.5), unused);
}

void main() {
  int star = int(gl_GlobalInvocationID.x);
  if (star >= star_count) return;
  for (int k = 0; k < 4; ++k) places[4 * star + k] = vec4(0.0);
  vec2 frag;
  if (!GetCameraFragCoordFromDirection(camera, directions[star].xyz, frag)) return;
  vec2 f = frag - vec2(0.5);
  ivec2 origin = ivec2(floor(f));
  vec2 a = f - vec2(origin);
  ivec2 pixel[4];
  float weight[4];
  float kept = 0.0;
  for (int k = 0; k < 4; ++k) {
    pixel[k] = origin + ivec2(k & 1, k >> 1);
    if (camera.kind == kCameraEquirect) pixel[k].x = (pixel[k].x % camera.width + camera.width) % camera.width;
    weight[k] = ((k & 1) == 1 ? a.x : 1.0 - a.x) * ((k >> 1) == 1 ? a.y : 1.0 - a.y);
    if (!Seen(pixel[k])) weight[k] = 0.0;
    kept += weight[k];
  }
  if (!(kept > 0.0)) return;
  for (int k = 0; k < 4; ++k) {
    if (weight[k] == 0.0) continue;
    float solid_angle = GetCameraPixelSolidAngle(camera, pixel[k]);
    if (!(solid_angle > 0.0)) continue;
    vec2 clip = (vec2(pixel[k]) + vec2(0.5)) / vec2(camera.width, camera.height) * 2.0 - 1.0;
    places[4 * star + k] = vec4(clip, weight[k] / kept / solid_angle, 0.0);
  }
}
)glsl";

// Then the points: each place with its star's value (this batch's three outputs).
constexpr const char* kStarsVertexSource = R"glsl(#version 430 core
layout(std430, binding = 1) readonly buffer Values { vec4 values[]; };
layout(std430, binding = 2) readonly buffer Places { vec4 places[]; };
flat out vec3 star_value;
void main() {
  vec4 place = places[gl_VertexID];
  gl_PointSize = 1.0;
  star_value = values[gl_VertexID >> 2].rgb * place.z;
  // A share of 0: outside the viewport, nothing drawn.
  gl_Position = place.z > 0.0 ? vec4(place.xy, 0.0, 1.0) : vec4(2.0, 2.0, 0.0, 1.0);
}
)glsl";

// The moon: frame += moonlit * scale, plus the disc's patch where it lies.
constexpr const char* kMoonMain = R"glsl(
layout(local_size_x = 8, local_size_y = 8) in;
layout(rgba32f, binding = 0) uniform image2D frame;
layout(rgba32f, binding = 1) uniform readonly image2D moonlit;
layout(std430, binding = 0) readonly buffer Disc { vec4 disc[]; };
uniform vec3 scale;
uniform ivec2 disc_origin;
uniform ivec2 disc_size;

void main() {
  ivec2 size = imageSize(frame);
  ivec2 pixel = ivec2(gl_GlobalInvocationID.xy);
  if (any(greaterThanEqual(pixel, size))) return;
  vec4 value = imageLoad(frame, pixel);
  value.rgb += imageLoad(moonlit, pixel).rgb * scale;
  ivec2 at = pixel - disc_origin;
  if (all(greaterThanEqual(at, ivec2(0))) && all(lessThan(at, disc_size))) value.rgb += disc[at.y * disc_size.x + at.x].rgb;
  imageStore(frame, pixel, value);
}
)glsl";

constexpr const char* kStarsFragmentSource = R"glsl(#version 430 core
flat in vec3 star_value;
layout(location = 0) out vec4 colour;
void main() { colour = vec4(star_value, 0.0); }
)glsl";

unsigned MakeBuffer(const void* data, std::size_t bytes) {
  unsigned buffer = 0;
  glCreateBuffers(1, &buffer);
  // A buffer of 0 bytes cannot be bound as a range: at least one vec4.
  glNamedBufferStorage(buffer, static_cast<GLsizeiptr>(std::max<std::size_t>(bytes, 16)), nullptr, GL_DYNAMIC_STORAGE_BIT);
  if (bytes > 0 && data != nullptr) glNamedBufferSubData(buffer, 0, static_cast<GLsizeiptr>(bytes), data);
  return buffer;
}

void DeleteBuffer(unsigned& buffer) {
  if (buffer != 0) glDeleteBuffers(1, &buffer);
  buffer = 0;
}

// Outputs [3 b, 3 b + 3) of `values` (rows of `outputs`), as `rows` vec4.
std::vector<float> BatchColumns(const std::vector<float>& values, std::size_t rows, int outputs, std::size_t b) {
  std::vector<float> out(rows * 4, 0.0f);
  for (std::size_t r = 0; r < rows; ++r) {
    for (std::size_t k = 0; k < 3 && 3 * b + k < static_cast<std::size_t>(outputs); ++k) {
      out[4 * r + k] = values[r * static_cast<std::size_t>(outputs) + 3 * b + k];
    }
  }
  return out;
}

}  // namespace

NightSkyGl::NightSkyGl(const Context& context) : context_(context) {
  context_.MakeCurrent();
  const std::span<const float> grid = NightSky::ZodiacalGrid();
  zodiacal_grid_ = MakeBuffer(grid.data(), grid.size_bytes());
  glCreateVertexArrays(1, &vertex_array_);
  glCreateFramebuffers(1, &framebuffer_);
  star_program_ = std::make_unique<ComputeProgram>(kStarsVertexSource, kStarsFragmentSource, "night stars", "");
  CheckGlError("night sky buffers");
}

NightSkyGl::~NightSkyGl() {
  Release();
  DeleteBuffer(zodiacal_grid_);
  if (vertex_array_ != 0) glDeleteVertexArrays(1, &vertex_array_);
  if (framebuffer_ != 0) glDeleteFramebuffers(1, &framebuffer_);
}

void NightSkyGl::Release() {
  for (Batch& batch : batches_) {
    DeleteBuffer(batch.airglow);
    DeleteBuffer(batch.transmitted);
    DeleteBuffer(batch.stars);
  }
  batches_.clear();
  DeleteBuffer(star_directions_);
  DeleteBuffer(star_places_);
  DeleteBuffer(starlight_grid_);
  star_count_ = 0;
  glow_ = false;
}

void NightSkyGl::Set(const NightSky::Folded& folded) {
  context_.MakeCurrent();
  Release();
  const NightSky* night = folded.night();
  if (night == nullptr || folded.outputs() < 1) return;
  const int outputs = folded.outputs();
  const std::size_t batches = (static_cast<std::size_t>(outputs) + 2) / 3;
  glow_ = night->glow() && !folded.airglow().empty();
  zodiacal_ = night->zodiacal();
  zodiacal_scale_ = night->zodiacal_relative();
  if (glow_ && night->starlight()) {
    starlight_grid_ = MakeBuffer(night->starlight_grid().data(), night->starlight_grid().size() * sizeof(float));
  }
  ecliptic_pole_ = night->ecliptic_pole();
  sun_direction_ = night->sun_direction();
  std::vector<glm::dvec3> directions;
  std::vector<float> values;
  folded.Stars(directions, values);
  star_count_ = directions.size();
  std::vector<float> packed(star_count_ * 4, 0.0f);
  for (std::size_t i = 0; i < star_count_; ++i) {
    for (int k = 0; k < 3; ++k) packed[4 * i + k] = static_cast<float>(directions[i][k]);
  }
  star_directions_ = MakeBuffer(packed.data(), packed.size() * sizeof(float));
  star_places_ = MakeBuffer(nullptr, star_count_ * 4 * 4 * sizeof(float));
  constexpr std::size_t kAngles = NightSky::kAngleSamples;
  batches_.resize(batches);
  for (std::size_t b = 0; b < batches; ++b) {
    if (glow_) {
      const std::vector<float> airglow = BatchColumns(folded.airglow(), kAngles, outputs, b);
      const std::vector<float> transmitted = BatchColumns(folded.transmitted(), kAngles, outputs, b);
      batches_[b].airglow = MakeBuffer(airglow.data(), airglow.size() * sizeof(float));
      batches_[b].transmitted = MakeBuffer(transmitted.data(), transmitted.size() * sizeof(float));
    }
    const std::vector<float> stars = BatchColumns(values, star_count_, outputs, b);
    batches_[b].stars = MakeBuffer(stars.data(), stars.size() * sizeof(float));
  }
  CheckGlError("night sky upload");
}

void NightSkyGl::Add(const shared::CameraParameters& camera, std::span<const GpuTexture* const> frames,
                     PassTimings* timings) const {
  if (frames.size() > batches_.size()) {
    throw Error("GL night sky: " + std::to_string(frames.size()) + " frames for a fold of " +
                std::to_string(batches_.size()) + " batches");
  }
  for (const GpuTexture* frame : frames) {
    if (frame == nullptr || frame->empty() || frame->is_3d() || frame->size2().x != camera.width ||
        frame->size2().y != camera.height) {
      throw Error("GL night sky: a frame texture is not the camera's size");
    }
  }
  context_.MakeCurrent();
  GpuPassTimer timer(timings);
  // The frame passes wrote the textures as images.
  glMemoryBarrier(GL_SHADER_IMAGE_ACCESS_BARRIER_BIT | GL_FRAMEBUFFER_BARRIER_BIT);
  if (glow_) {
    const ComputeProgram& program = context_.Program({"definitions.glsl", "geometry.glsl", "camera.glsl"}, kGlowMain,
                                                     "night glow");
    SetCameraUniforms(program, "camera", camera);
    program.SetVec3("ecliptic_pole", ecliptic_pole_);
    program.SetVec3("sun_direction", sun_direction_);
    program.SetInt("zodiacal", zodiacal_ ? 1 : 0);
    program.SetFloat("zodiacal_scale", zodiacal_scale_);
    program.SetInt("starlight", starlight_grid_ != 0 ? 1 : 0);
    glBindBufferBase(GL_SHADER_STORAGE_BUFFER, 3, zodiacal_grid_);
    if (starlight_grid_ != 0) glBindBufferBase(GL_SHADER_STORAGE_BUFFER, 4, starlight_grid_);
    for (std::size_t b = 0; b < frames.size(); ++b) {
      glBindImageTexture(0, frames[b]->id(), 0, GL_FALSE, 0, GL_READ_WRITE, GL_RGBA32F);
      glBindBufferBase(GL_SHADER_STORAGE_BUFFER, 1, batches_[b].airglow);
      glBindBufferBase(GL_SHADER_STORAGE_BUFFER, 2, batches_[b].transmitted);
      DispatchCompute2D(program, frames[b]->size2());
    }
    glMemoryBarrier(GL_FRAMEBUFFER_BARRIER_BIT | GL_TEXTURE_FETCH_BARRIER_BIT | GL_SHADER_IMAGE_ACCESS_BARRIER_BIT);
    timer.Stop("night_glow");
  }
  if (star_count_ > 0) {
    const ComputeProgram& places = context_.Program({"definitions.glsl", "geometry.glsl", "camera.glsl"},
                                                    kStarPlacesMain, "night star places");
    SetCameraUniforms(places, "camera", camera);
    places.SetInt("star_count", static_cast<int>(star_count_));
    glBindBufferBase(GL_SHADER_STORAGE_BUFFER, 0, star_directions_);
    glBindBufferBase(GL_SHADER_STORAGE_BUFFER, 2, star_places_);
    DispatchCompute1D(places, static_cast<int>(star_count_));
    glMemoryBarrier(GL_SHADER_STORAGE_BARRIER_BIT);
    const ComputeProgram& program = *star_program_;
    program.Use();
    // The state this pass changes, restored after it.
    GLint previous_framebuffer = 0;
    GLint viewport[4] = {0, 0, 0, 0};
    glGetIntegerv(GL_DRAW_FRAMEBUFFER_BINDING, &previous_framebuffer);
    glGetIntegerv(GL_VIEWPORT, viewport);
    const GLboolean blend = glIsEnabled(GL_BLEND);
    const GLboolean program_point_size = glIsEnabled(GL_PROGRAM_POINT_SIZE);
    glBindFramebuffer(GL_DRAW_FRAMEBUFFER, framebuffer_);
    glViewport(0, 0, camera.width, camera.height);
    glEnable(GL_BLEND);
    glBlendEquation(GL_FUNC_ADD);
    glBlendFunc(GL_ONE, GL_ONE);
    glEnable(GL_PROGRAM_POINT_SIZE);
    glBindVertexArray(vertex_array_);
    for (std::size_t b = 0; b < frames.size(); ++b) {
      glNamedFramebufferTexture(framebuffer_, GL_COLOR_ATTACHMENT0, frames[b]->id(), 0);
      glNamedFramebufferDrawBuffer(framebuffer_, GL_COLOR_ATTACHMENT0);
      if (glCheckNamedFramebufferStatus(framebuffer_, GL_DRAW_FRAMEBUFFER) != GL_FRAMEBUFFER_COMPLETE) {
        throw Error("GL night sky: a frame texture cannot be drawn into");
      }
      glBindBufferBase(GL_SHADER_STORAGE_BUFFER, 1, batches_[b].stars);
      glDrawArrays(GL_POINTS, 0, static_cast<GLsizei>(4 * star_count_));
    }
    glNamedFramebufferTexture(framebuffer_, GL_COLOR_ATTACHMENT0, 0, 0);
    glBindVertexArray(0);
    if (!blend) glDisable(GL_BLEND);
    if (!program_point_size) glDisable(GL_PROGRAM_POINT_SIZE);
    glBindFramebuffer(GL_DRAW_FRAMEBUFFER, static_cast<GLuint>(previous_framebuffer));
    glViewport(viewport[0], viewport[1], viewport[2], viewport[3]);
    timer.Stop("night_stars");
  }
  CheckGlError("night sky pass");
}

void NightSkyGl::AddMoon(std::span<const GpuTexture* const> frames, std::span<const GpuTexture* const> moonlit,
                         std::span<const shared::vec3> scale, const Image& disc, shared::ivec2 disc_origin,
                         PassTimings* timings) const {
  if (moonlit.size() != frames.size() || scale.size() != frames.size() ||
      (disc.width > 0 && static_cast<std::size_t>(disc.channels) > 3 * frames.size())) {
    throw Error("GL moon: the frames, the moonlit frames, the scales and the disc do not match");
  }
  for (std::size_t b = 0; b < frames.size(); ++b) {
    if (frames[b] == nullptr || moonlit[b] == nullptr || frames[b]->size2().x != moonlit[b]->size2().x ||
        frames[b]->size2().y != moonlit[b]->size2().y) {
      throw Error("GL moon: a moonlit frame is not the frame's size");
    }
  }
  context_.MakeCurrent();
  GpuPassTimer timer(timings);
  const ComputeProgram& program = context_.Program({}, kMoonMain, "moon");
  glMemoryBarrier(GL_SHADER_IMAGE_ACCESS_BARRIER_BIT | GL_FRAMEBUFFER_BARRIER_BIT);
  const std::size_t texels = static_cast<std::size_t>(std::max(disc.width, 0)) * std::max(disc.height, 0);
  const std::size_t channels = static_cast<std::size_t>(std::max(disc.channels, 0));
  std::vector<float> patch(std::max<std::size_t>(texels, 1) * 4, 0.0f);
  unsigned buffer = 0;
  for (std::size_t b = 0; b < frames.size(); ++b) {
    std::fill(patch.begin(), patch.end(), 0.0f);
    for (std::size_t i = 0; i < texels; ++i) {
      for (std::size_t k = 0; k < 3 && 3 * b + k < channels; ++k) patch[4 * i + k] = disc.pixels[i * channels + 3 * b + k];
    }
    DeleteBuffer(buffer);
    buffer = MakeBuffer(patch.data(), patch.size() * sizeof(float));
    program.SetVec3("scale", scale[b]);
    glProgramUniform2i(program.id(), glGetUniformLocation(program.id(), "disc_origin"), disc_origin.x, disc_origin.y);
    glProgramUniform2i(program.id(), glGetUniformLocation(program.id(), "disc_size"), texels > 0 ? disc.width : 0,
                       texels > 0 ? disc.height : 0);
    glBindImageTexture(0, frames[b]->id(), 0, GL_FALSE, 0, GL_READ_WRITE, GL_RGBA32F);
    glBindImageTexture(1, moonlit[b]->id(), 0, GL_FALSE, 0, GL_READ_ONLY, GL_RGBA32F);
    glBindBufferBase(GL_SHADER_STORAGE_BUFFER, 0, buffer);
    DispatchCompute2D(program, frames[b]->size2());
  }
  glMemoryBarrier(GL_FRAMEBUFFER_BARRIER_BIT | GL_TEXTURE_FETCH_BARRIER_BIT | GL_SHADER_IMAGE_ACCESS_BARRIER_BIT);
  DeleteBuffer(buffer);
  timer.Stop("moon");
  CheckGlError("moon pass");
}

}  // namespace atmo::gl
