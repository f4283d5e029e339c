#pragma once
/// @file
/// 3D Systems (Geomagic, SensAble) devices — Touch, Touch X, Phantom Omni, Phantom Premium —
/// through OpenHaptics' HD API, `libHD.so`, loaded at run time (spec
/// `openhaptics[,device=NAME][,library=PATH][,model=M]`): no SDK is needed to build HoF.
///
/// The device's servo loop is the haptic loop's clock: HoF's tick runs inside an asynchronous
/// scheduler callback, once per servo frame (hdBeginFrame, the tick, hdEndFrame), with nothing
/// blocking in it (Device::start_servo). The HD API works in millimetres: positions and
/// velocities are converted to metres once, here; its frame (x right, y up, z toward the
/// user) is HoF's device frame. The limits come from the device: the force limit is its
/// nominal maximum force (HD_NOMINAL_MAX_FORCE), and over time its nominal continuous force
/// (HD_NOMINAL_MAX_CONTINUOUS_FORCE) is held too, as the motors' heating: the peak is allowed
/// while the mean force delivered over the last second is low, and the cap slides down to the
/// continuous force as that mean rises to it (the mean then settles at it at most). The
/// calibration state is read when the device opens (calibration()). A device runs in real
/// time only: outside a servo frame it gives no reading.

#include <memory>
#include <optional>
#include <string>

#include "hof/core/error.h"
#include "hof/haptics/device.h"

namespace hof::haptics {

struct OpenHapticsConfig {
  std::string device;   ///< the configuration name (Touch Setup's); empty: the default device
  std::string library;  ///< the SDK's file; empty: $HOF_HD_LIBRARY, else libHD.so from the loader's path
  std::optional<DeviceSpec>
      model;  ///< a known model's figures (device_spec_for_model) instead of what the device reports
};

/// Opens the device and starts the HD scheduler. Errors: the SDK not found (the file names
/// tried and where, and how to install it), a function missing from it (named), the device
/// not found or not initialised (the HD API's error code and text).
[[nodiscard]] Expected<std::unique_ptr<Device>> open_openhaptics_device(const OpenHapticsConfig& config);

/// The calibration state an OpenHaptics device reported when it opened ("ok", "updated
/// automatically", "needs manual input: ..."); empty for any other device.
[[nodiscard]] std::string openhaptics_calibration(const Device& device);

}  // namespace hof::haptics
