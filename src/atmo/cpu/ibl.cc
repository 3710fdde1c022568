// Image-based lighting from a cube map (atmo/ibl.h): spherical harmonics, irradiance, the GGX
// specular prefilter.
#include "atmo/ibl.h"

#include <algorithm>
#include <bit>
#include <cstdint>
#include <cmath>
#include <numbers>
#include <string>

#include <oneapi/tbb/blocked_range.h>
#include <oneapi/tbb/combinable.h>
#include <oneapi/tbb/parallel_for.h>

#include "atmo/error.h"

namespace atmo {
namespace {

constexpr double kPi = std::numbers::pi;

void CheckColourCube(const Cubemap& cube, const char* what) {
  if (cube.face_size < 1 || cube.channels() != 3) {
    throw Error(std::string(what) + " needs a cube map of 3 channels (got " + std::to_string(cube.channels()) + ")");
  }
}

// The texel solid angles of a face of size n (the same on every face), row-major.
std::vector<double> FaceSolidAngles(int n) {
  std::vector<double> omega(static_cast<std::size_t>(n) * n);
  for (int j = 0; j < n; ++j) {
    for (int i = 0; i < n; ++i) omega[static_cast<std::size_t>(j) * n + i] = CubeTexelSolidAngle(n, i, j);
  }
  return omega;
}

glm::dvec3 TexelDirection(int face, int n, int i, int j) {
  return CubeFaceDirection(static_cast<CubeFace>(face), (i + 0.5) / n, (j + 0.5) / n);
}

glm::dvec3 Texel(const Image& face, int i, int j) {
  const float* p = &face.pixels[(static_cast<std::size_t>(j) * face.width + i) * 3];
  return {p[0], p[1], p[2]};
}

// Bilinear within one face at texel coordinates (s, t), clamped at the face's edges.
glm::dvec3 Bilinear(const Image& face, double s, double t) {
  const int n = face.width;
  const double x = std::clamp(s * n - 0.5, 0.0, n - 1.0);
  const double y = std::clamp(t * n - 0.5, 0.0, n - 1.0);
  const int x0 = std::min(static_cast<int>(x), n - 1);
  const int y0 = std::min(static_cast<int>(y), n - 1);
  const int x1 = std::min(x0 + 1, n - 1);
  const int y1 = std::min(y0 + 1, n - 1);
  const double fx = x - x0;
  const double fy = y - y0;
  return (1.0 - fy) * ((1.0 - fx) * Texel(face, x0, y0) + fx * Texel(face, x1, y0)) +
         fy * ((1.0 - fx) * Texel(face, x0, y1) + fx * Texel(face, x1, y1));
}

Cubemap Resized(const Cubemap& cube, int size) {
  Cubemap out = cube;
  while (out.face_size > size) out = DownsampleCubemap(out);
  return out;
}

// Van der Corput radical inverse in base 2, for the Hammersley points (k / K, phi2(k)).
double RadicalInverse(std::uint32_t bits) {
  bits = (bits << 16u) | (bits >> 16u);
  bits = ((bits & 0x55555555u) << 1u) | ((bits & 0xAAAAAAAAu) >> 1u);
  bits = ((bits & 0x33333333u) << 2u) | ((bits & 0xCCCCCCCCu) >> 2u);
  bits = ((bits & 0x0F0F0F0Fu) << 4u) | ((bits & 0xF0F0F0F0u) >> 4u);
  bits = ((bits & 0x00FF00FFu) << 8u) | ((bits & 0xFF00FF00u) >> 8u);
  return static_cast<double>(bits) * 2.3283064365386963e-10;
}

}  // namespace

std::array<double, 9> ShBasis(const glm::dvec3& d) {
  const double x = d.x;
  const double y = d.y;
  const double z = d.z;
  return {0.282094791773878, 0.488602511902920 * y, 0.488602511902920 * z, 0.488602511902920 * x,
          1.092548430592079 * x * y, 1.092548430592079 * y * z, 0.315391565252520 * (3.0 * z * z - 1.0),
          1.092548430592079 * x * z, 0.546274215296040 * (x * x - y * y)};
}

SphericalHarmonics ProjectSphericalHarmonics(const Cubemap& radiance, ShFrame frame) {
  CheckColourCube(radiance, "spherical harmonics");
  const int n = radiance.face_size;
  const std::vector<double> omega = FaceSolidAngles(n);
  // One partial sum per face (fixed order: the result does not depend on the thread count).
  std::array<std::array<glm::dvec3, 9>, kCubeFaceCount> partial{};
  oneapi::tbb::parallel_for(0, kCubeFaceCount, [&](int f) {
    std::array<glm::dvec3, 9> sum{};
    const Image& face = radiance.faces[f];
    for (int j = 0; j < n; ++j) {
      for (int i = 0; i < n; ++i) {
        const glm::dvec3 cube = TexelDirection(f, n, i, j);
        const std::array<double, 9> y = ShBasis(frame == ShFrame::kEnu ? EnuFromCube(cube) : cube);
        const glm::dvec3 weighted = Texel(face, i, j) * omega[static_cast<std::size_t>(j) * n + i];
        for (int k = 0; k < 9; ++k) sum[k] += y[k] * weighted;
      }
    }
    partial[f] = sum;
  });
  SphericalHarmonics sh;
  sh.frame = frame;
  for (const auto& p : partial) {
    for (int k = 0; k < 9; ++k) sh.radiance[k] += p[k];
  }
  return sh;
}

std::array<glm::dvec3, 9> ShIrradianceCoefficients(const SphericalHarmonics& sh) {
  static constexpr int kBand[9] = {0, 1, 1, 1, 2, 2, 2, 2, 2};
  std::array<glm::dvec3, 9> e{};
  for (int k = 0; k < 9; ++k) e[k] = kShCosineLobe[kBand[k]] * sh.radiance[k];
  return e;
}

glm::dvec3 ShIrradiance(const SphericalHarmonics& sh, const glm::dvec3& normal) {
  const std::array<double, 9> y = ShBasis(glm::normalize(normal));
  const std::array<glm::dvec3, 9> e = ShIrradianceCoefficients(sh);
  glm::dvec3 sum(0.0);
  for (int k = 0; k < 9; ++k) sum += y[k] * e[k];
  return sum;
}

glm::dvec3 CubemapIrradiance(const Cubemap& radiance, const glm::dvec3& normal_cube) {
  CheckColourCube(radiance, "irradiance");
  const int n = radiance.face_size;
  const std::vector<double> omega = FaceSolidAngles(n);
  const glm::dvec3 normal = glm::normalize(normal_cube);
  std::array<glm::dvec3, kCubeFaceCount> partial{};
  oneapi::tbb::parallel_for(0, kCubeFaceCount, [&](int f) {
    glm::dvec3 sum(0.0);
    for (int j = 0; j < n; ++j) {
      for (int i = 0; i < n; ++i) {
        const double c = glm::dot(normal, TexelDirection(f, n, i, j));
        if (c > 0.0) sum += Texel(radiance.faces[f], i, j) * (c * omega[static_cast<std::size_t>(j) * n + i]);
      }
    }
    partial[f] = sum;
  });
  glm::dvec3 sum(0.0);
  for (const glm::dvec3& p : partial) sum += p;
  return sum;
}

Cubemap IrradianceCubemap(const Cubemap& radiance, int size, int source_size) {
  CheckColourCube(radiance, "an irradiance cube map");
  if (size < 1 || size > kMaxImageSide || source_size < 1) throw Error("irradiance cube sizes must be at least 1");
  const Cubemap source = Resized(radiance, source_size);
  const int m = source.face_size;
  // The source as flat arrays: direction, and L dOmega per texel.
  const std::size_t count = static_cast<std::size_t>(kCubeFaceCount) * m * m;
  std::vector<float> dx(count), dy(count), dz(count), lr(count), lg(count), lb(count);
  const std::vector<double> omega = FaceSolidAngles(m);
  for (int f = 0; f < kCubeFaceCount; ++f) {
    for (int j = 0; j < m; ++j) {
      for (int i = 0; i < m; ++i) {
        const std::size_t k = (static_cast<std::size_t>(f) * m + j) * m + i;
        const glm::dvec3 d = TexelDirection(f, m, i, j);
        const glm::dvec3 l = Texel(source.faces[f], i, j) * omega[static_cast<std::size_t>(j) * m + i];
        dx[k] = static_cast<float>(d.x);
        dy[k] = static_cast<float>(d.y);
        dz[k] = static_cast<float>(d.z);
        lr[k] = static_cast<float>(l.x);
        lg[k] = static_cast<float>(l.y);
        lb[k] = static_cast<float>(l.z);
      }
    }
  }
  Cubemap out(size, 3);
  for (Image& face : out.faces) face.colour_space = radiance.faces[0].colour_space;
  oneapi::tbb::parallel_for(oneapi::tbb::blocked_range<int>(0, kCubeFaceCount * size), [&](const auto& rows) {
    for (int row = rows.begin(); row < rows.end(); ++row) {
      const int f = row / size;
      const int j = row % size;
      for (int i = 0; i < size; ++i) {
        const glm::dvec3 normal = TexelDirection(f, size, i, j);
        const float nx = static_cast<float>(normal.x);
        const float ny = static_cast<float>(normal.y);
        const float nz = static_cast<float>(normal.z);
        // float sums of at most 6 x 16^2 terms by default: ~1e-6 relative, far below the 1e-2
        // the tests ask.
        float r = 0.0f, g = 0.0f, b = 0.0f;
#pragma omp simd reduction(+ : r, g, b)
        for (std::size_t k = 0; k < count; ++k) {
          const float c = std::max(nx * dx[k] + ny * dy[k] + nz * dz[k], 0.0f);
          r += c * lr[k];
          g += c * lg[k];
          b += c * lb[k];
        }
        float* p = &out.faces[f].pixels[(static_cast<std::size_t>(j) * size + i) * 3];
        p[0] = r;
        p[1] = g;
        p[2] = b;
      }
    }
  });
  return out;
}

glm::dvec3 SampleCubemap(const Cubemap& cube, const glm::dvec3& direction) {
  CubeFace face;
  double s = 0.0;
  double t = 0.0;
  CubeFaceCoordinates(direction, face, s, t);
  return Bilinear(cube.face(face), s, t);
}

std::vector<Cubemap> PrefilterSpecular(const Cubemap& radiance, const SpecularSettings& settings) {
  CheckColourCube(radiance, "the specular prefilter");
  const int n = radiance.face_size;
  const int max_levels = std::bit_width(static_cast<unsigned>(n));
  if (settings.levels < 1 || settings.levels > max_levels) {
    throw Error("specular levels must be in 1.." + std::to_string(max_levels) + " for " + std::to_string(n) +
                "-texel faces (got " + std::to_string(settings.levels) + ")");
  }
  if (settings.samples < 1) throw Error("the specular prefilter needs at least 1 sample");
  // The radiance's mip pyramid, for the filtered importance sampling.
  std::vector<Cubemap> pyramid = {radiance};
  while (pyramid.back().face_size > 1) pyramid.push_back(DownsampleCubemap(pyramid.back()));
  const double max_lod = static_cast<double>(pyramid.size() - 1);
  const double texel_solid_angle = 4.0 * kPi / (6.0 * n * n);

  std::vector<Cubemap> levels;
  levels.push_back(radiance);  // roughness 0: the GGX lobe is a delta, the radiance itself
  for (int m = 1; m < settings.levels; ++m) {
    const double roughness = static_cast<double>(m) / (settings.levels - 1);
    const double alpha = roughness * roughness;
    const double a2 = alpha * alpha;
    // The samples in the tangent frame of n (= v = r): l = 2 (n.h) h - n, the same for every
    // texel, with their weight n.l and mip level.
    struct Sample {
      glm::dvec3 l;
      double weight;
      double lod;
    };
    std::vector<Sample> samples;
    double weight_sum = 0.0;
    for (int k = 0; k < settings.samples; ++k) {
      const double u = (k + 0.5) / settings.samples;
      const double v = RadicalInverse(static_cast<std::uint32_t>(k));
      // GGX importance sampling of h (Walter et al. 2007): cos^2(theta_h) = (1 - u) / (1 + (a^2 - 1) u).
      const double cos2 = (1.0 - u) / (1.0 + (a2 - 1.0) * u);
      const double cos_h = std::sqrt(cos2);
      const double sin_h = std::sqrt(std::max(0.0, 1.0 - cos2));
      const double phi = 2.0 * kPi * v;
      const glm::dvec3 l(2.0 * cos_h * sin_h * std::cos(phi), 2.0 * cos_h * sin_h * std::sin(phi), 2.0 * cos2 - 1.0);
      if (l.z <= 0.0) continue;
      // pdf(l) = D(h) (n.h) / (4 v.h) = D(h) / 4 at n = v.
      const double denominator = (a2 - 1.0) * cos2 + 1.0;
      const double d = a2 / (kPi * denominator * denominator);
      const double pdf = d / 4.0;
      const double sample_solid_angle = 1.0 / (settings.samples * pdf);
      const double lod = std::clamp(0.5 * std::log2(sample_solid_angle / texel_solid_angle) + 1.0, 0.0, max_lod);
      samples.push_back({l, l.z, lod});
      weight_sum += l.z;
    }
    const int size = std::max(1, n >> m);
    Cubemap out(size, 3);
    for (Image& face : out.faces) face.colour_space = radiance.faces[0].colour_space;
    oneapi::tbb::parallel_for(oneapi::tbb::blocked_range<int>(0, kCubeFaceCount * size), [&](const auto& rows) {
      for (int row = rows.begin(); row < rows.end(); ++row) {
        const int f = row / size;
        const int j = row % size;
        for (int i = 0; i < size; ++i) {
          const glm::dvec3 normal = TexelDirection(f, size, i, j);
          const glm::dvec3 helper = std::abs(normal.y) < 0.999 ? glm::dvec3(0.0, 1.0, 0.0) : glm::dvec3(1.0, 0.0, 0.0);
          const glm::dvec3 tangent = glm::normalize(glm::cross(helper, normal));
          const glm::dvec3 bitangent = glm::cross(normal, tangent);
          glm::dvec3 sum(0.0);
          for (const Sample& sample : samples) {
            const glm::dvec3 l = sample.l.x * tangent + sample.l.y * bitangent + sample.l.z * normal;
            CubeFace face;
            double s = 0.0;
            double t = 0.0;
            CubeFaceCoordinates(l, face, s, t);
            const int lo = static_cast<int>(sample.lod);
            const int hi = std::min(lo + 1, static_cast<int>(max_lod));
            const double frac = sample.lod - lo;
            glm::dvec3 value = Bilinear(pyramid[lo].face(face), s, t);
            if (frac > 0.0 && hi != lo) value = (1.0 - frac) * value + frac * Bilinear(pyramid[hi].face(face), s, t);
            sum += sample.weight * value;
          }
          const glm::dvec3 mean = sum / weight_sum;
          float* p = &out.faces[f].pixels[(static_cast<std::size_t>(j) * size + i) * 3];
          p[0] = static_cast<float>(mean.x);
          p[1] = static_cast<float>(mean.y);
          p[2] = static_cast<float>(mean.z);
        }
      }
    });
    levels.push_back(std::move(out));
  }
  return levels;
}

}  // namespace atmo
