// atmo::Error: the one exception type of the library.
//
// To use it: catch `atmo::Error` around any library call that reads user input (parameters,
// files, options); `what()` is a single line meant for the user, naming the offending value.
#pragma once

#include <stdexcept>
#include <string>

namespace atmo {

class Error : public std::runtime_error {
 public:
  explicit Error(const std::string& message) : std::runtime_error(message) {}
};

}  // namespace atmo
