#pragma once
/// @file
/// 3Dconnexion SpaceMouse through spacenavd and libspnav (spec `spacemouse[,scale=M]`).
/// Input only: write_force() is ignored. The puck is a rate controller: its translation
/// deflection (spacenavd units, about ±350 at full deflection) times `scale` (m per unit per
/// second) is the stylus velocity, integrated into a position on the device's own polling
/// thread and kept inside the workspace sphere (spec().workspace_radius_m). Axes: spacenavd
/// reports x right, y up, z into the screen; the device frame has z toward the user, so z is
/// negated. Buttons map to bits (button n → bit n). Orientation stays the identity.
///
/// libspnav holds one global connection per process, so at most one SpacemouseDevice can be
/// open at a time. When no spacenavd runs, open() fails at once with "spacemouse: no
/// spacenavd running (spnav_open failed)" (spnav_open() connects to a Unix socket; the path
/// may be overridden with the SPNAV_SOCKET environment variable).

#include <memory>

#include "hof/haptics/device.h"

namespace hof::haptics {

/// Settings of the SpaceMouse backend (from the spec `spacemouse[,scale=M]`).
struct SpacemouseConfig {
  double scale_m_per_unit_s{2e-4};  ///< velocity per unit of deflection (m/s per unit), > 0
  /// A deflection not refreshed for this long counts as released (the puck normally repeats
  /// its report while held), so a lost release event cannot make the stylus drift away.
  double hold_timeout_s{0.5};
  DeviceSpec spec{};
};

/// The SpaceMouse as an input-only device (see the file comment).
class SpacemouseDevice final : public Device {
 public:
  /// Connects to spacenavd and starts the polling thread. Errors: kInvalidArgument (scale),
  /// kIo ("spacemouse: no spacenavd running (spnav_open failed)", or already open).
  [[nodiscard]] static Expected<std::unique_ptr<SpacemouseDevice>> open(const SpacemouseConfig& config);
  ~SpacemouseDevice() override;

  [[nodiscard]] const DeviceSpec& spec() const override { return spec_; }
  [[nodiscard]] std::string_view backend() const override { return "spacemouse"; }
  /// The integrated position, the current commanded velocity and the buttons; time_s is
  /// passed through. Invalid once the connection to spacenavd failed (kFailed).
  DeviceReading read(double time_s) override;
  /// Ignored: the SpaceMouse renders no force.
  void write_force(const Vec3& force_n, const Vec3& torque_n_m) override;
  [[nodiscard]] DeviceHealth health() const override;
  /// Stops the polling thread and closes the spacenavd connection. Idempotent.
  void close() override;

 private:
  struct Impl;
  SpacemouseDevice(std::unique_ptr<Impl> impl, const DeviceSpec& spec);
  std::unique_ptr<Impl> impl_;
  DeviceSpec spec_;
};

}  // namespace hof::haptics
