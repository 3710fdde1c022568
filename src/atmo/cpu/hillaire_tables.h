// CPU evaluation of the hillaire tables that shares work between texels (private).
//
// The per-texel kernels of src/atmo/shared (ComputeMultiScatteringTexel, ComputeSkyViewTexel,
// ComputeGroundIrradianceTexel) define the values; the GPU runs them as they are. On the CPU the
// same sums are evaluated in an order that does the sun-independent work of a ray once (the
// transmittance table, which has no such sharing, vectorises over its texels' samples instead):
// along a ray of fixed (r, mu) the positions, media, step transmittances and throughputs do not
// depend on the sun, only the transmittance to the sun and the multiple-scattering lookups do,
// which are summed in float as the tables are stored. Mirror symmetry about the sun's vertical
// plane halves the rest. tests/hillaire_tables_test.cc checks that every texel equals its
// per-texel kernel.
#pragma once

#include <span>

#include "shared/shared.h"

namespace atmo::cpu {

// Fills `table` (already sized) like shared::ComputeTransmittanceToTopAtmosphereBoundaryTexel: the
// same sample points and weights, with the density profiles evaluated for the samples of 16 texels
// at once in loops that the compiler vectorises (glibc's libmvec exp).
void ComputeTransmittanceTable(const shared::AtmosphereParameters& atmosphere, int sample_count,
                               shared::Texture2D& table);
// The same for several channel batches of one atmosphere (same geometry and density profiles,
// other coefficients: ToSharedParameters of each batch), tables[b] for batches[b], all sized
// alike: the density integrals along each texel's ray, which do not depend on the channels, are
// computed once for all batches.
void ComputeTransmittanceTables(std::span<const shared::AtmosphereParameters> batches, int sample_count,
                                std::span<shared::Texture2D* const> tables);

// Fills `table` (already sized) like shared::ComputeMultiScatteringTexel, in parallel over rows;
// with gathered_orders > 1, orders 2.. like shared::ComputeMultiScatteringGatherTexel over
// gather_direction_count directions (0: direction_count), then GetMultiScatteringFromOrders.
void ComputeMultipleScatteringTable(const shared::AtmosphereParameters& atmosphere,
                                    const shared::Texture2D& transmittance, int direction_count, int sample_count,
                                    bool media_phase, const glm::dvec3& ground_transfer, shared::Texture2D& table,
                                    int gathered_orders = 1, int gather_direction_count = 0);

// Fills `table` (already sized) like shared::ComputeSkyViewTexel for an observer at radius
// r <= top radius and a sun at zenith cosine mu_s, in parallel over rows.
void ComputeSkyViewTable(const shared::AtmosphereParameters& atmosphere, const shared::Texture2D& transmittance,
                         const shared::Texture2D& multiple_scattering, double r, double mu_s, int sample_count,
                         shared::Texture2D& table);

// Fills `table` (already sized, one row) like shared::ComputeGroundIrradianceTexel: each ray of the
// direction set from the ground is marched once, and each texel (a sun zenith) only sums its
// sun-dependent part; in parallel over directions.
void ComputeGroundIrradianceTable(const shared::AtmosphereParameters& atmosphere, const shared::Texture2D& transmittance,
                                  const shared::Texture2D& multiple_scattering, int direction_count, int sample_count,
                                  shared::Texture2D& table);

}  // namespace atmo::cpu
