// The property tests of tests/property_test.cc on the GL backend, through the same generator
// (tests/property_generator.h): random valid atmospheres over many decades, observers from the
// ground to 1000 km, horizontal and grazing views, suns below the horizon. Every answer of the
// float GPU path must be finite, radiance >= 0 and transmittance in [0, 1].
// - hillaire: HillaireGl's tables, then per observer its sky-view pass and one Sample pass over
//   that observer's random views (what `atmo sample --backend gl` does);
// - elek: the tables computed on GL (PrecomputeElekGl) answered by the model's views.
// CI runs the counts below (ATMO_PROPERTY_SCALE=1); scripts/property_sweep.sh multiplies the
// atmospheres.
#include <cmath>
#include <cstdio>
#include <memory>
#include <random>
#include <vector>

#include <gtest/gtest.h>

#include "gl/elek_gl.h"
#include "gl/hillaire_gl.h"
#include "gl_test_context.h"
#include "models/elek_model.h"
#include "models/hillaire_model.h"
#include "property_generator.h"

namespace atmo::gl {
namespace {

using atmo::testing::RandomAtmosphere;
using atmo::testing::RandomObserver;
using atmo::testing::RandomView;
using atmo::testing::Scale;

bool Physical(double radiance, double transmittance) {
  return std::isfinite(radiance) && radiance >= 0.0 && transmittance >= 0.0 && transmittance <= 1.0;
}

// `atmospheres` random atmospheres, `observers` observers each, `views` views per observer;
// returns the number of queries checked.
int CheckHillaireGl(const Context& context, int atmospheres, int observers, int views, std::uint64_t seed) {
  const HillaireSettings settings = HillaireSettings::FromOptions(
      {{"transmittance_lut", "32x16"}, {"multiple_scattering_lut", "8x8"}, {"multiple_scattering_directions", "8"},
       {"sky_view_lut", "32x16"}, {"ground_irradiance_lut", "8"}});
  std::mt19937_64 rng(seed);
  int checked = 0;
  for (int a = 0; a < atmospheres; ++a) {
    const AtmosphereParameters p = RandomAtmosphere(rng);
    HillaireGl sky(context, p, settings);
    sky.Precompute();
    for (int o = 0; o < observers; ++o) {
      double altitude_m = 0.0;
      glm::dvec3 sun;
      RandomObserver(rng, p, altitude_m, sun);
      std::vector<glm::dvec3> directions;
      for (int v = 0; v < views; ++v) directions.push_back(RandomView(rng, p, altitude_m));
      sky.SetView(altitude_m, sun, /*ground=*/false);
      std::vector<double> radiance, transmittance;
      sky.Sample(directions, radiance, transmittance);
      const std::size_t nc = sky.channel_count();
      EXPECT_EQ(radiance.size(), directions.size() * nc);
      for (std::size_t i = 0; i < radiance.size(); ++i) {
        if (!Physical(radiance[i], transmittance[i])) {
          ADD_FAILURE() << "hillaire gl atmosphere " << a << " (" << ToJson(p) << "): altitude " << altitude_m
                        << " view z " << directions[i / nc].z << " sun z " << sun.z << ": L " << radiance[i] << " T "
                        << transmittance[i];
          return checked;
        }
      }
      checked += views;
    }
  }
  return checked;
}

int CheckElekGl(const Context& context, int atmospheres, int queries, std::uint64_t seed) {
  const ElekSettings settings = ElekSettings::FromOptions({{"size", "8x16x8"}, {"orders", "2"}});
  std::mt19937_64 rng(seed);
  int checked = 0;
  for (int a = 0; a < atmospheres; ++a) {
    const AtmosphereParameters p = RandomAtmosphere(rng);
    ElekModel model(p, settings);
    PrecomputeElekGl(context, model);
    std::vector<double> l(3), t(3), d(3);
    for (const atmo::testing::Query& q : atmo::testing::RandomQueries(rng, p, queries)) {
      const auto view = model.View(q.altitude_m, q.sun);
      view->Radiance(q.view, l);
      view->Transmittance(q.view, t);
      view->SunDiscRadiance(q.view, d);
      for (int c = 0; c < 3; ++c) {
        if (!Physical(l[c], t[c]) || !(std::isfinite(d[c]) && d[c] >= 0.0)) {
          ADD_FAILURE() << "elek gl atmosphere " << a << " (" << ToJson(p) << "): altitude " << q.altitude_m
                        << " view z " << q.view.z << " sun z " << q.sun.z << ": L " << l[c] << " T " << t[c]
                        << " disc " << d[c];
          return checked;
        }
      }
      ++checked;
    }
  }
  return checked;
}

TEST(GlProperties, RandomAtmospheresAndQueriesGiveFinitePhysicalValues) {
  ATMO_REQUIRE_GL_CONTEXT(context);
  const int s = Scale();
  const int hillaire = CheckHillaireGl(context, 10 * s, 4, 50, 11);
  const int elek = CheckElekGl(context, 6 * s, 100, 12);
  std::printf("GL: %d hillaire + %d elek queries, all finite, radiance >= 0, transmittance in [0, 1]\n", hillaire,
              elek);
  EXPECT_EQ(hillaire, 2000 * s);
  EXPECT_EQ(elek, 600 * s);
}

}  // namespace
}  // namespace atmo::gl
