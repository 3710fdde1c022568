// The part of oneTBB's blocked_range that atmo uses, for the WebAssembly builds
// (web/CMakeLists.txt): a range is only its bounds (parallel_for.h cuts it into chunks itself).
#pragma once

#include <cstddef>

namespace oneapi::tbb {

template <typename Value>
class blocked_range {
 public:
  using const_iterator = Value;
  blocked_range(Value begin, Value end, std::size_t grainsize = 1) : begin_(begin), end_(end) {
    (void)grainsize;
  }
  Value begin() const { return begin_; }
  Value end() const { return end_; }
  std::size_t size() const { return static_cast<std::size_t>(end_ - begin_); }
  bool empty() const { return !(begin_ < end_); }

 private:
  Value begin_;
  Value end_;
};

}  // namespace oneapi::tbb
