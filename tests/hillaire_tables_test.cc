// The CPU's row-sharing evaluation of the hillaire tables equals the shared per-texel kernels
// that define them (and that the GPU runs as they are).
#include <algorithm>
#include <cmath>
#include <cstdio>
#include <vector>

#include <gtest/gtest.h>

#include "atmo/aerosol.h"
#include "atmo/parameters.h"
#include "cpu/hillaire_tables.h"
#include "physics/shared_parameters.h"
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

// The density-table path (us-standard's air, and OPAC's layered aerosol of a haze request): the
// table's exp is in float, so each sample's density carries a relative error of a few 1e-7 (the
// table itself approximates a profile to 2e-4, DensityTable's tests), and a texel's transmittance
// one of that times its optical depth.
TEST(HillaireTables, TabulatedTransmittanceEqualsPerTexelKernel) {
  AtmosphereParameters hazy = Preset("earth");
  AerosolSettings haze;
  haze.aod_550 = 0.2;
  ApplyAerosol(hazy, haze);
  for (const AtmosphereParameters& p : {Preset("us-standard"), hazy}) {
    const shared::AtmosphereParameters a = ToSharedParameters(p, 0);
    ASSERT_EQ(a.density_table_enabled, 1) << p.name;
    Texture2D table(32, 12);
    ComputeTransmittanceTable(a, 40, table);
    double worst = 0.0;
    for (int y = 0; y < table.height; ++y) {
      for (int x = 0; x < table.width; ++x) {
        const glm::dvec3 reference =
            shared::ComputeTransmittanceToTopAtmosphereBoundaryTexel(a, ivec2(32, 12), vec2(x + 0.5, y + 0.5), 40);
        for (int c = 0; c < 3; ++c) {
          const double optical_depth = -std::log(std::max(reference[c], 1e-300));
          const double error = std::abs(table.at(x, y)[c] - reference[c]) / reference[c];
          EXPECT_LE(error, 2e-7 * (1.0 + optical_depth)) << p.name << " texel " << x << "," << y << " channel " << c;
          worst = std::max(worst, error / (1.0 + optical_depth));
        }
      }
    }
    std::printf("%s: largest relative error / (1 + optical depth) %.2e\n", p.name.c_str(), worst);
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

// The gathered orders (multiple_scattering_orders > 1) from the per-texel kernels, order by
// order through float tables as a GPU keeps them: order 1's Psi, f_ms and ground irradiance, then
// each order from the previous one's tables, then GetMultiScatteringFromOrders.
Texture2D GatheredTableFromKernels(const shared::AtmosphereParameters& a, const Texture2D& transmittance, ivec2 size,
                                   int directions, int samples, const glm::dvec3& ground_transfer, int orders) {
  std::vector<glm::dvec3> sum(size.x * size.y), f(size.x * size.y), last(size.x * size.y);
  Texture2D order(size.x, size.y), ground(size.x, 1);
  for (int y = 0; y < size.y; ++y) {
    for (int x = 0; x < size.x; ++x) {
      glm::dvec3 psi, f_ms, irradiance;
      shared::ComputeMultiScatteringFirstOrderTexel(a, transmittance, size, vec2(x + 0.5, y + 0.5), directions, samples,
                                                    false, ground_transfer, psi, f_ms, irradiance);
      sum[y * size.x + x] = last[y * size.x + x] = psi;
      f[y * size.x + x] = f_ms;
      if (y == 0) ground.at(x, 0) = glm::vec3(shared::EncodeMultiScattering(irradiance));
    }
  }
  for (int n = 2; n <= orders; ++n) {
    for (int k = 0; k < size.x * size.y; ++k) order.texels[k] = glm::vec3(shared::EncodeMultiScattering(last[k]));
    Texture2D next_ground(size.x, 1);
    for (int y = 0; y < size.y; ++y) {
      for (int x = 0; x < size.x; ++x) {
        glm::dvec3 psi, irradiance;
        shared::ComputeMultiScatteringGatherTexel(a, order, ground, size, vec2(x + 0.5, y + 0.5), directions, samples,
                                                  psi, irradiance);
        sum[y * size.x + x] += psi;
        last[y * size.x + x] = psi;
        if (y == 0) next_ground.at(x, 0) = glm::vec3(shared::EncodeMultiScattering(irradiance));
      }
    }
    ground = next_ground;
  }
  Texture2D table(size.x, size.y);
  for (int k = 0; k < size.x * size.y; ++k) {
    table.texels[k] = glm::vec3(shared::EncodeMultiScattering(shared::GetMultiScatteringFromOrders(sum[k], last[k], f[k])));
  }
  return table;
}

TEST(HillaireTables, GatheredOrdersEqualThePerTexelKernels) {
  const shared::AtmosphereParameters a = testing::EarthLike();
  const Texture2D transmittance = TransmittanceTable(a);
  const ivec2 size(8, 6);
  const glm::dvec3 ground_transfer = shared::GetGroundTransfer(a, 8, 10);
  for (int orders : {2, 4}) {
    Texture2D table(size.x, size.y);
    ComputeMultipleScatteringTable(a, transmittance, 16, 12, false, ground_transfer, table, orders);
    const Texture2D kernels = GatheredTableFromKernels(a, transmittance, size, 16, 12, ground_transfer, orders);
    for (int y = 0; y < size.y; ++y) {
      for (int x = 0; x < size.x; ++x) {
        // ln(Psi_ms) in both; the CPU keeps order K and the sums in double, the kernels' path
        // rounds order K through a float logarithm (2e-6 of Psi near ln = -20).
        ExpectSameTexel(glm::vec3(shared::DecodeMultiScattering(shared::vec3(table.at(x, y)))),
                        shared::DecodeMultiScattering(shared::vec3(kernels.at(x, y))), x, y, 1e-5);
      }
    }
  }
}

// One gathered order is Hillaire 2020's table bit for bit, and the gathered tables converge with
// the orders: what the series assumes after order K matters less as K grows (the change from 4 to
// 8 orders is a fraction of that from 1 to 2), and 16 orders change 8's by little.
TEST(HillaireTables, GatheredOrdersConverge) {
  const shared::AtmosphereParameters a = testing::EarthLike();
  const Texture2D transmittance = TransmittanceTable(a);
  const glm::dvec3 ground_transfer = shared::GetGroundTransfer(a, 8, 10);
  std::vector<Texture2D> tables;
  for (int orders : {1, 2, 4, 8, 16}) {
    tables.emplace_back(8, 6);
    ComputeMultipleScatteringTable(a, transmittance, 16, 12, false, ground_transfer, tables.back(), orders);
  }
  Texture2D hillaire(8, 6);
  ComputeMultipleScatteringTable(a, transmittance, 16, 12, false, ground_transfer, hillaire);
  // The largest relative change of Psi_ms between two tables, over the texels not deep in the shadow.
  const auto change = [&](const Texture2D& from, const Texture2D& to) {
    double worst = 0.0;
    for (std::size_t k = 0; k < from.texels.size(); ++k) {
      for (int c = 0; c < 3; ++c) {
        const double p = std::exp(double(from.texels[k][c]));
        const double q = std::exp(double(to.texels[k][c]));
        if (p > 1e-20) worst = std::max(worst, std::abs(q - p) / p);
      }
    }
    return worst;
  };
  for (std::size_t k = 0; k < hillaire.texels.size(); ++k) EXPECT_EQ(hillaire.texels[k], tables[0].texels[k]);
  const double first = change(tables[0], tables[1]);
  const double later = change(tables[2], tables[3]);
  const double last = change(tables[3], tables[4]);
  std::printf("gathered orders: largest change 1 -> 2 orders %.3g, 4 -> 8 %.3g, 8 -> 16 %.3g\n", first, later, last);
  EXPECT_GT(first, 0.05);  // the gathering changes the table: it is not the series again
  EXPECT_LT(later, 0.25 * first);
  EXPECT_LT(last, 0.01);
}

// The small multiple-scattering table that the sky-view and ground-irradiance tables read here.
Texture2D SmallMultipleScatteringTable(const shared::AtmosphereParameters& a, const Texture2D& transmittance) {
  Texture2D table(8, 8);
  ComputeMultipleScatteringTable(a, transmittance, 16, 10, false, glm::dvec3(0.0), table);
  return table;
}

TEST(HillaireTables, SkyViewRowsEqualPerTexelKernel) {
  const shared::AtmosphereParameters a = testing::EarthLike();
  const Texture2D transmittance = TransmittanceTable(a);
  const Texture2D multiple_scattering = SmallMultipleScatteringTable(a, transmittance);
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

TEST(HillaireTables, GroundIrradianceEqualsPerTexelKernel) {
  const shared::AtmosphereParameters a = testing::EarthLike();
  const Texture2D transmittance = TransmittanceTable(a);
  const Texture2D multiple_scattering = SmallMultipleScatteringTable(a, transmittance);
  for (int directions : {1, 7, 64}) {
    for (int width : {9, 32}) {  // suns from -1 to 1: day, twilight and night texels
      Texture2D table(width, 1);
      ComputeGroundIrradianceTable(a, transmittance, multiple_scattering, directions, 12, table);
      for (int x = 0; x < width; ++x) {
        ExpectSameTexel(table.at(x, 0),
                        shared::ComputeGroundIrradianceTexel(a, transmittance, multiple_scattering, width, x + 0.5,
                                                             directions, 12),
                        x, 0, 1e-5);
      }
    }
  }
}

}  // namespace
}  // namespace atmo::cpu
