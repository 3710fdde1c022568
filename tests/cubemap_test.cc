// Cube maps (atmo/cubemap.h): the face convention against the perspective cameras and OpenEXR's
// own envmap functions, texel solid angles, the sun disc's energy over the six faces, the EXR cube
// read back, the equirect's latlong convention, and the KTX2 file read back by ktx-parse (npm,
// under node), whose writer must also reproduce it byte for byte.
#include "atmo/cubemap.h"

#include <cmath>
#include <cstdio>
#include <filesystem>
#include <numbers>
#include <string>

#include <ImfEnvmap.h>
#include <ImfInputFile.h>
#include <ImfStandardAttributes.h>
#include <gtest/gtest.h>
#include <nlohmann/json.hpp>

#include "atmo/image.h"
#include "atmo/model.h"
#include "atmo/parameters.h"
#include "atmo/render.h"
#include "cli_fixture.h"
#include "cpu/camera.h"
#include "shared/shared.h"
#include "sun_disc_integral.h"

namespace atmo {
namespace {

constexpr double kPi = std::numbers::pi;
namespace fs = std::filesystem;

// The direction (cube frame) of pixel (i, j) of a face's camera image (its view from inside).
glm::dvec3 CameraDirection(CubeFace face, int n, int i, int j) {
  const shared::CameraParameters camera = ToSharedCamera(CubeFaceCamera(face, n));
  shared::vec3 d;
  shared::GetCameraRayDirection(camera, shared::vec2(i + 0.5, j + 0.5), d);
  return CubeFromEnu(glm::dvec3(d));
}

// The cube-map texel that camera pixel (i, j) shows (CubeFaceCamera's flip).
void CameraToTexel(CubeFace face, int n, int i, int j, int& ti, int& tj) {
  const bool y_face = face == CubeFace::kPositiveY || face == CubeFace::kNegativeY;
  ti = y_face ? i : n - 1 - i;
  tj = y_face ? n - 1 - j : j;
}

TEST(CubeFaces, TableDirectionsAreTheFaceCamerasFlipped) {
  const int n = 8;
  for (int f = 0; f < kCubeFaceCount; ++f) {
    const CubeFace face = static_cast<CubeFace>(f);
    for (int j = 0; j < n; ++j) {
      for (int i = 0; i < n; ++i) {
        int ti = 0;
        int tj = 0;
        CameraToTexel(face, n, i, j, ti, tj);
        const glm::dvec3 table = CubeFaceDirection(face, (ti + 0.5) / n, (tj + 0.5) / n);
        EXPECT_LT(glm::length(table - CameraDirection(face, n, i, j)), 1e-12) << f << " " << i << " " << j;
        CubeFace back;
        double s = 0.0;
        double t = 0.0;
        CubeFaceCoordinates(table, back, s, t);
        EXPECT_EQ(back, face);
        EXPECT_NEAR(s, (ti + 0.5) / n, 1e-12);
        EXPECT_NEAR(t, (tj + 0.5) / n, 1e-12);
      }
    }
  }
  // The axes: +X east, +Y up, +Z south, in ENU.
  EXPECT_LT(glm::length(EnuFromCube(CubeFaceDirection(CubeFace::kPositiveX, 0.5, 0.5)) - glm::dvec3(1, 0, 0)), 1e-15);
  EXPECT_LT(glm::length(EnuFromCube(CubeFaceDirection(CubeFace::kPositiveY, 0.5, 0.5)) - glm::dvec3(0, 0, 1)), 1e-15);
  EXPECT_LT(glm::length(EnuFromCube(CubeFaceDirection(CubeFace::kPositiveZ, 0.5, 0.5)) - glm::dvec3(0, -1, 0)), 1e-15);
  EXPECT_LT(glm::length(EnuFromCube(CubeFaceDirection(CubeFace::kNegativeZ, 0.5, 0.5)) - glm::dvec3(0, 1, 0)), 1e-15);
}

TEST(CubeFaces, TexelSolidAnglesSumTo4Pi) {
  for (const int n : {1, 2, 7, 64, 256}) {
    double sum = 0.0;
    for (int j = 0; j < n; ++j) {
      for (int i = 0; i < n; ++i) sum += CubeTexelSolidAngle(n, i, j);
    }
    EXPECT_NEAR(kCubeFaceCount * sum, 4.0 * kPi, 1e-12) << n;
    const std::vector<double> table = CubeFaceSolidAngles(n);
    for (int j = 0; j < n; ++j) {
      for (int i = 0; i < n; ++i) {
        EXPECT_NEAR(table[static_cast<std::size_t>(j) * n + i], CubeTexelSolidAngle(n, i, j), 1e-15) << n;
      }
    }
  }
}

TEST(CubeFaces, HalfFloatsRoundToNearestEven) {
  EXPECT_EQ(FloatToHalf(1.0f), 0x3c00);
  EXPECT_EQ(FloatToHalf(-2.0f), 0xc000);
  EXPECT_EQ(FloatToHalf(65504.0f), 0x7bff);
  EXPECT_EQ(FloatToHalf(1e9f), 0x7bff);  // clamped, not infinite
  EXPECT_EQ(FloatToHalf(5.9604645e-8f), 0x0001);  // the smallest subnormal
  EXPECT_EQ(FloatToHalf(1.0f + 1.0f / 2048.0f), 0x3c00);  // halfway, to even
  EXPECT_EQ(FloatToHalf(1.0f + 3.0f / 2048.0f), 0x3c02);
  for (const float v : {0.1f, 3.14159f, 1234.5f, 6.1e-5f, 1e-6f, 30000.0f}) {
    EXPECT_NEAR(HalfToFloat(FloatToHalf(v)), v, v * 4.9e-4 + 6e-8) << v;
  }
}

class CubemapSky : public ::testing::Test {
 protected:
  static void SetUpTestSuite() { model_ = CreateModel("hillaire", Preset("earth")).release(); }
  static void TearDownTestSuite() {
    delete model_;
    model_ = nullptr;
  }
  static inline Model* model_ = nullptr;
  static inline const std::vector<double> kOnes = {1.0, 1.0, 1.0};
};

using atmo::testing::DiscIrradiance;

// sum over the six faces of value x texel solid angle, channel c.
double CubeEnergy(const Cubemap& cube, int c) {
  double sum = 0.0;
  for (const Image& face : cube.faces) {
    for (int j = 0; j < cube.face_size; ++j) {
      for (int i = 0; i < cube.face_size; ++i) sum += face.at(i, j, c) * CubeTexelSolidAngle(cube.face_size, i, j);
    }
  }
  return sum;
}

// The disc over the six faces holds the transmitted irradiance within 1 %, wherever it falls: in
// a face, across the edge between +X and +Y (elevation 45, azimuth 90: cube (1, 1, 0)), on the
// corner of +X, +Y and +Z (cube (1, 1, 1): elevation 35.26, azimuth 135).
TEST_F(CubemapSky, SunDiscEnergyOverTheFacesIsTheTransmittedIrradiance) {
  const double corner_elevation = std::asin(1.0 / std::sqrt(3.0)) * 180.0 / kPi;
  const RadianceTerms disc_only_off{false, false};
  const RadianceTerms disc_on{true, false};
  for (const auto& [elevation, azimuth] : std::vector<std::pair<double, double>>{
           {20.0, 200.0}, {45.0, 90.0}, {corner_elevation, 135.0}, {3.0, 0.0}}) {
    const auto sky = model_->View(0.0, SunDirection(elevation, azimuth));
    const std::vector<double> expected = DiscIrradiance(*sky);
    for (const int n : {64, 256}) {
      const Cubemap with = RenderCubemap(*sky, n, disc_on, kOnes);
      const Cubemap without = RenderCubemap(*sky, n, disc_only_off, kOnes);
      double worst = 0.0;
      for (int c = 0; c < 3; ++c) {
        const double error = (CubeEnergy(with, c) - CubeEnergy(without, c)) / expected[c] - 1.0;
        if (std::abs(error) > std::abs(worst)) worst = error;
      }
      std::printf("cube %3d, sun at elevation %6.3f, azimuth %5.1f: disc energy error %+.4f %%\n", n, elevation,
                  azimuth, 100.0 * worst);
      EXPECT_LT(std::abs(worst), 0.01) << n << " " << elevation << " " << azimuth;
    }
  }
}

// The EXR cube: OpenEXR's envmap attribute is ENVMAP_CUBE, the data window N x 6N, OpenEXR's own
// CubeMap functions put each of atmo's texel directions on that very pixel, and the pixels are
// the model's radiance along those directions.
TEST_F(CubemapSky, ExrCubeIsOpenExrsLayoutAndTheModelAlongTheFaceDirections) {
  const int n = 24;
  const auto sky = model_->View(0.0, SunDirection(25.0, 160.0));
  const Cubemap cube = RenderCubemap(*sky, n, RadianceTerms{false, false}, kOnes);
  const fs::path path = fs::temp_directory_path() / ("atmo_cube_" + std::to_string(::getpid()) + ".exr");
  WriteExr(path, CubemapExrImage(cube));
  {
    Imf::InputFile file(path.c_str());
    ASSERT_TRUE(Imf::hasEnvmap(file.header()));
    EXPECT_EQ(Imf::envmap(file.header()), Imf::ENVMAP_CUBE);
  }
  const Image exr = ReadExr(path);
  fs::remove(path);
  EXPECT_EQ(exr.envmap, EnvMap::kCube);
  ASSERT_EQ(exr.width, n);
  ASSERT_EQ(exr.height, 6 * n);
  const Imath::Box2i window(Imath::V2i(0, 0), Imath::V2i(n - 1, 6 * n - 1));
  EXPECT_EQ(Imf::CubeMap::sizeOfFace(window), n);
  double worst = 0.0;
  std::vector<double> l(3);
  for (int f = 0; f < kCubeFaceCount; ++f) {
    const CubeFace face = static_cast<CubeFace>(f);
    for (int j = 0; j < n; ++j) {
      for (int i = 0; i < n; ++i) {
        // EXR pixel (i, f n + j) is camera pixel (i, j) of face f.
        const glm::dvec3 d = CameraDirection(face, n, i, j);
        Imf::CubeMapFace exr_face;
        Imath::V2f in_face;
        Imf::CubeMap::faceAndPixelPosition(Imath::V3f(d.x, d.y, d.z), window, exr_face, in_face);
        const Imath::V2f position = Imf::CubeMap::pixelPosition(exr_face, window, in_face);
        EXPECT_EQ(static_cast<int>(exr_face), f);
        EXPECT_EQ(std::lround(position.x), i) << f << " " << i << " " << j;
        EXPECT_EQ(std::lround(position.y), f * n + j) << f << " " << i << " " << j;
        sky->Radiance(EnuFromCube(d), l);
        for (int c = 0; c < 3; ++c) {
          worst = std::max(worst, std::abs(exr.at(i, f * n + j, c) / l[c] - 1.0));
        }
      }
    }
  }
  std::printf("EXR cube against SkyView::Radiance along the face directions: worst relative difference %.2e\n", worst);
  EXPECT_LT(worst, 1e-3);
}

// Equirect EXRs say ENVMAP_LATLONG; OpenEXR's latlong frame is atmo's with +Z the centre column's
// azimuth (yaw), +X 90 degrees to its left, +Y up, so at yaw 180 it is the cube frame. OpenEXR
// puts the first and last pixel centres on the edges (longitude +-pi, latitude +-pi/2), atmo
// centres pixels: the two agree within half a pixel.
TEST_F(CubemapSky, EquirectIsOpenExrsLatLongWithinHalfAPixel) {
  const int w = 64;
  const int h = 32;
  const Camera camera{CameraKind::kEquirect, w, h, 90.0, 180.0, 0.0};
  const auto sky = model_->View(0.0, SunDirection(25.0, 160.0));
  const Image image = RenderView(*sky, camera, RadianceTerms{false, false}, kOnes);
  EXPECT_EQ(image.envmap, EnvMap::kLatLong);
  const fs::path path = fs::temp_directory_path() / ("atmo_latlong_" + std::to_string(::getpid()) + ".exr");
  WriteExr(path, image);
  {
    Imf::InputFile file(path.c_str());
    ASSERT_TRUE(Imf::hasEnvmap(file.header()));
    EXPECT_EQ(Imf::envmap(file.header()), Imf::ENVMAP_LATLONG);
  }
  fs::remove(path);
  const shared::CameraParameters c = ToSharedCamera(camera);
  const Imath::Box2i window(Imath::V2i(0, 0), Imath::V2i(w - 1, h - 1));
  double worst_rad = 0.0;
  for (int y = 0; y < h; ++y) {
    for (int x = 0; x < w; ++x) {
      shared::vec3 d;
      shared::GetCameraRayDirection(c, shared::vec2(x + 0.5, y + 0.5), d);
      const glm::dvec3 ours = CubeFromEnu(glm::dvec3(d));
      const Imath::V3f theirs = Imf::LatLongMap::direction(window, Imath::V2f(x, y));
      const double angle = std::acos(std::clamp(glm::dot(ours, glm::normalize(glm::dvec3(theirs.x, theirs.y, theirs.z))), -1.0, 1.0));
      worst_rad = std::max(worst_rad, angle);
    }
  }
  // Half a pixel in longitude and latitude: (2 pi / w) / 2 and (pi / h) / 2, plus OpenEXR's
  // (w - 1) spacing.
  const double half_pixel = std::hypot(kPi / w, 0.5 * kPi / h) * 1.05;
  std::printf("equirect vs OpenEXR LatLongMap: worst angle %.4f rad (half a pixel: %.4f)\n", worst_rad, half_pixel);
  EXPECT_LT(worst_rad, half_pixel);
}

// Runs `command`, returning its stdout; exit status in `status`.
std::string Capture(const std::string& command, int& status) {
  std::string out;
  FILE* pipe = ::popen(command.c_str(), "r");
  if (pipe == nullptr) {
    status = -1;
    return out;
  }
  char buffer[4096];
  for (std::size_t got; (got = std::fread(buffer, 1, sizeof(buffer), pipe)) > 0;) out.append(buffer, got);
  status = ::pclose(pipe);
  return out;
}

// The KTX2 file read by ktx-parse (npm; tests/ktx2_inspect.mjs) under node: header, format, face
// and level counts, the data format descriptor, KTXorientation, texels equal to the render (to
// half precision, 2^-11 relative, for RGBA16F; exactly for RGBA32F) and ktx-parse's writer giving
// back the same bytes from what it read.
TEST_F(CubemapSky, Ktx2IsReadBackByKtxParse) {
  if (std::string(ATMO_NODE).empty()) {
    GTEST_SKIP() << "node is not installed (scripts/install_deps.sh installs nodejs and npm): the KTX2 file is "
                    "not read back by ktx-parse";
  }
  ASSERT_TRUE(fs::exists(fs::path(ATMO_NODE_MODULES) / "ktx-parse" / "package.json"))
      << "node is installed but ktx-parse is not in " << ATMO_NODE_MODULES
      << " (configure installs it with npm: re-run cmake with network access)";
  const int n = 32;
  const auto sky = model_->View(0.0, SunDirection(15.0, 120.0));
  Cubemap cube = RenderCubemap(*sky, n, RadianceTerms{}, kOnes);
  for (Image& face : cube.faces) face.colour_space = ColourSpace::kLinearSrgb;
  std::vector<Cubemap> chain = {cube};
  while (chain.back().face_size > 1) chain.push_back(DownsampleCubemap(chain.back()));
  for (const bool float32 : {false, true}) {
    const fs::path path =
        fs::temp_directory_path() / ("atmo_ktx2_" + std::to_string(::getpid()) + (float32 ? "_f32" : "_f16") + ".ktx2");
    WriteKtx2(path, chain, float32, "atmo test");
    const std::vector<std::array<int, 4>> probes = {{0, 0, 3, 5}, {0, 2, 16, 16}, {0, 5, 31, 0}, {1, 4, 7, 9}, {5, 1, 0, 0}};
    std::string command = "NODE_PATH='" ATMO_NODE_MODULES "' '" ATMO_NODE "' '" ATMO_SOURCE_DIR "/tests/ktx2_inspect.mjs' '" +
                          path.string() + "'";
    for (const auto& p : probes) {
      for (int k = 0; k < 4; ++k) {
        command += k == 0 ? ' ' : ',';
        command += std::to_string(p[k]);
      }
    }
    int status = 0;
    const std::string out = Capture(command + " 2>&1", status);
    fs::remove(path);
    ASSERT_EQ(status, 0) << out;
    const nlohmann::json j = nlohmann::json::parse(out);
    EXPECT_EQ(j["vkFormat"], float32 ? 109 : 97);
    EXPECT_EQ(j["typeSize"], float32 ? 4 : 2);
    EXPECT_EQ(j["pixelWidth"], n);
    EXPECT_EQ(j["pixelHeight"], n);
    EXPECT_EQ(j["pixelDepth"], 0);
    EXPECT_EQ(j["layerCount"], 0);
    EXPECT_EQ(j["faceCount"], 6);
    EXPECT_EQ(j["levelCount"], static_cast<int>(chain.size()));
    EXPECT_EQ(j["supercompressionScheme"], 0);
    ASSERT_EQ(j["levels"].size(), chain.size());
    for (std::size_t l = 0; l < chain.size(); ++l) {
      const int size = chain[l].face_size;
      EXPECT_EQ(j["levels"][l]["byteLength"], 6 * size * size * 4 * (float32 ? 4 : 2)) << l;
    }
    EXPECT_EQ(j["dfd"]["colorModel"], 1);        // KHR_DF_MODEL_RGBSDA
    EXPECT_EQ(j["dfd"]["colorPrimaries"], 1);    // BT709
    EXPECT_EQ(j["dfd"]["transferFunction"], 1);  // LINEAR
    EXPECT_EQ(j["dfd"]["bytesPlane0"], float32 ? 16 : 8);
    ASSERT_EQ(j["dfd"]["samples"].size(), 4u);
    EXPECT_EQ(j["dfd"]["samples"][3]["channelType"], 15 | 0x80 | 0x40);  // alpha, float, signed
    EXPECT_EQ(j["keyValue"]["KTXorientation"], "rd");
    EXPECT_EQ(j["keyValue"]["KTXwriter"], "atmo test");
    EXPECT_TRUE(j["rewrittenIdentical"].get<bool>()) << "ktx-parse writes these contents differently";
    for (const auto& t : j["texels"]) {
      const Image& face = chain[t["level"].get<int>()].faces[t["face"].get<int>()];
      for (int c = 0; c < 3; ++c) {
        const double ours = face.at(t["i"].get<int>(), t["j"].get<int>(), c);
        const double theirs = t["rgba"][c].get<double>();
        EXPECT_NEAR(theirs, ours, (float32 ? 0.0 : 4.9e-4) * std::abs(ours) + 1e-30) << t.dump();
      }
      EXPECT_EQ(t["rgba"][3].get<double>(), 1.0);
    }
  }
}

class CubemapCli : public testing::CliFixture {};

// `atmo render --camera cubemap` writes the EXR cube (envmap attribute, N x 6N), the KTX2 with
// its mip chain, the SH JSON, the irradiance cube and the specular chain.
TEST_F(CubemapCli, WritesEveryEnvironmentOutput) {
  const testing::RunResult r = Run(
      "render --preset earth --model hillaire --camera cubemap --face-size 32 --sun-elevation 20 --exr cube.exr --png cube.png "
      "--ktx2 sky.ktx2 --mips --sh sh.json --irradiance irradiance.exr --specular specular.ktx2 --specular-levels 4");
  ASSERT_EQ(r.exit_code, 0) << r.err;
  const Image exr = ReadExr(dir_ / "cube.exr");
  EXPECT_EQ(exr.envmap, EnvMap::kCube);
  EXPECT_EQ(exr.width, 32);
  EXPECT_EQ(exr.height, 6 * 32);
  EXPECT_TRUE(fs::exists(dir_ / "cube.png"));
  EXPECT_EQ(fs::file_size(dir_ / "sky.ktx2") > 6u * 32 * 32 * 8, true);
  const Image irradiance = ReadExr(dir_ / "irradiance.exr");
  EXPECT_EQ(irradiance.envmap, EnvMap::kCube);
  EXPECT_EQ(irradiance.width, 32);
  const nlohmann::json sh = nlohmann::json::parse(testing::ReadFile(dir_ / "sh.json"));
  EXPECT_EQ(sh["enu"]["radiance_coefficients"].size(), 9u);
  EXPECT_EQ(sh["y_up"]["irradiance_coefficients"].size(), 9u);
  EXPECT_GT(sh["horizontal_illuminance_lux"].get<double>(), 1000.0);
  EXPECT_TRUE(fs::exists(dir_ / "specular.ktx2"));
  const testing::RunResult bad = Run("render --preset earth --model hillaire --camera equirect --ktx2 x.ktx2 --png ''");
  EXPECT_NE(bad.exit_code, 0);
  EXPECT_NE(bad.err.find("--camera cubemap"), std::string::npos) << bad.err;
}

}  // namespace
}  // namespace atmo
