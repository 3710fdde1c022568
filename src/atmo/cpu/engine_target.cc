// Equirect conventions of the programs `--target` names (include/atmo/engine_target.h).
//
// How each entry follows from its program's lookup. atmo's equirect puts the compass azimuth A at
// image column u = 1/2 + (A - yaw) / 360 (u from the left, 0..1) and elevation e at
// v = 1/2 + e / 180 from the bottom. A program that maps a world direction d to
// u = 1/2 + phi(d) / 2 pi with phi growing eastwards-then-southwards (clockwise seen from above)
// agrees with it when yaw is the azimuth of phi = 0. Every program below grows u clockwise seen
// from above in the world frame it is given (none needs the image mirrored).
#include "atmo/engine_target.h"

#include <algorithm>
#include <string>

#include "atmo/error.h"

namespace atmo {

const std::vector<EngineTarget>& EngineTargets() {
  // u is the lookup's horizontal texture coordinate from the image's left, d the world direction.
  static const std::vector<EngineTarget> targets = {
      {"three", "three.js (scene.background / scene.environment with EquirectangularReflectionMapping)",
       // u = atan(d.z, d.x) / 2 pi + 1/2: centre +X (east), u = 1/4 at -Z (north), growing towards
       // +Z (south). v = asin(d.y) / pi + 1/2 from the bottom row (EXRLoader hands rows bottom-up).
       90.0, "Y up, right-handed; +X east, -Z north (glTF's frame)",
       "new EXRLoader().load('sky.exr', t => { t.mapping = THREE.EquirectangularReflectionMapping; "
       "scene.background = scene.environment = t; })",
       "three.js r187 src/renderers/shaders/ShaderChunk/common.glsl.js, equirectUv"},
      {"blender", "Blender (World: Environment Texture, equirectangular; Cycles and EEVEE)",
       // u = 1/2 - atan2(d.y, d.x) / 2 pi: centre +X (east), u = 1/4 at +Y (north), growing towards
       // -Y (south). v = 1 - acos(d.z) / pi from the bottom row (images load bottom row first).
       90.0, "Z up, right-handed; +X east, +Y north",
       "World > Surface: Background, Color from an Environment Texture node with sky.exr (Equirectangular)",
       "Blender 3.4 intern/cycles/kernel/camera/projection.h, direction_to_equirectangular (EEVEE: "
       "node_tex_environment_equirectangular, the same map)"},
      {"unreal", "Unreal Engine 5 (sky.exr imported as a long-lat Texture Cube: Sky Light, HDRI Backdrop)",
       // u = 1/2 + atan2(d.x, -d.y) / 2 pi: centre -Y (north), u = 1/4 at -X (west), growing towards
       // +X (east). v = acos(d.z) / pi from the top row.
       0.0,
       "Z up, left-handed; +X east, +Y south, so north is -Y (Unreal has no compass: atmo's choice, "
       "the east-south-up frame of geo-referenced Unreal worlds)",
       "import sky.exr (it becomes a Texture Cube from its long-lat layout); Sky Light: Source Type "
       "SLS Specified Cubemap, Cubemap sky; or an HDRI Backdrop's Cubemap",
       "Unreal Engine 5 TextureCompressorModule.cpp, GenerateBaseCubeMipFromLongitudeLatitude2D and "
       "LookupLongLatDouble"},
      {"unity", "Unity (a Skybox/Panoramic material, Latitude Longitude Layout)",
       // u = 1/2 - atan2(d.z, d.x) / 2 pi: centre +X (east), u = 1/4 at +Z (north), growing towards
       // -Z (south). v = 1 - acos(d.y) / pi from the bottom row.
       90.0, "Y up, left-handed; +X east, +Z north (Unity's forward)",
       "a material with shader Skybox/Panoramic, Mapping: Latitude Longitude Layout, Spherical (HDR) "
       "texture sky.exr (Texture Shape 2D); Lighting > Environment > Skybox Material",
       "Unity built-in shaders DefaultResourcesExtra/Skybox-Panoramic.shader, ToRadialCoords"},
      {"godot", "Godot 4 (Environment > Sky > PanoramaSkyMaterial)",
       // u = atan2(d.x, -d.z) / 2 pi (wrapped to [0, 1)): the seam at -Z (north), centre +Z (south),
       // u = 1/4 at +X (east). v = acos(d.y) / pi from the top row.
       180.0, "Y up, right-handed; +X east, -Z north (Godot's forward)",
       "WorldEnvironment > Environment: Background Sky, Sky Material PanoramaSkyMaterial with Panorama "
       "sky.exr, Sky Rotation 0",
       "Godot 4 servers/rendering/renderer_rd/shaders/environment/sky.glsl (panorama coordinates), "
       "scene/resources/sky_material.cpp (PanoramaSkyMaterial)"},
      {"pbrt", "pbrt (v3 reads the equirect; v4 after imgtool makeequiarea)",
       // u = phi / 2 pi, phi = atan2(d.y, d.x) in [0, 2 pi): u = 0 at +X (east), centre -X (west),
       // u = 1/4 at +Y (south). v = acos(d.z) / pi from the top row.
       270.0,
       "Z up, left-handed; +X east, +Y south, so north is -Y (pbrt has no compass: atmo's choice)",
       "pbrt-v3: LightSource \"infinite\" \"string mapname\" \"sky.exr\"; pbrt-v4: imgtool makeequiarea "
       "sky.exr --outfile sky-equal-area.exr, then LightSource \"infinite\" \"string filename\" "
       "\"sky-equal-area.exr\"",
       "pbrt-v3 src/lights/infinite.cpp (SphericalPhi, SphericalTheta); pbrt-v4 cmd/imgtool.cpp, "
       "makeequiarea"},
      {"mitsuba", "Mitsuba 3 (envmap emitter)",
       // u = atan2(d.x, -d.z) / 2 pi (wrapped to [0, 1)): centre +Z (south), u = 1/4 at +X (east).
       // v = acos(d.y) / pi from the top row.
       180.0, "Y up, right-handed; +X east, -Z north (glTF's frame)",
       "<emitter type=\"envmap\"><string name=\"filename\" value=\"sky.exr\"/></emitter> (no to_world)",
       "Mitsuba 3.9 src/emitters/envmap.cpp, direction_to_uv"},
  };
  return targets;
}

std::string EngineTargetNames() {
  std::string names;
  for (const EngineTarget& t : EngineTargets()) names += (names.empty() ? "" : ", ") + std::string(t.name);
  return names;
}

const EngineTarget& FindEngineTarget(std::string_view name) {
  for (const EngineTarget& t : EngineTargets()) {
    if (name == t.name) return t;
  }
  std::string shown(name.substr(0, 32));
  std::replace_if(shown.begin(), shown.end(), [](char c) { return c < 0x20 || c == 0x7f; }, '?');
  throw Error("unknown --target '" + shown + "' (known: " + EngineTargetNames() + ")");
}

Cubemap CubeTextureForThree(const Cubemap& cube) {
  // Face f of the result holds the radiance along M d, M = diag(-1, 1, 1), d the GL direction of
  // its texel: +X (1, -b, -a) -> (-1, -b, -a) is the -X face at a' = -a; +Y (a, 1, b) -> (-a, 1, b)
  // is the +Y face at a' = -a; and so on: swap the X faces, mirror s (a) on all.
  Cubemap out = cube;
  for (int f = 0; f < kCubeFaceCount; ++f) {
    const int source = f == 0 ? 1 : f == 1 ? 0 : f;
    const Image& in = cube.faces[source];
    Image& face = out.faces[f];
    const int n = in.width;
    for (int j = 0; j < in.height; ++j) {
      for (int i = 0; i < n; ++i) {
        for (int c = 0; c < in.channels; ++c) face.at(i, j, c) = in.at(n - 1 - i, j, c);
      }
    }
  }
  return out;
}

}  // namespace atmo
