// oneTBB's this_task_arena for the WebAssembly builds (web/CMakeLists.txt): the loops' threads
// (thread_pool.h), and isolation, which the pool's nested loops have already (they run in order
// on their own thread).
#pragma once

#include "oneapi/tbb/thread_pool.h"

namespace oneapi::tbb::this_task_arena {

inline int max_concurrency() { return detail::Concurrency(); }

template <typename F>
auto isolate(const F& f) -> decltype(f()) {
  return f();
}

}  // namespace oneapi::tbb::this_task_arena
