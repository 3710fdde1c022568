// The table cache (include/atmo/table_cache.h): tables read back equal the computed ones bit for
// bit, every change of what they depend on misses, a damaged file is never read, an unwritable
// folder costs only the saving, the folder is trimmed oldest first, and the command line's
// --table-cache keeps and finds them.
#include <gtest/gtest.h>

#include <algorithm>
#include <cstring>
#include <fstream>
#include <string>
#include <vector>

#include "atmo/elek.h"
#include "atmo/error.h"
#include "atmo/model.h"
#include "atmo/parameters.h"
#include "atmo/table_cache.h"
#include "atmo/timing.h"
#include "cli_fixture.h"
#include "io/table_cache_file.h"
#include "models/elek_model.h"
#include "models/source4d_model.h"

namespace atmo {
namespace {

namespace fs = std::filesystem;
using testing::ReadFile;

// A small source4d (about 0.1 s to compute).
const ModelOptions kSmall = {{"table", "8x12x16x4"}, {"gather", "17x5"}, {"orders", "2"}};

bool Ran(const Model& model, const std::string& pass) {
  const auto& entries = model.timings().entries();
  return std::any_of(entries.begin(), entries.end(), [&](const PassTiming& p) { return p.name == pass; });
}

std::vector<unsigned char> Bytes(const fs::path& path) {
  std::ifstream in(path, std::ios::binary);
  return {std::istreambuf_iterator<char>(in), std::istreambuf_iterator<char>()};
}

void WriteBytes(const fs::path& path, const std::vector<unsigned char>& bytes) {
  std::ofstream out(path, std::ios::binary | std::ios::trunc);
  out.write(reinterpret_cast<const char*>(bytes.data()), static_cast<std::streamsize>(bytes.size()));
}

// Every texel of every batch's tables, bit for bit.
void ExpectSameTables(const Model& a, const Model& b) {
  const auto& x = static_cast<const Source4dModel&>(a).batches();
  const auto& y = static_cast<const Source4dModel&>(b).batches();
  ASSERT_EQ(x.size(), y.size());
  const auto same = [](const std::vector<glm::vec3>& p, const std::vector<glm::vec3>& q) {
    return p.size() == q.size() && !p.empty() && std::memcmp(p.data(), q.data(), p.size() * sizeof(glm::vec3)) == 0;
  };
  for (std::size_t i = 0; i < x.size(); ++i) {
    EXPECT_TRUE(same(x[i].tables.transmittance.texels, y[i].tables.transmittance.texels)) << i;
    EXPECT_TRUE(same(x[i].tables.rayleigh.texels, y[i].tables.rayleigh.texels)) << i;
    EXPECT_TRUE(same(x[i].tables.mie.texels, y[i].tables.mie.texels)) << i;
    EXPECT_TRUE(same(x[i].tables.ground_irradiance.texels, y[i].tables.ground_irradiance.texels)) << i;
    EXPECT_EQ(x[i].tables.mu_s_size, y[i].tables.mu_s_size);
  }
}

std::size_t CacheFiles(const fs::path& folder) {
  std::size_t n = 0;
  for (const auto& entry : fs::directory_iterator(folder)) n += entry.path().extension() == ".atmotables";
  return n;
}

class TableCacheTest : public testing::CliFixture {
 protected:
  void SetUp() override {
    CliFixture::SetUp();
    cache_ = TableCache{.folder = dir_ / "cache", .shipped = {}};
    SetTableCache(cache_);
  }
  void TearDown() override {
    SetTableCache(TableCache{{}, std::uint64_t{1} << 30, ShippedTableFolders()});  // the process's default
    SetProgressHandler({});
    CliFixture::TearDown();
  }
  TableCache cache_;
};

TEST_F(TableCacheTest, TablesReadBackAreTheComputedOnesBitForBit) {
  // 15 channels: five batches in one file.
  const AtmosphereParameters p = Preset("us-standard");
  const auto computed = CreateModel("source4d", p, kSmall);
  EXPECT_TRUE(Ran(*computed, "source4d_gather_1"));
  EXPECT_FALSE(Ran(*computed, "table_cache_read"));
  EXPECT_TRUE(fs::is_regular_file(io::CachedTablesPath(cache_.folder, io::TableCacheKey("source4d", kSmall, p))));

  const auto read = CreateModel("source4d", p, kSmall);
  EXPECT_TRUE(Ran(*read, "table_cache_read"));
  EXPECT_EQ(read->timings().entries().size(), 1u) << "nothing but the read";
  ExpectSameTables(*computed, *read);
  // The same sky: radiance from both, every channel, the sun low and high.
  for (double sun_elevation : {3.0, 40.0}) {
    const glm::dvec3 sun = DirectionFromZenithAzimuth(glm::radians(90.0 - sun_elevation), 0.0);
    const auto a = computed->View(0.0, sun);
    const auto b = read->View(0.0, sun);
    std::vector<double> ra(p.channel_count()), rb(p.channel_count());
    for (double zenith : {0.0, 60.0, 89.0}) {
      const glm::dvec3 view = DirectionFromZenithAzimuth(glm::radians(zenith), glm::radians(120.0));
      a->Radiance(view, ra);
      b->Radiance(view, rb);
      EXPECT_EQ(ra, rb) << "sun " << sun_elevation << ", zenith " << zenith;
      EXPECT_GT(ra[7], 0.0);
    }
  }
}

TEST_F(TableCacheTest, WhatTheTablesDependOnIsInTheKey) {
  const AtmosphereParameters earth = Preset("earth");
  CreateModel("source4d", earth, kSmall);
  EXPECT_EQ(CacheFiles(cache_.folder), 1u);

  // The atmosphere's name is not: its dump under another name is the same atmosphere.
  AtmosphereParameters renamed = FromJson(ToJson(earth));
  renamed.name = "my-earth";
  EXPECT_TRUE(Ran(*CreateModel("source4d", renamed, kSmall), "table_cache_read"));

  // Nor is what only scales or frames images: the tables, computed, ignore it.
  AtmosphereParameters framed = earth;
  framed.solar_irradiance = {1.5, 1.9, 1.7};
  framed.exposure = 3.0;
  framed.observer_altitude_m = 2000.0;
  EXPECT_TRUE(Ran(*CreateModel("source4d", framed, kSmall), "table_cache_read"));
  SetTableCache(std::nullopt);
  ExpectSameTables(*CreateModel("source4d", earth, kSmall), *CreateModel("source4d", framed, kSmall));
  SetTableCache(cache_);

  // The medium, the ground and the options are.
  AtmosphereParameters hazy = earth;
  hazy.mie.scattering_per_m[1] *= 1.5;
  AtmosphereParameters dark = earth;
  dark.ground_albedo[0] = 0.05;
  ModelOptions more = kSmall;
  more["orders"] = "3";
  for (const auto& model : {CreateModel("source4d", hazy, kSmall), CreateModel("source4d", dark, kSmall),
                            CreateModel("source4d", earth, more)}) {
    EXPECT_FALSE(Ran(*model, "table_cache_read"));
  }
  EXPECT_EQ(CacheFiles(cache_.folder), 4u);

  // And the build.
  const std::string key = io::TableCacheKey("source4d", kSmall, earth);
  EXPECT_NE(key.find(std::string(BuildId())), std::string::npos);
  EXPECT_EQ(BuildId().size(), 32u);
  EXPECT_EQ(std::string(BuildId()).find_first_not_of("0123456789abcdef"), std::string::npos);
}

TEST_F(TableCacheTest, ADamagedFileIsNeverReadAndIsReplaced) {
  const AtmosphereParameters p = Preset("earth");
  const auto computed = CreateModel("source4d", p, kSmall);
  const fs::path file = io::CachedTablesPath(cache_.folder, io::TableCacheKey("source4d", kSmall, p));
  const std::vector<unsigned char> good = Bytes(file);
  ASSERT_GT(good.size(), 1000u);

  std::vector<std::vector<unsigned char>> damaged;
  damaged.emplace_back(good.begin(), good.begin() + static_cast<long>(good.size() / 2));  // truncated
  damaged.push_back(good);
  damaged.back()[good.size() / 2] ^= 0x10;  // one bit of a texel
  damaged.push_back(good);
  damaged.back()[40] ^= 0x01;  // one bit of the key
  damaged.push_back(good);
  damaged.back().push_back(0);  // a byte too many
  damaged.emplace_back();       // empty
  for (std::size_t i = 0; i < damaged.size(); ++i) {
    WriteBytes(file, damaged[i]);
    const auto model = CreateModel("source4d", p, kSmall);
    EXPECT_FALSE(Ran(*model, "table_cache_read")) << "damage " << i;
    ExpectSameTables(*computed, *model);
    EXPECT_EQ(Bytes(file), good) << "damage " << i << ": the file is written again";
  }
  // Payloads that do not fit the model's settings are refused by the model (the key was right).
  io::TableBytesWriter writer;
  writer.Int(1);
  writer.Int(16);
  EXPECT_EQ(io::WriteCachedTables(cache_, io::TableCacheKey("source4d", kSmall, p), writer.bytes()), "");
  const auto model = CreateModel("source4d", p, kSmall);
  EXPECT_FALSE(Ran(*model, "table_cache_read"));
  ExpectSameTables(*computed, *model);
}

TEST_F(TableCacheTest, AFolderThatCannotBeWrittenCostsOnlyTheSaving) {
  std::vector<std::string> messages;
  SetProgressHandler([&](const std::string& m) { messages.push_back(m); });
  testing::WriteFile(dir_ / "a-file", "not a folder");
  SetTableCache(TableCache{.folder = dir_ / "a-file" / "tables", .shipped = {}});
  const auto model = CreateModel("source4d", Preset("earth"), kSmall);
  EXPECT_FALSE(Ran(*model, "table_cache_read"));
  ASSERT_EQ(messages.size(), 1u);
  EXPECT_NE(messages[0].find("table cache: the source4d tables were not kept in"), std::string::npos) << messages[0];
  EXPECT_EQ(ReadFile(dir_ / "a-file"), "not a folder");
}

TEST_F(TableCacheTest, TheLeastRecentlyUsedFilesGoFirst) {
  const AtmosphereParameters earth = Preset("earth");
  CreateModel("source4d", earth, kSmall);
  const fs::path first = io::CachedTablesPath(cache_.folder, io::TableCacheKey("source4d", kSmall, earth));
  const std::uintmax_t one = fs::file_size(first);
  // Room for two files: the third atmosphere pushes out the least recently used.
  cache_.max_bytes = 2 * one + one / 2;
  SetTableCache(cache_);
  AtmosphereParameters second = earth;
  second.ground_albedo[1] = 0.2;
  AtmosphereParameters third = earth;
  third.ground_albedo[1] = 0.4;
  CreateModel("source4d", second, kSmall);
  const fs::path second_file = io::CachedTablesPath(cache_.folder, io::TableCacheKey("source4d", kSmall, second));
  // The first is used again (read back) after the second was written: the second is the oldest.
  fs::last_write_time(second_file, fs::last_write_time(first) - std::chrono::seconds(10));
  EXPECT_TRUE(Ran(*CreateModel("source4d", earth, kSmall), "table_cache_read"));
  CreateModel("source4d", third, kSmall);
  EXPECT_TRUE(fs::exists(first));
  EXPECT_FALSE(fs::exists(second_file));
  EXPECT_TRUE(fs::exists(io::CachedTablesPath(cache_.folder, io::TableCacheKey("source4d", kSmall, third))));
  EXPECT_EQ(CacheFiles(cache_.folder), 2u);
  // A model's tables larger than the whole cache are not kept.
  cache_.max_bytes = one / 2;
  SetTableCache(cache_);
  std::vector<std::string> messages;
  SetProgressHandler([&](const std::string& m) { messages.push_back(m); });
  AtmosphereParameters fourth = earth;
  fourth.ground_albedo[1] = 0.6;
  CreateModel("source4d", fourth, kSmall);
  EXPECT_FALSE(fs::exists(io::CachedTablesPath(cache_.folder, io::TableCacheKey("source4d", kSmall, fourth))));
  ASSERT_EQ(messages.size(), 1u);
  EXPECT_NE(messages[0].find("larger than the cache"), std::string::npos) << messages[0];
}

TEST_F(TableCacheTest, ShippedFoldersAreReadAndNeverWritten) {
  const AtmosphereParameters earth = Preset("earth");
  const auto computed = CreateModel("source4d", earth, kSmall);
  const fs::path file = io::CachedTablesPath(cache_.folder, io::TableCacheKey("source4d", kSmall, earth));
  const auto written = fs::last_write_time(file) - std::chrono::hours(1);
  fs::last_write_time(file, written);
  // The folder as a shipped one, and nothing that keeps tables.
  SetTableCache(TableCache{{}, 1 << 16, {dir_ / "elsewhere", cache_.folder}});
  const auto read = CreateModel("source4d", earth, kSmall);
  EXPECT_TRUE(Ran(*read, "table_cache_read"));
  ExpectSameTables(*computed, *read);
  EXPECT_EQ(fs::last_write_time(file), written) << "a shipped file is not renewed";
  // Larger than max_bytes (64 KiB): shipped files are read whatever the cache's size.
  EXPECT_GT(fs::file_size(file), std::uintmax_t{1} << 16);
  // Another atmosphere is computed and kept nowhere.
  AtmosphereParameters other = earth;
  other.ground_albedo[2] = 0.5;
  EXPECT_FALSE(Ran(*CreateModel("source4d", other, kSmall), "table_cache_read"));
  EXPECT_EQ(CacheFiles(cache_.folder), 1u);
  EXPECT_FALSE(fs::exists(dir_ / "elsewhere"));
  // std::nullopt: not even the shipped tables.
  SetTableCache(std::nullopt);
  EXPECT_FALSE(Ran(*CreateModel("source4d", earth, kSmall), "table_cache_read"));
}

// elek keeps its transmittance and summed tables (read back, a batch has no orders, as a loaded
// table); an elek that loads its table from files keeps nothing (the files may change).
TEST_F(TableCacheTest, ElekTablesReadBackGiveTheSameSky) {
  const ModelOptions small = {{"size", "8x32x8"}, {"orders", "2"}};
  const AtmosphereParameters p = Preset("us-standard");  // 15 channels, five batches
  const auto computed = CreateModel("elek", p, small);
  EXPECT_TRUE(Ran(*computed, "elek_scatter_2_lut"));
  const auto read = CreateModel("elek", p, small);
  EXPECT_TRUE(Ran(*read, "table_cache_read"));
  EXPECT_FALSE(Ran(*read, "elek_single_lut"));
  const auto& a = static_cast<const ElekModel&>(*computed).batches();
  const auto& b = static_cast<const ElekModel&>(*read).batches();
  ASSERT_EQ(a.size(), 5u);
  ASSERT_EQ(b.size(), a.size());
  for (std::size_t i = 0; i < a.size(); ++i) {
    EXPECT_EQ(b[i].transmittance.texels, a[i].transmittance.texels) << i;
    EXPECT_EQ(b[i].total.rayleigh.texels, a[i].total.rayleigh.texels) << i;
    EXPECT_EQ(b[i].total.mie.texels, a[i].total.mie.texels) << i;
    EXPECT_TRUE(b[i].orders.empty());
  }
  const glm::dvec3 sun = DirectionFromZenithAzimuth(glm::radians(80.0), 0.0);
  std::vector<double> ra(p.channel_count()), rb(p.channel_count());
  computed->View(500.0, sun)->Radiance(DirectionFromZenithAzimuth(glm::radians(70.0), 1.0), ra);
  read->View(500.0, sun)->Radiance(DirectionFromZenithAzimuth(glm::radians(70.0), 1.0), rb);
  EXPECT_EQ(ra, rb);
  EXPECT_GT(ra[7], 0.0);

  const std::size_t files = CacheFiles(cache_.folder);
  ExportElekTable(*computed, dir_ / "exported");
  ModelOptions loading = small;
  loading["table"] = (dir_ / "exported").string();
  for (int k = 0; k < 2; ++k) EXPECT_FALSE(Ran(*CreateModel("elek", p, loading), "table_cache_read"));
  EXPECT_EQ(CacheFiles(cache_.folder), files);
}

TEST_F(TableCacheTest, ModelsWithoutCostlyTablesKeepNothing) {
  CreateModel("hillaire", Preset("earth"));
  CreateModel("simple", Preset("simple"));
  EXPECT_FALSE(fs::exists(cache_.folder) && CacheFiles(cache_.folder) > 0);
}

TEST(DefaultTableCache, FollowsTheEnvironment) {
  const auto with = [](const char* cache, const char* xdg, const char* home) {
    const auto set = [](const char* name, const char* value) {
      if (value == nullptr) {
        ::unsetenv(name);
      } else {
        ::setenv(name, value, 1);
      }
    };
    const char* saved[3] = {std::getenv("ATMO_TABLE_CACHE"), std::getenv("XDG_CACHE_HOME"), std::getenv("HOME")};
    const std::string kept[3] = {saved[0] ? saved[0] : "", saved[1] ? saved[1] : "", saved[2] ? saved[2] : ""};
    set("ATMO_TABLE_CACHE", cache);
    set("XDG_CACHE_HOME", xdg);
    set("HOME", home);
    const TableCache found = DefaultTableCache();
    set("ATMO_TABLE_CACHE", saved[0] ? kept[0].c_str() : nullptr);
    set("XDG_CACHE_HOME", saved[1] ? kept[1].c_str() : nullptr);
    set("HOME", saved[2] ? kept[2].c_str() : nullptr);
    EXPECT_EQ(found.shipped, ShippedTableFolders());
    return found.folder.empty() ? std::string("none") : found.folder.string();
  };
  EXPECT_EQ(with("off", "/x", "/h"), "none");
  EXPECT_EQ(with("", "/x", "/h"), "none");
  EXPECT_EQ(with("/c", "/x", "/h"), "/c");
  EXPECT_EQ(with(nullptr, "/x", "/h"), "/x/atmo/tables");
  EXPECT_EQ(with(nullptr, "relative", "/h"), "/h/.cache/atmo/tables");  // XDG paths must be absolute
  EXPECT_EQ(with(nullptr, nullptr, "/h"), "/h/.cache/atmo/tables");
  EXPECT_EQ(with(nullptr, nullptr, nullptr), "none");
}

// The default sky's tables, made when atmo was built: read, and the bytes this build computes.
TEST(ShippedTables, HoldTheDefaultSkyAsThisBuildComputesIt) {
  const std::vector<fs::path> shipped = ShippedTableFolders();
  if (shipped.empty()) GTEST_SKIP() << "configured with -DATMO_BAKE_TABLES=OFF: no shipped tables";
  const AtmosphereParameters p = Preset("us-standard");
  SetTableCache(TableCache{{}, std::uint64_t{1} << 30, shipped});
  const auto read = CreateModel("source4d", p);
  EXPECT_TRUE(Ran(*read, "table_cache_read"));
  SetTableCache(std::nullopt);
  const auto computed = CreateModel("source4d", p);
  SetTableCache(TableCache{{}, std::uint64_t{1} << 30, shipped});
  EXPECT_FALSE(Ran(*computed, "table_cache_read"));
  ExpectSameTables(*computed, *read);
}

// The command line: a second render finds the first one's tables and writes the same image.
class TableCacheCli : public testing::CliFixture {};

TEST_F(TableCacheCli, ASecondRenderReadsTheTablesAndWritesTheSameImage) {
  const std::string render =
      "render --model source4d --option table=8x12x16x4 --option gather=17x5 --option orders=2 --width 48 "
      "--height 24 --sun-elevation 5 --no-png";
  const testing::RunResult first = Run(render + " --table-cache tables --exr first.exr");
  ASSERT_EQ(first.exit_code, 0) << first.err;
  EXPECT_EQ(CacheFiles(dir_ / "tables"), 1u);
  const testing::RunResult second = Run(render + " --table-cache tables --exr second.exr");
  ASSERT_EQ(second.exit_code, 0) << second.err;
  EXPECT_EQ(CacheFiles(dir_ / "tables"), 1u);
  EXPECT_EQ(ReadFile(dir_ / "first.exr").size(), ReadFile(dir_ / "second.exr").size());
  // The pixels (the files' attributes hold the passes' times, which differ).
  const std::string pixels = "sample --model source4d --option table=8x12x16x4 --option gather=17x5 --option orders=2 "
                             "--altitude 0 --sun-elevation 5 --view-zenith 80 --azimuth 30 --table-cache ";
  const testing::RunResult computed = Run(pixels + "off");
  const testing::RunResult read = Run(pixels + "tables");
  ASSERT_EQ(computed.exit_code, 0) << computed.err;
  EXPECT_EQ(computed.out, read.out);
  // off keeps nothing; a path that is a file is refused before any work.
  EXPECT_EQ(Run(render + " --exr third.exr --table-cache off").exit_code, 0);
  EXPECT_FALSE(fs::exists(dir_ / "off"));
  ExpectFailureKeepingOutputs(render + " --exr fourth.exr --table-cache first.exr", "is not a folder", {"fourth.exr"});
}

}  // namespace
}  // namespace atmo
