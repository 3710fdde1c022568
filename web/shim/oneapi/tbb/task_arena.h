// oneTBB's this_task_arena for the single-threaded WebAssembly build (web/CMakeLists.txt): one
// thread, and isolation is what one thread already has.
#pragma once

namespace oneapi::tbb::this_task_arena {

inline int max_concurrency() { return 1; }

template <typename F>
auto isolate(const F& f) -> decltype(f()) {
  return f();
}

}  // namespace oneapi::tbb::this_task_arena
