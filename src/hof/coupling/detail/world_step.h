#pragma once
/// @file
/// The world a session steps, and the one stepping function used by both virtual and real
/// time: commands → the contacts since the last step become forces on the touched bodies →
/// every due deformable body steps (in parallel when there are several) → one snapshot is
/// published. Free functions over the plain `World` record: the session, the runner, the
/// command seam and the snapshot publisher each hold it by reference.

#include <array>
#include <atomic>
#include <chrono>
#include <cstdint>
#include <memory>
#include <span>
#include <vector>

#include "hof/core/triple_buffer.h"
#include "hof/coupling/detail/body_contact_pass.h"
#include "hof/coupling/session.h"

namespace hof::coupling {
class CommandSeam;
}

namespace hof::coupling::detail {

class SnapshotPublisher;

using Clock = std::chrono::steady_clock;
inline double seconds_between(Clock::time_point a, Clock::time_point b) {
  return std::chrono::duration<double>(b - a).count();
}

// The FEM-reaction coupling's patch: the surface within this radius of the contact (or twice the
// contact triangle's longest edge, when larger), at most this many nodes.
constexpr double kFemReactionPatchRadius_m = 0.01;
constexpr std::size_t kFemReactionPatchCapacity = 4096;

/// The FEM-reaction coupling needs one simulation step per haptic tick.
bool fem_reaction_step_fits(double dt_s, double rate_hz);

/// What one hand left on a body since the body last stepped.
struct HandLoad {
  // The proxy's contact: its reaction summed, where it touched last.
  Vec3 reaction_sum{Vec3::Zero()};
  int contact_ticks{0};
  std::int32_t last_triangle{-1};  // local to the body's surface
  Vec3 last_barycentric{Vec3::Zero()};
  // The tool in or on this body: its force summed, its latest state.
  Vec3 tool_force_sum{Vec3::Zero()};
  int tool_ticks{0};
  haptics::ToolState last_tool;

  void clear() {
    reaction_sum.setZero();
    contact_ticks = 0;
    tool_force_sum.setZero();
    tool_ticks = 0;
  }
};

/// A body and what the world keeps of it between steps.
struct BodyRuntime {
  SessionBody body;
  mechanics::MechanicalState state;  // deformable bodies
  std::vector<Vec3> surface_positions, surface_velocities;
  // Contact since this body last stepped, one load per hand (the first hand's first).
  std::vector<HandLoad> loads;
  std::int64_t ticks_at_last_step{0};
  double next_step_s{0.0};
  BodyReport report;
  bool inside_since_start{false};
  std::size_t layer{0};  // haptic layer
  std::size_t part{0};   // part of the layer's snapshot
  // FEM-reaction coupling: the nodes of the contact's neighbourhood (reserved: no allocation).
  std::vector<std::int32_t> patch_nodes;
  std::vector<double> patch_weights;
  int threads{0};  // the threads its state's arena was set to (0: the model's own setting)

  // This step's reaction of the tissue at a contact on triangle `tri` (barycentric `bary`,
  // carried by `triangle_nodes`), felt at the next tick (world_step.cpp says how).
  Vec3 fem_reaction(const mesh::Tri& tri, const std::array<double, 3>& bary,
                    std::span<const std::int32_t> triangle_nodes);
};

/// A haptic layer: the bodies felt through one proxy, as one snapshot.
struct LayerRuntime {
  std::vector<std::size_t> bodies;                  // indices into World::bodies, in part order
  haptics::SurfaceSnapshot rest;                    // the layer's surfaces at rest (parts name bodies)
  TripleBuffer<haptics::SurfaceSnapshot> surfaces;  // to the haptic loop
  TripleBuffer<haptics::SurfaceSnapshot> graphics;  // to a reader (the window)
  std::vector<Vec3> positions, velocities;          // the layer's vertices now
  Vec3 proxy{Vec3::Zero()};                         // this layer's proxy at the last tick
  std::int32_t proxy_triangle{-1};                  // the triangle it touched at that tick (-1: none)
  bool proxy_outside_box{false};                    // outside the box of `positions` (fall-through test)
};

/// Wall time of the steps in the thesis' three states (SessionReport::rate_*).
struct StateTimer {
  double untouched_s{0}, deforming_s{0}, contact_s{0};
  std::int64_t untouched{0}, deforming{0}, contact{0};
  void add(bool in_contact, bool moving, double seconds) {
    if (in_contact) {
      contact_s += seconds;
      ++contact;
    } else if (moving) {
      deforming_s += seconds;
      ++deforming;
    } else {
      untouched_s += seconds;
      ++untouched;
    }
  }
  static double rate(std::int64_t n, double s) { return s > 0.0 ? static_cast<double>(n) / s : 0.0; }
};

/// A hand beyond the first: its device, its haptic loop and what that reads and writes. The
/// first hand is World's own device, loop and settings (the commands reach it).
struct HandRuntime {
  HandConfig config;
  std::unique_ptr<haptics::Device> device;  // declared before the loop: it outlives it
  // Its snapshot of each layer (a TripleBuffer has one reader): filled by the publisher
  // from the first hand's, never computed twice.
  std::vector<std::unique_ptr<TripleBuffer<haptics::SurfaceSnapshot>>> surfaces;
  TripleBuffer<haptics::HapticSettings> settings;
  std::unique_ptr<haptics::HapticLoop> loop;
  HandReport report;
};

/// Everything the simulation steps and the haptic loop it feeds. Written by the simulation
/// thread only (in real time) or by the caller's (virtual time); the atomics are read anywhere.
struct World {
  SessionConfig config;
  std::vector<BodyRuntime> bodies;
  std::vector<BodyRuntime*> due;  // the bodies stepping this step (scratch)
  std::vector<char> step_ok;      // their results (scratch)
  std::vector<char> due_flags;    // (bodies) 1 for the bodies stepping this step (scratch)
  BodyContactPass body_contacts;  // contact between bodies (inactive unless config.contacts.enabled)
  std::vector<std::unique_ptr<LayerRuntime>> layers;
  std::atomic<double> dt{0.01};   // written by the simulation (a dt command), read anywhere
  double time_s{0.0};             // simulated time of the world
  std::int64_t virtual_ticks{0};  // haptic ticks run in virtual time so far (their clock)
  // The device and those switched to: kept until the loop is gone (declared before it).
  std::unique_ptr<haptics::Device> device;
  std::vector<std::shared_ptr<haptics::Device>> switched_devices;
  haptics::Device* last_device{nullptr};           // the device the ticks used at the last step
  TripleBuffer<haptics::HapticSettings> settings;  // to the haptic loop
  haptics::HapticSettings current_settings;
  std::unique_ptr<haptics::HapticLoop> loop;  // the first hand's
  HandReport first_hand;                      // the first hand's figures (the report's are its too)
  std::vector<std::unique_ptr<HandRuntime>> more_hands;
  // Contact since the last step.
  int ticks_since_step{0};
  std::int32_t last_body{-1};
  std::int32_t last_triangle{-1};  // in its layer's snapshot
  Vec3 last_barycentric{Vec3::Zero()};
  std::int32_t contact_ticks_since_publish{0};
  bool last_proxy_valid{false};
  bool last_tick_valid{false};
  bool first_reading_seen{false};
  std::int64_t contact_ticks_this_step{0};
  // Set by commands.
  bool paused{false};
  int single_steps{0};
  std::atomic<std::uint64_t> calibrations_applied{0};
  int step_threads{0};  // the bodies' threads while in real time (0: their own setting)
  std::atomic<std::uint64_t> steps_taken{0};
};

/// Makes the world of `bodies` (checked by Session::make) and its hands' haptic loops.
/// `more_devices[i]` is the device of config.more_hands[i].
void init_world(World& world, std::vector<SessionBody> bodies, std::unique_ptr<haptics::Device> device,
                const SessionConfig& config, std::vector<std::unique_ptr<haptics::Device>> more_devices = {});
/// Hands: the first (World::loop) and the more_hands.
[[nodiscard]] inline std::size_t hand_count(const World& w) { return 1 + w.more_hands.size(); }
[[nodiscard]] inline haptics::HapticLoop& hand_loop(World& w, std::size_t hand) {
  return hand == 0 ? *w.loop : *w.more_hands[hand - 1]->loop;
}
/// The hands' reports as they stand (the first's, then the others').
[[nodiscard]] std::vector<HandReport> hand_reports(World& world);

/// The one stepping function: commands, contact forces, every due body steps, publish.
/// Returns false on divergence (report.divergence says which body and why).
bool step_world(World& world, CommandSeam& seam, SnapshotPublisher& publisher, SessionReport& report, StateTimer& timer,
                double clock_s);
/// The haptic ticks' contacts since the last step, summed on the bodies they touched.
void take_contacts(World& world, SessionReport& report);
/// Counts the steps whose proxy fell through a closed body.
void count_fall_through(World& world, SessionReport& report);
/// Contact forces onto the due bodies, then they step. False on divergence.
bool advance_bodies(World& world, SessionReport& report);
/// The contact's local model for layer `l`'s next snapshot (compliance or FEM reaction).
[[nodiscard]] haptics::LocalContactModel local_contact_model(World& world, std::size_t layer);
/// Sets a body's threads to the model's own or the world's step_threads.
void fit_threads(const World& world, BodyRuntime& r);
/// Hands current_settings to the haptic loop.
void publish_settings(World& world);
/// Each run reports on itself: per-body figures start again.
void begin_run(World& world);

}  // namespace hof::coupling::detail
