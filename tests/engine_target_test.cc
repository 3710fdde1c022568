// `atmo render --target`: equirects that the real programs read with the sun where it is
// (docs/environment.md). three.js's own EXRLoader and equirect lookup run under node
// (tests/three_equirect.mjs); Blender renders the map with Cycles (tests/blender_target.py): the
// sun at the centre of a camera aimed at it, and a white plane lit with atmo's illuminance.
#include <cmath>
#include <cstdio>
#include <numbers>
#include <string>

#include <gtest/gtest.h>
#include <nlohmann/json.hpp>

#include "atmo/engine_target.h"
#include "atmo/error.h"
#include "atmo/image.h"
#include "cli_fixture.h"

namespace atmo::testing {
namespace {

struct Sun {
  double azimuth_deg;
  double elevation_deg;
};

class EngineTarget : public CliFixture {
 protected:
  // Runs `tests/SCRIPT ARGS X Y Z` under node with three (ATMO_NODE_MODULES), X Y Z the sun's
  // direction in three's world (+X east, +Y up, -Z north); its stdout, its stderr into `err`.
  std::string Node(const std::string& script, const std::string& args, const Sun& sun, int& status,
                   std::string& err) const {
    const double a = sun.azimuth_deg * std::numbers::pi / 180.0, e = sun.elevation_deg * std::numbers::pi / 180.0;
    char direction[128];
    std::snprintf(direction, sizeof direction, "%.17g %.17g %.17g", std::sin(a) * std::cos(e), std::sin(e),
                  -std::cos(a) * std::cos(e));
    return Shell("NODE_PATH='" ATMO_NODE_MODULES "' '" ATMO_NODE "' '" ATMO_SOURCE_DIR "/tests/" + script + "' " + args +
                     " " + direction,
                 status, &err);
  }
  // Runs a shell command in the test's folder; its stdout (stderr into `err`).
  std::string Shell(const std::string& command, int& status, std::string* err = nullptr) const {
    const std::string full = "cd '" + dir_.string() + "' && " + command + " >shell_out.txt 2>shell_err.txt";
    status = std::system(full.c_str());
    if (err != nullptr) *err = ReadFile(dir_ / "shell_err.txt");
    return ReadFile(dir_ / "shell_out.txt") + (err == nullptr ? ReadFile(dir_ / "shell_err.txt") : "");
  }
};

constexpr Sun kSuns[] = {{135.0, 30.0}, {250.0, 8.0}};

std::string SunFlags(const Sun& sun) {
  char text[96];
  std::snprintf(text, sizeof text, "--sun-azimuth %g --sun-elevation %g", sun.azimuth_deg, sun.elevation_deg);
  return text;
}

TEST_F(EngineTarget, ThreeJsReadsTheSunWhereItIs) {
  if (std::string(ATMO_NODE).empty()) GTEST_SKIP() << "node is not installed (scripts/install_deps.sh installs it)";
  ASSERT_TRUE(fs::exists(fs::path(ATMO_NODE_MODULES) / "three" / "package.json"))
      << "three is not in " << ATMO_NODE_MODULES << " (configure installs it with npm)";
  for (const Sun& sun : kSuns) {
    ASSERT_EQ(Run("render --model hillaire --preset earth --target three --width 1024 --height 512 --no-png -o three " + SunFlags(sun)).exit_code, 0);
    int status = 0;
    std::string err;
    const std::string out = Node("three_equirect.mjs", "three.exr", sun, status, err);
    ASSERT_EQ(status, 0) << out << err;
    // three's EXRLoader reads string, int and float attributes and skips atmo's doubles, one
    // console warning each (docs/environment.md); nothing else may go wrong.
    for (const std::string& line : Lines(err)) {
      EXPECT_NE(line.find("Skipped unknown header attribute type 'double'"), std::string::npos) << line;
    }
    const nlohmann::json j = nlohmann::json::parse(out);
    // EXRLoader hands the rows bottom-up with flipY false: v from row 0 is three's v.
    EXPECT_FALSE(j["loaderFlipY"].get<bool>());
    const double width = j["width"], height = j["height"];
    const double du = (j["sunU"].get<double>() - j["expectedU"].get<double>()) * width;
    const double dv = (j["sunV"].get<double>() - j["expectedV"].get<double>()) * height;
    std::printf("[ figures ] three.js: sun at azimuth %g, elevation %g is %.2f px, %.2f px from where equirectUv "
                "looks for it\n",
                sun.azimuth_deg, sun.elevation_deg, du, dv);
    EXPECT_LE(std::abs(du), 1.0) << out;
    EXPECT_LE(std::abs(dv), 1.0) << out;
  }
}

TEST_F(EngineTarget, ThreeJsCubeTextureReadsTheSunWhereItIs) {
  // --camera cubemap --target three --hdr-faces: six RGBE faces that three's HDRLoader reads and
  // its CubeTexture samples (the x flip and OpenGL's face rule, tests/three_cube.mjs) with the sun
  // in its texel.
  if (std::string(ATMO_NODE).empty()) GTEST_SKIP() << "node is not installed (scripts/install_deps.sh installs it)";
  ASSERT_TRUE(fs::exists(fs::path(ATMO_NODE_MODULES) / "three" / "package.json"));
  for (const Sun& sun : {Sun{120.0, 30.0}, Sun{250.0, 8.0}, Sun{10.0, 55.0}}) {
    ASSERT_EQ(Run("render --model hillaire --preset earth --camera cubemap --face-size 64 --target three --hdr-faces cube --png '' " + SunFlags(sun))
                  .exit_code,
              0);
    int status = 0;
    std::string err;
    const std::string out = Node("three_cube.mjs", "cube", sun, status, err);
    ASSERT_EQ(status, 0) << out << err;
    EXPECT_EQ(err, "");
    const nlohmann::json j = nlohmann::json::parse(out);
    EXPECT_FALSE(j["flipY"].get<bool>());
    EXPECT_EQ(j["sunFace"].get<int>(), j["expectedFace"].get<int>()) << out;
    const double dc = j["sunColumn"].get<double>() - j["expectedColumn"].get<double>();
    const double dr = j["sunRow"].get<double>() - j["expectedRow"].get<double>();
    std::printf("[ figures ] three.js CubeTexture: sun at azimuth %g, elevation %g on face %d, %.2f and %.2f texels "
                "from where three samples it\n",
                sun.azimuth_deg, sun.elevation_deg, j["sunFace"].get<int>(), dc, dr);
    EXPECT_LE(std::abs(dc), 1.0) << out;
    EXPECT_LE(std::abs(dr), 1.0) << out;
  }
}

TEST_F(EngineTarget, BlenderSeesTheSunWhereItIsAndLightsAPlaneWithAtmosIlluminance) {
  if (std::string(ATMO_BLENDER).empty()) {
    GTEST_SKIP() << "blender is not installed (scripts/install_deps.sh installs Debian's blender)";
  }
  for (const Sun& sun : kSuns) {
    ASSERT_EQ(Run("render --model hillaire --preset earth --target blender --width 1024 --height 512 --no-png -o blender " + SunFlags(sun)).exit_code,
              0);
    const RunResult lux = Run("illuminance --model hillaire --preset earth --sun-elevation " + std::to_string(sun.elevation_deg));
    ASSERT_EQ(lux.exit_code, 0) << lux.err;
    const std::vector<std::string> header = Split(Lines(lux.out)[0]), row = Split(Lines(lux.out)[1]);
    double expected_lux = 0.0;
    for (std::size_t i = 0; i < header.size(); ++i) {
      if (header[i] == "global_horizontal_lux") expected_lux = std::stod(row[i]);
    }
    ASSERT_GT(expected_lux, 0.0) << lux.out;
    char arguments[128];
    std::snprintf(arguments, sizeof arguments, "%g %g 256", sun.azimuth_deg, sun.elevation_deg);
    int status = 0;
    const std::string out = Shell("'" ATMO_BLENDER "' -b --factory-startup -P '" ATMO_SOURCE_DIR
                                  "/tests/blender_target.py' -- blender.exr render " + std::string(arguments),
                                  status);
    ASSERT_EQ(status, 0) << out;

    // 1. The sun's centroid in a 65-pixel, 10-degree view aimed at it: the image's centre.
    const Image view = ReadExr(dir_ / "render_sun.exr");
    double brightest = 0.0;
    for (int y = 0; y < view.height; ++y) {
      for (int x = 0; x < view.width; ++x) {
        brightest = std::max(brightest, Luminance(view.at(x, y, 0), view.at(x, y, 1), view.at(x, y, 2)));
      }
    }
    double sum = 0.0, sx = 0.0, sy = 0.0;
    for (int y = 0; y < view.height; ++y) {
      for (int x = 0; x < view.width; ++x) {
        const double l = Luminance(view.at(x, y, 0), view.at(x, y, 1), view.at(x, y, 2));
        if (l > 0.5 * brightest) {
          sum += l;
          sx += l * (x + 0.5);
          sy += l * (y + 0.5);
        }
      }
    }
    const double dx = sx / sum - 0.5 * view.width, dy = sy / sum - 0.5 * view.height;
    // 2. The plane: E = pi * the mean luminance of its pixels (albedo 1).
    const Image plane = ReadExr(dir_ / "render_plane.exr");
    double mean = 0.0;
    for (int y = 0; y < plane.height; ++y) {
      for (int x = 0; x < plane.width; ++x) mean += Luminance(plane.at(x, y, 0), plane.at(x, y, 1), plane.at(x, y, 2));
    }
    const double blender_lux = std::numbers::pi * mean / (plane.width * plane.height);
    std::printf("[ figures ] Blender: sun at azimuth %g, elevation %g is %.2f px, %.2f px from the centre of a view "
                "aimed at it (0.154 deg a px); the plane's illuminance %.1f lux against atmo illuminance's %.1f "
                "(%+.2f %%)\n",
                sun.azimuth_deg, sun.elevation_deg, dx, dy, blender_lux, expected_lux,
                100.0 * (blender_lux / expected_lux - 1.0));
    EXPECT_LE(std::abs(dx), 1.0);
    EXPECT_LE(std::abs(dy), 1.0);
    EXPECT_NEAR(blender_lux, expected_lux, 0.05 * expected_lux);
  }
}

// Each program's equirect lookup, as its source has it (the files engine_target.cc names), for a
// direction given by compass azimuth and elevation in the world frame atmo states for it: (u, v)
// with u from the image's left and v from its top row, both in [0, 1).
struct Uv {
  double u;
  double v;
};
Uv ProgramLookup(const std::string& program, double azimuth_deg, double elevation_deg) {
  constexpr double pi = std::numbers::pi;
  const double a = azimuth_deg * pi / 180.0, e = elevation_deg * pi / 180.0;
  const double east = std::sin(a) * std::cos(e), north = std::cos(a) * std::cos(e), up = std::sin(e);
  const auto wrap = [](double u) { return u - std::floor(u); };
  if (program == "three") {  // (x, y, z) = (east, up, -north); v = asin(y) / pi + 1/2 from the bottom
    const double x = east, y = up, z = -north;
    return {wrap(std::atan2(z, x) / (2 * pi) + 0.5), 1.0 - (std::asin(y) / pi + 0.5)};
  }
  if (program == "blender") {  // (x, y, z) = (east, north, up); v = 1 - acos(z) / pi from the bottom
    const double x = east, y = north, z = up;
    return {wrap(0.5 - std::atan2(y, x) / (2 * pi)), std::acos(z) / pi};
  }
  if (program == "unreal") {  // (x, y, z) = (east, south, up)
    const double x = east, y = -north, z = up;
    return {wrap(0.5 + std::atan2(x, -y) / (2 * pi)), std::acos(z) / pi};
  }
  if (program == "unity") {  // (x, y, z) = (east, up, north), left-handed; v = 1 - acos(y) / pi from the bottom
    const double x = east, y = up, z = north;
    return {wrap(0.5 - std::atan2(z, x) / (2 * pi)), std::acos(y) / pi};
  }
  if (program == "godot" || program == "mitsuba") {  // (x, y, z) = (east, up, -north)
    const double x = east, y = up, z = -north;
    return {wrap(std::atan2(x, -z) / (2 * pi)), std::acos(y) / pi};
  }
  if (program == "pbrt") {  // (x, y, z) = (east, south, up), left-handed; phi in [0, 2 pi)
    const double x = east, y = -north, z = up;
    return {wrap(std::atan2(y, x) / (2 * pi)), std::acos(z) / pi};
  }
  ADD_FAILURE() << "no lookup for " << program;
  return {0.0, 0.0};
}

TEST_F(EngineTarget, EveryTargetPutsTheSunWhereItsProgramsLookupFindsIt) {
  // The programs that cannot run here (Unreal, Unity, Godot, pbrt, Mitsuba) are checked against
  // their lookups as their sources write them; three.js and Blender also run above.
  for (const atmo::EngineTarget& target : EngineTargets()) {
    for (const Sun& sun : {Sun{135.0, 30.0}, Sun{250.0, 8.0}, Sun{10.0, 55.0}}) {
      ASSERT_EQ(Run("render --model hillaire --preset earth --target " + std::string(target.name) + " --width 512 --height 256 --no-png -o t " +
                    SunFlags(sun))
                    .exit_code,
                0);
      const Image image = ReadExr(dir_ / "t.exr");
      double brightest = 0.0;
      for (float v : image.pixels) brightest = std::max(brightest, static_cast<double>(v));
      double sum = 0.0, su = 0.0, sv = 0.0;
      for (int y = 0; y < image.height; ++y) {
        for (int x = 0; x < image.width; ++x) {
          const double l = Luminance(image.at(x, y, 0), image.at(x, y, 1), image.at(x, y, 2));
          if (l > 0.25 * brightest) {
            sum += l;
            su += l * (x + 0.5) / image.width;
            sv += l * (y + 0.5) / image.height;
          }
        }
      }
      const Uv expected = ProgramLookup(target.name, sun.azimuth_deg, sun.elevation_deg);
      double du = su / sum - expected.u;
      du -= std::round(du);  // across the seam
      EXPECT_LE(std::abs(du) * image.width, 1.0) << target.name << " azimuth " << sun.azimuth_deg;
      EXPECT_LE(std::abs(sv / sum - expected.v) * image.height, 1.0) << target.name << " azimuth " << sun.azimuth_deg;
    }
  }
}

TEST_F(EngineTarget, TheMapIsFixedInTheWorldAndRecorded) {
  // The sun moves, the map does not: the centre column stays east for three.
  ASSERT_EQ(Run("render --model hillaire --preset earth --target three --width 64 --height 32 --no-png -o a --sun-azimuth 100").exit_code, 0);
  ASSERT_EQ(Run("render --model hillaire --preset earth --target three --width 64 --height 32 --no-png -o b --sun-azimuth 260").exit_code, 0);
  for (const char* name : {"a.exr", "b.exr"}) {
    ImageMetadata metadata;
    ReadExr(dir_ / name, &metadata);
    std::string yaw, target;
    for (const auto& [key, value] : metadata) {
      if (key == "atmo:cameraYawDeg") yaw = value;
      if (key == "atmo:target") target = value;
    }
    EXPECT_EQ(yaw, "90") << name;
    EXPECT_EQ(target, "three") << name;
  }
  // --target alone is an equirect of 2048 x 1024.
  ASSERT_EQ(Run("render --model hillaire --preset earth --target blender --no-png -o c --sun-elevation 20").exit_code, 0);
  const Image c = ReadExr(dir_ / "c.exr");
  EXPECT_EQ(c.width, 2048);
  EXPECT_EQ(c.height, 1024);
}

TEST_F(EngineTarget, BadTargetsAreRefusedBeforeAnyWork) {
  ExpectFailureKeepingOutputs("render --model hillaire --preset earth --target maya -o sky",
                              "unknown --target 'maya' (known: three, blender, unreal, unity, godot, pbrt, mitsuba)",
                              {"sky.exr", "sky.png"});
  ExpectFailureKeepingOutputs("render --model hillaire --preset earth --target three --camera fisheye -o sky", "--target three writes an equirect",
                              {"sky.exr", "sky.png"});
  ExpectFailureKeepingOutputs("render --model hillaire --preset earth --target blender --camera cubemap --hdr-faces c -o sky",
                              "cube maps are written for three only", {"sky.exr", "c_px.hdr"});
  ExpectFailureKeepingOutputs("render --model hillaire --preset earth --target three --camera cubemap -o sky", "writes --hdr-faces NAME",
                              {"sky.exr"});
  ExpectFailureKeepingOutputs("render --model hillaire --preset earth --hdr-faces c -o sky", "need --camera cubemap", {"sky.exr", "c_nz.hdr"});
  EXPECT_THROW(FindEngineTarget(""), Error);
}

}  // namespace
}  // namespace atmo::testing
