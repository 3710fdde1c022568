// oneTBB's combinable for the WebAssembly builds (web/CMakeLists.txt): one value per thread of
// the loops (thread_pool.h; one in the single-threaded build).
#pragma once

#include <functional>
#include <optional>
#include <vector>

#include "oneapi/tbb/thread_pool.h"

namespace oneapi::tbb {

template <typename T>
class combinable {
 public:
  combinable() : values_(detail::Concurrency()) {}
  template <typename Init>
  explicit combinable(Init init) : init_(std::move(init)), values_(detail::Concurrency()) {}
  T& local() {
    std::optional<T>& value = values_[detail::ThreadIndex()];
    if (!value) value.emplace(init_ ? init_() : T{});
    return *value;
  }
  template <typename F>
  T combine(F f) {
    std::optional<T> result;
    for (std::optional<T>& value : values_) {
      if (value) result = result ? f(*result, *value) : *value;
    }
    return result ? *result : (init_ ? init_() : T{});
  }
  template <typename F>
  void combine_each(F f) {
    for (std::optional<T>& value : values_) {
      if (value) f(*value);
    }
  }

 private:
  std::function<T()> init_;
  std::vector<std::optional<T>> values_;
};

}  // namespace oneapi::tbb
