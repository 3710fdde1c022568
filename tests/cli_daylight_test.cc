// The daylighting commands end to end (docs/daylighting.md): `atmo irradiance`, `atmo calibrate`
// and `atmo annual`, their outputs as files and their refusals (one line, nothing written).
#include <sys/wait.h>

#include <sstream>
#include <string>
#include <vector>

#include <gtest/gtest.h>

#include "cli_fixture.h"

namespace {

namespace fs = std::filesystem;
using atmo::testing::Lines;
using atmo::testing::ReadFile;
using atmo::testing::Split;
using atmo::testing::WriteFile;

class DaylightCli : public atmo::testing::CliFixture {
 protected:
  // The TMY3 file's header and `count` rows from `first_row`, as day.epw in the test's folder.
  void WriteEpw(std::size_t first_row, std::size_t count, const std::string& name = "day.epw") const {
    std::istringstream in(ReadFile(fs::path(ATMO_SOURCE_DIR) / "tests/data/greensboro_tmy3.epw"));
    std::string out, line;
    for (std::size_t i = 0; std::getline(in, line); ++i) {
      if (i < 8 || (i >= 8 + first_row && i < 8 + first_row + count)) out += line + "\n";
    }
    WriteFile(dir_ / name, out);
  }
};

// atmo calibrate's config, given to atmo irradiance, gives back the measurements (within 1 %, the
// irradiance command's finer sky grid against the calibration's patches).
TEST_F(DaylightCli, CalibrateWritesAConfigThatReproducesTheMeasurements) {
  const auto r = Run("calibrate --model hillaire --sun-elevation 40 --direct-normal-lux 70000 "
                     "--diffuse-horizontal-lux 16000 --out sky.json");
  ASSERT_EQ(r.exit_code, 0) << r.err;
  EXPECT_NE(r.out.find("aod_550"), std::string::npos);
  const auto e = Run("irradiance --model hillaire --config sky.json --sun-elevation 40 --plane 0:180 --plane sun");
  ASSERT_EQ(e.exit_code, 0) << e.err;
  const std::vector<std::string> lines = Lines(e.out);
  ASSERT_EQ(lines.size(), 3u);
  const std::vector<std::string> horizontal = Split(lines[1]), sun = Split(lines[2]);
  EXPECT_NEAR(std::stod(horizontal[5]), 16000.0, 160.0);                       // sky_diffuse_lux
  EXPECT_NEAR(std::stod(sun[3]) + std::stod(sun[4]), 70000.0, 700.0);        // direct + circumsolar
}

TEST_F(DaylightCli, RefusalsChangeNothing) {
  WriteEpw(4320, 24);
  // Clouds: no clear sky gives this much diffuse light.
  ExpectFailureKeepingOutputs("calibrate --model hillaire --sun-elevation 40 --direct-normal-lux 20000 "
                              "--diffuse-horizontal-lux 60000 --out sky.json",
                              "no clear sky reproduces these measurements (too-much-diffuse)", {"sky.json"});
  ExpectFailureKeepingOutputs("calibrate --sun-elevation 40 --direct-normal-lux 2e4 --diffuse-horizontal-lux 1e4 "
                              "--aod 0.2 --out sky.json",
                              "give only --aerosol TYPE", {"sky.json"});
  ExpectFailureKeepingOutputs("irradiance --model hillaire --plane 200:0 --out e.csv", "--plane 200:0", {"e.csv"});
  ExpectFailureKeepingOutputs("irradiance --model hillaire --plane up --out e.csv", "TILT:AZIMUTH", {"e.csv"});
  ExpectFailureKeepingOutputs("irradiance --model hillaire --out e.png", "--out", {"e.png"});
  // A weather file with a broken row: the file and line named, no run folder made.
  std::string text = ReadFile(dir_ / "day.epw");
  const std::size_t row = text.find("1989,6,30,5,");
  ASSERT_NE(row, std::string::npos);
  text.replace(row, 12, "1989,6,30,x,");
  WriteFile(dir_ / "broken.epw", text);
  auto r = Run("annual --model hillaire --epw broken.epw --out-dir year");
  EXPECT_EQ(r.exit_code, 1);
  EXPECT_NE(r.err.find("broken.epw:13: the hour is not a number"), std::string::npos) << r.err;
  EXPECT_FALSE(fs::exists(dir_ / "year"));
  r = Run("annual --model hillaire --epw day.epw --out-dir year --latitude 40");
  EXPECT_NE(r.err.find("its latitude 36.10 disagrees with --latitude 40.00"), std::string::npos) << r.err;
  EXPECT_FALSE(fs::exists(dir_ / "year"));
  r = Run("annual --model hillaire --epw day.epw --out-dir year --shard 2/2");
  EXPECT_NE(r.err.find("--shard must be I/N"), std::string::npos) << r.err;
  r = Run("annual --model hillaire --epw day.epw --out-dir year --hours 30:40");
  EXPECT_NE(r.err.find("selects no hour"), std::string::npos) << r.err;
  EXPECT_EQ(Lines(r.err).size(), 1u);
}

// A day in two shards, the second finishing the run: the outputs appear only then; the CSVs hold
// every hour and every daylight hour's planes.
TEST_F(DaylightCli, AnnualRunsInShardsAndMerges) {
  WriteEpw(4320, 24);
  auto r = Run("annual --model hillaire --epw day.epw --out-dir year --plane 30:180 --hours 0:12");
  ASSERT_EQ(r.exit_code, 0) << r.err;
  EXPECT_NE(r.out.find("12 of the file's 24 hours done"), std::string::npos) << r.out;
  EXPECT_FALSE(fs::exists(dir_ / "year" / "sky.mtx"));
  r = Run("annual --model hillaire --epw day.epw --out-dir year --plane 30:180");
  ASSERT_EQ(r.exit_code, 0) << r.err;
  EXPECT_NE(r.out.find("12 hours computed (12 of the selection already done)"), std::string::npos) << r.out;
  const std::vector<std::string> hours = Lines(ReadFile(dir_ / "year" / "hours.csv"));
  EXPECT_EQ(hours.size(), 25u);
  int daylight = 0;
  for (std::size_t i = 1; i < hours.size(); ++i) {
    const std::string status = Split(hours[i])[5];
    if (status != "night") ++daylight;
  }
  const std::vector<std::string> planes = Lines(ReadFile(dir_ / "year" / "irradiance.csv"));
  EXPECT_EQ(planes.size(), 1u + 3u * daylight);  // horizontal, sun, 30:180
  // Other settings into the same folder: refused.
  r = Run("annual --model hillaire --epw day.epw --out-dir year --plane 45:180");
  EXPECT_NE(r.err.find("holds a run of other settings"), std::string::npos) << r.err;
}

}  // namespace
