// The memory budget (include/atmo/memory.h): sizes, the limit, and the models' checks.
#include <cmath>
#include <string>

#include <gtest/gtest.h>

#include "error_of.h"

#include "atmo/error.h"
#include "atmo/memory.h"
#include "atmo/model.h"
#include "atmo/parameters.h"

namespace atmo {
namespace {

using atmo::testing::ErrorOf;

// Restores the default limit when a test ends.
struct LimitGuard {
  ~LimitGuard() { SetMemoryLimitBytes(0); }
};

TEST(Memory, ByteSizesParseInPowersOf1024) {
  EXPECT_EQ(ParseByteSize("4G"), std::uint64_t{4} << 30);
  EXPECT_EQ(ParseByteSize("512M"), std::uint64_t{512} << 20);
  EXPECT_EQ(ParseByteSize("1.5GB"), std::uint64_t{3} << 29);
  EXPECT_EQ(ParseByteSize("2gib"), std::uint64_t{2} << 30);
  EXPECT_EQ(ParseByteSize("1T"), std::uint64_t{1} << 40);
  EXPECT_EQ(ParseByteSize("2048k"), std::uint64_t{2} << 20);
  EXPECT_EQ(ParseByteSize("1048576"), std::uint64_t{1} << 20);
  for (const char* bad : {"", "G", "4X", "-1G", "nanG", "inf", " 4G", "4 G", "1e400"}) {
    EXPECT_NE(ErrorOf([&] { ParseByteSize(bad); }).find("memory size"), std::string::npos) << bad;
  }
  EXPECT_NE(ErrorOf([] { ParseByteSize("1000"); }).find("outside [1M, 1024T]"), std::string::npos);
  EXPECT_NE(ErrorOf([] { ParseByteSize("2048T"); }).find("outside [1M, 1024T]"), std::string::npos);
  EXPECT_EQ(FormatBytes(1536.0), "1.5 KB");
  EXPECT_EQ(FormatBytes(3.0 * (1 << 30)), "3.0 GB");
  EXPECT_EQ(FormatBytes(100.0), "100 bytes");
}

TEST(Memory, TheLimitDefaultsToHalfTheMachineAndIsChecked) {
  const LimitGuard guard;
  SetMemoryLimitBytes(0);
  const std::uint64_t physical = PhysicalMemoryBytes();
  ASSERT_GT(physical, 0u);  // Linux says
  EXPECT_EQ(MemoryLimitBytes(), physical / 2);
  EXPECT_NO_THROW(CheckMemory("a small thing", 1e6));
  EXPECT_NE(ErrorOf([] { CheckMemory("a thing", 1e30); }).find("half of this machine's memory"), std::string::npos);
  EXPECT_NE(ErrorOf([] { CheckMemory("a thing", NAN); }).find("a thing would need about more than 1 EB"),
            std::string::npos);
  SetMemoryLimitBytes(std::uint64_t{1} << 30);
  EXPECT_NO_THROW(CheckMemory("a thing", 1024.0 * 1024.0 * 1024.0));
  EXPECT_EQ(ErrorOf([] { CheckMemory("a thing", 2.0 * 1024 * 1024 * 1024); }),
            "a thing would need about 2.0 GB, more than the memory limit of 1.0 GB (--max-memory)");
}

// The models refuse table sizes over the limit when they are made, before allocating: the
// sizes that ended in std::bad_alloc (elek size=1024x4096x1024) or took the machine's memory.
TEST(Memory, ModelsRefuseTablesOverTheLimit) {
  const LimitGuard guard;
  EXPECT_NE(ErrorOf([] { CreateModel("elek", Preset("earth"), {{"size", "1024x4096x1024"}}); })
                .find("elek tables of size=1024x4096x1024 at 3 channels would need about 512.0 GB"),
            std::string::npos);
  SetMemoryLimitBytes(std::uint64_t{256} << 20);
  EXPECT_NE(ErrorOf([] { CreateModel("source4d", Preset("earth"), {{"table", "64x64x64x64"}}); })
                .find("source4d tables of table=64x64x64x64 at 3 channels would need about 1.0 GB"),
            std::string::npos);
  // The defaults fit a small limit.
  SetMemoryLimitBytes(std::uint64_t{128} << 20);
  EXPECT_NO_THROW(CreateModel("elek", Preset("earth"), {{"size", "16x64x16"}}));
}

}  // namespace
}  // namespace atmo
