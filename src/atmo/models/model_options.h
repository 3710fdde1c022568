// Helpers every model uses to read its options and check its inputs (private).
#pragma once

#include <chrono>
#include <string>

#include <glm/glm.hpp>

namespace atmo {

// An integer option value in [lo, hi]; throws atmo::Error "option key=value: expected ...".
int ParseIntOption(const std::string& key, const std::string& value, int lo, int hi);
// A finite floating-point option value in [lo, hi].
double ParseDoubleOption(const std::string& key, const std::string& value, double lo, double hi);
// A table size "WxH", or "N" for N x N, each side in [lo, hi].
glm::ivec2 ParseSizeOption(const std::string& key, const std::string& value, int lo, int hi);
// Throws atmo::Error unless `v` is finite and non-zero; `what` names it in the message.
void CheckDirection(const glm::dvec3& v, const char* what);

// Milliseconds since `start` (for Model::RecordPass).
inline double MillisecondsSince(std::chrono::steady_clock::time_point start) {
  return std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - start).count();
}

}  // namespace atmo
