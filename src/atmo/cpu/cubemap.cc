// Cube maps of a sky: face directions, texel solid angles, rendering through six perspective
// cameras (atmo/cubemap.h, docs/environment.md).
#include "atmo/cubemap.h"

#include <cmath>
#include <string>
#include <vector>

#include <oneapi/tbb/parallel_for.h>

#include "atmo/error.h"

namespace atmo {
namespace {

void CheckFaceSize(int size) {
  if (size < 1 || size > kMaxImageSide) {
    throw Error("cube face size " + std::to_string(size) + " is outside 1.." + std::to_string(kMaxImageSide));
  }
}

// The solid angle of the face-plane rectangle [0, x] x [0, y] (plane at distance 1).
double RectangleSolidAngle(double x, double y) { return std::atan(x * y / std::sqrt(1.0 + x * x + y * y)); }

// Whether a face's camera image is its texel grid mirrored left-right (X and Z faces) rather than
// top-bottom (Y faces): see CubeFaceCamera.
bool MirroredLeftRight(CubeFace face) { return face != CubeFace::kPositiveY && face != CubeFace::kNegativeY; }

// The camera image of `face` turned into the cube map convention, or back (the flip is its own
// inverse).
Image FlipFace(const Image& image, CubeFace face) {
  Image out = image;
  const int n = image.width;
  const int c = image.channels;
  const bool left_right = MirroredLeftRight(face);
  for (int j = 0; j < image.height; ++j) {
    for (int i = 0; i < n; ++i) {
      const int si = left_right ? n - 1 - i : i;
      const int sj = left_right ? j : image.height - 1 - j;
      for (int k = 0; k < c; ++k) out.at(i, j, k) = image.at(si, sj, k);
    }
  }
  return out;
}

template <typename RenderFace>
Cubemap RenderFaces(int face_size, const RenderFace& render_face) {
  CheckFaceSize(face_size);
  Cubemap cube;
  cube.face_size = face_size;
  for (int f = 0; f < kCubeFaceCount; ++f) {
    const CubeFace face = static_cast<CubeFace>(f);
    cube.faces[f] = FlipFace(render_face(CubeFaceCamera(face, face_size)), face);
  }
  return cube;
}

}  // namespace

Cubemap::Cubemap(int size, int channels) : face_size(size) {
  for (Image& f : faces) f = Image(size, size, channels);
}

glm::dvec3 CubeFaceDirection(CubeFace face, double s, double t) {
  const double a = 2.0 * s - 1.0;
  const double b = 2.0 * t - 1.0;
  glm::dvec3 d(0.0);
  switch (face) {
    case CubeFace::kPositiveX: d = {1.0, -b, -a}; break;
    case CubeFace::kNegativeX: d = {-1.0, -b, a}; break;
    case CubeFace::kPositiveY: d = {a, 1.0, b}; break;
    case CubeFace::kNegativeY: d = {a, -1.0, -b}; break;
    case CubeFace::kPositiveZ: d = {a, -b, 1.0}; break;
    case CubeFace::kNegativeZ: d = {-a, -b, -1.0}; break;
  }
  return glm::normalize(d);
}

void CubeFaceCoordinates(const glm::dvec3& d, CubeFace& face, double& s, double& t) {
  const glm::dvec3 m = glm::abs(d);
  double a = 0.0;
  double b = 0.0;
  // The inverse of CubeFaceDirection's table: a and b are the face-plane coordinates of d / |major|.
  if (m.x >= m.y && m.x >= m.z) {
    face = d.x > 0.0 ? CubeFace::kPositiveX : CubeFace::kNegativeX;
    a = (d.x > 0.0 ? -d.z : d.z) / m.x;
    b = -d.y / m.x;
  } else if (m.y >= m.z) {
    face = d.y > 0.0 ? CubeFace::kPositiveY : CubeFace::kNegativeY;
    a = d.x / m.y;
    b = (d.y > 0.0 ? d.z : -d.z) / m.y;
  } else {
    face = d.z > 0.0 ? CubeFace::kPositiveZ : CubeFace::kNegativeZ;
    a = (d.z > 0.0 ? d.x : -d.x) / m.z;
    b = -d.y / m.z;
  }
  s = 0.5 * (a + 1.0);
  t = 0.5 * (b + 1.0);
}

double CubeTexelSolidAngle(int size, int i, int j) {
  const double step = 2.0 / size;
  const double x0 = i * step - 1.0;
  const double x1 = x0 + step;
  const double y0 = j * step - 1.0;
  const double y1 = y0 + step;
  return RectangleSolidAngle(x1, y1) - RectangleSolidAngle(x0, y1) - RectangleSolidAngle(x1, y0) +
         RectangleSolidAngle(x0, y0);
}

std::vector<double> CubeFaceSolidAngles(int size) {
  // The rectangle form at the (size + 1)^2 texel corners once, each texel the inclusion-exclusion
  // of its four: a quarter of the atan calls of CubeTexelSolidAngle per texel, the same values.
  const int c = size + 1;
  const double step = 2.0 / size;
  std::vector<double> corner(static_cast<std::size_t>(c) * c);
  for (int j = 0; j < c; ++j) {
    for (int i = 0; i < c; ++i) corner[static_cast<std::size_t>(j) * c + i] = RectangleSolidAngle(i * step - 1.0, j * step - 1.0);
  }
  std::vector<double> omega(static_cast<std::size_t>(size) * size);
  for (int j = 0; j < size; ++j) {
    for (int i = 0; i < size; ++i) {
      const std::size_t k = static_cast<std::size_t>(j) * c + i;
      omega[static_cast<std::size_t>(j) * size + i] = corner[k + c + 1] - corner[k + c] - corner[k + 1] + corner[k];
    }
  }
  return omega;
}

Camera CubeFaceCamera(CubeFace face, int size) {
  // The perspective camera looks along forward = (sin yaw cos pitch, cos yaw cos pitch, sin pitch)
  // (ENU) with right = (cos yaw, -sin yaw, 0) and up = right x forward (shared/camera.glsl): its
  // image is the view from inside, not mirrored. East, for example (yaw 90): right = south =
  // cube +Z, up = cube +Y, against texel (i, j) of face +X at (1, -b, -a), whose s grows towards
  // -Z: the camera's column i is the face's column N - 1 - i. At pitch 90 (the zenith, yaw 0)
  // right = east = cube +X and up = (0, -1, 0) ENU = south = cube +Z, against +Y's (a, 1, b)
  // whose t grows towards +Z: the camera's row j is the face's row N - 1 - j.
  Camera camera;
  camera.kind = CameraKind::kPerspective;
  camera.width = size;
  camera.height = size;
  camera.fov_deg = 90.0;
  switch (face) {
    case CubeFace::kPositiveX: camera.yaw_deg = 90.0; camera.pitch_deg = 0.0; break;
    case CubeFace::kNegativeX: camera.yaw_deg = 270.0; camera.pitch_deg = 0.0; break;
    case CubeFace::kPositiveY: camera.yaw_deg = 0.0; camera.pitch_deg = 90.0; break;
    case CubeFace::kNegativeY: camera.yaw_deg = 0.0; camera.pitch_deg = -90.0; break;
    case CubeFace::kPositiveZ: camera.yaw_deg = 180.0; camera.pitch_deg = 0.0; break;
    case CubeFace::kNegativeZ: camera.yaw_deg = 0.0; camera.pitch_deg = 0.0; break;
  }
  return camera;
}

Cubemap RenderCubemap(const SkyView& sky, int face_size, const RadianceTerms& terms,
                      std::span<const double> solar_irradiance) {
  return RenderFaces(face_size, [&](const Camera& camera) { return RenderView(sky, camera, terms, solar_irradiance); });
}

Cubemap RenderCubemapFolded(const SkyView& sky, int face_size, const RadianceTerms& terms,
                            std::span<const glm::vec3> weights) {
  return RenderFaces(face_size, [&](const Camera& camera) { return RenderViewFolded(sky, camera, terms, weights); });
}

Image CubemapExrImage(const Cubemap& cube) {
  const int n = cube.face_size;
  const int c = cube.channels();
  Image out(n, kCubeFaceCount * n, c);
  out.channel_names = cube.faces[0].channel_names;
  out.colour_space = cube.faces[0].colour_space;
  out.envmap = EnvMap::kCube;
  for (int f = 0; f < kCubeFaceCount; ++f) {
    // OpenEXR's faces are the camera images (ImfEnvmap.h's diagram: +X has +Y up and +Z to the
    // right, seen from inside), the flip of the cube map convention.
    const Image face = FlipFace(cube.faces[f], static_cast<CubeFace>(f));
    std::copy(face.pixels.begin(), face.pixels.end(),
              out.pixels.begin() + static_cast<std::ptrdiff_t>(f) * n * n * c);
  }
  return out;
}

Cubemap CubemapFromExrImage(const Image& image) {
  const int n = image.width;
  if (n < 1 || image.height != kCubeFaceCount * n || image.channels < 1 ||
      image.pixels.size() != static_cast<std::size_t>(n) * image.height * image.channels) {
    throw Error("a cube map image is N wide and 6 N high (OpenEXR's layout), got " + std::to_string(image.width) +
                "x" + std::to_string(image.height));
  }
  const int c = image.channels;
  Cubemap cube(n, c);
  for (int f = 0; f < kCubeFaceCount; ++f) {
    Image face(n, n, c);
    std::copy(image.pixels.begin() + static_cast<std::ptrdiff_t>(f) * n * n * c,
              image.pixels.begin() + static_cast<std::ptrdiff_t>(f + 1) * n * n * c, face.pixels.begin());
    cube.faces[f] = FlipFace(face, static_cast<CubeFace>(f));
    cube.faces[f].channel_names = image.channel_names;
    cube.faces[f].colour_space = image.colour_space;
  }
  return cube;
}

Cubemap DownsampleCubemap(const Cubemap& cube) {
  const int n = cube.face_size;
  if (n <= 1) return cube;
  const int h = n / 2;
  const int c = cube.channels();
  Cubemap out(h, c);
  // Each coarse texel is the solid-angle weighted mean of its 2 x 2 children, sum L dOmega /
  // sum dOmega: the children tile it exactly (for even n), so the energy sum L dOmega is kept.
  const std::vector<double> omega = CubeFaceSolidAngles(n);
  oneapi::tbb::parallel_for(0, kCubeFaceCount, [&](int f) {
    const Image& in = cube.faces[f];
    Image& o = out.faces[f];
    o.channel_names = in.channel_names;
    o.colour_space = in.colour_space;
    for (int j = 0; j < h; ++j) {
      for (int i = 0; i < h; ++i) {
        double weight = 0.0;
        double sum[4] = {0.0, 0.0, 0.0, 0.0};
        for (int dj = 0; dj < 2; ++dj) {
          for (int di = 0; di < 2; ++di) {
            const int x = 2 * i + di;
            const int y = 2 * j + dj;
            const double w = omega[static_cast<std::size_t>(y) * n + x];
            weight += w;
            for (int k = 0; k < c && k < 4; ++k) sum[k] += w * in.at(x, y, k);
          }
        }
        for (int k = 0; k < c; ++k) {
          if (k < 4) {
            o.at(i, j, k) = static_cast<float>(sum[k] / weight);
          } else {
            double s = 0.0;
            for (int dj = 0; dj < 2; ++dj) {
              for (int di = 0; di < 2; ++di) {
                s += omega[static_cast<std::size_t>(2 * j + dj) * n + 2 * i + di] * in.at(2 * i + di, 2 * j + dj, k);
              }
            }
            o.at(i, j, k) = static_cast<float>(s / weight);
          }
        }
      }
    }
  });
  return out;
}

}  // namespace atmo
