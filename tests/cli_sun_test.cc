// End-to-end tests of the sun from a date and place on the `atmo` command line (--date,
// --latitude, --longitude, --refraction for render, sample and bench) and of the render
// time-lapse (--until, --step, --mp4): the sun each command uses is the library's
// (ComputeSunPosition), and every misuse fails in one line before any output is written.
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <filesystem>
#include <map>
#include <numbers>
#include <string>
#include <vector>

#include <gtest/gtest.h>

#include "atmo/image.h"
#include "atmo/sun_position.h"
#include "cli_fixture.h"

namespace {

namespace fs = std::filesystem;
using atmo::testing::Lines;
using atmo::testing::ReadFile;
using atmo::testing::RunResult;
using atmo::testing::Split;
using atmo::testing::WriteFile;

// The metadata holds angles with 10 significant digits (5e-8 degrees), and a time-lapse frame's
// instant, start + k step, can differ from the same instant parsed anew by the resolution of a
// Julian day in a double (40 microseconds, 2e-7 degrees of the sun's daily motion).
constexpr double kMetadataToleranceDeg = 1e-6;

class CliSunTest : public atmo::testing::CliFixture {
 protected:
  std::map<std::string, std::string> ExrMetadata(const std::string& name) const {
    atmo::ImageMetadata metadata;
    atmo::ReadExr(dir_ / name, &metadata);
    return {metadata.begin(), metadata.end()};
  }
};

// Interlaken, Switzerland, at 12:00 CEST on the June solstice of 2026.
#define ATMO_PLACE " --latitude 46.5 --longitude 7.9"
constexpr const char* kNoon = "2026-06-21T12:00+02:00";
#define ATMO_TINY " --width 8 --height 4"

TEST_F(CliSunTest, RenderTakesTheSunOfTheDateAndRecordsIt) {
  const RunResult r = Run(std::string("render --model hillaire --preset earth --date ") + kNoon + ATMO_PLACE ATMO_TINY " --exr sky.exr --png ''");
  ASSERT_EQ(r.exit_code, 0) << r.err;
  auto values = ExrMetadata("sky.exr");
  const atmo::SunPosition sun = atmo::ComputeSunPosition(atmo::ParseIsoDateTime(kNoon), 46.5, 7.9);
  EXPECT_NEAR(std::stod(values["atmo:sunElevationDeg"]), sun.elevation_deg, kMetadataToleranceDeg);
  EXPECT_NEAR(std::stod(values["atmo:sunAzimuthDeg"]), sun.azimuth_deg, kMetadataToleranceDeg);
  // 10:00 UT, an hour and a half before the sun's transit here (about 11:30 UT): in the south-east,
  // below the transit's 90 - 46.5 + 23.44 = 66.94 degrees.
  EXPECT_GT(sun.elevation_deg, 45.0);
  EXPECT_LT(sun.elevation_deg, 66.94);
  EXPECT_GT(sun.azimuth_deg, 90.0);
  EXPECT_LT(sun.azimuth_deg, 180.0);
  EXPECT_EQ(values["atmo:date"], "2026-06-21T10:00:00Z");
  EXPECT_EQ(values["atmo:latitudeDeg"], "46.5");
  EXPECT_EQ(values["atmo:longitudeDeg"], "7.9");
  EXPECT_EQ(values["atmo:refraction"], "off");
  // The perspective view looks towards the sun unless --yaw says otherwise.
  EXPECT_NEAR(std::stod(values["atmo:cameraYawDeg"]), sun.azimuth_deg, kMetadataToleranceDeg);
}

TEST_F(CliSunTest, RefractionLiftsTheRenderedSun) {
  // At 05:40 CEST the sun is a few degrees up, where refraction is several arcminutes.
  const std::string date = "2026-06-21T05:40+02:00";
  const RunResult r = Run("render --model hillaire --preset earth --date " + date + ATMO_PLACE ATMO_TINY " --refraction --exr sky.exr --png ''");
  ASSERT_EQ(r.exit_code, 0) << r.err;
  auto values = ExrMetadata("sky.exr");
  atmo::SunPositionOptions refracted;
  refracted.refraction = true;
  const atmo::SunPosition sun = atmo::ComputeSunPosition(atmo::ParseIsoDateTime(date), 46.5, 7.9, refracted);
  EXPECT_GT(sun.elevation_deg - sun.geometric_elevation_deg, 5.0 / 60.0);
  EXPECT_NEAR(std::stod(values["atmo:sunElevationDeg"]), sun.elevation_deg, kMetadataToleranceDeg);
  EXPECT_EQ(values["atmo:refraction"], "on");
}

TEST_F(CliSunTest, SampleTakesTheSunZenithOfTheDate) {
  const RunResult dated =
      Run(std::string("sample --model hillaire --preset earth --date ") + kNoon + ATMO_PLACE " --altitude 0 --view-zenith 60 --azimuth 90");
  ASSERT_EQ(dated.exit_code, 0) << dated.err;
  const std::vector<std::string> lines = Lines(dated.out);
  ASSERT_EQ(lines.size(), 4u) << dated.out;
  const std::vector<std::string> row = Split(lines[1]);
  ASSERT_EQ(row.size(), 8u);
  const atmo::SunPosition sun = atmo::ComputeSunPosition(atmo::ParseIsoDateTime(kNoon), 46.5, 7.9);
  EXPECT_NEAR(std::stod(row[1]), 90.0 - sun.elevation_deg, 1e-7);
  // The same query with that zenith given as --sun-zenith gives the same radiance.
  const RunResult plain = Run("sample --model hillaire --preset earth --sun-zenith " + row[1] + " --altitude 0 --view-zenith 60 --azimuth 90");
  ASSERT_EQ(plain.exit_code, 0) << plain.err;
  EXPECT_EQ(plain.out, dated.out);
}

TEST_F(CliSunTest, BenchTakesTheSunOfTheDate) {
  const RunResult r = Run(std::string("bench --repeat 1 --date ") + kNoon + ATMO_PLACE ATMO_TINY);
  ASSERT_EQ(r.exit_code, 0) << r.err;
  const atmo::SunPosition sun = atmo::ComputeSunPosition(atmo::ParseIsoDateTime(kNoon), 46.5, 7.9);
  char line[128];
  std::snprintf(line, sizeof line, "sun: elevation %.4f deg, azimuth %.4f deg", sun.elevation_deg, sun.azimuth_deg);
  EXPECT_NE(r.out.find(line), std::string::npos) << r.out;
}

TEST_F(CliSunTest, TimeLapseWritesNumberedFramesAsTheMorningSunRises) {
  // 06:00 to 07:00 CEST every 30 minutes: 3 frames, the sun climbing in the north-east to east.
  const RunResult r = Run("render --model hillaire --preset earth --date 2026-06-21T06:00+02:00 --until 2026-06-21T07:00+02:00 --step 30min" ATMO_PLACE
                          ATMO_TINY " --exr tl.exr --png tl.png");
  ASSERT_EQ(r.exit_code, 0) << r.err;
  EXPECT_EQ(r.err, "");  // no progress bar: stderr is not a terminal
  EXPECT_EQ(Lines(r.out).size(), 1u) << r.out;
  EXPECT_NE(r.out.find("wrote 3 frames"), std::string::npos) << r.out;
  const char* dates[] = {"2026-06-21T04:00:00Z", "2026-06-21T04:30:00Z", "2026-06-21T05:00:00Z"};
  double previous_elevation = -90.0, previous_azimuth = 0.0;
  for (int frame = 0; frame < 3; ++frame) {
    const std::string stem = "tl_000" + std::to_string(frame);
    ASSERT_TRUE(fs::exists(dir_ / (stem + ".png"))) << stem;
    auto values = ExrMetadata(stem + ".exr");
    EXPECT_EQ(values["atmo:date"], dates[frame]);
    const atmo::SunPosition sun = atmo::ComputeSunPosition(atmo::ParseIsoDateTime(dates[frame]), 46.5, 7.9);
    const double elevation = std::stod(values["atmo:sunElevationDeg"]);
    const double azimuth = std::stod(values["atmo:sunAzimuthDeg"]);
    EXPECT_NEAR(elevation, sun.elevation_deg, kMetadataToleranceDeg) << stem;
    EXPECT_NEAR(azimuth, sun.azimuth_deg, kMetadataToleranceDeg) << stem;
    EXPECT_GT(elevation, previous_elevation) << stem;
    EXPECT_GT(azimuth, previous_azimuth) << stem;
    EXPECT_GT(azimuth, 45.0);
    EXPECT_LT(azimuth, 90.0);
    previous_elevation = elevation;
    previous_azimuth = azimuth;
  }
  EXPECT_FALSE(fs::exists(dir_ / "tl_0003.exr"));
  EXPECT_FALSE(fs::exists(dir_ / "tl.exr"));
}

TEST_F(CliSunTest, TimeLapseNamesFramesBeforeTheLastExtension) {
  // --until off the step: the frames stop at the last step before it (06:00, 06:30).
  const RunResult r = Run("render --model hillaire --preset earth --date 2026-06-21T06:00+02:00 --until 2026-06-21T06:59+02:00 --step 30min" ATMO_PLACE
                          ATMO_TINY " --exr sky.v1.exr --png frames.png");
  ASSERT_EQ(r.exit_code, 0) << r.err;
  for (const char* name : {"sky.v1_0000.exr", "sky.v1_0001.exr", "frames_0000.png", "frames_0001.png"}) {
    EXPECT_TRUE(fs::exists(dir_ / name)) << name;
  }
  EXPECT_FALSE(fs::exists(dir_ / "sky.v1_0002.exr"));
}

bool HaveFfmpeg() { return std::system("command -v ffmpeg >/dev/null 2>&1") == 0; }

TEST_F(CliSunTest, TimeLapseAssemblesAnMp4WithFfmpeg) {
  if (!HaveFfmpeg()) GTEST_SKIP() << "no ffmpeg on PATH";
  // Odd sides: ffmpeg pads them to even for yuv420p.
  const RunResult r = Run("render --model hillaire --preset earth --date 2026-06-21T06:00+02:00 --until 2026-06-21T07:00+02:00 --step 30min" ATMO_PLACE
                          " --width 9 --height 5 --exr '' --png f.png --mp4 lapse.mp4");
  ASSERT_EQ(r.exit_code, 0) << r.err;
  const std::string mp4 = ReadFile(dir_ / "lapse.mp4");
  ASSERT_GT(mp4.size(), 12u);
  EXPECT_EQ(mp4.substr(4, 4), "ftyp");  // an ISO base media file
}

TEST_F(CliSunTest, Mp4WithoutFfmpegFailsBeforeAnyFrame) {
  const char* path = std::getenv("PATH");
  const std::string saved = path != nullptr ? path : "";
  fs::create_directories(dir_ / "empty");
  ::setenv("PATH", (dir_ / "empty").c_str(), 1);
  const RunResult r = Run("render --model hillaire --preset earth --date 2026-06-21T06:00+02:00 --until 2026-06-21T07:00+02:00 --step 30min" ATMO_PLACE
                          ATMO_TINY " --png f.png --mp4 lapse.mp4");
  ::setenv("PATH", saved.c_str(), 1);
  EXPECT_EQ(r.exit_code, 1);
  EXPECT_EQ(r.err, "atmo: error: --mp4 needs ffmpeg on PATH, and there is none\n");
  EXPECT_FALSE(fs::exists(dir_ / "f_0000.png"));
  EXPECT_FALSE(fs::exists(dir_ / "lapse.mp4"));
}

// A command that must fail: non-zero exit, one `atmo: error:` line on stderr naming the problem,
// and no output written or changed.
struct SunFailureCase {
  const char* name;
  const char* args;
  const char* message_part;
};

class CliSunFailureTest : public CliSunTest, public ::testing::WithParamInterface<SunFailureCase> {};

TEST_P(CliSunFailureTest, FailsWithOneLineAndWritesNothing) {
  WriteFile(dir_ / "grid.csv", "altitude_m,sun_zenith_deg,view_zenith_deg,azimuth_deg\n0,30,60,90\n");
  ExpectFailureKeepingOutputs(GetParam().args, GetParam().message_part, {"out.csv", "sky.exr", "sky.png"});
  EXPECT_FALSE(fs::exists(dir_ / "sky_0000.exr"));
  EXPECT_FALSE(fs::exists(dir_ / "sky_0000.png"));
}

#define ATMO_QUERY " --altitude 0 --view-zenith 60 --azimuth 90 --out out.csv"
#define ATMO_LAPSE " --date 2026-06-21T06:00Z --until 2026-06-21T07:00Z"

const SunFailureCase kSunFailureCases[] = {
    {"DateWithoutZone", "render --model hillaire --preset earth --date 2026-06-21T12:00" ATMO_PLACE ATMO_TINY, "'2026-06-21T12:00' has no zone"},
    {"MalformedDate", "render --model hillaire --preset earth --date 21.06.2026" ATMO_PLACE ATMO_TINY, "'21.06.2026' is not ISO 8601"},
    {"MonthOutOfRange", "render --model hillaire --preset earth --date 2026-13-01T12:00Z" ATMO_PLACE ATMO_TINY, "month out of range"},
    {"DayOutOfRange", "sample --model hillaire --preset earth --date 2026-02-29T12:00Z" ATMO_PLACE ATMO_QUERY, "day out of range"},
    {"LatitudeWithoutDate", "render --model hillaire --preset earth --latitude 46.5" ATMO_TINY, "--latitude requires --date"},
    {"LongitudeWithoutDate", "sample --model hillaire --preset earth --longitude 7.9 --sun-zenith 30" ATMO_QUERY, "--longitude requires --date"},
    {"RefractionWithoutDate", "bench --refraction --repeat 1" ATMO_TINY, "--refraction requires --date"},
    {"DateWithoutPlace", "render --model hillaire --preset earth --date 2026-06-21T12:00Z" ATMO_TINY, "--date requires --latitude"},
    {"DateAndSunElevation", "render --model hillaire --preset earth --date 2026-06-21T12:00Z --sun-elevation 10" ATMO_PLACE ATMO_TINY, "--date"},
    {"DateAndSunAzimuth", "render --model hillaire --preset earth --date 2026-06-21T12:00Z --sun-azimuth 10" ATMO_PLACE ATMO_TINY, "--date"},
    {"DateAndSunZenith", "sample --model hillaire --preset earth --date 2026-06-21T12:00Z --sun-zenith 30" ATMO_PLACE ATMO_QUERY, "--date"},
    {"DateAndGrid", "sample --model hillaire --preset earth --date 2026-06-21T12:00Z --grid grid.csv --out out.csv" ATMO_PLACE, "--date"},
    {"LatitudeOutOfRange", "render --model hillaire --preset earth --date 2026-06-21T12:00Z --latitude 95 --longitude 0" ATMO_TINY, "--latitude"},
    {"BadStep", "render" ATMO_LAPSE " --step 10m" ATMO_PLACE ATMO_TINY, "duration '10m'"},
    {"UntilBeforeDate", "render --model hillaire --preset earth --date 2026-06-21T07:00Z --until 2026-06-21T06:00Z --step 10min" ATMO_PLACE ATMO_TINY,
     "is before --date"},
    {"TooManyFrames", "render --model hillaire --preset earth --date 2026-01-01T00:00Z --until 2027-01-01T00:00Z --step 1min" ATMO_PLACE ATMO_TINY,
     "more than 100000"},
    {"UntilWithoutStep", "render" ATMO_LAPSE ATMO_PLACE ATMO_TINY, "--until requires --step"},
    {"StepWithoutUntil", "render --model hillaire --preset earth --date 2026-06-21T06:00Z --step 10min" ATMO_PLACE ATMO_TINY, "--step requires --until"},
    {"UntilWithoutDate", "render --model hillaire --preset earth --until 2026-06-21T07:00Z --step 10min" ATMO_TINY, "--until requires --date"},
    {"Mp4WithoutTimeLapse", "render --model hillaire --preset earth --date 2026-06-21T06:00Z --mp4 x.mp4" ATMO_PLACE ATMO_TINY, "--mp4 requires --until"},
    {"Mp4WithoutPng", "render" ATMO_LAPSE " --step 30min --png '' --mp4 x.mp4" ATMO_PLACE ATMO_TINY, "give --png"},
};

INSTANTIATE_TEST_SUITE_P(CliSun, CliSunFailureTest, ::testing::ValuesIn(kSunFailureCases),
                         [](const ::testing::TestParamInfo<SunFailureCase>& info) { return info.param.name; });

}  // namespace

namespace {

// The spectral issue's closing check: a spectral sky for 46.5 N, 7.9 E at the June solstice's noon
// (2026-06-21T12:00+02:00: 10:00 UTC, 1.5 h before the local solar noon at 7.9 E, the sun ~61 degrees
// up, below the day's 66.9 degree maximum) in cd/m^2 has a zenith luminance in the range
// published for clear skies: Karayel et al. 1984's L_z = (1.376 T - 1.81) tan(alpha) + 0.38 kcd/m^2
// for Linke turbidity T = 2 (very clean) to 3.5.
TEST_F(CliSunTest, SolsticeNoonZenithLuminanceIsInThePublishedClearSkyRange) {
  const RunResult r = Run("render --model hillaire --preset earth-spectral --camera fisheye --width 33 --height 33 "
                          "--date 2026-06-21T12:00+02:00 --latitude 46.5 --longitude 7.9 --exr noon.exr --png ''");
  ASSERT_EQ(r.exit_code, 0) << r.err;
  atmo::ImageMetadata metadata;
  const atmo::Image image = atmo::ReadExr(dir_ / "noon.exr", &metadata);
  std::map<std::string, std::string> values(metadata.begin(), metadata.end());
  EXPECT_EQ(values["atmo:unit"], "luminance");
  const double elevation = std::stod(values["atmo:sunElevationDeg"]);
  EXPECT_GT(elevation, 55.0);
  EXPECT_LT(elevation, 66.9);
  // The centre pixel of the fisheye looks at the zenith; Y of linear sRGB is the luminance.
  const double luminance = 0.2126 * image.at(16, 16, 0) + 0.7152 * image.at(16, 16, 1) + 0.0722 * image.at(16, 16, 2);
  const auto karayel = [&](double t) {
    return ((1.376 * t - 1.81) * std::tan(elevation * std::numbers::pi / 180.0) + 0.38) * 1e3;
  };
  EXPECT_GT(luminance, karayel(2.0));
  EXPECT_LT(luminance, karayel(3.5));
}

}  // namespace
