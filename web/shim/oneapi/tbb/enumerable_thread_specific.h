// oneTBB's enumerable_thread_specific for the WebAssembly builds (web/CMakeLists.txt): one value
// per thread of the loops (thread_pool.h; one in the single-threaded build), made on first use.
#pragma once

#include <optional>
#include <vector>

#include "oneapi/tbb/thread_pool.h"

namespace oneapi::tbb {

template <typename T>
class enumerable_thread_specific {
 public:
  enumerable_thread_specific() : values_(detail::Concurrency()) {}
  T& local() {
    std::optional<T>& value = values_[detail::ThreadIndex()];
    if (!value) value.emplace();
    return *value;
  }
  template <typename F>
  void combine_each(F f) {
    for (std::optional<T>& value : values_) {
      if (value) f(*value);
    }
  }

 private:
  std::vector<std::optional<T>> values_;
};

}  // namespace oneapi::tbb
