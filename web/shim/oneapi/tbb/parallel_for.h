// oneTBB's parallel_for as the single-threaded WebAssembly build runs it (web/CMakeLists.txt):
// the whole range on the calling thread, in order. Same results as the threaded loop, since atmo's
// loops write disjoint outputs.
#pragma once

#include <type_traits>

#include "oneapi/tbb/blocked_range.h"

namespace oneapi::tbb {

template <typename Range, typename Body>
void parallel_for(const Range& range, const Body& body) {
  if (!range.empty()) body(range);
}

template <typename Index, typename Body>
  requires std::is_integral_v<Index>
void parallel_for(Index first, Index last, const Body& body) {
  for (Index i = first; i < last; ++i) body(i);
}

template <typename Index, typename Body>
  requires std::is_integral_v<Index>
void parallel_for(Index first, Index last, Index step, const Body& body) {
  for (Index i = first; i < last; i += step) body(i);
}

}  // namespace oneapi::tbb
