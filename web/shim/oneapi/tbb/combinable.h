// oneTBB's combinable for the single-threaded WebAssembly build (web/CMakeLists.txt): one
// thread, one value.
#pragma once

#include <functional>
#include <optional>

namespace oneapi::tbb {

template <typename T>
class combinable {
 public:
  combinable() = default;
  template <typename Init>
  explicit combinable(Init init) : init_(std::move(init)) {}
  T& local() {
    if (!value_) value_.emplace(init_ ? init_() : T{});
    return *value_;
  }
  template <typename F>
  T combine(F f) {
    (void)f;
    return value_ ? *value_ : (init_ ? init_() : T{});
  }
  template <typename F>
  void combine_each(F f) {
    if (value_) f(*value_);
  }

 private:
  std::function<T()> init_;
  std::optional<T> value_;
};

}  // namespace oneapi::tbb
