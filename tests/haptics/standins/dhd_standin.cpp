// A stand-in for Force Dimension's SDK (libdhd.so): the same C functions, simulating one
// device, so that the tests exercise HoF's run-time loading of the SDK with no hardware and
// no vendor software. The "hand" holding the device moves as the test sets it (in the SDK's
// frame: x toward the user, y right, z up; metres); every force the device is sent is
// recorded. `standin_dhd_*` functions, found by the test through dlsym on the same file,
// set the scene and inject faults. Built twice: DHD_STANDIN_WITHOUT_SET_FORCE leaves out
// dhdSetForce (an SDK missing a function).

#include <atomic>
#include <chrono>
#include <cmath>
#include <limits>
#include <mutex>
#include <thread>

namespace {

struct State {
  std::mutex mutex;
  int devices{1};
  int system_type{33};     // omega.3
  double max_force{-1.0};  // dhdGetMaxForce: negative = no limit reported
  bool open{false};
  bool forces_enabled{false};
  double position[3]{0.0, 0.0, 0.0};
  double velocity[3]{0.0, 0.0, 0.0};
  // Faults: after `fault_after` position reads, kind 1 makes every call fail (the device
  // gone), kind 2 gives NaN positions, kind 3 stalls one read by `stall_ms`.
  int fault{0};
  long fault_after{0};
  int stall_ms{0};
  long reads{0};
  long forces_sent{0};
  double last_force[3]{0.0, 0.0, 0.0};
  double max_force_seen{0.0};
  bool non_finite_force{false};
  const char* last_error{"no error"};
};

State& state() {
  static State s;
  return s;
}

bool gone(State& s) { return s.fault == 1 && s.reads >= s.fault_after; }

}  // namespace

extern "C" {

// ---- the SDK's functions (dhdc.h)

int dhdGetDeviceCount() {
  std::lock_guard lock(state().mutex);
  return state().devices;
}

int dhdOpenID(char index) {
  State& s = state();
  std::lock_guard lock(s.mutex);
  if (index < 0 || index >= s.devices) {
    s.last_error = "invalid index";
    return -1;
  }
  s.open = true;
  return index;
}

int dhdClose(char) {
  std::lock_guard lock(state().mutex);
  state().open = false;
  return 0;
}

int dhdGetSystemType(char) { return state().system_type; }

const char* dhdGetSystemName(char) { return "omega.3 (stand-in)"; }

int dhdEnableForce(unsigned char on, char) {
  std::lock_guard lock(state().mutex);
  state().forces_enabled = on != 0;
  return 0;
}

double dhdGetMaxForce(char) { return state().max_force; }

int dhdGetPosition(double* x, double* y, double* z, char) {
  State& s = state();
  int stall = 0;
  {
    std::lock_guard lock(s.mutex);
    ++s.reads;
    if (gone(s)) {
      s.last_error = "communication error (stand-in: unplugged)";
      return -1;
    }
    if (s.fault == 3 && s.reads == s.fault_after) stall = s.stall_ms;
    const bool nan = s.fault == 2 && s.reads >= s.fault_after;
    *x = nan ? std::numeric_limits<double>::quiet_NaN() : s.position[0];
    *y = s.position[1];
    *z = s.position[2];
  }
  if (stall > 0) std::this_thread::sleep_for(std::chrono::milliseconds(stall));
  return 0;
}

int dhdGetLinearVelocity(double* x, double* y, double* z, char) {
  State& s = state();
  std::lock_guard lock(s.mutex);
  if (gone(s)) return -1;
  *x = s.velocity[0];
  *y = s.velocity[1];
  *z = s.velocity[2];
  return 0;
}

unsigned int dhdGetButtonMask(char) { return 1; }

#ifndef DHD_STANDIN_WITHOUT_SET_FORCE
int dhdSetForce(double fx, double fy, double fz, char) {
  State& s = state();
  std::lock_guard lock(s.mutex);
  if (gone(s)) return -1;
  if (!std::isfinite(fx) || !std::isfinite(fy) || !std::isfinite(fz)) s.non_finite_force = true;
  s.last_force[0] = fx;
  s.last_force[1] = fy;
  s.last_force[2] = fz;
  s.max_force_seen = std::max(s.max_force_seen, std::sqrt(fx * fx + fy * fy + fz * fz));
  ++s.forces_sent;
  return 0;
}
#endif

const char* dhdErrorGetLastStr() { return state().last_error; }

// ---- the test's controls

void standin_dhd_reset(int devices, int system_type, double max_force) {
  State& s = state();
  std::lock_guard lock(s.mutex);
  s.devices = devices;
  s.system_type = system_type;
  s.max_force = max_force;
  s.fault = 0;
  s.fault_after = 0;
  s.stall_ms = 0;
  s.reads = 0;
  s.forces_sent = 0;
  s.max_force_seen = 0.0;
  s.non_finite_force = false;
  s.last_force[0] = s.last_force[1] = s.last_force[2] = 0.0;
  s.position[0] = s.position[1] = s.position[2] = 0.0;
  s.velocity[0] = s.velocity[1] = s.velocity[2] = 0.0;
  s.last_error = "no error";
}

void standin_dhd_set_hand(double x, double y, double z, double vx, double vy, double vz) {
  State& s = state();
  std::lock_guard lock(s.mutex);
  s.position[0] = x;
  s.position[1] = y;
  s.position[2] = z;
  s.velocity[0] = vx;
  s.velocity[1] = vy;
  s.velocity[2] = vz;
}

void standin_dhd_set_fault(int kind, long after_reads, int stall_ms) {
  State& s = state();
  std::lock_guard lock(s.mutex);
  s.fault = kind;
  s.fault_after = after_reads;
  s.stall_ms = stall_ms;
}

// Forces sent so far, the largest magnitude, whether one was not finite, the last one.
long standin_dhd_forces(double* max_magnitude, int* non_finite, double* last) {
  State& s = state();
  std::lock_guard lock(s.mutex);
  *max_magnitude = s.max_force_seen;
  *non_finite = s.non_finite_force ? 1 : 0;
  for (int i = 0; i < 3; ++i) last[i] = s.last_force[i];
  return s.forces_sent;
}

long standin_dhd_reads() {
  std::lock_guard lock(state().mutex);
  return state().reads;
}

int standin_dhd_open() {
  std::lock_guard lock(state().mutex);
  return state().open ? 1 : 0;
}

}  // extern "C"
