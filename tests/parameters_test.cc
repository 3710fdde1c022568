// Tests of atmosphere parameters: presets against docs/design.md §3, validation messages, JSON round
// trips and merges, the parameter hash, and density profiles against their closed forms.
#include <gtest/gtest.h>

#include <cmath>
#include <cstdint>
#include <filesystem>
#include <fstream>
#include <functional>
#include <limits>
#include <numbers>
#include <string>
#include <vector>

#include "atmo/error.h"
#include "atmo/parameters.h"

namespace atmo {
namespace {

// The message of the atmo::Error that `f` throws; fails the test if it throws nothing.
std::string ErrorMessage(const std::function<void()>& f) {
  try {
    f();
  } catch (const Error& error) {
    return error.what();
  }
  ADD_FAILURE() << "expected atmo::Error";
  return "";
}

// ---------------------------------------------------------------------------------------------
// Presets.

TEST(Presets, NamesListThePresets) {
  EXPECT_EQ(PresetNames(), (std::vector<std::string>{"earth", "earth-spectral", "atmosphere-plus", "simple", "us-standard", "tropical", "midlatitude-summer", "midlatitude-winter", "subarctic-summer", "subarctic-winter"}));
  for (const std::string& name : PresetNames()) {
    const AtmosphereParameters p = Preset(name);
    EXPECT_EQ(p.name, name);
    EXPECT_NO_THROW(Validate(p)) << name;
    const bool spectral = name != "earth" && name != "atmosphere-plus" && name != "simple";
    EXPECT_EQ(p.channel_count(), spectral ? 15u : 3u) << name;
  }
}

TEST(Presets, UnknownNameListsKnownOnes) {
  EXPECT_EQ(ErrorMessage([] { Preset("x"); }),
            "unknown preset 'x' (known: earth, earth-spectral, atmosphere-plus, simple, us-standard, tropical, midlatitude-summer, midlatitude-winter, subarctic-summer, subarctic-winter)");
}

TEST(Presets, EarthMatchesDesignTable) {
  const AtmosphereParameters p = Preset("earth");
  EXPECT_EQ(p.geometry, Geometry::kSpherical);
  EXPECT_DOUBLE_EQ(p.ground_radius_m, 6360e3);
  EXPECT_DOUBLE_EQ(p.top_radius_m, 6460e3);
  EXPECT_EQ(p.wavelengths_nm, (std::vector<double>{680, 550, 440}));

  EXPECT_DOUBLE_EQ(p.rayleigh.scattering_per_m[0], 5.802e-6);
  EXPECT_DOUBLE_EQ(p.rayleigh.scattering_per_m[1], 13.558e-6);
  EXPECT_DOUBLE_EQ(p.rayleigh.scattering_per_m[2], 33.100e-6);
  EXPECT_EQ(p.rayleigh.absorption_per_m, (std::vector<double>{0, 0, 0}));
  EXPECT_EQ(p.rayleigh.density, DensityProfile::Exponential(8000));
  EXPECT_EQ(p.rayleigh.phase, PhaseFunction::kRayleigh);

  for (std::size_t c = 0; c < 3; ++c) {
    EXPECT_DOUBLE_EQ(p.mie.scattering_per_m[c], 3.996e-6);
    EXPECT_DOUBLE_EQ(p.mie.absorption_per_m[c], 0.444e-6);
    // Extinction 4.440e-6: within a few ulps of the sum of the two decimal constants.
    EXPECT_NEAR(p.mie.extinction_per_m(c), 4.440e-6, 1e-20);
  }
  EXPECT_EQ(p.mie.density, DensityProfile::Exponential(1200));
  EXPECT_EQ(p.mie.phase, PhaseFunction::kCornetteShanks);
  EXPECT_DOUBLE_EQ(p.mie.phase_g, 0.8);

  EXPECT_EQ(p.ozone.scattering_per_m, (std::vector<double>{0, 0, 0}));
  EXPECT_DOUBLE_EQ(p.ozone.absorption_per_m[0], 0.650e-6);
  EXPECT_DOUBLE_EQ(p.ozone.absorption_per_m[1], 1.881e-6);
  EXPECT_DOUBLE_EQ(p.ozone.absorption_per_m[2], 0.085e-6);
  EXPECT_EQ(p.ozone.density, DensityProfile::Tent(10e3, 25e3, 40e3));
  EXPECT_EQ(p.ozone.phase, PhaseFunction::kIsotropic);
  EXPECT_TRUE(p.rayleigh.present());
  EXPECT_TRUE(p.mie.present());
  EXPECT_TRUE(p.ozone.present());

  EXPECT_EQ(p.ground_albedo, (std::vector<double>{0.3, 0.3, 0.3}));
  EXPECT_DOUBLE_EQ(p.sun_angular_radius_rad, 0.004675);
  EXPECT_EQ(p.solar_irradiance, (std::vector<double>{1, 1, 1}));
  EXPECT_DOUBLE_EQ(p.exposure, 10.0);
  EXPECT_DOUBLE_EQ(p.observer_altitude_m, 0.0);
}

TEST(Presets, AtmospherePlusMatchesDesignTable) {
  const AtmosphereParameters p = Preset("atmosphere-plus");
  EXPECT_EQ(p.geometry, Geometry::kSpherical);
  EXPECT_DOUBLE_EQ(p.ground_radius_m, 6371e3);
  EXPECT_DOUBLE_EQ(p.top_radius_m, 6471e3);
  EXPECT_EQ(p.wavelengths_nm, (std::vector<double>{650, 510, 475}));
  EXPECT_DOUBLE_EQ(p.rayleigh.scattering_per_m[0], 6.55e-6);
  EXPECT_DOUBLE_EQ(p.rayleigh.scattering_per_m[1], 1.73e-5);
  EXPECT_DOUBLE_EQ(p.rayleigh.scattering_per_m[2], 2.30e-5);
  EXPECT_EQ(p.rayleigh.density, DensityProfile::Exponential(8000));
  EXPECT_EQ(p.rayleigh.phase, PhaseFunction::kRayleigh);
  for (std::size_t c = 0; c < 3; ++c) {
    EXPECT_DOUBLE_EQ(p.mie.scattering_per_m[c], 2e-6);
    // Extinction = scattering / 0.9, i.e. single-scattering albedo 0.9.
    EXPECT_DOUBLE_EQ(p.mie.absorption_per_m[c], 2e-6 / 0.9 - 2e-6);
    EXPECT_DOUBLE_EQ(p.mie.scattering_per_m[c] / p.mie.extinction_per_m(c), 0.9);
  }
  EXPECT_EQ(p.mie.density, DensityProfile::Exponential(1200));
  EXPECT_EQ(p.mie.phase, PhaseFunction::kCornetteShanks);
  EXPECT_DOUBLE_EQ(p.mie.phase_g, 0.85);  // the seed's -0.85 in its opposite sign convention
  EXPECT_FALSE(p.ozone.present());
  EXPECT_EQ(p.ground_albedo, (std::vector<double>{0, 0, 0}));
  EXPECT_DOUBLE_EQ(p.sun_angular_radius_rad, 0.004675);
  EXPECT_EQ(p.solar_irradiance, (std::vector<double>{20.344770, 16.907042, 23.453083}));
  EXPECT_DOUBLE_EQ(p.exposure, 1.0);
  EXPECT_DOUBLE_EQ(p.observer_altitude_m, 0.0);
}

TEST(Presets, SimpleMatchesDesignTable) {
  const AtmosphereParameters p = Preset("simple");
  EXPECT_EQ(p.geometry, Geometry::kHalfSpace);
  EXPECT_DOUBLE_EQ(p.ground_radius_m, 0.0);
  EXPECT_DOUBLE_EQ(p.top_radius_m, 0.0);
  EXPECT_EQ(p.wavelengths_nm, (std::vector<double>{680, 550, 440}));
  EXPECT_EQ(p.rayleigh.scattering_per_m, (std::vector<double>{0.1, 0.3, 0.7}));
  EXPECT_EQ(p.rayleigh.absorption_per_m, (std::vector<double>{0, 0, 0}));
  EXPECT_EQ(p.rayleigh.density, DensityProfile::Constant());
  EXPECT_EQ(p.rayleigh.phase, PhaseFunction::kIsotropic);
  EXPECT_TRUE(p.rayleigh.present());
  EXPECT_FALSE(p.mie.present());
  EXPECT_FALSE(p.ozone.present());
  EXPECT_EQ(p.ground_albedo, (std::vector<double>{0, 0, 0}));
  EXPECT_DOUBLE_EQ(p.sun_angular_radius_rad, 0.0045);
  EXPECT_EQ(p.solar_irradiance, (std::vector<double>{1, 1, 1}));
  EXPECT_DOUBLE_EQ(p.exposure, 12.566370614359172);
  EXPECT_DOUBLE_EQ(p.exposure, 4.0 * std::numbers::pi);
  EXPECT_DOUBLE_EQ(p.observer_altitude_m, -0.3);
}

// ---------------------------------------------------------------------------------------------
// Density profiles.

TEST(DensityProfile, ExponentialIsExpOfMinusAltitudeOverScaleHeight) {
  const DensityProfile profile = DensityProfile::Exponential(8000);
  for (double h : {0.0, 1000.0, 8000.0, 20000.0, 100e3}) {
    EXPECT_NEAR(profile.Evaluate(h), std::exp(-h / 8000), 1e-15) << h;
  }
  // Below 0 (inside a half-space) the density is clamped to 1.
  EXPECT_DOUBLE_EQ(profile.Evaluate(-500.0), 1.0);
}

TEST(DensityProfile, TentRisesToOneAtPeakAndIsClampedOutside) {
  const DensityProfile tent = DensityProfile::Tent(10e3, 25e3, 40e3);
  // Tolerance: the linear terms 1/15 km and constants are rounded decimals, a few ulps apart.
  constexpr double kTolerance = 1e-12;
  EXPECT_NEAR(tent.Evaluate(10e3), 0.0, kTolerance);
  EXPECT_NEAR(tent.Evaluate(17.5e3), 0.5, kTolerance);
  EXPECT_NEAR(tent.Evaluate(25e3), 1.0, kTolerance);
  EXPECT_NEAR(tent.Evaluate(32.5e3), 0.5, kTolerance);
  EXPECT_NEAR(tent.Evaluate(40e3), 0.0, kTolerance);
  EXPECT_DOUBLE_EQ(tent.Evaluate(0.0), 0.0);
  EXPECT_DOUBLE_EQ(tent.Evaluate(5e3), 0.0);
  EXPECT_DOUBLE_EQ(tent.Evaluate(45e3), 0.0);
  EXPECT_DOUBLE_EQ(tent.Evaluate(100e3), 0.0);
  for (double h = 0; h <= 60e3; h += 250) {
    EXPECT_GE(tent.Evaluate(h), 0.0);
    EXPECT_LE(tent.Evaluate(h), 1.0);
  }
}

TEST(DensityProfile, ConstantIsOneEverywhere) {
  const DensityProfile profile = DensityProfile::Constant();
  for (double h : {-10.0, 0.0, 1.0, 1e6}) EXPECT_DOUBLE_EQ(profile.Evaluate(h), 1.0);
}

TEST(DensityProfile, TentRejectsUnorderedPoints) {
  EXPECT_THROW(DensityProfile::Tent(25e3, 10e3, 40e3), Error);
}

// ---------------------------------------------------------------------------------------------
// Validation: one mutation of a valid preset per check, each naming its key.

struct InvalidCase {
  const char* preset;
  std::function<void(AtmosphereParameters&)> mutate;
  std::string expected;  // a substring of the message: at least the key
};

TEST(Validate, EachInvalidValueNamesItsKey) {
  const double nan = std::nan("");
  const double inf = std::numeric_limits<double>::infinity();
  using P = AtmosphereParameters;
  const std::vector<InvalidCase> cases = {
      // Channels.
      {"earth", [](P& p) { p.wavelengths_nm.clear(); },
       "wavelengths_nm must have at least one channel"},
      {"earth", [](P& p) { p.wavelengths_nm.assign(4097, 500.0); }, "wavelengths_nm has 4097"},
      {"earth", [](P& p) { p.wavelengths_nm[1] = 0; }, "wavelengths_nm[1]"},
      {"earth", [](P& p) { p.wavelengths_nm[2] = -440; }, "wavelengths_nm[2]"},
      {"earth", [=](P& p) { p.wavelengths_nm[0] = nan; }, "wavelengths_nm[0]"},
      // Per-channel vector lengths.
      {"earth", [](P& p) { p.ozone.absorption_per_m.pop_back(); },
       "ozone.absorption_per_m has 2 values but there are 3 channels"},
      {"earth", [](P& p) { p.rayleigh.scattering_per_m.push_back(1e-6); },
       "rayleigh.scattering_per_m has 4 values"},
      {"earth", [](P& p) { p.rayleigh.absorption_per_m.clear(); }, "rayleigh.absorption_per_m has 0"},
      {"earth", [](P& p) { p.mie.scattering_per_m.pop_back(); }, "mie.scattering_per_m has 2"},
      {"earth", [](P& p) { p.ground_albedo.pop_back(); }, "ground_albedo has 2 values"},
      {"earth", [](P& p) { p.solar_irradiance.push_back(1); }, "solar_irradiance has 4 values"},
      // Coefficients.
      {"earth", [](P& p) { p.rayleigh.scattering_per_m[1] = -1; },
       "rayleigh.scattering_per_m[1] must be in [0, 1000] per m (got -1)"},
      {"earth", [=](P& p) { p.mie.scattering_per_m[2] = nan; }, "mie.scattering_per_m[2]"},
      {"earth", [=](P& p) { p.mie.absorption_per_m[0] = inf; }, "mie.absorption_per_m[0]"},
      {"earth", [](P& p) { p.ozone.absorption_per_m[1] = -1e-6; }, "ozone.absorption_per_m[1]"},
      {"earth", [](P& p) { p.ozone.scattering_per_m[0] = -1; }, "ozone.scattering_per_m[0]"},
      // Geometry.
      {"earth", [](P& p) { p.ground_radius_m = 0; }, "ground_radius_m must be in [1, 1e+10] m (got 0)"},
      {"earth", [](P& p) { p.ground_radius_m = -1; }, "ground_radius_m"},
      {"earth", [=](P& p) { p.ground_radius_m = nan; }, "ground_radius_m"},
      {"earth", [](P& p) { p.top_radius_m = 6000000; },
       "top_radius_m (6000000) must be greater than ground_radius_m (6360000)"},
      {"earth", [](P& p) { p.top_radius_m = p.ground_radius_m; }, "top_radius_m"},
      {"earth", [=](P& p) { p.top_radius_m = inf; }, "top_radius_m"},
      {"simple", [=](P& p) { p.ground_radius_m = nan; }, "ground_radius_m"},
      // Phase asymmetry.
      {"earth", [](P& p) { p.mie.phase_g = 1; }, "mie.phase_g must satisfy |g| < 1 (got 1)"},
      {"earth", [](P& p) { p.mie.phase_g = -1.5; }, "mie.phase_g"},
      {"earth", [=](P& p) { p.mie.phase_g = nan; }, "mie.phase_g"},
      {"earth", [](P& p) { p.rayleigh.phase_g = 1; }, "rayleigh.phase_g"},
      {"earth", [](P& p) { p.ozone.phase_g = -1; }, "ozone.phase_g"},
      // Density layers.
      {"earth", [](P& p) { p.rayleigh.density.lower.width_m = -1; },
       "rayleigh.density.lower.width_m must be in [0, 1e+11] m (got -1)"},
      {"earth", [](P& p) { p.ozone.density.upper.width_m = -5; }, "ozone.density.upper.width_m"},
      {"earth", [=](P& p) { p.mie.density.upper.exp_term = nan; }, "mie.density.upper.exp_term"},
      {"earth", [=](P& p) { p.mie.density.lower.exp_scale_per_m = inf; },
       "mie.density.lower.exp_scale_per_m"},
      {"earth", [=](P& p) { p.ozone.density.lower.linear_term_per_m = -inf; },
       "ozone.density.lower.linear_term_per_m"},
      {"earth", [=](P& p) { p.rayleigh.density.upper.constant_term = nan; },
       "rayleigh.density.upper.constant_term"},
      // Ground albedo.
      {"earth", [](P& p) { p.ground_albedo[0] = 1.5; },
       "ground_albedo[0] must be in [0, 1] (got 1.5)"},
      {"earth", [](P& p) { p.ground_albedo[2] = -0.1; }, "ground_albedo[2]"},
      {"earth", [=](P& p) { p.ground_albedo[1] = nan; }, "ground_albedo[1]"},
      // Sun.
      {"earth", [](P& p) { p.sun_angular_radius_rad = 0; }, "sun_angular_radius_rad"},
      {"earth", [](P& p) { p.sun_angular_radius_rad = -0.01; }, "sun_angular_radius_rad"},
      {"earth", [](P& p) { p.sun_angular_radius_rad = std::numbers::pi / 2; },
       "sun_angular_radius_rad"},
      {"earth", [=](P& p) { p.sun_angular_radius_rad = nan; }, "sun_angular_radius_rad"},
      {"earth", [](P& p) { p.solar_irradiance[1] = -1; }, "solar_irradiance[1]"},
      {"earth", [=](P& p) { p.solar_irradiance[0] = inf; }, "solar_irradiance[0]"},
      // Display defaults.
      {"earth", [](P& p) { p.exposure = 0; }, "exposure"},
      {"earth", [](P& p) { p.exposure = -1; }, "exposure"},
      {"earth", [=](P& p) { p.exposure = inf; }, "exposure"},
      {"earth", [](P& p) { p.observer_altitude_m = -1; }, "observer_altitude_m"},
      {"earth", [=](P& p) { p.observer_altitude_m = nan; }, "observer_altitude_m"},
      {"simple", [=](P& p) { p.observer_altitude_m = inf; }, "observer_altitude_m"},
  };
  for (std::size_t i = 0; i < cases.size(); ++i) {
    AtmosphereParameters p = Preset(cases[i].preset);
    cases[i].mutate(p);
    const std::string message = ErrorMessage([&] { Validate(p); });
    EXPECT_NE(message.find(cases[i].expected), std::string::npos)
        << "case " << i << ": expected '" << cases[i].expected << "' in '" << message << "'";
    EXPECT_EQ(message.find('\n'), std::string::npos) << "case " << i << ": " << message;
  }
}

TEST(Validate, HalfSpaceIgnoresRadiiAndAllowsObserverBelowBoundary) {
  AtmosphereParameters p = Preset("simple");
  p.ground_radius_m = 0;
  p.top_radius_m = 0;
  p.observer_altitude_m = -10;
  EXPECT_NO_THROW(Validate(p));
}

// ---------------------------------------------------------------------------------------------
// JSON.

TEST(ParametersJson, RoundTripIsExactForEveryPreset) {
  for (const std::string& name : PresetNames()) {
    const AtmosphereParameters p = Preset(name);
    const std::string json = ToJson(p);
    const AtmosphereParameters back = FromJson(json);
    EXPECT_EQ(back, p) << name;
    EXPECT_EQ(back.name, name);
    EXPECT_EQ(ToJson(back), json) << name;
  }
}

TEST(ParametersJson, RoundTripIsExactForCustomParameters) {
  AtmosphereParameters p = Preset("earth");
  p.name = "custom";
  p.ground_albedo = {0.1, 0.2, 0.30000000000000004};
  p.mie.phase = PhaseFunction::kHenyeyGreenstein;
  p.mie.phase_g = 0.7612345678901234;
  p.rayleigh.phase = PhaseFunction::kModifiedRayleigh;
  p.rayleigh.scattering_per_m[0] = 1.0 / 3.0 * 1e-5;
  EXPECT_EQ(FromJson(ToJson(p)), p);
}

TEST(ParametersJson, WritesEveryKeyWithTwoSpaceIndent) {
  const std::string json = ToJson(Preset("earth"));
  EXPECT_EQ(json.rfind("{\n  \"preset\": \"earth\",\n  \"geometry\": \"spherical\",", 0), 0u)
      << json;
  for (const char* key :
       {"\"ground_radius_m\"", "\"top_radius_m\"", "\"wavelengths_nm\"", "\"rayleigh\"", "\"mie\"",
        "\"ozone\"", "\"scattering_per_m\"", "\"absorption_per_m\"", "\"phase_function\"",
        "\"phase_g\"", "\"density\"", "\"lower\"", "\"upper\"", "\"width_m\"", "\"exp_term\"",
        "\"exp_scale_per_m\"", "\"linear_term_per_m\"", "\"constant_term\"", "\"ground_albedo\"",
        "\"sun_angular_radius_rad\"", "\"sun_limb_darkening\"", "\"solar_irradiance\"", "\"exposure\"",
        "\"observer_altitude_m\"", "\"cornette_shanks\""}) {
    EXPECT_NE(json.find(key), std::string::npos) << key;
  }
  EXPECT_NE(ToJson(Preset("simple")).find("\"half_space\""), std::string::npos);
}

TEST(ParametersJson, EmptyObjectIsEarth) { EXPECT_EQ(FromJson("{}"), Preset("earth")); }

TEST(ParametersJson, PresetKeyAloneGivesThePreset) {
  EXPECT_EQ(FromJson(R"({"preset": "simple"})"), Preset("simple"));
  EXPECT_EQ(FromJson(R"({"preset": "atmosphere-plus"})"), Preset("atmosphere-plus"));
}

TEST(ParametersJson, PartialConfigOverridesOnlyItsKeys) {
  const AtmosphereParameters p = FromJson(R"({"preset": "earth", "mie": {"phase_g": 0.7}})");
  AtmosphereParameters expected = Preset("earth");
  expected.mie.phase_g = 0.7;
  expected.name = "custom";
  EXPECT_EQ(p, expected);
}

TEST(ParametersJson, NestedDensityMergesKeyByKey) {
  const AtmosphereParameters p = FromJson(
      R"({"preset": "earth", "rayleigh": {"density": {"upper": {"exp_scale_per_m": -1e-4}}}})");
  const AtmosphereParameters earth = Preset("earth");
  EXPECT_DOUBLE_EQ(p.rayleigh.density.upper.exp_scale_per_m, -1e-4);
  EXPECT_EQ(p.rayleigh.density.upper.exp_term, earth.rayleigh.density.upper.exp_term);
  EXPECT_EQ(p.rayleigh.density.lower, earth.rayleigh.density.lower);
  EXPECT_EQ(p.rayleigh.scattering_per_m, earth.rayleigh.scattering_per_m);
  EXPECT_EQ(p.mie, earth.mie);
}

TEST(ParametersJson, NameStaysThePresetWhenValuesAreUnchanged) {
  EXPECT_EQ(FromJson(R"({"preset": "earth", "exposure": 10, "mie": {"phase_g": 0.8}})").name,
            "earth");
  EXPECT_EQ(FromJson(R"({"preset": "earth", "exposure": 11})").name, "custom");
}

TEST(ParametersJson, CustomPresetNameStartsFromEarth) {
  const AtmosphereParameters p = FromJson(R"({"preset": "custom", "exposure": 3})");
  AtmosphereParameters expected = Preset("earth");
  expected.exposure = 3;
  expected.name = "custom";
  EXPECT_EQ(p, expected);
}

TEST(ParametersJson, SingleNumberBroadcastsToEveryChannel) {
  const AtmosphereParameters p = FromJson(
      R"({"preset": "earth", "ground_albedo": 0.5, "mie": {"scattering_per_m": 1e-6}})");
  EXPECT_EQ(p.ground_albedo, (std::vector<double>{0.5, 0.5, 0.5}));
  EXPECT_EQ(p.mie.scattering_per_m, (std::vector<double>{1e-6, 1e-6, 1e-6}));
}

TEST(ParametersJson, BroadcastUsesTheChannelCountOfTheDocumentsWavelengths) {
  const AtmosphereParameters p = FromJson(R"({
    "preset": "earth",
    "wavelengths_nm": [400, 500, 600, 700],
    "rayleigh": {"scattering_per_m": 1e-5, "absorption_per_m": 0},
    "mie": {"scattering_per_m": 4e-6, "absorption_per_m": 4e-7},
    "ozone": {"scattering_per_m": 0, "absorption_per_m": [1e-6, 2e-6, 1e-6, 1e-7]},
    "ground_albedo": 0.2,
    "solar_irradiance": 1.5
  })");
  EXPECT_EQ(p.channel_count(), 4u);
  EXPECT_EQ(p.rayleigh.scattering_per_m, std::vector<double>(4, 1e-5));
  EXPECT_EQ(p.mie.absorption_per_m, std::vector<double>(4, 4e-7));
  EXPECT_EQ(p.ground_albedo, std::vector<double>(4, 0.2));
  EXPECT_EQ(p.solar_irradiance, std::vector<double>(4, 1.5));
}

TEST(ParametersJson, ChangingChannelCountWithoutVectorsFailsValidation) {
  EXPECT_NE(ErrorMessage([] { FromJson(R"({"wavelengths_nm": [500]})"); })
                .find("rayleigh.scattering_per_m has 3 values but there is 1 channel"),
            std::string::npos);
}

TEST(ParametersJson, EveryPhaseFunctionAndGeometryNameReadsBack) {
  for (PhaseFunction phase :
       {PhaseFunction::kIsotropic, PhaseFunction::kRayleigh, PhaseFunction::kModifiedRayleigh,
        PhaseFunction::kCornetteShanks, PhaseFunction::kHenyeyGreenstein}) {
    const std::string json =
        R"({"mie": {"phase_function": ")" + std::string(ToString(phase)) + R"("}})";
    EXPECT_EQ(FromJson(json).mie.phase, phase) << json;
  }
  EXPECT_EQ(ToString(PhaseFunction::kModifiedRayleigh), "modified_rayleigh");
  EXPECT_EQ(ToString(Geometry::kHalfSpace), "half_space");
  EXPECT_EQ(FromJson(R"({"preset": "simple", "geometry": "half_space"})").geometry,
            Geometry::kHalfSpace);
}

TEST(ParametersJson, MalformedJsonSaysWhere) {
  const std::string message = ErrorMessage([] { FromJson("{\n  \"preset\": \"earth\",\n  }"); });
  EXPECT_NE(message.find("malformed JSON"), std::string::npos) << message;
  EXPECT_NE(message.find("line 3"), std::string::npos) << message;
  EXPECT_EQ(message.find('\n'), std::string::npos) << message;
  EXPECT_NE(ErrorMessage([] { FromJson(""); }).find("malformed JSON"), std::string::npos);
}

TEST(ParametersJson, RootMustBeAnObject) {
  EXPECT_NE(ErrorMessage([] { FromJson("[1, 2]"); }).find("JSON object"), std::string::npos);
}

TEST(ParametersJson, UnknownKeysAreNamedWithTheirPath) {
  EXPECT_EQ(ErrorMessage([] { FromJson(R"({"foo": 1})"); }), "unknown key 'foo'");
  EXPECT_EQ(ErrorMessage([] { FromJson(R"({"rayleigh": {"foo": 1}})"); }),
            "unknown key 'rayleigh.foo'");
  EXPECT_EQ(ErrorMessage([] { FromJson(R"({"ozone": {"density": {"lower": {"bar": 0}}}})"); }),
            "unknown key 'ozone.density.lower.bar'");
}

TEST(ParametersJson, WrongTypesAreNamedWithTheirPath) {
  EXPECT_EQ(ErrorMessage([] { FromJson(R"({"rayleigh": {"scattering_per_m": "abc"}})"); }),
            "rayleigh.scattering_per_m must be a number or an array of numbers");
  EXPECT_EQ(ErrorMessage([] { FromJson(R"({"ground_albedo": [0.1, "x", 0.3]})"); }),
            "ground_albedo must be a number or an array of numbers");
  EXPECT_EQ(ErrorMessage([] { FromJson(R"({"exposure": "bright"})"); }),
            "exposure must be a number");
  EXPECT_EQ(ErrorMessage([] { FromJson(R"({"exposure": true})"); }), "exposure must be a number");
  EXPECT_EQ(ErrorMessage([] { FromJson(R"({"mie": 5})"); }), "mie must be an object");
  EXPECT_EQ(ErrorMessage([] { FromJson(R"({"preset": 3})"); }), "preset must be a string");
  EXPECT_EQ(ErrorMessage([] { FromJson(R"({"mie": {"phase_function": 1}})"); }),
            "mie.phase_function must be a string");
}

TEST(ParametersJson, UnknownNamesListTheKnownOnes) {
  const std::string phase =
      ErrorMessage([] { FromJson(R"({"rayleigh": {"phase_function": "mie"}})"); });
  EXPECT_NE(phase.find("rayleigh.phase_function"), std::string::npos) << phase;
  EXPECT_NE(phase.find("unknown phase function 'mie'"), std::string::npos) << phase;
  EXPECT_NE(phase.find("henyey_greenstein"), std::string::npos) << phase;
  const std::string geometry = ErrorMessage([] { FromJson(R"({"geometry": "flat"})"); });
  EXPECT_NE(geometry.find("unknown geometry 'flat'"), std::string::npos) << geometry;
  EXPECT_EQ(ErrorMessage([] { FromJson(R"({"preset": "mars"})"); }),
            "unknown preset 'mars' (known: earth, earth-spectral, atmosphere-plus, simple, us-standard, tropical, midlatitude-summer, midlatitude-winter, subarctic-summer, subarctic-winter)");
}

TEST(ParametersJson, ValuesAreValidated) {
  EXPECT_EQ(ErrorMessage([] { FromJson(R"({"preset": "earth", "mie": {"phase_g": 1}})"); }),
            "mie.phase_g must satisfy |g| < 1 (got 1)");
  EXPECT_EQ(ErrorMessage([] { FromJson(R"({"ground_albedo": [1.5, 0.3, 0.3]})"); }),
            "ground_albedo[0] must be in [0, 1] (got 1.5)");
}

class ParametersFileTest : public ::testing::Test {
 protected:
  void SetUp() override {
    directory_ = std::filesystem::temp_directory_path() /
                 ("atmo_parameters_test_" + std::to_string(::testing::UnitTest::GetInstance()
                                                                ->random_seed()) +
                  "_" + ::testing::UnitTest::GetInstance()->current_test_info()->name());
    std::filesystem::create_directories(directory_);
  }
  void TearDown() override { std::filesystem::remove_all(directory_); }

  std::filesystem::path Write(const std::string& name, const std::string& text) {
    const std::filesystem::path path = directory_ / name;
    std::ofstream(path) << text;
    return path;
  }

  std::filesystem::path directory_;
};

TEST_F(ParametersFileTest, MissingFileSaysCannotRead) {
  const std::filesystem::path path = directory_ / "missing.json";
  const std::string message = ErrorMessage([&] { LoadParametersFile(path); });
  EXPECT_EQ(message.rfind("cannot read config '" + path.string() + "': ", 0), 0u) << message;
}

TEST_F(ParametersFileTest, DirectorySaysCannotRead) {
  const std::string message = ErrorMessage([&] { LoadParametersFile(directory_); });
  EXPECT_EQ(message.rfind("cannot read config '", 0), 0u) << message;
}

TEST_F(ParametersFileTest, ReadsWhatToJsonWrote) {
  const AtmosphereParameters p = Preset("atmosphere-plus");
  EXPECT_EQ(LoadParametersFile(Write("plus.json", ToJson(p))), p);
}

TEST_F(ParametersFileTest, ErrorsArePrefixedWithThePath) {
  const std::filesystem::path bad = Write("bad.json", "{ \"preset\": ");
  const std::string message = ErrorMessage([&] { LoadParametersFile(bad); });
  EXPECT_EQ(message.rfind("config '" + bad.string() + "': malformed JSON", 0), 0u) << message;
  const std::filesystem::path invalid = Write("invalid.json", R"({"exposure": -1})");
  EXPECT_EQ(ErrorMessage([&] { LoadParametersFile(invalid); }),
            "config '" + invalid.string() + "': exposure must be in [1e-10, 1e+10] (got -1)");
}

// ---------------------------------------------------------------------------------------------
// Hash.

// FNV-1a 64 written out independently, checked against the published test vector for "a".
std::uint64_t ReferenceFnv1a(const std::string& bytes) {
  std::uint64_t hash = 0xcbf29ce484222325ull;
  for (unsigned char c : bytes) hash = (hash ^ c) * 0x100000001b3ull;
  return hash;
}

TEST(ParameterHash, IsFnv1aOfTheCanonicalJsonWithoutTheName) {
  ASSERT_EQ(ReferenceFnv1a("a"), 0xaf63dc4c8601ec8cull);
  AtmosphereParameters p = Preset("earth");
  const std::uint64_t hash = ParameterHash(p);
  p.name = "custom";
  EXPECT_EQ(hash, ReferenceFnv1a(ToJson(p)));
  p.name = "anything";
  EXPECT_EQ(ParameterHash(p), hash);  // the physics decide, not the name
}

TEST(ParameterHash, StableEqualForEqualAndSensitiveToOneCoefficient) {
  const AtmosphereParameters p = Preset("earth");
  const std::uint64_t hash = ParameterHash(p);
  EXPECT_EQ(ParameterHash(p), hash);
  EXPECT_EQ(ParameterHash(Preset("earth")), hash);
  EXPECT_EQ(ParameterHash(FromJson(ToJson(p))), hash);
  AtmosphereParameters changed = p;
  changed.rayleigh.scattering_per_m[1] = std::nextafter(changed.rayleigh.scattering_per_m[1], 1.0);
  EXPECT_NE(ParameterHash(changed), hash);
  EXPECT_NE(ParameterHash(Preset("simple")), hash);
  EXPECT_NE(ParameterHash(Preset("atmosphere-plus")), hash);
}

TEST(ParameterHash, HexIsSixteenLowercaseDigits) {
  for (const std::string& name : PresetNames()) {
    const AtmosphereParameters p = Preset(name);
    const std::string hex = ParameterHashHex(p);
    ASSERT_EQ(hex.size(), 16u);
    for (char c : hex) EXPECT_TRUE((c >= '0' && c <= '9') || (c >= 'a' && c <= 'f')) << hex;
    EXPECT_EQ(std::stoull(hex, nullptr, 16), ParameterHash(p));
  }
}

}  // namespace
}  // namespace atmo
