// atmo-viewer: the sky of models hillaire, elek, simple, reference and source4d live in a window,
// on the GL backend (docs/viewer.md).
//
//   atmo-viewer [--preset P | --config F.json] [--option K=V] [render flags of `atmo render`:
//               --camera --width --height --fov --yaw --pitch --altitude --sun-elevation
//               --sun-azimuth --date ... --ev --exposure --tonemap ...]
//               [--frames N [--screenshot F.png|F.exr|NAME]] [--script F] [--save-config F.json]
//               [--recompute-every-frame] [--source4d-tables gpu|cpu|auto] [--hidden] [--offscreen]
//
// This file only parses the command line (the flags of `atmo render` through apps/atmo/cli_flags.h)
// and calls RunViewer. Errors: one line `atmo-viewer: error: ...` on stderr; exit 2 for a command
// line that does not parse, 1 for anything else.
#include <CLI/CLI.hpp>
#include <cstdio>
#include <exception>
#include <string>

#include "atmo/error.h"
#include "atmo/interrupt.h"
#include "cli_flags.h"
#include "viewer.h"

int main(int argc, char** argv) {
  atmo::InstallInterruptHandlers("atmo-viewer");
  CLI::App app{"atmo-viewer: the sky of hillaire, elek, simple, reference or source4d live in a window "
               "(docs/viewer.md)",
               "atmo-viewer"};
  app.set_version_flag("--version", std::string("atmo-viewer ") + ATMO_VERSION);
  atmo::viewer::ViewerOptions options;
  // The screenshot of the last --frames frame goes where `atmo render` writes (--exr, --png, -o);
  // by default nowhere.
  options.render.exr_path.clear();
  options.render.png_path.clear();
  atmo::cli::AddCommonOptions(&app, options.common);
  atmo::cli::RenderFlags flags;
  atmo::cli::AddRenderFlags(&app, options.render, flags);
  app.add_option("--frames", options.frames, "stop after N frames (default: when the window is closed)")
      ->check(atmo::cli::kInteger)
      ->check(CLI::Range(1, 100000000));
  std::string screenshot;
  app.add_option("--screenshot", screenshot,
                 "write the last frame: F.png or F.exr, or NAME for NAME.exr and NAME.png, with the metadata of "
                 "`atmo render` (needs --frames)")
      ->excludes("--exr")
      ->excludes("--png")
      ->excludes("--output");
  app.add_option("--script", options.script_path, "timed camera, sun and atmosphere moves (docs/viewer.md#scripts)");
  app.add_option("--save-config", options.save_config,
                 "write the atmosphere as JSON at the end (`atmo render --config` reads it back)");
  app.add_flag("--recompute-every-frame", options.recompute_every_frame,
               "recompute every table every frame (the benchmark of docs/performance.md)");
  app.add_flag("--no-panels", options.no_panels, "the sky alone, without the panels");
  app.add_option("--window-screenshot", options.window_screenshot,
                 "write the last frame as the window shows it, F.png (the display's tone mapping; needs --frames)");
  app.add_option("--build-budget", options.build_budget_ms,
                 "milliseconds of elek's and source4d's table steps per frame while they build: GPU time (and the "
                 "CPU's time issuing them) on a GPU, the wall clock on a software GL (default 25)")
      ->check(CLI::Range(1.0, 1000.0));
  // A common flag (AddCommonOptions, as `atmo render --backend gl`); here the CPU's build runs on a
  // worker thread while the window stays live.
  app.get_option("--source4d-tables")
      ->description("where source4d's tables are built: gpu, cpu (a worker thread) or auto (cpu on a software GL "
                    "such as llvmpipe, else gpu; default)");
  app.add_option("--frame-log", options.frame_log,
                 "write one line per frame: number, ms, model shown, model being built, its progress");
  app.add_option("--reference-divisor", options.reference_divisor,
                 "model reference renders at the window's size divided by this (default 4)")
      ->check(CLI::Range(1, 64));
  app.add_option("--compare", options.compare,
                 "compare mode: a second model (hillaire, elek, simple, reference, source4d) on the same "
                 "atmosphere and view");
  app.add_option("--compare-view", options.compare_view,
                 "split (the first model left of the split, the second right) or difference ((B - A) / A of "
                 "luminance in false colour)");
  app.add_option("--split", options.split, "compare split: the fraction of the width left of the line (default 0.5)")
      ->check(CLI::Range(0.0, 1.0));
  app.add_option("--false-colour", options.false_colour,
                 "luminance: log10 of the luminance in false colour instead of the tone-mapped image");
  app.add_flag("--hidden", options.hidden, "an invisible window (scripted runs; a display is still needed)");
  app.add_flag("--offscreen", options.offscreen,
               "no window: draw into a framebuffer on a headless context (needs --frames; no display needed)");
  try {
    app.parse(argc, argv);
  } catch (const CLI::ParseError& error) {
    if (error.get_exit_code() == 0) return app.exit(error);
    std::fprintf(stderr, "atmo-viewer: error: %s\n", error.what());
    return 2;
  }
  if (!screenshot.empty()) flags.output = screenshot;
  // The display flags set the window's exposure and curve too: no "applies to the PNG only".
  atmo::cli::FinishRenderFlags(&app, options.render, flags, /*png_only_warnings=*/false);
  try {
    return atmo::viewer::RunViewer(options);
  } catch (const std::exception& error) {
    std::string line = error.what();
    for (char& c : line) {
      if (c == '\n' || c == '\r') c = ' ';
    }
    std::fprintf(stderr, "atmo-viewer: error: %s\n", line.c_str());
  }
  return 1;
}
