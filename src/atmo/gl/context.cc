// The EGL sequence for headless OpenGL compute on Mesa's surfaceless platform (docs/architecture.md,
// "Context"), with its traps:
//  - platform displays come from eglGetPlatformDisplayEXT resolved through eglGetProcAddress
//    (epoxy cannot resolve the EGL 1.5 core eglGetPlatformDisplay before a display exists);
//  - eglChooseConfig defaults EGL_SURFACE_TYPE to EGL_WINDOW_BIT, and the surfaceless configs are
//    pbuffer-only, so the config asks for EGL_PBUFFER_BIT (else: 0 configs and no error);
//  - EGL_KHR_surfaceless_context lets the context be current with EGL_NO_SURFACE.
// A hardware device (EGL_EXT_platform_device, as the NVIDIA driver offers) is tried first: on a
// machine with a GPU and Mesa installed, the surfaceless platform alone could land on llvmpipe.
#include "gl/context.h"

#include <cctype>
#include <chrono>
#include <cstdio>
#include <cstdlib>
#include <map>
#include <mutex>
#include <string>
#include <string_view>
#include <vector>

#include <epoxy/egl.h>
#include <epoxy/gl.h>
#ifdef ATMO_HAVE_GLFW
#include <GLFW/glfw3.h>
#endif

#include "atmo/error.h"
#include "gl/program.h"
#include "gl/shader_sources.h"
#include "gl/timer_queries.h"

namespace atmo::gl {
namespace {

// A platform display is one per process (per device) and eglTerminate ends every context on it,
// so each is terminated only when no Context uses it.
std::mutex g_display_mutex;
std::map<EGLDisplay, int> g_live_contexts;

void TerminateIfUnused(EGLDisplay display) {
  if (display != EGL_NO_DISPLAY && g_live_contexts[display] == 0) eglTerminate(display);
}

std::string EglErrorText() {
  char text[32];
  std::snprintf(text, sizeof(text), "EGL error 0x%04x", static_cast<unsigned>(eglGetError()));
  return text;
}

// A current OpenGL 4.5 core context on `display`, or EGL_NO_CONTEXT with `why` set (the display
// terminated unless in use).
EGLContext CreateContextOn(EGLDisplay display, std::string& why) {
  const auto fail = [&](const std::string& what) {
    why = what + " (" + EglErrorText() + ")";
    TerminateIfUnused(display);
    return EGL_NO_CONTEXT;
  };
  EGLint major = 0;
  EGLint minor = 0;
  if (!eglInitialize(display, &major, &minor)) {
    why = "eglInitialize failed (" + EglErrorText() + ")";
    return EGL_NO_CONTEXT;
  }
  if (!eglBindAPI(EGL_OPENGL_API)) return fail("eglBindAPI(EGL_OPENGL_API) failed");
  const EGLint config_attributes[] = {EGL_SURFACE_TYPE, EGL_PBUFFER_BIT, EGL_RENDERABLE_TYPE, EGL_OPENGL_BIT,
                                      EGL_NONE};
  EGLConfig config = nullptr;
  EGLint config_count = 0;
  if (!eglChooseConfig(display, config_attributes, &config, 1, &config_count) || config_count < 1) {
    return fail("no EGL config for desktop OpenGL");
  }
  const EGLint context_attributes[] = {EGL_CONTEXT_MAJOR_VERSION, 4,
                                       EGL_CONTEXT_MINOR_VERSION, 5,
                                       EGL_CONTEXT_OPENGL_PROFILE_MASK, EGL_CONTEXT_OPENGL_CORE_PROFILE_BIT,
                                       EGL_NONE};
  EGLContext context = eglCreateContext(display, config, EGL_NO_CONTEXT, context_attributes);
  if (context == EGL_NO_CONTEXT) return fail("eglCreateContext(4.5 core) failed");
  if (!eglMakeCurrent(display, EGL_NO_SURFACE, EGL_NO_SURFACE, context)) {
    eglDestroyContext(display, context);
    return fail("eglMakeCurrent without a surface failed");
  }
  return context;
}

// The displays of the hardware EGL devices (not Mesa's software device), in the driver's order.
std::vector<EGLDisplay> HardwareDeviceDisplays(PFNEGLGETPLATFORMDISPLAYEXTPROC get_platform_display) {
  const auto query_devices = reinterpret_cast<PFNEGLQUERYDEVICESEXTPROC>(eglGetProcAddress("eglQueryDevicesEXT"));
  const auto query_device_string =
      reinterpret_cast<PFNEGLQUERYDEVICESTRINGEXTPROC>(eglGetProcAddress("eglQueryDeviceStringEXT"));
  std::vector<EGLDisplay> displays;
  if (query_devices == nullptr || query_device_string == nullptr) return displays;
  EGLDeviceEXT devices[16];
  EGLint count = 0;
  if (!query_devices(16, devices, &count)) return displays;
  for (EGLint i = 0; i < count; ++i) {
    const char* extensions = query_device_string(devices[i], EGL_EXTENSIONS);
    if (extensions != nullptr && std::string_view(extensions).find("EGL_MESA_device_software") != std::string_view::npos) {
      continue;
    }
    EGLDisplay display = get_platform_display(EGL_PLATFORM_DEVICE_EXT, devices[i], nullptr);
    if (display != EGL_NO_DISPLAY) displays.push_back(display);
  }
  return displays;
}

}  // namespace

Context::Context() {
  const std::lock_guard<std::mutex> lock(g_display_mutex);
  const auto get_platform_display =
      reinterpret_cast<PFNEGLGETPLATFORMDISPLAYEXTPROC>(eglGetProcAddress("eglGetPlatformDisplayEXT"));
  if (get_platform_display == nullptr) {
    throw Error("no headless OpenGL 4.5 context: eglGetPlatformDisplayEXT is not available");
  }
  // LIBGL_ALWAYS_SOFTWARE=1 asks for llvmpipe (reference runs on a machine with a GPU).
  const char* software = std::getenv("LIBGL_ALWAYS_SOFTWARE");
  std::vector<EGLDisplay> candidates;
  if (software == nullptr || std::string_view(software) != "1") candidates = HardwareDeviceDisplays(get_platform_display);
  candidates.push_back(get_platform_display(EGL_PLATFORM_SURFACELESS_MESA, EGL_DEFAULT_DISPLAY, nullptr));
  std::string why = "no EGL surfaceless display";
  for (EGLDisplay display : candidates) {
    if (display == EGL_NO_DISPLAY) continue;
    EGLContext context = CreateContextOn(display, why);
    if (context == EGL_NO_CONTEXT) continue;
    display_ = display;
    context_ = context;
    ++g_live_contexts[display];
    break;
  }
  if (context_ == nullptr) throw Error("no headless OpenGL 4.5 context: " + why);
  FinishConstruction();
}

bool IsSoftwareRenderer(std::string_view renderer) {
  std::string lower(renderer);
  for (char& c : lower) c = static_cast<char>(std::tolower(static_cast<unsigned char>(c)));
  for (const std::string_view name : {"llvmpipe", "softpipe", "swr", "software rasterizer"}) {
    if (lower.find(name) != std::string::npos) return true;
  }
  return false;
}

void Context::FinishConstruction() {
  const auto* renderer = reinterpret_cast<const char*>(glGetString(GL_RENDERER));
  const auto* version = reinterpret_cast<const char*>(glGetString(GL_VERSION));
  renderer_ = renderer != nullptr ? renderer : "";
  version_ = version != nullptr ? version : "";
  work_group_forms_ = !software_renderer();
  timer_queries_ = std::make_shared<TimerQueries>();
  SetCurrentTimerQueries(timer_queries_.get());
}

void Context::EndTimerQueries() {
  // While the context is current: the times still unread are read, so that a PassTimings that
  // outlives the context holds them (timer_queries.h).
  timer_queries_->Drain();
  if (CurrentTimerQueries() == timer_queries_) SetCurrentTimerQueries(nullptr);
  timer_queries_.reset();
}

#ifdef ATMO_HAVE_GLFW
namespace {

// GLFW is initialised once for all windows and terminated with the last one.
int g_live_windows = 0;
std::string g_glfw_error;

void RecordGlfwError(int /*code*/, const char* description) { g_glfw_error = description != nullptr ? description : ""; }

}  // namespace
#endif

Context::Context(const WindowOptions& options) {
#ifdef ATMO_HAVE_GLFW
  const std::lock_guard<std::mutex> lock(g_display_mutex);
  if (options.width < 1 || options.height < 1 || options.width > 16384 || options.height > 16384) {
    throw Error("window size must be in [1, 16384] (got " + std::to_string(options.width) + "x" +
                std::to_string(options.height) + ")");
  }
  glfwSetErrorCallback(RecordGlfwError);
  if (g_live_windows == 0 && glfwInit() != GLFW_TRUE) {
    throw Error("no windowed OpenGL context: " + (g_glfw_error.empty() ? std::string("glfwInit failed") : g_glfw_error));
  }
  glfwDefaultWindowHints();
  glfwWindowHint(GLFW_CONTEXT_VERSION_MAJOR, 4);
  glfwWindowHint(GLFW_CONTEXT_VERSION_MINOR, 5);
  glfwWindowHint(GLFW_OPENGL_PROFILE, GLFW_OPENGL_CORE_PROFILE);
  glfwWindowHint(GLFW_OPENGL_FORWARD_COMPAT, GLFW_TRUE);
  glfwWindowHint(GLFW_VISIBLE, options.visible ? GLFW_TRUE : GLFW_FALSE);
  GLFWwindow* window = glfwCreateWindow(options.width, options.height, options.title.c_str(), nullptr, nullptr);
  if (window == nullptr) {
    const std::string message = "no windowed OpenGL 4.5 context: " +
                                (g_glfw_error.empty() ? std::string("glfwCreateWindow failed") : g_glfw_error);
    if (g_live_windows == 0) glfwTerminate();
    throw Error(message);
  }
  ++g_live_windows;
  window_ = window;
  glfwMakeContextCurrent(window);
  FinishConstruction();
#else
  (void)options;
  throw Error("no windowed OpenGL context: this build has no GLFW (apt: libglfw3-dev)");
#endif
}

Context::~Context() {
#ifdef ATMO_HAVE_GLFW
  if (window_ != nullptr) {
    glfwMakeContextCurrent(static_cast<GLFWwindow*>(window_));
    EndTimerQueries();
    programs_.clear();  // while the context is current
    const std::lock_guard<std::mutex> lock(g_display_mutex);
    glfwDestroyWindow(static_cast<GLFWwindow*>(window_));
    if (--g_live_windows == 0) glfwTerminate();
    return;
  }
#endif
  auto display = static_cast<EGLDisplay>(display_);
  eglMakeCurrent(display, EGL_NO_SURFACE, EGL_NO_SURFACE, static_cast<EGLContext>(context_));
  EndTimerQueries();
  programs_.clear();  // while the context is current
  const std::lock_guard<std::mutex> lock(g_display_mutex);
  eglMakeCurrent(display, EGL_NO_SURFACE, EGL_NO_SURFACE, EGL_NO_CONTEXT);
  eglDestroyContext(display, static_cast<EGLContext>(context_));
  --g_live_contexts[display];
  TerminateIfUnused(display);
}

void Context::MakeCurrent() const {
#ifdef ATMO_HAVE_GLFW
  if (window_ != nullptr) {
    glfwMakeContextCurrent(static_cast<GLFWwindow*>(window_));
    SetCurrentTimerQueries(timer_queries_.get());
    return;
  }
#endif
  if (!eglMakeCurrent(static_cast<EGLDisplay>(display_), EGL_NO_SURFACE, EGL_NO_SURFACE,
                      static_cast<EGLContext>(context_))) {
    throw Error("OpenGL context: eglMakeCurrent failed (" + EglErrorText() + ")");
  }
  SetCurrentTimerQueries(timer_queries_.get());
}

void Context::SwapBuffers() const {
#ifdef ATMO_HAVE_GLFW
  if (window_ != nullptr) glfwSwapBuffers(static_cast<GLFWwindow*>(window_));
#endif
}

void Context::Finish() const { glFinish(); }

const ComputeProgram& Context::Program(std::span<const std::string_view> shared_files,
                                       std::string_view main_source, std::string_view name,
                                       double* compile_ms) const {
  const auto start = std::chrono::steady_clock::now();
  // The key names the files and holds the main source (~1 kB): the full source (~50 kB) is
  // assembled only to compile.
  std::string key;
  for (std::string_view file : shared_files) (key += file) += '\n';
  (key += '\0') += main_source;
  auto found = programs_.find(key);
  if (found == programs_.end()) {
    auto program = std::make_unique<ComputeProgram>(BuildComputeShaderSource(shared_files, main_source), name,
                                                    DescribeSourceStrings(shared_files));
    found = programs_.emplace(std::move(key), std::move(program)).first;
  }
  if (compile_ms != nullptr) {
    *compile_ms = std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - start).count();
  }
  return *found->second;
}

}  // namespace atmo::gl
