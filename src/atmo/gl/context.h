// A headless OpenGL 4.5 core context (private to the GL backend).
//
// EGL surfaceless (EGL_MESA_platform_surfaceless): no window, no X server, no environment
// variables. On a machine without a GPU it runs on Mesa llvmpipe; on one with a GPU, Mesa picks its
// render node (set LIBGL_ALWAYS_SOFTWARE=1 to force llvmpipe for reference runs).
//
// To use it: `gl::Context context;` (throws atmo::Error, one line, when no context can be made),
// then issue GL calls on the same thread; the context is current from construction until
// destruction. Not copyable or movable: GL objects belong to it. Not thread-safe: one thread
// uses a context at a time.
#pragma once

#include <initializer_list>
#include <map>
#include <memory>
#include <string>
#include <string_view>

namespace atmo::gl {

class ComputeProgram;

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

  // The compute program of the shared files (in shared.h's order) and `main_source`
  // (BuildComputeShaderSource), compiled and linked on first use and kept until the context
  // ends, so that passes run again (bench repeats, a viewer's frames) do not recompile. `name`
  // names the pass in compiler errors (atmo::Error). `compile_ms`, when given, receives the time
  // this call spent compiling (0 for a cached program).
  const ComputeProgram& Program(std::initializer_list<std::string_view> shared_files, std::string_view main_source,
                                std::string_view name, double* compile_ms = nullptr) const;

 private:
  void* display_ = nullptr;  // EGLDisplay (kept opaque so that this header does not pull in EGL)
  void* context_ = nullptr;  // EGLContext
  std::string renderer_;
  std::string version_;
  mutable std::map<std::string, std::unique_ptr<ComputeProgram>> programs_;  // by full source
};

}  // namespace atmo::gl
