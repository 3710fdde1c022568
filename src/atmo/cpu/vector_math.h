// Elementary functions for the CPU kernels' vectorised loops (private): branch-free, inline
// versions that a compiler can vectorise wherever the loop is, on every target (WebAssembly
// included, which has no vector libm).
#pragma once

#include <bit>
#include <cmath>

namespace atmo::cpu {

// exp in float, for values read from float tables: Cody-Waite reduction to |r| <= ln(2) / 2 and
// Cephes' degree-7 polynomial, relative error < 1e-7 on [-87, 20]. Arguments are clamped to
// [-87, 88] (the tables' logarithms are >= ln 1e-30 = -69); NaN gives exp(-87).
inline float ExpFloat(float x) {
  x = !(x > -87.0f) ? -87.0f : (x < 88.0f ? x : 88.0f);
  const float n = std::floor(x * 1.44269504088896341f + 0.5f);
  const float r = (x - n * 0.693359375f) + n * 2.12194440e-4f;
  float p = 1.9875691500e-4f;
  p = p * r + 1.3981999507e-3f;
  p = p * r + 8.3334519073e-3f;
  p = p * r + 4.1665795894e-2f;
  p = p * r + 1.6666665459e-1f;
  p = p * r + 5.0000001201e-1f;
  p = p * r * r + r + 1.0f;
  return p * std::bit_cast<float>((static_cast<int>(n) + 127) << 23);
}

}  // namespace atmo::cpu
