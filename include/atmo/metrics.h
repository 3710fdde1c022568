// The named error metrics of atmo, defined once and used everywhere: `atmo compare`, the tests
// and the viewer (docs/accuracy.md, "How `atmo compare` works").
//
// To use it:
//   double e = atmo::RelativeError(model_radiance, reference_radiance);      // signed, (M - R) / R
//   double mae = atmo::RelMae(model_values, reference_values);               // mean |(M - R) / R|
//   atmo::RelativeErrorSummary s = atmo::SummarizeRelativeErrors(errors);    // median, p95, max, ...
//
// Conventions: `test` is the value under test (M), `reference` the value it is judged against (R).
// Span arguments that pair test and reference values must have the same length (atmo::Error
// otherwise). Statistics of an empty set are NaN (counts are 0). NaN inputs propagate.
#pragma once

#include <cstddef>
#include <span>
#include <string_view>

namespace atmo {

// Signed relative error e = (M - R) / R. A reference of 0 gives 0 when M is 0 too (exact
// agreement) and +-infinity otherwise: relative statistics should leave such points out (as
// `atmo compare` does below its floor) rather than average infinities.
double RelativeError(double test, double reference);

// The error in units of the combined standard error of a Monte Carlo estimate:
// z = (M - R) / sqrt(se_M^2 + se_R^2). NaN when both standard errors are 0 (deterministic values
// have no such scale). For an unbiased estimator |z| is below 2 for about 95 % of the points.
double ErrorInStandardErrors(double test, double reference, double test_standard_error,
                             double reference_standard_error);

// Percentile p in [0, 100] of `values` (not necessarily sorted; NaN for an empty set), by linear
// interpolation between closest ranks (Hyndman & Fan type 7, the default of NumPy and R): with
// the n values sorted ascending as v[0..n-1], the position is h = (n - 1) p / 100 and the result
// v[floor(h)] + (h - floor(h)) (v[floor(h) + 1] - v[floor(h)]). p = 0 gives the minimum, p = 100
// the maximum; {1, 2, 3, 4} has median 2.5 and p95 3.85. Throws atmo::Error for p outside [0, 100].
double Percentile(std::span<const double> values, double p);
// Percentile(values, 50).
double Median(std::span<const double> values);

// rel_mae, the mean absolute relative error: (1/n) sum_i |M_i - R_i| / |R_i|.
double RelMae(std::span<const double> test, std::span<const double> reference);
// The largest absolute relative error: max_i |M_i - R_i| / |R_i|.
double MaxRelativeError(std::span<const double> test, std::span<const double> reference);
// rmse, the root mean square error in the values' own unit: sqrt((1/n) sum_i (M_i - R_i)^2).
double Rmse(std::span<const double> test, std::span<const double> reference);
// PSNR in dB on linear (HDR) values: 10 log10(peak^2 / mse), mse = rmse^2, with the peak the
// largest reference value (not 1, and not on tone-mapped values). +infinity for identical inputs.
double Psnr(std::span<const double> test, std::span<const double> reference);

// The statistics `atmo compare` reports for a set of signed relative errors e_i.
struct RelativeErrorSummary {
  std::size_t count = 0;  // n, the number of errors summarised
  double median_abs = 0;  // Median(|e_i|)
  double p95_abs = 0;     // Percentile(|e_i|, 95)
  double max_abs = 0;     // max |e_i|
  double rel_mae = 0;     // mean |e_i|: RelMae of the underlying values
  double mean = 0;        // mean e_i, signed: the bias (negative: the model is too dark)
};
// Summarises signed relative errors (as RelativeError returns them). Empty: count 0, the rest NaN.
RelativeErrorSummary SummarizeRelativeErrors(std::span<const double> relative_errors);

// The names of the metrics as written in tool output and JSON keys, in one place.
namespace metric_names {
inline constexpr std::string_view kRelativeError = "relative_error";
inline constexpr std::string_view kErrorInStandardErrors = "error_in_stderr";
inline constexpr std::string_view kMedianAbs = "median_abs";
inline constexpr std::string_view kP95Abs = "p95_abs";
inline constexpr std::string_view kMaxAbs = "max_abs";
inline constexpr std::string_view kRelMae = "rel_mae";
inline constexpr std::string_view kMean = "mean";
inline constexpr std::string_view kRmse = "rmse";
inline constexpr std::string_view kPsnr = "psnr_db";
}  // namespace metric_names

}  // namespace atmo
