// Model `elek` (docs/models/elek.md): mappings, tables against their per-texel kernels, single
// scattering against an independent quadrature, orders, export/load, options, robustness, and the
// measurements that docs/models/elek.md quotes (ElekMeasurements.*, which print their figures).
#include <algorithm>
#include <array>
#include <cmath>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <iterator>
#include <numbers>
#include <random>
#include <string>
#include <vector>

#include <gtest/gtest.h>

#include "error_of.h"

#include "atmo/elek.h"
#include "atmo/error.h"
#include "atmo/image.h"
#include "atmo/model.h"
#include "atmo/parameters.h"
#include "cpu/elek_tables.h"
#include "models/elek_model.h"
#include "shared/shared.h"

namespace atmo {
namespace {

namespace fs = std::filesystem;

std::unique_ptr<ElekModel> MakeElek(const AtmosphereParameters& p, const ModelOptions& options) {
  std::unique_ptr<Model> model = CreateModel("elek", p, options);
  return std::unique_ptr<ElekModel>(static_cast<ElekModel*>(model.release()));
}

glm::dvec3 Direction(double zenith_deg, double azimuth_deg) {
  return DirectionFromZenithAzimuth(glm::radians(zenith_deg), glm::radians(azimuth_deg));
}

std::vector<double> Radiance(const Model& model, double altitude_m, double sun_zenith_deg, double view_zenith_deg,
                             double azimuth_deg) {
  const auto sky = model.View(altitude_m, Direction(sun_zenith_deg, 0.0));
  std::vector<double> out(model.channel_count());
  sky->Radiance(Direction(view_zenith_deg, azimuth_deg), out);
  return out;
}

double RelativeDifference(double a, double b) { return std::abs(a - b) / std::max(std::abs(b), 1e-30); }

// --- Mappings -------------------------------------------------------------------------------------

TEST(ElekMapping, RoundTripsForBothParameterisations) {
  shared::AtmosphereParameters a{};  // only the radii matter to the mappings
  a.bottom_radius = 6371e3;
  a.top_radius = 6471e3;
  std::mt19937 rng(1);
  std::uniform_real_distribution<double> unit(0.0, 1.0);
  for (int mapping : {shared::kElekMappingLinear, shared::kElekMappingNonLinear}) {
    for (int i = 0; i < 1000; ++i) {
      const double h = 100e3 * unit(rng), mu = 2.0 * unit(rng) - 1.0, mu_s = 2.0 * unit(rng) - 1.0;
      const shared::vec3 uvw = shared::GetElekUvwFromHMuMuS(a, mapping, h, mu, mu_s);
      double h2, mu2, mu_s2;
      shared::GetElekHMuMuSFromUvw(a, mapping, uvw, h2, mu2, mu_s2);
      EXPECT_NEAR(h2, h, 1e-7) << mapping;
      EXPECT_NEAR(mu2, mu, 1e-12) << mapping;
      EXPECT_NEAR(mu_s2, mu_s, 1e-12) << mapping;
      // And from texture coordinates back.
      shared::GetElekHMuMuSFromUvw(a, mapping, shared::vec3(unit(rng), unit(rng), unit(rng)), h2, mu2, mu_s2);
      const shared::vec3 back = shared::GetElekUvwFromHMuMuS(a, mapping, h2, mu2, mu_s2);
      double h3, mu3, mu_s3;
      shared::GetElekHMuMuSFromUvw(a, mapping, back, h3, mu3, mu_s3);
      EXPECT_NEAR(h3, h2, 1e-7);
      EXPECT_NEAR(mu3, mu2, 1e-12);
    }
  }
  // The seed's values: u = sqrt(h / H_a), v = 0.5 (1 + cbrt(mu)); the horizon at v = 0.5.
  const shared::vec3 uvw = shared::GetElekUvwFromHMuMuS(a, shared::kElekMappingNonLinear, 25e3, 0.125, -0.125);
  EXPECT_NEAR(uvw.x, 0.5, 1e-12);
  EXPECT_NEAR(uvw.y, 0.75, 1e-12);
  EXPECT_NEAR(uvw.z, 0.25, 1e-12);
  // Texels at x / (W - 1): the first and last texels at 0 and 1, read back exactly by the sampler.
  EXPECT_EQ(shared::GetElekUvwFromTexel(glm::ivec3(32, 256, 32), glm::ivec3(31, 255, 0)), shared::vec3(1.0, 1.0, 0.0));
  shared::Texture3D t(4, 3, 2);
  for (int i = 0; i < 24; ++i) t.texels[i] = glm::vec3(float(i));
  for (int x = 0; x < 4; ++x) {
    const shared::vec3 uvw2 = shared::GetElekUvwFromTexel(glm::ivec3(4, 3, 2), glm::ivec3(x, 2, 1));
    EXPECT_NEAR(shared::texture(t, shared::GetElekTextureCoordFromUvw(glm::ivec3(4, 3, 2), uvw2)).x,
                t.at(x, 2, 1).x, 1e-6);
  }
}

// --- Tables equal their per-texel kernels ----------------------------------------------------------

TEST(ElekTables, EqualThePerTexelKernels) {
  for (const char* mapping : {"nonlinear", "linear"}) {
    const auto model = MakeElek(Preset("earth"), {{"size", "6x20x7"}, {"orders", "2"}, {"mapping", mapping}});
    const ElekModel::Batch& batch = model->batches()[0];
    const cpu::ElekGrid grid = model->grid();
    // The gather of order 1, recomputed as the model does.
    const auto matrix = cpu::ComputeElekGatherMatrix(batch.atmosphere, grid.mapping, model->settings().gather_rows,
                                                     grid.size.y, model->settings().gather_points,
                                                     model->settings().gather_azimuths);
    cpu::ElekScattering gather;
    cpu::ComputeElekGatherTable(matrix, model->settings().gather_rows, batch.orders[0], false, gather);
    // earth's albedo 0.3: the ground's reflection of the sun joins the gather (option ground=auto).
    ASSERT_TRUE(model->settings().UsesGround(model->parameters()));
    const shared::Texture2D irradiance = cpu::ComputeElekGroundIrradiance(batch.atmosphere, batch.transmittance,
                                                                          nullptr, grid, model->settings().gather_azimuths);
    cpu::AddElekGatheredGround(
        matrix, cpu::ComputeElekGroundRadianceTable(batch.atmosphere, batch.transmittance, irradiance, grid), gather);
    double worst = 0.0;
    for (int z = 0; z < grid.size.z; ++z) {
      for (int y = 0; y < grid.size.y; ++y) {
        for (int x = 0; x < grid.size.x; ++x) {
          shared::vec3 r1, m1, r2, m2;
          shared::ComputeElekSingleScatteringTexel(batch.atmosphere, batch.transmittance, grid.mapping, grid.steps,
                                                   grid.size, glm::ivec3(x, y, z), grid.sample_count, r1, m1);
          shared::ComputeElekMultipleScatteringTexel(batch.atmosphere, gather.rayleigh, gather.mie, gather.rayleigh,
                                                     gather.mie, grid.mapping, grid.steps, grid.size,
                                                     glm::ivec3(x, y, z), grid.sample_count, r2, m2);
          for (int c = 0; c < 3; ++c) {
            // Tables hold floats (relative 6e-8); the CPU's cbrt differs from the kernel's
            // pow(x, 1/3) by an ulp in a texture coordinate.
            const auto check = [&](double table, double kernel) {
              const double e = std::abs(table - kernel) / std::max(std::abs(kernel), 1e-12);
              worst = std::max(worst, e);
            };
            check(batch.orders[0].rayleigh.at(x, y, z)[c], r1[c]);
            check(batch.orders[0].mie.at(x, y, z)[c], m1[c]);
            check(batch.orders[1].rayleigh.at(x, y, z)[c], r2[c]);
            check(batch.orders[1].mie.at(x, y, z)[c], m2[c]);
          }
        }
      }
    }
    EXPECT_LT(worst, 1e-6) << mapping;
    // The gather matrix against its per-texel kernel (normalised rows).
    std::vector<glm::dvec2> sums;
    cpu::ComputeElekGatherMatrix(batch.atmosphere, grid.mapping, 5, grid.size.y, 4, 64, &sums);
    const auto m5 = cpu::ComputeElekGatherMatrix(batch.atmosphere, grid.mapping, 5, grid.size.y, 4, 64);
    for (int y = 0; y < 5; ++y) {
      for (int j = 0; j < grid.size.y; ++j) {
        const glm::dvec2 k = shared::ComputeElekGatherWeightTexel(batch.atmosphere, grid.mapping, 5, grid.size.y, y, j, 4, 64);
        EXPECT_NEAR(m5[y * grid.size.y + j].x, k.x / sums[y].x, 1e-12);
        EXPECT_NEAR(m5[y * grid.size.y + j].y, k.y / sums[y].y, 1e-12);
      }
    }
  }
}

// --- The ground (option ground) --------------------------------------------------------------------

// The sky's irradiance on the ground that feeds the next order (ComputeElekGroundSkyIrradiance,
// from the table at h = 0) against the hemisphere integral of the model's own rendered sky of that
// order, integral of L cos(theta) d(omega) by a midpoint rule (1 degree in zenith, 2 in azimuth),
// at the sun cosines of the table's slices. With mie=rgb the rendered sky is the table's exactly.
TEST(ElekGround, SkyIrradianceIsTheHemisphereIntegralOfTheModelsOwnSky) {
  const AtmosphereParameters p = Preset("earth");
  const auto model = MakeElek(p, {{"orders", "1"}, {"mie", "rgb"}, {"size", "32x128x32"}});
  const ElekModel::Batch& batch = model->batches()[0];
  const cpu::ElekGrid grid = model->grid();
  const shared::Texture2D table = cpu::ComputeElekGroundIrradiance(batch.atmosphere, batch.transmittance,
                                                                     &batch.orders[0], grid, 64);
  int checked = 0;
  for (int z = 0; z < grid.size.z; ++z) {
    double h, mu, mu_s;
    shared::GetElekHMuMuSFromUvw(batch.atmosphere, grid.mapping,
                                 shared::GetElekUvwFromTexel(grid.size, glm::ivec3(0, 0, z)), h, mu, mu_s);
    if (mu_s < 0.1) continue;  // sun zenith <= 84 degrees: a sky bright enough to compare
    const auto sky = model->View(0.0, glm::dvec3(std::sqrt(1.0 - mu_s * mu_s), 0.0, mu_s));
    constexpr int kZenith = 90;
    constexpr int kAzimuth = 180;
    glm::dvec3 e(0.0);
    std::array<double, 3> l{};
    for (int i = 0; i < kZenith; ++i) {
      const double theta = (i + 0.5) * (std::numbers::pi / 2.0) / kZenith;
      const double d_omega = std::sin(theta) * (std::numbers::pi / 2.0 / kZenith) * (2.0 * std::numbers::pi / kAzimuth);
      for (int j = 0; j < kAzimuth; ++j) {
        const double phi = (j + 0.5) * 2.0 * std::numbers::pi / kAzimuth;
        sky->Radiance(glm::dvec3(std::sin(theta) * std::cos(phi), std::sin(theta) * std::sin(phi), std::cos(theta)), l);
        e += glm::dvec3(l[0], l[1], l[2]) * (std::cos(theta) * d_omega);
      }
    }
    for (int c = 0; c < 3; ++c) {
      EXPECT_NEAR(table.at(z, 0)[c] / e[c], 1.0, 0.01) << "sun cosine " << mu_s << ", channel " << c;
    }
    ++checked;
  }
  EXPECT_GE(checked, 8);
}

// The ground's light enters at order 2 in proportion to the albedo (the reflection of the direct
// sun is linear in it), only adds light, and leaves order 1 alone. ground=off, whatever the albedo,
// gives the seed's tables bit for bit (those of albedo 0).
TEST(ElekGround, FeedsOrderTwoInProportionToTheAlbedo) {
  const auto tables = [](double albedo, const char* ground) {
    AtmosphereParameters p = Preset("earth");
    p.ground_albedo.assign(3, albedo);
    return MakeElek(p, {{"size", "8x64x16"}, {"orders", "2"}, {"ground", ground}});
  };
  const auto seed = tables(0.0, "auto");
  const auto off = tables(0.3, "off");
  const auto low = tables(0.3, "auto");
  const auto high = tables(0.6, "on");
  EXPECT_FALSE(seed->settings().UsesGround(seed->parameters()));
  EXPECT_FALSE(off->settings().UsesGround(off->parameters()));
  const auto& o = seed->batches()[0].orders;
  EXPECT_EQ(off->batches()[0].orders[1].rayleigh.texels, o[1].rayleigh.texels);
  EXPECT_EQ(off->batches()[0].orders[1].mie.texels, o[1].mie.texels);
  EXPECT_EQ(low->batches()[0].orders[0].rayleigh.texels, o[0].rayleigh.texels);
  double largest_gain = 0.0;  // over texels of at least 1 % of the table's largest value
  double worst_linearity = 0.0;
  double brightest = 0.0;
  for (const auto& t : o[1].rayleigh.texels) brightest = std::max({brightest, double(t.x), double(t.y), double(t.z)});
  const auto& lo = low->batches()[0].orders[1];
  const auto& hi = high->batches()[0].orders[1];
  for (std::size_t i = 0; i < o[1].rayleigh.texels.size(); ++i) {
    for (int c = 0; c < 3; ++c) {
      for (shared::Texture3D cpu::ElekScattering::*part : {&cpu::ElekScattering::rayleigh, &cpu::ElekScattering::mie}) {
        const double base = (o[1].*part).texels[i][c];
        const double d_low = (lo.*part).texels[i][c] - base;
        const double d_high = (hi.*part).texels[i][c] - base;
        EXPECT_GE(d_low, -1e-6 * base);
        if (base <= 0.0) continue;
        if (base > 0.01 * brightest) largest_gain = std::max(largest_gain, d_low / base);
        if (d_low > 1e-3 * base) worst_linearity = std::max(worst_linearity, std::abs(d_high / (2.0 * d_low) - 1.0));
      }
    }
  }
  EXPECT_GT(largest_gain, 0.05);        // the ground matters: over 5 % of order 2 somewhere
  EXPECT_LT(worst_linearity, 1e-4);     // float tables
  std::printf("albedo 0.3 adds up to %.1f %% to order 2 (texels above 1 %% of its largest); linear in the albedo to %.1e\n", 100.0 * largest_gain,
              worst_linearity);
}

// --- Single scattering against an independent quadrature -------------------------------------------

// The seed's single scattering (section 2.1) for a view in the sun's vertical plane, written from
// its equations with the preset's values: fine uniform midpoint steps, transmittances by direct
// quadrature, the planet shadow by a ray-sphere test, normalised phase functions.
struct Independent {
  const AtmosphereParameters& p;
  double Density(const DensityProfile& d, double h) const { return d.Evaluate(std::max(h, 0.0)); }
  double Extinction(double h, int c) const {
    return p.rayleigh.extinction_per_m(c) * Density(p.rayleigh.density, h) +
           p.mie.extinction_per_m(c) * Density(p.mie.density, h) + p.ozone.extinction_per_m(c) * Density(p.ozone.density, h);
  }
  // Distance from x along unit d to the sphere of radius R (far root), or -1.
  static double Exit(const glm::dvec3& x, const glm::dvec3& d, double radius) {
    const double b = glm::dot(x, d), c = glm::dot(x, x) - radius * radius, disc = b * b - c;
    return disc < 0.0 ? -1.0 : -b + std::sqrt(disc);
  }
  // For a point on or above the sphere: the ray goes down and meets it.
  static bool HitsGround(const glm::dvec3& x, const glm::dvec3& d, double radius) {
    const double b = glm::dot(x, d), c = glm::dot(x, x) - radius * radius;
    return b < 0.0 && b * b - c >= 0.0;
  }
  double OpticalDepth(const glm::dvec3& x, const glm::dvec3& d, double length, int c, int n) const {
    double sum = 0.0;
    for (int i = 0; i < n; ++i) {
      const glm::dvec3 q = x + d * ((i + 0.5) / n * length);
      sum += Extinction(glm::length(q) - p.ground_radius_m, c);
    }
    return sum * length / n;
  }
  double Radiance(double h, double view_zenith, double sun_zenith, int c) const {
    const glm::dvec3 x(0.0, 0.0, p.ground_radius_m + h);
    const glm::dvec3 v(std::sin(view_zenith), 0.0, std::cos(view_zenith));
    const glm::dvec3 s(std::sin(sun_zenith), 0.0, std::cos(sun_zenith));
    const bool ground = HitsGround(x, v, p.ground_radius_m);
    const double b = glm::dot(x, v), cc = glm::dot(x, x) - p.ground_radius_m * p.ground_radius_m;
    const double length = ground ? std::max(-b - std::sqrt(std::max(b * b - cc, 0.0)), 0.0) : Exit(x, v, p.top_radius_m);
    const int n = 800;
    const double dt = length / n;
    const double nu = glm::dot(v, s);
    double rayleigh = 0.0, mie = 0.0, depth = 0.0;
    for (int i = 0; i < n; ++i) {
      const glm::dvec3 q = x + v * ((i + 0.5) * dt);
      const double hq = glm::length(q) - p.ground_radius_m;
      const double depth_here = depth + 0.5 * dt * Extinction(hq, c);
      depth += dt * Extinction(hq, c);
      if (HitsGround(q, s, p.ground_radius_m)) continue;  // the P_c rule
      const double to_sun = OpticalDepth(q, s, Exit(q, s, p.top_radius_m), c, 100);
      const double t = std::exp(-depth_here - to_sun) * dt;
      rayleigh += t * p.rayleigh.scattering_per_m[c] * Density(p.rayleigh.density, hq);
      mie += t * p.mie.scattering_per_m[c] * Density(p.mie.density, hq);
    }
    const double pr = shared::EvaluatePhaseFunction(shared::kPhaseRayleigh, 0.0, nu);
    const double pm = shared::EvaluatePhaseFunction(shared::kPhaseCornetteShanks, p.mie.phase_g, nu);
    return pr * rayleigh + pm * mie;
  }
};

TEST(ElekSingleScattering, MatchesAnIndependentQuadratureInTheSunPlane) {
  const AtmosphereParameters p = Preset("atmosphere-plus");
  const auto model = MakeElek(p, {{"orders", "1"}, {"mie", "rgb"}});
  const Independent reference{p};
  const shared::AtmosphereParameters& a = model->batches()[0].atmosphere;
  // Altitude of texel x and sun zenith of texel z of the 32x256x32 non-linear table.
  const auto texel = [&](int x, int z, double& h, double& sun_deg) {
    double mu, mu_s;
    shared::GetElekHMuMuSFromUvw(a, shared::kElekMappingNonLinear, shared::vec3(x / 31.0, 0.5, z / 31.0), h, mu, mu_s);
    sun_deg = glm::degrees(std::acos(mu_s));
  };
  const auto worst_over = [&](const std::vector<double>& altitudes, const std::vector<double>& suns) {
    double worst = 0.0;
    for (double h : altitudes) {
      for (double sun : suns) {
        for (double view : {0.0, 40.0, 75.0, 110.0, 150.0}) {
          const auto l = Radiance(*model, h, sun, view, 0.0);
          for (int c = 0; c < 3; ++c) {
            worst = std::max(worst, RelativeDifference(l[c], reference.Radiance(h, glm::radians(view), glm::radians(sun), c)));
          }
        }
      }
    }
    return worst;
  };
  // On texels in altitude and sun zenith (x = 0, 4, 14; z = 31, 28, 24, 20: sun 0 to 88.6
  // degrees): only the view axis is interpolated, so the gap is N = 30 quadratic steps and the
  // transmittance table against fine quadrature (ElekMeasurements.StepDistribution... measures
  // N = 30 alone at 2.4e-2 worst). Measured 2.4e-2.
  std::vector<double> altitudes, suns;
  for (int x : {0, 4, 14}) {
    double h, sun;
    texel(x, 31, h, sun);
    altitudes.push_back(h);
  }
  for (int z : {31, 28, 24, 20}) {
    double h, sun;
    texel(0, z, h, sun);
    suns.push_back(sun);
  }
  const double on_texels = worst_over(altitudes, suns);
  // Between texels: trilinear interpolation adds its error, largest for a low sun where the
  // radiance falls exponentially with the sun's air mass between texels 1.2 degrees apart.
  // Measured 1.2e-1 (sun 88 degrees, blue, looking down); 2.6e-2 for suns up to 45 degrees.
  const double between = worst_over({2000.0, 7000.0}, {20.0, 60.0, 88.0});
  const double between_high_sun = worst_over({2000.0, 7000.0}, {20.0, 45.0});
  std::printf("single scattering vs independent quadrature: on texels %.2e, between %.2e (sun <= 45 deg: %.2e)\n",
              on_texels, between, between_high_sun);
  EXPECT_LT(on_texels, 0.03);
  EXPECT_LT(between_high_sun, 0.03);
  EXPECT_LT(between, 0.15);
}

// --- Orders ---------------------------------------------------------------------------------------

TEST(ElekOrders, EachOrderContributesLessThanThePrevious) {
  const auto model = MakeElek(Preset("atmosphere-plus"), {{"size", "32x64x32"}});
  const auto& orders = model->batches()[0].orders;
  ASSERT_EQ(orders.size(), 4u);
  std::vector<double> mean(4, 0.0);
  for (int k = 0; k < 4; ++k) {
    for (const glm::vec3& t : orders[k].rayleigh.texels) mean[k] += t.x + t.y + t.z;
    for (const glm::vec3& t : orders[k].mie.texels) mean[k] += t.x;
  }
  std::printf("elek mean factored scattering per order: %.4g %.4g %.4g %.4g\n", mean[0], mean[1], mean[2], mean[3]);
  EXPECT_GT(mean[1], 0.0);
  EXPECT_GT(mean[1], mean[2]);
  EXPECT_GT(mean[2], mean[3]);
  EXPECT_GT(mean[3], 0.0);
  // The summed table is the sum of the orders.
  const auto& total = model->batches()[0].total;
  for (std::size_t i = 0; i < total.rayleigh.texels.size(); i += 97) {
    double sum = 0.0;
    for (int k = 0; k < 4; ++k) sum += orders[k].rayleigh.texels[i].y;
    EXPECT_NEAR(total.rayleigh.texels[i].y, sum, 1e-6 * sum + 1e-30);
  }
}

// --- Export and load -------------------------------------------------------------------------------

class ElekFiles : public ::testing::Test {
 protected:
  void SetUp() override {
    folder_ = fs::temp_directory_path() / ("atmo_elek_test_" + std::to_string(::getpid()));
    fs::create_directories(folder_);
    name_ = (folder_ / "table").string();
  }
  void TearDown() override { fs::remove_all(folder_); }
  fs::path folder_;
  std::string name_;
};

TEST_F(ElekFiles, ExportThenLoadGivesIdenticalRadiance) {
  const ModelOptions options = {{"size", "8x16x8"}, {"orders", "2"}};
  const auto model = MakeElek(Preset("earth"), options);
  const ElekTableFiles files = ExportElekTable(*model, name_);
  EXPECT_TRUE(fs::exists(files.exr));
  EXPECT_EQ(fs::file_size(files.raw), 8u * 16 * 8 * 16);
  ModelOptions load = options;
  load["table"] = name_;
  const auto loaded = MakeElek(Preset("earth"), load);
  EXPECT_TRUE(loaded->batches()[0].orders.empty());
  for (double view : {0.0, 60.0, 89.0, 95.0, 140.0}) {
    for (double azimuth : {0.0, 90.0, 180.0}) {
      EXPECT_EQ(Radiance(*model, 500.0, 70.0, view, azimuth), Radiance(*loaded, 500.0, 70.0, view, azimuth));
    }
  }
  // The raw file is the seed's layout: texel (x, y, z) at i = x + y W + z W H, RGBA.
  std::ifstream raw(files.raw, std::ios::binary);
  const std::size_t i = 3 + 5 * 8 + 6 * 8 * 16;
  raw.seekg(static_cast<std::streamoff>(16 * i));
  float rgba[4];
  raw.read(reinterpret_cast<char*>(rgba), 16);
  EXPECT_EQ(rgba[1], model->batches()[0].total.rayleigh.at(3, 5, 6).y);
  EXPECT_EQ(rgba[3], model->batches()[0].total.mie.at(3, 5, 6).x);
  // The sun-transmittance table beside it: RGB float32, texel (x, y) at 3 (x + W y), the same
  // values as the model's 256 x 64 table, and listed in the manifest.
  const shared::Texture2D& transmittance = model->batches()[0].transmittance;
  EXPECT_EQ(fs::file_size(files.transmittance_raw), 12u * transmittance.width * transmittance.height);
  std::ifstream t_raw(files.transmittance_raw, std::ios::binary);
  t_raw.seekg(static_cast<std::streamoff>(12 * (7 + 9 * transmittance.width)));
  float rgb[3];
  t_raw.read(reinterpret_cast<char*>(rgb), 12);
  EXPECT_EQ(rgb[2], transmittance.at(7, 9).z);
  const Image t_exr = ReadExr(files.transmittance_exr);
  EXPECT_EQ(t_exr.at(7, 9, 2), transmittance.at(7, 9).z);
  std::ifstream manifest(files.json);
  const std::string text((std::istreambuf_iterator<char>(manifest)), std::istreambuf_iterator<char>());
  EXPECT_NE(text.find("\"raw\": \"table_transmittance.raw\""), std::string::npos);
}

using atmo::testing::ErrorOf;

TEST_F(ElekFiles, LoadRefusesMismatches) {
  const ModelOptions options = {{"size", "4x8x4"}, {"orders", "1"}};
  ExportElekTable(*MakeElek(Preset("earth"), options), name_);
  ModelOptions load = options;
  load["table"] = name_;
  // Another atmosphere.
  EXPECT_NE(ErrorOf([&] { MakeElek(Preset("atmosphere-plus"), load); }).find("parameter hash"), std::string::npos);
  // Another size or option.
  ModelOptions other = load;
  other["size"] = "4x8x5";
  EXPECT_NE(ErrorOf([&] { MakeElek(Preset("earth"), other); }).find("size 4x8x4 does not match"), std::string::npos);
  other = load;
  other["orders"] = "2";
  EXPECT_NE(ErrorOf([&] { MakeElek(Preset("earth"), other); }).find("orders"), std::string::npos);
  // Edited manifest: format and atmo versions.
  const std::string json_path = name_ + ".json";
  std::string json;
  {
    std::ifstream in(json_path);
    json.assign(std::istreambuf_iterator<char>(in), std::istreambuf_iterator<char>());
  }
  const auto write_json = [&](const std::string& text) { std::ofstream(json_path) << text; };
  std::string edited = json;
  edited.replace(edited.find("\"format_version\": 1"), 19, "\"format_version\": 7");
  write_json(edited);
  EXPECT_NE(ErrorOf([&] { MakeElek(Preset("earth"), load); }).find("format version 7"), std::string::npos);
  // Another atmo version with this format version loads, with one warning line on stderr.
  edited = json;
  edited.replace(edited.find("\"atmo_version\": \""), 17, "\"atmo_version\": \"9.9.9-");
  write_json(edited);
  ::testing::internal::CaptureStderr();
  EXPECT_NO_THROW(MakeElek(Preset("earth"), load));
  const std::string warning = ::testing::internal::GetCapturedStderr();
  EXPECT_EQ(warning.rfind("atmo: warning: ", 0), 0u) << warning;
  EXPECT_NE(warning.find("written by atmo 9.9.9-"), std::string::npos) << warning;
  EXPECT_EQ(std::count(warning.begin(), warning.end(), '\n'), 1) << warning;
  write_json(json);
  EXPECT_NO_THROW(MakeElek(Preset("earth"), load));
  // A corrupted data file.
  {
    std::fstream raw(name_ + ".raw", std::ios::in | std::ios::out | std::ios::binary);
    raw.seekp(100);
    raw.put('\x7f');
  }
  const std::string message = ErrorOf([&] { MakeElek(Preset("earth"), load); });
  EXPECT_NE(message.find("data hash"), std::string::npos) << message;
  EXPECT_EQ(message.find('\n'), std::string::npos);
  // A missing file.
  load["table"] = name_ + "_missing";
  EXPECT_NE(ErrorOf([&] { MakeElek(Preset("earth"), load); }).find("cannot read"), std::string::npos);
}

// --- Options ---------------------------------------------------------------------------------------

TEST(ElekOptions, ModifiedRayleighReshapesTheRayleighLobe) {
  const ModelOptions base = {{"size", "8x32x8"}, {"orders", "1"}};
  ModelOptions modified = base;
  modified["rayleigh_phase"] = "modified";
  const AtmosphereParameters p = Preset("atmosphere-plus");
  const auto plain = MakeElek(p, base);
  const auto flat = MakeElek(p, modified);
  // Single scattering's factored table does not depend on the phase function.
  EXPECT_EQ(plain->Rgba(0), flat->Rgba(0));
  // The radiance does, through p_R(nu): the modified lobe (1.4 + 0.5 nu^2) is flatter, brighter
  // at 90 degrees from the sun and darker towards and away from it; Mie is unchanged.
  const auto side_plain = Radiance(*plain, 0.0, 45.0, 45.0, 90.0);
  const auto side_flat = Radiance(*flat, 0.0, 45.0, 45.0, 90.0);
  const auto back_plain = Radiance(*plain, 0.0, 45.0, 45.0, 0.0);  // towards the sun
  const auto back_flat = Radiance(*flat, 0.0, 45.0, 45.0, 0.0);
  for (int c = 0; c < 3; ++c) {
    EXPECT_GT(side_flat[c], side_plain[c]);
    EXPECT_LT(back_flat[c], back_plain[c]);
  }
  // The same through the parameters.
  AtmosphereParameters q = p;
  q.rayleigh.phase = PhaseFunction::kModifiedRayleigh;
  EXPECT_EQ(Radiance(*MakeElek(q, base), 0.0, 45.0, 45.0, 90.0), side_flat);
  // With multiple orders the gather uses it too, so the tables differ.
  ModelOptions k2 = base;
  k2["orders"] = "2";
  ModelOptions k2m = k2;
  k2m["rayleigh_phase"] = "modified";
  EXPECT_NE(MakeElek(p, k2)->Rgba(0), MakeElek(p, k2m)->Rgba(0));
}

TEST(ElekOptions, BadOptionsAreRefused) {
  const AtmosphereParameters p = Preset("earth");
  EXPECT_NE(ErrorOf([&] { CreateModel("elek", p, {{"colour", "1"}}); }).find("unknown option 'colour'"), std::string::npos);
  EXPECT_NE(ErrorOf([&] { CreateModel("elek", p, {{"size", "1x8x8"}}); }).find("size=1"), std::string::npos);
  EXPECT_NE(ErrorOf([&] { CreateModel("elek", p, {{"size", "8x8"}}); }).find("WxHxD"), std::string::npos);
  EXPECT_NE(ErrorOf([&] { CreateModel("elek", p, {{"orders", "0"}}); }).find("orders=0"), std::string::npos);
  EXPECT_NE(ErrorOf([&] { CreateModel("elek", p, {{"mapping", "cubic"}}); }).find("nonlinear or linear"), std::string::npos);
  EXPECT_NE(ErrorOf([&] { CreateModel("elek", p, {{"gather", "x"}}); }).find("seed or phase"), std::string::npos);
  EXPECT_NE(ErrorOf([&] { CreateModel("elek", p, {{"mie", "rgb"}, {"table", "t"}}); }).find("mie=rgb"), std::string::npos);
  EXPECT_NE(ErrorOf([&] { CreateModel("elek", Preset("simple")); }).find("spherical"), std::string::npos);
  const auto model = CreateModel("elek", p, {{"size", "4x8x4"}, {"orders", "1"}});
  EXPECT_THROW(model->View(-1.0, Direction(0.0, 0.0)), Error);
}

// --- Any preset ------------------------------------------------------------------------------------

TEST(ElekPresets, EarthWithOzoneIsFiniteAndNonNegativeEverywhere) {
  for (const char* preset : {"earth", "atmosphere-plus"}) {
    const auto model = CreateModel("elek", Preset(preset), {{"size", "16x64x16"}, {"orders", "3"}});
    std::mt19937 rng(7);
    std::uniform_real_distribution<double> unit(0.0, 1.0);
    std::vector<double> l(3), t(3);
    for (int i = 0; i < 2000; ++i) {
      const double altitude = i % 10 == 0 ? 150e3 * unit(rng) : 100e3 * unit(rng) * unit(rng);
      const auto sky = model->View(altitude, Direction(180.0 * unit(rng), 0.0));
      const glm::dvec3 view = Direction(180.0 * unit(rng), 360.0 * unit(rng));
      sky->Radiance(view, l);
      sky->Transmittance(view, t);
      for (int c = 0; c < 3; ++c) {
        ASSERT_TRUE(std::isfinite(l[c]) && l[c] >= 0.0) << preset << " " << altitude;
        ASSERT_TRUE(t[c] >= 0.0 && t[c] <= 1.0);
      }
    }
  }
  // Ozone absorbs: removing it brightens the low-sun sky (it only attenuates).
  AtmosphereParameters no_ozone = Preset("earth");
  std::fill(no_ozone.ozone.absorption_per_m.begin(), no_ozone.ozone.absorption_per_m.end(), 0.0);
  const ModelOptions small = {{"size", "16x64x16"}, {"orders", "2"}};
  const auto with = Radiance(*CreateModel("elek", Preset("earth"), small), 0.0, 85.0, 0.0, 0.0);
  const auto without = Radiance(*CreateModel("elek", no_ozone, small), 0.0, 85.0, 0.0, 0.0);
  for (int c = 0; c < 3; ++c) EXPECT_LT(with[c], without[c]);
}

// --- Measurements quoted by docs/models/elek.md -----------------------------------------------------

// Mean and worst relative difference of model a against model b over a grid of skies from the
// ground and 5 km, sun zeniths 0..100 degrees, view zeniths 0..180, azimuths 0..180 (green channel
// and all channels).
struct Difference {
  double mean = 0.0;
  double worst = 0.0;
};
Difference Compare(const Model& a, const Model& b, bool canonical_only = false) {
  Difference d;
  int n = 0;
  for (double h : {0.0, 5000.0}) {
    for (double sun = 0.0; sun <= 100.0; sun += 12.5) {
      for (double view = 0.0; view <= 180.0; view += 15.0) {
        for (double azimuth = 0.0; azimuth <= 180.0; azimuth += canonical_only ? 360.0 : 45.0) {
          const auto la = Radiance(a, h, sun, view, azimuth);
          const auto lb = Radiance(b, h, sun, view, azimuth);
          for (int c = 0; c < 3; ++c) {
            if (lb[c] < 1e-7) continue;  // night
            const double e = RelativeDifference(la[c], lb[c]);
            d.mean += e;
            d.worst = std::max(d.worst, e);
            ++n;
          }
        }
      }
    }
  }
  d.mean /= std::max(n, 1);
  return d;
}

TEST(ElekMeasurements, StepDistributionAgainstAFineReference) {
  // Order 1 (the ray integrals alone) with N = 30 against N = 3000 uniform steps.
  const AtmosphereParameters p = Preset("atmosphere-plus");
  const ModelOptions base = {{"size", "32x64x32"}, {"orders", "1"}, {"mie", "rgb"}};
  ModelOptions fine = base;
  fine["samples"] = "3000";
  fine["steps"] = "uniform";
  const auto reference = CreateModel("elek", p, fine);
  for (const char* steps : {"quadratic", "uniform"}) {
    ModelOptions o = base;
    o["steps"] = steps;
    const Difference d = Compare(*CreateModel("elek", p, o), *reference, true);
    std::printf("steps=%s N=30 vs N=3000: mean %.2e worst %.2e\n", steps, d.mean, d.worst);
    EXPECT_LT(d.mean, 0.05);
  }
}

TEST(ElekMeasurements, GatherRebuildCouplingAndMieChannel) {
  const AtmosphereParameters p = Preset("atmosphere-plus");
  const ModelOptions base = {{"size", "32x64x32"}};
  const auto seed = CreateModel("elek", p, base);
  ModelOptions o = base;
  o["gather"] = "phase";
  const auto phase = CreateModel("elek", p, o);
  o = base;
  o["coupling"] = "total";
  const auto total = CreateModel("elek", p, o);
  o = base;
  o["mie"] = "rgb";
  const auto rgb = CreateModel("elek", p, o);
  Difference d = Compare(*seed, *phase);
  std::printf("gather=seed vs gather=phase: mean %.2e worst %.2e\n", d.mean, d.worst);
  d = Compare(*seed, *total);
  std::printf("coupling=separate vs coupling=total: mean %.2e worst %.2e\n", d.mean, d.worst);
  d = Compare(*seed, *rgb);
  std::printf("mie=alpha (Bruneton ratio) vs mie=rgb: mean %.2e worst %.2e\n", d.mean, d.worst);
  EXPECT_LT(d.mean, 0.05);
  // The gather matrix's quadrature before normalisation (rows should sum to 1).
  const auto& batch = static_cast<const ElekModel&>(*seed).batches()[0];
  std::vector<glm::dvec2> sums;
  cpu::ComputeElekGatherMatrix(batch.atmosphere, shared::kElekMappingNonLinear, 64, 64, 4, 64, &sums);
  double worst_r = 0.0, worst_m = 0.0;
  for (const auto& s : sums) {
    worst_r = std::max(worst_r, std::abs(s.x - 1.0));
    worst_m = std::max(worst_m, std::abs(s.y - 1.0));
  }
  std::printf("gather matrix row sums before normalisation: |1 - sum| <= %.2e (Rayleigh), %.2e (Mie)\n", worst_r,
              worst_m);
}

}  // namespace
}  // namespace atmo
