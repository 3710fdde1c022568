// oneTBB's parallel_for for the WebAssembly builds (web/CMakeLists.txt): the range cut into about
// four chunks per thread of the pool (thread_pool.h), or, in the single-threaded build, the whole
// range on the calling thread, in order. atmo's loops write disjoint outputs, so the results do not
// depend on the chunks.
#pragma once

#include <algorithm>
#include <type_traits>

#include "oneapi/tbb/blocked_range.h"
#include "oneapi/tbb/thread_pool.h"

namespace oneapi::tbb {

template <typename Value, typename Body>
void parallel_for(const blocked_range<Value>& range, const Body& body) {
  if (range.empty()) return;
  const long long size = static_cast<long long>(range.size());
  const int threads = detail::Concurrency();
  if (threads == 1) {
    body(range);
    return;
  }
  const long long grain = std::max<long long>(1, size / (4LL * threads));
  const int chunks = static_cast<int>((size + grain - 1) / grain);
  detail::Run(chunks, [&](int k) {
    const Value begin = range.begin() + static_cast<Value>(k * grain);
    const Value end = range.begin() + static_cast<Value>(std::min<long long>(size, (k + 1) * grain));
    body(blocked_range<Value>(begin, end));
  });
}

template <typename Index, typename Body>
  requires std::is_integral_v<Index>
void parallel_for(Index first, Index last, const Body& body) {
  parallel_for(blocked_range<Index>(first, last), [&](const blocked_range<Index>& r) {
    for (Index i = r.begin(); i < r.end(); ++i) body(i);
  });
}

template <typename Index, typename Body>
  requires std::is_integral_v<Index>
void parallel_for(Index first, Index last, Index step, const Body& body) {
  if (!(first < last)) return;
  const Index count = (last - first + step - 1) / step;
  parallel_for(Index(0), count, [&](Index k) { body(first + k * step); });
}

}  // namespace oneapi::tbb
