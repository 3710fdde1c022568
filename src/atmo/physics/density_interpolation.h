// The interpolation rule of tabulated densities (DensityProfile's tables, the standard
// atmospheres' levels, the aerosol profiles): exponential in altitude between two positive
// values, linear where one of them is 0.
#pragma once

#include <cmath>

namespace atmo {

// The density a fraction f of the way from a value a to a value b.
inline double InterpolateDensity(double a, double b, double f) {
  return a > 0.0 && b > 0.0 ? a * std::pow(b / a, f) : a + (b - a) * f;
}

// The integral of that interpolation over an interval of length dz from a to b.
inline double IntegrateDensity(double a, double b, double dz) {
  if (a > 0.0 && b > 0.0 && std::fabs(a - b) > 1e-12 * a) return dz * (b - a) / std::log(b / a);
  return 0.5 * (a + b) * dz;
}

}  // namespace atmo
