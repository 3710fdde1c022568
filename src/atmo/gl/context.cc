// The EGL sequence of docs: /work/shared/notes/build.md, "Headless OpenGL compute on llvmpipe":
//  - the platform display comes from eglGetPlatformDisplayEXT resolved through eglGetProcAddress
//    (epoxy cannot resolve the EGL 1.5 core eglGetPlatformDisplay before a display exists);
//  - eglChooseConfig defaults EGL_SURFACE_TYPE to EGL_WINDOW_BIT, and the surfaceless configs are
//    pbuffer-only, so the config asks for EGL_PBUFFER_BIT (else: 0 configs and no error);
//  - EGL_KHR_surfaceless_context lets the context be current with EGL_NO_SURFACE.
#include "gl/context.h"

#include <chrono>
#include <cstdio>
#include <mutex>
#include <string>

#include <epoxy/egl.h>
#include <epoxy/gl.h>

#include "atmo/error.h"
#include "gl/program.h"
#include "gl/shader_sources.h"

namespace atmo::gl {
namespace {

// The surfaceless display is one per process and eglTerminate ends every context on it, so it is
// terminated only when no Context uses it.
std::mutex g_display_mutex;
int g_live_contexts = 0;

void TerminateIfUnused(EGLDisplay display) {
  if (display != EGL_NO_DISPLAY && g_live_contexts == 0) eglTerminate(display);
}

std::string EglErrorText() {
  char text[32];
  std::snprintf(text, sizeof(text), "EGL error 0x%04x", static_cast<unsigned>(eglGetError()));
  return text;
}

[[noreturn]] void Fail(EGLDisplay display, const std::string& what) {
  const std::string message = "no headless OpenGL 4.5 context: " + what + " (" + EglErrorText() + ")";
  TerminateIfUnused(display);
  throw Error(message);
}

}  // namespace

Context::Context() {
  const std::lock_guard<std::mutex> lock(g_display_mutex);
  const auto get_platform_display =
      reinterpret_cast<PFNEGLGETPLATFORMDISPLAYEXTPROC>(eglGetProcAddress("eglGetPlatformDisplayEXT"));
  if (get_platform_display == nullptr) Fail(EGL_NO_DISPLAY, "eglGetPlatformDisplayEXT is not available");
  EGLDisplay display = get_platform_display(EGL_PLATFORM_SURFACELESS_MESA, EGL_DEFAULT_DISPLAY, nullptr);
  if (display == EGL_NO_DISPLAY) Fail(display, "no EGL surfaceless display");
  EGLint major = 0;
  EGLint minor = 0;
  if (!eglInitialize(display, &major, &minor)) Fail(EGL_NO_DISPLAY, "eglInitialize failed");
  if (!eglBindAPI(EGL_OPENGL_API)) Fail(display, "eglBindAPI(EGL_OPENGL_API) failed");

  const EGLint config_attributes[] = {EGL_SURFACE_TYPE, EGL_PBUFFER_BIT, EGL_RENDERABLE_TYPE, EGL_OPENGL_BIT,
                                      EGL_NONE};
  EGLConfig config = nullptr;
  EGLint config_count = 0;
  if (!eglChooseConfig(display, config_attributes, &config, 1, &config_count) || config_count < 1) {
    Fail(display, "no EGL config for desktop OpenGL");
  }
  const EGLint context_attributes[] = {EGL_CONTEXT_MAJOR_VERSION, 4,
                                       EGL_CONTEXT_MINOR_VERSION, 5,
                                       EGL_CONTEXT_OPENGL_PROFILE_MASK, EGL_CONTEXT_OPENGL_CORE_PROFILE_BIT,
                                       EGL_NONE};
  EGLContext context = eglCreateContext(display, config, EGL_NO_CONTEXT, context_attributes);
  if (context == EGL_NO_CONTEXT) Fail(display, "eglCreateContext(4.5 core) failed");
  if (!eglMakeCurrent(display, EGL_NO_SURFACE, EGL_NO_SURFACE, context)) {
    eglDestroyContext(display, context);
    Fail(display, "eglMakeCurrent without a surface failed");
  }
  display_ = display;
  context_ = context;
  ++g_live_contexts;
  const auto* renderer = reinterpret_cast<const char*>(glGetString(GL_RENDERER));
  const auto* version = reinterpret_cast<const char*>(glGetString(GL_VERSION));
  renderer_ = renderer != nullptr ? renderer : "";
  version_ = version != nullptr ? version : "";
}

Context::~Context() {
  auto display = static_cast<EGLDisplay>(display_);
  eglMakeCurrent(display, EGL_NO_SURFACE, EGL_NO_SURFACE, static_cast<EGLContext>(context_));
  programs_.clear();  // while the context is current
  const std::lock_guard<std::mutex> lock(g_display_mutex);
  eglMakeCurrent(display, EGL_NO_SURFACE, EGL_NO_SURFACE, EGL_NO_CONTEXT);
  eglDestroyContext(display, static_cast<EGLContext>(context_));
  --g_live_contexts;
  TerminateIfUnused(display);
}

void Context::MakeCurrent() const {
  if (!eglMakeCurrent(static_cast<EGLDisplay>(display_), EGL_NO_SURFACE, EGL_NO_SURFACE,
                      static_cast<EGLContext>(context_))) {
    throw Error("OpenGL context: eglMakeCurrent failed (" + EglErrorText() + ")");
  }
}

}  // namespace atmo::gl

namespace atmo::gl {

const ComputeProgram& Context::Program(std::initializer_list<std::string_view> shared_files,
                                       std::string_view main_source, std::string_view name,
                                       double* compile_ms) const {
  const auto start = std::chrono::steady_clock::now();
  std::string source = BuildComputeShaderSource(shared_files, main_source);
  auto found = programs_.find(source);
  if (found == programs_.end()) {
    auto program = std::make_unique<ComputeProgram>(source, name, DescribeSourceStrings(shared_files));
    found = programs_.emplace(std::move(source), std::move(program)).first;
  }
  if (compile_ms != nullptr) {
    *compile_ms = std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - start).count();
  }
  return *found->second;
}

}  // namespace atmo::gl
