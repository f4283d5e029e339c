// open_device(const DeviceConfig&): one typed configuration, one backend, and the known
// models' figures. No string selects anything here; users' spec strings are parsed before
// (scene::parse_device_spec).

#include <array>
#include <memory>
#include <type_traits>
#include <utility>

#include "hof/haptics/device_backends/mouse_device.h"
#include "hof/haptics/device_backends/replay_device.h"
#include "hof/haptics/device_config.h"

namespace hof::haptics {

DeviceSpec device_spec_for_model(DeviceModel model) {
  struct Figures {
    const char* name;
    double max_force_n, max_stiffness_n_per_m, max_damping_n_s_per_m, workspace_radius_m;
  };
  // In DeviceModel's order after kVirtual (whose figures are DeviceSpec's defaults).
  static constexpr std::array<Figures, 3> kKnown{{
      {"falcon", 8.0, 3000.0, 20.0, 0.04},
      {"omni", 3.3, 700.0, 5.0, 0.10},
      {"touch", 3.3, 400.0, 4.0, 0.075},
  }};
  DeviceSpec s;
  if (model == DeviceModel::kVirtual) return s;
  const Figures& f = kKnown[static_cast<std::size_t>(model) - 1];
  s.model = f.name;
  s.max_force_n = f.max_force_n;
  s.max_stiffness_n_per_m = f.max_stiffness_n_per_m;
  s.max_damping_n_s_per_m = f.max_damping_n_s_per_m;
  s.workspace_radius_m = f.workspace_radius_m;
  return s;
}

namespace {

template <typename T>
Expected<std::unique_ptr<Device>> as_device(Expected<std::unique_ptr<T>> opened) {
  if (!opened) return std::unexpected(opened.error());
  return std::unique_ptr<Device>(std::move(*opened));
}

Expected<std::unique_ptr<Device>> open(const ReplayConfig& c) {
  return as_device(ReplayDevice::open(c.file, c.loop, c.spec));
}

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
Expected<std::unique_ptr<Device>> open(const MouseConfig& c) {
  return std::unique_ptr<Device>(std::make_unique<MouseDevice>(c.spec));
}
Expected<std::unique_ptr<Device>> open(const DhdConfig& c) { return open_dhd_device(c); }
Expected<std::unique_ptr<Device>> open(const OpenHapticsConfig& c) { return open_openhaptics_device(c); }

}  // namespace

Expected<std::unique_ptr<Device>> open_device(const DeviceConfig& config) {
  return std::visit([](const auto& c) { return open(c); }, config);
}

}  // namespace hof::haptics
