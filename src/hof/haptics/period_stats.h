#pragma once
/// @file
/// Statistics of a loop's period: a histogram with 1 µs bins up to 20 ms (preallocated, so
/// recording is allocation-free), giving p50/p99/max and overrun counts.

#include <array>
#include <cstdint>
#include <vector>

namespace hof::haptics {

class PeriodStats {
 public:
  explicit PeriodStats(double nominal_period_s = 1e-3);

  /// Records one period (s). `overrun` marks a tick that missed its deadline.
  void record(double period_s, bool overrun);
  void clear();

  [[nodiscard]] std::uint64_t count() const { return count_; }
  [[nodiscard]] std::uint64_t overruns() const { return overruns_; }
  [[nodiscard]] double max_s() const { return max_s_; }
  [[nodiscard]] double mean_s() const { return count_ ? sum_s_ / static_cast<double>(count_) : 0.0; }
  /// Period below which a fraction q of the recorded periods fall (q in [0, 1]).
  [[nodiscard]] double quantile_s(double q) const;
  [[nodiscard]] double nominal_s() const { return nominal_s_; }
  /// Achieved rate: 1 / mean period.
  [[nodiscard]] double rate_hz() const { return mean_s() > 0.0 ? 1.0 / mean_s() : 0.0; }
  /// Counts per 1 µs bin (for histograms).
  [[nodiscard]] const std::vector<std::uint32_t>& bins() const { return bins_; }

 private:
  static constexpr double kBinWidth = 1e-6;
  double nominal_s_;
  std::vector<std::uint32_t> bins_;
  std::uint64_t count_{0};
  std::uint64_t overruns_{0};
  double max_s_{0.0};
  double sum_s_{0.0};
};

}  // namespace hof::haptics
