// Environment maps for a named program (`atmo render --target NAME`, docs/environment.md): the
// orientation, handedness and up axis each program expects of an equirect (latitude-longitude)
// image, fixed in the world so that the map does not turn as the sun moves.
//
// To use it:
//   const atmo::EngineTarget& three = atmo::FindEngineTarget("three");
//   settings.camera.kind = atmo::CameraKind::kEquirect;
//   settings.camera.yaw_deg = three.equirect_centre_azimuth_deg;   // east at the centre
//   atmo::Image image = atmo::RenderView(*sky, settings.camera, {});
//
// Each program's world is tied to the compass by the convention its users follow (stated per
// target in `world`): Y-up right-handed programs (three.js, glTF, Mitsuba) take +X east and -Z
// north, Z-up right-handed ones (Blender, pbrt) +X east and +Y north. atmo's equirect has the
// azimuth `yaw` at its centre column and azimuths growing to the right, elevation +90 at the top;
// in these frames every target's lookup does too, so a target is a yaw.
#pragma once

#include <string>
#include <string_view>
#include <vector>

#include "atmo/cubemap.h"

namespace atmo {

struct EngineTarget {
  const char* name;     // the --target value
  const char* program;  // what it is, for messages and docs
  // The compass azimuth (0 north, 90 east) the program's lookup puts at the image's centre column
  // with the world frame below.
  double equirect_centre_azimuth_deg;
  const char* world;   // the program's axes and how they meet the compass, one line
  const char* recipe;  // where the map goes in the program, one line
  const char* source;  // where the convention comes from (a file and function of the program)
};

// Every target, in the order of `--help`.
const std::vector<EngineTarget>& EngineTargets();
// The target called `name`; throws atmo::Error naming the known ones otherwise.
const EngineTarget& FindEngineTarget(std::string_view name);
// "three, blender, ..." for messages.
std::string EngineTargetNames();

// A cube map (the cube-frame GL convention of atmo/cubemap.h) as three.js's CubeTexture wants its
// six images: three samples a cube texture that is not a render target along (-x, y, z) for the
// world direction (x, y, z) (src/renderers/webgl/WebGLBackground.js and WebGLMaterials.js, the
// matrix _m; PMREMGenerator's flipEnvMap), so its +X image holds the world's -X side: the +X and
// -X faces swap and every face is mirrored left-right. Faces in three's order px, nx, py, ny, pz,
// nz; rows from t = 0 (three uploads cube images with flipY false).
Cubemap CubeTextureForThree(const Cubemap& cube);

}  // namespace atmo
