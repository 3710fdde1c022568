// What C++20 code of atmo's needs and the libc++ 14 of Debian's Emscripten 3.1.6 lacks:
// std::bit_cast (libc++ 15) and the floating-point std::to_chars and std::from_chars (libc++ 16
// and 20). Force-included into every translation unit of the WebAssembly build
// (web/CMakeLists.txt); a library that has them keeps its own.
#pragma once

#include <bit>
#include <charconv>
#include <cerrno>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <type_traits>

#if defined(_LIBCPP_VERSION)

#if !defined(__cpp_lib_bit_cast)
namespace std {
template <typename To, typename From>
  requires(sizeof(To) == sizeof(From) && is_trivially_copyable_v<To> && is_trivially_copyable_v<From>)
constexpr To bit_cast(const From& from) noexcept {
  return __builtin_bit_cast(To, from);
}
}  // namespace std
#endif

#if _LIBCPP_VERSION < 16000
namespace std {
// The shortest text that reads back as `value` (the fewest significant digits of %g that
// round-trip), as the standard's shortest form promises; %g's choice of fixed or scientific.
inline to_chars_result to_chars(char* first, char* last, double value) {
  char buffer[40];
  int length = 0;
  for (int precision = 1; precision <= 17; ++precision) {
    length = std::snprintf(buffer, sizeof buffer, "%.*g", precision, value);
    if (std::strtod(buffer, nullptr) == value) break;
  }
  if (length < 0 || length > last - first) return {last, errc::value_too_large};
  std::memcpy(first, buffer, static_cast<std::size_t>(length));
  return {first + length, errc{}};
}
}  // namespace std
#endif

#if _LIBCPP_VERSION < 20000
namespace std {
// strtod on a bounded copy, with from_chars's rules: no leading white space or '+'.
inline from_chars_result from_chars(const char* first, const char* last, double& value) {
  if (first == last || *first == '+' || *first == ' ' || *first == '\t' || *first == '\n' || last - first > 256) {
    return {first, errc::invalid_argument};
  }
  char buffer[260];
  std::memcpy(buffer, first, static_cast<std::size_t>(last - first));
  buffer[last - first] = '\0';
  char* end = nullptr;
  errno = 0;
  const double parsed = std::strtod(buffer, &end);
  if (end == buffer) return {first, errc::invalid_argument};
  if (errno == ERANGE) return {first + (end - buffer), errc::result_out_of_range};
  value = parsed;
  return {first + (end - buffer), errc{}};
}
}  // namespace std
#endif

#endif  // _LIBCPP_VERSION
