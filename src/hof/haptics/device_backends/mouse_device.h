#pragma once
/// @file
/// The mouse as a haptic device (spec `mouse[,model=M]`), for the window when no hardware is
/// connected (as HAPI's MouseHapticsDevice): the window sets a target position in the device
/// frame from the cursor (on a plane facing the camera) and the wheel (depth); the stylus
/// follows it through a first-order filter (time constant `smoothing_s`), so that a cursor
/// that jumps between frames moves the stylus smoothly at the haptic rate and the proxy
/// renders a steady force. write_force() is recorded (the window shows it) and not rendered.

#include <atomic>
#include <memory>

#include "hof/core/triple_buffer.h"
#include "hof/haptics/device.h"

namespace hof::haptics {

class MouseDevice final : public Device {
 public:
  explicit MouseDevice(const DeviceSpec& spec = DeviceSpec{.model = "mouse"}, double smoothing_s = 0.02);

  [[nodiscard]] const DeviceSpec& spec() const override { return spec_; }
  [[nodiscard]] std::string_view backend() const override { return "mouse"; }
  DeviceReading read(double time_s) override;
  void write_force(const Vec3& force_n, const Vec3& torque_n_m) override;
  [[nodiscard]] DeviceHealth health() const override { return DeviceHealth::kOk; }

  /// Where the stylus should go (device frame, m) and the buttons held. One writer thread
  /// (the window); never blocks the haptic thread.
  void set_target(const Vec3& position_m, std::uint32_t buttons = 0);
  /// Jumps to `position_m` at once (no filtering): the stylus placed anew. The first reading
  /// is there even if a target was set since (it is then followed from there).
  void place(const Vec3& position_m);
  /// The stylus's orientation (device frame; identity until set): the window turns a tool
  /// with a shape with the mouse. Taken as it is (no filtering). One writer thread.
  void set_orientation(const Eigen::Quaterniond& orientation);

 private:
  struct Target {
    Vec3 position{Vec3::Zero()};
    Vec3 placed_at{Vec3::Zero()};  // where the stylus starts after place() (the target may have moved on)
    std::uint32_t buttons{0};
    std::uint64_t placed{0};  // changes when place() asks for a jump
    Eigen::Quaterniond orientation{Eigen::Quaterniond::Identity()};
  };
  DeviceSpec spec_;
  double smoothing_s_;
  TripleBuffer<Target> target_;
  Target writer_;  // the writer's copy (window thread)
  // Haptic thread only.
  Vec3 position_{Vec3::Zero()};
  Vec3 velocity_{Vec3::Zero()};
  double last_time_s_{-1.0};
  std::uint64_t last_placed_{0};
  bool started_{false};
};

}  // namespace hof::haptics
