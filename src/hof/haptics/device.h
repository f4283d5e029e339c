#pragma once
/// @file
/// The haptic device interface: position, velocity, orientation and buttons in; force and
/// torque out; a specification that the safety layer enforces. Backends are chosen by a typed
/// configuration (device_config.h; users' spec strings are parsed in scene/device_config.h). read() and write_force()
/// are called from the haptic thread every tick: they never allocate, lock a mutex, block or do I/O — backends that
/// talk to hardware or a network do it on their own thread and exchange with the tick through atomics.
///
/// Frames: positions are in the device frame (metres; x right, y up, z toward the user, as
/// H3D). The haptic loop applies the calibration (H3D positionCalibration /
/// orientationCalibration) to get world coordinates.

#include <Eigen/Geometry>
#include <cstdint>
#include <memory>
#include <string>
#include <string_view>

#include "hof/core/error.h"
#include "hof/core/types.h"

namespace hof::haptics {

/// What the device can do; the safety layer clamps to it (cf. CHAI3D cHapticDeviceInfo).
struct DeviceSpec {
  std::string model{"virtual"};
  double max_force_n{8.0};               ///< |F| never exceeds this at the device
  double max_stiffness_n_per_m{3000.0};  ///< largest stable rendering stiffness
  double max_damping_n_s_per_m{20.0};
  double workspace_radius_m{0.08};
  double nominal_rate_hz{1000.0};
  double max_force_rate_n_per_s{2000.0};  ///< force slew limit (safety)
};

/// One sample from the device, in the device frame.
struct DeviceReading {
  double time_s{0.0};  ///< device or virtual time of the sample
  Vec3 position_m{Vec3::Zero()};
  Vec3 velocity_m_per_s{Vec3::Zero()};
  Eigen::Quaterniond orientation{Eigen::Quaterniond::Identity()};
  std::uint32_t buttons{0};  ///< bit 0 = main button
  bool valid{false};         ///< false when the device has no fresh sample (absent, timed out, ended)
};

/// Connection state, readable from any thread.
enum class DeviceHealth : std::uint8_t {
  kOk,
  kTimedOut,  ///< no sample within the backend's timeout: the loop fades force to zero
  kEnded,     ///< a finite source (replay, script) has run out
  kFailed,    ///< the backend stopped working (socket error, device unplugged)
};

class Device {
 public:
  Device() = default;
  Device(const Device&) = delete;
  Device& operator=(const Device&) = delete;
  virtual ~Device() = default;

  [[nodiscard]] virtual const DeviceSpec& spec() const = 0;
  /// Backend name, e.g. "replay", "scripted", "virtual-hand", "udp", "spacemouse".
  [[nodiscard]] virtual std::string_view backend() const = 0;

  /// The sample for haptic time `time_s` (virtual time in lock-step mode, the loop's clock in
  /// real-time mode). Simulated backends compute it for that time; hardware backends return
  /// their latest sample. Real-time safe.
  virtual DeviceReading read(double time_s) = 0;

  /// The force (N) and torque (N·m) to render until the next call, in the device frame.
  /// Already clamped by the safety layer. Real-time safe.
  virtual void write_force(const Vec3& force_n, const Vec3& torque_n_m) = 0;

  [[nodiscard]] virtual DeviceHealth health() const = 0;
  /// Why health() is kFailed, in a sentence (empty otherwise). Any thread, once health() has
  /// said kFailed.
  [[nodiscard]] virtual std::string failure() const { return {}; }

  /// How long a finite motion lasts (a script, a recording played once), s; 0 for a live
  /// device or a motion that repeats forever. A run without a given length plays it whole.
  [[nodiscard]] virtual double script_duration_s() const { return 0.0; }

  /// Stops background threads and sends a zero force. Idempotent; the destructor calls it.
  virtual void close() {}

  /// A device whose own servo loop is to be the haptic loop's clock (OpenHaptics' scheduler
  /// calls back once per servo frame). start_servo() arranges for `tick(context)` to be called
  /// on the device's servo thread once per frame, read() and write_force() being valid inside
  /// it, and returns true: the haptic loop then starts no thread of its own. stop_servo()
  /// returns after the last call. The default: no servo loop (false).
  using ServoTick = void (*)(void* context);
  virtual bool start_servo(ServoTick /*tick*/, void* /*context*/) { return false; }
  virtual void stop_servo() {}
};

/// The models whose figures HoF knows (a spec's `model=`, parsed in scene/device_config.h).
enum class DeviceModel : std::uint8_t { kVirtual, kFalcon, kOmni, kTouch };

/// The DeviceSpec of a known model, with CHAI3D's figures (reference/literature.md §4):
/// kVirtual (the defaults above), kFalcon (Novint Falcon: 8 N, 3000 N/m, 20 N·s/m, 0.04 m),
/// kOmni (PHANTOM Omni: 3.3 N, 700 N/m, 5 N·s/m, 0.10 m), kTouch (3D Systems Touch: 3.3 N,
/// 400 N/m, 4 N·s/m, 0.075 m). DeviceSpec::model is the model's name ("falcon").
[[nodiscard]] DeviceSpec device_spec_for_model(DeviceModel model);

}  // namespace hof::haptics
