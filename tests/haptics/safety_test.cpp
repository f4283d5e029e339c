// The last stage before the device (src/hof/haptics/safety.cpp): the force limit holds whatever
// comes in (NaN, infinities, overflowing magnitudes, nonsense time steps and limits), a fault
// zeroes the request, the fades and the slew limit move the force by exactly the amounts the
// configuration gives, and the counters say what happened.

#include "hof/haptics/safety.h"

#include <gtest/gtest.h>

#include <cmath>
#include <limits>
#include <random>

namespace hof::haptics {
namespace {

constexpr double kNaN = std::numeric_limits<double>::quiet_NaN();
constexpr double kInf = std::numeric_limits<double>::infinity();
constexpr double kDt = 1e-3;
using Reading = SafetyFilter::Reading;

DeviceSpec device(double max_force_n = 8.0, double max_rate_n_per_s = 1e12) {
  DeviceSpec spec;
  spec.max_force_n = max_force_n;
  spec.max_force_rate_n_per_s = max_rate_n_per_s;
  return spec;
}

// No fade in, no slew to speak of: what goes in comes out (below the limit).
SafetyConfig immediate() {
  SafetyConfig config;
  config.fade_in_s = 0.0;
  return config;
}

Vec3 tick(SafetyFilter& filter, const Vec3& requested, Reading reading = Reading::kValid, double age_s = 0.0,
          bool overrunning = false, double dt = kDt) {
  return filter.filter(requested, reading, age_s, overrunning, dt);
}

TEST(SafetyFilter, TheForceLimitHoldsWhateverTheInput) {
  std::mt19937_64 rng(36);
  std::uniform_real_distribution<double> unit(-1.0, 1.0);
  std::uniform_real_distribution<double> exponent(-6.0, 300.0);
  std::uniform_int_distribution<int> pick(0, 9);
  const auto component = [&]() -> double {
    switch (pick(rng)) {
      case 0:
        return kNaN;
      case 1:
        return pick(rng) < 5 ? kInf : -kInf;
      case 2:
        return 0.0;
      default:
        return unit(rng) * std::pow(10.0, exponent(rng));
    }
  };
  const auto odd_value = [&]() -> double {
    switch (pick(rng)) {
      case 0:
        return kNaN;
      case 1:
        return kInf;
      case 2:
        return -1.0;
      case 3:
        return 0.0;
      case 4:
        return 1e9;
      default:
        return std::abs(unit(rng)) * 20.0;
    }
  };
  for (const double device_rate : {0.0, 2000.0, 1e12}) {
    for (const double device_limit : {3.3, 8.0, 40.0}) {
      SafetyConfig config;
      config.fade_in_s = pick(rng) < 3 ? 0.0 : 0.05;
      config.fade_out_s = pick(rng) < 3 ? 0.0 : 0.05;
      SafetyFilter filter(device(device_limit, device_rate), config);
      for (int i = 0; i < 20000; ++i) {
        if (i % 1000 == 0) filter.set_max_force(odd_value());
        if (i % 7000 == 0) filter.reset();
        const Vec3 requested(component(), component(), component());
        const Reading reading = pick(rng) == 0   ? Reading::kMissing
                                : pick(rng) == 0 ? Reading::kNonFinite
                                                 : Reading::kValid;
        const double age = pick(rng) == 0 ? odd_value() : 0.01;
        const double dt = pick(rng) == 0 ? odd_value() : kDt;
        const Vec3 f = filter.filter(requested, reading, age, pick(rng) == 0, dt);
        ASSERT_TRUE(f.allFinite()) << "tick " << i << " requested " << requested.transpose();
        ASSERT_LE(f.norm(), filter.force_limit_n()) << "tick " << i << " requested " << requested.transpose();
        ASSERT_LE(filter.force_limit_n(), device_limit);
        ASSERT_GT(filter.force_limit_n(), 0.0);
        ASSERT_EQ(f, filter.last_force());
        ASSERT_GE(filter.gain(), 0.0);
        ASSERT_LE(filter.gain(), 1.0);
      }
    }
  }
}

TEST(SafetyFilter, AForceAboveTheLimitIsScaledDownKeepingItsDirection) {
  SafetyFilter filter(device(8.0), immediate());
  const Vec3 requested(30.0, -40.0, 0.0);  // 50 N
  const Vec3 f = tick(filter, requested);
  EXPECT_LE(f.norm(), 8.0);
  EXPECT_NEAR(f.norm(), 8.0, 1e-12);
  EXPECT_NEAR(f.normalized().dot(requested.normalized()), 1.0, 1e-15);
  EXPECT_EQ(filter.counters().clamped, 1u);
  // Below the limit: untouched.
  EXPECT_EQ(tick(filter, Vec3(1.0, 2.0, -3.0)), Vec3(1.0, 2.0, -3.0));
  EXPECT_EQ(filter.counters().clamped, 1u);
}

TEST(SafetyFilter, AConfiguredLimitBelowTheDevicesHoldsAndNonsenseMeansTheDevices) {
  SafetyConfig config = immediate();
  config.max_force_n = 2.0;
  SafetyFilter filter(device(8.0), config);
  EXPECT_EQ(filter.force_limit_n(), 2.0);
  EXPECT_NEAR(tick(filter, Vec3(0, 0, 5.0)).z(), 2.0, 1e-12);
  filter.set_max_force(20.0);  // above the device's: the device's
  EXPECT_EQ(filter.force_limit_n(), 8.0);
  for (const double nonsense : {0.0, -1.0, kNaN, kInf}) {
    filter.set_max_force(nonsense);
    EXPECT_EQ(filter.force_limit_n(), 8.0) << nonsense;
  }
  filter.set_max_force(0.5);
  EXPECT_EQ(filter.force_limit_n(), 0.5);
}

TEST(SafetyFilter, TheForceFadesInLinearlyOverFadeInSeconds) {
  SafetyConfig config;
  config.fade_in_s = 0.5;
  SafetyFilter filter(device(), config);
  const Vec3 requested(0.0, 3.0, -4.0);
  EXPECT_EQ(filter.gain(), 0.0);
  Vec3 f;
  for (int i = 1; i <= 100; ++i) f = tick(filter, requested);
  EXPECT_NEAR(filter.gain(), 100 * kDt / 0.5, 1e-12);  // 0.2
  EXPECT_LT((f - 0.2 * requested).norm(), 1e-11);
  for (int i = 101; i <= 510; ++i) f = tick(filter, requested);
  EXPECT_EQ(filter.gain(), 1.0);  // capped at 1
  EXPECT_EQ(f, requested);
}

TEST(SafetyFilter, ANonFiniteRequestOrReadingGivesZeroForceAndFadesOut) {
  SafetyFilter filter(device(), immediate());
  ASSERT_EQ(tick(filter, Vec3(1, 1, 1)), Vec3(1, 1, 1));
  EXPECT_EQ(tick(filter, Vec3(kNaN, 0, 0)), Vec3::Zero());
  EXPECT_EQ(tick(filter, Vec3(0, kInf, 0)), Vec3::Zero());
  EXPECT_EQ(tick(filter, Vec3(1, 1, 1), Reading::kNonFinite), Vec3::Zero());
  EXPECT_EQ(filter.counters().non_finite, 3u);
  EXPECT_EQ(filter.counters().no_reading, 0u);
  // Each fault took fade_out's share of the gain: 1 − 3 · (1 ms / 50 ms).
  EXPECT_NEAR(filter.gain(), 1.0 - 3 * kDt / 0.05, 1e-12);
}

TEST(SafetyFilter, AMissingReadingGivesZeroForceCountedApart) {
  SafetyFilter filter(device(), immediate());
  tick(filter, Vec3(2, 0, 0));
  EXPECT_EQ(tick(filter, Vec3(2, 0, 0), Reading::kMissing), Vec3::Zero());
  EXPECT_EQ(filter.counters().no_reading, 1u);
  EXPECT_EQ(filter.counters().non_finite, 0u);
  EXPECT_EQ(filter.counters().watchdog, 0u);
}

TEST(SafetyFilter, AfterAFaultTheForceComesBackAtTheFadeInRateNotAtOnce) {
  SafetyConfig config;
  config.fade_in_s = 0.1;
  config.fade_out_s = 0.01;
  SafetyFilter filter(device(), config);
  const Vec3 requested(0, 0, 2.0);
  for (int i = 0; i < 200; ++i) tick(filter, requested);
  ASSERT_EQ(filter.gain(), 1.0);
  for (int i = 0; i < 5; ++i) tick(filter, requested, Reading::kMissing);
  EXPECT_NEAR(filter.gain(), 0.5, 1e-12);  // 5 ms of a 10 ms fade out
  const Vec3 f = tick(filter, requested);
  EXPECT_NEAR(filter.gain(), 0.5 + kDt / 0.1, 1e-12);
  EXPECT_NEAR(f.z(), 2.0 * 0.51, 1e-12);
}

TEST(SafetyFilter, AStaleSnapshotFadesTheRequestedForceOutWithoutZeroingIt) {
  SafetyConfig config = immediate();
  config.fade_out_s = 0.05;
  config.max_snapshot_age_s = 0.25;
  SafetyFilter filter(device(), config);
  const Vec3 requested(0, 1.0, 0);
  tick(filter, requested);
  EXPECT_EQ(tick(filter, requested, Reading::kValid, 0.25), requested);  // at the limit: fresh enough
  EXPECT_EQ(filter.counters().watchdog, 0u);
  Vec3 f = tick(filter, requested, Reading::kValid, 0.26);
  EXPECT_NEAR(f.y(), 1.0 - kDt / 0.05, 1e-12);
  f = tick(filter, requested, Reading::kValid, kNaN);  // an unknown age is stale
  EXPECT_NEAR(f.y(), 1.0 - 2 * kDt / 0.05, 1e-12);
  EXPECT_EQ(filter.counters().watchdog, 2u);
  for (int i = 0; i < 100; ++i) f = tick(filter, requested, Reading::kValid, 1.0);
  EXPECT_EQ(f, Vec3::Zero());
  EXPECT_EQ(filter.gain(), 0.0);  // never below 0
}

TEST(SafetyFilter, TheWatchdogTripsOnTheConfiguredNumberOfOverrunsInARow) {
  SafetyConfig config = immediate();
  config.max_consecutive_overruns = 20;
  SafetyFilter filter(device(), config);
  const Vec3 requested(1, 0, 0);
  for (int i = 0; i < 19; ++i) EXPECT_EQ(tick(filter, requested, Reading::kValid, 0.0, true), requested);
  tick(filter, requested, Reading::kValid, 0.0, false);  // one tick on time starts the count again
  for (int i = 0; i < 19; ++i) tick(filter, requested, Reading::kValid, 0.0, true);
  EXPECT_EQ(filter.counters().watchdog, 0u);
  const Vec3 f = tick(filter, requested, Reading::kValid, 0.0, true);  // the 20th in a row
  EXPECT_EQ(filter.counters().watchdog, 1u);
  EXPECT_LT(f.x(), 1.0);
}

TEST(SafetyFilter, TheSlewLimitMovesTheForceByAtMostRateTimesDtAlongTheChange) {
  SafetyFilter filter(device(8.0, 2000.0), immediate());  // 2 N per 1 ms tick
  const Vec3 requested(0.0, 3.0, 4.0);                    // 5 N
  const Vec3 unit = requested.normalized();
  Vec3 f = tick(filter, requested);
  EXPECT_LT((f - 2.0 * unit).norm(), 1e-12);
  f = tick(filter, requested);
  EXPECT_LT((f - 4.0 * unit).norm(), 1e-12);
  f = tick(filter, requested);
  EXPECT_EQ(f, requested);  // within reach: exact
  EXPECT_EQ(filter.counters().rate_limited, 2u);
  // A reversal: 10 N of change, 2 N per tick, through zero.
  f = tick(filter, -requested);
  EXPECT_LT((f - 3.0 * unit).norm(), 1e-12);
  // A fault's zero force is reached at the slew rate too.
  f = tick(filter, Vec3(kNaN, 0, 0));
  EXPECT_LT((f - 1.0 * unit).norm(), 1e-12);
  f = tick(filter, Vec3(kNaN, 0, 0));
  EXPECT_EQ(f, Vec3::Zero());
}

TEST(SafetyFilter, ANonsenseTimeStepCountsAsOneMillisecond) {
  SafetyConfig config;
  config.fade_in_s = 0.5;
  for (const double dt : {0.0, -1.0, kNaN, kInf}) {
    SafetyFilter filter(device(), config);
    tick(filter, Vec3(1, 0, 0), Reading::kValid, 0.0, false, dt);
    EXPECT_NEAR(filter.gain(), 1e-3 / 0.5, 1e-15) << dt;
  }
}

TEST(SafetyFilter, ResetStartsOverFromZero) {
  SafetyConfig config;
  config.fade_in_s = 0.01;
  config.max_consecutive_overruns = 2;
  SafetyFilter filter(device(), config);
  for (int i = 0; i < 20; ++i) tick(filter, Vec3(1, 0, 0));
  tick(filter, Vec3(1, 0, 0), Reading::kValid, 0.0, true);
  filter.reset();
  EXPECT_EQ(filter.gain(), 0.0);
  EXPECT_EQ(filter.last_force(), Vec3::Zero());
  // The overrun count started over too: one more overrun is not two in a row.
  tick(filter, Vec3(1, 0, 0), Reading::kValid, 0.0, true);
  EXPECT_EQ(filter.counters().watchdog, 0u);
  EXPECT_NEAR(filter.gain(), kDt / 0.01, 1e-12);
}

TEST(SafetyFilter, EarlierCountersAddUp) {
  SafetyFilter filter(device(1.0), immediate());
  tick(filter, Vec3(5, 0, 0));
  tick(filter, Vec3(5, 0, 0), Reading::kMissing);
  SafetyCounters earlier;
  earlier.non_finite = 1;
  earlier.no_reading = 2;
  earlier.clamped = 3;
  earlier.rate_limited = 4;
  earlier.watchdog = 5;
  filter.add_counters(earlier);
  EXPECT_EQ(filter.counters().non_finite, 1u);
  EXPECT_EQ(filter.counters().no_reading, 3u);
  EXPECT_EQ(filter.counters().clamped, 4u);
  EXPECT_EQ(filter.counters().rate_limited, 4u);
  EXPECT_EQ(filter.counters().watchdog, 5u);
}

}  // namespace
}  // namespace hof::haptics
