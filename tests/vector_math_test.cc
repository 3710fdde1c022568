// The inline elementary functions of the vectorised kernels (src/atmo/cpu/vector_math.h) against
// the C library's, over the ranges the kernels feed them.
#include "cpu/vector_math.h"

#include <algorithm>
#include <cmath>
#include <limits>

#include <gtest/gtest.h>

namespace atmo::cpu {
namespace {

TEST(VectorMath, ExpFloatIsWithinItsStatedErrorOfExp) {
  // Relative error < 1e-7 on [-87, 20] beside float rounding of the result (6e-8).
  double largest = 0.0;
  for (int i = 0; i <= 100000; ++i) {
    const float x = static_cast<float>(-87.0 + 107.0 * i / 100000.0);
    const double expected = std::exp(static_cast<double>(x));
    largest = std::max(largest, std::abs(ExpFloat(x) - expected) / expected);
  }
  EXPECT_LT(largest, 1.7e-7);
  // Clamped (the tables' logarithms never go below ln 1e-30), and NaN maps to exp(-87).
  EXPECT_FLOAT_EQ(ExpFloat(-1000.0f), ExpFloat(-87.0f));
  EXPECT_FLOAT_EQ(ExpFloat(std::numeric_limits<float>::quiet_NaN()), ExpFloat(-87.0f));
}

}  // namespace
}  // namespace atmo::cpu
