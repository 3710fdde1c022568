#include "gl/exposure_gl.h"

#include <string>

#include <epoxy/gl.h>

#include "atmo/error.h"

namespace atmo::gl {
namespace {

constexpr int kHistogramGroupSize = 16;  // 16 x 16 invocations
constexpr int kHistogramGroups = 16;     // per axis at most: a grid-stride loop covers the rest
constexpr int kReduceGroupSize = 256;

// Pass 1. BATCH_COUNT, HAS_ALPHA and the binding of frame0..frame7 come before it.
constexpr const char* kHistogramMain = R"glsl(
layout(local_size_x = 16, local_size_y = 16) in;
layout(std430, binding = 0) buffer Histogram { uint bins[]; };
uniform mat3 weights[8];
uniform ivec2 frame_size;
const int kBins = 4096;
shared uint local_bins[kBins];

void main() {
  const uint lane = gl_LocalInvocationIndex;
  for (uint i = lane; i < kBins; i += 256u) local_bins[i] = 0u;
  barrier();
  const ivec2 stride = ivec2(gl_NumWorkGroups.xy * gl_WorkGroupSize.xy);
  for (int y = int(gl_GlobalInvocationID.y); y < frame_size.y; y += stride.y) {
    for (int x = int(gl_GlobalInvocationID.x); x < frame_size.x; x += stride.x) {
      const ivec2 texel = ivec2(x, y);
      const vec4 first = texelFetch(frame0, texel, 0);
#if HAS_ALPHA
      // alpha > 0 (a NaN alpha is outside too), on the bits as below.
      const uint alpha_bits = floatBitsToUint(first.a);
      if ((alpha_bits & 0x80000000u) != 0u || alpha_bits == 0u || (alpha_bits & 0x7f800000u) == 0x7f800000u &&
          (alpha_bits & 0x007fffffu) != 0u) continue;
#endif
      vec3 rgb = weights[0] * first.rgb;
      SUM_OTHER_BATCHES
      const float l = dot(rgb, vec3(0.2126, 0.7152, 0.0722));
      // Finite and > 0, tested on the bits: a GPU compiler may assume no NaN or infinity and fold
      // comparisons and isinf/isnan away (the NVIDIA driver did: NaN and infinite texels counted).
      const uint bits = floatBitsToUint(l);
      if ((bits & 0x80000000u) != 0u || (bits & 0x7f800000u) == 0x7f800000u || bits == 0u) continue;
      const int bin = clamp(int(floor((log2(l) + 64.0) * 32.0)), 0, kBins - 1);
      atomicAdd(local_bins[bin], 1u);
    }
  }
  barrier();
  for (uint i = lane; i < kBins; i += 256u) {
    if (local_bins[i] != 0u) atomicAdd(bins[i], local_bins[i]);
  }
}
)glsl";

// Pass 2: one work group of 256; invocation t owns bins [16 t, 16 t + 16).
constexpr const char* kReduceSource = R"glsl(#version 450 core
layout(local_size_x = 256) in;
layout(std430, binding = 0) buffer Histogram { uint bins[]; };
layout(std430, binding = 1) buffer Result { float log2_average; uint pixels; };
const int kBins = 4096;
const int kPer = 16;
shared uint prefix[256];  // counts of the bins before each invocation's
shared float partial[256];
shared int low_bin;
shared int high_bin;

float Centre(int bin) { return -64.0 + (float(bin) + 0.5) / 32.0; }

void main() {
  const int t = int(gl_LocalInvocationIndex);
  uint own = 0u;
  for (int i = 0; i < kPer; ++i) own += bins[t * kPer + i];
  prefix[t] = own;
  barrier();
  // Inclusive scan (Hillis and Steele), then exclusive by subtracting the own count.
  for (int offset = 1; offset < 256; offset *= 2) {
    const uint add = t >= offset ? prefix[t - offset] : 0u;
    barrier();
    prefix[t] += add;
    barrier();
  }
  const uint n = prefix[255];
  const uint before = prefix[t] - own;
  if (t == 0) {
    low_bin = 0;
    high_bin = 0;
  }
  barrier();
  if (n > 0u) {
    // AutoExposureEv100's ranks (0-based) of the 2nd and 98th percentiles.
    const uint low_rank = uint(floor(0.02 * float(n - 1u)));
    const uint high_rank = uint(ceil(0.98 * float(n - 1u)));
    uint seen = before;
    for (int i = 0; i < kPer; ++i) {
      const uint c = bins[t * kPer + i];
      if (c != 0u && low_rank >= seen && low_rank < seen + c) low_bin = t * kPer + i;
      if (c != 0u && high_rank >= seen && high_rank < seen + c) high_bin = t * kPer + i;
      seen += c;
    }
  }
  barrier();
  const float low = Centre(low_bin);
  const float high = Centre(high_bin);
  float sum = 0.0;
  for (int i = 0; i < kPer; ++i) {
    const uint c = bins[t * kPer + i];
    sum += float(c) * clamp(Centre(t * kPer + i), low, high);
  }
  partial[t] = sum;
  barrier();
  for (int offset = 128; offset > 0; offset /= 2) {
    if (t < offset) partial[t] += partial[t + offset];
    barrier();
  }
  if (t == 0) {
    log2_average = n > 0u ? partial[0] / float(n) : 0.0;
    pixels = n;
  }
}
)glsl";

}  // namespace

ExposureMeter::ExposureMeter() {
  glCreateBuffers(1, &histogram_);
  glNamedBufferStorage(histogram_, kBins * sizeof(std::uint32_t), nullptr, GL_DYNAMIC_STORAGE_BIT);
  glCreateBuffers(1, &result_);
  glNamedBufferStorage(result_, 8, nullptr, 0);
  for (Slot& slot : slots_) {
    glCreateBuffers(1, &slot.buffer);
    glNamedBufferStorage(slot.buffer, 8, nullptr, GL_CLIENT_STORAGE_BIT);
  }
  reduce_program_ = std::make_unique<ComputeProgram>(kReduceSource, "exposure reduction");
  CheckGlError("exposure meter buffers");
}

ExposureMeter::~ExposureMeter() {
  for (Slot& slot : slots_) {
    if (slot.fence != nullptr) glDeleteSync(static_cast<GLsync>(slot.fence));
    glDeleteBuffers(1, &slot.buffer);
  }
  glDeleteBuffers(1, &result_);
  glDeleteBuffers(1, &histogram_);
}

const ComputeProgram& ExposureMeter::HistogramProgram(int batches, bool has_alpha) {
  const int key = batches * 2 + (has_alpha ? 1 : 0);
  const auto found = histogram_programs_.find(key);
  if (found != histogram_programs_.end()) return *found->second;
  std::string source = "#version 450 core\n#define HAS_ALPHA " + std::to_string(has_alpha ? 1 : 0) + "\n";
  std::string others;
  for (int b = 0; b < batches; ++b) {
    const std::string index = std::to_string(b);
    source += "layout(binding = " + index + ") uniform sampler2D frame" + index + ";\n";
    if (b > 0) others += "rgb += weights[" + index + "] * texelFetch(frame" + index + ", texel, 0).rgb; ";
  }
  source += "#define SUM_OTHER_BATCHES " + others + "\n" + kHistogramMain;
  auto program = std::make_unique<ComputeProgram>(source, "exposure histogram");
  return *histogram_programs_.emplace(key, std::move(program)).first->second;
}

void ExposureMeter::Meter(std::span<const GpuTexture* const> frames, std::span<const glm::mat3> weights,
                          bool has_alpha) {
  const int batches = static_cast<int>(frames.size());
  if (batches < 1 || batches > kMaxBatches) {
    throw Error("exposure meter: 1 to " + std::to_string(kMaxBatches) + " frame textures (got " +
                std::to_string(batches) + ")");
  }
  if (weights.size() < frames.size()) throw Error("exposure meter: a weight matrix per frame texture");
  const shared::ivec2 size = frames[0]->size2();
  for (const GpuTexture* frame : frames) {
    if (frame->size2() != size) throw Error("exposure meter: the frame textures differ in size");
  }
  // The slot to copy into: a free one, else the oldest (its result is dropped unread).
  Slot* slot = &slots_[0];
  for (Slot& s : slots_) {
    if (s.fence == nullptr) {
      slot = &s;
      break;
    }
    if (s.generation < slot->generation) slot = &s;
  }
  if (slot->fence != nullptr) {
    glDeleteSync(static_cast<GLsync>(slot->fence));
    slot->fence = nullptr;
  }

  const GLuint zero = 0;
  glClearNamedBufferData(histogram_, GL_R32UI, GL_RED_INTEGER, GL_UNSIGNED_INT, &zero);
  const ComputeProgram& histogram = HistogramProgram(batches, has_alpha);
  histogram.Use();
  glUniformMatrix3fv(glGetUniformLocation(histogram.id(), "weights"), batches, GL_FALSE, &weights[0][0][0]);
  glUniform2i(glGetUniformLocation(histogram.id(), "frame_size"), size.x, size.y);
  for (int b = 0; b < batches; ++b) glBindTextureUnit(b, frames[b]->id());
  glBindBufferBase(GL_SHADER_STORAGE_BUFFER, 0, histogram_);
  const auto groups = [](int extent) {
    return std::min(kHistogramGroups, (extent + kHistogramGroupSize - 1) / kHistogramGroupSize);
  };
  glMemoryBarrier(GL_TEXTURE_FETCH_BARRIER_BIT | GL_BUFFER_UPDATE_BARRIER_BIT);
  glDispatchCompute(static_cast<GLuint>(groups(size.x)), static_cast<GLuint>(groups(size.y)), 1);
  glMemoryBarrier(GL_SHADER_STORAGE_BARRIER_BIT);
  reduce_program_->Use();
  glBindBufferBase(GL_SHADER_STORAGE_BUFFER, 1, result_);
  glDispatchCompute(1, 1, 1);
  glMemoryBarrier(GL_BUFFER_UPDATE_BARRIER_BIT);
  glCopyNamedBufferSubData(result_, slot->buffer, 0, 0, 8);
  slot->fence = glFenceSync(GL_SYNC_GPU_COMMANDS_COMPLETE, 0);
  slot->generation = ++generation_;
  glUseProgram(0);
  CheckGlError("exposure meter");
}

std::optional<ExposureMeter::Reading> ExposureMeter::Latest(bool wait) {
  // The newest slot whose copy is done; older ones are dropped.
  Slot* newest = nullptr;
  for (Slot& slot : slots_) {
    if (slot.fence == nullptr) continue;
    if (wait && slot.generation == generation_) {
      glClientWaitSync(static_cast<GLsync>(slot.fence), GL_SYNC_FLUSH_COMMANDS_BIT, GLuint64{10'000'000'000});
    }
    GLint status = GL_UNSIGNALED;
    glGetSynciv(static_cast<GLsync>(slot.fence), GL_SYNC_STATUS, 1, nullptr, &status);
    if (status == GL_SIGNALED && (newest == nullptr || slot.generation > newest->generation)) newest = &slot;
  }
  if (newest != nullptr) {
    struct {
      float log2_average;
      std::uint32_t pixels;
    } bytes{};
    glGetNamedBufferSubData(newest->buffer, 0, 8, &bytes);
    latest_ = Reading{bytes.log2_average, bytes.pixels, newest->generation};
    for (Slot& slot : slots_) {
      if (slot.fence != nullptr && slot.generation <= newest->generation) {
        glDeleteSync(static_cast<GLsync>(slot.fence));
        slot.fence = nullptr;
      }
    }
  } else if (generation_ > 0 && !latest_) {
    // Nothing arrived yet: make sure the commands reach the GPU.
    glFlush();
  }
  return latest_;
}

}  // namespace atmo::gl
