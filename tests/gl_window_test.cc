// A windowed context (GLFW, for the viewer) runs the same GL passes as a headless one.
//
// Label `gl`. Without a display (DISPLAY unset) these tests skip; ctest also runs them under
// Xvfb (the test gl_window_under_xvfb, where xvfb-run is installed, as in CI), with
// ATMO_REQUIRE_WINDOW=1 so that a missing window fails there instead of skipping.
#include <cmath>
#include <cstdlib>
#include <string>

#include <epoxy/gl.h>
#include <gtest/gtest.h>

#include "atmo/error.h"
#include "atmo/parameters.h"
#include "gl/context.h"
#include "gl/hillaire_gl.h"
#include "gl/resources.h"
#include "physics/shared_parameters.h"

namespace atmo::gl {
namespace {

bool WindowRequired() {
  const char* required = std::getenv("ATMO_REQUIRE_WINDOW");
  return required != nullptr && std::string(required) == "1";
}

#define ATMO_REQUIRE_DISPLAY()                                                   \
  if (std::getenv("DISPLAY") == nullptr && !WindowRequired()) {                  \
    GTEST_SKIP() << "no display (DISPLAY is unset); ctest runs this under Xvfb"; \
  }

TEST(GlWindow, RunsTheSamePassesAsHeadless) {
  ATMO_REQUIRE_DISPLAY();
  const shared::AtmosphereParameters km = ToSharedParameters(Preset("earth"), 0, 1000.0);
  // The headless reference first, its context ended before the window's begins: libglvnd does
  // not make an EGL context current on a thread whose GLX context is current.
  shared::Texture2D reference;
  {
    const Context headless;
    const GpuTexture from_headless = GpuTexture::Make2D({64, 16});
    RunTransmittancePass(headless, km, 40, from_headless);
    reference = from_headless.Download2D();
  }
  std::unique_ptr<Context> window;
  try {
    window = std::make_unique<Context>(WindowOptions{64, 32, "atmo test", /*visible=*/false});
  } catch (const Error& e) {
    if (WindowRequired()) FAIL() << e.what();
    GTEST_SKIP() << e.what();
  }
  ASSERT_NE(window->window(), nullptr);
  std::printf("window context: %s, %s\n", window->renderer().c_str(), window->version().c_str());
  const GpuTexture from_window = GpuTexture::Make2D({64, 16});
  RunTransmittancePass(*window, km, 40, from_window);
  const shared::Texture2D windowed = from_window.Download2D();
  // The window's default framebuffer can be cleared and presented.
  glClearColor(0.25f, 0.5f, 0.75f, 1.0f);
  glClear(GL_COLOR_BUFFER_BIT);
  window->SwapBuffers();
  EXPECT_EQ(glGetError(), static_cast<GLenum>(GL_NO_ERROR));
  double max_abs = 0.0;
  for (std::size_t i = 0; i < reference.texels.size(); ++i) {
    for (int c = 0; c < 3; ++c) max_abs = std::max(max_abs, double(std::abs(windowed.texels[i][c] - reference.texels[i][c])));
  }
  // Tolerance: the same shader on the same driver; a different driver behind the window (GLX on a
  // GPU vs EGL on llvmpipe) would differ in float rounding only (the transmittance test's 3e-5).
  EXPECT_LT(max_abs, 3e-5);
  std::printf("transmittance 64x16, window vs headless: max abs %.3g\n", max_abs);
}

TEST(GlWindow, RejectsAnAbsurdSize) {
  EXPECT_THROW(Context(WindowOptions{0, 32, "atmo test", false}), Error);
  EXPECT_THROW(Context(WindowOptions{64, 100000, "atmo test", false}), Error);
}

}  // namespace
}  // namespace atmo::gl
