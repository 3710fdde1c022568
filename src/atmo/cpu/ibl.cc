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
std::vector<double> FaceSolidAngles(int n) { return CubeFaceSolidAngles(n); }

glm::dvec3 TexelDirection(int face, int n, int i, int j) {
  return CubeFaceDirection(static_cast<CubeFace>(face), (i + 0.5) / n, (j + 0.5) / n);
}

// A cube of `size` texels per face, 3 channels in `colour_space`: fill(direction, rgb) sets each
// texel from its centre's direction, in parallel over the rows of all faces.
template <typename Fill>
Cubemap FillCubemap(int size, ColourSpace colour_space, const Fill& fill) {
  Cubemap out(size, 3);
  for (Image& face : out.faces) face.colour_space = colour_space;
  oneapi::tbb::parallel_for(oneapi::tbb::blocked_range<int>(0, kCubeFaceCount * size), [&](const auto& rows) {
    for (int row = rows.begin(); row < rows.end(); ++row) {
      const int f = row / size;
      const int j = row % size;
      for (int i = 0; i < size; ++i) {
        fill(TexelDirection(f, size, i, j), &out.faces[f].pixels[(static_cast<std::size_t>(j) * size + i) * 3]);
      }
    }
  });
  return out;
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

// Adds weight x the bilinear value at (s, t) (clamped at the face's edges) to acc[0..2], in float.
inline void AccumulateBilinear(const Image& face, float s, float t, float weight, float* acc) {
  const int n = face.width;
  const float x = std::clamp(s * n - 0.5f, 0.0f, static_cast<float>(n - 1));
  const float y = std::clamp(t * n - 0.5f, 0.0f, static_cast<float>(n - 1));
  const int x0 = std::min(static_cast<int>(x), n - 1);
  const int y0 = std::min(static_cast<int>(y), n - 1);
  const int x1 = std::min(x0 + 1, n - 1);
  const int y1 = std::min(y0 + 1, n - 1);
  const float fx = x - x0;
  const float fy = y - y0;
  const float w00 = weight * (1.0f - fx) * (1.0f - fy);
  const float w10 = weight * fx * (1.0f - fy);
  const float w01 = weight * (1.0f - fx) * fy;
  const float w11 = weight * fx * fy;
  const float* p00 = &face.pixels[(static_cast<std::size_t>(y0) * n + x0) * 3];
  const float* p10 = &face.pixels[(static_cast<std::size_t>(y0) * n + x1) * 3];
  const float* p01 = &face.pixels[(static_cast<std::size_t>(y1) * n + x0) * 3];
  const float* p11 = &face.pixels[(static_cast<std::size_t>(y1) * n + x1) * 3];
  for (int c = 0; c < 3; ++c) acc[c] += w00 * p00[c] + w10 * p10[c] + w01 * p01[c] + w11 * p11[c];
}

// CubeFaceCoordinates in float, for the specular prefilter's inner loop (the same table).
inline int FaceCoordinates(float x, float y, float z, float& s, float& t) {
  const float ax = std::abs(x);
  const float ay = std::abs(y);
  const float az = std::abs(z);
  int face = 0;
  float a = 0.0f;
  float b = 0.0f;
  if (ax >= ay && ax >= az) {
    const float inv = 1.0f / ax;
    face = x > 0.0f ? 0 : 1;
    a = (x > 0.0f ? -z : z) * inv;
    b = -y * inv;
  } else if (ay >= az) {
    const float inv = 1.0f / ay;
    face = y > 0.0f ? 2 : 3;
    a = x * inv;
    b = (y > 0.0f ? z : -z) * inv;
  } else {
    const float inv = 1.0f / az;
    face = z > 0.0f ? 4 : 5;
    a = (z > 0.0f ? x : -x) * inv;
    b = -y * inv;
  }
  s = 0.5f * (a + 1.0f);
  t = 0.5f * (b + 1.0f);
  return face;
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
  std::array<double, kCubeFaceCount> kernel{};
  oneapi::tbb::parallel_for(0, kCubeFaceCount, [&](int f) {
    glm::dvec3 sum(0.0);
    double weight = 0.0;
    for (int j = 0; j < n; ++j) {
      for (int i = 0; i < n; ++i) {
        const double c = glm::dot(normal, TexelDirection(f, n, i, j));
        if (c > 0.0) {
          const double w = c * omega[static_cast<std::size_t>(j) * n + i];
          sum += Texel(radiance.faces[f], i, j) * w;
          weight += w;
        }
      }
    }
    partial[f] = sum;
    kernel[f] = weight;
  });
  glm::dvec3 sum(0.0);
  double weight = 0.0;
  for (int f = 0; f < kCubeFaceCount; ++f) {
    sum += partial[f];
    weight += kernel[f];
  }
  // The kernel's texel-centre quadrature, normalised to its exact integral pi (IrradianceCubemap).
  return sum * (kPi / weight);
}

Cubemap IrradianceCubemap(const Cubemap& radiance, int size, int source_size) {
  CheckColourCube(radiance, "an irradiance cube map");
  if (size < 1 || size > kMaxImageSide || source_size < 1) throw Error("irradiance cube sizes must be at least 1");
  const Cubemap source = Resized(radiance, source_size);
  const int m = source.face_size;
  // The source as flat arrays: direction, and L dOmega per texel.
  const std::size_t count = static_cast<std::size_t>(kCubeFaceCount) * m * m;
  std::vector<float> dx(count), dy(count), dz(count), lr(count), lg(count), lb(count), w(count);
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
        w[k] = static_cast<float>(omega[static_cast<std::size_t>(j) * m + i]);
      }
    }
  }
  // Bands of 4 source rows (contiguous in the arrays), with the face-plane corners of each.
  struct Band {
    std::size_t begin, end;
    std::array<glm::dvec3, 4> corners;
  };
  std::vector<Band> bands;
  constexpr int kBandRows = 4;
  for (int f = 0; f < kCubeFaceCount; ++f) {
    for (int j0 = 0; j0 < m; j0 += kBandRows) {
      const int j1 = std::min(m, j0 + kBandRows);
      const CubeFace face = static_cast<CubeFace>(f);
      const double t0 = static_cast<double>(j0) / m;
      const double t1 = static_cast<double>(j1) / m;
      bands.push_back({(static_cast<std::size_t>(f) * m + j0) * m, (static_cast<std::size_t>(f) * m + j1) * m,
                       {CubeFaceDirection(face, 0.0, t0), CubeFaceDirection(face, 1.0, t0), CubeFaceDirection(face, 0.0, t1),
                        CubeFaceDirection(face, 1.0, t1)}});
    }
  }
  return FillCubemap(size, radiance.faces[0].colour_space, [&](const glm::dvec3& normal, float* p) {
    const float nx = static_cast<float>(normal.x);
    const float ny = static_cast<float>(normal.y);
    const float nz = static_cast<float>(normal.z);
    // The texel-centre quadrature of the kernel, sum of max(n.w, 0) dOmega, misses its exact
    // integral pi by O(texel^2) (the kink at n.w = 0 most): dividing by it and multiplying by
    // pi makes the weights integrate exactly, so a constant sky gives pi L to rounding.
    // Float sums of 6 x 32^2 terms: ~1e-6 relative, far below what the tests ask. Bands of
    // source rows wholly behind the normal are skipped: n.d is linear in the (unnormalised)
    // face-plane direction d, so its largest value over a band is at one of its corners.
    float r = 0.0f, g = 0.0f, b = 0.0f, kernel = 0.0f;
    for (const Band& band : bands) {
      bool seen = false;
      for (const glm::dvec3& corner : band.corners) seen = seen || glm::dot(normal, corner) > 0.0;
      if (!seen) continue;
      const float* bx = dx.data();
      const float* by = dy.data();
      const float* bz = dz.data();
      const float* br = lr.data();
      const float* bg = lg.data();
      const float* bb = lb.data();
      const float* bw = w.data();
#pragma omp simd reduction(+ : r, g, b, kernel)
      for (std::size_t k = band.begin; k < band.end; ++k) {
        const float c = std::max(nx * bx[k] + ny * by[k] + nz * bz[k], 0.0f);
        r += c * br[k];
        g += c * bg[k];
        b += c * bb[k];
        kernel += c * bw[k];
      }
    }
    const float scale = static_cast<float>(kPi) / kernel;
    p[0] = r * scale;
    p[1] = g * scale;
    p[2] = b * scale;
  });
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
    // A sample: its direction in the tangent frame, and its weight n.l split between the two
    // pyramid levels around its lod (trilinear).
    struct Sample {
      glm::vec3 l;
      int lo, hi;
      float weight_lo, weight_hi;
    };
    std::vector<Sample> samples;
    double weight_sum = 0.0;
    // Fewer samples for narrower lobes: with filtered importance sampling each sample reads a mip
    // texel of about its share of the lobe (Omega_s), so the lobe is covered at any count; the
    // count only sets how finely its shape is resolved, and a lobe of roughness r spans ~r of the
    // widest one. K = max(8, round(samples r)), the full count at roughness 1.
    const int count = std::max(std::min(8, settings.samples), static_cast<int>(std::lround(settings.samples * roughness)));
    for (int k = 0; k < count; ++k) {
      const double u = (k + 0.5) / count;
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
      const double sample_solid_angle = 1.0 / (count * pdf);
      const double lod = std::clamp(0.5 * std::log2(sample_solid_angle / texel_solid_angle) + settings.lod_bias, 0.0, max_lod);
      const int lo = static_cast<int>(lod);
      const int hi = std::min(lo + 1, static_cast<int>(max_lod));
      const double frac = hi == lo ? 0.0 : lod - lo;
      samples.push_back({glm::vec3(l), lo, hi, static_cast<float>(l.z * (1.0 - frac)), static_cast<float>(l.z * frac)});
      weight_sum += l.z;
    }
    const int size = std::max(1, n >> m);
    levels.push_back(FillCubemap(size, radiance.faces[0].colour_space, [&](const glm::dvec3& normal, float* p) {
      const glm::dvec3 helper = std::abs(normal.y) < 0.999 ? glm::dvec3(0.0, 1.0, 0.0) : glm::dvec3(1.0, 0.0, 0.0);
      const glm::dvec3 tangent = glm::normalize(glm::cross(helper, normal));
      const glm::dvec3 bitangent = glm::cross(normal, tangent);
      const glm::vec3 tf(tangent);
      const glm::vec3 bf(bitangent);
      const glm::vec3 nf(normal);
      float acc[3] = {0.0f, 0.0f, 0.0f};
      for (const Sample& sample : samples) {
        const glm::vec3 l = sample.l.x * tf + sample.l.y * bf + sample.l.z * nf;
        float s = 0.0f;
        float t = 0.0f;
        const int face = FaceCoordinates(l.x, l.y, l.z, s, t);
        AccumulateBilinear(pyramid[sample.lo].faces[face], s, t, sample.weight_lo, acc);
        if (sample.weight_hi > 0.0f) AccumulateBilinear(pyramid[sample.hi].faces[face], s, t, sample.weight_hi, acc);
      }
      const glm::dvec3 sum(acc[0], acc[1], acc[2]);
      const glm::dvec3 mean = sum / weight_sum;
      p[0] = static_cast<float>(mean.x);
      p[1] = static_cast<float>(mean.y);
      p[2] = static_cast<float>(mean.z);
    }));
  }
  return levels;
}

}  // namespace atmo
