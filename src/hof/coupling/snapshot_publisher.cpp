#include "hof/coupling/detail/snapshot_publisher.h"

#include <algorithm>
#include <array>
#include <chrono>

#include "hof/core/cpu_affinity.h"

namespace hof::coupling::detail {

namespace {
// How often the publisher thread looks for a shape staged by the simulation.
constexpr std::chrono::microseconds kPublisherPoll{200};
}  // namespace

TripleBuffer<haptics::SurfaceSnapshot>& SnapshotPublisher::graphics_surfaces(std::size_t layer) {
  graphics_wanted_.store(true, std::memory_order_release);
  return world_.layers[std::min(layer, world_.layers.size() - 1)]->graphics;
}

TripleBuffer<std::vector<std::vector<double>>>& SnapshotPublisher::graphics_states() {
  states_wanted_.store(true, std::memory_order_release);
  return graphics_states_;
}

TripleBuffer<BodyContactsView>& SnapshotPublisher::graphics_contacts() {
  contacts_wanted_.store(true, std::memory_order_release);
  return graphics_contacts_;
}

void gather_body_contacts(const World& w, std::vector<BodyContactView>& out) {
  out.clear();
  const ContactSettings& settings = w.config.contacts;
  for (const collision::BodyContact& c : w.body_contacts.contacts()) {
    const auto a = static_cast<std::size_t>(c.a.body), b = static_cast<std::size_t>(c.b.body);
    // The penalty response's spring (body_contact_pass.h): k (contact distance − gap) along n.
    const double k = pair_contact_stiffness(settings, w.bodies[a].body.collision, w.bodies[b].body.collision);
    out.push_back(BodyContactView{c.a.body, c.b.body, c.a.point, c.b.point, c.normal, c.distance,
                                  k * (settings.contact_distance_m - c.distance) * c.normal});
  }
}

void SnapshotPublisher::publish(double clock_s) {
  World& w = world_;
  const bool threaded = thread_.joinable();
  PublishJob& job = threaded ? jobs_->write_slot() : inline_job_;
  job.clock_s = clock_s;
  job.layers.resize(w.layers.size());
  for (std::size_t l = 0; l < w.layers.size(); ++l) {
    LayerRuntime& layer = *w.layers[l];
    for (const std::size_t i : layer.bodies) {
      BodyRuntime& r = w.bodies[i];
      if (!r.body.deformable()) continue;
      const haptics::SurfacePart& part = layer.rest.parts[r.part];
      r.body.mapping.apply({r.state.x.data(), static_cast<std::size_t>(r.state.x.size())}, r.surface_positions);
      r.body.mapping.apply({r.state.v.data(), static_cast<std::size_t>(r.state.v.size())}, r.surface_velocities);
      std::copy(r.surface_positions.begin(), r.surface_positions.end(), layer.positions.begin() + part.first_vertex);
      std::copy(r.surface_velocities.begin(), r.surface_velocities.end(), layer.velocities.begin() + part.first_vertex);
    }
    LayerJob& staged = job.layers[l];
    staged.local = local_contact_model(w, l);
    if (threaded) {
      // Sized when the publisher started: the copy reuses the slot's storage.
      staged.positions.assign(layer.positions.begin(), layer.positions.end());
      staged.velocities.assign(layer.velocities.begin(), layer.velocities.end());
    }
  }
  if (threaded) {
    jobs_->publish();
  } else {
    for (std::size_t l = 0; l < w.layers.size(); ++l) {
      make_snapshot_of(l, w.layers[l]->positions, w.layers[l]->velocities, job.layers[l].local, clock_s);
    }
  }
  if (states_wanted_.load(std::memory_order_acquire)) {
    std::vector<std::vector<double>>& slot = graphics_states_.write_slot();
    slot.resize(w.bodies.size());
    for (std::size_t i = 0; i < w.bodies.size(); ++i) {
      if (!w.bodies[i].body.deformable()) {
        slot[i].clear();
        continue;
      }
      const Eigen::VectorXd& x = w.bodies[i].state.x;
      slot[i].assign(x.data(), x.data() + x.size());
    }
    graphics_states_.publish();
  }
  if (contacts_wanted_.load(std::memory_order_acquire)) {
    BodyContactsView& slot = graphics_contacts_.write_slot();
    slot.enabled = w.config.contacts.enabled;
    slot.time_s = w.time_s;
    gather_body_contacts(w, slot.contacts);
    graphics_contacts_.publish();
  }
  w.contact_ticks_since_publish = 0;
}

void SnapshotPublisher::make_snapshot_of(std::size_t l, std::span<const Vec3> positions,
                                         std::span<const Vec3> velocities, const haptics::LocalContactModel& local,
                                         double clock_s) {
  LayerRuntime& layer = *world_.layers[l];
  haptics::SurfaceSnapshot& slot = layer.surfaces.write_slot();
  haptics::update_snapshot(slot, positions, velocities, clock_s);
  // update_snapshot counts the publishes of its own slot (one in three): the buffer's count
  // makes the sequence a reader sees (a sample's snapshot_sequence) increase with every one.
  slot.sequence = layer.surfaces.published() + 1;
  slot.local = local;
  if (graphics_wanted_.load(std::memory_order_acquire)) {
    // The same shape for the window: copied from the haptic loop's snapshot (before that is
    // published, while only this thread reads it), not computed a second time.
    haptics::SurfaceSnapshot& shown = layer.graphics.write_slot();
    haptics::copy_snapshot_geometry(shown, slot);
    shown.sequence = layer.graphics.published() + 1;
    layer.graphics.publish();
  }
  // Every other hand reads the same shape through a buffer of its own (one reader each),
  // copied from this one. The contact's local model is the first hand's contact point: the
  // others render the surface alone.
  for (auto& hand : world_.more_hands) {
    TripleBuffer<haptics::SurfaceSnapshot>& buffer = *hand->surfaces[l];
    haptics::SurfaceSnapshot& theirs = buffer.write_slot();
    haptics::copy_snapshot_geometry(theirs, slot);
    theirs.sequence = buffer.published() + 1;
    theirs.local = haptics::LocalContactModel{};
    buffer.publish();
  }
  layer.surfaces.publish();
}

void SnapshotPublisher::publisher_loop() {
  for (;;) {
    const bool stopping = stop_.load(std::memory_order_acquire);
    // The latest shape only: one staged while the last was being made replaces the older.
    if (jobs_->acquire()) {
      const PublishJob& job = jobs_->read();
      for (std::size_t l = 0; l < job.layers.size(); ++l) {
        make_snapshot_of(l, job.layers[l].positions, job.layers[l].velocities, job.layers[l].local, job.clock_s);
      }
    } else if (stopping) {
      break;  // the last shape staged is made
    } else {
      // Polled, not woken: waking a sleeping thread on another CPU from the simulation's
      // step (a futex wake: an interrupt between CPUs, a trap to the hypervisor on a virtual
      // machine) cost the step a few hundredths of its time; this costs the haptic CPU a
      // timer wake-up every poll and a shape at most one poll of latency.
      std::this_thread::sleep_for(kPublisherPoll);
    }
  }
}

void SnapshotPublisher::start(int cpu) {
  PublishJob sized;
  for (const auto& layer : world_.layers) sized.layers.push_back(LayerJob{layer->positions, layer->velocities, {}});
  jobs_ = std::make_unique<TripleBuffer<PublishJob>>(sized);
  stop_.store(false, std::memory_order_release);
  thread_ = std::thread([this, cpu] {
    // Beside the haptic loop, which sleeps most of each millisecond: off the simulation's CPUs.
    if (cpu >= 0) pin_current_thread(std::array<int, 1>{cpu});
    publisher_loop();
  });
}

void SnapshotPublisher::stop() {
  if (!thread_.joinable()) return;
  // The last shape staged is made before the thread ends (it runs the loop once more).
  stop_.store(true, std::memory_order_release);
  thread_.join();
  jobs_.reset();
}

}  // namespace hof::coupling::detail
