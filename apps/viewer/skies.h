// The models atmo-viewer shows (docs/viewer.md), behind one interface: what a frame needs of a
// model on the GL backend.
//
//   hillaire   gl::HillaireGl: every table in the frame that asks for it.
//   elek       gl::ElekTablesBuilder: the tables a few steps per frame (Build's time budget), so
//              that the window keeps drawing (the last finished sky) while they are computed.
//   simple     gl::RunSimpleFramePass: no tables, the closed form per pixel.
//   source4d   gl::Source4dTablesBuilder: the tables a few steps per frame, as elek's; or, with
//              request.source4d_cpu_tables (--source4d-tables cpu), cpu::ComputeSource4dTables
//              on a worker thread, uploaded when done; the frame pass gl::RunSource4dFramePass.
//   reference  the CPU path tracer's progressive render (RenderProgressive) on a background
//              thread at a fraction of the window's size, each finished pass uploaded; restarted
//              when the view, the camera, the terms, the night sky or the moon change. The night
//              sky and the moon are traced in it (DrawsNight), not added by the viewer.
//
// To use it (the window's gl::Context current on this thread):
//   std::unique_ptr<Sky> sky = MakeSky(context, request);   // throws atmo::Error for bad parameters
//   while (!sky->Build(25.0, &timings)) { draw the previous sky }
//   sky->SetView(altitude_m, sun_elevation_deg, sun_azimuth_deg, ground, &timings);
//   sky->RenderFrame(camera, terms, &timings);             // into frame_texture(b), b < batch_count()
// Everything is called on the context's thread; only reference and source4d's CPU tables run
// work of their own elsewhere. A sky destroyed while its CPU tables build does not wait for them
// (the build stops after its current pass); JoinSource4dCpuBuilds() waits for those at exit.
#pragma once

#include <cstddef>
#include <glm/glm.hpp>
#include <memory>
#include <string>
#include <vector>

#include "atmo/hillaire_tables.h"
#include "atmo/image.h"
#include "atmo/model.h"
#include "atmo/moon.h"
#include "atmo/night_sky.h"
#include "atmo/parameters.h"
#include "atmo/render.h"
#include "atmo/timing.h"
#include "gl/context.h"
#include "gl/resources.h"
#include "models/elek_model.h"
#include "models/hillaire_model.h"
#include "models/source4d_model.h"

namespace atmo::gl {
class HillaireGl;
}  // namespace atmo::gl

namespace atmo::viewer {

// The model names of the viewer, in the panel's order.
const std::vector<std::string>& ViewerModelNames();

struct SkyRequest {
  std::string model;                // one of ViewerModelNames()
  AtmosphereParameters parameters;  // the model's (solar_irradiance 1 in physical units)
  HillaireSettings hillaire;        // model hillaire
  ElekSettings elek;                // model elek
  Source4dModelSettings source4d;   // model source4d
  bool source4d_cpu_tables = false; // source4d: the tables from the CPU on a worker thread, not GL passes
  ModelOptions reference_options;   // model reference (CreateModel's options; seed included)
  std::uint64_t reference_spp = 0;  // reference: paths per pixel to stop at (0: the model's samples)
  int reference_divisor = 4;        // reference: the frame is the window's size / this (at least 1 pixel)
};

class Sky {
 public:
  virtual ~Sky() = default;
  virtual std::size_t batch_count() const = 0;
  // The table work of this frame, for about `budget_ms` (at least one step; GPU time on a GPU,
  // the wall clock on a software GL: StepBudget in skies.cc); true once every table is built and
  // the sky can be drawn.
  virtual bool Build(double budget_ms, PassTimings* timings) = 0;
  virtual double progress() const { return 1.0; }  // of Build, 0 .. 1
  // Whether Build's work runs on a thread of its own (source4d's CPU tables): the frames meanwhile
  // had better leave the cores to it.
  virtual bool BuildsOnItsOwnThread() const { return false; }
  // Whether RenderFrame with the same camera, terms and view draws the same frame (not reference,
  // whose frames are the passes of its background render).
  virtual bool SameInputsSameFrame() const { return true; }
  // A line on what Build does (source4d: where its tables are built, the CPU's passes done), or empty.
  virtual std::string BuildStatus() const { return ""; }
  // Every table again, at once (--recompute-every-frame).
  virtual void Recompute(PassTimings* timings) = 0;
  // The observer (metres) and the sun (degrees, as RenderSettings); `ground`: the lit ground is wanted.
  virtual void SetView(double altitude_m, double sun_elevation_deg, double sun_azimuth_deg, bool ground,
                       PassTimings* timings) = 0;
  // The frame of `camera` (the window's size) into the frame textures.
  virtual void RenderFrame(const Camera& camera, const RadianceTerms& terms, PassTimings* timings) = 0;
  // Batch b's frame (rgba32f; the window's size, or smaller for reference: the display scales).
  virtual const gl::GpuTexture& frame_texture(std::size_t batch) const = 0;
  // Whether a frame is there to read (reference: after its first pass).
  virtual bool HasFrame() const { return true; }
  // The last frame read back, one channel per wavelength (auto-exposure meters it).
  virtual Image ReadFrame() const = 0;
  // The frame of `render` as `atmo render` computes it for this model (the sun disc integrated
  // over the pixels on the host); a Monte Carlo model also fills `standard_error` and may return
  // a smaller image (its own size). `samples_per_pixel`: its paths per pixel, else 0.
  virtual Image Screenshot(const RenderSettings& render, Image* standard_error, std::uint64_t* samples_per_pixel) = 0;
  // A line for the panel (reference: its paths per pixel and standard error), or empty.
  virtual std::string Status() const { return ""; }
  // Whether the shown estimate is final (reference: reference_spp reached); true for the others.
  virtual bool Converged() const { return true; }
  // Whether the sky draws the night sky and the moon into its own frames (reference: its
  // progressive render traces them as `atmo render --model reference` does). The viewer adds them
  // to the other models' frames on the GPU.
  virtual bool DrawsNight() const { return false; }
  // For a sky that DrawsNight: the night sky (active, made for the view of SetView) and the moon to
  // draw from the next RenderFrame on, null for none (also when made for other channels than this
  // sky's). Shared, so that a render on a thread of its own keeps them alive; a new pointer
  // restarts such a render.
  virtual void SetNight(std::shared_ptr<const NightSky> /*night*/, std::shared_ptr<const Moon> /*moon*/) {}
  // Model hillaire's GL sky (the viewer's fused frame-and-display pass runs its frame code), else null.
  virtual const gl::HillaireGl* hillaire_gl() const { return nullptr; }
};

std::unique_ptr<Sky> MakeSky(const gl::Context& context, const SkyRequest& request);

// Waits for the CPU table builds of source4d skies destroyed before their build finished (each
// cancelled: it stops after the pass it is in). Call at exit, once no sky is left.
void JoinSource4dCpuBuilds();

// The median over pixels and channels of standard error / radiance (pixels of radiance 0 left
// out): the panel's measure of a progressive estimate's noise.
double MedianRelativeStandardError(const Image& radiance, const Image& standard_error);

}  // namespace atmo::viewer
