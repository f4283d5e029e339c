#pragma once
/// @file
/// Force Dimension devices (omega.3/.6/.7, delta.3/.6, sigma.7, lambda.7, and the Novint
/// Falcon through Force Dimension's driver) through their haptic SDK, `libdhd.so`, loaded at
/// run time (spec `dhd[,index=N][,library=PATH][,model=M]`): no SDK is needed to build HoF,
/// and none is shipped. docs/devices.md says how to install it.
///
/// The SDK's calls are the device's own servo I/O (a USB transaction of tens of microseconds)
/// and are made in the haptic tick, as CHAI3D does: position, velocity, buttons in; force out.
/// Units are the SDK's (metres, m/s, newtons); its frame (x toward the user, y right, z up)
/// is turned into HoF's device frame (x right, y up, z toward the user).
///
/// The device's specification: the model from dhdGetSystemType, its force limit from
/// dhdGetMaxForce where the SDK has it (3.10 and later), else the per-model table below
/// (CHAI3D's figures); a project's limit can only lower it (the safety filter takes the
/// smaller). No force is sent before the device has given a position; an SDK error, a
/// non-finite position or a device that disappears marks it failed: it gives no reading from
/// then on (the loop fades the force to zero) and failure() says why.

#include <atomic>
#include <memory>
#include <optional>
#include <string>

#include "hof/core/error.h"
#include "hof/haptics/device.h"

namespace hof::haptics {

struct DhdConfig {
  int index{0};         ///< which device, in the SDK's enumeration order
  std::string library;  ///< the SDK's file; empty: $HOF_DHD_LIBRARY, else libdhd.so from the loader's path
  std::optional<DeviceSpec>
      model;  ///< a known model's figures (device_spec_for_model) instead of what the device reports
};

/// The Force Dimension model of a dhdGetSystemType() value and its figures: name, maximum
/// continuous force (N), workspace radius (m). Unknown types: the omega.3's figures, named by
/// their number.
struct DhdModel {
  std::string name;
  double max_force_n{12.0};
  double workspace_radius_m{0.075};
};
[[nodiscard]] DhdModel dhd_model(int system_type);

/// Opens the device. Errors: the SDK not found (the file names tried and where, and how to
/// install it), a function missing from it (named), no device found by the SDK, an index out
/// of range, the SDK refusing to open it (its own message).
[[nodiscard]] Expected<std::unique_ptr<Device>> open_dhd_device(const DhdConfig& config);

}  // namespace hof::haptics
