#pragma once
/// @file
/// A device as a typed configuration: one alternative per backend, with typed fields.
/// open_device(const DeviceConfig&) opens it; no string selects a backend or a key here. The
/// spec strings users type (`scripted:poke,start=...`, `udp:HOST:PORT`, ...) are parsed into
/// a DeviceConfig by scene::parse_device_spec (scene/device_config.h).

#include <filesystem>
#include <memory>
#include <optional>
#include <variant>

#include "hof/core/error.h"
#include "hof/haptics/device.h"
#include "hof/haptics/device_backends/dhd_device.h"
#include "hof/haptics/device_backends/openhaptics_device.h"
#include "hof/haptics/device_backends/scripted_device.h"
#include "hof/haptics/device_backends/spacemouse_device.h"
#include "hof/haptics/device_backends/udp_device.h"
#include "hof/haptics/device_backends/virtual_hand_device.h"

namespace hof::haptics {

/// `replay:PATH.csv[,loop]`: a recorded trajectory.
struct ReplayConfig {
  std::filesystem::path file;
  bool loop{false};
  DeviceSpec spec{};
};

/// `scripted:MOTION,...`: a built-in motion (ScriptedMotion::make validates it on open).
struct ScriptedConfig {
  MotionConfig motion;
  DeviceSpec spec{};
};

/// `virtual-hand:MOTION,...`: a compliant hand following a scripted motion.
struct VirtualHandConfig {
  MotionConfig motion;
  VirtualHandParams hand;
  DeviceSpec spec{};
};

/// `mouse`: the window's cursor (input only); its figures are the virtual device's unless a
/// model is given, under the name "mouse".
struct MouseConfig {
  DeviceSpec spec{.model = "mouse"};
};

using DeviceConfig = std::variant<ReplayConfig, ScriptedConfig, VirtualHandConfig, UdpDeviceConfig, SpacemouseConfig,
                                  MouseConfig, DhdConfig, OpenHapticsConfig>;

/// Opens the device `config` describes. Errors are the backend's own (a missing file, an
/// invalid motion or hand, an absent device or SDK), without the spec string: the caller that
/// had one names it.
[[nodiscard]] Expected<std::unique_ptr<Device>> open_device(const DeviceConfig& config);

}  // namespace hof::haptics
