// End-to-end tests of the `atmo` command line (docs/design.md §4): each test runs the program in a
// fresh temporary folder, capturing stdout and stderr to files, with tiny images so the whole
// file stays fast.
#include <sys/wait.h>
#include <unistd.h>

#include <cctype>
#include <algorithm>
#include <cmath>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <map>
#include <sstream>
#include <string>
#include <vector>

#include <gtest/gtest.h>
#include <png.h>

#include "atmo/colour.h"
#include "atmo/image.h"
#include "atmo/spectrum.h"
#include "cli_fixture.h"

namespace {

namespace fs = std::filesystem;
using atmo::testing::Lines;
using atmo::testing::ReadFile;
using atmo::testing::RunResult;
using atmo::testing::Split;
using atmo::testing::WriteFile;

constexpr const char* kOutputHeader =
    "altitude_m,sun_zenith_deg,view_zenith_deg,azimuth_deg,wavelength_nm,radiance,transmittance,stderr";
constexpr const char* kGridHeader = "altitude_m,sun_zenith_deg,view_zenith_deg,azimuth_deg";

class CliTest : public atmo::testing::CliFixture {};

// The rows of a sample CSV, header checked, each split into 8 fields.
std::vector<std::vector<std::string>> SampleRows(const std::string& csv) {
  const std::vector<std::string> lines = Lines(csv);
  EXPECT_FALSE(lines.empty());
  if (lines.empty()) return {};
  EXPECT_EQ(lines[0], kOutputHeader);
  std::vector<std::vector<std::string>> rows;
  for (std::size_t i = 1; i < lines.size(); ++i) {
    rows.push_back(Split(lines[i], ','));
    EXPECT_EQ(rows.back().size(), 8u) << lines[i];
  }
  return rows;
}

TEST_F(CliTest, VersionPrintsTheVersion) {
  const RunResult r = Run("--version");
  EXPECT_EQ(r.exit_code, 0);
  EXPECT_EQ(r.out, std::string("atmo ") + ATMO_VERSION + "\n");
}

TEST_F(CliTest, NoSubcommandPrintsHelpAndFails) {
  const RunResult r = Run("");
  EXPECT_NE(r.exit_code, 0);
  EXPECT_NE((r.out + r.err).find("render"), std::string::npos);  // the help lists the subcommands
}

TEST_F(CliTest, EverySubcommandHasHelp) {
  for (const char* subcommand : {"render", "sample", "bench", "compare", "precompute", "illuminance"}) {
    const RunResult r = Run(std::string(subcommand) + " --help");
    EXPECT_EQ(r.exit_code, 0) << subcommand;
    EXPECT_NE(r.out.find("--model"), std::string::npos) << subcommand;
    // One layout: the flags in groups, an example and the model and preset names in the footer.
    EXPECT_NE(r.out.find("Model and atmosphere:"), std::string::npos) << subcommand << ":\n" << r.out;
    EXPECT_NE(r.out.find("Example"), std::string::npos) << subcommand;
    EXPECT_NE(r.out.find("Models: elek, hillaire, reference, simple"), std::string::npos) << subcommand << ":\n" << r.out;
    EXPECT_NE(r.out.find("Presets: earth"), std::string::npos) << subcommand;
  }
  // presets takes only the flag it uses.
  const RunResult presets = Run("presets --help");
  EXPECT_EQ(presets.exit_code, 0);
  EXPECT_NE(presets.out.find("--dump"), std::string::npos);
  EXPECT_EQ(presets.out.find("--model"), std::string::npos) << presets.out;
  EXPECT_EQ(Run("presets --threads 2").exit_code, 2);
}

TEST_F(CliTest, PresetsListsTheThreePresets) {
  const RunResult r = Run("presets");
  ASSERT_EQ(r.exit_code, 0) << r.err;
  for (const char* name : {"earth", "atmosphere-plus", "simple"}) {
    bool found = false;
    for (const std::string& line : Lines(r.out)) found = found || line.rfind(std::string(name) + " ", 0) == 0;
    EXPECT_TRUE(found) << name << " in:\n" << r.out;
  }
}

TEST_F(CliTest, DumpedPresetGivesTheSameSamplesAsThePreset) {
  RunResult r = Run("presets --dump earth");
  ASSERT_EQ(r.exit_code, 0) << r.err;
  WriteFile(dir_ / "earth.json", r.out);
  const std::string query = " --altitude 0 --sun-zenith 60 --view-zenith 80 --azimuth 45";
  const RunResult from_preset = Run("sample --model hillaire --preset earth" + query);
  const RunResult from_config = Run("sample --model hillaire --config earth.json" + query);
  ASSERT_EQ(from_preset.exit_code, 0) << from_preset.err;
  ASSERT_EQ(from_config.exit_code, 0) << from_config.err;
  EXPECT_EQ(from_preset.out, from_config.out);
}

TEST_F(CliTest, SingleConfigurationGivesOneRowPerChannel) {
  const RunResult r =
      Run("sample --model hillaire --preset earth --altitude 0 --sun-zenith 30 "
          "--view-zenith 60 --azimuth 90");
  ASSERT_EQ(r.exit_code, 0) << r.err;
  const auto rows = SampleRows(r.out);
  ASSERT_EQ(rows.size(), 3u);
  const char* wavelengths[] = {"680", "550", "440"};
  for (int c = 0; c < 3; ++c) {
    ASSERT_EQ(rows[c].size(), 8u);
    EXPECT_EQ(rows[c][0], "0");
    EXPECT_EQ(rows[c][1], "30");
    EXPECT_EQ(rows[c][2], "60");
    EXPECT_EQ(rows[c][3], "90");
    EXPECT_EQ(rows[c][4], wavelengths[c]);
    const double radiance = std::stod(rows[c][5]);
    const double transmittance = std::stod(rows[c][6]);
    EXPECT_TRUE(std::isfinite(radiance) && radiance > 0.0) << rows[c][5];
    EXPECT_GT(transmittance, 0.0);  // an upward view reaches the top of the atmosphere
    EXPECT_LE(transmittance, 1.0);
    EXPECT_EQ(std::stod(rows[c][7]), 0.0);  // a deterministic model
  }
}

TEST_F(CliTest, ViewIntoTheGroundHasZeroTransmittance) {
  const RunResult r = Run("sample --model hillaire --preset earth --altitude 0 --sun-zenith 30 --view-zenith 120 --azimuth 0");
  ASSERT_EQ(r.exit_code, 0) << r.err;
  const auto rows = SampleRows(r.out);
  ASSERT_EQ(rows.size(), 3u);
  for (const auto& row : rows) {
    ASSERT_EQ(row.size(), 8u);
    EXPECT_EQ(std::stod(row[6]), 0.0);
  }
}

TEST_F(CliTest, GridGivesThreeRowsPerInputRowWithInputsEchoed) {
  // Surrounding whitespace, CRLF line ends and blank lines are tolerated.
  WriteFile(dir_ / "grid.csv", std::string(" ") + kGridHeader +
                                   " \r\n"
                                   "0,30,60,90\r\n"
                                   "\n"
                                   "1000, 30, 10, 180\n"
                                   "1000,85.5,90,0\n"
                                   "20000,100,45,270\n");
  const RunResult r = Run("sample --model hillaire --preset earth --grid grid.csv --out out.csv");
  ASSERT_EQ(r.exit_code, 0) << r.err;
  const auto rows = SampleRows(ReadFile(dir_ / "out.csv"));
  const std::vector<std::vector<std::string>> inputs = {{"0", "30", "60", "90"},
                                                        {"1000", "30", "10", "180"},
                                                        {"1000", "85.5", "90", "0"},
                                                        {"20000", "100", "45", "270"}};
  ASSERT_EQ(rows.size(), inputs.size() * 3);
  for (std::size_t i = 0; i < rows.size(); ++i) {
    ASSERT_EQ(rows[i].size(), 8u);
    for (int k = 0; k < 4; ++k) EXPECT_EQ(rows[i][k], inputs[i / 3][k]) << "row " << i;
    EXPECT_TRUE(std::isfinite(std::stod(rows[i][5])));
    EXPECT_GE(std::stod(rows[i][5]), 0.0);
  }
}

TEST_F(CliTest, RenderWritesExrAndPngForEveryCamera) {
  for (const char* camera : {"perspective", "fisheye", "equirect"}) {
    const std::string exr = std::string(camera) + ".exr";
    const std::string png = std::string(camera) + ".png";
    const RunResult r = Run(std::string("render --model hillaire --preset earth --width 64 --height 32 --camera ") + camera + " --exr " +
                            exr + " --png " + png);
    ASSERT_EQ(r.exit_code, 0) << camera << ": " << r.err;
    EXPECT_EQ(Lines(r.out).size(), 1u) << r.out;
    EXPECT_GT(fs::file_size(dir_ / exr), 0u);
    const std::string png_bytes = ReadFile(dir_ / png);
    ASSERT_GE(png_bytes.size(), 8u);
    EXPECT_EQ(png_bytes.substr(0, 8), std::string("\x89PNG\r\n\x1a\n", 8)) << camera;
  }
}

// render, sample and illuminance default to the accurate model on the real sky (whatever --model
// says, the preset stays us-standard); bench, compare and precompute keep theirs.
TEST_F(CliTest, DefaultsAreTheAccurateModelOnTheRealSky) {
  const auto attributes = [&](const std::string& flags) {
    const RunResult r = Run("render --width 16 --height 8 --sun-elevation 20 --png '' --exr d.exr " + flags);
    EXPECT_EQ(r.exit_code, 0) << r.err;
    atmo::ImageMetadata metadata;
    atmo::ReadExr(dir_ / "d.exr", &metadata);
    return std::map<std::string, std::string>(metadata.begin(), metadata.end());
  };
  std::map<std::string, std::string> values = attributes("");
  EXPECT_EQ(values["atmo:model"], "source4d");
  EXPECT_EQ(values["atmo:preset"], "us-standard");
  EXPECT_EQ(std::count(values["atmo:wavelengthsNm"].begin(), values["atmo:wavelengthsNm"].end(), ','), 14);
  values = attributes("--model hillaire");
  EXPECT_EQ(values["atmo:model"], "hillaire");
  EXPECT_EQ(values["atmo:preset"], "us-standard");
  const RunResult sample = Run("sample --altitude 0 --sun-elevation 30 --view-zenith 60 --azimuth 90");
  ASSERT_EQ(sample.exit_code, 0) << sample.err;
  EXPECT_EQ(SampleRows(sample.out).size(), 15u);
  const RunResult lux = Run("illuminance --sun-elevation 30");
  ASSERT_EQ(lux.exit_code, 0) << lux.err;
  // The help says each command's own default.
  for (const char* command : {"render", "sample", "illuminance", "irradiance", "calibrate", "annual"}) {
    const std::string help = Run(std::string(command) + " --help").out;
    EXPECT_NE(help.find("--model TEXT=source4d"), std::string::npos) << command;
    EXPECT_NE(help.find("--preset TEXT=us-standard"), std::string::npos) << command;
  }
  for (const char* command : {"bench", "compare"}) {
    const std::string help = Run(std::string(command) + " --help").out;
    EXPECT_NE(help.find("--model TEXT=hillaire"), std::string::npos) << command;
    EXPECT_NE(help.find("--preset TEXT=earth"), std::string::npos) << command;
  }
}

TEST_F(CliTest, RenderedExrCarriesItsSettings) {
  const RunResult r =
      Run("render --model hillaire --preset earth --width 16 --height 8 --camera equirect --sun-elevation 20 --seed 7 "
          "--threads 1 --exr sky.exr --png ''");
  ASSERT_EQ(r.exit_code, 0) << r.err;
  EXPECT_FALSE(fs::exists(dir_ / "sky.png"));
  atmo::ImageMetadata metadata;
  const atmo::Image image = atmo::ReadExr(dir_ / "sky.exr", &metadata);
  EXPECT_EQ(image.width, 16);
  EXPECT_EQ(image.height, 8);
  std::map<std::string, std::string> values(metadata.begin(), metadata.end());
  EXPECT_EQ(values["atmo:version"], ATMO_VERSION);
  EXPECT_EQ(values["atmo:model"], "hillaire");
  EXPECT_EQ(values["atmo:preset"], "earth");
  EXPECT_EQ(values["atmo:camera"], "equirect");
  EXPECT_EQ(values["atmo:sunElevationDeg"], "20");
  EXPECT_EQ(values["atmo:wavelengthsNm"], "680, 550, 440");
  EXPECT_EQ(values["atmo:parameterHash"].size(), 16u);
  for (const char* key : {"atmo:radianceUnit", "atmo:renderTimeMs", "atmo:sunAzimuthDeg", "atmo:altitudeM"}) {
    EXPECT_FALSE(values[key].empty()) << key;
  }
}

// --sun-size sets the disc's angular diameter (recorded in the EXR); the default is the preset's.
TEST_F(CliTest, RenderSunSizeIsTheDiscDiameter) {
  std::map<std::string, int> bright;
  for (const std::string size : {"", "5"}) {
    const std::string exr = "sun" + size + ".exr";
    const RunResult r = Run("render --model hillaire --preset earth --unit relative --width 256 --height 128 --camera equirect --sun-elevation 30 "
                            "--exr " + exr + " --png ''" + (size.empty() ? "" : " --sun-size " + size));
    ASSERT_EQ(r.exit_code, 0) << r.err;
    atmo::ImageMetadata metadata;
    const atmo::Image image = atmo::ReadExr(dir_ / exr, &metadata);
    std::map<std::string, std::string> values(metadata.begin(), metadata.end());
    // earth: 2 x 0.004675 rad = 0.5357 degrees.
    EXPECT_EQ(values["atmo:sunAngularDiameterDeg"], size.empty() ? "0.5357155384" : "5");
    for (std::size_t i = 0; i < image.pixels.size(); i += 3) bright[size] += image.pixels[i] > 30.0f;
  }
  // The same energy spread wider: the Sun's disc falls into a few of the 1.4 degree pixels, a
  // 5 degree disc (radiance ~120 per unit irradiance) into ~20.
  std::printf("pixels above 30: %d (the Sun), %d (5 degrees)\n", bright[""], bright["5"]);
  EXPECT_GT(bright["5"], 2 * bright[""]);
  for (const char* bad : {"0", "-1", "20.5", "nan"}) {
    const RunResult r = Run(std::string("render --model hillaire --preset earth --width 8 --height 4 --exr '' --png '' --sun-size ") + bad);
    EXPECT_NE(r.exit_code, 0) << bad;
    EXPECT_NE(r.err.find("--sun-size"), std::string::npos) << r.err;
  }
}

// `atmo render --model reference`: progressive, with standard-error channels. Small images
// (16x8 equirect, sun 30 degrees high, observer at 0 m, seed 1) keep these fast.
#define ATMO_REFERENCE_RENDER \
  "render --preset earth --model reference --camera equirect --width 16 --height 8 --sun-elevation 30 --altitude 0 --seed 1 "

TEST_F(CliTest, ReferenceRenderHasStandardErrorChannelsThatShrinkAsOneOverSqrtSpp) {
  std::map<int, atmo::Image> images;
  for (int spp : {16, 64}) {
    const std::string exr = "spp" + std::to_string(spp) + ".exr";
    const RunResult r = Run(ATMO_REFERENCE_RENDER "--spp " + std::to_string(spp) + " --exr " + exr + " --png ''");
    ASSERT_EQ(r.exit_code, 0) << r.err;
    EXPECT_EQ(r.err, "");  // no progress bar: stderr is not a terminal
    atmo::ImageMetadata metadata;
    images[spp] = atmo::ReadExr(dir_ / exr, &metadata);
    std::map<std::string, std::string> values(metadata.begin(), metadata.end());
    EXPECT_EQ(values["atmo:samplesPerPixel"], std::to_string(spp));
    EXPECT_FALSE(values["atmo:standardErrorChannels"].empty());
  }
  const atmo::Image& a = images[16];
  const atmo::Image& b = images[64];
  ASSERT_EQ(a.channels, 6);
  EXPECT_EQ(a.channel_names, (std::vector<std::string>{"R", "G", "B", "stderr.R", "stderr.G", "stderr.B"}));
  // Summed over the 128 pixels and 3 channels, the standard errors of 64 paths are
  // sqrt(16 / 64) = 0.5 of those of 16 (the first 16 of the same paths). The path values are
  // skewed (in red many paths score 0: a pixel can even get 16 zeros, standard error 0), so the
  // standard error of 16 paths is biased low: over seeds 1 to 8 the ratio was 0.52 to 0.55. The
  // stated tolerance is 0.5 +- 0.1.
  double sum_a = 0.0, sum_b = 0.0;
  for (int y = 0; y < 8; ++y) {
    for (int x = 0; x < 16; ++x) {
      for (int c = 0; c < 3; ++c) {
        const float se_a = a.at(x, y, 3 + c);
        const float se_b = b.at(x, y, 3 + c);
        EXPECT_TRUE(std::isfinite(se_a) && se_a >= 0.0f) << x << "," << y;
        EXPECT_TRUE(std::isfinite(se_b) && se_b >= 0.0f) << x << "," << y;
        sum_a += se_a;
        sum_b += se_b;
      }
    }
  }
  EXPECT_NEAR(sum_b / sum_a, 0.5, 0.1);
}

TEST_F(CliTest, ReferenceRenderIsTheSameForOneAndTwoThreads) {
  for (const char* threads : {"1", "2"}) {
    const RunResult r = Run(ATMO_REFERENCE_RENDER "--spp 16 --png '' --exr t" + std::string(threads) +
                            ".exr --threads " + threads);
    ASSERT_EQ(r.exit_code, 0) << r.err;
  }
  const atmo::Image one = atmo::ReadExr(dir_ / "t1.exr");
  const atmo::Image two = atmo::ReadExr(dir_ / "t2.exr");
  ASSERT_EQ(one.channels, 6);
  EXPECT_EQ(one.pixels, two.pixels);
}

TEST_F(CliTest, ReferenceRenderPixelMatchesSample) {
  // Equirect pixel (x, y) of a 16x8 image looks at view zenith 180 (y + 0.5) / 8 and at azimuth
  // 360 ((x + 0.5) / 16 - 0.5) from the sun (the view is centred on the sun). Pixel (12, 2): view
  // zenith 56.25, azimuth 101.25, well clear of the sun disc and the ground. With --unit relative
  // the render multiplies by the solar irradiance, 1 for the earth preset.
  const RunResult render = Run(ATMO_REFERENCE_RENDER "--spp 512 --unit relative --exr px.exr --png ''");
  ASSERT_EQ(render.exit_code, 0) << render.err;
  const atmo::Image image = atmo::ReadExr(dir_ / "px.exr");
  const RunResult sample = Run(
      "sample --preset earth --model reference --altitude 0 --sun-zenith 60 --view-zenith 56.25 --azimuth 101.25 --samples 4096 "
      "--seed 2");
  ASSERT_EQ(sample.exit_code, 0) << sample.err;
  const auto rows = SampleRows(sample.out);
  ASSERT_EQ(rows.size(), 3u);
  for (int c = 0; c < 3; ++c) {
    const double radiance = std::stod(rows[c][5]);
    const double se = std::stod(rows[c][7]);
    const double pixel = image.at(12, 2, c);
    const double pixel_se = image.at(12, 2, 3 + c);
    EXPECT_GT(pixel_se, 0.0);
    EXPECT_LE(std::abs(pixel - radiance), 3.0 * std::hypot(se, pixel_se))
        << "channel " << c << ": pixel " << pixel << " +- " << pixel_se << ", sample " << radiance << " +- " << se;
  }
}

// A command that must fail: non-zero exit, one `atmo: error:` line on stderr, and the outputs
// that existed before untouched.
struct FailureCase {
  const char* name;
  const char* args;
  const char* message_part;  // a part of the error message that says what was wrong
};

class CliFailureTest : public CliTest, public ::testing::WithParamInterface<FailureCase> {};

TEST_P(CliFailureTest, FailsWithOneLineAndLeavesOutputsUntouched) {
  WriteFile(dir_ / "bad.json", "{\"top_radius_m\": 6460000,");
  WriteFile(dir_ / "negative_top.json", "{\"top_radius_m\": -1}");
  WriteFile(dir_ / "unknown_key.json", "{\"no_such_key\": 1}");
  WriteFile(dir_ / "earth.json", "{}");
  WriteFile(dir_ / "bad_header.csv", "altitude,sun_zenith_deg,view_zenith_deg,azimuth_deg\n0,30,60,90\n");
  WriteFile(dir_ / "three_numbers.csv", std::string(kGridHeader) + "\n0,30,60,90\n0,30,60\n");
  ExpectFailureKeepingOutputs(GetParam().args, GetParam().message_part, {"out.csv", "sky.exr", "sky.png"});
}

#define ATMO_SAMPLE_ONE " --altitude 0 --sun-zenith 30 --view-zenith 60 --azimuth 90 --out out.csv"
#define ATMO_TINY_RENDER " --width 8 --height 4"

const FailureCase kFailureCases[] = {
    {"MalformedJsonConfig", "sample --config bad.json" ATMO_SAMPLE_ONE, "bad.json"},
    {"NegativeTopRadius", "sample --config negative_top.json" ATMO_SAMPLE_ONE, "top_radius_m"},
    {"UnknownConfigKey", "render --config unknown_key.json" ATMO_TINY_RENDER, "no_such_key"},
    {"NanAltitudeRender", "render --altitude nan" ATMO_TINY_RENDER, "--altitude"},
    {"NanAltitudeSample", "sample --altitude nan --sun-zenith 30 --view-zenith 60 --azimuth 90 --out out.csv",
     "--altitude"},
    {"UnwritablePng", "render --png /nonexistent-dir/x.png" ATMO_TINY_RENDER, "/nonexistent-dir"},
    {"UnwritableOut",
     "sample --altitude 0 --sun-zenith 30 --view-zenith 60 --azimuth 90 --out /nonexistent-dir/x.csv",
     "/nonexistent-dir"},
    {"AbsurdResolution", "render --width 100000 --height 4", "--width"},
    {"UnknownModel", "sample --model no-such-model" ATMO_SAMPLE_ONE, "no-such-model"},
    {"UnknownPreset", "render --preset no-such-preset" ATMO_TINY_RENDER, "no-such-preset"},
    {"BadCsvHeader", "sample --grid bad_header.csv --out out.csv", "bad_header.csv:1:"},
    {"CsvRowWithThreeNumbers", "sample --grid three_numbers.csv --out out.csv",
     "three_numbers.csv:3: expected 4 comma-separated numbers"},
    {"PresetAndConfigTogether", "sample --preset earth --config earth.json" ATMO_SAMPLE_ONE, "--config"},
#ifdef ATMO_HAVE_GL
    {"GlBackendOtherModel", "render --backend gl --model simple --preset simple" ATMO_TINY_RENDER,
     "the gl backend runs models hillaire, elek and source4d"},
    {"GlBackendOtherCommand", "compare --backend gl", "the gl backend runs `atmo render`, `sample`"},
#else
    {"GlBackend", "render --backend gl" ATMO_TINY_RENDER, "the gl backend is not available in this build"},
#endif
    {"ViewZenithOutOfRange",
     "sample --altitude 0 --sun-zenith 30 --view-zenith 190 --azimuth 0 --out out.csv", "--view-zenith"},
    {"GridWithSingleConfiguration", "sample --grid three_numbers.csv --altitude 0 --out out.csv", "--grid"},
    {"MissingSingleConfigurationValue", "sample --altitude 0 --sun-zenith 30 --view-zenith 60 --out out.csv",
     "--azimuth"},
    {"MalformedModelOption", "sample --option novalue" ATMO_SAMPLE_ONE, "novalue"},
    {"ThreadsOutOfRange", "render --threads 0" ATMO_TINY_RENDER, "--threads"},
    {"SppForADeterministicModel", "render --model simple --preset simple --spp 16" ATMO_TINY_RENDER,
     "takes no --spp"},
    {"SppOfOne", "render --preset earth --model reference --spp 1" ATMO_TINY_RENDER, "--spp"},
    {"UnknownUnit", "render --model hillaire --preset earth --unit lumens" ATMO_TINY_RENDER, "--unit"},
    {"XyzWithoutLuminance", "render --model hillaire --preset earth --unit radiance --xyz" ATMO_TINY_RENDER, "--xyz needs --unit luminance"},
    {"SpectralTooFew", "sample --model hillaire --preset earth --spectral 2" ATMO_SAMPLE_ONE, "--spectral"},
};

INSTANTIATE_TEST_SUITE_P(Cli, CliFailureTest, ::testing::ValuesIn(kFailureCases),
                         [](const ::testing::TestParamInfo<FailureCase>& info) { return info.param.name; });

TEST_F(CliTest, RenderUnitsAreRecordedAndConsistent) {
  // One equirect in the three units: luminance (linear sRGB with chromaticities, cd/m^2),
  // radiance (one channel per wavelength, W m^-2 sr^-1 nm^-1) and relative. Each is the same sky:
  // radiance = relative x E_sun(lambda), luminance = the colour conversion of relative.
  const std::string base = "render --model hillaire --preset earth --camera equirect --width 16 --height 8 --sun-elevation 30 --png '' --spectral 5 ";
  for (const char* unit : {"luminance", "radiance", "relative"}) {
    const RunResult r = Run(base + "--unit " + unit + " --exr " + unit + ".exr");
    ASSERT_EQ(r.exit_code, 0) << unit << ": " << r.err;
  }
  atmo::ImageMetadata metadata;
  const atmo::Image luminance = atmo::ReadExr(dir_ / "luminance.exr", &metadata);
  std::map<std::string, std::string> values(metadata.begin(), metadata.end());
  EXPECT_EQ(values["atmo:unit"], "luminance");
  EXPECT_NE(values["atmo:radianceUnit"].find("cd/m^2"), std::string::npos);
  EXPECT_EQ(luminance.colour_space, atmo::ColourSpace::kLinearSrgb);
  ASSERT_EQ(luminance.channels, 3);
  const atmo::Image radiance = atmo::ReadExr(dir_ / "radiance.exr");
  const atmo::Image relative = atmo::ReadExr(dir_ / "relative.exr");
  ASSERT_EQ(radiance.channels, 5);
  ASSERT_EQ(relative.channels, 5);
  const atmo::SpectralConversion convert(atmo::SpectralWavelengths(5));
  // Relative holds r x solar_irradiance, and MakeSpectral sets solar_irradiance to E_sun: in this
  // case relative and radiance hold the same numbers.
  for (int c = 0; c < 5; ++c) EXPECT_NEAR(radiance.at(4, 2, c), relative.at(4, 2, c), 1e-6 * relative.at(4, 2, c));
  std::vector<double> r(5);
  for (int c = 0; c < 5; ++c) r[c] = relative.at(4, 2, c) / convert.solar_irradiance()[c];
  const glm::dvec3 rgb = convert.LinearSrgb(r);
  for (int k = 0; k < 3; ++k) EXPECT_NEAR(luminance.at(4, 2, k), rgb[k], 1e-4 * std::abs(rgb[k]) + 1e-3) << k;
  // XYZ on request, with the XYZ chromaticities.
  ASSERT_EQ(Run(base + "--xyz --exr xyz.exr").exit_code, 0);
  const atmo::Image xyz = atmo::ReadExr(dir_ / "xyz.exr");
  EXPECT_EQ(xyz.colour_space, atmo::ColourSpace::kCieXyz);
  EXPECT_EQ(xyz.channel_names, (std::vector<std::string>{"X", "Y", "Z"}));
}

// 8-bit RGB samples of a PNG, as stored (the files are sRGB-tagged: no conversion applies).
std::vector<unsigned char> ReadPngRgb(const fs::path& path, int* width, int* height) {
  png_image image{};
  image.version = PNG_IMAGE_VERSION;
  if (!png_image_begin_read_from_file(&image, path.c_str())) return {};
  image.format = PNG_FORMAT_RGB;
  std::vector<unsigned char> rgb(PNG_IMAGE_SIZE(image));
  if (!png_image_finish_read(&image, nullptr, rgb.data(), 0, nullptr)) return {};
  *width = static_cast<int>(image.width);
  *height = static_cast<int>(image.height);
  return rgb;
}

TEST_F(CliTest, SunriseSunIsNearWhiteWithAgxAndKeepsItsHueOnTheLuminanceCurve) {
  // A 2-degree view centred on a sun 1 degree up: the disc fills the middle. Its EXR colour is a
  // deep orange. The default AgX rolls it off to near white, as film and the eye see a sun far
  // over the exposure; the exp curve on luminance keeps the hue (chromaticity kept).
  const std::string view = "render --model hillaire --preset earth --width 64 --height 64 --fov 2 --pitch 1 --sun-elevation 1 --exr sun.exr ";
  ASSERT_EQ(Run(view + "--png agx.png").exit_code, 0);
  ASSERT_EQ(Run(view + "--png sun.png --tonemap exp").exit_code, 0);
  ASSERT_EQ(Run(view + "--png seed.png --per-channel --gamma 2.2").exit_code, 0);
  const atmo::Image exr = atmo::ReadExr(dir_ / "sun.exr");
  const float r = exr.at(32, 32, 0), g = exr.at(32, 32, 1);
  ASSERT_GT(r, 2.0f * g) << "the sunrise sun is orange in the EXR";
  int w = 0, h = 0;
  const std::vector<unsigned char> agx = ReadPngRgb(dir_ / "agx.png", &w, &h);
  ASSERT_EQ(agx.size(), 64u * 64u * 3u);
  for (int c = 0; c < 3; ++c) EXPECT_GE(agx[(32 * 64 + 32) * 3 + c], 235) << c;
  const std::vector<unsigned char> png = ReadPngRgb(dir_ / "sun.png", &w, &h);
  ASSERT_EQ(png.size(), 64u * 64u * 3u);
  const unsigned char* centre = &png[(32 * 64 + 32) * 3];
  EXPECT_GT(centre[0], centre[1]);
  EXPECT_GT(centre[1], centre[2]);
  // sRGB-decoded G/R equals the linear G/R of the EXR within 10 % (8-bit codes and dither).
  const auto decode = [](unsigned char code) { return atmo::SrgbDecode(code / 255.0); };
  EXPECT_NEAR(decode(centre[1]) / decode(centre[0]), g / r, 0.1 * g / r);
  const std::vector<unsigned char> seed = ReadPngRgb(dir_ / "seed.png", &w, &h);
  const unsigned char* seed_centre = &seed[(32 * 64 + 32) * 3];
  EXPECT_GT(seed_centre[1], 200) << "the per-channel curve saturates green too: a near-white sun";
}

// Mean Rec.601 luma (the "brightness" of 8-bit sRGB codes) of rows [y0, y1) of an RGB PNG.
double MeanLuma(const std::vector<unsigned char>& rgb, int width, int y0, int y1) {
  double sum = 0.0;
  for (int y = y0; y < y1; ++y) {
    for (int x = 0; x < width; ++x) {
      const unsigned char* p = &rgb[(static_cast<std::size_t>(y) * width + x) * 3];
      sum += 0.299 * p[0] + 0.587 * p[1] + 0.114 * p[2];
    }
  }
  return sum / (static_cast<double>(y1 - y0) * width);
}

TEST_F(CliTest, OutputNamesOfAnotherFormatAreRefused) {
  // -o NAME.jpg would have written NAME.jpg.exr and NAME.jpg.png.
  ExpectFailureKeepingOutputs("render --model hillaire --preset earth --width 8 --height 8 -o out.jpg", "-o 'out.jpg' ends in .jpg",
                              {"out.jpg.exr", "out.jpg.png"});
  ExpectFailureKeepingOutputs("render --model hillaire --preset earth --width 8 --height 8 -o sky.HDR", "ends in .hdr", {"sky.HDR.exr"});
  // A dot that is not a format's extension is part of the name.
  ASSERT_EQ(Run("render --model hillaire --preset earth --width 8 --height 8 -o sky.v2").exit_code, 0);
  EXPECT_TRUE(fs::exists(dir_ / "sky.v2.exr"));
  EXPECT_TRUE(fs::exists(dir_ / "sky.v2.png"));
}

TEST_F(CliTest, MistypedFlagsAndSubcommandsGetASuggestion) {
  const auto error_of = [&](const std::string& args) {
    const RunResult r = Run(args);
    EXPECT_EQ(r.exit_code, 2) << args;
    EXPECT_EQ(Lines(r.err).size(), 1u) << r.err;
    return r.err;
  };
  EXPECT_NE(error_of("rendr").find("(did you mean render?)"), std::string::npos);
  EXPECT_NE(error_of("iluminance").find("(did you mean illuminance?)"), std::string::npos);
  EXPECT_NE(error_of("render --model hillaire --preset earth --sun-elevaton 5").find("(did you mean --sun-elevation?)"), std::string::npos);
  EXPECT_NE(error_of("sample --model hillaire --preset earth --altitud=3").find("(did you mean --altitude?)"), std::string::npos);
  EXPECT_NE(error_of("illuminance --model hillaire --preset earth --sun-elevatoin 5").find("(did you mean --sun-elevation?)"), std::string::npos);
  // Nothing close: no guess.
  EXPECT_EQ(error_of("xyzzy").find("did you mean"), std::string::npos);
  EXPECT_EQ(error_of("render --model hillaire --preset earth --frobnicate 3").find("did you mean"), std::string::npos);
}

TEST_F(CliTest, TheFirstPictureLooksLikeDaylightAndTheSunIsWhite) {
  // Noon (sun 60 degrees, default exposure and display): the top third of the frame has a mean
  // luma of at least 100 of 255, and a time-lapse keeps dusk darker than noon.
  for (const char* elevation : {"60", "-8"}) {
    ASSERT_EQ(Run(std::string("render --model hillaire --preset earth --width 320 --height 180 --no-exr --sun-elevation ") + elevation +
                  " -o sky" + elevation)
                  .exit_code,
              0);
  }
  int w = 0, h = 0;
  const std::vector<unsigned char> noon = ReadPngRgb(dir_ / "sky60.png", &w, &h);
  const double noon_top = MeanLuma(noon, w, 0, h / 3);
  EXPECT_GE(noon_top, 100.0);
  const std::vector<unsigned char> dusk = ReadPngRgb(dir_ / "sky-8.png", &w, &h);
  EXPECT_LT(MeanLuma(dusk, w, 0, h / 3), noon_top - 30.0) << "nautical twilight darker than noon";
  // Sun 30 degrees up, spectral, a 5-degree field of 400 x 400: the disc's centre is near white
  // (every channel at least 235) and not darker than the sky 40 pixels (half a degree) away.
  ASSERT_EQ(Run("render --model hillaire --preset earth-spectral --sun-elevation 30 --pitch 30 --fov 5 --width 400 --height 400 "
                "--no-exr -o disc")
                .exit_code,
            0);
  const std::vector<unsigned char> disc = ReadPngRgb(dir_ / "disc.png", &w, &h);
  ASSERT_EQ(w, 400);
  const unsigned char* centre = &disc[(200 * 400 + 200) * 3];
  for (const int offset : {-40, 40}) {
    const unsigned char* beside = &disc[(200 * 400 + 200 + offset) * 3];
    const unsigned char* above = &disc[((200 + offset) * 400 + 200) * 3];
    for (int c = 0; c < 3; ++c) {
      EXPECT_GE(centre[c], 235) << c;
      EXPECT_GE(centre[c], beside[c]) << c;
      EXPECT_GE(centre[c], above[c]) << c;
    }
  }
}

TEST_F(CliTest, CivilTwilightIsVisibleWithAutoExposure) {
  // Sun 4 degrees below the horizon, the all-sky fisheye: at sunny-16 exposure (EV100 15) the sky
  // is black; auto-exposure shows it (mean sRGB code of the sky well above black).
  const std::string base = "render --model hillaire --preset earth-spectral --camera fisheye --width 64 --height 64 "
                           "--sun-elevation -4 --exr '' ";
  ASSERT_EQ(Run(base + "--ev 15 --png day.png").exit_code, 0);
  ASSERT_EQ(Run(base + "--auto-exposure --png auto.png").exit_code, 0);
  const auto mean_code = [&](const char* name) {
    int w = 0, h = 0;
    const std::vector<unsigned char> rgb = ReadPngRgb(dir_ / name, &w, &h);
    double sum = 0.0;
    int n = 0;
    for (int y = 0; y < h; ++y) {
      for (int x = 0; x < w; ++x) {
        const double dx = x + 0.5 - w / 2.0, dy = y + 0.5 - h / 2.0;
        if (dx * dx + dy * dy > 0.8 * 0.25 * w * w) continue;  // inside the circle
        for (int c = 0; c < 3; ++c) sum += rgb[(y * w + x) * 3 + c];
        n += 3;
      }
    }
    return sum / n;
  };
  EXPECT_LT(mean_code("day.png"), 5.0);
  EXPECT_GT(mean_code("auto.png"), 50.0);
}

TEST_F(CliTest, SampleUnitsAgree) {
  const std::string query = "sample --model hillaire --preset earth --altitude 0 --sun-zenith 40 --view-zenith 70 --azimuth 120 ";
  const RunResult relative = Run(query);
  const RunResult radiance = Run(query + "--unit radiance");
  const RunResult luminance = Run(query + "--unit luminance");
  ASSERT_EQ(luminance.exit_code, 0) << luminance.err;
  const auto rel = SampleRows(relative.out);
  const auto rad = SampleRows(radiance.out);
  ASSERT_EQ(rel.size(), 3u);
  ASSERT_EQ(rad.size(), 3u);
  const std::vector<double> wavelengths = {680.0, 550.0, 440.0};
  const atmo::SpectralConversion convert(wavelengths);
  std::vector<double> r(3);
  for (int c = 0; c < 3; ++c) {
    r[c] = std::stod(rel[c][5]);
    EXPECT_NEAR(std::stod(rad[c][5]), r[c] * atmo::SolarSpectralIrradiance(wavelengths[c]), 1e-8 * std::stod(rad[c][5]));
  }
  const std::vector<std::string> lines = Lines(luminance.out);
  ASSERT_EQ(lines.size(), 2u);
  EXPECT_EQ(lines[0], "altitude_m,sun_zenith_deg,view_zenith_deg,azimuth_deg,luminance_cd_m2,luminous_transmittance,stderr");
  const std::vector<std::string> fields = Split(lines[1]);
  EXPECT_NEAR(std::stod(fields[4]), convert.Luminance(r), 1e-6 * convert.Luminance(r));
}

TEST_F(CliTest, CsvRowErrorNamesTheLine) {
  WriteFile(dir_ / "grid.csv", std::string(kGridHeader) + "\n0,30,60,90\n0,30,60\n");
  const RunResult r = Run("sample --model hillaire --preset earth --grid grid.csv");
  EXPECT_NE(r.exit_code, 0);
  EXPECT_EQ(r.err, "atmo: error: grid.csv:3: expected 4 comma-separated numbers\n");
  EXPECT_EQ(r.out, "");
}

}  // namespace

namespace {

// The command line as a new user meets it: names, outputs, warnings, aliases, timing.
TEST_F(CliTest, NonIntegerSideIsSaidToBeNoInteger) {
  const RunResult r = Run("render --model hillaire --preset earth --width abc");
  EXPECT_EQ(r.exit_code, 2);
  EXPECT_EQ(r.err, "atmo: error: --width: 'abc' is not an integer\n");
}

TEST_F(CliTest, OutputNameWritesBothFilesOrTheOneItsExtensionNames) {
  ASSERT_EQ(Run("render --model hillaire --preset earth --width 8 --height 4 -o both").exit_code, 0);
  EXPECT_TRUE(fs::exists(dir_ / "both.exr"));
  EXPECT_TRUE(fs::exists(dir_ / "both.png"));
  ASSERT_EQ(Run("render --model hillaire --preset earth --width 8 --height 4 --output only.png").exit_code, 0);
  EXPECT_TRUE(fs::exists(dir_ / "only.png"));
  EXPECT_FALSE(fs::exists(dir_ / "only.png.exr"));
  EXPECT_FALSE(fs::exists(dir_ / "only.exr"));
  const RunResult no_png = Run("render --model hillaire --preset earth --width 8 --height 4 --no-png --exr solo.exr");
  ASSERT_EQ(no_png.exit_code, 0) << no_png.err;
  EXPECT_TRUE(fs::exists(dir_ / "solo.exr"));
  EXPECT_FALSE(fs::exists(dir_ / "sky.png"));
  EXPECT_EQ(Lines(no_png.out).size(), 1u);
  EXPECT_EQ(no_png.out.rfind("wrote solo.exr (8x4 perspective, hillaire, earth) in ", 0), 0u) << no_png.out;
  EXPECT_NE(no_png.out.find(": precompute "), std::string::npos) << no_png.out;
  EXPECT_NE(no_png.out.find(", write "), std::string::npos) << no_png.out;
  EXPECT_EQ(Run("render --model hillaire --preset earth -o a --exr b.exr").exit_code, 2);
  EXPECT_EQ(Run("render --model hillaire --preset earth --no-png --png b.png").exit_code, 2);
}

TEST_F(CliTest, AnOutputWithTheWrongExtensionIsRefused) {
  ExpectFailureKeepingOutputs("render --model hillaire --preset earth --width 8 --height 4 --png x.jpg", "--png 'x.jpg' must end in .png", {"x.jpg"});
  ExpectFailureKeepingOutputs("render --model hillaire --preset earth --width 8 --height 4 --exr x.png --png ''", "--exr 'x.png' must end in .exr",
                              {"x.png"});
  ExpectFailureKeepingOutputs("sample --model hillaire --preset earth --altitude 0 --sun-zenith 30 --view-zenith 0 --azimuth 0 --out x.txt",
                              "--out 'x.txt' must end in .csv", {"x.txt"});
  WriteFile(dir_ / "g.csv", std::string(kGridHeader) + "\n0,30,0,0\n");
  ExpectFailureKeepingOutputs("compare --grid g.csv --json x.csv", "--json 'x.csv' must end in .json", {"x.csv"});
  EXPECT_EQ(Run("render --model hillaire --preset earth --width 8 --height 4 --png X.PNG --exr ''").exit_code, 0);  // case does not matter
}

TEST_F(CliTest, FlagsTheCameraDoesNotUseAreNamedInAWarning) {
  const RunResult r = Run("render --model hillaire --preset earth --camera equirect --width 16 --height 8 --fov 60 --pitch 5 --png ''");
  ASSERT_EQ(r.exit_code, 0) << r.err;
  EXPECT_EQ(r.err,
            "atmo: warning: --fov applies to the perspective camera only\n"
            "atmo: warning: --pitch applies to the perspective camera only\n");
  atmo::ImageMetadata metadata;
  atmo::ReadExr(dir_ / "sky.exr", &metadata);
  std::map<std::string, std::string> values(metadata.begin(), metadata.end());
  EXPECT_EQ(values.count("atmo:cameraFovDeg"), 0u);    // the equirect has no field of view
  EXPECT_EQ(values.count("atmo:cameraPitchDeg"), 0u);  // nor a pitch
  EXPECT_EQ(values.count("atmo:cameraYawDeg"), 1u);
  const RunResult png_only = Run("render --model hillaire --preset earth --width 8 --height 4 --png '' --exposure 2");
  EXPECT_EQ(png_only.exit_code, 0);
  EXPECT_EQ(png_only.err, "atmo: warning: --exposure applies to the PNG only\n");
  const RunResult perspective = Run("render --model hillaire --preset earth --width 8 --height 4 --fov 60 --png ''");
  EXPECT_EQ(perspective.err, "");
  metadata.clear();
  atmo::ReadExr(dir_ / "sky.exr", &metadata);
  values = std::map<std::string, std::string>(metadata.begin(), metadata.end());
  EXPECT_EQ(values["atmo:cameraFovDeg"], "60");
  EXPECT_EQ(values["atmo:cameraPitchDeg"], "10");
  // A cube map's faces fix their own directions: no yaw, field of view or pitch is recorded.
  ASSERT_EQ(Run("render --model hillaire --preset earth --camera cubemap --face-size 4 --png ''").exit_code, 0);
  metadata.clear();
  atmo::ReadExr(dir_ / "sky.exr", &metadata);
  values = std::map<std::string, std::string>(metadata.begin(), metadata.end());
  for (const char* key : {"atmo:cameraYawDeg", "atmo:cameraFovDeg", "atmo:cameraPitchDeg"}) {
    EXPECT_EQ(values.count(key), 0u) << key;
  }
  EXPECT_EQ(values["atmo:camera"], "cubemap");
}

TEST_F(CliTest, GridDashReadsStandardInput) {
  const std::string grid = std::string(kGridHeader) + "\n0,30,0,0\n1000,85,89,180\n";
  WriteFile(dir_ / "grid.csv", grid);
  const RunResult from_file = Run("sample --model hillaire --preset earth --grid grid.csv");
  const RunResult from_stdin = Run("sample --model hillaire --preset earth --grid - < grid.csv");
  ASSERT_EQ(from_stdin.exit_code, 0) << from_stdin.err;
  EXPECT_EQ(from_stdin.out, from_file.out);
  WriteFile(dir_ / "bad.csv", std::string(kGridHeader) + "\n0,30,0\n");
  const RunResult bad = Run("sample --model hillaire --preset earth --grid - < bad.csv");
  EXPECT_EQ(bad.exit_code, 1);
  EXPECT_EQ(bad.err, "atmo: error: <stdin>:2: expected 4 comma-separated numbers\n");
  const RunResult compare = Run("compare --model hillaire --against hillaire --grid - --image-size 32 < grid.csv");
  EXPECT_EQ(compare.exit_code, 0) << compare.err;
  EXPECT_EQ(compare.err, "atmo: warning: --image-size applies to the --image only\n");
  EXPECT_NE(compare.out.find("2 configurations x 3 channels = 6 rows"), std::string::npos) << compare.out;
}

TEST_F(CliTest, SampleTakesTheSunElevationAndBothPathCountNames) {
  const RunResult zenith = Run("sample --model hillaire --preset earth --altitude 0 --sun-zenith 60 --view-zenith 80 --azimuth 90");
  const RunResult elevation = Run("sample --model hillaire --preset earth --altitude 0 --sun-elevation 30 --view-zenith 80 --azimuth 90");
  ASSERT_EQ(elevation.exit_code, 0) << elevation.err;
  EXPECT_EQ(elevation.out, zenith.out);
  EXPECT_EQ(Run("sample --model hillaire --preset earth --altitude 0 --sun-elevation 30 --sun-zenith 60 --view-zenith 80 --azimuth 90").exit_code, 2);
  const std::string one = "sample --preset earth --model reference --seed 3 --altitude 0 --sun-zenith 60 --view-zenith 80 --azimuth 90 ";
  const RunResult samples = Run(one + "--samples 64");
  const RunResult spp = Run(one + "--spp 64");
  ASSERT_EQ(spp.exit_code, 0) << spp.err;
  EXPECT_EQ(spp.out, samples.out);
  const RunResult render = Run(ATMO_REFERENCE_RENDER "--samples 8 --exr s.exr --png ''");
  ASSERT_EQ(render.exit_code, 0) << render.err;
  atmo::ImageMetadata metadata;
  atmo::ReadExr(dir_ / "s.exr", &metadata);
  std::map<std::string, std::string> values(metadata.begin(), metadata.end());
  EXPECT_EQ(values["atmo:samplesPerPixel"], "8");
}

TEST_F(CliTest, PrecomputeDefaultsToTheModelItExports) {
  const RunResult r = Run("precompute --preset atmosphere-plus --option size=8x16x8 --option orders=1 --out t");
  ASSERT_EQ(r.exit_code, 0) << r.err;
  EXPECT_TRUE(fs::exists(dir_ / "t.raw"));
  EXPECT_EQ(r.out.rfind("wrote t.exr, t.raw, t_transmittance.exr, t_transmittance.raw, t.json (elek, ", 0), 0u)
      << r.out;
}

// --model hillaire exports its six tables and the manifest; the view flags reach the manifest, an
// observer above the atmosphere is refused in one line before anything is written, and the
// hillaire-only flags are named in a warning for elek.
TEST_F(CliTest, PrecomputeHillaireWritesTheTablesOfTheView) {
  const std::string small = "--option transmittance_lut=32x16 --option multiple_scattering_lut=8x8 "
                            "--option sky_view_lut=32x16 --aerial-size 4x4x4 --width 64 --height 32 ";
  const RunResult r =
      Run("precompute --model hillaire " + small + "--altitude 250 --sun-elevation 33 --sun-azimuth 90 --out h");
  ASSERT_EQ(r.exit_code, 0) << r.err;
  EXPECT_EQ(r.out.rfind("wrote h.json and 6 tables as h_<table>.exr, .raw (hillaire, earth, cpu, altitude 250 m, sun "
                        "elevation 33 deg)", 0), 0u) << r.out;
  for (const char* table : {"transmittance", "multiple_scattering", "sky_view", "sky_view_ground", "aerial_radiance",
                            "aerial_transmittance"}) {
    EXPECT_TRUE(fs::exists(dir_ / ("h_" + std::string(table) + ".exr"))) << table;
    EXPECT_TRUE(fs::exists(dir_ / ("h_" + std::string(table) + ".raw"))) << table;
  }
  const std::string manifest = ReadFile(dir_ / "h.json");
  EXPECT_NE(manifest.find("\"altitude_m\": 250.0"), std::string::npos);
  EXPECT_NE(manifest.find("\"sun_elevation_deg\": 33.0"), std::string::npos);
  EXPECT_NE(manifest.find("\"sky_view_lut\": \"32x16\""), std::string::npos);
  ExpectFailureKeepingOutputs("precompute --model hillaire " + small + "--altitude 200000 --out x",
                              "inside the atmosphere", {"x.json", "x_sky_view.raw"});
  ExpectFailureKeepingOutputs("precompute --model hillaire --aerial-size 4x4 --out x", "--aerial-size 4x4",
                              {"x.json"});
  const RunResult elek = Run("precompute --preset atmosphere-plus --option size=8x16x8 --option orders=1 "
                             "--altitude 5 --out e");
  ASSERT_EQ(elek.exit_code, 0) << elek.err;
  EXPECT_EQ(elek.err, "atmo: warning: --altitude applies to --model hillaire only\n");
  EXPECT_EQ(Run("precompute --model simple --out s").exit_code, 1);
}

}  // namespace
