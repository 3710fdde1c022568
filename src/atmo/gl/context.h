// A headless OpenGL 4.5 core context (private to the GL backend).
//
// EGL surfaceless (EGL_MESA_platform_surfaceless): no window, no X server, no environment
// variables. On a machine without a GPU it runs on Mesa llvmpipe; on one with a GPU, Mesa picks its
// render node (set LIBGL_ALWAYS_SOFTWARE=1 to force llvmpipe for reference runs).
//
// To use it: `gl::Context context;` (throws atmo::Error, one line, when no context can be made),
// then issue GL calls on the same thread; the context is current from construction until
// destruction. Not copyable or movable: GL objects belong to it.
#pragma once

#include <string>

namespace atmo::gl {

class Context {
 public:
  Context();
  ~Context();
  Context(const Context&) = delete;
  Context& operator=(const Context&) = delete;

  // Makes the context current on the calling thread again (after another context was).
  void MakeCurrent() const;

  const std::string& renderer() const { return renderer_; }  // GL_RENDERER, e.g. "llvmpipe (LLVM 15.0.6, 256 bits)"
  const std::string& version() const { return version_; }    // GL_VERSION, e.g. "4.5 (Core Profile) Mesa 22.3.6"

 private:
  void* display_ = nullptr;  // EGLDisplay (kept opaque so that this header does not pull in EGL)
  void* context_ = nullptr;  // EGLContext
  std::string renderer_;
  std::string version_;
};

}  // namespace atmo::gl
