#include "hof/haptics/device_backends/openhaptics_device.h"

#include <fmt/format.h>

#include <algorithm>
#include <array>
#include <atomic>
#include <cmath>
#include <cstdlib>
#include <thread>
#include <vector>

#include "hof/core/shared_library.h"

// hdGetError() returns this C struct by value (hdDefines.h). Declared with the HD API's own
// name at global scope: a call through a function pointer is checked (UBSan's function
// sanitizer) against the callee's type, so the struct must be the same named type as the
// library's, not one of our namespace.
struct HDErrorInfo {
  unsigned int errorCode;
  int internalErrorCode;
  unsigned int hHD;
};

namespace hof::haptics {

namespace {

// The HD API's C types and values (OpenHaptics' hdDefines.h, hdDevice.h, hdScheduler.h; C
// linkage; the calling convention is the platform's on x86-64 Linux).
using HHD = unsigned int;
using HDenum = unsigned int;
using HDCallbackCode = unsigned int;
using HDSchedulerHandle = unsigned long;
using HDSchedulerCallback = HDCallbackCode (*)(void*);

constexpr HHD kInvalidHandle = 0xFFFFFFFFu;
constexpr unsigned int kSuccess = 0;
constexpr HDCallbackCode kCallbackDone = 0;
constexpr HDCallbackCode kCallbackContinue = 1;
constexpr HDenum kCurrentButtons = 0x2000;
constexpr HDenum kCurrentPosition = 0x2050;
constexpr HDenum kCurrentVelocity = 0x2051;
constexpr HDenum kCurrentForce = 0x2700;
constexpr HDenum kDeviceModelType = 0x2501;
constexpr HDenum kUsableWorkspaceDimensions = 0x2551;
constexpr HDenum kNominalMaxStiffness = 0x2602;
constexpr HDenum kNominalMaxForce = 0x2603;
constexpr HDenum kNominalMaxContinuousForce = 0x2604;
constexpr HDenum kNominalMaxDamping = 0x2609;
constexpr HDenum kForceOutput = 0x4000;
constexpr HDenum kCalibrationOk = 0x5000;
constexpr HDenum kCalibrationNeedsUpdate = 0x5001;
constexpr HDenum kCalibrationNeedsManualInput = 0x5002;
constexpr HDenum kCalibrationStyleAuto = 2;
constexpr unsigned short kMaxSchedulerPriority = 65535;

constexpr double kMetresPerMillimetre = 1e-3;
// The window of the continuous-force mean, s.
constexpr double kContinuousForceWindow_s = 1.0;

constexpr std::string_view kHdInstall =
    "Install OpenHaptics for Linux and the device's driver (3D Systems' Touch Device Driver) and put libHD.so on "
    "LD_LIBRARY_PATH, or give the file: --device openhaptics,library=/path/to/libHD.so (docs/devices.md)";

struct Api {
  SharedLibrary library;
  HHD (*init_device)(const char*){};
  void (*disable_device)(HHD){};
  void (*begin_frame)(HHD){};
  void (*end_frame)(HHD){};
  HDErrorInfo (*get_error)(){};
  const char* (*get_error_string)(unsigned int){};
  void (*enable)(HDenum){};
  void (*get_doublev)(HDenum, double*){};
  void (*get_integerv)(HDenum, int*){};
  void (*set_doublev)(HDenum, const double*){};
  const char* (*get_string)(HDenum){};
  void (*start_scheduler)(){};
  void (*stop_scheduler)(){};
  HDSchedulerHandle (*schedule_asynchronous)(HDSchedulerCallback, void*, unsigned short){};
  void (*schedule_synchronous)(HDSchedulerCallback, void*, unsigned short){};
  void (*unschedule)(HDSchedulerHandle){};
  HDenum (*check_calibration)(){};
  void (*update_calibration)(HDenum){};

  // The pending error as a sentence ("" when none): the HD API keeps a stack of them.
  [[nodiscard]] std::string error() const {
    const HDErrorInfo e = get_error();
    if (e.errorCode == kSuccess) return {};
    const char* text = get_error_string ? get_error_string(e.errorCode) : nullptr;
    return fmt::format("{} (HD error 0x{:x}, internal {})", text && *text ? text : "unknown error", e.errorCode,
                       e.internalErrorCode);
  }
};

class OpenHapticsDevice final : public Device {
 public:
  OpenHapticsDevice(Api api, HHD handle, DeviceSpec spec, double continuous_force_n, std::string calibration)
      : api_(std::move(api)),
        handle_(handle),
        spec_(std::move(spec)),
        continuous_force_n_(continuous_force_n),
        calibration_(std::move(calibration)) {}
  ~OpenHapticsDevice() override { OpenHapticsDevice::close(); }

  [[nodiscard]] const DeviceSpec& spec() const override { return spec_; }
  [[nodiscard]] std::string_view backend() const override { return "openhaptics"; }
  [[nodiscard]] const std::string& calibration() const { return calibration_; }

  DeviceReading read(double time_s) override {
    DeviceReading r;
    r.time_s = time_s;
    if (!in_frame_ || failed_.load(std::memory_order_relaxed)) return r;
    std::array<double, 3> p{}, v{};
    int buttons = 0;
    api_.get_doublev(kCurrentPosition, p.data());
    api_.get_doublev(kCurrentVelocity, v.data());
    api_.get_integerv(kCurrentButtons, &buttons);
    r.position_m = kMetresPerMillimetre * Vec3(p[0], p[1], p[2]);
    r.velocity_m_per_s = kMetresPerMillimetre * Vec3(v[0], v[1], v[2]);
    if (!r.position_m.allFinite()) {
      fail("the device gave a position that is not a number");
      return r;
    }
    if (!r.velocity_m_per_s.allFinite()) r.velocity_m_per_s.setZero();
    r.buttons = static_cast<std::uint32_t>(buttons);
    r.valid = true;
    ready_ = true;
    return r;
  }

  void write_force(const Vec3& force_n, const Vec3& /*torque_n_m*/) override {
    if (!in_frame_) return;
    Vec3 f = ready_ && !failed_.load(std::memory_order_relaxed) && force_n.allFinite() ? force_n : Vec3::Zero();
    // The continuous limit, as a motor's heating: the peak force is allowed while the mean
    // force delivered over the last second is low, and the cap slides down to the continuous
    // force as that mean rises to it (smoothly: no step in what the hand feels). The mean
    // then settles at the continuous force at most.
    if (continuous_force_n_ > 0.0 && continuous_force_n_ < spec_.max_force_n) {
      const double heat = std::clamp(mean_force_n_ / continuous_force_n_, 0.0, 1.0);
      const double cap = spec_.max_force_n - (spec_.max_force_n - continuous_force_n_) * heat;
      const double magnitude = f.norm();
      if (magnitude > cap) f *= cap / magnitude;
    }
    mean_force_n_ += (f.norm() - mean_force_n_) * std::min(1.0, frame_period_s_ / kContinuousForceWindow_s);
    const std::array<double, 3> out{f.x(), f.y(), f.z()};
    api_.set_doublev(kCurrentForce, out.data());
  }

  [[nodiscard]] DeviceHealth health() const override {
    return failed_.load(std::memory_order_acquire) ? DeviceHealth::kFailed : DeviceHealth::kOk;
  }
  [[nodiscard]] std::string failure() const override {
    return failed_.load(std::memory_order_acquire) ? std::string(failure_.data()) : std::string();
  }

  bool start_servo(ServoTick tick, void* context) override {
    if (closed_ || servo_ != 0) return false;
    tick_ = tick;
    context_ = context;
    stop_.store(false, std::memory_order_release);
    servo_ = api_.schedule_asynchronous(&OpenHapticsDevice::frame, this, kMaxSchedulerPriority);
    return true;
  }

  void stop_servo() override {
    if (servo_ == 0) return;
    stop_.store(true, std::memory_order_release);
    api_.unschedule(servo_);
    // hdUnschedule does not wait for a frame in progress: the callback is done when this
    // clears (a frame lasts a millisecond).
    while (in_callback_.load(std::memory_order_acquire)) std::this_thread::yield();
    servo_ = 0;
  }

  void close() override {
    if (closed_) return;
    stop_servo();
    closed_ = true;
    api_.stop_scheduler();
    api_.disable_device(handle_);
  }

 private:
  // One servo frame (the HD scheduler's thread, 1 kHz): the state in, HoF's tick, the force out.
  static HDCallbackCode frame(void* self_pointer) {
    auto& self = *static_cast<OpenHapticsDevice*>(self_pointer);
    self.in_callback_.store(true, std::memory_order_release);
    if (self.stop_.load(std::memory_order_acquire)) {
      self.in_callback_.store(false, std::memory_order_release);
      return kCallbackDone;
    }
    self.api_.begin_frame(self.handle_);
    self.in_frame_ = true;
    self.tick_(self.context_);
    self.in_frame_ = false;
    self.api_.end_frame(self.handle_);
    const HDErrorInfo e = self.api_.get_error();
    if (e.errorCode != kSuccess) self.fail_code(e);
    self.in_callback_.store(false, std::memory_order_release);
    return kCallbackContinue;
  }

  void fail(std::string_view what) {
    if (failed_.load(std::memory_order_relaxed)) return;
    const auto end = fmt::format_to_n(failure_.data(), failure_.size() - 1, "{}: {}", spec_.model, what);
    *end.out = '\0';
    failed_.store(true, std::memory_order_release);
  }
  void fail_code(const HDErrorInfo& e) {
    if (failed_.load(std::memory_order_relaxed)) return;
    const char* text = api_.get_error_string ? api_.get_error_string(e.errorCode) : nullptr;
    const auto end =
        fmt::format_to_n(failure_.data(), failure_.size() - 1,
                         "{}: {} (HD error 0x{:x}, internal {}) - unplugged, or its driver stopped?", spec_.model,
                         text && *text ? text : "device error", e.errorCode, e.internalErrorCode);
    *end.out = '\0';
    failed_.store(true, std::memory_order_release);
  }

  Api api_;
  HHD handle_;
  DeviceSpec spec_;
  double continuous_force_n_;
  std::string calibration_;
  double frame_period_s_{1e-3};
  double mean_force_n_{0.0};
  ServoTick tick_{nullptr};
  void* context_{nullptr};
  HDSchedulerHandle servo_{0};
  std::atomic<bool> stop_{false};
  std::atomic<bool> in_callback_{false};
  bool in_frame_{false};
  bool ready_{false};
  bool closed_{false};
  std::atomic<bool> failed_{false};
  std::array<char, 512> failure_{};
};

// Runs `body` once on the scheduler's thread and waits for it (hdScheduleSynchronous): state
// calls such as the calibration check are made there.
template <class Body>
void on_scheduler(const Api& api, Body& body) {
  api.schedule_synchronous(
      [](void* data) -> HDCallbackCode {
        (*static_cast<Body*>(data))();
        return kCallbackDone;
      },
      &body, kMaxSchedulerPriority);
}

}  // namespace

Expected<std::unique_ptr<Device>> open_openhaptics_device(const OpenHapticsConfig& config) {
  std::vector<std::string> names;
  if (!config.library.empty()) {
    names.push_back(config.library);
  } else if (const char* env = std::getenv("HOF_HD_LIBRARY"); env && *env) {
    names.emplace_back(env);
  } else {
    names = {"libHD.so", "libHD.so.3.4", "libHD.so.3.0"};
  }
  auto library = SharedLibrary::open(names, "OpenHaptics (libHD)", kHdInstall);
  if (!library) return std::unexpected(library.error());
  Api api{std::move(*library)};
  const SharedLibrary& lib = api.library;
  for (auto bound :
       {lib.bind("hdInitDevice", api.init_device), lib.bind("hdDisableDevice", api.disable_device),
        lib.bind("hdBeginFrame", api.begin_frame), lib.bind("hdEndFrame", api.end_frame),
        lib.bind("hdGetError", api.get_error), lib.bind("hdGetErrorString", api.get_error_string),
        lib.bind("hdEnable", api.enable), lib.bind("hdGetDoublev", api.get_doublev),
        lib.bind("hdGetIntegerv", api.get_integerv), lib.bind("hdSetDoublev", api.set_doublev),
        lib.bind("hdGetString", api.get_string), lib.bind("hdStartScheduler", api.start_scheduler),
        lib.bind("hdStopScheduler", api.stop_scheduler), lib.bind("hdScheduleAsynchronous", api.schedule_asynchronous),
        lib.bind("hdScheduleSynchronous", api.schedule_synchronous), lib.bind("hdUnschedule", api.unschedule),
        lib.bind("hdCheckCalibration", api.check_calibration),
        lib.bind("hdUpdateCalibration", api.update_calibration)}) {
    if (!bound) return std::unexpected(bound.error());
  }
  const std::string name = config.device.empty() ? std::string("the default device") : "'" + config.device + "'";
  const HHD handle = api.init_device(config.device.empty() ? nullptr : config.device.c_str());
  if (const std::string error = api.error(); !error.empty() || handle == kInvalidHandle) {
    return make_error(ErrorCode::kIo,
                      fmt::format("OpenHaptics could not open {}: {}; is it plugged in, and set up with Touch "
                                  "Setup (docs/devices.md)?",
                                  name, error.empty() ? std::string("invalid handle") : error));
  }
  api.enable(kForceOutput);
  DeviceSpec spec;
  std::array<double, 6> workspace{};
  double max_force = 0.0, continuous = 0.0, stiffness = 0.0, damping = 0.0;
  api.get_doublev(kNominalMaxForce, &max_force);
  api.get_doublev(kNominalMaxContinuousForce, &continuous);
  api.get_doublev(kNominalMaxStiffness, &stiffness);
  api.get_doublev(kNominalMaxDamping, &damping);
  api.get_doublev(kUsableWorkspaceDimensions, workspace.data());
  const char* model = api.get_string(kDeviceModelType);
  if (config.model) {
    spec = *config.model;
  } else {
    spec.model = model && *model ? model : "OpenHaptics device";
    // The HD API's figures: N, N/mm, N·s/mm, and the usable workspace's box in mm
    // (min x, y, z, then max): the sphere inside it.
    if (max_force > 0.0 && std::isfinite(max_force)) spec.max_force_n = max_force;
    if (stiffness > 0.0 && std::isfinite(stiffness)) spec.max_stiffness_n_per_m = 1e3 * stiffness;
    if (damping > 0.0 && std::isfinite(damping)) spec.max_damping_n_s_per_m = 1e3 * damping;
    const double smallest =
        std::min({workspace[3] - workspace[0], workspace[4] - workspace[1], workspace[5] - workspace[2]});
    if (smallest > 0.0 && std::isfinite(smallest)) spec.workspace_radius_m = 0.5 * kMetresPerMillimetre * smallest;
  }
  api.start_scheduler();
  if (const std::string error = api.error(); !error.empty()) {
    api.disable_device(handle);
    return make_error(ErrorCode::kIo, fmt::format("OpenHaptics could not start its scheduler for {}: {}", name, error));
  }
  // The calibration, checked (and updated where the device can do it itself) on the
  // scheduler's thread.
  std::string calibration;
  auto check = [&] {
    const HDenum state = api.check_calibration();
    if (state == kCalibrationOk) {
      calibration = "ok";
    } else if (state == kCalibrationNeedsUpdate) {
      api.update_calibration(kCalibrationStyleAuto);
      calibration = "updated automatically";
    } else if (state == kCalibrationNeedsManualInput) {
      calibration = "needs manual input: put the stylus in its inkwell (or run Touch Diagnostic)";
    } else {
      calibration = fmt::format("unknown (0x{:x})", state);
    }
  };
  on_scheduler(api, check);
  return std::unique_ptr<Device>(
      std::make_unique<OpenHapticsDevice>(std::move(api), handle, std::move(spec), continuous, calibration));
}

std::string openhaptics_calibration(const Device& device) {
  const auto* d = dynamic_cast<const OpenHapticsDevice*>(&device);
  return d ? d->calibration() : std::string();
}

}  // namespace hof::haptics
