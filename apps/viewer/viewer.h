// atmo-viewer: models hillaire, elek, simple and reference live in a window on the GL backend
// (docs/viewer.md).
//
// Every frame runs the GL passes of the model shown (skies.h: hillaire's tables again when the
// atmosphere changed, elek's a few steps per frame, reference's CPU passes in the background; the
// frame always) into GPU textures, and a small fragment shader converts them to linear sRGB,
// exposes and tone-maps them (the curves of include/atmo/image.h) into the window; Dear ImGui
// draws the panels over it.
//
// To use it (apps/viewer/main.cc): fill ViewerOptions from the command line, then
//   return atmo::viewer::RunViewer(options);
// RunViewer throws atmo::Error (one line) for bad options, a script that does not parse, or no
// window (no DISPLAY); it returns 0 when the window is closed or the --frames ran out.
#pragma once

#include <string>

#include "commands.h"

namespace atmo::viewer {

struct ViewerOptions {
  // --model, --preset, --config, --option, --spectral (as `atmo render`), and --source4d-tables:
  // where source4d's tables are built, gpu (GL passes, a few steps per frame), cpu (the CPU
  // backend on a worker thread) or auto (cpu on a software GL, gl::IsSoftwareRenderer; else gpu).
  cli::CommonOptions common;
  cli::RenderCommand render;           // camera, observer, sun, display flags (as `atmo render`); the EXR
                                       // and PNG paths are the screenshot of the last frame (empty: none)
  int frames = 0;                      // stop after this many frames (0: when the window is closed)
  double build_budget_ms = 25.0;       // per frame, of elek's and source4d's table steps while they build
                                       // (GPU time and the CPU's issuing time on a GPU, wall clock on a software GL)
  std::string script_path;             // timed moves (script.h); empty: none
  std::string save_config;             // write the atmosphere as JSON (`atmo render --config`) at the end
  bool recompute_every_frame = false;  // every table every frame (the benchmark of docs/performance.md)
  bool hidden = false;                 // an invisible window (headless runs; Xvfb still needed)
  // No window: a headless EGL context drawing into a framebuffer of the window's size, at most two
  // frames ahead of the GPU (benchmarks and screenshots without a display; needs frames > 0).
  bool offscreen = false;
  bool no_panels = false;              // the sky alone, no ImGui panels
  // The last --frames frame as the window shows it (8-bit sRGB PNG read from the back buffer:
  // the display shader's tone mapping, and the panels unless no_panels); empty: none.
  std::string window_screenshot;
  // One line per frame: its number, its time (ms), the model shown, the model being built and
  // its progress (0..1); empty: none.
  std::string frame_log;
  int reference_divisor = 4;  // model reference renders at the window's size / this
  // Compare mode: a second model (empty: none) shown split or as the relative difference of its
  // luminance; split: the fraction of the width that shows the first model.
  std::string compare;
  std::string compare_view = "split";  // split | difference
  double split = 0.5;
  std::string false_colour;  // empty, or luminance
};

int RunViewer(const ViewerOptions& options);

}  // namespace atmo::viewer
