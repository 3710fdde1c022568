// The tables of model source4d (shared/source4d.glsl, docs/models/source4d.md), built on the CPU
// order by order by gathering.
//
// For each node (r_i, theta_s_j) of the table's r and sun-zenith axes, the radiance of order n
// arriving from a fixed grid of directions (theta'_a uniform on [0, pi], azimuth phi'_b from the
// sun's uniform on [0, pi]; the field is mirror-symmetric about the sun's vertical plane) is
// integrated along each direction's ray:
//   L1    single scattering (shadow-split march) + the ground's reflection of the direct sun,
//   Ln    the march of J = sigma_R G_R^(n) + sigma_M G_M^(n) + the ground's reflection of E^(n-1),
// and the next order's phase-weighted radiance follows by a matrix product over the grid,
//   G_m^(n+1)(v_cd) = sum_ab W_m[cd][ab] L^(n)(w_ab),
// where W_m[cd][ab] is the phase function p_m(v_cd . w) integrated against the bilinear hat of
// node ab over the sphere (both mirror halves), by 4 x 4 sub-samples per cell, rows normalised
// to 1 (the phase function's integral). The ground irradiance E^(n)(theta_s_j) is the
// cosine-weighted integral of L^(n) at the ground node by the same hats. After the last order a
// geometric tail G^(N) q / (1 - q), q = G^(N) / G^(N-1) per node and channel (summed over
// directions; at most kSource4dMaxTailRatio), stands for the orders above N.
#pragma once

#include <functional>
#include <span>
#include <string_view>
#include <vector>

#include <glm/glm.hpp>

#include "shared/shared.h"

namespace atmo::cpu {

struct Source4dSettings {
  // The table: r layers, view zeniths, sun zeniths, azimuths.
  int r_size = 16;
  int mu_size = 24;
  int mu_s_size = 48;
  int phi_size = 8;
  // The gathering grid of incident directions (zenith nodes over [0, pi], azimuth nodes over
  // [0, pi]) and the steps of each gathering ray.
  int gather_zeniths = 97;
  int gather_azimuths = 9;
  int gather_samples = 24;
  // Orders computed explicitly (>= 2; the geometric tail adds the rest). 1: single scattering
  // alone (the tables hold 0; for validation).
  int orders = 5;
  bool tail = true;
  glm::ivec2 transmittance_lut{256, 64};
  int transmittance_samples = 200;
};

inline constexpr double kSource4dMaxTailRatio = 0.9;

struct Source4dTables {
  shared::Texture2D transmittance;
  shared::Texture3D rayleigh;           // ln G_R, orders >= 2
  shared::Texture3D mie;                // ln G_M
  shared::Texture2D ground_irradiance;  // E of the sky, orders >= 1 (not the direct sun), mu_s_size x 1
  int mu_s_size = 0;
};

// Builds the tables of one channel batch. `record(pass, ms)` receives each pass's time.
void ComputeSource4dTables(const shared::AtmosphereParameters& atmosphere, const Source4dSettings& settings,
                           Source4dTables& tables,
                           const std::function<void(std::string_view, double)>& record = {});
// The same for every channel batch of one atmosphere (ToSharedParameters of each batch), tables[b]
// for batches[b]: the transmittance tables in one pass and the quadrature once (they share the
// geometry, the density profiles and the phase functions), then each batch's orders. Each
// batch's tables equal those of the one-batch call.
void ComputeSource4dTables(std::span<const shared::AtmosphereParameters> batches, const Source4dSettings& settings,
                           std::span<Source4dTables* const> tables,
                           const std::function<void(std::string_view, double)>& record = {});

// Quadrature matrices of the gathering grid (exposed for tests): W[cd * in + ab] for the output
// directions of the table (cd = c * phi_size + d: view zenith c, azimuth d) and the gathering
// grid's nodes (ab = a * gather_azimuths + b), and the cosine-weighted weights of the upper
// hemisphere for the ground irradiance.
struct Source4dQuadrature {
  int out_count = 0;
  int in_count = 0;
  std::vector<float> rayleigh;  // out_count x in_count
  std::vector<float> mie;
  std::vector<double> irradiance;  // in_count
  // Where the Rayleigh phase function is A + B nu^2 (every kind the air's medium can have, whose
  // asymmetry the Rayleigh phase ignores; checked numerically), its matrix has rank 5 (the mirror pair's nu_1^2 + nu_2^2 is a sum of five products of a function
  // of the view and one of the node), and rayleigh[cd][ab] = sum_t rayleigh_out[cd][t]
  // rayleigh_in[t][ab] to float rounding: the products then cost 5 / out_count of the full
  // matrix's. Empty for other phase functions.
  std::vector<float> rayleigh_out;  // out_count x kSource4dRayleighRank
  std::vector<float> rayleigh_in;   // kSource4dRayleighRank x in_count
};
inline constexpr int kSource4dRayleighRank = 5;
// The radiance of one order on the gathering grid, values[ab * columns + (node * 3 + channel)],
// with `tables` as the order below (exposed for tests): order 1 from single scattering; order
// n >= 2 by marching `tables.rayleigh`/`mie` and reflecting `tables.ground_irradiance`, either
// by the general per-ray march (shared::IntegrateSource4dRadianceInside) or, with
// `shared_geometry`, by the paths that the builder uses, which do the sun-independent work once
// per ray (order 1: for the (sun node, azimuth) pairs without a shadow edge on the ray; orders
// >= 2: one 2D slice of the tables per step, float exp).
std::vector<float> GatherSource4dOrder(const shared::AtmosphereParameters& atmosphere, const Source4dSettings& settings,
                                       const Source4dTables& tables, int order, bool shared_geometry);

Source4dQuadrature ComputeSource4dQuadrature(const shared::AtmosphereParameters& atmosphere,
                                             const Source4dSettings& settings);
// Its irradiance weights alone (they depend on the gathering grid only): for the GPU builder,
// whose matrices are computed on the GPU (gl/source4d_gl.h).
std::vector<double> ComputeSource4dIrradianceWeights(const Source4dSettings& settings);

}  // namespace atmo::cpu
