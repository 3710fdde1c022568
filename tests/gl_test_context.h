// What the GL tests share: one headless context per test program, the skip rule, and the
// sampler slack of a hardware GPU.
#pragma once

#include <algorithm>
#include <cmath>
#include <memory>
#include <string>

#include <gtest/gtest.h>

#include "atmo/error.h"
#include "atmo/image.h"
#include "gl/context.h"

namespace atmo::gl::testing {

// One context for the whole program (creating one costs ~10 ms on llvmpipe); null when none can
// be made, with the reason kept for the skip message.
struct SharedContext {
  std::unique_ptr<Context> context;
  std::string error;
};

inline SharedContext& GetSharedContext() {
  static SharedContext shared = [] {
    SharedContext s;
    try {
      s.context = std::make_unique<Context>();
    } catch (const Error& e) {
      s.error = e.what();
    }
    return s;
  }();
  return shared;
}

// Switches the shared context's work-group forms (Context::work_group_forms: hillaire's passes
// split over a GPU's work groups, or a texel per invocation) for a scope, so that a test checks
// both on any context; restores them at the end.
class ScopedWorkGroupForms {
 public:
  explicit ScopedWorkGroupForms(bool on)
      : context_(*GetSharedContext().context), saved_(context_.work_group_forms()) {
    context_.set_work_group_forms(on);
  }
  ~ScopedWorkGroupForms() { context_.set_work_group_forms(saved_); }
  ScopedWorkGroupForms(const ScopedWorkGroupForms&) = delete;
  ScopedWorkGroupForms& operator=(const ScopedWorkGroupForms&) = delete;

 private:
  Context& context_;
  bool saved_;
};

// The bounds of the GL tests are measured on llvmpipe, whose sampler blends texels with float
// weights. A hardware sampler blends with fixed-point weights (8 bits of fraction on NVIDIA and
// AMD): up to 1/512 of the difference of neighbouring texels per lookup, which the passes that
// sample tables inherit; a GPU's exp, log and sqrt are also a few ulp coarser than llvmpipe's.
// On a GPU the bounds of such comparisons are loosened by this factor, which held on an NVIDIA
// H200 (driver 580.159.04, 2026-12-04) for every comparison that uses it; those it did not hold
// for give their own GPU bound (GlBound).
inline double SamplerSlack(const Context& context) {
  return context.software_renderer() ? 1.0 : 20.0;
}

// A bound measured twice: `software` on llvmpipe (float sampler weights), `gpu` on the NVIDIA
// H200 above (twice its measured value), where 20 times the llvmpipe bound was not enough.
inline double GlBound(const Context& context, double software, double gpu) {
  return context.software_renderer() ? software : gpu;
}

// The mean relative difference of two images over values above 1e-4 of the largest.
inline double MeanRelative(const Image& a, const Image& b) {
  EXPECT_EQ(a.pixels.size(), b.pixels.size());
  const float peak = *std::max_element(b.pixels.begin(), b.pixels.end());
  double sum = 0.0;
  std::size_t count = 0;
  for (std::size_t i = 0; i < std::min(a.pixels.size(), b.pixels.size()); ++i) {
    if (b.pixels[i] > 1e-4f * peak) {
      sum += std::abs(double(a.pixels[i]) - b.pixels[i]) / b.pixels[i];
      ++count;
    }
  }
  return count > 0 ? sum / count : 0.0;
}

}  // namespace atmo::gl::testing

// Skips the test only when no context can be made (CI makes one: Mesa llvmpipe through EGL);
// otherwise declares `const Context& context`.
#define ATMO_REQUIRE_GL_CONTEXT(context)                                         \
  if (::atmo::gl::testing::GetSharedContext().context == nullptr) {              \
    GTEST_SKIP() << ::atmo::gl::testing::GetSharedContext().error;               \
  }                                                                              \
  const ::atmo::gl::Context& context = *::atmo::gl::testing::GetSharedContext().context
