// The C++ side of the GLSL/C++ common subset (after Bruneton 2017).
//
// The files `*.glsl` in this folder hold the per-sample physics of atmo, written once in the
// subset of GLSL that is also valid C++. The CPU backend includes them as C++ inside the
// namespace `atmo::shared` after this prelude; the GL backend embeds the same files as shader
// source after a GLSL prelude that defines the same names. Rules for the subset:
//   - scalars are `Number` (double here, float in GLSL); vectors are vec2/vec3/vec4, ivec2/ivec3;
//   - parameters are passed as IN(T), OUT(T) or INOUT(T); no references, pointers or templates;
//   - literals are written without suffix (1.0, not 1.0f); functions are free functions;
//   - textures are read with `texture(sampler, uv)` and `textureSize(sampler, 0)`;
//   - lengths are in whatever unit the parameters use (metres on the CPU, km on the GPU).
#pragma once

#include <cmath>
#include <cstddef>
#include <vector>

#include <glm/glm.hpp>

namespace atmo::shared {

using Number = double;
using vec2 = glm::dvec2;
using vec3 = glm::dvec3;
using vec4 = glm::dvec4;
using ivec2 = glm::ivec2;
using ivec3 = glm::ivec3;

using glm::abs;
using glm::acos;
using glm::atan;
using glm::clamp;
using glm::cos;
using glm::cross;
using glm::dot;
using glm::exp;
using glm::floor;
using glm::length;
using glm::max;
using glm::min;
using glm::mix;
using glm::normalize;
using glm::sin;
using glm::sqrt;
using glm::tan;

#define IN(type) const type&
#define OUT(type) type&
#define INOUT(type) type&

// A 2D float texture with the sampling rules of an OpenGL sampler using GL_LINEAR filtering:
// texel i has its centre at u = (i + 0.5) / width; outside [0, 1] the coordinate is clamped to
// the edge, or wrapped when `repeat_u` is set (GL_REPEAT on the s axis).
struct Texture2D {
  int width = 0;
  int height = 0;
  bool repeat_u = false;
  std::vector<glm::vec3> texels;  // row-major, texel (x, y) at index x + y * width

  Texture2D() = default;
  Texture2D(int w, int h, bool repeat = false)
      : width(w), height(h), repeat_u(repeat), texels(static_cast<std::size_t>(w) * h) {}
  glm::vec3& at(int x, int y) { return texels[static_cast<std::size_t>(x) + static_cast<std::size_t>(y) * width]; }
  const glm::vec3& at(int x, int y) const {
    return texels[static_cast<std::size_t>(x) + static_cast<std::size_t>(y) * width];
  }
};

// A 3D float texture (GL_LINEAR, clamp to edge on every axis).
struct Texture3D {
  int width = 0;
  int height = 0;
  int depth = 0;
  std::vector<glm::vec3> texels;  // texel (x, y, z) at index x + y * width + z * width * height

  Texture3D() = default;
  Texture3D(int w, int h, int d) : width(w), height(h), depth(d), texels(static_cast<std::size_t>(w) * h * d) {}
  glm::vec3& at(int x, int y, int z) {
    return texels[static_cast<std::size_t>(x) + static_cast<std::size_t>(width) * (y + static_cast<std::size_t>(height) * z)];
  }
  const glm::vec3& at(int x, int y, int z) const {
    return texels[static_cast<std::size_t>(x) + static_cast<std::size_t>(width) * (y + static_cast<std::size_t>(height) * z)];
  }
};

inline ivec2 textureSize(const Texture2D& t, int /*lod*/) { return ivec2(t.width, t.height); }
inline ivec3 textureSize(const Texture3D& t, int /*lod*/) { return ivec3(t.width, t.height, t.depth); }

namespace detail {
// Splits a texture coordinate into the two texels that GL_LINEAR blends and the weight of the
// second one. Any u, NaN and infinities included, gives texels inside the table: x is first
// brought into [-1, size] with comparisons that NaN fails (NaN -> -1, i.e. the first texel), so
// that the conversion to int is always defined (a NaN cast to int is undefined behaviour and
// gave an index of -2^31, the audit's segfault).
inline void LinearTaps(double u, int size, bool repeat, int& i0, int& i1, double& w) {
  // Wrapped coordinates keep their fraction; beyond 2^52 there is none, and NaN goes to 0.
  if (repeat) u = (u > -4.5e15 && u < 4.5e15) ? u - std::floor(u) : 0.0;
  double x = u * size - 0.5;
  x = !(x > -1.0) ? -1.0 : (x < static_cast<double>(size) ? x : static_cast<double>(size));
  const double fl = std::floor(x);
  w = x - fl;
  i0 = static_cast<int>(fl);
  i1 = i0 + 1;
  if (i0 >= 0 && i1 < size) return;  // inside: no wrapping or clamping
  if (repeat) {
    i0 = ((i0 % size) + size) % size;
    i1 = ((i1 % size) + size) % size;
  } else {
    i0 = i0 < 0 ? 0 : (i0 >= size ? size - 1 : i0);
    i1 = i1 < 0 ? 0 : (i1 >= size ? size - 1 : i1);
  }
}
}  // namespace detail

inline vec4 texture(const Texture2D& t, const vec2& uv) {
  int x0, x1, y0, y1;
  double wx, wy;
  detail::LinearTaps(uv.x, t.width, t.repeat_u, x0, x1, wx);
  detail::LinearTaps(uv.y, t.height, false, y0, y1, wy);
  const vec3 a = mix(vec3(t.at(x0, y0)), vec3(t.at(x1, y0)), wx);
  const vec3 b = mix(vec3(t.at(x0, y1)), vec3(t.at(x1, y1)), wx);
  return vec4(mix(a, b, wy), 1.0);
}

inline vec4 texture(const Texture3D& t, const vec3& uvw) {
  int x0, x1, y0, y1, z0, z1;
  double wx, wy, wz;
  detail::LinearTaps(uvw.x, t.width, false, x0, x1, wx);
  detail::LinearTaps(uvw.y, t.height, false, y0, y1, wy);
  detail::LinearTaps(uvw.z, t.depth, false, z0, z1, wz);
  auto plane = [&](int z) {
    const vec3 a = mix(vec3(t.at(x0, y0, z)), vec3(t.at(x1, y0, z)), wx);
    const vec3 b = mix(vec3(t.at(x0, y1, z)), vec3(t.at(x1, y1, z)), wx);
    return mix(a, b, wy);
  };
  return vec4(mix(plane(z0), plane(z1), wz), 1.0);
}

// Two textures of one size sampled at one coordinate: the taps are found once (GLSL, where the
// sampler does this in hardware, defines it as two texture() calls).
inline void TexturePair3D(const Texture3D& a, const Texture3D& b, const vec3& uvw, vec3& out_a, vec3& out_b) {
  int x0, x1, y0, y1, z0, z1;
  double wx, wy, wz;
  detail::LinearTaps(uvw.x, a.width, false, x0, x1, wx);
  detail::LinearTaps(uvw.y, a.height, false, y0, y1, wy);
  detail::LinearTaps(uvw.z, a.depth, false, z0, z1, wz);
  const std::size_t sx = 1, sy = static_cast<std::size_t>(a.width), sz = sy * static_cast<std::size_t>(a.height);
  const std::size_t i000 = x0 * sx + y0 * sy + z0 * sz;
  const std::size_t dx = (x1 - x0) * sx, dy = (y1 - y0) * sy, dz = (z1 - z0) * sz;
  const float fx = static_cast<float>(wx), fy = static_cast<float>(wy), fz = static_cast<float>(wz);
  auto trilinear = [&](const std::vector<glm::vec3>& t) {
    const glm::vec3 c00 = glm::mix(t[i000], t[i000 + dx], fx);
    const glm::vec3 c10 = glm::mix(t[i000 + dy], t[i000 + dy + dx], fx);
    const glm::vec3 c01 = glm::mix(t[i000 + dz], t[i000 + dz + dx], fx);
    const glm::vec3 c11 = glm::mix(t[i000 + dz + dy], t[i000 + dz + dy + dx], fx);
    return vec3(glm::mix(glm::mix(c00, c10, fy), glm::mix(c01, c11, fy), fz));
  };
  out_a = trilinear(a.texels);
  out_b = trilinear(b.texels);
}

using TransmittanceTexture = Texture2D;
using MultiScatteringTexture = Texture2D;
using SkyViewTexture = Texture2D;
using Source4dTexture = Texture3D;

}  // namespace atmo::shared
