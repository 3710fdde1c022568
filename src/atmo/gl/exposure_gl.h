// Auto-exposure metered on the GPU: the statistic of atmo::AutoExposureEv100 (include/atmo/image.h)
// computed from a frame's GPU textures, with only 8 bytes read back, asynchronously.
//
// AutoExposureEv100 takes the mean of log2 of each pixel's luminance, with the values below the
// 2nd and above the 98th percentile counted as those percentiles (a sun disc does not swing the
// exposure). Here two compute passes do the same on the GPU:
//   1. a histogram of log2 L in kBins bins of 1/32 stop over [-64, 64) stops (each work group
//      counts in shared memory, then adds its non-empty bins to the global histogram);
//   2. one work group finds the two percentiles' bins and the winsorised mean of the bins'
//      centres, and writes it with the pixel count (8 bytes).
// The 8 bytes are copied into one of a few read-back buffers behind a fence; Latest() returns
// the newest copy whose fence has signalled: no pipeline stall, the exposure a frame or two late
// (as an eye or a camera adapts anyway). Binning moves each value by at most 1/64 stop, so the
// metered EV100 is within 1/64 stop of AutoExposureEv100 of the read-back frame
// (tests/gl_exposure_test.cc measures it).
//
// To use it (atmo-viewer does):
//   gl::ExposureMeter meter;                       // a current gl::Context
//   meter.Meter(frames, weights, has_alpha);       // after the frame pass, every few frames
//   if (auto r = meter.Latest()) ev100 = MeteredEv100(r->log2_average, Metering::kAdaptive);
// Private to atmo (src/atmo/gl). Not thread-safe: the context's thread.
#pragma once

#include <array>
#include <cstdint>
#include <map>
#include <memory>
#include <optional>
#include <span>

#include <glm/glm.hpp>

#include "gl/program.h"
#include "gl/resources.h"

namespace atmo::gl {

class ExposureMeter {
 public:
  static constexpr int kBins = 4096;
  static constexpr float kLog2Min = -64.0f;  // stops; bin i covers kLog2Min + [i, i + 1) / 32
  static constexpr int kBinsPerStop = 32;
  static constexpr int kMaxBatches = 8;

  ExposureMeter();
  ~ExposureMeter();
  ExposureMeter(const ExposureMeter&) = delete;
  ExposureMeter& operator=(const ExposureMeter&) = delete;

  // Queues the metering of a frame: `frames[b]` holds batch b's three channels (rgba32f, all of
  // one size), `weights[b]` converts them to linear sRGB (colour = sum_b weights[b] * rgb_b);
  // with `has_alpha`, texels of alpha <= 0 (outside a fisheye's circle) are left out. Throws
  // atmo::Error for no frame, more than kMaxBatches, or sizes that differ.
  void Meter(std::span<const GpuTexture* const> frames, std::span<const glm::mat3> weights, bool has_alpha);

  struct Reading {
    double log2_average = 0.0;  // winsorised mean of log2 L (L: linear sRGB luminance)
    std::uint32_t pixels = 0;   // pixels with a finite L > 0 (0: no reading; AutoExposureEv100 gives 0)
    int generation = 0;         // counts Meter calls: 1 for the first
  };
  // The newest metering whose result has arrived (with `wait`: the last one queued, waiting for
  // it); nothing while none has.
  std::optional<Reading> Latest(bool wait = false);

 private:
  const ComputeProgram& HistogramProgram(int batches, bool has_alpha);

  struct Slot {
    unsigned buffer = 0;     // 8 bytes, the copy read back
    void* fence = nullptr;   // GLsync of the copy; null: free
    int generation = 0;
  };
  static constexpr int kSlots = 3;
  std::array<Slot, kSlots> slots_{};
  unsigned histogram_ = 0;  // kBins uint
  unsigned result_ = 0;     // float log2_average, uint pixels
  std::map<int, std::unique_ptr<ComputeProgram>> histogram_programs_;
  std::unique_ptr<ComputeProgram> reduce_program_;
  int generation_ = 0;
  std::optional<Reading> latest_;
};

}  // namespace atmo::gl
