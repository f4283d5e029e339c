#pragma once
/// @file
/// Makes the snapshots the haptic loop and the window read from the shape the simulation has
/// just stepped. The simulation stages the shape (the mapping to the surface and the contact's
/// local model read its state); the snapshot itself (normals, the bound tree's refit, about a
/// tenth of a medium liver's step) is made by the publisher thread in real time, on the core
/// the haptic loop leaves idle, and on the caller's thread in virtual time (the same result).

#include <atomic>
#include <memory>
#include <span>
#include <thread>
#include <vector>

#include "hof/core/triple_buffer.h"
#include "hof/coupling/contact_view.h"
#include "hof/coupling/detail/world_step.h"

namespace hof::coupling::detail {

class SnapshotPublisher {
 public:
  explicit SnapshotPublisher(World& world) : world_(world) {}
  ~SnapshotPublisher() { stop(); }
  SnapshotPublisher(const SnapshotPublisher&) = delete;
  SnapshotPublisher& operator=(const SnapshotPublisher&) = delete;

  /// Starts the publisher thread (real time), on `cpu` when it is >= 0.
  void start(int cpu);
  /// Makes the last shape staged, then ends the thread. Idempotent.
  void stop();
  /// Stages the world's shape after a step (simulation thread) and, without the thread, makes
  /// its snapshots now.
  void publish(double clock_s);

  /// The window's snapshot of a layer; from the first call on, every step publishes into it.
  TripleBuffer<haptics::SurfaceSnapshot>& graphics_surfaces(std::size_t layer);
  /// Every body's node positions; from the first call on, every step publishes into it.
  TripleBuffer<std::vector<std::vector<double>>>& graphics_states();
  /// The last contact pass's contacts between bodies; from the first call on, every step
  /// publishes into it.
  TripleBuffer<BodyContactsView>& graphics_contacts();

 private:
  struct LayerJob {  // a layer's shape after a step, staged for its snapshot
    std::vector<Vec3> positions, velocities;
    haptics::LocalContactModel local;
  };
  struct PublishJob {
    double clock_s{0.0};
    std::vector<LayerJob> layers;
  };
  void make_snapshot_of(std::size_t layer, std::span<const Vec3> positions, std::span<const Vec3> velocities,
                        const haptics::LocalContactModel& local, double clock_s);
  void publisher_loop();

  World& world_;
  std::thread thread_;
  std::unique_ptr<TripleBuffer<PublishJob>> jobs_;
  PublishJob inline_job_;  // virtual time: staged and made on the caller's thread
  std::atomic<bool> stop_{false};
  std::atomic<bool> graphics_wanted_{false};
  std::atomic<bool> states_wanted_{false};
  TripleBuffer<std::vector<std::vector<double>>> graphics_states_;
  std::atomic<bool> contacts_wanted_{false};
  TripleBuffer<BodyContactsView> graphics_contacts_;
};

/// The contacts between bodies of the world's last contact pass, with the force its response
/// gave each, into `out` (cleared first; its storage reused). The one place a reader's view of
/// the contact response is made: a response that solves its contacts otherwise (constraints)
/// fills it from its own pass here.
void gather_body_contacts(const World& world, std::vector<BodyContactView>& out);

}  // namespace hof::coupling::detail
