#include "hof/haptics/period_stats.h"

#include <algorithm>
#include <cmath>

namespace hof::haptics {

PeriodStats::PeriodStats(double nominal_period_s) : nominal_s_(nominal_period_s), bins_(20000, 0) {}

void PeriodStats::record(double period_s, bool overrun) {
  if (!(period_s >= 0.0)) return;
  // Nearest microsecond: bin b holds [b − 0.5, b + 0.5) µs, so that a period of exactly 1 ms
  // computed as a difference of times (0.000999999… s) is counted as 1000 µs.
  const auto bin =
      static_cast<std::size_t>(std::min(std::round(period_s / kBinWidth), static_cast<double>(bins_.size() - 1)));
  ++bins_[bin];
  ++count_;
  if (overrun) ++overruns_;
  max_s_ = std::max(max_s_, period_s);
  sum_s_ += period_s;
}

void PeriodStats::clear() {
  std::fill(bins_.begin(), bins_.end(), 0u);
  count_ = overruns_ = 0;
  max_s_ = sum_s_ = 0.0;
}

double PeriodStats::quantile_s(double q) const {
  if (count_ == 0) return 0.0;
  const auto target = static_cast<std::uint64_t>(std::ceil(std::clamp(q, 0.0, 1.0) * static_cast<double>(count_)));
  std::uint64_t seen = 0;
  for (std::size_t b = 0; b < bins_.size(); ++b) {
    seen += bins_[b];
    if (seen >= std::max<std::uint64_t>(target, 1)) return std::min(static_cast<double>(b) * kBinWidth, max_s_);
  }
  return max_s_;
}

}  // namespace hof::haptics
