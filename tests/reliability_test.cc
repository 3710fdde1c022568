// Reliability (docs/reliability.md): the audit's inputs that crashed, hung, printed NaN with exit
// 0, were silently accepted or overwrote a file, each as a regression test that finishes in
// seconds. The bad inputs are counted in kBadInputs (and the manifest and output tests below);
// docs/reliability.md lists them by category.
#include <sys/stat.h>
#include <unistd.h>

#include <algorithm>
#include <cctype>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <filesystem>
#include <iterator>
#include <limits>
#include <stdexcept>
#include <string>
#include <vector>

#include <gtest/gtest.h>
#include <png.h>

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
// Input text quoted in a message keeps the message one line: control characters are escaped
// (a key with "\n" gave a two-line atmo::Error, found by fuzz_json_parameters).
TEST(OneLineErrors, InputTextIsQuotedWithItsControlCharactersEscaped) {
  const std::pair<const char*, const char*> cases[] = {
      {R"({"sun_lim\nb": 1})", "unknown key 'sun_lim\\nb'"},
      {R"({"rayleigh": {"a\r\tb": 1}})", "unknown key 'rayleigh.a\\r\\tb'"},
      {R"({"preset": "ea\u0001rth"})", "unknown preset 'ea\\x01rth'"},
      {R"({"mie": {"phase_function": "x\ny"}})", "unknown phase function 'x\\ny'"},
      {R"({"geometry": "\n"})", "unknown geometry '\\n'"},
  };
  for (const auto& [json, part] : cases) {
    try {
      atmo::FromJson(json);
      ADD_FAILURE() << json << " was accepted";
    } catch (const atmo::Error& e) {
      const std::string message = e.what();
      EXPECT_EQ(message.find_first_of("\n\r\t\x01"), std::string::npos) << message;
      EXPECT_NE(message.find(part), std::string::npos) << message << " lacks " << part;
    }
  }
}

TEST(BoundedLoops, GrazingTransmittancesOnALargePlanetFinishQuickly) {
  atmo::AtmosphereParameters p = atmo::Preset("earth");
  p.ground_radius_m = 52796e3;
  p.top_radius_m = p.ground_radius_m + 100e3;
  const atmo::cpu::PathTracer tracer(p, atmo::cpu::PathTracerSettings{});
  std::vector<double> out(3);
  // Bounded loops: a hang fails this test by ctest's TIMEOUT (tests/CMakeLists.txt); no wall-clock
  // assertion, which a busy machine would break.
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
  for (const double mu : {1.0, 0.5, 0.01, 0.0, -0.01}) {
    const glm::dvec3 view(std::sqrt(1.0 - mu * mu), 0.0, mu);
    tracer.Transmittance(glm::dvec3(0.0, 0.0, p.ground_radius_m + 10.0), view, out);
    for (double t : out) EXPECT_TRUE(t >= 0.0 && t <= 1.0) << mu << " " << t;
  }
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
    // An error quotes at most 32 bytes of a line that is not a grid's (docs/reliability.md, "Trust boundaries").
    {"GridQuotesAnExcerpt", "sample --grid secret.txt --out out.csv",
     "secret.txt:1: expected the header 'altitude_m,sun_zenith_deg,view_zenith_deg,azimuth_deg', got "
     "'password=correct horse battery s...'"},
    // Accepted garbage and undefined conversions.
    // Cube-map products checked before any work: a refused command replaced sky.exr and sky.png.
    {"CubeKtx2MissingFolder", "render --camera cubemap --face-size 8 --ktx2 nodir/c.ktx2",
     "cannot write 'nodir/c.ktx2': folder 'nodir' does not exist"},
    {"CubeSpecularLevels", "render --camera cubemap --face-size 8 --specular s.ktx2",
     "--specular-levels must be in 1..4 for --face-size 8 (got 6)"},
    {"CubeKtx2IsTheExr", "render --camera cubemap --face-size 8 --ktx2 sky.exr",
     "--exr and --ktx2 name the same file 'sky.exr'"},
    {"CubeShIsTheKtx2", "render --camera cubemap --face-size 8 --sh c.json --ktx2 c.json",
     "--ktx2 and --sh name the same file 'c.json'"},
    {"CubeIrradianceIsTheSpecular", "render --camera cubemap --face-size 8 --irradiance i.ktx2 --specular i.ktx2",
     "--irradiance and --specular name the same file 'i.ktx2'"},
    {"CubeMipsWithoutKtx2", "render --camera cubemap --face-size 8 --mips", "--mips makes the --ktx2 file's mip chain"},
    {"CubeSpecularIsAFolder", "render --camera cubemap --face-size 8 --specular folder", "it is a folder"},
    // A samples file with a configuration twice (each was counted twice in compare's statistics).
    {"SamplesRepeatAConfiguration", "compare --against-samples repeated.csv --csv out.csv",
     "repeated.csv:5: the configuration of line 2 again: each configuration once"},
    // Time-lapse frames checked before the first one is written.
    {"TimeLapseFrameIsTheConfig",
     "render --config frame_0001.png --date 2026-06-21T06:00+02:00 --until 2026-06-21T07:00+02:00 --step 30min "
     "--latitude 46.5 --longitude 7.9" ATMO_TINY " --png frame.png",
     "--png frame 1 'frame_0001.png' is the --config input"},
    {"TimeLapseFrameIsAFolder",
     "render --date 2026-06-21T06:00+02:00 --until 2026-06-21T07:00+02:00 --step 30min --latitude 46.5 "
     "--longitude 7.9" ATMO_TINY " --png shot.png --exr shot.exr",
     "cannot write 'shot_0002.exr': it is a folder"},
    // Sizes over the memory limit, refused before any work with their estimate (docs/reliability.md).
    {"MaxMemoryMalformed", "render --max-memory 4X" ATMO_TINY,
     "memory size '4X': expected a number of bytes with an optional K, M, G or T, e.g. 4G"},
    {"MaxMemoryTooSmall", "render --max-memory 1000" ATMO_TINY, "memory size '1000' is outside [1M, 1024T]"},
    {"RenderOverMemory", "render --width 4096 --height 4096 --max-memory 64M --exr sky.exr --png sky.png",
     "a 4096x4096 render would need about 640.0 MB, more than the memory limit of 64.0 MB (--max-memory)"},
    {"CubeOverMemory", "render --camera cubemap --face-size 2048 --max-memory 64M --exr sky.exr",
     "a cube map of 2048-texel faces would need about 960.0 MB"},
    {"ElekOverMemory", "sample --model elek --preset earth --option size=1024x4096x1024 --max-memory 1G" ATMO_ONE " --out out.csv",
     "elek tables of size=1024x4096x1024 at 3 channels would need about 512.0 GB"},
    {"Source4dOverMemory", "sample --model source4d --preset earth --option table=64x64x64x64 --max-memory 256M" ATMO_ONE " --out out.csv",
     "source4d tables of table=64x64x64x64 at 3 channels would need about 1.0 GB"},
    {"AerialOverMemory", "precompute --model hillaire --aerial-size 512x512x512 --max-memory 1G --out sky",
     "an aerial-perspective volume of 512x512x512 at 3 channels would need about 3.0 GB"},
    // The real sky's knobs and tables (docs/aerosols.md, docs/parameters.md).
    {"AodTooLarge", "render --preset us-standard --aod 11" ATMO_TINY, "aerosol optical depth 11 at 550 nm is outside [0, 10]"},
    {"AodNegative", "sample --aod -0.1" ATMO_ONE " --out out.csv", "aerosol optical depth -0.1 at 550 nm is outside [0, 10]"},
    {"AodNan", "illuminance --aod nan --sun-elevation 30", "aerosol optical depth nan at 550 nm is outside [0, 10]"},
    {"AngstromNan", "render --angstrom nan" ATMO_TINY, "Angstrom exponent nan is outside [-1, 4]"},
    {"AngstromTooLarge", "render --angstrom 4.5" ATMO_TINY, "Angstrom exponent 4.5 is outside [-1, 4]"},
    {"AngstromTooSmall", "sample --angstrom -2" ATMO_ONE " --out out.csv", "Angstrom exponent -2 is outside [-1, 4]"},
    {"VisibilityZero", "render --visibility 0" ATMO_TINY, "visibility 0 km must be positive and finite"},
    {"VisibilityBeyondAir", "sample --visibility 500" ATMO_ONE " --out out.csv", "km that the air alone allows"},
    {"TurbidityTooClean", "render --preset us-standard --turbidity 1" ATMO_TINY, "Linke turbidity 1 is below the"},
    {"UnknownAerosol", "render --aerosol smog" ATMO_TINY, "unknown aerosol type 'smog' (known: continental-clean"},
    {"TwoAerosolAmounts", "render --aod 0.1 --visibility 20" ATMO_TINY, "at most one of --aod, --visibility and --turbidity"},
    {"AerosolOnAHalfSpace", "render --model simple --preset simple --aod 0.1" ATMO_TINY, "spherical"},
    {"TableNotIncreasing", "render --config table_order.json" ATMO_TINY,
     "mie.density.table altitudes must increase strictly: knot 1 is at 0 m after 1000 m"},
    {"TableNegativeDensity", "sample --config table_negative.json" ATMO_ONE " --out out.csv",
     "rayleigh.density.table[1].density must be in [0, 1] (got -0.5)"},
    {"TableAndLayers", "sample --config table_and_layers.json" ATMO_ONE " --out out.csv",
     "ozone.density holds either a table or lower/upper layers, not both"},
    {"ConfigAerosolKey", "render --config aerosol_key.json" ATMO_TINY, "unknown key 'aerosol.tau'"},
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
    // Flags that were not bounded (found by the generated tables below).
    {"ExposureBeyondTheBounds", "render --exposure 1e300" ATMO_TINY, "--exposure: 1e300 is outside [1e-10, 1e+10]"},
    {"EvBeyondTheBounds", "render --ev 1e9" ATMO_TINY, "--ev: 1e9 is outside [-32, 32]"},
    {"LongitudeBeyond180", "render --date 2024-06-21T12:00:00Z --latitude 45 --longitude 181" ATMO_TINY,
     "--longitude: 181 is outside [-180, 180]"},
    {"LatitudeBelowMinus90", "render --date 2024-06-21T12:00:00Z --latitude -90.5 --longitude 0" ATMO_TINY,
     "--latitude: -90.5 is outside [-90, 90]"},
    {"PrecomputeEmptyName", "precompute --model hillaire --out ''", "--out must be the tables' NAME"},
    {"PrecomputeNameEndingInASlash", "precompute --out tables/", "--out 'tables/' is a folder"},
    {"PrecomputeNameAFolder", "precompute --model hillaire --out folder", "--out 'folder' is a folder"},
    {"PrecomputeNameDot", "precompute --out .", "--out '.' is a folder"},
    {"NegativeSamplesShownAsGiven", "sample --model reference --samples -4" ATMO_ONE " --out out.csv",
     "--samples: Value -4 not in range 2 to 1099511627776"},
    {"NegativeSppShownAsGiven", "render --model reference --spp -4" ATMO_TINY, "--spp: Value -4 not in range"},
    {"AerialDistanceBeyondTheBounds", "precompute --model hillaire --aerial-distance 1e300 --out sky",
     "--aerial-distance: 1e300 is outside [1, 1e+11]"},
    // source4d's sky-view table and compare's samples file.
    {"Source4dSkyViewMode", "render --model source4d --option sky_view=maybe" ATMO_TINY, "expected auto, on or off"},
    {"Source4dSkyViewOddWidth", "render --model source4d --option sky_view_lut=5x4" ATMO_TINY, "must be even"},
    {"Source4dSkyViewTooLarge", "render --model source4d --option sky_view_lut=8192x8192" ATMO_TINY,
     "more than 2^24 texels"},
    {"CompareSamplesMissing", "compare --model hillaire --against-samples missing.csv", "missing.csv"},
    {"CompareSamplesFolder", "compare --model hillaire --against-samples folder", "folder"},
    {"CompareSamplesFifo", "compare --model hillaire --against-samples fifo", "fifo"},
    {"CompareSamplesTooLarge", "compare --model hillaire --against-samples large.json", "large.json"},
    {"CompareSamplesGridHeader", "compare --model hillaire --against-samples far.csv",
     "far.csv:1: expected the header 'altitude_m,sun_zenith_deg,view_zenith_deg,azimuth_deg,wavelength_nm"},
    {"CompareSamplesWithGrid", "compare --model hillaire --against-samples far.csv --grid far.csv",
     "--grid excludes --against-samples"},
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
  WriteFile(dir_ / "secret.txt", "password=correct horse battery staple and more words\n");
  // Valid text, a NUL, then bytes that were ignored.
  WriteFile(dir_ / "nul.json", std::string("{}") + '\0' + "{\"rayleigh\": 7}");
  WriteFile(dir_ / "nul.csv", std::string(kGridHeader) + "\n0,30,60,90\n" + '\0' + "garbage\n");
  WriteFile(dir_ / "exposure.json", R"({"exposure": 1e400})");
  WriteFile(dir_ / "sky.json", "{}");
  WriteFile(dir_ / "table_order.json", R"({"mie": {"density": {"table": [[1000, 1], [0, 0.5]]}}})");
  WriteFile(dir_ / "table_negative.json", R"({"rayleigh": {"density": {"table": [[0, 1], [1000, -0.5]]}}})");
  WriteFile(dir_ / "table_and_layers.json", R"({"ozone": {"density": {"table": [[0, 1], [1, 0]], "lower": {}}}})");
  WriteFile(dir_ / "aerosol_key.json", R"({"aerosol": {"tau": 0.2}})");
  WriteFile(dir_ / "frame_0001.png", "{}");  // a config named like a time-lapse frame
  {
    std::string repeated = "altitude_m,sun_zenith_deg,view_zenith_deg,azimuth_deg,wavelength_nm,radiance,"
                           "transmittance,stderr\n";
    for (int copy = 0; copy < 2; ++copy) {
      for (const char* wavelength : {"680", "550", "440"}) repeated += std::string("0,30,60,90,") + wavelength + ",0.1,0.5,0\n";
    }
    WriteFile(dir_ / "repeated.csv", repeated);
  }
  fs::create_directory(dir_ / "shot_0002.exr");
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
  // No export without a name (precompute --out "" wrote .json, .exr and .raw), nor a time-lapse
  // frame before the one that is refused.
  for (const char* name : {".json", ".exr", ".raw", "_transmittance.raw", "sky_transmittance.raw", "folder.json",
                           "shot_0000.png", "shot_0000.exr", "frame_0000.png"}) {
    EXPECT_FALSE(fs::exists(dir_ / name)) << name;
  }
}

INSTANTIATE_TEST_SUITE_P(Reliability, BadInputTest, ::testing::ValuesIn(kBadInputs),
                         [](const ::testing::TestParamInfo<BadInput>& info) { return info.param.name; });

// ---------------------------------------------------------------------------------------------
constexpr const char* kConfigArgs = "sample --config bad.json" ATMO_ONE " --out out.csv";

// Every parameter key of a config out of range, of the wrong type or null, and malformed JSON
// (generated: kBadInputs above are the audit's cases). Each through `atmo sample --config`, which
// must refuse it in one line naming the key, before any work.

// A generated bad input: `args` for atmo, the message part, and the text of bad.json (for the
// configs) or bad.csv (for the grids) when there is one.
struct GeneratedBadInput {
  std::string name;
  std::string args;
  std::string message_part;
  std::string file_text;
};

// A name for gtest: letters and digits only.
std::string TestName(const std::string& text) {
  std::string name;
  bool upper = true;
  for (const char c : text) {
    if (std::isalnum(static_cast<unsigned char>(c))) {
      name += upper ? static_cast<char>(std::toupper(static_cast<unsigned char>(c))) : c;
      upper = false;
    } else {
      upper = true;
    }
  }
  return name;
}

// {"a": {"b": {"c": VALUE}}} for the key path "a.b.c".
std::string Nested(const std::string& path, const std::string& value) {
  std::string json, closing;
  std::size_t start = 0;
  while (true) {
    const std::size_t dot = path.find('.', start);
    json += "{\"" + path.substr(start, dot == std::string::npos ? std::string::npos : dot - start) + "\": ";
    closing += "}";
    if (dot == std::string::npos) break;
    start = dot + 1;
  }
  return json + value + closing;
}

std::vector<GeneratedBadInput> BadConfigs() {
  std::vector<GeneratedBadInput> cases;
  // One key with a bad value; the message names the key (and `part` what is wrong, when given).
  const auto add = [&](const std::string& key, const std::string& value, const std::string& why,
                       const std::string& part = "") {
    cases.push_back({TestName(key) + TestName(why), kConfigArgs, part.empty() ? key : key + part, Nested(key, value)});
  };
  for (const char* medium : {"rayleigh", "mie", "ozone"}) {
    const std::string m = medium;
    for (const char* layer : {"lower", "upper"}) {
      const std::string l = m + ".density." + layer;
      add(l + ".width_m", "1e12", "too wide", " must be in");
      add(l + ".width_m", "-1", "negative", " must be in");
      add(l + ".width_m", "\"10\"", "string", " must be a number");
      for (const char* term : {"exp_term", "exp_scale_per_m", "linear_term_per_m", "constant_term"}) {
        add(l + "." + term, "2e6", "too large", " must be in [-1e+06, 1e+06]");
        add(l + "." + term, "-1e300", "too small", " must be in [-1e+06, 1e+06]");
        add(l + "." + term, "null", "null", " must be a number");
      }
      add(l, "5", "not an object", " must be an object");
      add(l + ".width", "1", "unknown key");
    }
    add(m + ".density", "[]", "not an object", " must be an object");
    add(m + ".density.middle", "{}", "unknown key");
    for (const char* coefficient : {"scattering_per_m", "absorption_per_m"}) {
      const std::string c = m + "." + coefficient;
      add(c, "2e3", "too large", "[0] must be in [0, 1000]");
      add(c, "[1e-6, 1e-6, -1e-9]", "negative", "[2] must be in [0, 1000]");
      add(c, "[1e-6, \"x\", 1e-6]", "string element", " must be a number or an array of numbers");
      add(c, "{}", "object", " must be a number or an array of numbers");
      add(c, "[1e-6, 1e-6]", "two channels");
    }
    add(m + ".phase_g", "1", "one", " must");
    add(m + ".phase_g", "-1", "minus one", " must");
    add(m + ".phase_g", "0.9995", "beyond the bound", " must be in [-0.999, 0.999]");
    add(m + ".phase_g", "true", "boolean", " must be a number");
    add(m + ".phase_function", "\"mie\"", "unknown", ": unknown phase function 'mie'");
    add(m + ".phase_function", "3", "number", " must be a string");
    add(m, "1", "number", " must be an object");
    add(m, "\"thin\"", "string", " must be an object");
    add(m + ".scatter", "1", "unknown key");
  }
  add("ground_radius_m", "0.5", "below a metre", " must be in [1, 1e+10] m");
  add("ground_radius_m", "1e11", "beyond the bound", " must be in [1, 1e+10] m");
  add("ground_radius_m", "-6360000", "negative", " must be in [1, 1e+10] m");
  add("ground_radius_m", "\"6360000\"", "string", " must be a number");
  add("ground_radius_m", "null", "null", " must be a number");
  add("ground_radius_m", "[6360000]", "array", " must be a number");
  add("top_radius_m", "6000000", "below the ground");
  add("top_radius_m", "1e9", "twelve radii", " - ground_radius_m must be in");
  add("top_radius_m", "false", "boolean", " must be a number");
  add("sun_angular_radius_rad", "0", "zero", " must be in [1e-06, pi/2)");
  add("sun_angular_radius_rad", "1.6", "above pi over two", " must be in [1e-06, pi/2)");
  add("sun_angular_radius_rad", "-0.004", "negative", " must be in [1e-06, pi/2)");
  add("sun_angular_radius_rad", "{}", "object", " must be a number");
  add("exposure", "0", "zero", " must be in [1e-10, 1e+10]");
  add("exposure", "1e11", "too large", " must be in [1e-10, 1e+10]");
  add("exposure", "-1", "negative", " must be in [1e-10, 1e+10]");
  add("exposure", "\"1\"", "string", " must be a number");
  add("observer_altitude_m", "1e12", "too far", " must be in");
  add("observer_altitude_m", "-1", "below the ground", " must be >= 0 for spherical geometry");
  add("observer_altitude_m", "[]", "array", " must be a number");
  add("sun_limb_darkening", "1", "number", " must be true or false");
  add("sun_limb_darkening", "\"yes\"", "string", " must be true or false");
  add("sun_limb_darkening", "null", "null", " must be true or false");
  add("preset", "\"venus\"", "unknown", "");
  add("preset", "7", "number", " must be a string");
  add("preset", "null", "null", " must be a string");
  add("geometry", "\"flat\"", "unknown", ": unknown geometry 'flat'");
  add("geometry", "1", "number", " must be a string");
  add("wavelengths_nm", "[]", "empty", " must have at least one channel");
  add("wavelengths_nm", "[0.5]", "too short", "[0] must be in [1, 1e+05] nm");
  add("wavelengths_nm", "[680, 550, 1e6]", "too long", "[2] must be in [1, 1e+05] nm");
  add("wavelengths_nm", "\"visible\"", "string", " must be a number or an array of numbers");
  add("wavelengths_nm", "[550, null]", "null element", " must be a number or an array of numbers");
  {
    std::string many = "[";
    for (int i = 0; i < 4097; ++i) many += (i ? ", " : "") + std::to_string(400 + i % 300);
    add("wavelengths_nm", many + "]", "4097 channels", " has 4097 channels, more than the");
  }
  add("ground_albedo", "-0.1", "negative", "[0] must be in [0, 1]");
  add("ground_albedo", "1.1", "above one", "[0] must be in [0, 1]");
  add("ground_albedo", "[0.1, 0.2]", "two channels");
  add("ground_albedo", "\"grey\"", "string", " must be a number or an array of numbers");
  add("solar_irradiance", "-1", "negative", "[0] must be in [0, 1e+10]");
  add("solar_irradiance", "1e11", "too large", "[0] must be in [0, 1e+10]");
  add("solar_irradiance", "[1, 1, 1, 1]", "four channels");
  add("solar_irradiance", "null", "null", " must be a number or an array of numbers");
  for (const char* key : {"foo", "Ground_radius_m", "", "ground_radius_m "}) {
    cases.push_back({"UnknownRootKey" + TestName(std::string("x") + key), kConfigArgs,
                     "unknown key '" + std::string(key) + "'", Nested(key, "1")});
  }
  // Not an object, and malformed JSON: each names the config file.
  const std::pair<const char*, std::string> documents[] = {
      {"RootArray", "[]"}, {"RootNumber", "1"}, {"RootString", "\"earth\""}, {"RootNull", "null"}, {"RootTrue", "true"},
  };
  for (const auto& [name, json] : documents) cases.push_back({name, kConfigArgs, "the parameters must be a JSON object", json});
  const std::pair<const char*, std::string> malformed[] = {
      {"EmptyFile", ""},
      {"OnlyBlanks", " \n\t "},
      {"UnclosedObject", "{"},
      {"MissingValue", "{\"exposure\": }"},
      {"TrailingComma", "{\"exposure\": 1,}"},
      {"NanLiteral", "{\"exposure\": NaN}"},
      {"InfinityLiteral", "{\"exposure\": Infinity}"},
      {"MinusInfinityLiteral", "{\"exposure\": -Infinity}"},
      {"NumberUnderflowToMinusInfinity", "{\"exposure\": -1e400}"},
      {"LineComment", "// settings\n{}"},
      {"BlockComment", "{/* x */}"},
      {"SingleQuotes", "{'exposure': 1}"},
      {"UnquotedKey", "{exposure: 1}"},
      {"TwoDocuments", "{} {}"},
      {"HexNumber", "{\"exposure\": 0x10}"},
      {"LeadingZero", "{\"exposure\": 01}"},
      {"LeadingPlus", "{\"exposure\": +1}"},
      {"BareFraction", "{\"exposure\": .5}"},
      {"TrailingDot", "{\"exposure\": 1.}"},
      {"InvalidUtf8", "{\"preset\": \"\xff\xfe\"}"},
      {"UnterminatedString", "{\"preset\": \"earth}"},
      {"RawTabInString", "{\"preset\": \"ea\trth\"}"},
      {"LoneSurrogate", "{\"preset\": \"\\ud800\"}"},
      {"BadEscape", "{\"preset\": \"\\q\"}"},
      {"Utf16Text", std::string("\xff\xfe{\0}\0", 6)},
  };
  for (const auto& [name, json] : malformed) cases.push_back({name, kConfigArgs, "config 'bad.json': ", json});
  // Deep nesting: parsed without recursion, then refused as a value of the wrong type.
  cases.push_back({"DeeplyNestedArrays", kConfigArgs, "exposure must be a number",
                   "{\"exposure\": " + std::string(100000, '[') + std::string(100000, ']') + "}"});
  return cases;
}

class GeneratedBadInputTest : public ReliabilityCliTest, public ::testing::WithParamInterface<GeneratedBadInput> {};

TEST_P(GeneratedBadInputTest, FailsInOneLineAndLeavesOutputsUntouched) {
  const GeneratedBadInput& c = GetParam();
  WriteFile(dir_ / (c.args.find("bad.csv") != std::string::npos ? "bad.csv" : "bad.json"), c.file_text);
  ExpectFailureKeepingOutputs(c.args, c.message_part, {"out.csv", "sky.exr", "sky.png", "out.png", "out.json"});
}

std::string GeneratedName(const ::testing::TestParamInfo<GeneratedBadInput>& info) { return info.param.name; }

INSTANTIATE_TEST_SUITE_P(Configs, GeneratedBadInputTest, ::testing::ValuesIn(BadConfigs()), GeneratedName);

// ---------------------------------------------------------------------------------------------
// Every command's flags with absurd values, unusable paths, bad grids: generated like the configs.

std::vector<GeneratedBadInput> BadFlags() {
  std::vector<GeneratedBadInput> cases;
  const auto add = [&](const std::string& command, const std::string& flag, const std::string& value,
                       const std::string& part = "") {
    const std::string args = command + " " + flag + " " + value;
    const std::string shown = !value.empty() && value[0] == '-' ? "minus " + value.substr(1) : value;
    cases.push_back({TestName(command + " " + flag + " " + shown).substr(0, 100), args, part.empty() ? flag : part, ""});
  };
  // (Each command's other required arguments are given, so that the flag is what is wrong.)
  const std::string render = "render" ATMO_TINY;
  const std::string sample = "sample --out out.csv" ATMO_ONE;
  for (const char* value : {"0", "-1", "99999999", "abc", "1.5", "nan"}) add(render, "--width", value);
  for (const char* value : {"0", "1e9", "x"}) add(render, "--height", value);
  for (const char* value : {"0", "360", "nan", "-10", "inf"}) add(render, "--fov", value);
  for (const char* value : {"nan", "inf"}) add(render, "--yaw", value);
  for (const char* value : {"91", "-91", "nan"}) add(render, "--pitch", value);
  for (const char* value : {"0", "-1", "nan", "1e-11", "1.1e10"}) add(render, "--exposure", value);
  for (const char* value : {"nan", "-32.5", "33", "inf"}) add(render, "--ev", value);
  for (const char* value : {"0", "-1", "1e12", "-4", "99999999999999999999"}) add(render + " --model reference", "--spp", value);
  for (const char* value : {"0", "-5", "100000000"}) add(render, "--threads", value);
  for (const char* value : {"0", "5000", "-3"}) add(render, "--spectral", value);
  add(render, "--camera", "fish");
  add(render, "--tonemap", "filmic");
  for (const char* value : {"7", "0", "32"}) add(render, "--png-bits", value);
  add(render, "--unit", "furlongs");
  for (const char* value : {"91", "-91", "nan"}) add(render, "--sun-elevation", value);
  for (const char* value : {"nan", "inf"}) add(render, "--sun-azimuth", value);
  for (const char* value : {"0", "100", "nan"}) add(render, "--sun-size", value);
  for (const char* value : {"nan", "inf", "-1e12"}) add(render, "--altitude", value);
  add(render, "--model", "bruneton", "bruneton");
  add(render, "--preset", "venus", "venus");
  add(render, "--backend", "vulkan");
  for (const char* value : {"0", "nan", "-1"}) add(render, "--gamma", value);
  add(render, "--date", "yesterday");
  add(render, "--date", "2024-13-45T25:61:00Z");
  for (const char* value : {"91", "-91", "nan"}) add(render + " --date 2024-06-21T12:00:00Z", "--latitude", value);
  for (const char* value : {"inf", "-180.5", "180.5", "360"}) {
    add(render + " --date 2024-06-21T12:00:00Z --latitude 45", "--longitude", value);
  }
  add(render, "--option", "junk", "junk");
  add(render, "--option", "transmittance_lut=0x0", "transmittance_lut");
  add(render, "--option", "nonsense=1", "nonsense");
  add(render + " --model elek", "--option", "size=1x1x1", "size");
  add(render + " --model elek", "--option", "orders=0", "orders");
  add(render + " --model reference", "--option", "samples=0", "samples");
  add(render + " --model reference", "--option", "samples=1e99", "samples");
  add(render, "--seed", "abc");
  add(render, "--seed", "1e3");
  add(render, "--exr", "sky.png", "sky.png");
  add(render, "--png", "sky.exr", "sky.exr");
  add(render, "--exr", "/nonexistent-folder/sky.exr", "/nonexistent-folder/sky.exr");
  add(render, "--exr", "/proc/version", "/proc/version");
  add(render, "--png", "/dev/full", "/dev/full");
  add(render, "--exr", std::string(300, 'x') + ".exr", "xxxxxxxx");
  add(render, "--width", "", "--width");
  add(render, "--frobnicate", "1", "--frobnicate");
  for (const char* value : {"-1", "181", "nan"}) add(sample, "--sun-zenith", value);
  for (const char* value : {"-0.001", "180.5", "inf"}) add(sample, "--view-zenith", value);
  for (const char* value : {"nan", "inf"}) add(sample, "--azimuth", value);
  add("sample --out out.csv --sun-zenith 30 --view-zenith 60 --azimuth 90", "--altitude", "nan");
  add(sample, "--unit", "candela", "--unit");
  add(sample + " --model reference", "--samples", "0", "samples");
  add(sample + " --model reference", "--samples", "x", "--samples");
  // Shown as given: CLI11 wrapped a negative count into the unsigned type (samples=18446744073709551612).
  for (const char* value : {"-1", "1", "1099511627777"}) {
    add(sample + " --model reference", "--samples", value, std::string("--samples: Value ") + value + " not in range");
  }
  add("sample" ATMO_ONE, "--out", "out.txt", "out.txt");
  add("sample" ATMO_ONE, "--out", "/nonexistent-folder/out.csv", "/nonexistent-folder/out.csv");
  add(sample, "--config", "missing.json", "missing.json");
  add(sample + " --model elek --option size=4x8x4", "--table", "missing", "missing");
  add("sample --out out.csv", "--grid", "missing.csv", "missing.csv");
  const std::string cubemap = "render --camera cubemap --face-size 4 --no-png";
  for (const char* value : {"0", "1000000", "-2"}) add("render --camera cubemap --no-png", "--face-size", value);
  for (const char* value : {"0", "-1"}) add(cubemap, "--irradiance-size", value);
  for (const char* value : {"0", "100"}) add(cubemap, "--specular-levels", value);
  for (const char* value : {"0", "-1"}) add(cubemap, "--specular-samples", value);
  for (const char* value : {"0", "-1", "x"}) add("bench --quick" ATMO_TINY, "--repeat", value);
  add("bench --quick", "--width", "0");
  add("compare --json out.json", "--against", "bruneton", "bruneton");
  add("compare --json out.json", "--against-option", "junk", "junk");
  for (const char* value : {"0x0", "axb", "100000x100000"}) add("compare --json out.csv --image out.png", "--image-size", value);
  add("compare --json out.json", "--grid", "missing.csv", "missing.csv");
  add("precompute --model nosuchmodel", "--out", "table", "nosuchmodel");
  add("precompute --model elek --option size=4x8x4", "--out", "/nonexistent-folder/t", "/nonexistent-folder/t");
  add("precompute --model elek", "--out", "''", "--out must be the tables' NAME");
  add("precompute --model hillaire", "--out", "..", "--out '..' is a folder");
  add("precompute --model hillaire", "--out", "/tmp/", "--out '/tmp/' is a folder");
  for (const char* value : {"0", "0.5", "1.1e11", "nan"}) add("precompute --model hillaire --out sky", "--aerial-distance", value);
  for (const char* value : {"91", "-91", "nan"}) add("illuminance", "--sun-elevation", value);
  add("presets", "--dump", "venus", "venus");
  add("frobnicate", "", "", "frobnicate");
  // Bad grids through sample --grid.
  const std::pair<const char*, std::string> grids[] = {
      {"Empty", ""},
      {"WrongHeader", "altitude,sun,view,azimuth\n0,30,60,90\n"},
      {"ByteOrderMark", "\xef\xbb\xbf" + std::string(kGridHeader) + "\n0,30,60,90\n"},
      {"ThreeFields", std::string(kGridHeader) + "\n0,30,60\n"},
      {"FiveFields", std::string(kGridHeader) + "\n0,30,60,90,1\n"},
      {"TextField", std::string(kGridHeader) + "\n0,thirty,60,90\n"},
      {"NanField", std::string(kGridHeader) + "\n0,30,nan,90\n"},
      {"InfField", std::string(kGridHeader) + "\ninf,30,60,90\n"},
      {"SunZenithAbove180", std::string(kGridHeader) + "\n0,180.001,60,90\n"},
      {"ViewZenithNegative", std::string(kGridHeader) + "\n0,30,-1,90\n"},
      {"NumberOverflow", std::string(kGridHeader) + "\n1e400,30,60,90\n"},
      {"HexNumber", std::string(kGridHeader) + "\n0x10,30,60,90\n"},
      {"EmptyField", std::string(kGridHeader) + "\n0,,60,90\n"},
      {"SemicolonSeparated", std::string(kGridHeader) + "\n0;30;60;90\n"},
      {"BadRowAfterGoodRows", std::string(kGridHeader) + "\n0,30,60,90\n0,30,60,90\n0,30,60\n"},
  };
  for (const auto& [name, text] : grids) {
    cases.push_back({std::string("Grid") + name, "sample --grid bad.csv --out out.csv", "bad.csv", text});
  }
  return cases;
}

INSTANTIATE_TEST_SUITE_P(Flags, GeneratedBadInputTest, ::testing::ValuesIn(BadFlags()), GeneratedName);

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

// Bad elek tables (--table NAME): a table exported, then one of its files damaged or replaced, or
// loaded by a model it does not belong to. Each is refused in one line before any output.
struct BadTable {
  const char* name;
  void (*damage)(const fs::path& dir);  // changes table.json / table.raw in dir
  const char* model_args;               // the loading model's, when not the exporting one's
  const char* message_part;
};

// The manifest with `from` replaced by `to` (the first occurrence).
void EditManifest(const fs::path& dir, const std::string& from, const std::string& to) {
  std::string text = ReadFile(dir / "table.json");
  const std::size_t at = text.find(from);
  if (at == std::string::npos) throw std::runtime_error("no '" + from + "' in the manifest");
  text.replace(at, from.size(), to);
  WriteFile(dir / "table.json", text);
}

const BadTable kBadTables[] = {
    {"RawMissing", [](const fs::path& d) { fs::remove(d / "table.raw"); }, "", "table.raw"},
    {"RawTruncated", [](const fs::path& d) { fs::resize_file(d / "table.raw", fs::file_size(d / "table.raw") - 1); }, "",
     "bytes, expected"},
    {"RawLonger", [](const fs::path& d) { fs::resize_file(d / "table.raw", fs::file_size(d / "table.raw") + 4); }, "",
     "table.raw"},
    {"RawOneByteChanged",
     [](const fs::path& d) {
       std::string raw = ReadFile(d / "table.raw");
       raw[raw.size() / 2] ^= 0x40;
       WriteFile(d / "table.raw", raw);
     },
     "", "data hash"},
    {"RawIsAFolder",
     [](const fs::path& d) {
       fs::remove(d / "table.raw");
       fs::create_directory(d / "table.raw");
     },
     "", "is a directory"},
    {"RawIsAFifo",
     [](const fs::path& d) {
       fs::remove(d / "table.raw");
       ::mkfifo((d / "table.raw").c_str(), 0600);
     },
     "", "is not a regular file"},
    {"ManifestMissing", [](const fs::path& d) { fs::remove(d / "table.json"); }, "", "table.json"},
    {"ManifestEmpty", [](const fs::path& d) { WriteFile(d / "table.json", ""); }, "", "malformed JSON"},
    {"ManifestTruncated",
     [](const fs::path& d) { WriteFile(d / "table.json", ReadFile(d / "table.json").substr(0, 100)); }, "",
     "malformed JSON"},
    {"ManifestAnArray", [](const fs::path& d) { WriteFile(d / "table.json", "[1, 2]"); }, "", "table.json"},
    {"ManifestOtherFormat", [](const fs::path& d) { EditManifest(d, "atmo-elek-table", "atmo-hillaire-table"); }, "",
     "not an elek table manifest"},
    {"ManifestFormatVersion2", [](const fs::path& d) { EditManifest(d, "\"format_version\": 1", "\"format_version\": 2"); },
     "", "format version 2;"},
    // Another atmo version with the same format version loads, with a warning (HillaireExport and
    // ElekFiles test that); format version 0 is refused like 2.
    {"ManifestFormatVersion0", [](const fs::path& d) { EditManifest(d, "\"format_version\": 1", "\"format_version\": 0"); },
     "", "format version 0;"},
    {"ManifestWithoutParameterHash", [](const fs::path& d) { EditManifest(d, "\"parameter_hash\"", "\"parameter_hush\""); },
     "", "missing or malformed key"},
    {"ManifestHashNotAString", [](const fs::path& d) { EditManifest(d, "\"raw_hash_fnv1a64\": \"", "\"raw_hash_fnv1a64\": 7, \"x\": \""); },
     "", "missing or malformed key"},
    {"ManifestTwoBatches", [](const fs::path& d) { EditManifest(d, "\"batches\": 1", "\"batches\": 2"); }, "",
     "channel batches differ"},
    {"ManifestOptionsNotAnObject",
     [](const fs::path& d) { EditManifest(d, "\"options\": {", "\"options\": 5, \"options_was\": {"); }, "",
     "missing or malformed key"},
    {"OtherPreset", [](const fs::path&) {}, "--model elek --preset earth --option size=4x8x4 --option orders=1",
     "parameter hash"},
    {"OtherSize", [](const fs::path&) {}, "--model elek --preset atmosphere-plus --option size=8x8x4 --option orders=1",
     "does not match the model's"},
    {"OtherOrders", [](const fs::path&) {}, "--model elek --preset atmosphere-plus --option size=4x8x4 --option orders=2",
     "does not match the model's"},
};

class BadTableTest : public ReliabilityCliTest, public ::testing::WithParamInterface<BadTable> {};

TEST_P(BadTableTest, IsRefusedInOneLineBeforeAnyOutput) {
  const std::string elek = "--model elek --preset atmosphere-plus --option size=4x8x4 --option orders=1";
  const RunResult made = Run("precompute " + elek + " --out table");
  ASSERT_EQ(made.exit_code, 0) << made.err;
  GetParam().damage(dir_);
  const std::string loading = *GetParam().model_args != '\0' ? GetParam().model_args : elek;
  ExpectFailureKeepingOutputs("sample " + loading + " --table table" ATMO_ONE " --out out.csv", GetParam().message_part,
                              {"out.csv"});
}

INSTANTIATE_TEST_SUITE_P(Reliability, BadTableTest, ::testing::ValuesIn(kBadTables),
                         [](const ::testing::TestParamInfo<BadTable>& info) { return info.param.name; });

// Bad EXR files through the library's reader (atmo::ReadExr; the command line reads none): one
// atmo::Error line each, and a FIFO does not block.
TEST_F(ReliabilityCliTest, ReadExrRefusesBadFilesInOneLine) {
  atmo::Image image(16, 8, 3);
  for (std::size_t i = 0; i < image.pixels.size(); ++i) image.pixels[i] = static_cast<float>(i % 7);
  atmo::WriteExr(dir_ / "good.exr", image);
  const std::string good = ReadFile(dir_ / "good.exr");
  ASSERT_GT(good.size(), 100u);
  WriteFile(dir_ / "empty.exr", "");
  WriteFile(dir_ / "magic.exr", "v/1\x01");
  WriteFile(dir_ / "header_only.exr", good.substr(0, good.size() / 4));
  WriteFile(dir_ / "half.exr", good.substr(0, good.size() - 40));
  WriteFile(dir_ / "garbage.exr", std::string(4096, '\x5a'));
  WriteFile(dir_ / "png.exr", "\x89PNG\r\n\x1a\n" + std::string(100, '\0'));
  std::string wrong_version = good;
  wrong_version[4] = 9;
  WriteFile(dir_ / "version9.exr", wrong_version);
  ASSERT_EQ(::mkfifo((dir_ / "fifo.exr").c_str(), 0600), 0);
  fs::create_directory(dir_ / "folder.exr");
  const char* files[] = {"empty.exr", "magic.exr", "header_only.exr", "half.exr", "garbage.exr", "png.exr",
                         "version9.exr", "fifo.exr", "folder.exr", "missing.exr"};
  for (const char* file : files) {
    try {
      atmo::ReadExr(dir_ / file);
      ADD_FAILURE() << file << " was read";
    } catch (const atmo::Error& e) {
      const std::string message = e.what();
      EXPECT_NE(message.find(file), std::string::npos) << message;
      EXPECT_EQ(message.find('\n'), std::string::npos) << message;
    }
  }
  EXPECT_EQ(atmo::ReadExr(dir_ / "good.exr").pixels, image.pixels);
}

// The bad inputs of this file, counted for docs/reliability.md (at least 250, each refused in one
// line with a non-zero exit and the outputs unchanged).
TEST(BadInputCount, AtLeast250AreTried) {
  const std::size_t tables = std::size(kBadInputs) + BadConfigs().size() + BadFlags().size() + std::size(kBadTables);
  const std::size_t others = 5    // ElekManifestIntegersMustBeIntegers
                             + 10   // ReadExrRefusesBadFilesInOneLine
                             + 17   // PhysicalBounds.OutOfRangeValuesNameKeyValueAndRange
                             + 8    // WriteFileAtomicallyRefusesSpecialFiles, ReadFileBoundedRefuses...
                             + 5;   // OneLineErrors.InputTextIsQuotedWithItsControlCharactersEscaped
  std::printf("bad inputs: %zu audit, %zu configs, %zu flags and grids, %zu tables, %zu others: %zu\n",
              std::size(kBadInputs), BadConfigs().size(), BadFlags().size(), std::size(kBadTables), others,
              tables + others);
  EXPECT_GE(tables + others, 250u);
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
// The 8-bit RGB samples of a PNG (libpng's simplified API), empty when it cannot be read.
std::vector<unsigned char> PngSamples(const fs::path& path) {
  png_image image{};
  image.version = PNG_IMAGE_VERSION;
  if (!png_image_begin_read_from_file(&image, path.c_str())) return {};
  image.format = PNG_FORMAT_RGB;
  std::vector<unsigned char> samples(PNG_IMAGE_SIZE(image));
  if (!png_image_finish_read(&image, nullptr, samples.data(), 0, nullptr)) return {};
  return samples;
}

// The exposure flags at their bounds give a finite exposure and a PNG that is saturated (every
// pixel's brightest channel 255: nothing overflowed to a black pixel) or dark, for every tone
// curve; --exposure 1e300 had been accepted (a sun pixel times 1e300 is inf, shown black).
TEST_F(ReliabilityCliTest, ExposureBoundsGiveFiniteImages) {
  struct Bound {
    const char* flags;
    bool bright;
  };
  const Bound bounds[] = {{"--exposure 1e10", true},          {"--exposure 1e-10", false},
                          {"--ev -32", true},                 {"--ev 32", false},
                          {"--exposure 1e10 --tonemap aces", true}, {"--exposure 1e10 --tonemap none --per-channel", true}};
  for (const Bound& bound : bounds) {
    const RunResult r = Run(std::string("render --width 16 --height 8 --exr sky.exr --png sky.png ") + bound.flags);
    ASSERT_EQ(r.exit_code, 0) << bound.flags << ": " << r.err;
    atmo::ImageMetadata metadata;
    const atmo::Image exr = atmo::ReadExr(dir_ / "sky.exr", &metadata);
    for (const float v : exr.pixels) ASSERT_TRUE(std::isfinite(v)) << bound.flags;
    double exposure = kNan;
    for (const auto& [key, value] : metadata) {
      if (key == "atmo:pngExposure") exposure = std::strtod(value.c_str(), nullptr);
    }
    EXPECT_TRUE(exposure >= 1e-10 * 0.99 && exposure <= 1e10 * 1.01) << bound.flags << ": " << exposure;
    const std::vector<unsigned char> png = PngSamples(dir_ / "sky.png");
    ASSERT_EQ(png.size(), 16u * 8u * 3u) << bound.flags;
    for (std::size_t i = 0; i < png.size(); i += 3) {
      const int brightest = std::max({png[i], png[i + 1], png[i + 2]});
      if (bound.bright) {
        EXPECT_EQ(brightest, 255) << bound.flags << " pixel " << i / 3;
      } else {
        EXPECT_LE(brightest, 1) << bound.flags << " pixel " << i / 3;  // 1: the dither
      }
    }
  }
}

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
    // A hang is killed after 300 s (Run's limit, far above the seconds these take on a busy machine).
    const RunResult r = Run(std::string("sample --model reference --option samples=2 ") + args, 300);
    ExpectFiniteSamples(r, args);
  }
  // The audit's own command: `--samples 2`, the ground of the 52 796 km planet, a view just above
  // the horizon (at 90 degrees for an observer on the ground) and a sun near it.
  for (const char* view : {"89.9999", "89.999999", "90"}) {
    const RunResult r = Run(std::string("sample --model reference --samples 2 --config large_planet.json --altitude 0 "
                                        "--sun-zenith 89 --azimuth 0 --view-zenith ") + view, 300);
    ExpectFiniteSamples(r, view);
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
