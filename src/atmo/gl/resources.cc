#include "gl/resources.h"

#include <chrono>
#include <cstddef>
#include <string>

#include <epoxy/gl.h>

#include "atmo/error.h"
#include "gl/context.h"
#include "gl/timer_queries.h"

namespace atmo::gl {

std::string StepKind(std::string_view pass, bool whole) {
  std::string kind(pass);
  while (!kind.empty() && kind.back() >= '0' && kind.back() <= '9') kind.pop_back();
  if (whole) kind += "#whole";
  return kind;
}

void CheckGlError(std::string_view what) {
  const GLenum error = glGetError();
  if (error != GL_NO_ERROR) {
    throw Error("GL " + std::string(what) + " failed: GL error " + std::to_string(static_cast<unsigned>(error)));
  }
}

void GpuTexture::Create(shared::ivec3 size, bool is_3d, bool repeat_u) {
  if (size.x < 1 || size.y < 1 || size.z < 1) throw Error("GL table: every size must be >= 1");
  size_ = size;
  is_3d_ = is_3d;
  repeat_u_ = repeat_u;
  glCreateTextures(is_3d ? GL_TEXTURE_3D : GL_TEXTURE_2D, 1, &texture_);
  if (is_3d) {
    glTextureStorage3D(texture_, 1, GL_RGBA32F, size.x, size.y, size.z);
    glTextureParameteri(texture_, GL_TEXTURE_WRAP_R, GL_CLAMP_TO_EDGE);
  } else {
    glTextureStorage2D(texture_, 1, GL_RGBA32F, size.x, size.y);
  }
  glTextureParameteri(texture_, GL_TEXTURE_MIN_FILTER, GL_LINEAR);
  glTextureParameteri(texture_, GL_TEXTURE_MAG_FILTER, GL_LINEAR);
  glTextureParameteri(texture_, GL_TEXTURE_WRAP_S, repeat_u ? GL_REPEAT : GL_CLAMP_TO_EDGE);
  glTextureParameteri(texture_, GL_TEXTURE_WRAP_T, GL_CLAMP_TO_EDGE);
  CheckGlError("table allocation");
}

GpuTexture GpuTexture::Make2D(shared::ivec2 size, bool repeat_u) {
  GpuTexture t;
  t.Create({size.x, size.y, 1}, false, repeat_u);
  return t;
}

GpuTexture GpuTexture::Make3D(shared::ivec3 size) {
  GpuTexture t;
  t.Create(size, true, false);
  return t;
}

namespace {

template <typename Table>
std::vector<float> ToRgba(const Table& table) {
  std::vector<float> rgba(table.texels.size() * 4);
  for (std::size_t i = 0; i < table.texels.size(); ++i) {
    rgba[4 * i] = table.texels[i].x;
    rgba[4 * i + 1] = table.texels[i].y;
    rgba[4 * i + 2] = table.texels[i].z;
    rgba[4 * i + 3] = 1.0f;
  }
  return rgba;
}

template <typename Table>
void FromRgba(const std::vector<float>& rgba, Table& table) {
  for (std::size_t i = 0; i < table.texels.size(); ++i) {
    table.texels[i] = glm::vec3(rgba[4 * i], rgba[4 * i + 1], rgba[4 * i + 2]);
  }
}

}  // namespace

GpuTexture GpuTexture::Upload(const shared::Texture2D& table) {
  GpuTexture t = Make2D({table.width, table.height}, table.repeat_u);
  const std::vector<float> rgba = ToRgba(table);
  glTextureSubImage2D(t.texture_, 0, 0, 0, table.width, table.height, GL_RGBA, GL_FLOAT, rgba.data());
  CheckGlError("table upload");
  return t;
}

GpuTexture GpuTexture::Upload(const shared::Texture3D& table) {
  GpuTexture t = Make3D({table.width, table.height, table.depth});
  const std::vector<float> rgba = ToRgba(table);
  glTextureSubImage3D(t.texture_, 0, 0, 0, 0, table.width, table.height, table.depth, GL_RGBA, GL_FLOAT,
                      rgba.data());
  CheckGlError("table upload");
  return t;
}

GpuTexture::~GpuTexture() {
  if (texture_ != 0) glDeleteTextures(1, &texture_);
}

GpuTexture& GpuTexture::operator=(GpuTexture&& other) noexcept {
  if (this != &other) {
    if (texture_ != 0) glDeleteTextures(1, &texture_);
    texture_ = std::exchange(other.texture_, 0u);
    size_ = other.size_;
    is_3d_ = other.is_3d_;
    repeat_u_ = other.repeat_u_;
  }
  return *this;
}

void GpuTexture::BindSampler(unsigned unit) const { glBindTextureUnit(unit, texture_); }

void GpuTexture::BindImage(unsigned unit) const {
  glBindImageTexture(unit, texture_, 0, is_3d_ ? GL_TRUE : GL_FALSE, 0, GL_WRITE_ONLY, GL_RGBA32F);
}

std::vector<float> GpuTexture::DownloadRgba() const {
  std::vector<float> rgba(static_cast<std::size_t>(size_.x) * size_.y * size_.z * 4);
  glGetTextureImage(texture_, 0, GL_RGBA, GL_FLOAT, static_cast<GLsizei>(rgba.size() * sizeof(float)), rgba.data());
  CheckGlError("table readback");
  return rgba;
}

shared::Texture2D GpuTexture::Download2D() const {
  shared::Texture2D table(size_.x, size_.y, repeat_u_);
  FromRgba(DownloadRgba(), table);
  return table;
}

shared::Texture3D GpuTexture::Download3D() const {
  shared::Texture3D table(size_.x, size_.y, size_.z);
  FromRgba(DownloadRgba(), table);
  return table;
}

void BindSamplers(const ComputeProgram& program,
                  std::initializer_list<std::pair<const char*, const GpuTexture*>> tables) {
  GLuint unit = 0;
  for (const auto& [sampler, table] : tables) {
    program.SetInt(sampler, static_cast<int>(unit));
    table->BindSampler(unit++);
  }
}

namespace {

GLuint GroupCount(int size, int group) { return static_cast<GLuint>((size + group - 1) / group); }

void Dispatch(const ComputeProgram& program, GLuint x, GLuint y, GLuint z) {
  program.Use();
  glDispatchCompute(x, y, z);
  glMemoryBarrier(GL_TEXTURE_FETCH_BARRIER_BIT | GL_TEXTURE_UPDATE_BARRIER_BIT | GL_SHADER_IMAGE_ACCESS_BARRIER_BIT |
                  GL_SHADER_STORAGE_BARRIER_BIT | GL_BUFFER_UPDATE_BARRIER_BIT);
}

}  // namespace

void DispatchCompute2D(const ComputeProgram& program, shared::ivec2 size) {
  Dispatch(program, GroupCount(size.x, kGroupSize2D), GroupCount(size.y, kGroupSize2D), 1);
}

void DispatchCompute3D(const ComputeProgram& program, shared::ivec3 size) {
  Dispatch(program, GroupCount(size.x, kGroupSize3D), GroupCount(size.y, kGroupSize3D),
           GroupCount(size.z, kGroupSize3D));
}

void DispatchCompute1D(const ComputeProgram& program, int count) {
  Dispatch(program, GroupCount(count, kGroupSize1D), 1, 1);
}

void DispatchWorkGroups(const ComputeProgram& program, shared::ivec3 groups) {
  Dispatch(program, static_cast<GLuint>(groups.x), static_cast<GLuint>(groups.y), static_cast<GLuint>(groups.z));
}

namespace {

double NowMs() {
  return std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now().time_since_epoch()).count();
}

}  // namespace

GpuPassTimer::GpuPassTimer(PassTimings* timings) : timings_(timings) {
  if (timings_ == nullptr) return;
  const auto* renderer = reinterpret_cast<const char*>(glGetString(GL_RENDERER));
  const bool software = renderer != nullptr && IsSoftwareRenderer(renderer);
  if (!software) queries_ = CurrentTimerQueries();
  Start();
}

// An unstopped record is dropped unread (TimerQueries deletes its queries).
GpuPassTimer::~GpuPassTimer() = default;

void GpuPassTimer::Start() {
  if (queries_ != nullptr) {
    record_ = queries_->Begin();
  } else {
    glFinish();
    start_ms_ = NowMs();
  }
}

void GpuPassTimer::Stop(std::string_view name) {
  if (timings_ == nullptr) return;
  if (queries_ != nullptr) {
    queries_->End(*record_);
    timings_->AddDeferred(name, [queries = queries_, record = record_](bool wait) {
      return queries->Read(*record, wait);
    });
  } else {
    glFinish();
    timings_->Add(name, NowMs() - start_ms_);
  }
  Start();
}

}  // namespace atmo::gl
