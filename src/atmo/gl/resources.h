// GPU-resident tables, pass timers and dispatch for the GL backend (private).
//
// A table stays on the GPU between passes: a pass reads its inputs as GpuTextures bound to
// samplers and writes its output as an image; only what a caller asks for is read back
// (Download*). Tables upload from and download to the layout of shared::Texture2D / Texture3D,
// so either backend's table feeds either backend's lookups.
//
// To use it (a gl::Context current on this thread):
//   GpuTexture table = GpuTexture::Make2D({256, 64});
//   const ComputeProgram& program = context.Program(files, main_source, "transmittance table");
//   table.BindImage(0);
//   GpuPassTimer timer(&timings);                // nullptr: no timing and no synchronisation
//   DispatchCompute2D(program, table.size2());
//   timer.Stop("transmittance_lut");             // GPU time of the dispatch
//   shared::Texture2D host = table.Download2D();
#pragma once

#include <initializer_list>
#include <memory>
#include <string>
#include <string_view>
#include <utility>
#include <vector>

#include "atmo/timing.h"
#include "gl/program.h"
#include "gl/timer_queries.h"
#include "shared/shared.h"

namespace atmo::gl {

// An rgba32f texture, 2D or 3D, one level, sampled with GL_LINEAR and clamp to edge (repeat in s
// where repeat_u): the sampling rules of shared::Texture2D / Texture3D. Move-only; deleted with it.
class GpuTexture {
 public:
  GpuTexture() = default;
  static GpuTexture Make2D(shared::ivec2 size, bool repeat_u = false);
  static GpuTexture Make3D(shared::ivec3 size);
  static GpuTexture Upload(const shared::Texture2D& table);
  static GpuTexture Upload(const shared::Texture3D& table);
  ~GpuTexture();
  GpuTexture(GpuTexture&& other) noexcept { *this = std::move(other); }
  GpuTexture& operator=(GpuTexture&& other) noexcept;
  GpuTexture(const GpuTexture&) = delete;
  GpuTexture& operator=(const GpuTexture&) = delete;

  bool empty() const { return texture_ == 0; }
  bool is_3d() const { return is_3d_; }
  shared::ivec3 size() const { return size_; }
  shared::ivec2 size2() const { return {size_.x, size_.y}; }
  unsigned id() const { return texture_; }

  // Binds the texture to texture unit `unit` (for a sampler) or image unit `unit` (rgba32f,
  // write-only, all layers of a 3D texture).
  void BindSampler(unsigned unit) const;
  void BindImage(unsigned unit) const;

  // rgba per texel, x fastest, then y, then z; waits for the GPU.
  std::vector<float> DownloadRgba() const;
  shared::Texture2D Download2D() const;  // rgb; repeat_u as the texture's
  shared::Texture3D Download3D() const;  // rgb

 private:
  void Create(shared::ivec3 size, bool is_3d, bool repeat_u);

  unsigned texture_ = 0;
  shared::ivec3 size_{0, 0, 0};
  bool is_3d_ = false;
  bool repeat_u_ = false;
};

// Binds table i to texture unit i and gives the sampler uniform named with it that unit, so that
// names and units cannot disagree.
void BindSamplers(const ComputeProgram& program,
                  std::initializer_list<std::pair<const char*, const GpuTexture*>> tables);

// Dispatches `program` over `size` invocations with the work-group size the shader declares
// (8 x 8 x 1 for 2D, 4 x 4 x 4 for 3D, 64 x 1 x 1 for 1D: kGroupSize*) and makes its image and
// buffer writes visible to the passes and readbacks after it.
inline constexpr int kGroupSize2D = 8;
inline constexpr int kGroupSize3D = 4;
inline constexpr int kGroupSize1D = 64;
void DispatchCompute2D(const ComputeProgram& program, shared::ivec2 size);
void DispatchCompute3D(const ComputeProgram& program, shared::ivec3 size);
void DispatchCompute1D(const ComputeProgram& program, int count);
// One work group per element of `groups` (for passes whose work group cooperates on one texel).
void DispatchWorkGroups(const ComputeProgram& program, shared::ivec3 groups);

// The GPU time of the passes between construction (or the last Stop) and Stop(name), added to
// `timings` under `name`. On a GPU: a pair of GL_TIMESTAMP queries whose result `timings`
// collects later (PassTimings::AddDeferred; gl/timer_queries.h), so timing never waits for the
// GPU. On llvmpipe (which runs a dispatch on the CPU inside the call and whose queries read ~0):
// the wall clock up to glFinish, added at once. With a null `timings` it measures nothing and
// never waits for the GPU.
class GpuPassTimer {
 public:
  explicit GpuPassTimer(PassTimings* timings);
  ~GpuPassTimer();
  GpuPassTimer(const GpuPassTimer&) = delete;
  GpuPassTimer& operator=(const GpuPassTimer&) = delete;

  void Stop(std::string_view name);  // and starts timing the next pass

 private:
  void Start();

  PassTimings* timings_;
  std::shared_ptr<TimerQueries> queries_;  // null: the wall clock (a software GL, or no Context)
  std::shared_ptr<GpuTimeRecord> record_;
  double start_ms_ = 0.0;
};

// For passes with one work group of 64 invocations per texel (as Hillaire 2020 does for its
// multiple-scattering table): invocation `lane` integrates directions lane, lane + 64, ... and
// SumOverWorkGroup adds two vec3 partial sums over the group (a tree in shared memory); every
// invocation receives the totals. A GPU then runs 64 times more threads, each with 1/64 of a
// texel's rays. Used by hillaire's multiple-scattering and ground-irradiance passes and by
// source4d's quadrature pass.
inline constexpr std::string_view kWorkGroupSumSource = R"glsl(
layout(local_size_x = 64) in;
shared vec3 partial_a[64];
shared vec3 partial_b[64];

void SumOverWorkGroup(int lane, inout vec3 a, inout vec3 b) {
  partial_a[lane] = a;
  partial_b[lane] = b;
  memoryBarrierShared();
  barrier();
  for (int stride = 32; stride > 0; stride /= 2) {
    if (lane < stride) {
      partial_a[lane] += partial_a[lane + stride];
      partial_b[lane] += partial_b[lane + stride];
    }
    memoryBarrierShared();
    barrier();
  }
  a = partial_a[0];
  b = partial_b[0];
}
)glsl";

// The kind of a table builder's step (next_step_kind): `pass` without its trailing order number
// ("source4d_gather_3" -> "source4d_gather_"), plus "#whole" when the pass runs in one step.
std::string StepKind(std::string_view pass, bool whole);

// Throws atmo::Error naming `what` when GL has recorded an error.
void CheckGlError(std::string_view what);

}  // namespace atmo::gl
