#include "cpu/elek_tables.h"

#include <algorithm>
#include <cmath>

#include <oneapi/tbb/blocked_range.h>
#include <oneapi/tbb/parallel_for.h>

namespace atmo::cpu {
namespace {

using shared::ElekRayNode;
using shared::ivec3;
using shared::vec3;

template <typename Function>
void ParallelFor(int count, const Function& function) {
  oneapi::tbb::parallel_for(oneapi::tbb::blocked_range<int>(0, count),
                            [&](const oneapi::tbb::blocked_range<int>& range) {
                              for (int i = range.begin(); i < range.end(); ++i) function(i);
                            });
}

// The sun-independent part of the view ray of texel (x, y, *): its nodes and, per node, the view
// transmittance exp(-optical depth) evaluated exactly as in the per-texel kernels.
struct PreparedRay {
  double r = 0.0;
  double mu = 0.0;
  std::vector<ElekRayNode> nodes;
  std::vector<vec3> view;  // exp(-optical depth) from the observer to each node
};

void PrepareRay(const shared::AtmosphereParameters& atmosphere, const ElekGrid& grid, int x, int y, PreparedRay& ray) {
  double mu_s_unused;
  double t_max;
  shared::GetElekTexelRay(atmosphere, grid.mapping, grid.size, ivec3(x, y, 0), ray.r, ray.mu, mu_s_unused, t_max);
  const int n = grid.sample_count;
  ray.nodes.resize(n + 1);
  ray.view.resize(n + 1);
  vec3 optical_depth(0.0);
  ElekRayNode previous = shared::GetElekRayNode(atmosphere, grid.steps, ray.r, ray.mu, t_max, 0, n);
  for (int i = 0; i <= n; ++i) {
    const ElekRayNode node = shared::GetElekRayNode(atmosphere, grid.steps, ray.r, ray.mu, t_max, i, n);
    if (i > 0) optical_depth = shared::AccumulateElekOpticalDepth(optical_depth, previous, node);
    ray.nodes[i] = node;
    ray.view[i] = exp(-optical_depth);
    previous = node;
  }
}

// The sun cosine of slice z (its h and mu parts are unused).
double SunCosineOfSlice(const shared::AtmosphereParameters& atmosphere, const ElekGrid& grid, int z) {
  double h, mu, mu_s;
  shared::GetElekHMuMuSFromUvw(atmosphere, grid.mapping, shared::GetElekUvwFromTexel(grid.size, ivec3(0, 0, z)), h, mu,
                               mu_s);
  return mu_s;
}

// The w texture coordinate of a sun cosine: GetElekUvwFromHMuMuS's third component followed by
// GetTextureCoordFromUnitRange, with the C library's cbrt for the kernel's pow(|x|, 1/3) (they
// differ by an ulp; the tests compare tables with the kernels to float precision).
double SunTextureCoord(int mapping, double mu_s, int depth) {
  mu_s = shared::ClampCosine(mu_s);
  const double w = mapping == shared::kElekMappingLinear ? 0.5 * (mu_s + 1.0) : 0.5 * (1.0 + std::cbrt(mu_s));
  return shared::GetTextureCoordFromUnitRange(w, depth);
}

// shared::texture(t, (u, v, w)) is mix(plane(z0), plane(z1), wz) with plane(z) the bilinear
// blend of slice z at (u, v). A node's (u, v) does not depend on the sun, so its planes are
// blended once for every slice (`planes`, depth entries) and each sun cosine costs one mix: the
// same arithmetic as shared::texture.
void BlendPlanes(const shared::Texture3D& t, double u, double v, vec3* planes) {
  int x0, x1, y0, y1;
  double wx, wy;
  shared::detail::LinearTaps(u, t.width, false, x0, x1, wx);
  shared::detail::LinearTaps(v, t.height, false, y0, y1, wy);
  for (int z = 0; z < t.depth; ++z) {
    const vec3 p = glm::mix(vec3(t.at(x0, y0, z)), vec3(t.at(x1, y0, z)), wx);
    const vec3 q = glm::mix(vec3(t.at(x0, y1, z)), vec3(t.at(x1, y1, z)), wx);
    planes[z] = glm::mix(p, q, wy);
  }
}

vec3 BlendSlices(const vec3* planes, int depth, double w) {
  int z0, z1;
  double wz;
  shared::detail::LinearTaps(w, depth, false, z0, z1, wz);
  return glm::mix(planes[z0], planes[z1], wz);
}

// Stores a value as float, flushing what would be a subnormal float (< 1e-30, far below any
// visible radiance) to 0 so that later passes never compute with subnormals.
void Store(shared::Texture3D& table, int x, int y, int z, const vec3& value) {
  const vec3 flushed = glm::mix(value, vec3(0.0), glm::lessThan(glm::abs(value), vec3(1e-30)));
  table.at(x, y, z) = glm::vec3(flushed);
}

}  // namespace

void ComputeElekSingleScatteringTable(const shared::AtmosphereParameters& atmosphere,
                                      const shared::Texture2D& transmittance, const ElekGrid& grid,
                                      ElekScattering& out) {
  const glm::ivec3 size = grid.size;
  out = ElekScattering(size.x, size.y, size.z);
  std::vector<double> mu_s_of_slice(size.z);
  for (int z = 0; z < size.z; ++z) mu_s_of_slice[z] = SunCosineOfSlice(atmosphere, grid, z);
  ParallelFor(size.y, [&](int y) {
    PreparedRay ray;
    for (int x = 0; x < size.x; ++x) {
      PrepareRay(atmosphere, grid, x, y, ray);
      for (int z = 0; z < size.z; ++z) {
        const double mu_s = mu_s_of_slice[z];
        const double nu = shared::GetElekCanonicalNu(ray.mu, mu_s);
        vec3 rayleigh_sum(0.0);
        vec3 mie_sum(0.0);
        for (int i = 0; i <= grid.sample_count; ++i) {
          const ElekRayNode& node = ray.nodes[i];
          const vec3 sun = shared::GetTransmittanceToSun(atmosphere, transmittance, node.r,
                                                         shared::GetElekNodeSunCosine(ray.r, mu_s, nu, node));
          const vec3 light = sun * ray.view[i] * node.weight;
          rayleigh_sum += light * node.densities.x;
          mie_sum += light * node.densities.y;
        }
        Store(out.rayleigh, x, y, z, rayleigh_sum * atmosphere.rayleigh_scattering);
        Store(out.mie, x, y, z, mie_sum * atmosphere.mie_scattering);
      }
    }
  });
}

void ComputeElekMultipleScatteringTable(const shared::AtmosphereParameters& atmosphere,
                                        const ElekScattering& gather_0, const ElekScattering& gather_pi,
                                        const ElekGrid& grid, ElekScattering& out) {
  const glm::ivec3 size = grid.size;
  const ivec3 gather_size = shared::textureSize(gather_0.rayleigh, 0);
  const bool one_slice = &gather_0 == &gather_pi;
  out = ElekScattering(size.x, size.y, size.z);
  std::vector<double> mu_s_of_slice(size.z);
  for (int z = 0; z < size.z; ++z) mu_s_of_slice[z] = SunCosineOfSlice(atmosphere, grid, z);
  ParallelFor(size.y, [&](int y) {
    PreparedRay ray;
    std::vector<vec3> view_weight;
    const int n = grid.sample_count;
    const int slices = one_slice ? 1 : 2;
    const std::size_t depth = static_cast<std::size_t>(gather_size.z);
    // planes[((slice * 2 + component) * (n + 1) + node) * depth + z]
    std::vector<vec3> planes(static_cast<std::size_t>(slices) * 2 * (n + 1) * depth);
    const auto plane_of = [&](int slice, int component, int node) {
      return &planes[((static_cast<std::size_t>(slice) * 2 + component) * (n + 1) + node) * depth];
    };
    for (int x = 0; x < size.x; ++x) {
      PrepareRay(atmosphere, grid, x, y, ray);
      view_weight.resize(n + 1);
      // The h and mu texture coordinates of each node's gather lookup do not depend on the sun;
      // each component of GetElekUvwFromHMuMuS / GetElekTextureCoordFromUvw is computed alone, so
      // splitting them gives the kernel's values exactly.
      for (int i = 0; i <= n; ++i) {
        const ElekRayNode& node = ray.nodes[i];
        view_weight[i] = ray.view[i] * node.weight;
        const vec3 uvw = shared::GetElekUvwFromHMuMuS(atmosphere, grid.mapping, node.r - atmosphere.bottom_radius,
                                                      node.mu, 0.0);
        const vec3 coord = shared::GetElekTextureCoordFromUvw(gather_size, uvw);
        for (int slice = 0; slice < slices; ++slice) {
          const ElekScattering& gather = slice == 0 ? gather_0 : gather_pi;
          BlendPlanes(gather.rayleigh, coord.x, coord.y, plane_of(slice, 0, i));
          BlendPlanes(gather.mie, coord.x, coord.y, plane_of(slice, 1, i));
        }
      }
      for (int z = 0; z < size.z; ++z) {
        const double mu_s = mu_s_of_slice[z];
        const double nu = shared::GetElekCanonicalNu(ray.mu, mu_s);
        vec3 rayleigh_sum(0.0);
        vec3 mie_sum(0.0);
        for (int i = 0; i <= n; ++i) {
          const ElekRayNode& node = ray.nodes[i];
          const double mu_s_i = shared::GetElekNodeSunCosine(ray.r, mu_s, nu, node);
          const int slice = one_slice || nu - node.mu * mu_s_i >= 0.0 ? 0 : 1;
          const double w = SunTextureCoord(grid.mapping, mu_s_i, gather_size.z);
          const vec3 g_r = BlendSlices(plane_of(slice, 0, i), gather_size.z, w);
          const vec3 g_m = BlendSlices(plane_of(slice, 1, i), gather_size.z, w);
          rayleigh_sum += g_r * view_weight[i] * node.densities.x;
          mie_sum += g_m * view_weight[i] * node.densities.y;
        }
        Store(out.rayleigh, x, y, z, rayleigh_sum * atmosphere.rayleigh_scattering);
        Store(out.mie, x, y, z, mie_sum * atmosphere.mie_scattering);
      }
    }
  });
}

std::vector<glm::dvec2> ComputeElekGatherMatrix(const shared::AtmosphereParameters& atmosphere, int mapping,
                                                int gather_rows, int rows, int point_count, int azimuth_count,
                                                std::vector<glm::dvec2>* raw_row_sums) {
  std::vector<glm::dvec2> matrix(static_cast<std::size_t>(gather_rows) * rows);
  if (raw_row_sums != nullptr) raw_row_sums->assign(gather_rows, glm::dvec2(0.0));
  // The sums of ComputeElekGatherWeightTexel, with each quadrature point's azimuth-integrated
  // phases evaluated once for the two rows it weighs (the kernel evaluates them once per row).
  ParallelFor(gather_rows, [&](int y) {
    glm::dvec2* row = &matrix[static_cast<std::size_t>(y) * rows];
    const double mu_v = shared::GetElekMuFromV(mapping, double(y) / double(gather_rows - 1));
    const double dv = 1.0 / double(rows - 1);
    for (int first = 0; first < rows - 1; ++first) {
      for (int q = 0; q < point_count; ++q) {
        const double s = shared::GetElekGaussNode(point_count, q);
        const double v = (double(first) + s) * dv;
        const double w = shared::GetElekGaussWeight(point_count, q) * dv * shared::GetElekMuDerivative(mapping, v);
        const double mu_w = shared::GetElekMuFromV(mapping, v);
        const glm::dvec2 k(
            shared::GetElekAzimuthIntegratedPhase(atmosphere, atmosphere.rayleigh_phase, 0.0, mu_v, mu_w, azimuth_count),
            shared::GetElekAzimuthIntegratedPhase(atmosphere, atmosphere.mie_phase, atmosphere.mie_g, mu_v, mu_w, azimuth_count));
        row[first] += (w * (1.0 - s)) * k;
        row[first + 1] += (w * s) * k;
      }
    }
    glm::dvec2 sum(0.0);
    for (int j = 0; j < rows; ++j) sum += row[j];
    if (raw_row_sums != nullptr) (*raw_row_sums)[y] = sum;
    for (int j = 0; j < rows; ++j) matrix[static_cast<std::size_t>(y) * rows + j] /= sum;
  });
  return matrix;
}

void ComputeElekGatherTable(const std::vector<glm::dvec2>& matrix, int gather_rows, const ElekScattering& order,
                            bool coupled, ElekScattering& out) {
  const int w = order.rayleigh.width;
  const int rows = order.rayleigh.height;
  const int d = order.rayleigh.depth;
  out = ElekScattering(w, gather_rows, d);
  ParallelFor(d * gather_rows, [&](int index) {
    const int z = index / gather_rows;
    const int y = index % gather_rows;
    // Sums in double: float products of small weights and dim texels would be subnormal (slow).
    std::vector<glm::dvec3> r_sum(w, glm::dvec3(0.0)), m_sum(w, glm::dvec3(0.0));
    for (int j = 0; j < rows; ++j) {
      const glm::dvec2 m = matrix[static_cast<std::size_t>(y) * rows + j];
      const double m_r = m.x;
      const double m_m = m.y;
      for (int x = 0; x < w; ++x) {
        const glm::dvec3 i_r = order.rayleigh.at(x, j, z);
        const glm::dvec3 i_m = order.mie.at(x, j, z);
        if (coupled) {
          r_sum[x] += m_r * (i_r + i_m);
          m_sum[x] += m_m * (i_r + i_m);
        } else {
          r_sum[x] += m_r * i_r;
          m_sum[x] += m_m * i_m;
        }
      }
    }
    for (int x = 0; x < w; ++x) {
      Store(out.rayleigh, x, y, z, r_sum[x]);
      Store(out.mie, x, y, z, m_sum[x]);
    }
  });
}

void ComputeElekPhaseGatherTables(const shared::AtmosphereParameters& atmosphere, int mapping, int gather_rows,
                                  const ElekScattering& single, bool coupled, int point_count, int azimuth_count,
                                  ElekScattering& out_0, ElekScattering& out_pi) {
  const int w = single.rayleigh.width;
  const int rows = single.rayleigh.height;
  const int d = single.rayleigh.depth;
  out_0 = ElekScattering(w, gather_rows, d);
  out_pi = ElekScattering(w, gather_rows, d);
  const glm::ivec3 size(w, rows, d);
  ParallelFor(2 * d * gather_rows, [&](int index) {
    const int slice = index / (d * gather_rows);
    const int z = (index / gather_rows) % d;
    const int y = index % gather_rows;
    double h, mu, mu_s;
    shared::GetElekHMuMuSFromUvw(atmosphere, mapping, shared::GetElekUvwFromTexel(size, ivec3(0, 0, z)), h, mu, mu_s);
    std::vector<glm::dvec3> r_sum(w, glm::dvec3(0.0)), m_sum(w, glm::dvec3(0.0));
    for (int j = 0; j < rows; ++j) {
      // (RR, RM, MR, MM): gather phase first, restored phase second.
      const glm::dvec4 k = shared::ComputeElekPhaseGatherWeightTexel(atmosphere, mapping, gather_rows, rows, y, j, mu_s,
                                                                     slice == 1, point_count, azimuth_count);
      for (int x = 0; x < w; ++x) {
        const glm::dvec3 i_r = single.rayleigh.at(x, j, z);
        const glm::dvec3 i_m = single.mie.at(x, j, z);
        if (coupled) {
          r_sum[x] += k.x * i_r + k.y * i_m;
          m_sum[x] += k.z * i_r + k.w * i_m;
        } else {
          r_sum[x] += k.x * i_r;
          m_sum[x] += k.w * i_m;
        }
      }
    }
    ElekScattering& out = slice == 0 ? out_0 : out_pi;
    for (int x = 0; x < w; ++x) {
      Store(out.rayleigh, x, y, z, r_sum[x]);
      Store(out.mie, x, y, z, m_sum[x]);
    }
  });
}

shared::Texture2D ComputeElekGroundIrradiance(const shared::AtmosphereParameters& atmosphere,
                                              const shared::Texture2D& transmittance, const ElekScattering* order,
                                              const ElekGrid& grid, int azimuth_count) {
  const int depth = grid.size.z;
  shared::Texture2D table(depth, 1);
  ParallelFor(depth, [&](int z) {
    const double mu_s = SunCosineOfSlice(atmosphere, grid, z);
    const vec3 e = order == nullptr
                       ? shared::ComputeElekGroundDirectIrradiance(atmosphere, transmittance, mu_s)
                       : shared::ComputeElekGroundSkyIrradiance(atmosphere, order->rayleigh, order->mie, grid.mapping,
                                                                mu_s, shared::kElekGroundIntervals, azimuth_count);
    table.at(z, 0) = glm::vec3(e);
  });
  return table;
}

shared::Texture3D ComputeElekGroundRadianceTable(const shared::AtmosphereParameters& atmosphere,
                                                 const shared::Texture2D& transmittance,
                                                 const shared::Texture2D& ground_irradiance, const ElekGrid& grid) {
  const glm::ivec3 size = grid.size;
  shared::Texture3D table(size.x, size.y, size.z);
  ParallelFor(size.y, [&](int y) {
    for (int z = 0; z < size.z; ++z) {
      for (int x = 0; x < size.x; ++x) {
        const vec3 l = shared::ComputeElekGroundRadianceTexel(atmosphere, transmittance, ground_irradiance, grid.mapping,
                                                              ivec3(size.x, size.y, size.z), ivec3(x, y, z));
        Store(table, x, y, z, l);
      }
    }
  });
  return table;
}

void AddElekGatheredGround(const std::vector<glm::dvec2>& matrix, const shared::Texture3D& ground,
                           ElekScattering& gather) {
  const int w = ground.width;
  const int rows = ground.height;
  const int d = ground.depth;
  const int gather_rows = gather.rayleigh.height;
  ParallelFor(d * gather_rows, [&](int index) {
    const int z = index / gather_rows;
    const int y = index % gather_rows;
    std::vector<glm::dvec3> r_sum(w, glm::dvec3(0.0)), m_sum(w, glm::dvec3(0.0));
    for (int j = 0; j < rows; ++j) {
      const glm::dvec2 m = matrix[static_cast<std::size_t>(y) * rows + j];
      for (int x = 0; x < w; ++x) {
        const glm::dvec3 l = ground.at(x, j, z);
        r_sum[x] += m.x * l;
        m_sum[x] += m.y * l;
      }
    }
    for (int x = 0; x < w; ++x) {
      Store(gather.rayleigh, x, y, z, glm::dvec3(gather.rayleigh.at(x, y, z)) + r_sum[x]);
      Store(gather.mie, x, y, z, glm::dvec3(gather.mie.at(x, y, z)) + m_sum[x]);
    }
  });
}

}  // namespace atmo::cpu
