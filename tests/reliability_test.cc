// Reliability (docs/reliability.md): the audit's inputs that crashed, hung, printed NaN with exit
// 0, were silently accepted or overwrote a file, each as a regression test that finishes in
// seconds. The bad inputs are counted in kBadInputs (and the manifest and output tests below);
// docs/reliability.md lists them by category.
#include <sys/stat.h>
#include <unistd.h>

#include <chrono>
#include <cmath>
#include <cstdlib>
#include <filesystem>
#include <limits>
#include <string>
#include <vector>

#include <gtest/gtest.h>

#include "atmo/error.h"
#include "atmo/image.h"
#include "atmo/parameters.h"
#include "cli_fixture.h"
#include "cpu/path_tracer.h"
#include "shared/shared.h"

namespace {

namespace fs = std::filesystem;
using atmo::testing::Lines;
using atmo::testing::ReadFile;
using atmo::testing::RunResult;
using atmo::testing::Split;
using atmo::testing::WriteFile;

constexpr double kNan = std::numeric_limits<double>::quiet_NaN();
constexpr double kInf = std::numeric_limits<double>::infinity();

// ---------------------------------------------------------------------------------------------
// NaN never reaches an index (the second level of the fix of the crash).

TEST(NanSafeLookup, ClampToRangeMapsNanToTheLowerBound) {
  EXPECT_EQ(atmo::shared::ClampToRange(kNan, 0.0, 1.0), 0.0);
  EXPECT_EQ(atmo::shared::ClampToRange(kInf, 0.0, 1.0), 1.0);
  EXPECT_EQ(atmo::shared::ClampToRange(-kInf, 0.0, 1.0), 0.0);
  EXPECT_EQ(atmo::shared::ClampToRange(0.25, 0.0, 1.0), 0.25);
  EXPECT_EQ(atmo::shared::ClampCosine(kNan), -1.0);
  EXPECT_EQ(atmo::shared::SafeSqrt(kNan), 0.0);
  EXPECT_EQ(atmo::shared::ClampDistance(kNan), 0.0);
}

TEST(NanSafeLookup, LinearTapsStayInsideTheTableForAnyCoordinate) {
  for (const bool repeat : {false, true}) {
    for (const double u : {kNan, kInf, -kInf, 1e300, -1e300, 1e154, -0.5, 1.5, 0.0, 1.0, 0.37}) {
      int i0 = -1, i1 = -1;
      double w = kNan;
      atmo::shared::detail::LinearTaps(u, 8, repeat, i0, i1, w);
      EXPECT_GE(i0, 0) << u;
      EXPECT_LT(i0, 8) << u;
      EXPECT_GE(i1, 0) << u;
      EXPECT_LT(i1, 8) << u;
      EXPECT_TRUE(std::isfinite(w)) << u << (repeat ? " repeat" : "");
    }
  }
}

TEST(NanSafeLookup, TextureReadsWithNanCoordinatesGiveTexels) {
  atmo::shared::Texture2D t2(4, 3, /*repeat=*/true);
  for (auto& texel : t2.texels) texel = glm::vec3(2.0f);
  atmo::shared::Texture3D t3(2, 3, 4);
  for (auto& texel : t3.texels) texel = glm::vec3(3.0f);
  for (const double u : {kNan, kInf, -kInf}) {
    EXPECT_EQ(atmo::shared::texture(t2, atmo::shared::vec2(u, u)).x, 2.0) << u;
    EXPECT_EQ(atmo::shared::texture(t3, atmo::shared::vec3(u, 0.5, u)).y, 3.0) << u;
  }
}

// ---------------------------------------------------------------------------------------------
// Validation with physical bounds: one line naming the key, the value and the range.

std::string ValidationMessage(const atmo::AtmosphereParameters& p) {
  try {
    atmo::Validate(p);
  } catch (const atmo::Error& e) {
    return e.what();
  }
  return "";
}

TEST(PhysicalBounds, OutOfRangeValuesNameKeyValueAndRange) {
  using P = atmo::AtmosphereParameters;
  struct Case {
    void (*change)(P&);
    const char* message;
  };
  const Case cases[] = {
      {[](P& p) { p.ground_radius_m = 1e154, p.top_radius_m = 1.1e154; },
       "ground_radius_m must be in [1, 1e+10] m (got 1e+154)"},
      {[](P& p) { p.ground_radius_m = 1e-200, p.top_radius_m = 1e-199; }, "ground_radius_m must be in [1, 1e+10] m"},
      {[](P& p) { p.top_radius_m = p.ground_radius_m + 1.0; }, "top_radius_m - ground_radius_m must be in [1e-05, 10]"},
      {[](P& p) { p.top_radius_m = 12 * p.ground_radius_m; }, "top_radius_m - ground_radius_m"},
      {[](P& p) { p.rayleigh.scattering_per_m[1] = 1e300; },
       "rayleigh.scattering_per_m[1] must be in [0, 1000] per m (got 1e+300)"},
      {[](P& p) { p.ozone.absorption_per_m[0] = 2e3; }, "ozone.absorption_per_m[0] must be in [0, 1000]"},
      {[](P& p) { p.mie.density.upper.exp_term = 1e300; }, "mie.density.upper.exp_term must be in [-1e+06, 1e+06]"},
      {[](P& p) { p.mie.density.lower.linear_term_per_m = -1e300; }, "mie.density.lower.linear_term_per_m"},
      {[](P& p) { p.rayleigh.density.upper.exp_scale_per_m = 1e7; }, "rayleigh.density.upper.exp_scale_per_m"},
      {[](P& p) { p.ozone.density.lower.constant_term = -1e7; }, "ozone.density.lower.constant_term"},
      {[](P& p) { p.ozone.density.lower.width_m = 1e12; }, "ozone.density.lower.width_m must be in [0, 1e+11] m"},
      {[](P& p) { p.mie.phase_g = 0.9999; }, "mie.phase_g must be in [-0.999, 0.999] (got 0.9999)"},
      {[](P& p) { p.wavelengths_nm[2] = 1e9; }, "wavelengths_nm[2] must be in [1, 1e+05] nm (got 1000000000)"},
      {[](P& p) { p.sun_angular_radius_rad = 1e-9; }, "sun_angular_radius_rad must be in [1e-06, pi/2)"},
      {[](P& p) { p.solar_irradiance[0] = 1e20; }, "solar_irradiance[0] must be in [0, 1e+10]"},
      {[](P& p) { p.exposure = 1e20; }, "exposure must be in [1e-10, 1e+10] (got 1e+20)"},
      {[](P& p) { p.observer_altitude_m = 1e12; }, "observer_altitude_m must be in [-1e+11, 1e+11] m"},
  };
  for (const Case& c : cases) {
    P p = atmo::Preset("earth");
    c.change(p);
    const std::string message = ValidationMessage(p);
    EXPECT_NE(message.find(c.message), std::string::npos) << "got '" << message << "', want '" << c.message << "'";
    EXPECT_EQ(message.find('\n'), std::string::npos) << message;
  }
}

TEST(PhysicalBounds, TheBoundsThemselvesAreAccepted) {
  atmo::AtmosphereParameters p = atmo::Preset("earth");
  p.ground_radius_m = 1.0;
  p.top_radius_m = 11.0;
  p.rayleigh.scattering_per_m = {1e3, 1e3, 1e3};
  p.mie.phase_g = 0.999;
  p.mie.density.upper.exp_term = 1e6;
  p.mie.density.upper.exp_scale_per_m = 1e6;
  p.mie.density.upper.linear_term_per_m = -1e6;
  p.observer_altitude_m = 1e11;
  p.sun_angular_radius_rad = 1e-6;
  EXPECT_EQ(ValidationMessage(p), "");
  p.ground_radius_m = 1e10;
  p.top_radius_m = 1e10 * (1.0 + 1e-5);
  EXPECT_EQ(ValidationMessage(p), "");
  for (const std::string& name : atmo::PresetNames()) EXPECT_EQ(ValidationMessage(atmo::Preset(name)), "") << name;
}

// ---------------------------------------------------------------------------------------------
// Bounded loops of the reference model.

// Grazing rays over the audit's 52 796 km planet, every one close to the tangent of the ground
// and of the top: each optical depth is one adaptive quadrature, which must stay bounded.
TEST(BoundedLoops, GrazingTransmittancesOnALargePlanetFinishQuickly) {
  atmo::AtmosphereParameters p = atmo::Preset("earth");
  p.ground_radius_m = 52796e3;
  p.top_radius_m = p.ground_radius_m + 100e3;
  const atmo::cpu::PathTracer tracer(p, atmo::cpu::PathTracerSettings{});
  std::vector<double> out(3);
  const auto start = std::chrono::steady_clock::now();
  for (const double altitude_m : {0.0, 1.0, 1000.0, 99999.0, 100001.0, 400e3}) {
    const double r = p.ground_radius_m + altitude_m;
    // About the tangent to the ground, or to the top for an observer above it.
    const double radius = r > p.top_radius_m ? p.top_radius_m : p.ground_radius_m;
    const double horizon = -std::sqrt(1.0 - (radius / r) * (radius / r));
    for (int k = -20; k <= 20; ++k) {
      const double mu = horizon + k * 1e-9;
      const glm::dvec3 view(std::sqrt(std::max(0.0, 1.0 - mu * mu)), 0.0, mu);
      tracer.Transmittance(glm::dvec3(0.0, 0.0, r), view, out);
      for (double t : out) EXPECT_TRUE(t >= 0.0 && t <= 1.0) << altitude_m << " " << mu << " " << t;
    }
  }
  const double seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
  EXPECT_LT(seconds, 20.0);
}

// The densest allowed medium: optical depths of ~1e8 that the adaptive quadrature cannot resolve
// to 1e-10 (its error measure is weighted by the extinction), and ratio tracking that reaches 0
// in a few steps. Both must stop; the transmittances are 0 or in [0, 1].
TEST(BoundedLoops, DensestMediumFinishesQuickly) {
  atmo::AtmosphereParameters p = atmo::Preset("earth");
  p.rayleigh.scattering_per_m = {1e3, 1e3, 1e3};
  p.mie.absorption_per_m = {1e3, 1e3, 1e3};
  const atmo::cpu::PathTracer tracer(p, atmo::cpu::PathTracerSettings{});
  std::vector<double> out(3);
  const auto start = std::chrono::steady_clock::now();
  for (const double mu : {1.0, 0.5, 0.01, 0.0, -0.01}) {
    const glm::dvec3 view(std::sqrt(1.0 - mu * mu), 0.0, mu);
    tracer.Transmittance(glm::dvec3(0.0, 0.0, p.ground_radius_m + 10.0), view, out);
    for (double t : out) EXPECT_TRUE(t >= 0.0 && t <= 1.0) << mu << " " << t;
  }
  const double seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
  EXPECT_LT(seconds, 20.0);
}

// ---------------------------------------------------------------------------------------------
// The command line.

class ReliabilityCliTest : public atmo::testing::CliFixture {};

constexpr const char* kGridHeader = "altitude_m,sun_zenith_deg,view_zenith_deg,azimuth_deg";
#define ATMO_ONE " --altitude 0 --sun-zenith 30 --view-zenith 60 --azimuth 90"
#define ATMO_TINY " --width 8 --height 4"

// A bad input: non-zero exit, one `atmo: error:` line naming `message_part`, and out.csv,
// sky.exr, sky.png (written with "previous NAME" first) byte-identical afterwards.
struct BadInput {
  const char* name;
  const char* args;
  const char* message_part;
};

const BadInput kBadInputs[] = {
    // Crashes (exit 139) on values far outside any planet: now refused by the bounds.
    {"HugeRadiusSample", "sample --config huge_radius.json" ATMO_ONE " --out out.csv", "ground_radius_m must be in"},
    {"HugeRadiusRender", "render --config huge_radius.json" ATMO_TINY, "ground_radius_m must be in"},
    {"HugeRadiusBench", "bench --quick --config huge_radius.json" ATMO_TINY, "ground_radius_m must be in"},
    {"HugeRadiusCompare", "compare --config huge_radius.json --json out.csv", "ground_radius_m must be in"},
    {"TinyRadiusSample", "sample --config tiny_radius.json" ATMO_ONE " --out out.csv", "ground_radius_m must be in"},
    {"TinyRadiusRender", "render --config tiny_radius.json" ATMO_TINY, "ground_radius_m must be in"},
    {"ElekHugeRadius", "sample --model elek --config elek_radius.json" ATMO_ONE " --out out.csv",
     "ground_radius_m must be in"},
    {"MillimetrePlanet", "sample --config millimetre.json" ATMO_ONE " --out out.csv", "ground_radius_m must be in"},
    {"ThinAtmosphere", "sample --config thin.json" ATMO_ONE " --out out.csv", "top_radius_m - ground_radius_m"},
    // Hangs and NaN: coefficients and density terms beyond any medium.
    {"HugeCoefficientReference", "sample --model reference --option samples=2 --config huge_coefficient.json" ATMO_ONE
     " --out out.csv", "rayleigh.scattering_per_m[0] must be in [0, 1000] per m (got 1e+300)"},
    {"HugeCoefficientElek", "sample --model elek --config huge_coefficient.json" ATMO_ONE " --out out.csv",
     "rayleigh.scattering_per_m[0]"},
    {"OppositeDensityTerms", "sample --config opposite_density.json" ATMO_ONE " --out out.csv",
     "mie.density.upper.exp_term"},
    {"SteepExponential", "sample --config steep.json" ATMO_ONE " --out out.csv", "exp_scale_per_m"},
    {"AsymmetryTooClose", "sample --config g.json" ATMO_ONE " --out out.csv", "mie.phase_g"},
    {"WavelengthTooLong", "sample --config wavelength.json" ATMO_ONE " --out out.csv", "wavelengths_nm[0]"},
    {"SunTooSmall", "render --config sun.json" ATMO_TINY, "sun_angular_radius_rad"},
    {"SunSizeTooSmall", "render --sun-size 1e-10" ATMO_TINY, "--sun-size must be in [0.00012, 20] degrees"},
    {"ObserverTooFar", "render --config observer.json" ATMO_TINY, "observer_altitude_m"},
    {"AltitudeTooFar", "render --altitude 1e12" ATMO_TINY, "--altitude"},
    {"GridAltitudeTooFar", "sample --grid far.csv --out out.csv", "far.csv:2: altitude_m 1e+12 is outside"},
    // Accepted garbage and undefined conversions.
    {"NulInConfig", "sample --config nul.json" ATMO_ONE " --out out.csv", "NUL byte"},
    {"NulInGrid", "sample --grid nul.csv --out out.csv", "NUL byte"},
    {"ExposureBeyondDouble", "render --config exposure.json" ATMO_TINY, "config 'exposure.json': malformed JSON"},
    {"NegativeSeed", "sample --model reference --seed -1" ATMO_ONE " --out out.csv", "--seed"},
    {"SeedAboveTwoTo64", "sample --model reference --seed 18446744073709551616" ATMO_ONE " --out out.csv", "--seed"},
    {"SeedOptionAboveTwoTo64", "sample --model reference --option seed=18446744073709551616" ATMO_ONE " --out out.csv",
     "seed=18446744073709551616"},
    {"ZeroDeviceConfig", "sample --config /dev/zero" ATMO_ONE " --out out.csv",
     "cannot read config '/dev/zero': is not a regular file"},
    {"ZeroDeviceGrid", "sample --grid /dev/zero --out out.csv", "cannot read '/dev/zero': is not a regular file"},
    {"FifoConfig", "sample --config fifo" ATMO_ONE " --out out.csv", "is not a regular file"},
    {"DirectoryGrid", "sample --grid folder --out out.csv", "cannot read 'folder': is a directory"},
    {"DirectoryConfig", "sample --config folder" ATMO_ONE " --out out.csv", "cannot read config 'folder': is a directory"},
    {"OversizedConfig", "sample --config large.json" ATMO_ONE " --out out.csv", "larger than the 64 MiB allowed"},
    {"OversizedGrid", "sample --grid large.json --out out.csv", "larger than the 64 MiB allowed"},
    // The input used as the output.
    {"ConfigAsOut", "sample --config out.csv" ATMO_ONE " --out out.csv", "--out 'out.csv' is the --config input"},
    {"GridAsOut", "sample --grid out.csv --out out.csv", "--out 'out.csv' is the --grid input"},
    {"GridAsOutThroughDot", "sample --grid ./out.csv --out out.csv", "is the --grid input"},
    {"ConfigAsPng", "render --config sky.png --png sky.png" ATMO_TINY, "--png 'sky.png' is the --config input"},
    {"ExrAsPng", "render --exr sky.exr --png sky.exr" ATMO_TINY, "--exr and --png name the same file"},
    {"GridAsCompareCsv", "compare --grid out.csv --csv out.csv", "--csv 'out.csv' is the --grid input"},
    {"ConfigAsPrecompute", "precompute --model elek --config sky.json --out sky", "--out 'sky.json' is the --config"},
    // Outputs that are not regular files.
    {"OutToDevNull", "sample" ATMO_ONE " --out /dev/null", "it is not a regular file"},
    {"OutToFifo", "sample" ATMO_ONE " --out fifo", "it is not a regular file"},
    {"OutToDirectory", "sample" ATMO_ONE " --out folder", "it is a folder"},
    {"PngToDanglingLink", "render --png dangling.png" ATMO_TINY, "symbolic link to a missing file"},
};

class BadInputTest : public ReliabilityCliTest, public ::testing::WithParamInterface<BadInput> {};

TEST_P(BadInputTest, FailsInOneLineAndLeavesOutputsUntouched) {
  WriteFile(dir_ / "huge_radius.json", R"({"ground_radius_m": 1e155, "top_radius_m": 2e155})");
  WriteFile(dir_ / "tiny_radius.json", R"({"ground_radius_m": 1e-200, "top_radius_m": 1e-199})");
  WriteFile(dir_ / "elek_radius.json", R"({"preset": "atmosphere-plus", "ground_radius_m": 1e100, "top_radius_m": 2e100})");
  WriteFile(dir_ / "millimetre.json", R"({"ground_radius_m": 0.001, "top_radius_m": 0.002})");
  WriteFile(dir_ / "thin.json", R"({"top_radius_m": 6360000.01})");
  WriteFile(dir_ / "huge_coefficient.json", R"({"rayleigh": {"scattering_per_m": 1e300}})");
  WriteFile(dir_ / "opposite_density.json",
            R"({"mie": {"density": {"upper": {"exp_term": 1e300, "linear_term_per_m": -1e300}}}})");
  WriteFile(dir_ / "steep.json", R"({"rayleigh": {"density": {"upper": {"exp_scale_per_m": 1e9}}}})");
  WriteFile(dir_ / "g.json", R"({"mie": {"phase_g": 0.99999}})");
  WriteFile(dir_ / "wavelength.json", R"({"wavelengths_nm": [1e9, 550, 440]})");
  WriteFile(dir_ / "sun.json", R"({"sun_angular_radius_rad": 1e-12})");
  WriteFile(dir_ / "observer.json", R"({"observer_altitude_m": 1e15})");
  WriteFile(dir_ / "far.csv", std::string(kGridHeader) + "\n1e12,30,60,90\n");
  // Valid text, a NUL, then bytes that were ignored.
  WriteFile(dir_ / "nul.json", std::string("{}") + '\0' + "{\"rayleigh\": 7}");
  WriteFile(dir_ / "nul.csv", std::string(kGridHeader) + "\n0,30,60,90\n" + '\0' + "garbage\n");
  WriteFile(dir_ / "exposure.json", R"({"exposure": 1e400})");
  WriteFile(dir_ / "sky.json", "{}");
  ASSERT_EQ(::mkfifo((dir_ / "fifo").c_str(), 0600), 0);
  fs::create_directory(dir_ / "folder");
  fs::create_symlink("missing/target.png", dir_ / "dangling.png");
  WriteFile(dir_ / "large.json", "{}");
  fs::resize_file(dir_ / "large.json", (std::uintmax_t{64} << 20) + 1);  // sparse: costs no disc
  ExpectFailureKeepingOutputs(GetParam().args, GetParam().message_part, {"out.csv", "sky.exr", "sky.png"});
  // The special files are what they were.
  struct stat st {};
  ASSERT_EQ(::stat((dir_ / "fifo").c_str(), &st), 0);
  EXPECT_TRUE(S_ISFIFO(st.st_mode));
  ASSERT_EQ(::stat("/dev/null", &st), 0);
  EXPECT_TRUE(S_ISCHR(st.st_mode));
  EXPECT_TRUE(fs::is_directory(dir_ / "folder"));
  EXPECT_TRUE(fs::is_empty(dir_ / "folder"));
  EXPECT_TRUE(fs::is_symlink(dir_ / "dangling.png"));
}

INSTANTIATE_TEST_SUITE_P(Reliability, BadInputTest, ::testing::ValuesIn(kBadInputs),
                         [](const ::testing::TestParamInfo<BadInput>& info) { return info.param.name; });

// An elek table manifest whose integers are not integers, or beyond any table.
TEST_F(ReliabilityCliTest, ElekManifestIntegersMustBeIntegers) {
  const std::string elek = "--model elek --preset atmosphere-plus --option size=4x8x4 --option orders=1";
  const RunResult made = Run("precompute " + elek + " --out table");
  ASSERT_EQ(made.exit_code, 0) << made.err;
  const std::string manifest = ReadFile(dir_ / "table.json");
  struct Mutation {
    const char* key;
    const char* value;
    const char* message;
  };
  const Mutation mutations[] = {
      {"\"format_version\": ", "1.5", "format_version must be an integer"},
      {"\"format_version\": ", "1e30", "format_version must be an integer"},
      {"\"raw_bytes\": ", "1e30", "raw_bytes must be an integer"},
      {"\"raw_bytes\": ", "-1", "raw_bytes must be an integer"},
      {"\"batches\": ", "1.0", "batches must be an integer"},
  };
  for (const Mutation& m : mutations) {
    std::string text = manifest;
    const std::size_t at = text.find(m.key);
    ASSERT_NE(at, std::string::npos) << m.key;
    const std::size_t value_begin = at + std::string(m.key).size();
    const std::size_t value_end = text.find_first_of(",\n", value_begin);
    text.replace(value_begin, value_end - value_begin, m.value);
    WriteFile(dir_ / "table.json", text);
    ExpectFailureKeepingOutputs("sample " + elek + " --table table" ATMO_ONE " --out out.csv", m.message, {"out.csv"});
  }
}

TEST_F(ReliabilityCliTest, EveryTwentyDigitSeedUpToTwoTo64MinusOneIsAccepted) {
  for (const char* seed : {"0", "18446744073709551615", "10000000000000000000"}) {
    const RunResult r = Run(std::string("sample --model reference --option samples=2 --seed ") + seed + ATMO_ONE);
    EXPECT_EQ(r.exit_code, 0) << seed << ": " << r.err;
  }
  const RunResult option = Run("sample --model reference --option samples=2 --option seed=18446744073709551615" ATMO_ONE);
  EXPECT_EQ(option.exit_code, 0) << option.err;
}

// The rows of `atmo sample` output, every number in them finite.
void ExpectFiniteSamples(const RunResult& r, const std::string& what) {
  ASSERT_EQ(r.exit_code, 0) << what << ": " << r.err;
  const std::vector<std::string> lines = Lines(r.out);
  ASSERT_GT(lines.size(), 1u) << what;
  for (std::size_t i = 1; i < lines.size(); ++i) {
    for (const std::string& field : Split(lines[i])) {
      char* end = nullptr;
      const double value = std::strtod(field.c_str(), &end);
      EXPECT_TRUE(std::isfinite(value)) << what << ": " << lines[i];
    }
  }
}

// The extremes that the bounds allow give finite radiance and transmittance with every model
// (the audit's NaN with exit 0 came from just outside them, or from the lookups).
TEST_F(ReliabilityCliTest, InRangeExtremesGiveFiniteSamples) {
  struct Extreme {
    const char* name;
    const char* json;
    const char* grid;  // rows after the header
  };
  const Extreme extremes[] = {
      {"smallest planet, thinnest atmosphere", R"({"ground_radius_m": 1, "top_radius_m": 1.00001})",
       "0,30,60,90\n0,30,90,0\n1e6,30,180,0\n1e11,30,180,0\n"},
      {"smallest planet, thickest atmosphere", R"({"ground_radius_m": 1, "top_radius_m": 11})",
       "0,30,60,90\n0,95,90,0\n1e6,30,180,0\n5,30,100,0\n"},
      {"largest planet", R"({"ground_radius_m": 1e10, "top_radius_m": 1.001e10})",
       "0,30,60,90\n0,90,90,0\n1e8,30,180,0\n1e11,30,179,0\n"},
      {"largest planet, thinnest atmosphere", R"({"ground_radius_m": 1e10, "top_radius_m": 1.00001e10})",
       "0,30,89.9,90\n1e3,90,90,0\n1e11,30,180,0\n"},
      {"densest medium", R"({"rayleigh": {"scattering_per_m": 1000}, "mie": {"absorption_per_m": 1000}})",
       "0,30,60,90\n0,89,90,0\n1e5,30,180,0\n"},
      {"extreme density terms",
       R"({"mie": {"density": {"upper": {"exp_term": 1e6, "exp_scale_per_m": 1e6, "linear_term_per_m": -1e6,
           "constant_term": -1e6}}}})",
       "0,30,60,90\n1e5,30,180,0\n"},
      {"most peaked phase", R"({"mie": {"phase_g": 0.999}, "sun_angular_radius_rad": 1e-6})", "0,30,30,0\n0,30,60,90\n"},
  };
  const char* models[] = {
      "--model hillaire --option transmittance_lut=32x8 --option multiple_scattering_lut=8 --option sky_view_lut=32x16",
      "--model elek --option size=4x8x4 --option orders=1 --option transmittance_lut=32x8",
      "--model reference --option samples=2",
  };
  for (const Extreme& e : extremes) {
    WriteFile(dir_ / "extreme.json", e.json);
    WriteFile(dir_ / "extreme.csv", std::string(kGridHeader) + "\n" + e.grid);
    for (const char* model : models) {
      ExpectFiniteSamples(Run(std::string("sample ") + model + " --config extreme.json --grid extreme.csv"),
                          std::string(e.name) + " / " + model);
    }
  }
}

// The audit's hangs, through `timeout`: a grazing query over a 52 796 km planet with 2 samples,
// and the densest allowed medium (the 1e300 of the audit is refused above).
TEST_F(ReliabilityCliTest, ReferenceQueriesThatHungFinishInSeconds) {
  WriteFile(dir_ / "large_planet.json", R"({"ground_radius_m": 52796000, "top_radius_m": 52896000})");
  WriteFile(dir_ / "dense.json", R"({"rayleigh": {"scattering_per_m": 1000}})");
  // The horizon of an observer at 1000 m is at 90.3526417 degrees; rows about it and the tangent.
  WriteFile(dir_ / "grazing.csv", std::string(kGridHeader) +
                                      "\n1000,30,90.3526417213,0\n1000,90.3526417213,90.3526417213,0\n"
                                      "0,90,90,0\n0,30,90,90\n99999,30,90.0001,0\n");
  for (const char* args : {"--config large_planet.json --grid grid_in.csv", "--config dense.json --grid grid_in.csv"}) {
    fs::copy_file(dir_ / "grazing.csv", dir_ / "grid_in.csv", fs::copy_options::overwrite_existing);
    const auto start = std::chrono::steady_clock::now();
    const RunResult r = Run(std::string("sample --model reference --option samples=2 ") + args, 20);
    const double seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
    ExpectFiniteSamples(r, args);
    EXPECT_LT(seconds, 20.0) << args;
  }
}

// ---------------------------------------------------------------------------------------------
// Safe outputs.

TEST_F(ReliabilityCliTest, OutputThroughASymlinkReplacesTheTargetAndKeepsItsMode) {
  fs::create_directory(dir_ / "real");
  WriteFile(dir_ / "real" / "radiance.csv", "old");
  ASSERT_EQ(::chmod((dir_ / "real" / "radiance.csv").c_str(), 0640), 0);
  fs::create_symlink("real/radiance.csv", dir_ / "link.csv");
  const RunResult r = Run("sample" ATMO_ONE " --out link.csv");
  ASSERT_EQ(r.exit_code, 0) << r.err;
  EXPECT_TRUE(fs::is_symlink(dir_ / "link.csv"));
  EXPECT_EQ(fs::read_symlink(dir_ / "link.csv"), fs::path("real/radiance.csv"));
  EXPECT_EQ(ReadFile(dir_ / "real" / "radiance.csv").rfind("altitude_m,", 0), 0u);
  struct stat st {};
  ASSERT_EQ(::stat((dir_ / "real" / "radiance.csv").c_str(), &st), 0);
  EXPECT_EQ(st.st_mode & 07777, 0640u);
  // No temporary file is left beside the target.
  int entries = 0;
  for ([[maybe_unused]] const auto& entry : fs::directory_iterator(dir_ / "real")) ++entries;
  EXPECT_EQ(entries, 1);
}

// The library refuses too (WriteFileAtomically), without calling the writer.
TEST_F(ReliabilityCliTest, WriteFileAtomicallyRefusesSpecialFiles) {
  ASSERT_EQ(::mkfifo((dir_ / "fifo").c_str(), 0600), 0);
  fs::create_directory(dir_ / "folder");
  fs::create_symlink("nowhere/x", dir_ / "dangling");
  for (const fs::path& path : {fs::path("/dev/null"), dir_ / "fifo", dir_ / "folder", dir_ / "dangling"}) {
    bool called = false;
    try {
      atmo::WriteFileAtomically(path, [&](const fs::path& temporary) {
        called = true;
        WriteFile(temporary, "x");
      });
      ADD_FAILURE() << path << " was written";
    } catch (const atmo::Error& e) {
      EXPECT_NE(std::string(e.what()).find(path.string()), std::string::npos) << e.what();
    }
    EXPECT_FALSE(called) << path;
  }
  struct stat st {};
  ASSERT_EQ(::stat("/dev/null", &st), 0);
  EXPECT_TRUE(S_ISCHR(st.st_mode));
  ASSERT_EQ(::stat((dir_ / "fifo").c_str(), &st), 0);
  EXPECT_TRUE(S_ISFIFO(st.st_mode));
  EXPECT_TRUE(fs::is_empty(dir_ / "folder"));
}

TEST_F(ReliabilityCliTest, ReadFileBoundedRefusesWhatIsNoRegularFile) {
  ASSERT_EQ(::mkfifo((dir_ / "fifo").c_str(), 0600), 0);
  WriteFile(dir_ / "small.txt", "0123456789");
  const auto message = [](const fs::path& path, std::uintmax_t max_bytes) -> std::string {
    try {
      atmo::ReadFileBounded(path, "thing ", max_bytes);
    } catch (const atmo::Error& e) {
      return e.what();
    }
    return "";
  };
  EXPECT_EQ(message("/dev/zero", 100), "cannot read thing '/dev/zero': is not a regular file (a device, FIFO or socket)");
  EXPECT_NE(message(dir_ / "fifo", 100).find("is not a regular file"), std::string::npos);
  EXPECT_NE(message(dir_, 100).find("is a directory"), std::string::npos);
  EXPECT_NE(message(dir_ / "small.txt", 9).find("larger than the 9 bytes allowed"), std::string::npos);
  EXPECT_EQ(message(dir_ / "small.txt", 10), "");
  EXPECT_EQ(atmo::ReadFileBounded(dir_ / "small.txt"), "0123456789");
}

}  // namespace
