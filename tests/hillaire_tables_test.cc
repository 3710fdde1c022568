// The CPU's row-sharing evaluation of the hillaire tables equals the shared per-texel kernels
// that define them (and that the GPU runs as they are).
#include <cmath>

#include <gtest/gtest.h>

#include "cpu/hillaire_tables.h"
#include "shared/shared.h"
#include "test_atmospheres.h"

namespace atmo::cpu {
namespace {

using shared::ivec2;
using shared::Texture2D;
using shared::vec2;

Texture2D TransmittanceTable(const shared::AtmosphereParameters& a) {
  Texture2D t(64, 16);
  for (int y = 0; y < t.height; ++y) {
    for (int x = 0; x < t.width; ++x) {
      t.at(x, y) = glm::vec3(shared::ComputeTransmittanceToTopAtmosphereBoundaryTexel(a, ivec2(64, 16), vec2(x + 0.5, y + 0.5), 40));
    }
  }
  return t;
}

// Float storage of the tables bounds the agreement: a few float ulps. The sky-view rows read the
// multiple-scattering table, which holds ln(Psi_ms): a float ulp of a logarithm near -20 is 2e-6
// of Psi_ms, hence their looser `relative`.
void ExpectSameTexel(const glm::vec3& fast, const glm::dvec3& reference, int x, int y, double relative = 1e-6) {
  for (int c = 0; c < 3; ++c) {
    EXPECT_NEAR(fast[c], reference[c], relative * std::abs(reference[c]) + 1e-30) << "texel " << x << "," << y;
  }
}

TEST(HillaireTables, VectorisedTransmittanceEqualsPerTexelKernel) {
  // Same sample points and weights; libmvec's exp (<= 4 ulp) and the vector sums' order differ.
  for (const shared::AtmosphereParameters& a : {testing::EarthLike(), testing::SmallHomogeneous()}) {
    for (int samples : {1, 7, 40}) {
      Texture2D table(32, 12);
      ComputeTransmittanceTable(a, samples, table);
      for (int y = 0; y < table.height; ++y) {
        for (int x = 0; x < table.width; ++x) {
          ExpectSameTexel(table.at(x, y),
                          shared::ComputeTransmittanceToTopAtmosphereBoundaryTexel(a, ivec2(32, 12), vec2(x + 0.5, y + 0.5), samples),
                          x, y);
        }
      }
    }
  }
}

TEST(HillaireTables, MultipleScatteringRowsEqualPerTexelKernel) {
  const shared::AtmosphereParameters a = testing::EarthLike();
  const Texture2D transmittance = TransmittanceTable(a);
  for (int directions : {2, 16, 30}) {  // the seed's pair and two lattices
    for (bool media_phase : {false, true}) {
      const glm::dvec3 ground_transfer = media_phase ? shared::GetGroundTransfer(a, 8, 10) : glm::dvec3(0.0);
      Texture2D table(8, 6);
      ComputeMultipleScatteringTable(a, transmittance, directions, 12, media_phase, ground_transfer, table);
      for (int y = 0; y < table.height; ++y) {
        for (int x = 0; x < table.width; ++x) {
          ExpectSameTexel(table.at(x, y),
                          shared::ComputeMultiScatteringTexel(a, transmittance, ivec2(8, 6), vec2(x + 0.5, y + 0.5),
                                                              directions, 12, media_phase, ground_transfer),
                          x, y);
        }
      }
    }
  }
}

TEST(HillaireTables, SkyViewRowsEqualPerTexelKernel) {
  const shared::AtmosphereParameters a = testing::EarthLike();
  const Texture2D transmittance = TransmittanceTable(a);
  Texture2D multiple_scattering(8, 8);
  ComputeMultipleScatteringTable(a, transmittance, 16, 10, false, glm::dvec3(0.0), multiple_scattering);
  for (double altitude : {0.0, 1500.0, 60e3}) {
    for (double mu_s : {0.9, 0.05, -0.2}) {
      for (int width : {12, 13}) {  // even and odd: the mirrored columns
        Texture2D table(width, 10, true);  // the height must be even (sky and ground halves)
        const double r = a.bottom_radius + altitude;
        ComputeSkyViewTable(a, transmittance, multiple_scattering, r, mu_s, 16, table);
        for (int y = 0; y < table.height; ++y) {
          for (int x = 0; x < table.width; ++x) {
            ExpectSameTexel(table.at(x, y),
                            shared::ComputeSkyViewTexel(a, transmittance, multiple_scattering, ivec2(width, 10),
                                                        vec2(x + 0.5, y + 0.5), r, mu_s, 16),
                            x, y, 1e-5);
          }
        }
      }
    }
  }
}

}  // namespace
}  // namespace atmo::cpu
