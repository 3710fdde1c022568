// Cube environment maps of a sky: six 90-degree faces, written as an OpenEXR cube map or a KTX 2.0
// cubemap (docs/environment.md).
//
// To use it:
//   auto sky = model->View(0.0, atmo::SunDirection(20.0, 135.0));
//   atmo::Cubemap cube = atmo::RenderCubemap(*sky, 256, {}, model->parameters().solar_irradiance);
//   atmo::WriteExr("sky_cube.exr", atmo::CubemapExrImage(cube));   // envmap = ENVMAP_CUBE
//   atmo::WriteKtx2("sky.ktx2", {cube});                             // RGBA16F, one level
//
// Frames. atmo's local frame is east-north-up (x east, y north, z up). Cube maps live in the
// "cube frame", the Y-up right-handed frame of engines (glTF, OpenGL, Vulkan world space):
//   X = east, Y = up, Z = south      (so -Z, the glTF/OpenGL camera's forward, is north),
// i.e. cube (X, Y, Z) = ENU (x, z, -y). Face +X holds the eastern directions, -X west, +Y the
// zenith, -Y the nadir, +Z south, -Z north.
//
// Face images are stored in the OpenGL/Vulkan/KTX cube map convention (OpenGL 4.6 table 8.19):
// texel (i, j) of a face of size N has s = (i + 0.5) / N, t = (j + 0.5) / N (row j = 0 first, at
// t = 0), a = 2 s - 1, b = 2 t - 1, and the cube-frame direction (before normalising)
//   +X: ( 1, -b, -a)   -X: (-1, -b,  a)   +Y: ( a,  1,  b)
//   -Y: ( a, -1, -b)   +Z: ( a, -b,  1)   -Z: (-a, -b, -1),
// so that a shader's texture(cube, d) with d in the cube frame returns the radiance along d.
// That convention is mirrored (it comes from RenderMan's left-handed frame): seen from inside the
// cube, each face image is a mirror image of the view. OpenEXR's cube maps are not mirrored;
// CubemapExrImage flips the faces into OpenEXR's layout.
#pragma once

#include <array>
#include <cstdint>
#include <filesystem>
#include <span>
#include <string>
#include <vector>

#include <glm/glm.hpp>

#include "atmo/image.h"
#include "atmo/model.h"
#include "atmo/render.h"

namespace atmo {

// Face order of OpenGL, Vulkan, KTX and OpenEXR alike.
enum class CubeFace { kPositiveX = 0, kNegativeX, kPositiveY, kNegativeY, kPositiveZ, kNegativeZ };
constexpr int kCubeFaceCount = 6;

// Cube frame (X east, Y up, Z south) from ENU (x east, y north, z up), and back.
inline glm::dvec3 CubeFromEnu(const glm::dvec3& enu) { return {enu.x, enu.z, -enu.y}; }
inline glm::dvec3 EnuFromCube(const glm::dvec3& cube) { return {cube.x, -cube.z, cube.y}; }

// The unit cube-frame direction of face coordinates (s, t) in [0, 1]^2 (t downwards, the table
// above).
glm::dvec3 CubeFaceDirection(CubeFace face, double s, double t);
// The inverse: the face whose major axis is largest in |component| (ties: X before Y before Z)
// and (s, t) in [0, 1]^2. `direction` need not be unit; it must not be 0.
void CubeFaceCoordinates(const glm::dvec3& direction, CubeFace& face, double& s, double& t);
// The exact solid angle of texel (i, j) of a face of size `size` (the same for every face): the
// inclusion-exclusion of the rectangle form atan(X Y / sqrt(1 + X^2 + Y^2)) over its corners on
// the face plane at distance 1. The 6 N^2 texels sum to 4 pi.
double CubeTexelSolidAngle(int size, int i, int j);
// CubeTexelSolidAngle of every texel of a face, row-major (j * size + i), the same to rounding,
// from the rectangle form at the (size + 1)^2 corners once.
std::vector<double> CubeFaceSolidAngles(int size);

// Six square faces of `channels` values per texel, in the convention above.
struct Cubemap {
  int face_size = 0;
  std::array<Image, kCubeFaceCount> faces;

  Cubemap() = default;
  Cubemap(int size, int channels);
  int channels() const { return faces[0].channels; }
  Image& face(CubeFace f) { return faces[static_cast<int>(f)]; }
  const Image& face(CubeFace f) const { return faces[static_cast<int>(f)]; }
};

// The perspective camera (90-degree field of view, size x size) whose image is face `face` seen
// from inside, not mirrored: its pixel (i, j) looks along the face's texel (size - 1 - i, j) for
// the X and Z faces and (i, size - 1 - j) for the Y faces. Yaw and pitch: +X 90 and 0 (east),
// -X 270 and 0, +Y 0 and 90 (zenith, south at the top), -Y 0 and -90 (nadir, north at the top),
// +Z 180 and 0 (south), -Z 0 and 0 (north).
Camera CubeFaceCamera(CubeFace face, int size);

// Renders the six faces of a view as RenderView does (one channel per model channel, radiance x
// solar_irradiance): each face is the perspective camera above, mirrored into the cube map
// convention, so the pixel-integrated sun disc pass applies as it is and the disc's energy over
// the six faces is the transmitted irradiance. Throws atmo::Error for a face size outside
// [1, kMaxImageSide] and what RenderView rejects.
Cubemap RenderCubemap(const SkyView& sky, int face_size, const RadianceTerms& terms,
                      std::span<const double> solar_irradiance);
// The same folded into three channels (RenderViewFolded; with atmo::ColourWeights: linear sRGB).
Cubemap RenderCubemapFolded(const SkyView& sky, int face_size, const RadianceTerms& terms,
                            std::span<const glm::vec3> weights);

// OpenEXR's cube-map layout (ImfEnvmap.h): the faces stacked vertically, N wide and 6 N high, in
// the order +X, -X, +Y, -Y, +Z, -Z, each as OpenEXR orients it (the view from inside, not
// mirrored: the face cameras' images), and envmap = EnvMap::kCube. colour_space and
// channel_names are the faces'.
Image CubemapExrImage(const Cubemap& cube);
// The inverse: the Cubemap of an image in that layout (N wide, 6 N high; alpha is dropped). Throws
// atmo::Error for another shape.
Cubemap CubemapFromExrImage(const Image& image);

// A half-size copy: each texel the solid-angle weighted mean of its 2 x 2 children (so that
// sum L dOmega is kept for even sizes; odd sizes round down, size 1 stays 1).
Cubemap DownsampleCubemap(const Cubemap& cube);

// KTX 2.0 (Khronos KTX File Format Specification 2.0): a cubemap of RGBA texels (alpha 1) with
// `levels` as its mip levels, levels[0] the base (each level half the size of the one before,
// rounded down, at least 1). Texels are VK_FORMAT_R16G16B16A16_SFLOAT (97) or, with `float32`,
// VK_FORMAT_R32G32B32A32_SFLOAT (109); the data format descriptor says RGBSDA, linear transfer,
// BT.709 primaries where the faces are ColourSpace::kLinearSrgb (else unspecified); key/value
// data KTXorientation "rd" and KTXwriter. Level data is stored smallest level first, as the
// specification orders it, faces +X..-Z within a level, rows from t = 0. Needs 3-channel
// levels; half-float overflow (> 65504) is written as the largest half. Throws atmo::Error and
// leaves no partial file (WriteFileAtomically).
void WriteKtx2(const std::filesystem::path& path, std::span<const Cubemap> levels, bool float32 = false,
               const std::string& writer = "atmo");
// The bytes WriteKtx2 writes (for writers that are not files: the browser's downloads, web/).
// Throws atmo::Error for the levels WriteKtx2 refuses.
std::vector<std::uint8_t> EncodeKtx2(std::span<const Cubemap> levels, bool float32 = false,
                                     const std::string& writer = "atmo");

// IEEE 754 binary16 of a float, rounded to nearest even; values beyond the largest half
// (65504) clamp to it, NaN stays NaN (exposed for the tests).
std::uint16_t FloatToHalf(float value);
float HalfToFloat(std::uint16_t half);

}  // namespace atmo
