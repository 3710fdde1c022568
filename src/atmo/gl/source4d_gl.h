// Model source4d on the GL backend (configuration gl_f32_rgb), private to the backend. The frame
// pass evaluates GetSource4dRadiance of src/atmo/shared/source4d.glsl per pixel in float, with the
// atmosphere in km, as Source4dModel's SkyView does in double on the CPU. Its tables come either
// from the CPU (cpu/source4d_tables.h, in double, metres), uploaded, or from the GPU's own
// builder (ComputeSource4dTablesGl: the gathering, the matrix products, the ln-G writes and the
// ground irradiance as compute passes; the transmittance table and the quadrature matrices, which
// depend only on the phase functions, on the CPU). The tables do not depend on the length unit
// (transmittance, G and the ground irradiance are dimensionless or per unit solar irradiance;
// their coordinates are ratios of lengths), so CPU tables built in metres answer the GPU's
// lookups in km.
//
// To use it (a gl::Context alive on this thread):
//   Image image = gl::RenderSource4dGl(context, Preset("earth"), settings, render, &timings);  // GPU tables
// or, with the CPU's tables:
//   Source4dModel model(Preset("earth"), Source4dModelSettings::FromOptions(options));
//   model.Precompute();
//   Image image = gl::RenderSource4dGl(context, model, render, &timings);
// or, per batch, UploadSource4dTables / ComputeSource4dTablesGl and RunSource4dFramePass.
#pragma once

#include <memory>
#include <string>

#include <glm/glm.hpp>

#include "atmo/image.h"
#include "atmo/render.h"
#include "atmo/timing.h"
#include "gl/context.h"
#include "gl/resources.h"
#include "models/source4d_model.h"
#include "shared/shared.h"

namespace atmo::gl {

// The tables of one batch on the GPU: the 2D transmittance table, ln G_R and ln G_M (3D), the
// sky's ground irradiance (mu_s_size x 1), and the number of sun-zenith rows per r layer.
struct Source4dTablesGl {
  GpuTexture transmittance;
  GpuTexture rayleigh;
  GpuTexture mie;
  GpuTexture ground_irradiance;
  int mu_s_size = 0;
};

// Uploads the CPU-built tables of one batch (Source4dModel::Batch::tables, after Precompute).
Source4dTablesGl UploadSource4dTables(const cpu::Source4dTables& tables);

// The tables of one batch built on the GPU, the passes of cpu::ComputeSource4dTables in float:
// the transmittance table (hillaire's kernel), then per order the gathering (one invocation per
// ray and node), the products with the quadrature matrices (a tiled matrix product) and the
// ground irradiance, the ln-G tables of the order, then the geometric tail and the sums. GPU
// times as source4d_transmittance_lut, source4d_gather_N, source4d_convolve_N, source4d_sum; the
// quadrature matrices as source4d_quadrature on a hardware GPU, or on a software GL (where the
// CPU is faster) as cpu_source4d_quadrature, computed on a thread while the transmittance table
// is built; compilation as source4d_gl_compile. `km_atmosphere` = ToSharedParameters(parameters, batch, 1000). Throws
// atmo::Error for a table whose passes would need more than 65535 work groups.
Source4dTablesGl ComputeSource4dTablesGl(const Context& context, const shared::AtmosphereParameters& km_atmosphere,
                                         const cpu::Source4dSettings& settings, PassTimings* timings = nullptr);

// The same tables built a step at a time, for a program that must keep drawing while they are
// computed (atmo-viewer): every pass of ComputeSource4dTablesGl, in the same order and with the
// same results, but the gathering and the matrix products (the passes that take the time) in
// steps of `groups_per_step` work groups of 64 invocations for the gathering and 1/8 of that for
// the products, whose invocations cost ~10x more (0: whole passes, what ComputeSource4dTablesGl
// does). The CPU's transmittance table and quadrature matrices (~0.1 s) run on a thread of their
// own from the constructor on (with groups_per_step 0: in the first step); the first step uploads
// them once ready and returns at once (nothing done, progress unchanged) while they are not.
// Each Step() runs one step (its time under the pass's name into `timings`); after the last,
// done() and Take() gives the tables. Between steps the caller may run other passes on the
// context: every step sets the uniforms and binds what it uses. Throws as ComputeSource4dTablesGl.
class Source4dTablesBuilder {
 public:
  Source4dTablesBuilder(const Context& context, const shared::AtmosphereParameters& km_atmosphere,
                        const cpu::Source4dSettings& settings, int groups_per_step, PassTimings* timings = nullptr);
  ~Source4dTablesBuilder();
  Source4dTablesBuilder(const Source4dTablesBuilder&) = delete;
  Source4dTablesBuilder& operator=(const Source4dTablesBuilder&) = delete;

  bool done() const;
  double progress() const;  // steps done / steps in all: 0 .. 1, rising
  // What the next Step runs, as a key under which steps cost about the same GPU time: its pass
  // without the order's number, and "#whole" for a pass run in one step ("" when done). The
  // viewer budgets its frames by it (apps/viewer/skies.cc, StepBudget).
  std::string next_step_kind() const;
  void Step(PassTimings* timings = nullptr);
  Source4dTablesGl Take();  // once done()

 private:
  struct State;
  std::unique_ptr<State> state_;
};

// The quadrature matrices (cpu::ComputeSource4dQuadrature) computed by the builder's GPU pass and
// downloaded (the builder uses that pass on a hardware GPU; on a software GL the CPU's): for tests.
cpu::Source4dQuadrature ComputeSource4dQuadratureGl(const Context& context,
                                                    const shared::AtmosphereParameters& km_atmosphere,
                                                    const cpu::Source4dSettings& settings);

// Fills every batch of `model` with tables computed on GL (ComputeSource4dTablesGl) and
// downloaded (Source4dModel::SetComputedTables), so that its SkyView answers from them on the CPU.
void PrecomputeSource4dGl(const Context& context, Source4dModel& model, PassTimings* timings = nullptr);

// The sky-view tables of one batch for one observer and sun (RunSource4dSkyViewPass): per texel
// of sky.glsl's mapping the march of GetSource4dRadiance, without and with the lit ground.
struct Source4dSkyViewGl {
  GpuTexture sky;
  GpuTexture sky_and_ground;
  double horizon_nadir_angle = 0.0;  // shared::GetHorizonNadirAngle of the observer
};

// Whether `settings` read a sky-view table for an observer at `r_km` (sky_view auto or on, inside
// the atmosphere): on the GPU every frame pass does then (auto and on alike).
bool Source4dSkyViewServes(const Source4dModelSettings& settings, const shared::AtmosphereParameters& km_atmosphere,
                           double r_km);

// Fills `out` (made or remade at `size`, even x even) for an observer at `r_km` and the unit
// `sun_direction`, with `samples` steps per texel: the march of columns 0 .. width / 2, mirrored.
void RunSource4dSkyViewPass(const Context& context, const shared::AtmosphereParameters& km_atmosphere,
                            const Source4dTablesGl& tables, int samples, glm::ivec2 size, double r_km,
                            const glm::dvec3& sun_direction, Source4dSkyViewGl& out);

// Per pixel of `out` (rgba32f, the camera's size): the camera ray (GetCameraRayDirection),
// GetSource4dRadiance with `samples` steps for an observer at `r_km` (km from the planet's centre)
// and the unit `sun_direction`, plus its ground term where `ground` and the per-pixel sun disc
// (GetSunDiscRadiance) where `sun_disc`, times `solar_irradiance`; alpha 0 outside a fisheye's
// circle. `km_atmosphere` = ToSharedParameters(parameters, batch, 1000). With `sky_view` (made by
// RunSource4dSkyViewPass for the same observer and sun) each pixel reads it instead of marching.
void RunSource4dFramePass(const Context& context, const shared::AtmosphereParameters& km_atmosphere,
                          const Source4dTablesGl& tables, int samples, const shared::CameraParameters& camera,
                          double r_km, const glm::dvec3& sun_direction, bool ground, bool sun_disc,
                          const shared::vec3& solar_irradiance, const GpuTexture& out,
                          const Source4dSkyViewGl* sky_view = nullptr);

// One frame of a precomputed `model` (its CPU tables uploaded batch by batch, then the frame
// pass): what atmo::Render gives for the model, one channel per wavelength, the sun disc added on
// the host integrated over the pixels (AddSunDiscOnHost, gl/hillaire_gl.h); alpha for a fisheye.
// The frame pass is timed as frame_WxH (GPU time, summed over the batches), the upload as
// source4d_gl_upload. Throws atmo::Error (one line) for what atmo::Render rejects.
Image RenderSource4dGl(const Context& context, const Source4dModel& model, const RenderSettings& render,
                       PassTimings* timings = nullptr);

// The same with every batch's tables built on the GPU (ComputeSource4dTablesGl) and never read
// back; throws atmo::Error for parameters or settings the CPU model rejects.
Image RenderSource4dGl(const Context& context, const AtmosphereParameters& parameters,
                       const Source4dModelSettings& settings, const RenderSettings& render,
                       PassTimings* timings = nullptr);

}  // namespace atmo::gl
