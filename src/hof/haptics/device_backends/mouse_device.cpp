#include "hof/haptics/device_backends/mouse_device.h"

#include <algorithm>
#include <cmath>

namespace hof::haptics {

MouseDevice::MouseDevice(const DeviceSpec& spec, double smoothing_s)
    : spec_(spec), smoothing_s_(std::max(smoothing_s, 0.0)) {}

void MouseDevice::set_target(const Vec3& position_m, std::uint32_t buttons) {
  if (!position_m.allFinite()) return;
  writer_.position = position_m;
  writer_.buttons = buttons;
  target_.write_slot() = writer_;
  target_.publish();
}

void MouseDevice::place(const Vec3& position_m) {
  if (!position_m.allFinite()) return;
  writer_.position = position_m;
  writer_.placed_at = position_m;
  ++writer_.placed;
  target_.write_slot() = writer_;
  target_.publish();
}

void MouseDevice::set_orientation(const Eigen::Quaterniond& orientation) {
  const double norm = orientation.coeffs().norm();
  if (!orientation.coeffs().allFinite() || !(norm > 0.0)) return;
  writer_.orientation = Eigen::Quaterniond(orientation.coeffs() / norm);
  target_.write_slot() = writer_;
  target_.publish();
}

DeviceReading MouseDevice::read(double time_s) {
  target_.acquire();
  const Target& target = target_.read();
  const double dt = last_time_s_ < 0.0 ? 0.0 : std::max(time_s - last_time_s_, 0.0);
  last_time_s_ = time_s;
  if (!started_ || target.placed != last_placed_) {
    position_ = target.placed ? target.placed_at : target.position;
    velocity_.setZero();
    last_placed_ = target.placed;
    started_ = true;
  } else if (dt > 0.0) {
    // First-order follower: exact discretisation of dx/dt = (target − x) / τ.
    const double a = smoothing_s_ > 0.0 ? 1.0 - std::exp(-dt / smoothing_s_) : 1.0;
    const Vec3 next = position_ + a * (target.position - position_);
    velocity_ = (next - position_) / dt;
    position_ = next;
  }
  DeviceReading r;
  r.time_s = time_s;
  r.position_m = position_;
  r.velocity_m_per_s = velocity_;
  r.orientation = target.orientation;
  r.buttons = target.buttons;
  r.valid = true;
  return r;
}

void MouseDevice::write_force(const Vec3&, const Vec3&) {}

}  // namespace hof::haptics
