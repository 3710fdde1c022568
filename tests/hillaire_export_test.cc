// The exported hillaire tables (include/atmo/hillaire_tables.h, docs/tables.md): the manifest
// round trip, the mappings against their inverses, the engine-side lookups of
// src/atmo/shared/tables.glsl (compiled here as C++) against the model, the version rule and the
// atomic set. The GL side (the generated atmo_tables.glsl in a fresh program) is in
// tests/gl_hillaire_export_test.cc.
#include <unistd.h>

#include <algorithm>
#include <cmath>
#include <filesystem>
#include <fstream>
#include <functional>
#include <random>
#include <sstream>
#include <string>

#include <gtest/gtest.h>

#include "error_of.h"
#include <nlohmann/json.hpp>

#include "atmo/error.h"
#include "atmo/hillaire_tables.h"
#include "atmo/image.h"
#include "atmo/model.h"
#include "atmo/parameters.h"
#include "atmo/render.h"
#include "atmo/spectrum.h"
#include "physics/shared_parameters.h"
#include "shared/shared.h"

namespace atmo {
namespace {

namespace fs = std::filesystem;
using Json = nlohmann::ordered_json;

// Small tables: the test checks the format and the mappings, not the physics' convergence.
const ModelOptions kSmall = {{"transmittance_lut", "64x16"}, {"multiple_scattering_lut", "8x8"},
                             {"multiple_scattering_directions", "16"}, {"sky_view_lut", "48x24"}};

HillaireExportView SmallView() {
  HillaireExportView view;
  view.altitude_m = 300.0;
  view.sun_elevation_deg = 12.0;
  view.sun_azimuth_deg = 135.0;
  view.camera = {CameraKind::kPerspective, 64, 32, 80.0, 120.0, 5.0};
  view.aerial = {6, 4, 5, 20000.0};
  return view;
}

std::string Bytes(const fs::path& path) {
  std::ifstream in(path, std::ios::binary);
  std::stringstream s;
  s << in.rdbuf();
  return s.str();
}

bool HasTemporary(const fs::path& dir) {
  for (const auto& entry : fs::directory_iterator(dir)) {
    if (entry.path().filename().string().find(".tmp-") != std::string::npos) return true;
  }
  return false;
}

using atmo::testing::ErrorOf;

// Batch b of a 2D exported table as a shared texture (the CPU's GL_LINEAR sampler).
shared::Texture2D Texture(const ExportedTable& table, std::size_t b, bool repeat_u = false) {
  shared::Texture2D t(table.width, table.height, repeat_u);
  for (int y = 0; y < table.height; ++y) {
    for (int x = 0; x < table.width; ++x) {
      t.at(x, y) = glm::vec3(table.at(x, y, 0, b, 0), table.at(x, y, 0, b, 1), table.at(x, y, 0, b, 2));
    }
  }
  return t;
}

shared::Texture3D Texture3(const ExportedTable& table, std::size_t b) {
  shared::Texture3D t(table.width, table.height, table.depth);
  for (int z = 0; z < table.depth; ++z) {
    for (int y = 0; y < table.height; ++y) {
      for (int x = 0; x < table.width; ++x) {
        t.at(x, y, z) = glm::vec3(table.at(x, y, z, b, 0), table.at(x, y, z, b, 1), table.at(x, y, z, b, 2));
      }
    }
  }
  return t;
}

class HillaireExport : public ::testing::Test {
 protected:
  void SetUp() override {
    dir_ = fs::temp_directory_path() / ("atmo_hillaire_export_" + std::to_string(::getpid()) + "_" +
                                        ::testing::UnitTest::GetInstance()->current_test_info()->name());
    fs::remove_all(dir_);
    fs::create_directories(dir_);
  }
  void TearDown() override { fs::remove_all(dir_); }

  Json Manifest(const fs::path& name) const { return Json::parse(Bytes(name.string() + ".json")); }
  fs::path dir_;
};

TEST_F(HillaireExport, ManifestRoundTrip) {
  const AtmosphereParameters p = Preset("earth");
  const auto model = CreateModel("hillaire", p, kSmall);
  const HillaireTables tables = ComputeHillaireTables(*model, SmallView());
  const fs::path name = dir_ / "sky";
  const HillaireTableFiles files = ExportHillaireTables(tables, name);
  for (const fs::path& file : files.all()) EXPECT_TRUE(fs::is_regular_file(file)) << file;
  EXPECT_FALSE(HasTemporary(dir_));

  const HillaireTables again = ReadHillaireTables(name);
  ASSERT_EQ(again.tables.size(), tables.tables.size());
  for (std::size_t i = 0; i < tables.tables.size(); ++i) {
    const ExportedTable& a = tables.tables[i];
    const ExportedTable& b = again.tables[i];
    EXPECT_EQ(b.name, a.name);
    EXPECT_EQ(b.width, a.width);
    EXPECT_EQ(b.height, a.height);
    EXPECT_EQ(b.depth, a.depth);
    EXPECT_EQ(b.rgb, a.rgb) << a.name;  // bit for bit
    // The EXR holds the same floats, rows in the raw order.
    const Image exr = ReadExr(files.exr[i]);
    ASSERT_EQ(exr.width, a.width);
    ASSERT_EQ(exr.height, a.height * a.depth * static_cast<int>(a.batches));
    EXPECT_EQ(exr.pixels, a.rgb) << a.name;
  }
  EXPECT_EQ(ParameterHashHex(again.parameters), ParameterHashHex(p));
  EXPECT_EQ(again.options, tables.options);
  EXPECT_EQ(again.view.altitude_m, 300.0);
  EXPECT_EQ(again.view.camera.width, 64);
  EXPECT_EQ(again.view.aerial.depth, 5);
  EXPECT_EQ(again.view.aerial.max_distance_m, 20000.0);

  // Sizes follow the options; the manifest says what an engine needs.
  EXPECT_EQ(tables.table("transmittance").width, 64);
  EXPECT_EQ(tables.table("sky_view").height, 24);
  EXPECT_EQ(tables.table("aerial_radiance").depth, 5);
  const Json j = Manifest(name);
  EXPECT_EQ(j["format_version"], kHillaireTablesFormatVersion);
  EXPECT_EQ(j["atmo_version"], ATMO_VERSION);
  EXPECT_EQ(j["parameter_hash"], ParameterHashHex(p));
  EXPECT_DOUBLE_EQ(j["geometry_km"]["bottom_radius"].get<double>(), p.ground_radius_m / 1000.0);
  EXPECT_DOUBLE_EQ(j["geometry_km"]["top_radius"].get<double>(), p.top_radius_m / 1000.0);
  EXPECT_NEAR(j["view"]["r_km"].get<double>(), (p.ground_radius_m + 300.0) / 1000.0, 1e-9);
  for (std::string_view table : kHillaireTableNames) {
    const Json& entry = j["tables"][std::string(table)];
    for (const char* key : {"exr", "raw", "width", "height", "depth", "channels", "meaning", "units", "mapping",
                            "inverse", "glsl", "sampler", "raw_bytes", "raw_hash_fnv1a64"}) {
      EXPECT_TRUE(entry.contains(key)) << table << " lacks " << key;
    }
    EXPECT_EQ(entry["raw"], "sky_" + std::string(table) + ".raw");
  }
  // A spectral atmosphere exports every batch of three channels, one after the other.
  const AtmosphereParameters spectral = MakeSpectral(p, 5);
  const HillaireTables five = ComputeHillaireTables(*CreateModel("hillaire", spectral, kSmall), SmallView());
  for (const ExportedTable& t : five.tables) {
    EXPECT_EQ(t.batches, 2u);
    EXPECT_EQ(t.rgb.size(), 6 * t.texel_count());
  }
}

// u(inverse(u)) = u at every texel centre of each mapping the manifest states (the functions the
// generated GLSL copies), and the inverse of u(x) = x over the parameters' range.
TEST_F(HillaireExport, MappingsAndTheirInversesAgree) {
  const shared::AtmosphereParameters km = ToSharedParameters(Preset("earth"), 0, 1000.0);
  const shared::ivec2 size(64, 16);
  double worst = 0.0;
  for (int y = 0; y < size.y; ++y) {
    for (int x = 0; x < size.x; ++x) {
      const shared::vec2 uv((x + 0.5) / size.x, (y + 0.5) / size.y);
      double r, mu;
      shared::GetRMuFromTransmittanceTextureUv(km, size, uv, r, mu);
      if (!shared::RayIntersectsGround(km, r, mu)) {
        worst = std::max(worst, glm::length(shared::GetTransmittanceTextureUvFromRMu(km, size, r, mu) - uv));
      }
      double r_ms, mu_s;
      shared::GetRMuSFromMultiScatteringTextureUv(km, size, uv, r_ms, mu_s);
      worst = std::max(worst, glm::length(shared::GetMultiScatteringTextureUvFromRMuS(km, size, r_ms, mu_s) - uv));
      // The first ground row and the last sky row both map to the horizon (each half puts its
      // ends on texel centres); there the forward mapping takes the sky, so that row is skipped.
      for (double altitude_km : {0.0, 0.3, 8.0, 60.0}) {
        if (y == size.y / 2) continue;
        const double r_view = km.bottom_radius + altitude_km;
        double mu_view, azimuth;
        shared::GetViewAnglesFromSkyViewTextureUv(km, size, r_view, uv, mu_view, azimuth);
        shared::vec2 back = shared::GetSkyViewTextureUvFromViewAngles(km, size, r_view, mu_view, azimuth);
        worst = std::max(worst, glm::length(back - uv));
      }
    }
  }
  const shared::ivec3 volume(6, 4, 5);
  for (int z = 0; z < volume.z; ++z) {
    const shared::vec3 uvw(0.3, 0.7, (z + 0.5) / volume.z);
    shared::vec2 screen;
    double distance;
    shared::GetScreenDistanceFromAerialPerspectiveTextureUvw(volume, uvw, 20.0, screen, distance);
    EXPECT_NEAR(distance, (z + 1.0) / volume.z * 20.0, 1e-12);  // froxel z's distance
    worst = std::max(worst, glm::length(shared::GetAerialPerspectiveTextureUvwFromScreenDistance(volume, screen,
                                                                                                 distance, 20.0) -
                                        uvw));
  }
  // Double precision: the round trips agree to rounding.
  EXPECT_LT(worst, 1e-9);
}

// The engine-side lookups (atmo*, shared/tables.glsl) on the exported tables give what the model
// gives: the sky view what HillaireModel's own sky view returns, the aerial perspective what the
// volume's Lookup returns, the transmittance the model's.
TEST_F(HillaireExport, EngineLookupsMatchTheModel) {
  const AtmosphereParameters p = Preset("earth");
  const auto model = CreateModel("hillaire", p, kSmall);
  const HillaireExportView view = SmallView();
  const fs::path name = dir_ / "sky";
  ExportHillaireTables(ComputeHillaireTables(*model, view), name);
  const HillaireTables tables = ReadHillaireTables(name);
  const shared::AtmosphereParameters metres = ToSharedParameters(p, 0);
  const shared::Texture2D transmittance = Texture(tables.table("transmittance"), 0);
  const shared::Texture2D sky_view = Texture(tables.table("sky_view"), 0, /*repeat_u=*/true);
  const shared::Texture3D aerial_l = Texture3(tables.table("aerial_radiance"), 0);
  const shared::Texture3D aerial_t = Texture3(tables.table("aerial_transmittance"), 0);
  const glm::dvec3 sun = glm::normalize(SunDirection(view.sun_elevation_deg, view.sun_azimuth_deg));
  const auto sky = model->View(view.altitude_m, sun);
  const AerialPerspectiveVolume volume = ComputeAerialPerspectiveVolume(*sky, view.camera, view.aerial);
  const double r = metres.bottom_radius + view.altitude_m;
  std::mt19937 rng(7);
  std::uniform_real_distribution<double> unit(0.0, 1.0);
  double sky_worst = 0.0, transmittance_worst = 0.0, aerial_worst = 0.0;
  for (int i = 0; i < 500; ++i) {
    const double z = 2.0 * unit(rng) - 1.0;
    const double phi = 2.0 * shared::kPi * unit(rng);
    const glm::dvec3 v(std::sqrt(1.0 - z * z) * std::cos(phi), std::sqrt(1.0 - z * z) * std::sin(phi), z);
    double expected[3], transmitted[3];
    sky->Radiance(v, expected);
    sky->Transmittance(v, transmitted);
    const glm::dvec3 got = shared::atmoSkyView(metres, sky_view, r, v, sun);
    const glm::dvec3 t = shared::atmoTransmittance(metres, transmittance, r, v.z);
    for (int c = 0; c < 3; ++c) {
      sky_worst = std::max(sky_worst, std::abs(got[c] - expected[c]) / std::max(expected[c], 1e-12));
      transmittance_worst = std::max(transmittance_worst, std::abs(t[c] - transmitted[c]));
    }
    // A screen point and a distance from before the first slice to beyond the last.
    const shared::vec2 screen(unit(rng), unit(rng));
    const double distance_m = 25000.0 * unit(rng);
    double l_ref[3], t_ref[3];
    volume.Lookup(screen.x * view.camera.width, screen.y * view.camera.height, distance_m, l_ref, t_ref);
    shared::vec3 l, tr;
    shared::atmoAerialPerspective(aerial_l, aerial_t, screen, distance_m, view.aerial.max_distance_m, l, tr);
    for (int c = 0; c < 3; ++c) {
      aerial_worst = std::max(aerial_worst, std::abs(l[c] - l_ref[c]) / std::max(l_ref[c], 1e-12));
      aerial_worst = std::max(aerial_worst, std::abs(tr[c] - t_ref[c]));
    }
  }
  std::printf("engine lookups vs the model: sky view max rel %.2e, transmittance max abs %.2e, aerial %.2e\n",
              sky_worst, transmittance_worst, aerial_worst);
  // The same table and the same functions in double: only the float storage of the froxel values
  // (the volume's Lookup interpolates the same floats in another order) separates them.
  EXPECT_LT(sky_worst, 1e-6);
  EXPECT_LT(transmittance_worst, 1e-6);
  EXPECT_LT(aerial_worst, 1e-5);
}

TEST_F(HillaireExport, AnotherAtmoVersionWarnsAnotherFormatIsRefused) {
  const auto model = CreateModel("hillaire", Preset("earth"), kSmall);
  const fs::path name = dir_ / "sky";
  ExportHillaireTables(ComputeHillaireTables(*model, SmallView()), name);
  const fs::path json_path = name.string() + ".json";
  const std::string json = Bytes(json_path);
  const auto write_json = [&](const std::string& text) { std::ofstream(json_path, std::ios::binary) << text; };
  // Same format version, another atmo: loads, one warning line on stderr.
  std::string edited = json;
  edited.replace(edited.find("\"atmo_version\": \""), 17, "\"atmo_version\": \"9.9.9-");
  write_json(edited);
  ::testing::internal::CaptureStderr();
  EXPECT_NO_THROW(ReadHillaireTables(name));
  const std::string warning = ::testing::internal::GetCapturedStderr();
  EXPECT_EQ(warning.rfind("atmo: warning: ", 0), 0u) << warning;
  EXPECT_NE(warning.find("written by atmo 9.9.9-"), std::string::npos) << warning;
  EXPECT_EQ(std::count(warning.begin(), warning.end(), '\n'), 1) << warning;
  // Another format version: refused in one line.
  edited = json;
  edited.replace(edited.find("\"format_version\": 1"), 19, "\"format_version\": 2");
  write_json(edited);
  const std::string refusal = ErrorOf([&] { ReadHillaireTables(name); });
  EXPECT_NE(refusal.find("format version 2"), std::string::npos) << refusal;
  EXPECT_EQ(refusal.find('\n'), std::string::npos);
  write_json(json);
  EXPECT_NO_THROW(ReadHillaireTables(name));
  // A corrupted table: its hash.
  {
    std::fstream raw(name.string() + "_sky_view.raw", std::ios::in | std::ios::out | std::ios::binary);
    raw.seekp(40);
    raw.put('\x7f');
  }
  const std::string corrupt = ErrorOf([&] { ReadHillaireTables(name); });
  EXPECT_NE(corrupt.find("data hash"), std::string::npos) << corrupt;
}

// A manifest whose tables do not make one set, or whose view the export would refuse, is refused
// in one line although every raw file matches its sizes and hash (the fuzz target's invariants,
// fuzz/fuzz_targets.h): each case keeps a table's texel count, so its bytes and hash stay valid.
TEST_F(HillaireExport, ATableSetOfMismatchedSizesOrAnInvalidViewIsRefused) {
  const auto model = CreateModel("hillaire", Preset("earth"), kSmall);
  const fs::path name = dir_ / "sky";
  ExportHillaireTables(ComputeHillaireTables(*model, SmallView()), name);
  const fs::path json_path = name.string() + ".json";
  const Json original = Json::parse(Bytes(json_path));
  struct Case {
    const char* what;
    std::function<void(Json&)> edit;
    const char* message_part;
  };
  const Case cases[] = {
      {"sky views of two sizes",
       [](Json& j) {
         j["tables"]["sky_view_ground"]["width"] = 24;
         j["tables"]["sky_view_ground"]["height"] = 48;
       },
       "they must be of one size"},
      {"aerial tables of two sizes",
       [](Json& j) {
         j["tables"]["aerial_transmittance"]["width"] = 4;
         j["tables"]["aerial_transmittance"]["height"] = 6;
       },
       "they must be of one size"},
      {"a 2D table with a depth",
       [](Json& j) {
         j["tables"]["transmittance"]["height"] = 8;
         j["tables"]["transmittance"]["depth"] = 2;
       },
       "a 2D table has depth 1"},
      {"a table one texel wide",
       [](Json& j) {
         j["tables"]["multiple_scattering"]["width"] = 1;
         j["tables"]["multiple_scattering"]["height"] = 64;
       },
       "at least 2 texels a side"},
      {"an odd sky-view height",
       [](Json& j) {
         for (const char* t : {"sky_view", "sky_view_ground"}) {
           j["tables"][t]["width"] = 128;
           j["tables"][t]["height"] = 9;
         }
       },
       "even and >= 4"},
      {"an observer below the ground", [](Json& j) { j["view"]["altitude_m"] = -1.0; }, "view: "},
      {"an observer above the top", [](Json& j) { j["view"]["altitude_m"] = 2e5; }, "view: "},
      {"a fisheye camera", [](Json& j) { j["aerial_camera"]["kind"] = "fisheye"; }, "aerial_camera.kind"},
      {"a field of view of 180 degrees", [](Json& j) { j["aerial_camera"]["fov_deg"] = 180.0; }, "view: fov"},
      {"an infinite aerial distance", [](Json& j) { j["aerial_camera"]["max_distance_km"] = 1e306; }, "view: "},
  };
  for (const Case& c : cases) {
    Json j = original;
    c.edit(j);
    std::ofstream(json_path, std::ios::binary | std::ios::trunc) << j.dump(2);
    const std::string message = ErrorOf([&] { ReadHillaireTables(name); });
    EXPECT_NE(message.find(c.message_part), std::string::npos) << c.what << ": " << message;
    EXPECT_EQ(message.find('\n'), std::string::npos) << c.what << ": " << message;
  }
  std::ofstream(json_path, std::ios::binary | std::ios::trunc) << original.dump(2);
  EXPECT_NO_THROW(ReadHillaireTables(name));
}

// The manifest is staged last: when its write fails, none of the twelve table files published
// before it in the same set changes, and no temporary file is left.
TEST_F(HillaireExport, AFailedManifestWriteChangesNoTable) {
  const auto model = CreateModel("hillaire", Preset("earth"), kSmall);
  HillaireExportView other = SmallView();
  other.sun_elevation_deg = 40.0;  // other sky-view and aerial tables
  const fs::path name = dir_ / "sky";
  const HillaireTableFiles files = ExportHillaireTables(ComputeHillaireTables(*model, SmallView()), name);
  std::vector<std::string> before;
  for (std::size_t i = 0; i < files.raw.size(); ++i) {
    before.push_back(Bytes(files.raw[i]));
    before.push_back(Bytes(files.exr[i]));
  }
  // A dangling symbolic link is refused as a target: the manifest cannot be written.
  fs::remove(files.json);
  fs::create_symlink(dir_ / "missing" / "sky.json", files.json);
  EXPECT_THROW(ExportHillaireTables(ComputeHillaireTables(*model, other), name), Error);
  for (std::size_t i = 0; i < files.raw.size(); ++i) {
    EXPECT_EQ(Bytes(files.raw[i]), before[2 * i]) << files.raw[i];
    EXPECT_EQ(Bytes(files.exr[i]), before[2 * i + 1]) << files.exr[i];
  }
  EXPECT_FALSE(HasTemporary(dir_));
}

TEST_F(HillaireExport, BadViewsAreRefusedInOneLine) {
  const AtmosphereParameters p = Preset("earth");
  const auto model = CreateModel("hillaire", p, kSmall);
  HillaireExportView view = SmallView();
  view.altitude_m = p.top_radius_m - p.ground_radius_m + 10.0;
  const std::string above = ErrorOf([&] { ComputeHillaireTables(*model, view); });
  EXPECT_NE(above.find("inside the atmosphere"), std::string::npos) << above;
  view = SmallView();
  view.aerial.depth = 0;
  EXPECT_NE(ErrorOf([&] { ComputeHillaireTables(*model, view); }).find("[1, 512]"), std::string::npos);
  const auto elek = CreateModel("elek", Preset("atmosphere-plus"), {{"size", "4x8x4"}, {"orders", "1"}});
  EXPECT_NE(ErrorOf([&] { ComputeHillaireTables(*elek, SmallView()); }).find("model hillaire"), std::string::npos);
}

}  // namespace
}  // namespace atmo
