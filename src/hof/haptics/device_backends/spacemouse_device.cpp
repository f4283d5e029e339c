#include "hof/haptics/device_backends/spacemouse_device.h"

#include <fcntl.h>
#include <poll.h>
#include <spnav.h>
#include <unistd.h>

#include <fmt/format.h>

#include <array>
#include <atomic>
#include <cerrno>
#include <chrono>
#include <cmath>
#include <thread>

#include "hof/haptics/device_backends/udp_device.h"  // SeqLock

namespace hof::haptics {
namespace {

using Clock = std::chrono::steady_clock;

/// libspnav keeps a single process-wide connection: this flag says whether a device owns it.
std::atomic<bool> g_connection_taken{false};

struct Snapshot {
  double p[3]{};
  double v[3]{};
  std::uint32_t buttons{0};
  std::uint32_t pad{0};
};

}  // namespace

struct SpacemouseDevice::Impl {
  SpacemouseConfig config;
  int wake_read{-1};
  int wake_write{-1};
  std::thread thread;
  std::atomic<bool> stop{false};
  std::atomic<bool> closed{false};
  std::atomic<DeviceHealth> health{DeviceHealth::kOk};
  SeqLock<Snapshot> state;
  Snapshot last_read{};

  ~Impl() {
    for (const int fd : {wake_read, wake_write}) {
      if (fd >= 0) ::close(fd);
    }
  }

  void run();
};

// The polling loop: wait (≤ 2 ms) for spacenavd events or the wake pipe, fold events into a
// commanded velocity and the button mask, integrate the position over the elapsed time and
// publish. A deflection older than hold_timeout_s is treated as released.
void SpacemouseDevice::Impl::run() {
  const int fd = spnav_fd();
  Vec3 p = Vec3::Zero();
  Vec3 v = Vec3::Zero();
  std::uint32_t buttons = 0;
  const double radius = config.spec.workspace_radius_m;
  auto last_time = Clock::now();
  auto last_motion = last_time;
  while (!stop.load(std::memory_order_acquire)) {
    std::array<pollfd, 2> fds{pollfd{fd, POLLIN, 0}, pollfd{wake_read, POLLIN, 0}};
    const int ready = ::poll(fds.data(), fds.size(), 2);
    if (ready < 0 && errno != EINTR) break;
    if (fds[1].revents != 0) break;
    const auto now = Clock::now();
    if ((fds[0].revents & (POLLERR | POLLHUP | POLLNVAL)) != 0) {
      health.store(DeviceHealth::kFailed, std::memory_order_release);
      break;
    }
    spnav_event event{};
    while (spnav_poll_event(&event) != 0) {
      if (event.type == SPNAV_EVENT_MOTION) {
        v = config.scale_m_per_unit_s * Vec3(event.motion.x, event.motion.y, -event.motion.z);
        last_motion = now;
      } else if (event.type == SPNAV_EVENT_BUTTON && event.button.bnum >= 0 && event.button.bnum < 32) {
        const std::uint32_t bit = 1U << event.button.bnum;
        buttons = event.button.press != 0 ? (buttons | bit) : (buttons & ~bit);
      }
    }
    if (std::chrono::duration<double>(now - last_motion).count() > config.hold_timeout_s) v.setZero();

    const double dt = std::chrono::duration<double>(now - last_time).count();
    last_time = now;
    p += dt * v;
    if (radius > 0.0 && p.norm() > radius) p *= radius / p.norm();  // stay in the workspace

    Snapshot s;
    for (int i = 0; i < 3; ++i) {
      s.p[i] = p[i];
      s.v[i] = v[i];
    }
    s.buttons = buttons;
    state.store(s);
  }
}

SpacemouseDevice::SpacemouseDevice(std::unique_ptr<Impl> impl, const DeviceSpec& spec)
    : impl_(std::move(impl)), spec_(spec) {}

SpacemouseDevice::~SpacemouseDevice() { close(); }

Expected<std::unique_ptr<SpacemouseDevice>> SpacemouseDevice::open(const SpacemouseConfig& config) {
  if (!std::isfinite(config.scale_m_per_unit_s) || config.scale_m_per_unit_s <= 0.0) {
    return make_error(
        ErrorCode::kInvalidArgument,
        fmt::format("spacemouse: scale must be > 0 m per unit per second (got {})", config.scale_m_per_unit_s));
  }
  if (g_connection_taken.exchange(true)) {
    return make_error(ErrorCode::kIo, "spacemouse: already open (libspnav allows one connection per process)");
  }
  if (spnav_open() == -1) {
    g_connection_taken.store(false);
    return make_error(ErrorCode::kIo, "spacemouse: no spacenavd running (spnav_open failed)");
  }
  auto impl = std::make_unique<Impl>();
  impl->config = config;
  std::array<int, 2> pipe_fds{-1, -1};
  if (::pipe2(pipe_fds.data(), O_CLOEXEC | O_NONBLOCK) != 0) {
    spnav_close();
    g_connection_taken.store(false);
    return make_error(ErrorCode::kIo, "spacemouse: cannot create the wake pipe");
  }
  impl->wake_read = pipe_fds[0];
  impl->wake_write = pipe_fds[1];
  Impl* raw = impl.get();
  impl->thread = std::thread([raw] { raw->run(); });
  return std::unique_ptr<SpacemouseDevice>(new SpacemouseDevice(std::move(impl), config.spec));
}

DeviceReading SpacemouseDevice::read(double time_s) {
  Snapshot s;
  if (impl_->state.try_load(s)) impl_->last_read = s;
  s = impl_->last_read;
  DeviceReading r;
  r.time_s = time_s;
  r.position_m = Vec3(s.p[0], s.p[1], s.p[2]);
  r.velocity_m_per_s = Vec3(s.v[0], s.v[1], s.v[2]);
  r.buttons = s.buttons;
  r.valid = health() == DeviceHealth::kOk;
  return r;
}

void SpacemouseDevice::write_force(const Vec3& /*force_n*/, const Vec3& /*torque_n_m*/) {}

DeviceHealth SpacemouseDevice::health() const { return impl_->health.load(std::memory_order_acquire); }

void SpacemouseDevice::close() {
  if (!impl_ || impl_->closed.exchange(true)) return;
  impl_->stop.store(true, std::memory_order_release);
  const std::uint8_t byte = 1;
  [[maybe_unused]] const ssize_t w = ::write(impl_->wake_write, &byte, 1);
  if (impl_->thread.joinable()) impl_->thread.join();
  spnav_close();
  g_connection_taken.store(false);
}

}  // namespace hof::haptics
