// PassTimings (include/atmo/timing.h): passes added at once and passes whose time arrives later
// (GPU timer queries), collected in order, without waiting or waiting.
#include <optional>
#include <string>
#include <vector>

#include <gtest/gtest.h>

#include "atmo/timing.h"

namespace atmo {
namespace {

// A deferred time that becomes ready when `*ready` is true; counts how often it was asked.
PassTimings::DeferredMs Later(double ms, const bool* ready, int* asked) {
  return [ms, ready, asked](bool wait) -> std::optional<double> {
    ++*asked;
    if (wait || *ready) return ms;
    return std::nullopt;
  };
}

TEST(PassTimings, AddsCallsAndKeepsTheOrderOfFirstUse) {
  PassTimings t;
  t.Add("a", 2.0);
  t.Add("b", 1.0);
  t.Add("a", 4.0);
  ASSERT_EQ(t.entries().size(), 2u);
  EXPECT_EQ(t.entries()[0].name, "a");
  EXPECT_EQ(t.entries()[0].calls, 2);
  EXPECT_DOUBLE_EQ(t.entries()[0].total_ms, 6.0);
  EXPECT_DOUBLE_EQ(t.LastMs("a"), 4.0);
  EXPECT_DOUBLE_EQ(t.LastMs("missing"), -1.0);
}

TEST(PassTimings, DeferredTimesKeepTheirPlaceAndArriveInOrder) {
  PassTimings t;
  bool first_ready = false;
  bool second_ready = true;
  int asked_first = 0;
  int asked_second = 0;
  t.AddDeferred("gpu_a", Later(3.0, &first_ready, &asked_first));
  t.Add("cpu", 1.0);
  t.AddDeferred("gpu_b", Later(5.0, &second_ready, &asked_second));
  EXPECT_TRUE(t.has_pending());
  // Not waiting: the first is not ready, so nothing is collected (the second waits its turn).
  EXPECT_FALSE(t.Collect(false));
  EXPECT_EQ(asked_first, 1);
  EXPECT_EQ(asked_second, 0);
  first_ready = true;
  EXPECT_TRUE(t.Collect(false));
  EXPECT_FALSE(t.has_pending());
  const std::vector<PassTiming>& e = t.entries();
  ASSERT_EQ(e.size(), 3u);
  EXPECT_EQ(e[0].name, "gpu_a");  // the place of its AddDeferred, not of its arrival
  EXPECT_EQ(e[1].name, "cpu");
  EXPECT_EQ(e[2].name, "gpu_b");
  EXPECT_DOUBLE_EQ(e[0].last_ms, 3.0);
  EXPECT_DOUBLE_EQ(e[2].last_ms, 5.0);
  EXPECT_EQ(e[2].calls, 1);
}

TEST(PassTimings, ReadingWaitsForTheDeferredTimes) {
  PassTimings t;
  const bool never = false;
  int asked = 0;
  t.AddDeferred("gpu", Later(7.0, &never, &asked));
  t.AddDeferred("gpu", Later(9.0, &never, &asked));
  EXPECT_DOUBLE_EQ(t.LastMs("gpu"), 9.0);  // waits: both collected
  EXPECT_EQ(t.entries()[0].calls, 2);
  EXPECT_DOUBLE_EQ(t.entries()[0].total_ms, 16.0);
}

TEST(PassTimings, ClearDropsTimesNotCollected) {
  PassTimings t;
  const bool never = false;
  int asked = 0;
  t.AddDeferred("gpu", Later(7.0, &never, &asked));
  t.Clear();
  EXPECT_FALSE(t.has_pending());
  EXPECT_TRUE(t.entries().empty());
  EXPECT_EQ(asked, 0);
}

TEST(PassTimings, AnUnreadableTimeIsDroppedWhenWaitedFor) {
  PassTimings t;
  t.AddDeferred("lost", [](bool) -> std::optional<double> { return std::nullopt; });
  t.Add("cpu", 1.0);
  EXPECT_TRUE(t.Collect(true));
  EXPECT_DOUBLE_EQ(t.LastMs("lost"), -1.0);  // never ran, as far as anyone can tell
  EXPECT_DOUBLE_EQ(t.LastMs("cpu"), 1.0);
}

}  // namespace
}  // namespace atmo
