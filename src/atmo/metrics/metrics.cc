// The error metrics of include/atmo/metrics.h; each formula is stated there, once.
#include "atmo/metrics.h"

#include <algorithm>
#include <cmath>
#include <limits>
#include <string>
#include <vector>

#include "atmo/error.h"

namespace atmo {

namespace {

constexpr double kNaN = std::numeric_limits<double>::quiet_NaN();

void CheckSameSize(std::span<const double> test, std::span<const double> reference, const char* metric) {
  if (test.size() != reference.size()) {
    throw Error(std::string(metric) + ": " + std::to_string(test.size()) + " test values against " +
                std::to_string(reference.size()) + " reference values");
  }
}

// Percentile of values already sorted ascending (type 7, see the header).
double SortedPercentile(const std::vector<double>& sorted, double p) {
  if (sorted.empty()) return kNaN;
  const double h = static_cast<double>(sorted.size() - 1) * p / 100.0;
  const std::size_t lower = static_cast<std::size_t>(std::floor(h));
  if (lower + 1 >= sorted.size()) return sorted.back();
  return sorted[lower] + (h - static_cast<double>(lower)) * (sorted[lower + 1] - sorted[lower]);
}

void CheckPercentile(double p) {
  if (!(p >= 0.0 && p <= 100.0)) throw Error("percentile " + std::to_string(p) + " is outside [0, 100]");
}

}  // namespace

double RelativeError(double test, double reference) {
  if (reference == 0.0) {
    if (test == 0.0) return 0.0;
    return test > 0.0 ? std::numeric_limits<double>::infinity() : -std::numeric_limits<double>::infinity();
  }
  return (test - reference) / reference;
}

double ErrorInStandardErrors(double test, double reference, double test_standard_error,
                             double reference_standard_error) {
  const double combined = std::hypot(test_standard_error, reference_standard_error);
  if (!(combined > 0.0)) return kNaN;
  return (test - reference) / combined;
}

double Percentile(std::span<const double> values, double p) {
  CheckPercentile(p);
  std::vector<double> sorted(values.begin(), values.end());
  if (std::any_of(sorted.begin(), sorted.end(), [](double v) { return std::isnan(v); })) return kNaN;
  std::sort(sorted.begin(), sorted.end());
  return SortedPercentile(sorted, p);
}

double Median(std::span<const double> values) { return Percentile(values, 50.0); }

double RelMae(std::span<const double> test, std::span<const double> reference) {
  CheckSameSize(test, reference, "rel_mae");
  if (test.empty()) return kNaN;
  double sum = 0.0;
  for (std::size_t i = 0; i < test.size(); ++i) sum += std::abs(RelativeError(test[i], reference[i]));
  return sum / static_cast<double>(test.size());
}

double MaxRelativeError(std::span<const double> test, std::span<const double> reference) {
  CheckSameSize(test, reference, "max relative error");
  if (test.empty()) return kNaN;
  double worst = 0.0;
  for (std::size_t i = 0; i < test.size(); ++i) {
    const double e = std::abs(RelativeError(test[i], reference[i]));
    if (std::isnan(e)) return kNaN;
    worst = std::max(worst, e);
  }
  return worst;
}

double Rmse(std::span<const double> test, std::span<const double> reference) {
  CheckSameSize(test, reference, "rmse");
  if (test.empty()) return kNaN;
  double sum = 0.0;
  for (std::size_t i = 0; i < test.size(); ++i) sum += (test[i] - reference[i]) * (test[i] - reference[i]);
  return std::sqrt(sum / static_cast<double>(test.size()));
}

double Psnr(std::span<const double> test, std::span<const double> reference) {
  CheckSameSize(test, reference, "psnr");
  if (test.empty()) return kNaN;
  const double peak = *std::max_element(reference.begin(), reference.end());
  const double rmse = Rmse(test, reference);
  if (rmse == 0.0) return std::numeric_limits<double>::infinity();
  return 20.0 * std::log10(peak / rmse);
}

RelativeErrorSummary SummarizeRelativeErrors(std::span<const double> relative_errors) {
  RelativeErrorSummary summary;
  summary.count = relative_errors.size();
  if (relative_errors.empty()) {
    summary.median_abs = summary.p95_abs = summary.max_abs = summary.rel_mae = summary.mean = kNaN;
    return summary;
  }
  if (std::any_of(relative_errors.begin(), relative_errors.end(), [](double e) { return std::isnan(e); })) {
    summary.median_abs = summary.p95_abs = summary.max_abs = summary.rel_mae = summary.mean = kNaN;
    return summary;
  }
  std::vector<double> magnitudes;
  magnitudes.reserve(relative_errors.size());
  double sum = 0.0;
  double sum_abs = 0.0;
  for (double e : relative_errors) {
    magnitudes.push_back(std::abs(e));
    sum += e;
    sum_abs += std::abs(e);
  }
  std::sort(magnitudes.begin(), magnitudes.end());
  summary.median_abs = SortedPercentile(magnitudes, 50.0);
  summary.p95_abs = SortedPercentile(magnitudes, 95.0);
  summary.max_abs = magnitudes.back();
  // Same as RelMae over the underlying values: mean |e_i|.
  summary.rel_mae = sum_abs / static_cast<double>(relative_errors.size());
  summary.mean = sum / static_cast<double>(relative_errors.size());
  return summary;
}

}  // namespace atmo
