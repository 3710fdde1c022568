// The viewer's state and its script: timed moves of the camera, the sun and the atmosphere.
//
// A script is a text file, one command per line ('#' starts a comment, blank lines are skipped),
// with frame numbers counted from 0 (docs/viewer.md#scripts):
//   at FRAME KEY VALUE            sets KEY to VALUE from frame FRAME on
//   ramp FIRST LAST KEY FROM TO   moves KEY linearly from FROM (at FIRST) to TO (at LAST)
//   screenshot FRAME PATH         writes the frame FRAME shows to PATH (.exr or .png)
// KEY is one of ViewKeyNames() (the flags of `atmo render` without their dashes, plus the
// atmosphere's knobs); `camera` takes perspective, fisheye or equirect, `model` a model's name,
// `spectral` on or off, the others numbers.
//
// To use it:
//   ViewerScript script = ParseViewerScript(ReadFileBounded(path), path.string());
//   for (int frame = 0; ...; ++frame) { ApplyScript(script, frame, state); ... }
// Parsing throws atmo::Error naming the file, the line and what is wrong.
#pragma once

#include <string>
#include <string_view>
#include <vector>

#include "atmo/render.h"

namespace atmo::viewer {

// What the viewer shows; every field can be changed by a panel, the mouse, or a script.
struct ViewState {
  // Camera and observer (the meanings of `atmo render`'s flags, docs/cli.md#atmo-render).
  // The model shown: hillaire, elek, simple or reference (skies.h).
  std::string model = "hillaire";
  // The atmosphere's spectral form (atmo::MakeSpectral of the loaded one) instead of the loaded one.
  bool spectral = false;
  CameraKind camera = CameraKind::kPerspective;
  double yaw_deg = 180.0;
  double pitch_deg = 10.0;
  double fov_deg = 90.0;
  double altitude_m = 0.0;
  double sun_elevation_deg = 10.0;
  double sun_azimuth_deg = 180.0;
  bool sun_disc = true;
  bool ground = true;
  // With --date: hours after it (the sun follows the date; moving the sun by hand leaves it).
  double date_hours = 0.0;
  // Display: EV100 of the exposure, or metered from the frame (auto_exposure).
  double ev100 = 0.0;
  bool auto_exposure = true;
  // The atmosphere relative to the loaded one: density multipliers of the three media, the
  // Mie asymmetry g, the ground albedo (grey, every channel) and the planet radius (the
  // atmosphere keeps its thickness).
  double rayleigh_density = 1.0;
  double mie_density = 1.0;
  double ozone_density = 1.0;
  double mie_g = 0.8;
  double ground_albedo = 0.3;
  double ground_radius_m = 6360e3;
};

// The camera of the view at a frame size.
Camera ViewCamera(const ViewState& state, int width, int height);
// Puts the sun where pixel position (x, y) of a width x height frame looks (pixel units, (0, 0)
// the top-left corner, as the mouse reports it): the view direction of the frame pass's own
// shared::GetCameraRayDirection, as a compass azimuth in [0, 360) and an elevation. Returns false
// and leaves the sun where the camera sees nothing there (outside the fisheye's circle).
bool PutSunAtPixel(ViewState& state, int width, int height, double x, double y);

std::vector<std::string> ViewKeyNames();
// Sets the key to `value` (a number, or a camera name for `camera`); throws atmo::Error for an
// unknown key or a value that is not one.
void SetViewValue(ViewState& state, std::string_view key, std::string_view value);

struct ScriptCommand {
  enum class Kind { kAt, kRamp, kScreenshot };
  Kind kind = Kind::kAt;
  int first_frame = 0;
  int last_frame = 0;  // kRamp
  std::string key;     // kAt, kRamp
  std::string value;   // kAt: the value as written
  double from = 0.0;   // kRamp
  double to = 0.0;     // kRamp
  std::string path;    // kScreenshot
  int line = 0;        // in the file, for messages
};

struct ViewerScript {
  std::vector<ScriptCommand> commands;  // in file order
  // The last frame any command names (0 for an empty script).
  int LastFrame() const;
};

// Parses the text of a script; `name` names it in errors ("script.txt:3: ...").
ViewerScript ParseViewerScript(std::string_view text, const std::string& name);
// Applies, in file order, every command that acts at `frame`: `at` at its frame, `ramp` from its
// first to its last frame (its end value held after it is not re-applied). Returns the paths of
// the screenshots asked for at `frame`.
std::vector<std::string> ApplyScript(const ViewerScript& script, int frame, ViewState& state);

}  // namespace atmo::viewer
