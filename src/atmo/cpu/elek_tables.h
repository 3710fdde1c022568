// CPU evaluation of the elek tables (private): the per-texel kernels of src/atmo/shared/elek.glsl
// in an order that shares work, and the gather as a matrix product.
//
// Along the view ray of a texel (x, y) the nodes, media and view transmittances do not depend on
// the sun; only the sun transmittance (order 1) or the gather lookups (orders >= 2) do. So each
// (x, y) ray is prepared once and its D sun cosines are looped over inside, with the same
// arithmetic as the per-texel kernel (tests/elek_model_test.cc checks texels against it).
#pragma once

#include <vector>

#include "shared/shared.h"

namespace atmo::cpu {

// The factored scattering of one order (or of a gather), Rayleigh and Mie per channel.
struct ElekScattering {
  shared::Texture3D rayleigh;
  shared::Texture3D mie;

  ElekScattering() = default;
  ElekScattering(int w, int h, int d) : rayleigh(w, h, d), mie(w, h, d) {}
};

// The table grid and the ray integration.
struct ElekGrid {
  glm::ivec3 size{32, 256, 32};
  int mapping = shared::kElekMappingNonLinear;
  int steps = shared::kElekStepsQuadratic;
  int sample_count = 30;
};

// Order 1 (ComputeElekSingleScatteringTexel) into `out` (sized here).
void ComputeElekSingleScatteringTable(const shared::AtmosphereParameters& atmosphere,
                                      const shared::Texture2D& transmittance, const ElekGrid& grid,
                                      ElekScattering& out);

// Order k >= 2 (ComputeElekMultipleScatteringTexel) from the gather of order k - 1 for the two
// azimuth slices (the same tables twice where the gather has no azimuth).
void ComputeElekMultipleScatteringTable(const shared::AtmosphereParameters& atmosphere,
                                        const ElekScattering& gather_0, const ElekScattering& gather_pi,
                                        const ElekGrid& grid, ElekScattering& out);

// The gather matrix, gather_rows x rows entries (row-major), of ComputeElekGatherWeightTexel:
// x = Rayleigh, y = Mie. Each row is normalised to sum to 1 (see elek.glsl); `raw_row_sums`, when
// given, receives the sums before normalisation (the quadrature's own error).
std::vector<glm::dvec2> ComputeElekGatherMatrix(const shared::AtmosphereParameters& atmosphere, int mapping,
                                                int gather_rows, int rows, int point_count, int azimuth_count,
                                                std::vector<glm::dvec2>* raw_row_sums = nullptr);

// G_c[x, y, z] = sum_j M_c[y][j] I_c[x, j, z] with I_c = the order's component c (`coupled`:
// I_R + I_M for both, the light of either kind feeds both). `out` is sized here.
void ComputeElekGatherTable(const std::vector<glm::dvec2>& matrix, int gather_rows, const ElekScattering& order,
                            bool coupled, ElekScattering& out);

// The first gather with single scattering's own phase restored
// (ComputeElekPhaseGatherWeightTexel), for the two azimuth slices.
void ComputeElekPhaseGatherTables(const shared::AtmosphereParameters& atmosphere, int mapping, int gather_rows,
                                  const ElekScattering& single, bool coupled, int point_count, int azimuth_count,
                                  ElekScattering& out_0, ElekScattering& out_pi);

// The ground (option ground, elek.glsl "The ground"): the ground's irradiance per unit solar
// irradiance at the sun cosines of the grid's D slices, a D x 1 table: from the sun when `order`
// is null (E^(0)), from that order's table otherwise (E^(j)).
shared::Texture2D ComputeElekGroundIrradiance(const shared::AtmosphereParameters& atmosphere,
                                              const shared::Texture2D& transmittance, const ElekScattering* order,
                                              const ElekGrid& grid, int azimuth_count);

// L_g (ComputeElekGroundRadianceTexel) of every texel of the grid, from a ground irradiance table.
shared::Texture3D ComputeElekGroundRadianceTable(const shared::AtmosphereParameters& atmosphere,
                                                 const shared::Texture2D& transmittance,
                                                 const shared::Texture2D& ground_irradiance, const ElekGrid& grid);

// gather_c[x, y, z] += sum_j M_c[y][j] L_g[x, j, z]: the ground's light, gathered with the same
// (normalised) matrix as the air's, feeds both components (it has not scattered in the air yet).
void AddElekGatheredGround(const std::vector<glm::dvec2>& matrix, const shared::Texture3D& ground,
                           ElekScattering& gather);

}  // namespace atmo::cpu
