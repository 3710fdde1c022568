// `atmo compare` end to end: each test runs the program in a fresh temporary folder on a small
// grid (24 configurations), so the file stays fast; one test runs the standard grid once.
#include <sys/wait.h>
#include <unistd.h>

#include <cctype>
#include <cmath>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <map>
#include <numbers>
#include <set>
#include <sstream>
#include <string>
#include <vector>

#include <gtest/gtest.h>
#include <nlohmann/json.hpp>

#include "cli_fixture.h"

namespace {

namespace fs = std::filesystem;
using atmo::testing::Lines;
using atmo::testing::ReadFile;
using atmo::testing::RunResult;
using atmo::testing::Split;

constexpr const char* kCsvHeader =
    "altitude_m,sun_zenith_deg,view_zenith_deg,azimuth_deg,wavelength_nm,radiance,stderr,reference_radiance,"
    "reference_stderr,relative_error,error_in_stderr,included";

// 2 altitudes x 2 sun zeniths x 3 view zeniths x 2 azimuths = 24 configurations. View zenith 120
// from the ground meets the ground at once: reference 0, excluded from the statistics.
std::string SmallGrid() {
  std::string csv = "altitude_m,sun_zenith_deg,view_zenith_deg,azimuth_deg\n";
  for (const char* altitude : {"0", "10000"}) {
    for (const char* sun : {"0", "95"}) {
      for (const char* view : {"0", "85", "120"}) {
        for (const char* azimuth : {"0", "180"}) {
          csv += std::string(altitude) + "," + sun + "," + view + "," + azimuth + "\n";
        }
      }
    }
  }
  return csv;
}
constexpr std::size_t kSmallGridConfigurations = 24;
constexpr std::size_t kChannels = 3;  // preset earth





// One CSV row of `atmo compare --csv`.
struct CompareRow {
  double altitude_m, sun_zenith_deg, view_zenith_deg, azimuth_deg, wavelength_nm;
  double radiance, reference, relative_error;
  bool included;
};

std::vector<CompareRow> ReadCompareCsv(const fs::path& path) {
  const std::vector<std::string> lines = Lines(ReadFile(path));
  EXPECT_FALSE(lines.empty());
  if (lines.empty()) return {};
  EXPECT_EQ(lines[0], kCsvHeader);
  std::vector<CompareRow> rows;
  for (std::size_t i = 1; i < lines.size(); ++i) {
    const std::vector<std::string> f = Split(lines[i]);
    EXPECT_EQ(f.size(), 12u) << lines[i];
    if (f.size() != 12) continue;
    rows.push_back({std::stod(f[0]), std::stod(f[1]), std::stod(f[2]), std::stod(f[3]), std::stod(f[4]),
                    std::stod(f[5]), std::stod(f[7]), std::stod(f[9]), f[11] == "1"});
  }
  return rows;
}

class CompareTest : public atmo::testing::CliFixture {
 protected:
  void SetUp() override {
    CliFixture::SetUp();
    std::ofstream(dir_ / "grid.csv") << SmallGrid();
  }

  // Expects a failure reported as exactly one `atmo: error:` line.
  void ExpectOneErrorLine(const RunResult& r, const std::string& mentions) const {
    EXPECT_NE(r.exit_code, 0);
    const std::vector<std::string> lines = Lines(r.err);
    ASSERT_EQ(lines.size(), 1u) << r.err;
    EXPECT_EQ(lines[0].rfind("atmo: error: ", 0), 0u) << lines[0];
    EXPECT_NE(lines[0].find(mentions), std::string::npos) << lines[0];
  }
};

TEST_F(CompareTest, HasHelp) {
  const RunResult r = Run("compare --help");
  EXPECT_EQ(r.exit_code, 0);
  for (const char* flag : {"--against", "--against-option", "--against-samples", "--grid", "--csv", "--json", "--image",
                           "--image-range"}) {
    EXPECT_NE(r.out.find(flag), std::string::npos) << flag;
  }
}

TEST_F(CompareTest, ModelAgainstItselfHasZeroErrors) {
  const RunResult r = Run("compare --model hillaire --against hillaire --grid grid.csv --csv out.csv");
  ASSERT_EQ(r.exit_code, 0) << r.err;
  const std::vector<CompareRow> rows = ReadCompareCsv(dir_ / "out.csv");
  ASSERT_EQ(rows.size(), kSmallGridConfigurations * kChannels);
  std::size_t included = 0;
  for (const CompareRow& row : rows) {
    EXPECT_EQ(row.radiance, row.reference);  // the same deterministic model: bit for bit
    EXPECT_EQ(row.relative_error, 0.0);
    included += row.included;
  }
  EXPECT_GT(included, 0u);
  EXPECT_NE(r.out.find("overall"), std::string::npos);
}

// A reference sampled once (`atmo sample`) and read back gives the rows a reference model gives
// (its radiances and standard errors, to the file's 10 digits), so several models can be measured
// against one expensive Monte Carlo run.
TEST_F(CompareTest, SamplesFileStandsInForTheReferenceModel) {
  const RunResult sampled = Run("sample --preset earth --model reference --samples 256 --seed 3 --grid grid.csv --out ref.csv");
  ASSERT_EQ(sampled.exit_code, 0) << sampled.err;
  const RunResult direct = Run(
      "compare --model hillaire --against reference --against-option samples=256 --seed 3 --grid grid.csv --csv a.csv");
  ASSERT_EQ(direct.exit_code, 0) << direct.err;
  const RunResult from_file = Run("compare --model hillaire --against-samples ref.csv --csv b.csv --json b.json");
  ASSERT_EQ(from_file.exit_code, 0) << from_file.err;
  EXPECT_NE(from_file.out.find("against the samples of ref.csv"), std::string::npos) << from_file.out;
  const std::vector<CompareRow> a = ReadCompareCsv(dir_ / "a.csv");
  const std::vector<CompareRow> b = ReadCompareCsv(dir_ / "b.csv");
  ASSERT_EQ(a.size(), kSmallGridConfigurations * kChannels);
  ASSERT_EQ(b.size(), a.size());
  std::size_t included = 0;
  for (std::size_t i = 0; i < a.size(); ++i) {
    EXPECT_EQ(b[i].view_zenith_deg, a[i].view_zenith_deg);
    EXPECT_EQ(b[i].radiance, a[i].radiance);
    EXPECT_NEAR(b[i].reference, a[i].reference, 1e-9 * a[i].reference) << i;
    EXPECT_NEAR(b[i].relative_error, a[i].relative_error, 1e-7) << i;
    EXPECT_EQ(b[i].included, a[i].included) << i;
    included += b[i].included;
  }
  EXPECT_GT(included, kSmallGridConfigurations);
  const nlohmann::json j = nlohmann::json::parse(ReadFile(dir_ / "b.json"));
  EXPECT_EQ(j["reference"]["samples"], "ref.csv");
  EXPECT_EQ(j["configurations"].get<std::size_t>(), kSmallGridConfigurations);
}

// A samples file of other media, of other channels, cut short, or combined with a grid or a
// reference model is refused in one line; the output never replaces the samples file.
TEST_F(CompareTest, SamplesFileMismatchesAreRefused) {
  ASSERT_EQ(Run("sample --preset earth --model hillaire --grid grid.csv --out ref.csv").exit_code, 0);
  const std::string before = ReadFile(dir_ / "ref.csv");
  ExpectOneErrorLine(Run("compare --model hillaire --preset atmosphere-plus --against-samples ref.csv"),
                     "wavelength_nm 680 where the atmosphere's channel 1 is 650 nm");
  // The same channels, ten times the red Rayleigh coefficient: caught by the transmittance.
  std::string thick = Run("presets --dump earth").out;
  const std::size_t red = thick.find("5.802e-06");
  ASSERT_NE(red, std::string::npos);
  thick.replace(red, 9, "5.802e-05");
  std::ofstream(dir_ / "thick.json") << thick;
  ExpectOneErrorLine(Run("compare --model hillaire --config thick.json --against-samples ref.csv"),
                     "the samples were taken with other parameters");
  ExpectOneErrorLine(Run("compare --model hillaire --against-samples ref.csv --grid grid.csv"),
                     "--grid excludes --against-samples");
  ExpectOneErrorLine(Run("compare --model hillaire --against-samples ref.csv --against reference"), "excludes");
  ExpectOneErrorLine(Run("compare --model hillaire --against-samples ref.csv --csv ref.csv"),
                     "is the --against-samples input");
  ExpectOneErrorLine(Run("compare --model hillaire --against-samples ref.csv --image e.png"),
                     "--image needs a reference model");
  std::vector<std::string> lines = Lines(before);
  ASSERT_GT(lines.size(), 3u);
  std::string cut;
  for (std::size_t i = 0; i + 1 < lines.size(); ++i) cut += lines[i] + "\n";  // the last channel row gone
  std::ofstream(dir_ / "cut.csv") << cut;
  ExpectOneErrorLine(Run("compare --model hillaire --against-samples cut.csv"), "the last configuration has 2 of its 3");
  EXPECT_EQ(ReadFile(dir_ / "ref.csv"), before);
}

TEST_F(CompareTest, TwoDirectionMultipleScatteringIsDarkerAtNoon) {
  const RunResult r = Run(
      "compare --model hillaire --option multiple_scattering_directions=2 --against hillaire --grid grid.csv "
      "--csv out.csv");
  ASSERT_EQ(r.exit_code, 0) << r.err;
  const std::vector<CompareRow> rows = ReadCompareCsv(dir_ / "out.csv");
  ASSERT_EQ(rows.size(), kSmallGridConfigurations * kChannels);
  int checked = 0;
  for (const CompareRow& row : rows) {
    if (row.altitude_m != 0.0 || row.sun_zenith_deg != 0.0 || row.view_zenith_deg != 85.0) continue;
    // The seed's up/down pair misses most of the second-order light: darker everywhere at noon.
    EXPECT_LT(row.relative_error, 0.0) << row.wavelength_nm;
    EXPECT_TRUE(row.included);
    if (row.wavelength_nm == 440.0) {
      // About -19 % in blue near the horizon (docs/accuracy.md); the band allows for table changes.
      EXPECT_GT(row.relative_error, -0.25);
      EXPECT_LT(row.relative_error, -0.13);
    }
    ++checked;
  }
  EXPECT_EQ(checked, 2 * 3);  // two azimuths x three channels
}

TEST_F(CompareTest, ZeroReferenceRowsAreReportedButExcluded) {
  const RunResult r = Run("compare --model hillaire --against hillaire --grid grid.csv --csv out.csv --json out.json");
  ASSERT_EQ(r.exit_code, 0) << r.err;
  std::size_t excluded = 0;
  for (const CompareRow& row : ReadCompareCsv(dir_ / "out.csv")) {
    if (row.altitude_m == 0.0 && row.view_zenith_deg == 120.0) {
      EXPECT_EQ(row.reference, 0.0);  // looking into the ground from the ground
      EXPECT_FALSE(row.included);
    }
    excluded += !row.included;
  }
  EXPECT_GE(excluded, 2u * 2u * kChannels);  // 2 suns x 2 azimuths x channels, at least
  const nlohmann::json j = nlohmann::json::parse(ReadFile(dir_ / "out.json"));
  EXPECT_EQ(j["overall"]["excluded"].get<std::size_t>(), excluded);
  EXPECT_EQ(j["overall"]["rows"].get<std::size_t>() + excluded, kSmallGridConfigurations * kChannels);
}

TEST_F(CompareTest, JsonHoldsMetadataAndBands) {
  const RunResult r = Run(
      "compare --model hillaire --option multiple_scattering_directions=2 --against hillaire "
      "--against-option sky_view=off --seed 7 --grid grid.csv --json out.json");
  ASSERT_EQ(r.exit_code, 0) << r.err;
  const nlohmann::json j = nlohmann::json::parse(ReadFile(dir_ / "out.json"));
  EXPECT_EQ(j["atmo_version"], ATMO_VERSION);
  EXPECT_EQ(j["model"]["name"], "hillaire");
  EXPECT_EQ(j["model"]["options"]["multiple_scattering_directions"], "2");
  EXPECT_EQ(j["model"]["options"]["seed"], "7");  // --seed goes to both models
  EXPECT_EQ(j["reference"]["options"]["sky_view"], "off");
  EXPECT_EQ(j["reference"]["options"]["seed"], "7");
  EXPECT_EQ(j["preset"], "earth");
  EXPECT_EQ(j["parameter_hash"].get<std::string>().size(), 16u);
  EXPECT_EQ(j["configurations"], kSmallGridConfigurations);
  EXPECT_EQ(j["rows"], kSmallGridConfigurations * kChannels);

  std::set<std::string> bands;
  for (const auto& band : j["sun_zenith_bands"]) {
    bands.insert(band["band"].get<std::string>());
    EXPECT_TRUE(band.contains("definition"));
    EXPECT_TRUE(band.contains("median_abs"));
    EXPECT_TRUE(band.contains("p95_abs"));
    EXPECT_TRUE(band.contains("max_abs"));
  }
  EXPECT_EQ(bands, (std::set<std::string>{"sun_up", "twilight"}));  // sun zeniths 0 and 95
  ASSERT_EQ(j["altitudes"].size(), 2u);
  EXPECT_EQ(j["altitudes"][1]["altitude_m"], 10000.0);
  ASSERT_EQ(j["channels"].size(), kChannels);
  EXPECT_GT(j["overall"]["max_abs"].get<double>(), 0.0);
  EXPECT_LT(j["overall"]["mean"].get<double>(), 0.0);  // the 2-direction variant is darker
}

TEST_F(CompareTest, StandardGridHasEveryConfiguration) {
  const RunResult r = Run("compare --model hillaire --against hillaire --csv out.csv");
  ASSERT_EQ(r.exit_code, 0) << r.err;
  // 5 altitudes x 7 sun zeniths x 27 view zeniths x 5 azimuths.
  EXPECT_NE(r.out.find("4725 configurations x 3 channels = 14175 rows"), std::string::npos) << r.out;
  EXPECT_EQ(Lines(ReadFile(dir_ / "out.csv")).size(), 1u + 4725u * kChannels);
  for (const char* label : {"sun up (<90)", "twilight (90-100)", "altitude 100000 m"}) {
    EXPECT_NE(r.out.find(label), std::string::npos) << label;
  }
}

// The twilight grid: the standard altitudes, views and azimuths, the sun from 90 to 108 degrees
// every 2; the rows past 100 degrees go to the night band.
TEST_F(CompareTest, TwilightGridMovesTheSunTo108Degrees) {
  const RunResult r = Run("compare --model hillaire --against hillaire --grid twilight --csv out.csv");
  ASSERT_EQ(r.exit_code, 0) << r.err;
  EXPECT_NE(r.out.find("6750 configurations x 3 channels = 20250 rows"), std::string::npos) << r.out;
  std::map<double, std::size_t> per_sun;
  for (const CompareRow& row : ReadCompareCsv(dir_ / "out.csv")) ++per_sun[row.sun_zenith_deg];
  ASSERT_EQ(per_sun.size(), 10u);
  double expected = 90.0;
  for (const auto& [sun, count] : per_sun) {
    EXPECT_DOUBLE_EQ(sun, expected);
    EXPECT_EQ(count, 5u * 27u * 5u * kChannels);
    expected += 2.0;
  }
  EXPECT_NE(r.out.find("night (>100)"), std::string::npos) << r.out;
}

// The space grid: for every observer (100-1000 km), views set by tangent altitude across the limb
// (r sin(theta) - r_ground in the list, below the atmosphere's top), then into the ground past the
// planet's horizon, and the nadir. Views across the limb see sky (R > 0 with the sun up); every
// ground view is darker than the limb's brightest.
TEST_F(CompareTest, SpaceGridSamplesTheLimbByTangentAltitude) {
  const RunResult r = Run("compare --model hillaire --against hillaire --grid space --csv out.csv");
  ASSERT_EQ(r.exit_code, 0) << r.err;
  EXPECT_NE(r.out.find("2975 configurations"), std::string::npos) << r.out;
  constexpr double kGround = 6360e3;  // earth
  constexpr double kTop = 6460e3;
  const std::set<double> tangents = {80e3, 60e3, 40e3, 30e3, 20e3, 15e3, 10e3, 5e3, 2e3, 1e3, 500.0};
  std::map<double, std::set<double>> views;
  std::size_t limb_rows = 0;
  for (const CompareRow& row : ReadCompareCsv(dir_ / "out.csv")) {
    EXPECT_GE(row.altitude_m, 100e3);
    EXPECT_LE(row.altitude_m, 1000e3);
    views[row.altitude_m].insert(row.view_zenith_deg);
    const double r_observer = kGround + row.altitude_m;
    const double sine = std::sin(row.view_zenith_deg * std::numbers::pi / 180.0);
    const double tangent = r_observer * sine - kGround;
    if (tangent > 0.0) {  // across the limb: the tangent altitude is one of the list, inside the air
      EXPECT_LT(kGround + tangent, kTop);
      const auto nearest = tangents.lower_bound(tangent - 1.0);
      ASSERT_NE(nearest, tangents.end()) << tangent;
      EXPECT_NEAR(*nearest, tangent, 0.05) << row.view_zenith_deg;  // the CSV prints 10 digits
      if (row.sun_zenith_deg < 60.0) {
        EXPECT_GT(row.reference, 0.0) << row.altitude_m << " " << row.view_zenith_deg;
        ++limb_rows;
      }
    }
  }
  EXPECT_GT(limb_rows, 0u);
  ASSERT_EQ(views.size(), 5u);
  for (const auto& [altitude, set] : views) EXPECT_EQ(set.size(), 17u) << altitude;  // 11 + 5 + nadir
}

TEST_F(CompareTest, MarkdownTableHasTheSummaryRows) {
  const RunResult r = Run("compare --model hillaire --against hillaire --grid grid.csv --markdown table.md");
  ASSERT_EQ(r.exit_code, 0) << r.err;
  const std::vector<std::string> lines = Lines(ReadFile(dir_ / "table.md"));
  ASSERT_GE(lines.size(), 4u);
  EXPECT_EQ(lines[0], "| group | rows | excluded | median abs(e) | p95 abs(e) | max abs(e) | rel_mae | mean e |");
  EXPECT_EQ(lines[1], "|---|---:|---:|---:|---:|---:|---:|---:|");
  EXPECT_EQ(lines[2].rfind("| overall | ", 0), 0u) << lines[2];
  // A model against itself: every error 0.
  EXPECT_NE(lines[2].find("| 0% | 0% | 0% | 0% | 0% |"), std::string::npos) << lines[2];
  EXPECT_NE(ReadFile(dir_ / "table.md").find("Largest |e|"), std::string::npos);
  ExpectOneErrorLine(Run("compare --model hillaire --against hillaire --grid grid.csv --markdown t.txt"), ".md");
}

TEST_F(CompareTest, ImageWritesAPng) {
  const RunResult r = Run(
      "compare --model hillaire --against hillaire --option sky_view=off --grid grid.csv --image err.png "
      "--image-size 32 --altitude 1000 --sun-zenith 80 --image-range 2");
  ASSERT_EQ(r.exit_code, 0) << r.err;
  const std::string png = ReadFile(dir_ / "err.png");
  ASSERT_GT(png.size(), 24u);
  EXPECT_EQ(png.substr(0, 8), std::string("\x89PNG\r\n\x1a\n", 8));
  const auto be32 = [&](std::size_t at) {
    return (static_cast<unsigned char>(png[at]) << 24) | (static_cast<unsigned char>(png[at + 1]) << 16) |
           (static_cast<unsigned char>(png[at + 2]) << 8) | static_cast<unsigned char>(png[at + 3]);
  };
  EXPECT_EQ(be32(16), 24u + 3u * (32u + 24u));  // one fisheye per channel, with margins
  EXPECT_GT(be32(20), 32u);                     // the discs plus title and colour bar
}

TEST_F(CompareTest, BadInputsFailWithOneErrorLine) {
  ExpectOneErrorLine(Run("compare --model nosuch --against hillaire --grid grid.csv"), "nosuch");
  ExpectOneErrorLine(Run("compare --model hillaire --against nosuch --grid grid.csv"), "nosuch");
  ExpectOneErrorLine(Run("compare --model hillaire --against hillaire --grid missing.csv"), "missing.csv");
  std::ofstream(dir_ / "bad.csv") << "altitude_m,sun_zenith_deg,view_zenith_deg,azimuth_deg\n0,30,x,0\n";
  ExpectOneErrorLine(Run("compare --model hillaire --against hillaire --grid bad.csv"), "bad.csv:2");
  ExpectOneErrorLine(Run("compare --model hillaire --against hillaire --grid grid.csv --csv /nonexistent/x.csv"),
                     "/nonexistent/x.csv");
  ExpectOneErrorLine(Run("compare --model hillaire --against hillaire --grid grid.csv --against-option foo=1"),
                     "foo");
  ExpectOneErrorLine(Run("compare --model hillaire --against hillaire --grid grid.csv --seed 1 --option seed=2"),
                     "seed");
  EXPECT_FALSE(fs::exists("/nonexistent/x.csv"));
}

}  // namespace
