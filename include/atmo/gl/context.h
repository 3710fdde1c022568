// An OpenGL 4.5 core context for the GL backend (atmo::gl): headless, or in a window.
//
// To use it: create one `atmo::gl::Context` and pass it to the backend's entry points
// (atmo/gl/hillaire_gl.h, atmo/gl/elek_gl.h) on the thread that created it.
//
// Headless, `gl::Context context;`: EGL without a window or an X server. A hardware EGL device
// (EGL_EXT_platform_device, e.g. the NVIDIA driver) is preferred; otherwise the surfaceless
// platform (EGL_MESA_platform_surfaceless), which on a machine without a GPU is Mesa llvmpipe.
// LIBGL_ALWAYS_SOFTWARE=1 skips the hardware devices (reference runs on llvmpipe).
// Windowed, `gl::Context context(WindowOptions{1280, 720, "atmo"});`: a GLFW window (GLX on
// X11) whose context runs the same passes, for the viewer; it needs a display (DISPLAY; Xvfb
// will do) and a build with GLFW.
//
// Either throws atmo::Error, one line, when no context can be made. Issue GL calls on the same
// thread; the context is current from construction until destruction (MakeCurrent() after
// another context was). Not copyable or movable: GL objects belong to it. Not thread-safe: one
// thread uses a context at a time.
#pragma once

#include <initializer_list>
#include <memory>
#include <span>
#include <string>
#include <string_view>
#include <unordered_map>

namespace atmo::gl {

class ComputeProgram;
class TimerQueries;

// Whether a GL_RENDERER string names one of Mesa's software rasterisers: llvmpipe, softpipe,
// SWR (OpenSWR) or swrast ("Software Rasterizer"), compared without case. On those the GL passes
// run on the CPU's cores (llvmpipe: its own threads), so work that the CPU backend does faster
// is better done there.
bool IsSoftwareRenderer(std::string_view renderer);

struct WindowOptions {
  int width = 1280;   // pixels, [1, 16384]
  int height = 720;   // pixels, [1, 16384]
  std::string title = "atmo";
  bool visible = true;
};

class Context {
 public:
  Context();                                       // headless (EGL)
  explicit Context(const WindowOptions& options);  // in a GLFW window
  ~Context();
  Context(const Context&) = delete;
  Context& operator=(const Context&) = delete;

  // Makes the context current on the calling thread again (after another context was).
  void MakeCurrent() const;

  // The GLFW window (GLFWwindow*) of a windowed context, null for a headless one.
  void* window() const { return window_; }
  // Presents the window's back buffer (nothing for a headless context).
  void SwapBuffers() const;
  // Waits until the GPU has run every command issued so far (glFinish).
  void Finish() const;

  const std::string& renderer() const { return renderer_; }  // GL_RENDERER, e.g. "llvmpipe (LLVM 15.0.6, 256 bits)"
  const std::string& version() const { return version_; }    // GL_VERSION, e.g. "4.5 (Core Profile) Mesa 22.3.6"
  // Whether renderer() is a software rasteriser (IsSoftwareRenderer): the "GPU" is the CPU.
  bool software_renderer() const { return IsSoftwareRenderer(renderer_); }
  // Whether the passes that split a texel's work over a work group (hillaire's tables: a ray's
  // march in segments, a texel's rays over lanes) take that form, or one texel per invocation.
  // Defaults to !software_renderer(): on llvmpipe the work groups' barriers cost more than their
  // lanes win. The tests switch it on to check the GPU's form on llvmpipe.
  bool work_group_forms() const { return work_group_forms_; }
  void set_work_group_forms(bool on) { work_group_forms_ = on; }

  // For the backend's passes (src/atmo/gl/program.h, private; callers outside atmo do not need it).
  // The compute program of the shared files (in shared.h's order) and `main_source`
  // (BuildComputeShaderSource), compiled and linked on first use and kept until the context
  // ends, so that passes run again (bench repeats, a viewer's frames) do not recompile. `name`
  // names the pass in compiler errors (atmo::Error). `compile_ms`, when given, receives the time
  // this call spent compiling (0 for a cached program).
  const ComputeProgram& Program(std::span<const std::string_view> shared_files, std::string_view main_source,
                                std::string_view name, double* compile_ms = nullptr) const;
  const ComputeProgram& Program(std::initializer_list<std::string_view> shared_files, std::string_view main_source,
                                std::string_view name, double* compile_ms = nullptr) const {
    return Program(std::span<const std::string_view>(shared_files.begin(), shared_files.size()), main_source, name,
                   compile_ms);
  }

 private:
  void* display_ = nullptr;  // EGLDisplay (kept opaque so that this header does not pull in EGL)
  void* context_ = nullptr;  // EGLContext
  void* window_ = nullptr;   // GLFWwindow* (windowed), else null

  void FinishConstruction();  // driver strings, timer queries (once current)
  void EndTimerQueries();     // reads the GPU times still unread (while current)
  std::string renderer_;
  std::string version_;
  bool work_group_forms_ = false;
  // By the shared files' names and the main source.
  mutable std::unordered_map<std::string, std::unique_ptr<ComputeProgram>> programs_;
  // The GPU timer queries of the passes run in this context (src/atmo/gl/timer_queries.h).
  std::shared_ptr<TimerQueries> timer_queries_;
};

}  // namespace atmo::gl
