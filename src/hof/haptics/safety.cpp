#include "hof/haptics/safety.h"

#include "hof/core/assert.h"

#include <algorithm>
#include <cmath>

namespace hof::haptics {

SafetyFilter::SafetyFilter(const DeviceSpec& spec, const SafetyConfig& config) : spec_(spec), config_(config) {
  set_max_force(config.max_force_n);
}

void SafetyFilter::set_max_force(double max_force_n) {
  config_.max_force_n = max_force_n;
  limit_n_ =
      max_force_n > 0.0 && std::isfinite(max_force_n) ? std::min(max_force_n, spec_.max_force_n) : spec_.max_force_n;
}

void SafetyFilter::reset() {
  gain_ = 0.0;
  consecutive_overruns_ = 0;
  last_.setZero();
}

Vec3 SafetyFilter::filter(const Vec3& requested, Reading reading, double snapshot_age_s, bool overrunning, double dt) {
  if (!(dt > 0.0) || !std::isfinite(dt)) dt = 1e-3;
  consecutive_overruns_ = overrunning ? consecutive_overruns_ + 1 : 0;
  Vec3 force = requested;
  bool fault = false;
  if (reading == Reading::kMissing) {
    ++counters_.no_reading;
    force.setZero();
    fault = true;
  } else if (reading == Reading::kNonFinite || !force.allFinite()) {
    ++counters_.non_finite;
    force.setZero();
    fault = true;
  }
  // Watchdog: stale geometry or a loop that cannot keep its rate fades the force out.
  const bool stale = !(snapshot_age_s <= config_.max_snapshot_age_s);
  const bool struggling = consecutive_overruns_ >= config_.max_consecutive_overruns;
  if (stale || struggling || fault) {
    if (stale || struggling) ++counters_.watchdog;
    gain_ = config_.fade_out_s > 0.0 ? std::max(0.0, gain_ - dt / config_.fade_out_s) : 0.0;
  } else {
    gain_ = config_.fade_in_s > 0.0 ? std::min(1.0, gain_ + dt / config_.fade_in_s) : 1.0;
  }
  force *= gain_;
  // Slew limit.
  const double max_step = spec_.max_force_rate_n_per_s * dt;
  const Vec3 change = force - last_;
  const double change_norm = change.norm();
  if (change_norm > max_step && max_step > 0.0) {
    force = last_ + change * (max_step / change_norm);
    ++counters_.rate_limited;
  }
  // Magnitude clamp, last.
  const double magnitude = force.norm();
  if (magnitude > limit_n_) {
    force *= limit_n_ / magnitude;
    // Rounding can leave |F| one ulp above the limit: shave until it is not.
    for (int i = 0; i < 4 && force.norm() > limit_n_; ++i) force *= 1.0 - 1e-15;
    ++counters_.clamped;
  }
  if (!force.allFinite()) force.setZero();  // cannot happen; never let it through regardless
  // The safety rule itself: what leaves this filter is finite and within the limit.
  HOF_ASSERT(force.allFinite() && force.norm() <= limit_n_);
  last_ = force;
  return force;
}

}  // namespace hof::haptics
