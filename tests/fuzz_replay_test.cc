// Every seed and every kept crash of the fuzz targets (fuzz/fuzz_targets.h), replayed through the
// same entry functions as the libFuzzer binaries: no input may crash, escape with an exception
// other than atmo::Error, break an accepted input's invariant or take more than a second.
#include <algorithm>
#include <filesystem>
#include <fstream>
#include <iterator>
#include <set>
#include <string>
#include <vector>

#include <gtest/gtest.h>

#include "fuzz_targets.h"

namespace atmo::fuzz {
namespace {

namespace fs = std::filesystem;

const fs::path kFuzzDir = fs::path(ATMO_SOURCE_DIR) / "fuzz";

std::vector<std::uint8_t> ReadBytes(const fs::path& path) {
  std::ifstream in(path, std::ios::binary);
  return {std::istreambuf_iterator<char>(in), std::istreambuf_iterator<char>()};
}

// The files of fuzz/<kind>/<target>/, sorted.
std::vector<fs::path> InputsOf(const std::string& kind, std::string_view target) {
  std::vector<fs::path> files;
  const fs::path folder = kFuzzDir / kind / std::string(target);
  if (!fs::is_directory(folder)) return files;
  for (const auto& entry : fs::directory_iterator(folder)) {
    if (entry.is_regular_file() && entry.path().filename() != "README.md") files.push_back(entry.path());
  }
  std::sort(files.begin(), files.end());
  return files;
}

// Every folder of fuzz/corpus and fuzz/regressions is a target, and every target has seeds.
TEST(FuzzReplay, EveryTargetHasSeedsAndEveryFolderATarget) {
  std::set<std::string> names;
  for (const FuzzTarget& target : kFuzzTargets) {
    names.insert(std::string(target.name));
    EXPECT_GE(InputsOf("corpus", target.name).size(), 3u) << target.name;
  }
  for (const char* kind : {"corpus", "regressions"}) {
    for (const auto& entry : fs::directory_iterator(kFuzzDir / kind)) {
      if (entry.is_directory()) {
        EXPECT_TRUE(names.count(entry.path().filename().string())) << entry.path();
      }
    }
  }
}

class FuzzReplayTest : public ::testing::TestWithParam<FuzzTarget> {};

TEST_P(FuzzReplayTest, CorpusAndRegressionsRunWithoutCrashOrForeignException) {
  const FuzzTarget target = GetParam();
  int replayed = 0;
  for (const char* kind : {"corpus", "regressions"}) {
    for (const fs::path& file : InputsOf(kind, target.name)) {
      const std::vector<std::uint8_t> bytes = ReadBytes(file);
      try {
        EXPECT_EQ(target.run(bytes.data(), bytes.size()), 0) << file;
      } catch (const std::exception& e) {
        ADD_FAILURE() << file << ": an exception other than a one-line atmo::Error: " << e.what();
      }
      ++replayed;
    }
  }
  EXPECT_GT(replayed, 0);
}

INSTANTIATE_TEST_SUITE_P(Targets, FuzzReplayTest, ::testing::ValuesIn(kFuzzTargets),
                         [](const ::testing::TestParamInfo<FuzzTarget>& info) { return std::string(info.param.name); });

// The entries refuse what their parsers refuse, quietly (no exception escapes): a few inputs each.
TEST(FuzzReplay, EntriesRefuseGarbageWithAtmoErrors) {
  const std::string inputs[] = {"", "\xff\xfe", "{", std::string(1, '\0'), "v/1\x01", "[[[[[[[[[[[[[[[[[[[[[["};
  for (const FuzzTarget& target : kFuzzTargets) {
    for (const std::string& input : inputs) {
      EXPECT_NO_THROW(target.run(reinterpret_cast<const std::uint8_t*>(input.data()), input.size()))
          << target.name << " '" << input << "'";
    }
  }
}

}  // namespace
}  // namespace atmo::fuzz
