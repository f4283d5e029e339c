#include "hof/haptics/device_backends/dhd_device.h"

#include <fmt/format.h>

#include <array>
#include <cmath>
#include <cstdlib>
#include <mutex>
#include <vector>

#include "hof/core/shared_library.h"

namespace hof::haptics {

namespace {

// The SDK's C functions (dhdc.h: extern "C", the device ID a char, -1 for the default device;
// a default argument does not exist through a pointer, so every call passes it). Getters
// return 0, or DHD_TIMEGUARD (1: cached data, not an error); setters 0 or
// DHD_MOTOR_SATURATED (2); −1 is an error.
using GetDeviceCount = int();
using OpenId = int(char);
using Close = int(char);
using GetSystemType = int(char);
using GetSystemName = const char*(char);
using EnableForce = int(unsigned char, char);
using GetVector = int(double*, double*, double*, char);
using SetForce = int(double, double, double, char);
using GetButtonMask = unsigned int(char);
using GetMaxForce = double(char);
using ErrorGetLastStr = const char*();

constexpr std::string_view kDhdInstall =
    "Install Force Dimension's SDK (https://www.forcedimension.com/software/sdk) and put its lib/ folder on "
    "LD_LIBRARY_PATH, or give the file: --device dhd,library=/path/to/libdhd.so (docs/devices.md)";

// SDK frame (x toward the user, y right, z up) to HoF's device frame (x right, y up, z toward
// the user), and back.
Vec3 from_sdk(double x, double y, double z) { return {y, z, x}; }

class DhdDevice final : public Device {
 public:
  struct Api {
    SharedLibrary library;
    GetDeviceCount* get_device_count{};
    OpenId* open_id{};
    Close* close{};
    GetSystemType* get_system_type{};
    GetSystemName* get_system_name{};  // optional (SDK 3.2+)
    EnableForce* enable_force{};
    GetVector* get_position{};
    GetVector* get_linear_velocity{};  // optional
    SetForce* set_force{};
    GetButtonMask* get_button_mask{};  // optional
    GetMaxForce* get_max_force{};      // optional (SDK 3.10+)
    ErrorGetLastStr* error_string{};
  };

  DhdDevice(Api api, char id, DeviceSpec spec) : api_(std::move(api)), id_(id), spec_(std::move(spec)) {}
  ~DhdDevice() override { DhdDevice::close(); }

  [[nodiscard]] const DeviceSpec& spec() const override { return spec_; }
  [[nodiscard]] std::string_view backend() const override { return "dhd"; }

  DeviceReading read(double time_s) override {
    DeviceReading r;
    r.time_s = time_s;
    if (failed_.load(std::memory_order_relaxed) || closed_) return r;
    double x = 0.0, y = 0.0, z = 0.0;
    if (api_.get_position(&x, &y, &z, id_) < 0) {
      fail("dhdGetPosition failed");
      return r;
    }
    r.position_m = from_sdk(x, y, z);
    if (!r.position_m.allFinite()) {
      fail("the SDK gave a position that is not a number");
      return r;
    }
    // The velocity needs two position updates inside the SDK's window: until then it errs
    // (a timeout), which is not a fault.
    if (api_.get_linear_velocity && api_.get_linear_velocity(&x, &y, &z, id_) >= 0) {
      const Vec3 v = from_sdk(x, y, z);
      if (v.allFinite()) r.velocity_m_per_s = v;
    }
    if (api_.get_button_mask) r.buttons = api_.get_button_mask(id_);
    r.valid = true;
    ready_ = true;
    return r;
  }

  void write_force(const Vec3& force_n, const Vec3& /*torque_n_m*/) override {
    // No force before the device has given a position, none after a fault; the safety layer
    // has clamped it, a non-finite one never reaches the motors.
    if (!ready_ || closed_ || failed_.load(std::memory_order_relaxed)) return;
    const Vec3 f = force_n.allFinite() ? force_n : Vec3::Zero();
    if (api_.set_force(f.z(), f.x(), f.y(), id_) < 0) fail("dhdSetForce failed");
  }

  [[nodiscard]] DeviceHealth health() const override {
    return failed_.load(std::memory_order_acquire) ? DeviceHealth::kFailed : DeviceHealth::kOk;
  }
  [[nodiscard]] std::string failure() const override {
    if (!failed_.load(std::memory_order_acquire)) return {};
    return std::string(failure_.data());
  }

  void close() override {
    if (closed_) return;
    closed_ = true;
    api_.set_force(0.0, 0.0, 0.0, id_);
    api_.close(id_);
  }

 private:
  // Once, on the haptic thread (into a fixed buffer: the tick does not allocate); the message
  // is written before the flag that publishes it.
  void fail(std::string_view what) {
    if (failed_.load(std::memory_order_relaxed)) return;
    const char* why = api_.error_string ? api_.error_string() : nullptr;
    const auto end = fmt::format_to_n(failure_.data(), failure_.size() - 1,
                                      "{} {} (device {}): {} - unplugged, switched off, or its driver stopped?",
                                      spec_.model, what, static_cast<int>(id_), why ? why : "no reason given");
    *end.out = '\0';
    failed_.store(true, std::memory_order_release);
    api_.set_force(0.0, 0.0, 0.0, id_);  // a fault never leaves a force on
  }

  Api api_;
  char id_;
  DeviceSpec spec_;
  std::atomic<bool> failed_{false};
  std::array<char, 512> failure_{};
  bool ready_{false};
  bool closed_{false};
};

std::string last_error(const DhdDevice::Api& api) {
  const char* why = api.error_string();
  return why && *why ? why : "no reason given";
}

}  // namespace

DhdModel dhd_model(int system_type) {
  // dhdc.h's DHD_DEVICE_* values; figures as CHAI3D gives them (CDeltaDevices.cpp): the
  // maximum continuous force and the radius of the workspace sphere.
  switch (system_type) {
    case 33:
      return {"omega.3", 12.0, 0.075};
    case 34:
      return {"omega.6", 12.0, 0.075};
    case 36:
      return {"omega.6 (left)", 12.0, 0.075};
    case 35:
      return {"omega.7", 12.0, 0.075};
    case 37:
      return {"omega.7 (left)", 12.0, 0.075};
    case 60:
      return {"Novint Falcon", 8.0, 0.04};
    case 63:
      return {"delta.3", 20.0, 0.15};
    case 64:
      return {"delta.6", 20.0, 0.15};
    case 104:
      return {"sigma.7", 12.0, 0.075};
    case 105:
      return {"sigma.7 (left)", 12.0, 0.075};
    case 106:
      return {"sigma.6+", 12.0, 0.09};
    case 107:
      return {"sigma.6+ (left)", 12.0, 0.09};
    case 108:
      return {"lambda.7", 12.0, 0.075};
    case 109:
      return {"lambda.7 (left)", 12.0, 0.075};
    default:
      break;
  }
  return {fmt::format("Force Dimension device type {}", system_type), 12.0, 0.075};
}

Expected<std::unique_ptr<Device>> open_dhd_device(const DhdConfig& config) {
  std::vector<std::string> names;
  if (!config.library.empty()) {
    names.push_back(config.library);
  } else if (const char* env = std::getenv("HOF_DHD_LIBRARY"); env && *env) {
    names.emplace_back(env);
  } else {
    names = {"libdhd.so", "libdhd.so.3"};
  }
  auto library = SharedLibrary::open(names, "the Force Dimension SDK (libdhd)", kDhdInstall);
  if (!library) return std::unexpected(library.error());
  DhdDevice::Api api{std::move(*library)};
  const SharedLibrary& lib = api.library;
  for (auto bound : {lib.bind("dhdGetDeviceCount", api.get_device_count), lib.bind("dhdOpenID", api.open_id),
                     lib.bind("dhdClose", api.close), lib.bind("dhdGetSystemType", api.get_system_type),
                     lib.bind("dhdEnableForce", api.enable_force), lib.bind("dhdGetPosition", api.get_position),
                     lib.bind("dhdSetForce", api.set_force), lib.bind("dhdErrorGetLastStr", api.error_string)}) {
    if (!bound) return std::unexpected(bound.error());
  }
  lib.bind_optional("dhdGetSystemName", api.get_system_name);
  lib.bind_optional("dhdGetLinearVelocity", api.get_linear_velocity);
  lib.bind_optional("dhdGetButtonMask", api.get_button_mask);
  lib.bind_optional("dhdGetMaxForce", api.get_max_force);

  const int count = api.get_device_count();
  if (count <= 0) {
    return make_error(ErrorCode::kIo,
                      fmt::format("no device found by the Force Dimension SDK ({}: {}); is it plugged in and "
                                  "switched on, and may this user open it (udev rules, docs/devices.md)?",
                                  lib.path(), count < 0 ? last_error(api) : "none connected"));
  }
  if (config.index < 0 || config.index >= count) {
    return make_error(ErrorCode::kInvalidArgument,
                      fmt::format("index={}: the Force Dimension SDK found {} device{} (index 0 to {})", config.index,
                                  count, count == 1 ? "" : "s", count - 1));
  }
  const int id = api.open_id(static_cast<char>(config.index));
  if (id < 0) {
    return make_error(ErrorCode::kIo, fmt::format("the Force Dimension SDK could not open device {}: {}", config.index,
                                                  last_error(api)));
  }
  const auto handle = static_cast<char>(id);
  const DhdModel model = dhd_model(api.get_system_type(handle));
  DeviceSpec spec;
  if (config.model) {
    spec = *config.model;
  } else {
    spec.model = model.name;
    if (api.get_system_name) {
      if (const char* name = api.get_system_name(handle); name && *name) spec.model = name;
    }
    spec.max_force_n = model.max_force_n;
    spec.workspace_radius_m = model.workspace_radius_m;
  }
  // The SDK's own force limit, where it reports one (negative: the limit is off).
  if (api.get_max_force) {
    const double sdk_max = api.get_max_force(handle);
    if (sdk_max > 0.0 && std::isfinite(sdk_max)) spec.max_force_n = std::min(spec.max_force_n, sdk_max);
  }
  if (api.enable_force(1, handle) < 0) {
    const std::string why = last_error(api);
    api.close(handle);
    return make_error(ErrorCode::kIo,
                      fmt::format("the Force Dimension SDK could not enable the forces of {}: {}", spec.model, why));
  }
  return std::unique_ptr<Device>(std::make_unique<DhdDevice>(std::move(api), handle, std::move(spec)));
}

}  // namespace hof::haptics
