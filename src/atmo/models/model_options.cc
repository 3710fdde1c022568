#include "models/model_options.h"

#include <cmath>
#include <cstdlib>

#include "atmo/error.h"

namespace atmo {

int ParseIntOption(const std::string& key, const std::string& value, int lo, int hi) {
  char* end = nullptr;
  const long v = std::strtol(value.c_str(), &end, 10);
  if (value.empty() || *end != '\0' || v < lo || v > hi) {
    throw Error("option " + key + "=" + value + ": expected an integer in [" + std::to_string(lo) + ", " +
                std::to_string(hi) + "]");
  }
  return static_cast<int>(v);
}

double ParseDoubleOption(const std::string& key, const std::string& value, double lo, double hi) {
  char* end = nullptr;
  const double v = std::strtod(value.c_str(), &end);
  if (value.empty() || *end != '\0' || !std::isfinite(v) || v < lo || v > hi) {
    throw Error("option " + key + "=" + value + ": expected a number in [" + std::to_string(lo) + ", " +
                std::to_string(hi) + "]");
  }
  return v;
}

glm::ivec2 ParseSizeOption(const std::string& key, const std::string& value, int lo, int hi) {
  const std::size_t x = value.find('x');
  if (x == std::string::npos) {
    const int n = ParseIntOption(key, value, lo, hi);
    return {n, n};
  }
  return {ParseIntOption(key, value.substr(0, x), lo, hi), ParseIntOption(key, value.substr(x + 1), lo, hi)};
}

void CheckDirection(const glm::dvec3& v, const char* what) {
  if (!std::isfinite(v.x) || !std::isfinite(v.y) || !std::isfinite(v.z) || glm::length(v) == 0.0) {
    throw Error(std::string(what) + " must be a finite, non-zero direction");
  }
}

}  // namespace atmo
