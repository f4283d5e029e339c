// A stand-in for OpenHaptics' HD API (libHD.so): the same C functions, simulating one
// Touch-like device with its servo scheduler (a thread calling the scheduled callbacks once
// per millisecond frame), so that the tests exercise HoF's run-time loading and its
// scheduler-callback mode with no hardware. It works in millimetres, as the HD API does.
// `standin_hd_*` functions, found by the test through dlsym on the same file, set the hand's
// position, read what was sent and count the frames.

#include <atomic>
#include <chrono>
#include <cmath>
#include <mutex>
#include <string_view>
#include <thread>
#include <vector>

// The HD API's error record, at global scope under its own name as in hdDefines.h (HoF calls
// hdGetError through a pointer whose type names this struct).
struct HDErrorInfo {
  unsigned int errorCode;
  int internalErrorCode;
  unsigned int hHD;
};

namespace {

using HHD = unsigned int;
using HDenum = unsigned int;
using HDCallbackCode = unsigned int;
using HDSchedulerHandle = unsigned long;
using HDSchedulerCallback = HDCallbackCode (*)(void*);

struct Scheduled {
  HDSchedulerCallback callback;
  void* data;
  HDSchedulerHandle handle;
};

struct State {
  std::mutex mutex;  // the callbacks' list
  std::vector<Scheduled> callbacks;
  HDSchedulerHandle next_handle{1};
  std::thread scheduler;
  std::atomic<bool> running{false};
  std::atomic<long> frames{0};       // frames begun and ended
  std::atomic<long> frames_open{0};  // a frame begun and not ended (must stay 0 or 1)
  bool in_frame{false};
  bool device_ok{true};
  unsigned int pending_error{0};
  std::atomic<double> position_mm[3]{0.0, 0.0, 0.0};  // set by the test while the servo runs
  std::atomic<double> force[3]{0.0, 0.0, 0.0};
  std::atomic<double> max_force_seen{0.0};
  std::atomic<long> forces_outside_frame{0};
  int calibration{0x5000};
};

State& state() {
  static State s;
  return s;
}

void scheduler_loop() {
  State& s = state();
  auto next = std::chrono::steady_clock::now();
  while (s.running.load()) {
    {
      std::lock_guard lock(s.mutex);
      for (std::size_t i = 0; i < s.callbacks.size();) {
        const Scheduled c = s.callbacks[i];
        if (c.callback(c.data) == 0) {  // HD_CALLBACK_DONE
          s.callbacks.erase(s.callbacks.begin() + static_cast<std::ptrdiff_t>(i));
        } else {
          ++i;
        }
      }
    }
    next += std::chrono::milliseconds(1);
    std::this_thread::sleep_until(next);
  }
}

}  // namespace

extern "C" {

HHD hdInitDevice(const char* name) {
  State& s = state();
  if (name && std::string_view(name) != "Default Device" && std::string_view(name) != "Touch") {
    s.pending_error = 0x300;  // HD_DEVICE_FAULT
    return 0xFFFFFFFFu;
  }
  return 1;
}

void hdDisableDevice(HHD) {}

void hdBeginFrame(HHD) {
  State& s = state();
  s.in_frame = true;
  s.frames_open.fetch_add(1);
}

void hdEndFrame(HHD) {
  State& s = state();
  s.in_frame = false;
  s.frames_open.fetch_sub(1);
  s.frames.fetch_add(1);
}

HDErrorInfo hdGetError() {
  State& s = state();
  const HDErrorInfo e{s.pending_error, s.pending_error ? 42 : 0, 1};
  s.pending_error = 0;
  return e;
}

const char* hdGetErrorString(unsigned int code) {
  return code == 0x300 ? "Device fault (stand-in)" : "Error (stand-in)";
}

void hdEnable(HDenum) {}

void hdGetDoublev(HDenum what, double* out) {
  State& s = state();
  switch (what) {
    case 0x2050:  // HD_CURRENT_POSITION, mm
      for (int i = 0; i < 3; ++i) out[i] = s.position_mm[i].load();
      break;
    case 0x2051:  // HD_CURRENT_VELOCITY, mm/s
      out[0] = out[1] = out[2] = 0.0;
      break;
    case 0x2603:
      *out = 3.3;
      break;  // HD_NOMINAL_MAX_FORCE, N
    case 0x2604:
      *out = 0.88;
      break;  // HD_NOMINAL_MAX_CONTINUOUS_FORCE, N
    case 0x2602:
      *out = 1.26;
      break;  // HD_NOMINAL_MAX_STIFFNESS, N/mm
    case 0x2609:
      *out = 0.005;
      break;        // HD_NOMINAL_MAX_DAMPING, N·s/mm
    case 0x2551: {  // HD_USABLE_WORKSPACE_DIMENSIONS, mm
      const double box[6] = {-80.0, -60.0, -35.0, 80.0, 60.0, 35.0};
      for (int i = 0; i < 6; ++i) out[i] = box[i];
      break;
    }
    default:
      break;
  }
}

void hdGetIntegerv(HDenum what, int* out) {
  if (what == 0x2000) *out = 0;  // HD_CURRENT_BUTTONS
}

void hdSetDoublev(HDenum what, const double* in) {
  State& s = state();
  if (what != 0x2700) return;  // HD_CURRENT_FORCE
  if (!s.in_frame) s.forces_outside_frame.fetch_add(1);
  for (int i = 0; i < 3; ++i) s.force[i].store(in[i]);
  s.max_force_seen.store(std::max(s.max_force_seen.load(), std::sqrt(in[0] * in[0] + in[1] * in[1] + in[2] * in[2])));
}

const char* hdGetString(HDenum what) { return what == 0x2501 ? "Touch (stand-in)" : ""; }

void hdStartScheduler() {
  State& s = state();
  if (s.running.exchange(true)) return;
  s.scheduler = std::thread(scheduler_loop);
}

void hdStopScheduler() {
  State& s = state();
  if (!s.running.exchange(false)) return;
  s.scheduler.join();
}

HDSchedulerHandle hdScheduleAsynchronous(HDSchedulerCallback callback, void* data, unsigned short) {
  State& s = state();
  std::lock_guard lock(s.mutex);
  s.callbacks.push_back({callback, data, s.next_handle});
  return s.next_handle++;
}

void hdScheduleSynchronous(HDSchedulerCallback callback, void* data, unsigned short) {
  State& s = state();
  std::atomic<bool> done{false};
  struct Call {
    HDSchedulerCallback callback;
    void* data;
    std::atomic<bool>* done;
  } call{callback, data, &done};
  {
    std::lock_guard lock(s.mutex);
    s.callbacks.push_back({[](void* c) -> HDCallbackCode {
                             auto* call_data = static_cast<Call*>(c);
                             call_data->callback(call_data->data);
                             call_data->done->store(true);
                             return 0;
                           },
                           &call, 0});
  }
  while (!done.load()) std::this_thread::sleep_for(std::chrono::microseconds(100));
}

void hdUnschedule(HDSchedulerHandle handle) {
  State& s = state();
  // Called from another thread than the scheduler's: takes the list's lock, which a frame in
  // progress holds; the real API does not wait, so this one returns once the list is changed.
  std::lock_guard lock(s.mutex);
  for (std::size_t i = 0; i < s.callbacks.size(); ++i) {
    if (s.callbacks[i].handle == handle) {
      s.callbacks.erase(s.callbacks.begin() + static_cast<std::ptrdiff_t>(i));
      break;
    }
  }
}

HDenum hdCheckCalibration() { return static_cast<HDenum>(state().calibration); }
void hdUpdateCalibration(HDenum) { state().calibration = 0x5000; }

// ---- the test's controls

void standin_hd_set_hand_mm(double x, double y, double z) {
  State& s = state();
  s.position_mm[0].store(x);
  s.position_mm[1].store(y);
  s.position_mm[2].store(z);
}

void standin_hd_set_calibration(int state_code) { state().calibration = state_code; }

long standin_hd_frames() { return state().frames.load(); }

long standin_hd_forces_outside_frame() { return state().forces_outside_frame.load(); }

double standin_hd_max_force() { return state().max_force_seen.load(); }

void standin_hd_last_force(double* out) {
  for (int i = 0; i < 3; ++i) out[i] = state().force[i].load();
}

}  // extern "C"
