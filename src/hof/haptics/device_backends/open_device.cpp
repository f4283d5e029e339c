// open_device(const DeviceConfig&): one typed configuration, one backend. No string selects
// anything here; the spec strings are parsed before (parse_device_spec).

#include <memory>
#include <type_traits>
#include <utility>

#include "hof/haptics/device_backends/mouse_device.h"
#include "hof/haptics/device_backends/replay_device.h"
#include "hof/haptics/device_config.h"

namespace hof::haptics {

namespace {

template <typename T>
Expected<std::unique_ptr<Device>> as_device(Expected<std::unique_ptr<T>> opened) {
  if (!opened) return std::unexpected(opened.error());
  return std::unique_ptr<Device>(std::move(*opened));
}

Expected<std::unique_ptr<Device>> open(const ReplayConfig& c) { return as_device(ReplayDevice::open(c.file, c.loop, c.spec)); }

Expected<std::unique_ptr<Device>> open(const ScriptedConfig& c) {
  auto motion = ScriptedMotion::make(c.motion);
  if (!motion) return std::unexpected(motion.error());
  return std::unique_ptr<Device>(std::make_unique<ScriptedDevice>(*motion, c.spec));
}

Expected<std::unique_ptr<Device>> open(const VirtualHandConfig& c) {
  auto motion = ScriptedMotion::make(c.motion);
  if (!motion) return std::unexpected(motion.error());
  if (auto valid = validate(c.hand); !valid) return std::unexpected(valid.error());
  return std::unique_ptr<Device>(std::make_unique<VirtualHandDevice>(*motion, c.hand, c.spec));
}

Expected<std::unique_ptr<Device>> open(const UdpDeviceConfig& c) { return as_device(UdpDevice::open(c)); }
Expected<std::unique_ptr<Device>> open(const SpacemouseConfig& c) { return as_device(SpacemouseDevice::open(c)); }
Expected<std::unique_ptr<Device>> open(const MouseConfig& c) { return std::unique_ptr<Device>(std::make_unique<MouseDevice>(c.spec)); }
Expected<std::unique_ptr<Device>> open(const DhdConfig& c) { return open_dhd_device(c); }
Expected<std::unique_ptr<Device>> open(const OpenHapticsConfig& c) { return open_openhaptics_device(c); }

}  // namespace

Expected<std::unique_ptr<Device>> open_device(const DeviceConfig& config) {
  return std::visit([](const auto& c) { return open(c); }, config);
}

}  // namespace hof::haptics
