// Tabulated density profiles (docs/parameters.md, "Tabulated profiles"): the public profile, its
// validation and JSON, the shared table every model reads, and the models on a tabulated copy of
// a layer atmosphere.
#include <cmath>
#include <span>
#include <string>
#include <utility>
#include <vector>

#include <gtest/gtest.h>

#include "atmo/error.h"
#include "atmo/model.h"
#include "atmo/parameters.h"
#include "physics/shared_parameters.h"
#include "shared/shared.h"

namespace atmo {
namespace {

// The profile sampled at `step_m` from 0 to `top_m` as a table.
DensityProfile Tabulate(const DensityProfile& profile, double step_m, double top_m) {
  std::vector<DensityKnot> knots;
  for (double h = 0.0; h <= top_m + 0.5 * step_m; h += step_m) knots.push_back({h, profile.Evaluate(h)});
  return DensityProfile::Tabulated(std::move(knots));
}

// `earth` with its three profiles tabulated every `step_m`.
AtmosphereParameters TabulatedEarth(double step_m) {
  AtmosphereParameters p = Preset("earth");
  p.name = "custom";
  const double top = p.top_radius_m - p.ground_radius_m;
  for (Medium* m : {&p.rayleigh, &p.mie, &p.ozone}) m->density = Tabulate(m->density, step_m, top);
  return p;
}

TEST(DensityTable, EvaluateIsExponentialBetweenPositiveKnotsAndLinearNearZero) {
  const DensityProfile p = DensityProfile::Tabulated({{0.0, 1.0}, {1000.0, 0.25}, {2000.0, 0.0}, {3000.0, 0.5}});
  EXPECT_DOUBLE_EQ(p.Evaluate(-50.0), 1.0);     // held below the first knot
  EXPECT_DOUBLE_EQ(p.Evaluate(0.0), 1.0);
  EXPECT_NEAR(p.Evaluate(500.0), 0.5, 1e-15);   // sqrt(1 * 0.25): exponential
  EXPECT_NEAR(p.Evaluate(1500.0), 0.125, 1e-15);  // linear towards 0
  EXPECT_NEAR(p.Evaluate(2500.0), 0.25, 1e-15);   // linear from 0
  EXPECT_DOUBLE_EQ(p.Evaluate(3000.0), 0.5);
  EXPECT_DOUBLE_EQ(p.Evaluate(1e6), 0.5);       // held above the last knot
  EXPECT_TRUE(p.tabulated());
  EXPECT_FALSE(DensityProfile::Exponential(8000.0).tabulated());
}

TEST(DensityTable, ValidationNamesTheKnot) {
  struct Case {
    std::vector<DensityKnot> knots;
    std::string message;
  };
  const Case cases[] = {
      {{{0.0, 1.0}}, "mie.density.table needs at least 2 knots (got 1)"},
      {{{0.0, 1.0}, {0.0, 0.5}}, "mie.density.table altitudes must increase strictly: knot 1 is at 0 m after 0 m"},
      {{{0.0, 1.0}, {100.0, 0.5}, {50.0, 0.2}}, "knot 2 is at 50 m after 100 m"},
      {{{0.0, -0.1}, {100.0, 0.5}}, "mie.density.table[0].density must be in [0, 1] (got -0.1)"},
      {{{0.0, 1.5}, {100.0, 0.5}}, "mie.density.table[0].density must be in [0, 1] (got 1.5)"},
      {{{0.0, 1.0}, {NAN, 0.5}}, "mie.density.table[1].altitude_m must be in"},
      {{{0.0, 1.0}, {100.0, NAN}}, "mie.density.table[1].density must be in [0, 1] (got nan)"},
  };
  for (const Case& c : cases) {
    AtmosphereParameters p = Preset("earth");
    p.mie.density = DensityProfile::Tabulated(c.knots);
    try {
      Validate(p);
      ADD_FAILURE() << "accepted: " << c.message;
    } catch (const Error& e) {
      EXPECT_NE(std::string(e.what()).find(c.message), std::string::npos) << e.what();
    }
  }
}

TEST(DensityTable, JsonRoundTripsAndRefusesMixedForms) {
  const AtmosphereParameters p = TabulatedEarth(5000.0);
  Validate(p);
  const std::string json = ToJson(p);
  EXPECT_NE(json.find("\"table\""), std::string::npos);
  EXPECT_EQ(ToJson(FromJson(json)), json);
  EXPECT_EQ(FromJson(json).mie.density, p.mie.density);
  EXPECT_NE(ParameterHash(p), ParameterHash(Preset("earth")));

  const AtmosphereParameters q = FromJson(R"({"mie": {"density": {"table": [[0, 1], [2000, 0.1], [4000, 0]]}}})");
  ASSERT_TRUE(q.mie.density.tabulated());
  EXPECT_NEAR(q.mie.density.Evaluate(1000.0), std::sqrt(0.1), 1e-12);
  EXPECT_FALSE(q.rayleigh.density.tabulated());

  // Layers given over a tabulated profile replace it.
  const AtmosphereParameters r =
      FromJson(ToJson(p).substr(0, 0) + R"({"mie": {"density": {"upper": {"exp_term": 1, "exp_scale_per_m": -0.001}}}})");
  EXPECT_FALSE(r.mie.density.tabulated());

  for (const char* bad : {
           R"({"mie": {"density": {"table": [[0, 1]], "lower": {}}}})",
           R"({"mie": {"density": {"table": []}}})",
           R"({"mie": {"density": {"table": [[0, 1, 2], [1, 0]]}}})",
           R"({"mie": {"density": {"table": [[0, "1"], [1, 0]]}}})",
           R"({"mie": {"density": {"table": [[0, 1], [1000, -0.5]]}}})",
           R"({"mie": {"density": {"table": [[1000, 1], [0, 0.5]]}}})",
       }) {
    EXPECT_THROW(FromJson(bad), Error) << bad;
  }
}

// The shared table (what every model and both backends read) follows the public profile: at
// every altitude within 2e-4 relative for the exponential air and aerosol of `earth`, and within
// 0.025 of the peak for its ozone tent, whose kinks fall between the table's knots (0.7-1 km apart
// there: the tent's slope of 1 / 15 km over half a spacing).
TEST(DensityTable, SharedTableFollowsThePublicProfile) {
  const AtmosphereParameters p = TabulatedEarth(250.0);
  const shared::AtmosphereParameters a = ToSharedParameters(p, 0);
  ASSERT_EQ(a.density_table_enabled, 1);
  EXPECT_DOUBLE_EQ(a.density_table_top, 100e3);
  for (double h = 0.0; h <= 100e3; h += 137.0) {
    const shared::vec4 d = shared::GetDensities(a, a.bottom_radius + h);
    EXPECT_NEAR(d.x, p.rayleigh.density.Evaluate(h), 2e-4 * p.rayleigh.density.Evaluate(h)) << h;
    EXPECT_NEAR(d.y, p.mie.density.Evaluate(h), 2e-4 * p.mie.density.Evaluate(h) + 1e-30) << h;
    EXPECT_NEAR(d.z, p.ozone.density.Evaluate(h), 0.025) << h;
  }
  // A layer atmosphere keeps its layers (outputs of the existing presets unchanged).
  EXPECT_EQ(ToSharedParameters(Preset("earth"), 0).density_table_enabled, 0);
}

// Every model on a tabulated copy of `earth` (knots every 250 m) gives the sky of `earth` itself:
// the same physics through the other profile path. Bounds: the table rounds the ozone tent's
// kinks (SharedTableFollowsThePublicProfile) and, exponential between its knots where the tent is
// linear, holds 0.1-0.2 % less ozone: the horizon's transmittance moves by up to 2e-3, the sky by
// under 0.5 %.
TEST(DensityTable, EveryModelSeesTheSameSkyOnATabulatedCopy) {
  const AtmosphereParameters layered = Preset("earth");
  const AtmosphereParameters tabulated = TabulatedEarth(250.0);
  const glm::dvec3 sun = DirectionFromZenithAzimuth(glm::radians(70.0), 0.0);
  const std::vector<glm::dvec3> views = {DirectionFromZenithAzimuth(0.0, 0.0),
                                         DirectionFromZenithAzimuth(glm::radians(85.0), 0.0),
                                         DirectionFromZenithAzimuth(glm::radians(60.0), glm::radians(120.0)),
                                         DirectionFromZenithAzimuth(glm::radians(89.0), glm::radians(180.0))};
  // Small tables (the same for both atmospheres): the comparison is of the profile path, not of
  // the models' resolution, and it keeps the test short under the sanitizers.
  const std::vector<std::pair<const char*, ModelOptions>> models = {
      {"hillaire", {}},
      {"elek", {{"size", "16x64x16"}, {"orders", "3"}, {"gather_rows", "32"}, {"gather_azimuths", "32"}}},
      {"source4d", {{"table", "8x12x16x4"}, {"gather", "25x5"}, {"orders", "3"}}}};
  for (const auto& [name, options] : models) {
    SCOPED_TRACE(name);
    const auto a = CreateModel(name, layered, options);
    const auto b = CreateModel(name, tabulated, options);
    for (double altitude : {0.0, 5000.0}) {
      const auto va = a->View(altitude, sun);
      const auto vb = b->View(altitude, sun);
      for (const glm::dvec3& v : views) {
        std::vector<double> la(3), lb(3), ta(3), tb(3);
        va->Radiance(v, la);
        vb->Radiance(v, lb);
        va->Transmittance(v, ta);
        vb->Transmittance(v, tb);
        for (int c = 0; c < 3; ++c) {
          EXPECT_NEAR(lb[c], la[c], 5e-3 * la[c]) << "altitude " << altitude << " channel " << c;
          EXPECT_NEAR(tb[c], ta[c], 2e-3 * ta[c] + 1e-9) << "altitude " << altitude << " channel " << c;
        }
      }
    }
  }
}

// The path tracer on the tabulated copy agrees with source4d on the same copy within its noise
// (3 standard errors plus source4d's 1 % error budget): the majorant bounds the table's densities.
TEST(DensityTable, ReferenceAgreesWithSource4dOnATabulatedAtmosphere) {
  const AtmosphereParameters p = TabulatedEarth(500.0);
  const auto reference = CreateModel("reference", p, {{"samples", "2048"}, {"seed", "3"}});
  const auto source4d = CreateModel("source4d", p);
  const glm::dvec3 sun = DirectionFromZenithAzimuth(glm::radians(60.0), 0.0);
  const auto vr = reference->View(0.0, sun);
  const auto vs = source4d->View(0.0, sun);
  for (const glm::dvec3& v : {DirectionFromZenithAzimuth(0.0, 0.0), DirectionFromZenithAzimuth(glm::radians(80.0),
                                                                                                glm::radians(90.0))}) {
    std::vector<double> l(3), e(3), s(3);
    vr->RadianceEstimate(v, l, e);
    vs->Radiance(v, s);
    for (int c = 0; c < 3; ++c) EXPECT_NEAR(s[c], l[c], 3.0 * e[c] + 0.01 * l[c]) << "channel " << c;
  }
}

}  // namespace
}  // namespace atmo
