// The night sky added to GL frames on the GPU: what atmo::AddNightSky and atmo::AddStars
// (include/atmo/render.h) do on the host after a read-back, for frames that stay on the GPU
// (atmo-viewer's). The sums are the host's, in float:
//   the glow  one compute pass per frame texture: at each pixel the view's per-angle tables (the
//             attenuated airglow and the transmittance) read as NightSky::Folded::Add reads them,
//             with the light from outside the atmosphere: the zodiacal grid
//             (NightSky::ZodiacalGrid) at the view's ecliptic latitude and elongation and the
//             integrated starlight's local grid (NightSky::starlight_grid); added in place (alpha kept);
//   the stars each star of NightSky::Folded::Stars drawn as four points, one per pixel of the
//             2 x 2 whose centres surround its direction, each carrying its bilinear share over
//             the pixel's solid angle (the shares of pixels outside the image or outside a
//             fisheye's circle go to the others, as on the host), added by blending (GL_ONE,
//             GL_ONE) into the frame texture: the star's energy is right at any resolution.
//             A compute pass places each star's points once per frame; the point pass then only
//             reads them (a vertex shader doing the projection took 58 ms for 13 000 stars on
//             llvmpipe, the two passes 3 ms).
// Frame texture b holds outputs 3b .. 3b + 2 of the fold (the batches of the GL renderers, with
// NightSky::Scaled(solar_irradiance)); its alpha is left as it is.
//
// To use it (a current gl::Context; atmo-viewer does):
//   gl::NightSkyGl night_gl(context);
//   night_gl.Set(night.Scaled(parameters.solar_irradiance));   // when the night sky changes
//   night_gl.Add(camera, frames, &timings);                     // after each frame pass
// Private to atmo (src/atmo/gl). Not thread-safe: the context's thread.
#pragma once

#include <cstddef>
#include <memory>
#include <span>
#include <vector>

#include "atmo/image.h"
#include "atmo/night_sky.h"
#include "atmo/timing.h"
#include "gl/program.h"
#include "gl/resources.h"
#include "shared/shared.h"

namespace atmo::gl {

class Context;

class NightSkyGl {
 public:
  explicit NightSkyGl(const Context& context);
  ~NightSkyGl();
  NightSkyGl(const NightSkyGl&) = delete;
  NightSkyGl& operator=(const NightSkyGl&) = delete;

  // Uploads `folded`'s tables and stars (the fold is read now: `folded` need not outlive this).
  // An inactive night sky (or one without glow) uploads nothing of what it lacks.
  void Set(const NightSky::Folded& folded);
  // Adds the glow and the stars to frames[b], batch b of the fold (rgba32f, the camera's size).
  // Throws atmo::Error for more frames than the fold has batches or a frame of another size.
  void Add(const shared::CameraParameters& camera, std::span<const GpuTexture* const> frames,
           PassTimings* timings = nullptr) const;

  // The moon (atmo-viewer): adds to frames[b] the moonlit frame moonlit[b] (the same renderer's
  // frame for a sun in the moon's direction, without its disc) times scale[b] (the moon's
  // irradiance relative to the sun's, per channel of the batch), and the disc's pixels `disc`
  // (every channel of the fold, integrated over the pixels on the host: AddMoonDiscLight) placed
  // with its pixel (0, 0) at `disc_origin` of the frames. Throws atmo::Error for sizes that differ.
  void AddMoon(std::span<const GpuTexture* const> frames, std::span<const GpuTexture* const> moonlit,
               std::span<const shared::vec3> scale, const Image& disc, shared::ivec2 disc_origin,
               PassTimings* timings = nullptr) const;

  bool glow() const { return glow_; }
  std::size_t star_count() const { return star_count_; }
  std::size_t batch_count() const { return batches_.size(); }

 private:
  struct Batch {
    unsigned airglow = 0;      // kAngleSamples vec4
    unsigned transmitted = 0;  // kAngleSamples vec4
    unsigned stars = 0;        // star_count_ vec4: the star's three outputs of this batch
  };
  void Release();

  const Context& context_;
  std::unique_ptr<ComputeProgram> star_program_;  // vertex + fragment: the star points
  std::vector<Batch> batches_;
  unsigned zodiacal_grid_ = 0;    // NightSky::ZodiacalGrid, uploaded once
  unsigned star_directions_ = 0;  // star_count_ vec4
  unsigned star_places_ = 0;      // 4 star_count_ vec4: each point's clip position and share
  unsigned vertex_array_ = 0;     // empty: the star points come from gl_VertexID
  unsigned framebuffer_ = 0;
  bool glow_ = false;
  bool zodiacal_ = false;
  double zodiacal_scale_ = 0.0;   // NightSky::zodiacal_relative
  unsigned starlight_grid_ = 0;   // NightSky::starlight_grid, or 0 without the starlight
  std::size_t star_count_ = 0;
  shared::vec3 ecliptic_pole_{1.0, 0.0, 0.0};
  shared::vec3 sun_direction_{0.0, 0.0, 1.0};
};

}  // namespace atmo::gl
