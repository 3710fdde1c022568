// Model elek computed on the GL backend: configuration gl_f32_rgb (docs/architecture.md,
// "Configurations"), private to the backend (the public entry points, with the model options by
// name, are in include/atmo/gl/elek_gl.h).
//
// The table of one batch of three channels is built by compute passes that call the per-texel
// kernels of src/atmo/shared/elek.glsl in float, with the atmosphere in km, and the tables stay on
// the GPU between passes (GpuTexture, resources.h): the transmittance table, order 1, the gather
// matrix, per order k >= 2 the gather table (the matrix product over view-zenith rows, or the
// phase gather of gather=phase for k = 2) and the scattering pass, and the sum. Each 3D table is
// two rgba32f textures (Rayleigh, Mie; rgb per channel). The passes mirror ElekModel's
// ComputeTables (cpu/elek_tables.h) and are timed under its pass names: elek_transmittance_lut,
// elek_single_lut, elek_gather_matrix_lut, elek_gather_K_lut, elek_scatter_K_lut, elek_sum_lut
// (plus elek_gl_compile for the programs and elek_gl_readback for PrecomputeElekGl's downloads).
// Every ElekSettings option is supported; mie=alpha|rgb only changes the lookup.
//
// To use it (a gl::Context alive on this thread):
//   ElekModel model(Preset("atmosphere-plus"), ElekSettings::FromOptions(options));  // not CreateModel
//   PassTimings timings;
//   gl::PrecomputeElekGl(context, model, &timings);  // instead of model.Precompute()
//   auto sky = model.View(0.0, sun);                 // the CPU lookups, on the GL-computed tables
// or, with the tables never leaving the GPU,
//   Image image = gl::RenderElekGl(context, Preset("atmosphere-plus"), ElekSettings{}, render, &timings);
// Tables and radiance do not depend on the length unit (I integrates sigma_s dt), so GL tables
// answer the CPU's lookups in metres.
//
// Any number of channels: as on the CPU, every batch of three channels has its own tables
// (ElekModel::batches(), ElekKmAtmosphere), and PrecomputeElekGl and RenderElekGl run the passes
// once per batch, under the same names (a PassTimings entry then sums its batches' calls).
//
// Errors (atmo::Error, one line): a model that loads its table (option table=NAME), parameters
// elek rejects, and for RenderElekGl what atmo::Render rejects.
#pragma once

#include <memory>
#include <string>
#include <vector>

#include <glm/glm.hpp>

#include "atmo/gl/elek_gl.h"  // the public entry points (options by name)
#include "atmo/image.h"
#include "atmo/parameters.h"
#include "atmo/render.h"
#include "atmo/timing.h"
#include "gl/context.h"
#include "gl/resources.h"
#include "models/elek_model.h"

namespace atmo::gl {

// One factored scattering table on the GPU: Rayleigh and Mie, rgb per channel.
struct ElekScatteringGl {
  GpuTexture rayleigh;
  GpuTexture mie;
};

// The tables of one batch on the GPU.
struct ElekTablesGl {
  GpuTexture transmittance;              // transmittance_lut, 2D
  std::vector<ElekScatteringGl> orders;  // I^(1) .. I^(K)
  ElekScatteringGl total;                // their sum
};

// The tables of one batch: `km_atmosphere` = ToSharedParameters(p, batch, 1000) with the
// settings' rayleigh_phase (ElekKmAtmosphere). `settings.table` must be empty.
ElekTablesGl ComputeElekTablesGl(const Context& context, const shared::AtmosphereParameters& km_atmosphere,
                                 const ElekSettings& settings, PassTimings* timings = nullptr);

// The same tables built a step at a time, for a program that must keep drawing while they are
// computed (atmo-viewer): every pass above, in the same order and with the same results, but a
// 3D pass in steps of `rows_per_step` work-group rows (4 texel rows each; 0: whole passes, what
// ComputeElekTablesGl does). Each Step() runs one step (GPU time under the pass's name into
// `timings`); after the last, done() and Take() gives the tables. Between steps the caller may run
// other passes on the context: every step binds what it uses. Throws as ComputeElekTablesGl.
class ElekTablesBuilder {
 public:
  ElekTablesBuilder(const Context& context, const shared::AtmosphereParameters& km_atmosphere,
                    const ElekSettings& settings, int rows_per_step, PassTimings* timings = nullptr);
  ~ElekTablesBuilder();
  ElekTablesBuilder(const ElekTablesBuilder&) = delete;
  ElekTablesBuilder& operator=(const ElekTablesBuilder&) = delete;

  bool done() const;
  double progress() const;  // steps done / steps in all: 0 .. 1, rising
  // What the next Step runs, as a key under which steps cost about the same GPU time: its pass
  // without the order's number, and "#whole" for a pass run in one step ("" when done). The
  // viewer budgets its frames by it (apps/viewer/skies.cc, StepBudget).
  std::string next_step_kind() const;
  void Step(PassTimings* timings = nullptr);
  ElekTablesGl Take();  // once done()

 private:
  struct State;
  std::unique_ptr<State> state_;
};

// The frame pass of RenderElekGl into `out` (rgba32f, the camera's size): per pixel
// GetElekRadiance of batch `km_atmosphere`'s tables for an observer at `r_km` (km from the
// planet's centre) and the unit `sun_direction`, plus the per-pixel sun disc where `sun_disc`,
// times `solar_irradiance`; alpha 0 outside a fisheye's circle.
void RunElekFramePass(const Context& context, const shared::AtmosphereParameters& km_atmosphere,
                      const ElekSettings& settings, const ElekTablesGl& tables,
                      const shared::CameraParameters& camera, double r_km, const glm::dvec3& sun_direction,
                      bool sun_disc, const shared::vec3& solar_irradiance, const GpuTexture& out);

// The km parameters of batch `batch` of `model` (its rayleigh_phase option applied).
shared::AtmosphereParameters ElekKmAtmosphere(const ElekModel& model, std::size_t batch);

// Fills every batch of `model` with tables computed on GL and downloaded (transmittance, orders,
// sum: ElekModel::SetComputedTables), so that its SkyView answers from them.
void PrecomputeElekGl(const Context& context, ElekModel& model, PassTimings* timings = nullptr);

// Per batch the tables on GL, then the frame pass: per pixel the camera ray
// (GetCameraRayDirection), GetElekRadiance (what ElekModel's SkyView answers) times the solar
// irradiance; the batches' frames make one image with one channel per wavelength, and the sun disc
// when render.terms.sun_disc is added on the host integrated over the pixels (AddSunDiscOnHost,
// gl/hillaire_gl.h); alpha (0 outside the circle) for a fisheye camera, as atmo::Render. Elek
// has no lit ground, so terms.ground adds nothing, as on the CPU. The frame pass is timed as
// frame_WxH (once per batch).
Image RenderElekGl(const Context& context, const AtmosphereParameters& parameters, const ElekSettings& settings,
                   const RenderSettings& render, PassTimings* timings = nullptr);

}  // namespace atmo::gl
