// End-to-end tests of the `atmo` command line (DESIGN.md §4): each test runs the program in a
// fresh temporary folder, capturing stdout and stderr to files, with tiny images so the whole
// file stays fast.
#include <sys/wait.h>
#include <unistd.h>

#include <cctype>
#include <cmath>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <map>
#include <sstream>
#include <string>
#include <vector>

#include <gtest/gtest.h>

#include "atmo/image.h"

namespace {

namespace fs = std::filesystem;

struct RunResult {
  int exit_code = -1;
  std::string out;
  std::string err;
};

std::string ReadFile(const fs::path& path) {
  std::ifstream file(path, std::ios::binary);
  std::stringstream buffer;
  buffer << file.rdbuf();
  return buffer.str();
}

void WriteFile(const fs::path& path, const std::string& text) {
  std::ofstream file(path, std::ios::binary);
  file << text;
}

std::vector<std::string> Lines(const std::string& text) {
  std::vector<std::string> lines;
  std::stringstream stream(text);
  for (std::string line; std::getline(stream, line);) lines.push_back(line);
  return lines;
}

std::vector<std::string> Split(const std::string& line, char separator) {
  std::vector<std::string> fields;
  std::stringstream stream(line);
  for (std::string field; std::getline(stream, field, separator);) fields.push_back(field);
  return fields;
}

constexpr const char* kOutputHeader =
    "altitude_m,sun_zenith_deg,view_zenith_deg,azimuth_deg,wavelength_nm,radiance,transmittance,stderr";
constexpr const char* kGridHeader = "altitude_m,sun_zenith_deg,view_zenith_deg,azimuth_deg";

class CliTest : public ::testing::Test {
 protected:
  void SetUp() override {
    const auto* info = ::testing::UnitTest::GetInstance()->current_test_info();
    std::string name = std::string(info->test_suite_name()) + "_" + info->name();
    for (char& c : name) {
      if (!std::isalnum(static_cast<unsigned char>(c))) c = '_';
    }
    dir_ = fs::temp_directory_path() / ("atmo_cli_test_" + name + "_" + std::to_string(::getpid()));
    fs::remove_all(dir_);
    fs::create_directories(dir_);
  }
  void TearDown() override {
    std::error_code ignored;
    fs::remove_all(dir_, ignored);
  }

  // Runs `atmo <args>` (a shell-quoted string) in the test's folder.
  RunResult Run(const std::string& args) const {
    const std::string command =
        "cd '" + dir_.string() + "' && '" ATMO_CLI_PATH "' " + args + " >stdout.txt 2>stderr.txt";
    const int status = std::system(command.c_str());
    RunResult result;
    result.exit_code = WIFEXITED(status) ? WEXITSTATUS(status) : -1;
    result.out = ReadFile(dir_ / "stdout.txt");
    result.err = ReadFile(dir_ / "stderr.txt");
    return result;
  }

  fs::path dir_;
};

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
  for (const char* subcommand : {"render", "sample", "presets", "bench"}) {
    const RunResult r = Run(std::string(subcommand) + " --help");
    EXPECT_EQ(r.exit_code, 0) << subcommand;
    EXPECT_NE(r.out.find("--model"), std::string::npos) << subcommand;
  }
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
  const RunResult from_preset = Run("sample --preset earth" + query);
  const RunResult from_config = Run("sample --config earth.json" + query);
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
  const RunResult r = Run("sample --altitude 0 --sun-zenith 30 --view-zenith 120 --azimuth 0");
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
  const RunResult r = Run("sample --grid grid.csv --out out.csv");
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
    const RunResult r = Run(std::string("render --width 64 --height 32 --camera ") + camera + " --exr " +
                            exr + " --png " + png);
    ASSERT_EQ(r.exit_code, 0) << camera << ": " << r.err;
    EXPECT_EQ(Lines(r.out).size(), 1u) << r.out;
    EXPECT_GT(fs::file_size(dir_ / exr), 0u);
    const std::string png_bytes = ReadFile(dir_ / png);
    ASSERT_GE(png_bytes.size(), 8u);
    EXPECT_EQ(png_bytes.substr(0, 8), std::string("\x89PNG\r\n\x1a\n", 8)) << camera;
  }
}

TEST_F(CliTest, RenderedExrCarriesItsSettings) {
  const RunResult r =
      Run("render --width 16 --height 8 --camera equirect --sun-elevation 20 --seed 7 "
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
  const std::vector<std::string> outputs = {"out.csv", "sky.exr", "sky.png"};
  for (const std::string& output : outputs) WriteFile(dir_ / output, "previous " + output);

  const RunResult r = Run(GetParam().args);
  EXPECT_NE(r.exit_code, 0);
  EXPECT_EQ(r.err.rfind("atmo: error:", 0), 0u) << r.err;
  EXPECT_EQ(Lines(r.err).size(), 1u) << r.err;
  EXPECT_NE(r.err.find(GetParam().message_part), std::string::npos) << r.err;
  for (const std::string& output : outputs) {
    EXPECT_EQ(ReadFile(dir_ / output), "previous " + output) << output;
  }
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
    {"GlBackend", "render --backend gl" ATMO_TINY_RENDER, "the gl backend is not available in this build"},
    {"ViewZenithOutOfRange",
     "sample --altitude 0 --sun-zenith 30 --view-zenith 190 --azimuth 0 --out out.csv", "--view-zenith"},
    {"GridWithSingleConfiguration", "sample --grid three_numbers.csv --altitude 0 --out out.csv", "--grid"},
    {"MissingSingleConfigurationValue", "sample --altitude 0 --sun-zenith 30 --view-zenith 60 --out out.csv",
     "--azimuth"},
    {"MalformedModelOption", "sample --option novalue" ATMO_SAMPLE_ONE, "novalue"},
    {"ThreadsOutOfRange", "render --threads 0" ATMO_TINY_RENDER, "--threads"},
};

INSTANTIATE_TEST_SUITE_P(Cli, CliFailureTest, ::testing::ValuesIn(kFailureCases),
                         [](const ::testing::TestParamInfo<FailureCase>& info) { return info.param.name; });

TEST_F(CliTest, CsvRowErrorNamesTheLine) {
  WriteFile(dir_ / "grid.csv", std::string(kGridHeader) + "\n0,30,60,90\n0,30,60\n");
  const RunResult r = Run("sample --grid grid.csv");
  EXPECT_NE(r.exit_code, 0);
  EXPECT_EQ(r.err, "atmo: error: grid.csv:3: expected 4 comma-separated numbers\n");
  EXPECT_EQ(r.out, "");
}

}  // namespace
