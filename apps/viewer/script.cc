// The viewer's script (script.h).
#include "script.h"

#include <algorithm>
#include <cerrno>
#include <cmath>
#include <cstdlib>
#include <sstream>

#include "atmo/error.h"
#include "atmo/parameters.h"
#include "cpu/camera.h"
#include "shared/shared.h"

namespace atmo::viewer {

namespace {

// A field of ViewState that scripts reach by name, and its bounds: the command line's for the
// same quantity (apps/atmo/cli_flags.cc, docs/parameters.md), open at an end where `open` says so.
struct NumberKey {
  const char* name;
  double ViewState::*field;
  double min;
  double max;
  bool open = false;  // (min, max) instead of [min, max]
};

constexpr double kNoBound = 1e300;

constexpr NumberKey kNumberKeys[] = {
    {"yaw", &ViewState::yaw_deg, -kNoBound, kNoBound},
    {"pitch", &ViewState::pitch_deg, -90.0, 90.0},
    {"fov", &ViewState::fov_deg, 0.0, 180.0, true},
    {"altitude", &ViewState::altitude_m, -kMaxAltitude_m, kMaxAltitude_m},
    {"sun-elevation", &ViewState::sun_elevation_deg, -90.0, 90.0},
    {"sun-azimuth", &ViewState::sun_azimuth_deg, -kNoBound, kNoBound},
    {"ev", &ViewState::ev100, -32.0, 32.0},
    {"date-hours", &ViewState::date_hours, -kNoBound, kNoBound},
    {"rayleigh-density", &ViewState::rayleigh_density, 0.0, 1e3},
    {"mie-density", &ViewState::mie_density, 0.0, 1e3},
    {"ozone-density", &ViewState::ozone_density, 0.0, 1e3},
    {"mie-g", &ViewState::mie_g, -0.999, 0.999},
    {"ground-albedo", &ViewState::ground_albedo, 0.0, 1.0},
    {"ground-radius", &ViewState::ground_radius_m, 1.0, 1e10},
};

// "KEY must be in [MIN, MAX] (got VALUE)" for a value outside the key's bounds.
void CheckBounds(const NumberKey& k, double value) {
  const bool inside = k.open ? value > k.min && value < k.max : value >= k.min && value <= k.max;
  if (inside) return;
  std::ostringstream message;
  message << k.name << " must be in " << (k.open ? "(" : "[") << k.min << ", " << k.max << (k.open ? ")" : "]")
          << " (got " << value << ")";
  throw Error(message.str());
}

bool ParseNumber(std::string_view text, double& value) {
  const std::string copy(text);
  char* end = nullptr;
  errno = 0;
  value = std::strtod(copy.c_str(), &end);
  return !copy.empty() && end == copy.c_str() + copy.size() && errno == 0 && std::isfinite(value);
}

bool ParseFrame(std::string_view text, int& frame) {
  double value = 0.0;
  if (!ParseNumber(text, value) || value < 0.0 || value > 1e9 || value != std::floor(value)) return false;
  frame = static_cast<int>(value);
  return true;
}

const NumberKey* FindNumberKey(std::string_view key) {
  for (const NumberKey& k : kNumberKeys) {
    if (key == k.name) return &k;
  }
  return nullptr;
}

std::string KeyList() {
  std::string list;
  for (const std::string& name : ViewKeyNames()) list += (list.empty() ? "" : ", ") + name;
  return list;
}

}  // namespace

Camera ViewCamera(const ViewState& state, int width, int height) {
  Camera camera;
  camera.kind = state.camera;
  camera.width = width;
  camera.height = height;
  camera.fov_deg = state.fov_deg;
  camera.yaw_deg = state.yaw_deg;
  camera.pitch_deg = state.pitch_deg;
  return camera;
}

bool PutSunAtPixel(ViewState& state, int width, int height, double x, double y) {
  const shared::CameraParameters camera = ToSharedCamera(ViewCamera(state, width, height));
  shared::vec3 direction;
  if (!shared::GetCameraRayDirection(camera, shared::vec2(x, y), direction)) return false;
  constexpr double kDegrees = 180.0 / 3.14159265358979323846;
  state.sun_elevation_deg = std::asin(std::clamp(static_cast<double>(direction.z), -1.0, 1.0)) * kDegrees;
  double azimuth = std::atan2(static_cast<double>(direction.x), static_cast<double>(direction.y)) * kDegrees;
  if (azimuth < 0.0) azimuth += 360.0;
  state.sun_azimuth_deg = azimuth;
  return true;
}

std::vector<std::string> ViewKeyNames() {
  std::vector<std::string> names = {"camera", "model", "spectral"};
  for (const NumberKey& k : kNumberKeys) names.emplace_back(k.name);
  return names;
}

void SetViewValue(ViewState& state, std::string_view key, std::string_view value) {
  if (key == "camera") {
    state.camera = ParseCameraKind(std::string(value));  // throws for an unknown camera
    return;
  }
  if (key == "spectral") {
    if (value != "on" && value != "off") throw Error("spectral takes on or off, got '" + std::string(value) + "'");
    state.spectral = value == "on";
    return;
  }
  if (key == "model") {
    if (value != "hillaire" && value != "elek" && value != "simple" && value != "reference" && value != "source4d") {
      throw Error("unknown model '" + std::string(value) + "' (known: hillaire, elek, simple, reference, source4d)");
    }
    state.model = std::string(value);
    return;
  }
  const NumberKey* k = FindNumberKey(key);
  if (k == nullptr) throw Error("unknown key '" + std::string(key) + "' (known: " + KeyList() + ")");
  double number = 0.0;
  if (!ParseNumber(value, number))
    throw Error(std::string(key) + " takes a finite number, got '" + std::string(value) + "'");
  CheckBounds(*k, number);
  state.*(k->field) = number;
  if (key == "ev") state.auto_exposure = false;  // a fixed EV100, as --ev
}

int ViewerScript::LastFrame() const {
  int last = 0;
  for (const ScriptCommand& c : commands)
    last = std::max(last, c.kind == ScriptCommand::Kind::kRamp ? c.last_frame : c.first_frame);
  return last;
}

ViewerScript ParseViewerScript(std::string_view text, const std::string& name) {
  ViewerScript script;
  std::istringstream lines{std::string(text)};
  std::string line;
  int number = 0;
  while (std::getline(lines, line)) {
    ++number;
    const std::size_t hash = line.find('#');
    if (hash != std::string::npos) line.resize(hash);
    std::istringstream words(line);
    std::vector<std::string> w;
    for (std::string word; words >> word;) w.push_back(word);
    if (w.empty()) continue;
    const std::string where = name + ":" + std::to_string(number) + ": ";
    ScriptCommand command;
    command.line = number;
    if (w[0] == "at") {
      if (w.size() != 4) throw Error(where + "expected 'at FRAME KEY VALUE'");
      command.kind = ScriptCommand::Kind::kAt;
      if (!ParseFrame(w[1], command.first_frame)) throw Error(where + "frame '" + w[1] + "' is not an integer >= 0");
      command.key = w[2];
      command.value = w[3];
      ViewState probe;
      try {
        SetViewValue(probe, command.key, command.value);
      } catch (const Error& error) {
        throw Error(where + error.what());
      }
    } else if (w[0] == "ramp") {
      if (w.size() != 6) throw Error(where + "expected 'ramp FIRST LAST KEY FROM TO'");
      command.kind = ScriptCommand::Kind::kRamp;
      if (!ParseFrame(w[1], command.first_frame)) throw Error(where + "frame '" + w[1] + "' is not an integer >= 0");
      if (!ParseFrame(w[2], command.last_frame)) throw Error(where + "frame '" + w[2] + "' is not an integer >= 0");
      if (command.last_frame <= command.first_frame) throw Error(where + "a ramp's LAST frame must come after FIRST");
      command.key = w[3];
      if (FindNumberKey(command.key) == nullptr) {
        const std::string numbers = KeyList().substr(std::string("camera, model, spectral, ").size());
        throw Error(where + "'" + command.key + "' cannot ramp (a number key: " + numbers + ")");
      }
      if (!ParseNumber(w[4], command.from) || !ParseNumber(w[5], command.to)) {
        throw Error(where + "a ramp's FROM and TO must be finite numbers");
      }
      try {  // the bounds are intervals: the frames between the ends stay inside them
        CheckBounds(*FindNumberKey(command.key), command.from);
        CheckBounds(*FindNumberKey(command.key), command.to);
      } catch (const Error& error) {
        throw Error(where + error.what());
      }
    } else if (w[0] == "screenshot") {
      if (w.size() != 3) throw Error(where + "expected 'screenshot FRAME PATH'");
      command.kind = ScriptCommand::Kind::kScreenshot;
      if (!ParseFrame(w[1], command.first_frame)) throw Error(where + "frame '" + w[1] + "' is not an integer >= 0");
      command.path = w[2];
      const std::string extension = command.path.size() >= 4 ? command.path.substr(command.path.size() - 4) : "";
      if (extension != ".exr" && extension != ".png") {
        throw Error(where + "screenshot '" + command.path + "' must end in .exr or .png");
      }
    } else {
      throw Error(where + "unknown command '" + w[0] + "' (known: at, ramp, screenshot)");
    }
    script.commands.push_back(command);
  }
  return script;
}

std::vector<std::string> ApplyScript(const ViewerScript& script, int frame, ViewState& state) {
  std::vector<std::string> screenshots;
  for (const ScriptCommand& c : script.commands) {
    switch (c.kind) {
      case ScriptCommand::Kind::kAt:
        if (frame == c.first_frame) SetViewValue(state, c.key, c.value);
        break;
      case ScriptCommand::Kind::kRamp:
        if (frame >= c.first_frame && frame <= c.last_frame) {
          const double t = static_cast<double>(frame - c.first_frame) / (c.last_frame - c.first_frame);
          state.*(FindNumberKey(c.key)->field) = c.from + t * (c.to - c.from);
          if (c.key == "ev") state.auto_exposure = false;
        }
        break;
      case ScriptCommand::Kind::kScreenshot:
        if (frame == c.first_frame) screenshots.push_back(c.path);
        break;
    }
  }
  return screenshots;
}

}  // namespace atmo::viewer
