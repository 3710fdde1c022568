// The threaded WebAssembly build's oneTBB loops (web/shim/oneapi/tbb, thread_pool.h), built natively
// on std::thread with four threads (ATMO_WEB_SHIM_THREADS, tests/CMakeLists.txt): every index is
// run exactly once, loops follow one another without mixing, nested loops run, exceptions reach
// the caller, per-thread values combine. This program does not link oneTBB: the shim stands in
// for it, as in the browser. The sanitizer stage (.ci/sanitize_and_fuzz.sh) also runs it under
// ThreadSanitizer.
#include <algorithm>
#include <atomic>
#include <mutex>
#include <numeric>
#include <stdexcept>
#include <thread>
#include <vector>

#include <gtest/gtest.h>

#include "oneapi/tbb/blocked_range.h"
#include "oneapi/tbb/combinable.h"
#include "oneapi/tbb/enumerable_thread_specific.h"
#include "oneapi/tbb/parallel_for.h"
#include "oneapi/tbb/task_arena.h"

namespace {

namespace tbb = oneapi::tbb;

TEST(WebShimThreadPool, HasTheThreadsItWasBuiltWith) {
  EXPECT_EQ(tbb::this_task_arena::max_concurrency(), ATMO_WEB_SHIM_THREADS);
}

TEST(WebShimThreadPool, RunsEveryIndexOnceForAnySize) {
  for (int size : {0, 1, 2, 3, 7, 15, 16, 17, 100, 1000, 4097}) {
    std::vector<std::atomic<int>> hits(size);
    tbb::parallel_for(0, size, [&](int i) { hits[i].fetch_add(1); });
    for (int i = 0; i < size; ++i) ASSERT_EQ(hits[i].load(), 1) << "index " << i << " of " << size;
    // The blocked form, from an offset, and the stepped form.
    std::vector<std::atomic<int>> block_hits(size + 5);
    tbb::parallel_for(tbb::blocked_range<int>(5, size + 5), [&](const tbb::blocked_range<int>& r) {
      for (int i = r.begin(); i < r.end(); ++i) block_hits[i].fetch_add(1);
    });
    for (int i = 0; i < size + 5; ++i) ASSERT_EQ(block_hits[i].load(), i >= 5 ? 1 : 0) << i;
    std::vector<std::atomic<int>> step_hits(size);
    tbb::parallel_for(0, size, 3, [&](int i) { step_hits[i].fetch_add(1); });
    for (int i = 0; i < size; ++i) ASSERT_EQ(step_hits[i].load(), i % 3 == 0 ? 1 : 0) << i;
  }
}

TEST(WebShimThreadPool, UsesSeveralThreadsAndLoopsDoNotMix) {
  std::vector<std::thread::id> seen;
  std::mutex seen_mutex;
  for (int loop = 0; loop < 200; ++loop) {
    std::vector<int> out(64, -1);
    tbb::parallel_for(0, 64, [&](int i) {
      // Long enough that the pool's threads take chunks too.
      volatile double x = 0.0;
      for (int k = 0; k < 2000; ++k) x = x + k;
      out[i] = loop;
      std::lock_guard<std::mutex> lock(seen_mutex);
      if (std::find(seen.begin(), seen.end(), std::this_thread::get_id()) == seen.end()) {
        seen.push_back(std::this_thread::get_id());
      }
    });
    // Every chunk of this loop ended before parallel_for returned.
    for (int i = 0; i < 64; ++i) ASSERT_EQ(out[i], loop);
  }
  EXPECT_GT(seen.size(), 1u);
  EXPECT_LE(seen.size(), static_cast<std::size_t>(ATMO_WEB_SHIM_THREADS));
}

TEST(WebShimThreadPool, NestedLoopsRunInsideTheirChunk) {
  std::vector<std::atomic<int>> hits(40 * 30);
  tbb::parallel_for(0, 40, [&](int i) {
    tbb::parallel_for(0, 30, [&](int j) { hits[i * 30 + j].fetch_add(1); });
  });
  for (const std::atomic<int>& h : hits) ASSERT_EQ(h.load(), 1);
}

TEST(WebShimThreadPool, AnExceptionReachesTheCallerAfterTheLoop) {
  std::atomic<int> done{0};
  EXPECT_THROW(tbb::parallel_for(0, 100,
                                 [&](int i) {
                                   if (i == 37) throw std::runtime_error("bad index");
                                   done.fetch_add(1);
                                 }),
               std::runtime_error);
  // The other indices of the chunks that did not throw still ran, and the pool still works.
  EXPECT_GE(done.load(), 1);
  std::atomic<int> after{0};
  tbb::parallel_for(0, 100, [&](int) { after.fetch_add(1); });
  EXPECT_EQ(after.load(), 100);
}

TEST(WebShimThreadPool, PerThreadValuesCombine) {
  tbb::enumerable_thread_specific<std::vector<long>> partial;
  tbb::parallel_for(0, 10000, [&](int i) { partial.local().push_back(i); });
  long total = 0;
  std::size_t count = 0;
  partial.combine_each([&](const std::vector<long>& values) {
    total += std::accumulate(values.begin(), values.end(), 0L);
    count += values.size();
  });
  EXPECT_EQ(count, 10000u);
  EXPECT_EQ(total, 10000L * 9999L / 2);

  tbb::combinable<long> sums([] { return 0L; });
  tbb::parallel_for(0, 10000, [&](int i) { sums.local() += i; });
  EXPECT_EQ(sums.combine([](long a, long b) { return a + b; }), 10000L * 9999L / 2);
}

}  // namespace
