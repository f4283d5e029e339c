#pragma once
/// @file
/// Recorded-trajectory playback (spec `replay:PATH.csv[,loop]`). The whole CSV is read and
/// checked by load_replay() when the device is opened; read() only interpolates.
///
/// File format (docs/device-protocol.md, "Replay files"): UTF-8 text, one sample per line,
/// fields separated by ','. '#' starts a comment (whole line or trailing); blank lines are
/// skipped. The first non-comment line is the header: `t` first, then the columns `x`, `y`,
/// `z` (required) and optionally `qw`, `qx`, `qy`, `qz` (all four or none) and `button`, in
/// any order. t is in seconds and strictly increasing; x, y, z in metres (device frame);
/// the quaternion (w, x, y, z) is normalised on load; button is an unsigned integer bit mask
/// (bit 0 = main button).

#include <atomic>
#include <cstdint>
#include <filesystem>
#include <vector>

#include "hof/haptics/device.h"

namespace hof::haptics {

/// One row of a replay file.
struct ReplaySample {
  double t_s{0.0};
  Vec3 position_m{Vec3::Zero()};
  Eigen::Quaterniond orientation{Eigen::Quaterniond::Identity()};
  std::uint32_t buttons{0};
};

/// Reads and validates a replay CSV. Errors: kIo (cannot open: file named), kParse with file
/// and 1-based line (bad header, unknown or duplicate column, wrong column count, bad or
/// non-finite number, zero quaternion, time not increasing, no samples).
[[nodiscard]] Expected<std::vector<ReplaySample>> load_replay(const std::filesystem::path& path);

/// Plays samples back. read(t) at the file's time t: position linear between the two
/// samples around t, orientation slerped, velocity the slope of that segment (at a sample
/// time, the segment that starts there), buttons of the earlier sample. Before the first
/// sample: the first sample, zero velocity. After the last: kEnded and invalid (the last
/// sample's position), or, with `loop`, time wraps to the first sample (period = last − first
/// time). write_force() is ignored.
class ReplayDevice final : public Device {
 public:
  /// @pre `samples` is non-empty with strictly increasing times (as load_replay() returns).
  ReplayDevice(std::vector<ReplaySample> samples, bool loop, const DeviceSpec& spec = DeviceSpec{});

  /// load_replay() + constructor.
  [[nodiscard]] static Expected<std::unique_ptr<ReplayDevice>> open(const std::filesystem::path& path, bool loop,
                                                                    const DeviceSpec& spec = DeviceSpec{});

  [[nodiscard]] const DeviceSpec& spec() const override { return spec_; }
  [[nodiscard]] std::string_view backend() const override { return "replay"; }
  DeviceReading read(double time_s) override;
  void write_force(const Vec3& force_n, const Vec3& torque_n_m) override;
  [[nodiscard]] DeviceHealth health() const override { return health_.load(std::memory_order_acquire); }
  [[nodiscard]] double script_duration_s() const override { return loop_ ? 0.0 : samples_.back().t_s; }

  [[nodiscard]] const std::vector<ReplaySample>& samples() const { return samples_; }
  [[nodiscard]] bool loops() const { return loop_; }

 private:
  DeviceSpec spec_;
  std::vector<ReplaySample> samples_;
  bool loop_{false};
  std::atomic<DeviceHealth> health_{DeviceHealth::kOk};
};

}  // namespace hof::haptics
