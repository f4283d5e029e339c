// Loop period statistics (src/hof/haptics/period_stats.cpp): 1 µs bins to the nearest
// microsecond, quantiles, mean and rate, overruns, what is ignored and what saturates.

#include "hof/haptics/period_stats.h"

#include <gtest/gtest.h>

#include <cmath>
#include <limits>

namespace hof::haptics {
namespace {

TEST(PeriodStats, EmptyStatisticsAreZero) {
  const PeriodStats stats;
  EXPECT_EQ(stats.count(), 0u);
  EXPECT_EQ(stats.quantile_s(0.5), 0.0);
  EXPECT_EQ(stats.mean_s(), 0.0);
  EXPECT_EQ(stats.rate_hz(), 0.0);
  EXPECT_EQ(stats.nominal_s(), 1e-3);
  EXPECT_EQ(stats.bins().size(), 20000u);  // 1 µs bins up to 20 ms
}

TEST(PeriodStats, QuantilesMeanRateAndMaxOfKnownPeriods) {
  PeriodStats stats(1e-4);
  for (int us = 1; us <= 100; ++us) stats.record(us * 1e-6, us > 95);
  EXPECT_EQ(stats.count(), 100u);
  EXPECT_EQ(stats.overruns(), 5u);
  EXPECT_NEAR(stats.quantile_s(0.5), 50e-6, 1e-12);
  EXPECT_NEAR(stats.quantile_s(0.99), 99e-6, 1e-12);
  EXPECT_NEAR(stats.quantile_s(0.0), 1e-6, 1e-12);  // the smallest
  EXPECT_NEAR(stats.quantile_s(1.0), 100e-6, 1e-12);
  EXPECT_NEAR(stats.quantile_s(7.0), 100e-6, 1e-12);  // q clamped to [0, 1]
  EXPECT_NEAR(stats.max_s(), 100e-6, 1e-18);
  EXPECT_NEAR(stats.mean_s(), 50.5e-6, 1e-15);
  EXPECT_NEAR(stats.rate_hz(), 1.0 / 50.5e-6, 1e-6);
}

TEST(PeriodStats, APeriodIsBinnedToTheNearestMicrosecond) {
  PeriodStats stats;
  stats.record(0.001 - 1e-12, false);  // 1 ms as a difference of clock readings
  stats.record(0.0010004, false);
  stats.record(0.0010006, false);
  EXPECT_EQ(stats.bins()[1000], 2u);
  EXPECT_EQ(stats.bins()[1001], 1u);
  EXPECT_EQ(stats.bins()[999], 0u);
}

TEST(PeriodStats, NegativeAndNaNPeriodsAreIgnoredAndLongOnesSaturate) {
  PeriodStats stats;
  stats.record(-1e-3, true);
  stats.record(std::numeric_limits<double>::quiet_NaN(), true);
  EXPECT_EQ(stats.count(), 0u);
  EXPECT_EQ(stats.overruns(), 0u);
  stats.record(0.5, true);  // a half-second stall
  EXPECT_EQ(stats.count(), 1u);
  EXPECT_EQ(stats.bins().back(), 1u);
  EXPECT_EQ(stats.max_s(), 0.5);  // the maximum keeps the real value
  EXPECT_LE(stats.quantile_s(1.0), stats.max_s());
  EXPECT_NEAR(stats.quantile_s(1.0), 19999e-6, 1e-12);  // quantiles end with the histogram
}

TEST(PeriodStats, ClearStartsOver) {
  PeriodStats stats;
  for (int i = 0; i < 10; ++i) stats.record(1e-3, true);
  stats.clear();
  EXPECT_EQ(stats.count(), 0u);
  EXPECT_EQ(stats.overruns(), 0u);
  EXPECT_EQ(stats.max_s(), 0.0);
  EXPECT_EQ(stats.mean_s(), 0.0);
  EXPECT_EQ(stats.bins()[1000], 0u);
  stats.record(2e-3, false);
  EXPECT_NEAR(stats.quantile_s(0.5), 2e-3, 1e-15);
}

}  // namespace
}  // namespace hof::haptics
