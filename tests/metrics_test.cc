// The error metrics of include/atmo/metrics.h on vectors small enough to compute by hand.
#include <cmath>
#include <limits>
#include <vector>

#include <gtest/gtest.h>

#include "atmo/error.h"
#include "atmo/metrics.h"

namespace atmo {
namespace {

constexpr double kInf = std::numeric_limits<double>::infinity();
// Exact decimal fractions computed by hand; the gap is the rounding of a few double operations.
constexpr double kTolerance = 1e-12;

TEST(Metrics, RelativeErrorIsSignedAndRelativeToTheReference) {
  EXPECT_DOUBLE_EQ(RelativeError(3.0, 2.0), 0.5);
  EXPECT_DOUBLE_EQ(RelativeError(1.0, 2.0), -0.5);
  EXPECT_DOUBLE_EQ(RelativeError(2.0, 2.0), 0.0);
  EXPECT_DOUBLE_EQ(RelativeError(0.0, 0.0), 0.0);  // agreement on a zero reference
  EXPECT_EQ(RelativeError(1.0, 0.0), kInf);
  EXPECT_EQ(RelativeError(-1.0, 0.0), -kInf);
}

TEST(Metrics, ErrorInStandardErrorsCombinesBothErrors) {
  EXPECT_NEAR(ErrorInStandardErrors(1.1, 1.0, 0.03, 0.04), 2.0, kTolerance);  // 0.1 / hypot(0.03, 0.04)
  EXPECT_NEAR(ErrorInStandardErrors(0.9, 1.0, 0.0, 0.05), -2.0, kTolerance);
  EXPECT_TRUE(std::isnan(ErrorInStandardErrors(1.1, 1.0, 0.0, 0.0)));  // deterministic: no scale
}

TEST(Metrics, PercentileInterpolatesLinearlyBetweenClosestRanks) {
  const std::vector<double> values = {4.0, 1.0, 3.0, 2.0};  // unsorted on purpose
  // Sorted {1, 2, 3, 4}, position h = 3 p / 100.
  EXPECT_DOUBLE_EQ(Percentile(values, 0.0), 1.0);
  EXPECT_DOUBLE_EQ(Percentile(values, 50.0), 2.5);   // h = 1.5
  EXPECT_NEAR(Percentile(values, 95.0), 3.85, kTolerance);  // h = 2.85
  EXPECT_DOUBLE_EQ(Percentile(values, 100.0), 4.0);
  EXPECT_DOUBLE_EQ(Median(values), 2.5);

  const std::vector<double> five = {10.0, 20.0, 30.0, 40.0, 50.0};  // h = 4 p / 100
  EXPECT_DOUBLE_EQ(Percentile(five, 25.0), 20.0);                  // h = 1
  EXPECT_NEAR(Percentile(five, 90.0), 46.0, kTolerance);           // h = 3.6
  EXPECT_DOUBLE_EQ(Median(five), 30.0);

  EXPECT_DOUBLE_EQ(Percentile(std::vector<double>{7.0}, 95.0), 7.0);
  EXPECT_TRUE(std::isnan(Percentile(std::vector<double>{}, 50.0)));
  EXPECT_TRUE(std::isnan(Median(std::vector<double>{1.0, std::nan(""), 2.0})));
  EXPECT_THROW(Percentile(values, 101.0), Error);
  EXPECT_THROW(Percentile(values, -1.0), Error);
}

TEST(Metrics, PairedMetricsOnHandComputedVectors) {
  const std::vector<double> test = {1.1, 1.8, 3.0};
  const std::vector<double> reference = {1.0, 2.0, 3.0};
  // |e| = 0.1, 0.1, 0.
  EXPECT_NEAR(RelMae(test, reference), 0.2 / 3.0, kTolerance);
  EXPECT_NEAR(MaxRelativeError(test, reference), 0.1, kTolerance);
  // Differences 0.1, -0.2, 0: rmse = sqrt(0.05 / 3).
  EXPECT_NEAR(Rmse(test, reference), std::sqrt(0.05 / 3.0), kTolerance);

  // One error of 0.1 among four values, peak 1: mse = 0.0025, psnr = 20 log10(1 / 0.05).
  EXPECT_NEAR(Psnr(std::vector<double>{0.0, 0.5, 1.0, 0.9}, std::vector<double>{0.0, 0.5, 1.0, 1.0}),
              20.0 * std::log10(20.0), 1e-9);
  EXPECT_EQ(Psnr(reference, reference), kInf);
  EXPECT_DOUBLE_EQ(RelMae(reference, reference), 0.0);
  EXPECT_DOUBLE_EQ(Rmse(reference, reference), 0.0);

  EXPECT_THROW(RelMae(test, std::vector<double>{1.0}), Error);
  EXPECT_THROW(Rmse(test, std::vector<double>{1.0}), Error);
  EXPECT_TRUE(std::isnan(RelMae(std::vector<double>{}, std::vector<double>{})));
}

TEST(Metrics, SummaryOfRelativeErrors) {
  const std::vector<double> errors = {-0.1, 0.2, -0.3, 0.4};
  const RelativeErrorSummary s = SummarizeRelativeErrors(errors);
  // |e| sorted {0.1, 0.2, 0.3, 0.4}.
  EXPECT_EQ(s.count, 4u);
  EXPECT_NEAR(s.median_abs, 0.25, kTolerance);
  EXPECT_NEAR(s.p95_abs, 0.385, kTolerance);  // h = 2.85: 0.3 + 0.85 * 0.1
  EXPECT_NEAR(s.max_abs, 0.4, kTolerance);
  EXPECT_NEAR(s.rel_mae, 0.25, kTolerance);
  EXPECT_NEAR(s.mean, 0.05, kTolerance);

  const RelativeErrorSummary empty = SummarizeRelativeErrors({});
  EXPECT_EQ(empty.count, 0u);
  EXPECT_TRUE(std::isnan(empty.median_abs));
  EXPECT_TRUE(std::isnan(empty.max_abs));
}

TEST(Metrics, SummaryAgreesWithThePairedMetrics) {
  const std::vector<double> test = {0.5, 2.2, 2.9, 4.4, 5.0};
  const std::vector<double> reference = {0.4, 2.0, 3.0, 4.0, 5.5};
  std::vector<double> errors;
  for (std::size_t i = 0; i < test.size(); ++i) errors.push_back(RelativeError(test[i], reference[i]));
  const RelativeErrorSummary s = SummarizeRelativeErrors(errors);
  EXPECT_NEAR(s.rel_mae, RelMae(test, reference), kTolerance);
  EXPECT_NEAR(s.max_abs, MaxRelativeError(test, reference), kTolerance);
}

}  // namespace
}  // namespace atmo
