// oneTBB's enumerable_thread_specific for the single-threaded WebAssembly build
// (web/CMakeLists.txt): one thread, one value, made on first use.
#pragma once

#include <optional>

namespace oneapi::tbb {

template <typename T>
class enumerable_thread_specific {
 public:
  T& local() {
    if (!value_) value_.emplace();
    return *value_;
  }
  template <typename F>
  void combine_each(F f) {
    if (value_) f(*value_);
  }

 private:
  std::optional<T> value_;
};

}  // namespace oneapi::tbb
