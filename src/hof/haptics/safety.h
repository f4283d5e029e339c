#pragma once
/// @file
/// The last stage before a force reaches a device — the device layer owns safety (CHAI3D's
/// setUseForceRise/setWaitForSmallForce, OpenHaptics' force ramping, H3D forceLimit):
///  - a non-finite force or device reading gives zero force;
///  - the force fades in over `fade_in_s` when the loop starts (and after a fault clears);
///  - a watchdog fades it out over `fade_out_s` when the geometry snapshot is older than
///    `max_snapshot_age_s` or the loop overran `max_consecutive_overruns` ticks in a row;
///  - its rate of change is limited to the device's max_force_rate_n_per_s;
///  - its magnitude is clamped to the device's max_force_n — last, so nothing after can
///    exceed it.

#include <cstdint>

#include "hof/core/types.h"
#include "hof/haptics/device.h"

namespace hof::haptics {

struct SafetyConfig {
  double fade_in_s{0.5};
  double fade_out_s{0.05};
  double max_snapshot_age_s{0.25};
  int max_consecutive_overruns{20};
  /// A force limit below the device's (a fragile device, a first lesson), N; 0: the device's.
  /// The force sent never exceeds the smaller of the two.
  double max_force_n{0.0};
  /// A reading farther than this from both the last reading rendered and the one before it
  /// (device frame, m) is garbage — a glitch, not a motion: no stylus moves a metre between two
  /// readings (the largest workspaces are ~0.1 m in radius). It is not rendered, so the proxy
  /// cannot be dragged across the scene and back in one tick. A reading that stays where it
  /// jumped is taken from the next tick on (the device was moved there). 0: no check.
  double max_reading_jump_m{1.0};
};

/// Counters of what the filter had to do (read by reports; written by the haptic thread).
struct SafetyCounters {
  std::uint64_t non_finite{
      0};  ///< ticks with a NaN/Inf force or a garbage reading (NaN/Inf, zero quaternion, a jump of metres)
  std::uint64_t no_reading{0};    ///< ticks without a device sample (absent, timed out, script ended)
  std::uint64_t clamped{0};       ///< ticks whose force exceeded the device maximum
  std::uint64_t rate_limited{0};  ///< ticks whose force change exceeded the slew limit
  std::uint64_t watchdog{0};      ///< ticks faded by the watchdog
};

class SafetyFilter {
 public:
  SafetyFilter(const DeviceSpec& spec, const SafetyConfig& config);

  /// What the device gave this tick.
  enum class Reading : std::uint8_t {
    kValid,      ///< a finite sample
    kMissing,    ///< no sample (device absent, timed out, scripted motion ended)
    kNonFinite,  ///< a sample with NaN/Inf values
  };

  /// The force to send for this tick.
  /// @param requested      force from rendering and effects, N
  /// @param reading        what the device gave
  /// @param snapshot_age_s how old the geometry snapshot is
  /// @param overrunning    whether this tick overran its period
  Vec3 filter(const Vec3& requested, Reading reading, double snapshot_age_s, bool overrunning, double dt);

  [[nodiscard]] const SafetyCounters& counters() const { return counters_; }
  [[nodiscard]] double gain() const { return gain_; }
  [[nodiscard]] const Vec3& last_force() const { return last_; }
  /// The limit |F| is clamped to: the device's, or the configured one when smaller.
  [[nodiscard]] double force_limit_n() const { return limit_n_; }
  /// Changes the configured limit (0: the device's); a limit above the device's is the device's.
  void set_max_force(double max_force_n);
  void reset();
  /// Adds counts kept by an earlier filter (the loop's totals survive a device switch).
  void add_counters(const SafetyCounters& earlier) {
    counters_.non_finite += earlier.non_finite;
    counters_.no_reading += earlier.no_reading;
    counters_.clamped += earlier.clamped;
    counters_.rate_limited += earlier.rate_limited;
    counters_.watchdog += earlier.watchdog;
  }

 private:
  DeviceSpec spec_;
  SafetyConfig config_;
  double limit_n_{0.0};
  SafetyCounters counters_;
  double gain_{0.0};  // fade factor in [0, 1]
  int consecutive_overruns_{0};
  Vec3 last_{Vec3::Zero()};
};

}  // namespace hof::haptics
