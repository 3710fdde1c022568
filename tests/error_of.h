// The one-line message of the atmo::Error that f() throws, or "" when it throws none: what the
// tests compare error messages with.
#pragma once

#include <string>

#include "atmo/error.h"

namespace atmo::testing {

template <typename F>
std::string ErrorOf(const F& f) {
  try {
    f();
  } catch (const Error& e) {
    return e.what();
  }
  return "";
}

}  // namespace atmo::testing
