#pragma once
/// @file
/// The haptic loop: read device → calibrate → update proxy on the latest surface snapshot →
/// force (surface + effects) → safety → write → publish. In real-time mode it runs on its own
/// thread at `rate_hz`, sleeping to an absolute clock; in virtual-time mode the caller ticks
/// it in lock-step (tests, CI, `hof run --deterministic`). A tick never allocates, locks a
/// mutex or does I/O; it exchanges with other threads only through the surface TripleBuffer
/// (in), the sample TripleBuffer and the telemetry SpscRing (out), and atomics.

#include <Eigen/Geometry>
#include <array>
#include <atomic>
#include <cstdint>
#include <memory>
#include <span>
#include <thread>
#include <vector>

#include "hof/core/spsc_ring.h"
#include "hof/core/triple_buffer.h"
#include "hof/haptics/device.h"
#include "hof/haptics/force_effects.h"
#include "hof/haptics/haptic_renderer.h"
#include "hof/haptics/period_stats.h"
#include "hof/haptics/safety.h"
#include "hof/haptics/surface_snapshot.h"
#include "hof/haptics/tool.h"

namespace hof::haptics {

/// Device frame → world frame, as H3D: tracker = positionCalibration · device position;
/// orientation = orientationCalibration · device orientation.
struct Calibration {
  Eigen::Matrix4d position{Eigen::Matrix4d::Identity()};
  Eigen::Quaterniond orientation{Eigen::Quaterniond::Identity()};

  [[nodiscard]] Vec3 to_world(const Vec3& p_device) const { return (position * p_device.homogeneous()).head<3>(); }
  /// Velocities and forces transform with the linear part only.
  [[nodiscard]] Vec3 vector_to_world(const Vec3& v) const { return position.topLeftCorner<3, 3>() * v; }
  [[nodiscard]] Vec3 vector_to_device(const Vec3& v) const;
};

struct HapticLoopConfig {
  double rate_hz{1000.0};
  RendererConfig renderer;
  SurfaceMaterial material;
  SafetyConfig safety;
  Calibration calibration;
  bool realtime_priority{true};  ///< ask for SCHED_FIFO (ignored when not permitted)
  int cpu{-1};                   ///< run the real-time thread on this CPU only (-1: anywhere; cpu_affinity.h)
  std::size_t telemetry_capacity{1 << 16};
};

/// Settings the haptic loop takes from the simulation thread between two ticks (the command
/// seam's route to the loop: no lock, no allocation in the tick). The producer writes a whole
/// slot each time. Force effects are copied into the loop's own storage, which holds up to
/// kMaxEffectsEach of each kind (validate_effects() refuses more).
struct HapticSettings {
  bool valid{false};  ///< false: the loop keeps its construction config
  RendererConfig renderer;
  std::vector<SurfaceMaterial> materials;  ///< per snapshot part (body); empty: config material
  ForceEffects effects;
  double max_force_n{0.0};  ///< the user's force limit (SafetyConfig::max_force_n)
  /// Device → world. A change restarts the proxy at the next reading (as a device switch does:
  /// the stylus jumps in the world, and must not be pulled back through a surface).
  Calibration calibration;
};
inline constexpr std::size_t kMaxEffectsEach = 32;
/// Triangles of all MagneticGeometryEffects together (each is searched every tick).
inline constexpr std::size_t kMaxMagnetTriangles = 2048;
/// Checks counts and values of a set of effects (finite, non-negative constants).
[[nodiscard]] Expected<void> validate_effects(const ForceEffects& effects);

/// Haptic layers (H3D HapticLayeredGroup): each layer has its own surfaces and its own proxy,
/// and the forces of the layers add up.
inline constexpr std::size_t kMaxLayers = 4;

/// What the simulation needs from one tick (its own channel, apart from telemetry).
struct HapticContact {
  struct Layer {
    Vec3 proxy{Vec3::Zero()};
    bool contact{false};
    std::int32_t triangle{-1};  ///< in this layer's snapshot
    Vec3 barycentric{Vec3::Zero()};
    Vec3 force{Vec3::Zero()};  ///< this layer's share of the force sent to the device, world, N
    /// The force whose opposite the tissue takes: `force`, except with the FEM-reaction
    /// coupling, where it is the renderer's spring (ContactState::coupling_force), as safety
    /// scales what is sent.
    Vec3 load{Vec3::Zero()};
  };
  /// The tool's state this tick; its force is its share of what was sent (as the layers').
  ToolState tool;
  std::uint64_t tick{0};
  double time_s{0.0};
  bool valid{false};         ///< the device gave a reading (proxies meaningful)
  Vec3 force{Vec3::Zero()};  ///< sent to the device, world, N
  bool clamped{false};       ///< the requested force exceeded the device's limit
  std::array<Layer, kMaxLayers> layers{};
  std::uint8_t layer_count{1};
};

/// One tick, as published to other threads and logged (world frame unless noted).
struct HapticSample {
  std::uint64_t tick{0};
  double time_s{0.0};
  Vec3 device{Vec3::Zero()};
  Vec3 device_velocity{Vec3::Zero()};
  Vec3 proxy{Vec3::Zero()};
  Vec3 force{Vec3::Zero()};            ///< sent to the device (after safety), world frame, N
  Vec3 requested_force{Vec3::Zero()};  ///< before safety
  bool contact{false};
  std::int32_t layer{0};      ///< the layer of the contact below (the first in contact)
  std::int32_t triangle{-1};  ///< in that layer's snapshot
  Vec3 barycentric{Vec3::Zero()};
  Vec3 contact_point{Vec3::Zero()};
  Vec3 contact_normal{Vec3::Zero()};
  double penetration_m{0.0};
  std::uint64_t snapshot_sequence{0};
  double period_s{0.0};
  std::uint32_t buttons{0};
  bool valid{false};
  ToolState tool;  ///< the mounted tool's state (tool.active false: none)
};

class HapticLoop {
 public:
  /// `surfaces` is written by the simulation (or a static scene) and read here; `settings`
  /// (optional) carries changed settings from the simulation thread.
  HapticLoop(Device& device, TripleBuffer<SurfaceSnapshot>& surfaces, const HapticLoopConfig& config,
             TripleBuffer<HapticSettings>* settings = nullptr);
  /// Several haptic layers (1 to kMaxLayers), outermost first: one proxy each.
  HapticLoop(Device& device, std::span<TripleBuffer<SurfaceSnapshot>* const> layers, const HapticLoopConfig& config,
             TripleBuffer<HapticSettings>* settings = nullptr);
  HapticLoop(const HapticLoop&) = delete;
  HapticLoop& operator=(const HapticLoop&) = delete;
  ~HapticLoop();

  /// One tick at haptic time `time_s` (virtual-time mode). Not to be mixed with start().
  void tick(double time_s);

  /// Switches to another device between two ticks (the command seam's route; call it from
  /// one producer thread, e.g. the simulation). The new device gets its own safety filter —
  /// its own force limit from the first tick, fading in from zero — and the proxy is placed
  /// anew at its first reading. `device` must outlive the loop. Returns false while an earlier
  /// switch has not been taken by a tick yet.
  bool switch_device(Device& device);
  /// The device the ticks use now (the producer may read it after a switch was taken).
  [[nodiscard]] Device& device() { return *binding_.load(std::memory_order_acquire)->device; }
  [[nodiscard]] const Device& device() const { return *binding_.load(std::memory_order_acquire)->device; }

  /// Mounts a tool (tool.h) whose tick runs after the surfaces and before the force effects;
  /// null: none. Call before the first tick or start(); `tool` must outlive the loop.
  void set_tool(Tool* tool) { tool_ = tool; }
  [[nodiscard]] Tool* tool() const { return tool_; }

  /// Real-time mode: starts the thread (or, for a device with a servo loop of its own, lets
  /// that loop call the ticks); time counts from the call.
  void start();
  /// The CPU the next start() runs the thread on (-1: anywhere). Not while running.
  void set_cpu(int cpu) { config_.cpu = cpu; }
  /// Whether the running thread got the CPU it was given.
  [[nodiscard]] bool pinned() const { return pinned_.load(std::memory_order_acquire); }
  /// Stops the thread (joins), then sends a zero force. Idempotent.
  void stop();
  [[nodiscard]] bool running() const { return running_.load(std::memory_order_acquire); }

  /// The simulation behind the surfaces has failed (diverged): its last geometry is not to be
  /// trusted, so the ticks treat it as stale at once — the watchdog fades the force out over
  /// SafetyConfig::fade_out_s instead of rendering it until it is max_snapshot_age_s old.
  /// Cleared (false) when the simulation steps again. Any thread.
  void set_simulation_failed(bool failed) { simulation_failed_.store(failed, std::memory_order_release); }
  [[nodiscard]] bool simulation_failed() const { return simulation_failed_.load(std::memory_order_acquire); }

  /// Latest sample (consumer side: one reader thread).
  TripleBuffer<HapticSample>& samples() { return samples_; }
  /// Every tick's sample, for logging (one consumer).
  SpscRing<HapticSample>& telemetry() { return telemetry_; }
  /// Every tick's contact, for the simulation (one consumer).
  SpscRing<HapticContact>& contacts() { return contacts_; }

  /// Period statistics and safety counters: read them after stop() (or in virtual mode).
  [[nodiscard]] const PeriodStats& period_stats() const { return stats_; }
  [[nodiscard]] const SafetyCounters& safety_counters() const { return binding_.load()->safety.counters(); }
  [[nodiscard]] std::uint64_t ticks() const { return ticks_.load(std::memory_order_relaxed); }
  /// The renderer (proxy) of the outermost layer; renderer(l) of layer l.
  [[nodiscard]] const HapticRenderer& renderer(std::size_t layer = 0) const { return renderers_[layer]; }
  [[nodiscard]] HapticRenderer& renderer(std::size_t layer = 0) { return renderers_[layer]; }
  [[nodiscard]] std::size_t layer_count() const { return layers_.size(); }
  ForceEffects& effects() { return effects_; }
  [[nodiscard]] double nominal_period_s() const { return 1.0 / config_.rate_hz; }

  /// What the real-time thread got when it asked for SCHED_FIFO (a report says it: without it,
  /// deadline misses on a loaded machine are expected, not a defect).
  /// `device_servo`: the device's own servo loop calls the ticks (Device::start_servo).
  enum class Scheduling : int { not_started, not_requested, realtime, refused, device_servo };
  [[nodiscard]] Scheduling scheduling() const {
    return static_cast<Scheduling>(scheduling_.load(std::memory_order_acquire));
  }

 private:
  void run_thread();
  /// One real-time tick: its time and period from the monotonic clock (the thread's loop, or
  /// the device's servo callback).
  void realtime_tick();
  static void servo_tick(void* loop) { static_cast<HapticLoop*>(loop)->realtime_tick(); }
  void tick_impl(double time_s, double period_s, bool overrun);
  void take_settings();
  /// The calibration the tick uses (and what follows from it: the force rotation, the scale).
  void apply_calibration(const Calibration& calibration);

  // A device and the safety filter made for its specification, switched as one.
  struct DeviceBinding {
    Device* device;
    SafetyFilter safety;
  };
  std::vector<std::unique_ptr<DeviceBinding>> bindings_;  // every binding made (producer side)
  std::atomic<DeviceBinding*> binding_{nullptr};          // the ticks' (written only by the tick)
  std::atomic<DeviceBinding*> pending_{nullptr};          // a switch waiting for the next tick
  std::vector<TripleBuffer<SurfaceSnapshot>*> layers_;
  HapticLoopConfig config_;
  std::vector<HapticRenderer> renderers_;
  std::vector<char> have_surface_;
  ForceEffects effects_;
  PeriodStats stats_;
  TripleBuffer<HapticSample> samples_;
  SpscRing<HapticSample> telemetry_;
  SpscRing<HapticContact> contacts_;
  TripleBuffer<HapticSettings>* settings_{nullptr};
  RendererConfig last_renderer_;  // the last renderer configuration taken from the settings
  double max_force_n_{0.0};       // the user's force limit (tick thread), kept across device switches
  std::atomic<bool> running_{false};
  std::atomic<bool> stop_requested_{false};
  std::atomic<bool> simulation_failed_{false};
  std::atomic<std::uint64_t> ticks_{0};
  std::atomic<int> scheduling_{static_cast<int>(Scheduling::not_started)};
  std::atomic<bool> pinned_{false};
  std::thread thread_;
  Eigen::Matrix3d world_to_device_{Eigen::Matrix3d::Identity()};
  double world_scale_{1.0};  // world units per metre of device travel
  Tool* tool_{nullptr};
  double last_time_s_{-1.0};
  double origin_s_{0.0};  // real-time mode: CLOCK_MONOTONIC at start(), s
  // Real-time ticks: the last one's start and when the next is due (s, monotonic).
  double last_start_s_{0.0};
  double next_due_s_{0.0};
  bool first_realtime_tick_{true};
  Device* servo_device_{nullptr};  // the device whose servo loop ticks, while it does
  bool proxy_initialised_{false};
  // The readings' recent positions (device frame), to tell a glitch from a motion.
  Vec3 last_reading_position_{Vec3::Zero()};
  Vec3 last_rendered_position_{Vec3::Zero()};
  bool have_reading_history_{false};
};

}  // namespace hof::haptics
