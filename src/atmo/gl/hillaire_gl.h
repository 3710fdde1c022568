// Model hillaire on the GL backend: configuration gl_f32_rgb (docs/architecture.md,
// "Configurations"), private to the backend (the public entry points, with the model options by
// name, are in include/atmo/gl/hillaire_gl.h).
//
// Every table and every per-pixel or per-direction evaluation is a GL compute pass whose main()
// calls the shared per-texel kernels of src/atmo/shared in float, with the atmosphere in km
// (ToSharedParameters(p, batch, 1000)): transmittance_lut, multiple_scattering_lut,
// ground_irradiance_lut, sky_view_lut, ground_view_lut, frame_WxH, sample_N. The tables stay on the
// GPU between passes (resources.h) and are read back only on request; programs are compiled once
// per context (Context::Program), so a pass run again costs only its dispatch.
//
// Any number of channels, as on the CPU (HillaireModel): the passes compute three channels (an
// rgba32f texel), so the channels go in batches of three (ChannelBatchCount; a last batch with
// fewer repeats its last channel) and every batch has its own set of GPU tables, sky-view tables
// and frame. Each pass runs once per batch, under the same name, so `timings` sums the batches;
// the read-backs (ReadFrame, Sample, ComputeAerialPerspective) assemble one value per channel.
// Three channels are one batch: the passes and their cost are those of an RGB atmosphere.
//
// To use it (a gl::Context alive on this thread):
//   gl::HillaireGl sky(context, Preset("earth"), HillaireSettings{});
//   sky.Precompute(&timings);                          // the view-independent tables
//   sky.SetView(altitude_m, sun_direction, /*ground=*/true, &timings);
//   sky.RenderFrame(ToSharedCamera(camera), terms, &timings);
//   Image image = sky.ReadFrame();
// or sky.Sample(directions, ...) for the radiance and transmittance of single directions (the
// `atmo sample` contract). timings (may be null) receives each pass's GPU time (summed over the
// batches).
//
// As on the CPU (HillaireModel), an observer inside the atmosphere looks the sky up in the
// sky-view table; above the atmosphere, or with sky_view=off, every pixel or direction is ray
// marched (IntegrateScatteredRadiance, ray_march_samples steps) and the lit ground is evaluated per
// pixel. Tables and results are interchangeable with the CPU's (shared::Texture2D layout; the
// values do not depend on the length unit).
#pragma once

#include <cstddef>
#include <span>
#include <string>
#include <string_view>
#include <vector>

#include <glm/glm.hpp>

#include "atmo/aerial_perspective.h"
#include "atmo/gl/hillaire_gl.h"  // the public entry points (options by name)
#include "atmo/hillaire_tables.h"
#include "atmo/image.h"
#include "atmo/model.h"
#include "atmo/parameters.h"
#include "atmo/render.h"
#include "atmo/timing.h"
#include "gl/context.h"
#include "gl/resources.h"
#include "models/hillaire_model.h"
#include "shared/shared.h"

namespace atmo::gl {

// The passes, one table (or image) each; inputs are sampled with GL_LINEAR and clamp to edge
// (repeat in u for the sky view), the rules of shared::Texture2D. `out` decides the size.

// texel (x, y) = ComputeTransmittanceToTopAtmosphereBoundaryTexel(km, size, (x + 0.5, y + 0.5), samples).
void RunTransmittancePass(const Context& context, const shared::AtmosphereParameters& km, int sample_count,
                          const GpuTexture& out);
// texel = ComputeMultiScatteringTexel(km, transmittance, size, centre, directions, samples,
// media_phase, ground_transfer); ground_transfer is unitless (shared::GetGroundTransfer, or 0).
void RunMultipleScatteringPass(const Context& context, const shared::AtmosphereParameters& km,
                               const GpuTexture& transmittance, int direction_count, int sample_count,
                               bool media_phase, const shared::vec3& ground_transfer, const GpuTexture& out);
// The table of multiple_scattering_orders = orders > 1 (shared/multiple_scattering.glsl): order 1
// (ComputeMultiScatteringFirstOrderTexel), orders 2 ... orders each from the previous one's tables
// (ComputeMultiScatteringGatherTexel over gather_direction_count directions), then
// GetMultiScatteringFromOrders into `out`.
void RunGatheredMultipleScatteringPasses(const Context& context, const shared::AtmosphereParameters& km,
                                         const GpuTexture& transmittance, int direction_count, int sample_count,
                                         bool media_phase, const shared::vec3& ground_transfer, int orders,
                                         int gather_direction_count, const GpuTexture& out);
// width x 1: texel x = ComputeGroundIrradianceTexel(km, transmittance, multiple_scattering, width, x + 0.5, ...).
void RunGroundIrradiancePass(const Context& context, const shared::AtmosphereParameters& km,
                             const GpuTexture& transmittance, const GpuTexture& multiple_scattering,
                             int direction_count, int sample_count, const GpuTexture& out);
// The sky view of an observer at r_km (inside the atmosphere) and a sun at zenith cosine mu_s:
// texel = ComputeSkyViewTexel(km, transmittance, multiple_scattering, size, centre, r_km, mu_s,
// samples). The height must be even (sky and ground halves); `out` should repeat in u.
void RunSkyViewPass(const Context& context, const shared::AtmosphereParameters& km, const GpuTexture& transmittance,
                    const GpuTexture& multiple_scattering, double r_km, double mu_s, int sample_count,
                    const GpuTexture& out);
// out = sky_view + ComputeGroundViewTexel(km, transmittance, ground_irradiance, size, centre, r_km,
// mu_s): the lit ground below the horizon (HillaireModel::AddGroundView on the CPU).
void RunGroundViewPass(const Context& context, const shared::AtmosphereParameters& km, const GpuTexture& transmittance,
                       const GpuTexture& ground_irradiance, const GpuTexture& sky_view, double r_km, double mu_s,
                       const GpuTexture& out);

class HillaireGl {
 public:
  // Throws atmo::Error for parameters hillaire rejects.
  HillaireGl(const Context& context, const AtmosphereParameters& parameters, const HillaireSettings& settings);

  std::size_t channel_count() const { return channel_count_; }
  std::size_t batch_count() const { return batches_.size(); }

  // transmittance_lut, multiple_scattering_lut, ground_irradiance_lut.
  void Precompute(PassTimings* timings = nullptr);
  // The observer (altitude >= 0, metres) and the sun (unit, local frame: x east, y north, z up).
  // Inside the atmosphere with the sky-view table on: sky_view_lut, and with `ground`
  // ground_view_lut (the table that frames with the ground term read). Needs Precompute().
  void SetView(double altitude_m, const glm::dvec3& sun_direction, bool ground, PassTimings* timings = nullptr);
  bool uses_sky_view() const { return uses_sky_view_; }

  // One frame through `camera` into a GPU image (frame_WxH): the sky (and the ground and the sun
  // disc as `terms` says; `ground` needs SetView(..., ground = true) with the sky-view table) per
  // unit solar irradiance times parameters.solar_irradiance, as atmo::RenderView; one frame per
  // batch.
  void RenderFrame(const shared::CameraParameters& camera, const RadianceTerms& terms,
                   PassTimings* timings = nullptr);
  // The frame pass's per-pixel work for a program of the caller's (atmo-viewer's display pass,
  // which tone-maps it in the same fragment shader instead of reading a frame back): the shared
  // files to build it from (BuildComputeShaderSource's list) and, to put in its main source,
  // the declarations and `vec4 GetFrameTexel(vec2 frag_coord)`, what RenderFrame stores at the
  // pixel centre frag_coord (row 0 at the top) of batch b once SetFrameUniforms(program, ..., b)
  // set its uniforms and bound its tables to texture units 0..3. RenderFrame itself runs this
  // code. SetFrameUniforms throws as RenderFrame does before SetView.
  static std::span<const std::string_view> FrameSharedFiles();
  std::string FrameFunctionSource() const;
  void SetFrameUniforms(const ComputeProgram& program, const shared::CameraParameters& camera,
                        const RadianceTerms& terms, std::size_t batch) const;
  // The last frame, one channel per wavelength (the batches' frames read back and interleaved),
  // with alpha (0 outside the circle) for a fisheye camera.
  Image ReadFrame() const;
  // The last frame of batch `batch` where it lies on the GPU (rgba32f, the camera's size, row 0 at
  // the top; rgb channels 3 batch .. 3 batch + 2, alpha 0 outside a fisheye's circle): what a
  // viewer draws without a read-back. Empty before RenderFrame; throws std::out_of_range for a
  // batch >= batch_count().
  const GpuTexture& frame_texture(std::size_t batch = 0) const { return batches_.at(batch).frame; }

  // Per unit direction (local frame): the scattered radiance per unit solar irradiance (no sun
  // disc, no ground light) and the transmittance to the top of the atmosphere (0 towards the
  // ground), as SkyView::Radiance and Transmittance (pass sample_N, once per batch): channel c of
  // view i at [i * channel_count() + c].
  void Sample(std::span<const glm::dvec3> views, std::vector<double>& radiance, std::vector<double>& transmittance,
              PassTimings* timings = nullptr);

  // The aerial-perspective volume of `camera` (aerial_perspective_lut; Hillaire 2020, section
  // 5.4), as atmo::ComputeAerialPerspectiveVolume on the CPU: per froxel the camera ray through
  // its centre, ray marched (ray_march_samples steps) to the slice's distance; kept on the GPU as
  // two 3D textures (radiance, transmittance) per batch pass and read back into the CPU's volume
  // type, one value per channel.
  AerialPerspectiveVolume ComputeAerialPerspective(const Camera& camera, const AerialPerspectiveSettings& settings,
                                                   PassTimings* timings = nullptr);

  // Read-backs of the tables of batch `batch` (shared::Texture2D layout: channels 3 batch ..
  // 3 batch + 2 in rgb). Throws std::out_of_range for a batch >= batch_count().
  shared::Texture2D ReadTransmittance(std::size_t batch = 0) const {
    return batches_.at(batch).transmittance.Download2D();
  }
  shared::Texture2D ReadMultipleScattering(std::size_t batch = 0) const {
    return batches_.at(batch).multiple_scattering.Download2D();
  }
  shared::Texture2D ReadGroundIrradiance(std::size_t batch = 0) const {
    return batches_.at(batch).ground_irradiance.Download2D();
  }
  shared::Texture2D ReadSkyView(std::size_t batch = 0) const { return batches_.at(batch).sky_view.Download2D(); }
  shared::Texture2D ReadSkyAndGroundView(std::size_t batch = 0) const {
    return batches_.at(batch).sky_and_ground_view.Download2D();
  }

 private:
  // Channels 3b .. 3b + 2: their atmosphere and their GPU tables and frame.
  struct Batch {
    shared::AtmosphereParameters metres;  // double, for what the host computes
    shared::AtmosphereParameters km;      // for the GPU (program.h)
    shared::vec3 solar_irradiance;
    GpuTexture transmittance;
    GpuTexture multiple_scattering;
    GpuTexture ground_irradiance;
    GpuTexture sky_view;
    GpuTexture sky_and_ground_view;
    GpuTexture frame;
  };

  void SetSkyUniforms(const ComputeProgram& program, const Batch& batch) const;

  const Context& context_;
  HillaireSettings settings_;
  std::size_t channel_count_ = 0;
  std::vector<Batch> batches_;   // batch 0's geometry (radii) serves every batch
  GpuTexture aerial_radiance_;   // one batch's volume at a time
  GpuTexture aerial_transmittance_;
  bool precomputed_ = false;
  bool view_set_ = false;
  bool uses_sky_view_ = false;
  bool has_ground_view_ = false;
  double r_km_ = 0.0;
  double mu_s_ = 1.0;
  double horizon_nadir_angle_ = 0.0;
  glm::dvec3 sun_{0.0, 0.0, 1.0};
  bool frame_has_alpha_ = false;
};

// The images' sun disc on the GL backend: the frame pass leaves it out and the host adds it after
// read-back with the CPU's pass (cpu/sun_disc.h: integrated over each pixel, the same strata as
// on the CPU), evaluating shared::GetSunDiscRadiance in double on the GPU's transmittance tables
// (read back, km units), one per batch of three channels (ChannelBatchCount of
// parameters.channel_count(), in order; `image` has one channel per wavelength). The disc needs
// up to ~10^5 radiances in the few pixels it covers, so this costs far less than a read-back; it
// keeps one disc pass for both backends. Throws atmo::Error when the table count is not the
// batch count. (RenderFrame with terms.sun_disc still draws a per-pixel disc on the GPU, for
// interactive use.)
void AddSunDiscOnHost(const AtmosphereParameters& parameters, std::span<const shared::Texture2D> transmittance_km,
                      const RenderSettings& render, Image& image);

// Renders one frame of model hillaire on the GL backend (a HillaireGl through all passes, the sun
// disc by AddSunDiscOnHost): what atmo::Render gives on the CPU, one channel per wavelength. Throws atmo::Error (one line) for what atmo::Render rejects.
Image RenderHillaireGl(const Context& context, const AtmosphereParameters& parameters,
                       const HillaireSettings& settings, const RenderSettings& render,
                       PassTimings* timings = nullptr);

// The exported tables of include/atmo/hillaire_tables.h computed on the GL backend (backend
// "gl"): Precompute, SetView with the ground (the sky-view table is computed whatever the sky_view
// option says) and ComputeAerialPerspective, each table read back. Throws atmo::Error as
// ComputeHillaireTables does.
HillaireTables ComputeHillaireTablesGl(const Context& context, const AtmosphereParameters& parameters,
                                       const HillaireSettings& settings, const HillaireExportView& view,
                                       PassTimings* timings = nullptr);

}  // namespace atmo::gl
