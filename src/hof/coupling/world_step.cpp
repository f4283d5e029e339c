#include "hof/coupling/detail/world_step.h"

#include <tbb/parallel_for.h>

#include <fmt/format.h>

#include <Eigen/Geometry>
#include <Eigen/LU>
#include <algorithm>
#include <chrono>
#include <cmath>
#include <limits>
#include <numbers>

#include "hof/collision/triangle_queries.h"
#include "hof/coupling/command_seam.h"
#include "hof/coupling/detail/snapshot_publisher.h"
#include "hof/mechanics/step.h"
#include "hof/mesh/surface_check.h"

namespace hof::coupling::detail {

namespace {

// Generalised winding number of a closed surface part at p (Van Oosterom & Strackee 1983):
// 1 inside, 0 outside.
bool inside_part(const haptics::SurfacePart& part, const std::vector<mesh::Tri>& triangles, const std::vector<Vec3>& x,
                 const Vec3& p) {
  double total = 0.0;
  for (std::int32_t t = part.first_triangle; t < part.first_triangle + part.triangle_count; ++t) {
    const mesh::Tri& tri = triangles[static_cast<std::size_t>(t)];
    const Vec3 a = x[tri[0]] - p, b = x[tri[1]] - p, c = x[tri[2]] - p;
    const double la = a.norm(), lb = b.norm(), lc = c.norm();
    // Single precision is ample for an inside test (each term's error ~1e-7 rad, the sum is
    // compared with 2π), and runs about twice as fast: this test runs after every step.
    total += 2.0 * static_cast<double>(
                       std::atan2(static_cast<float>(a.dot(b.cross(c))),
                                  static_cast<float>(la * lb * lc + a.dot(b) * lc + b.dot(c) * la + c.dot(a) * lb)));
  }
  return total / (4.0 * std::numbers::pi) > 0.5;
}

// How far inside a body the proxy must be to have fallen through it. A point proxy (the
// god-object) rides on the surface, and the surface of the step just taken may have passed it
// by the distance it moved in one step (tens of micrometres) before the next tick puts it back
// in front: grazing, not falling through. A proxy that fell through goes to the device,
// millimetres inside.
constexpr double kFallThroughDepth_m = 5e-4;

// Whether p is farther than `depth` from every triangle of the part (called only for a point
// inside, which is rare: the loop over the triangles then costs nothing on average).
bool deeper_than(const haptics::SurfacePart& part, const std::vector<mesh::Tri>& triangles, const std::vector<Vec3>& x,
                 const Vec3& p, double depth) {
  const double depth2 = depth * depth;
  for (std::int32_t t = part.first_triangle; t < part.first_triangle + part.triangle_count; ++t) {
    const mesh::Tri& tri = triangles[static_cast<std::size_t>(t)];
    if (collision::point_triangle_distance_squared(p, x[tri[0]], x[tri[1]], x[tri[2]]) <= depth2) return false;
  }
  return true;
}

// Haptic layers (H3D HapticLayeredGroup): the bodies' layer numbers, in order, become layers
// 0, 1, ... (at most kMaxLayers; deeper ones join the last), each with its rest snapshot.
std::vector<TripleBuffer<haptics::SurfaceSnapshot>*> build_layers(World& w) {
  std::vector<int> numbers;
  for (const BodyRuntime& r : w.bodies) numbers.push_back(r.body.layer);
  std::sort(numbers.begin(), numbers.end());
  numbers.erase(std::unique(numbers.begin(), numbers.end()), numbers.end());
  if (numbers.empty()) numbers.push_back(0);
  const std::size_t layer_count = std::min(numbers.size(), haptics::kMaxLayers);
  for (std::size_t l = 0; l < layer_count; ++l) w.layers.push_back(std::make_unique<LayerRuntime>());
  for (std::size_t i = 0; i < w.bodies.size(); ++i) {
    const auto at = static_cast<std::size_t>(std::lower_bound(numbers.begin(), numbers.end(), w.bodies[i].body.layer) -
                                             numbers.begin());
    w.bodies[i].layer = std::min(at, layer_count - 1);
    w.bodies[i].part = w.layers[w.bodies[i].layer]->bodies.size();
    w.layers[w.bodies[i].layer]->bodies.push_back(i);
  }
  std::vector<TripleBuffer<haptics::SurfaceSnapshot>*> buffers;
  for (auto& layer : w.layers) {
    std::vector<mesh::TriMesh> surfaces;
    std::unique_ptr<bool[]> is_static(new bool[std::max<std::size_t>(1, layer->bodies.size())]);
    std::unique_ptr<bool[]> closed(new bool[std::max<std::size_t>(1, layer->bodies.size())]);
    for (std::size_t k = 0; k < layer->bodies.size(); ++k) {
      const SessionBody& body = w.bodies[layer->bodies[k]].body;
      surfaces.push_back(body.surface);
      is_static[k] = !body.deformable();
      closed[k] = mesh::check_surface(body.surface).closed_manifold();
    }
    layer->rest = haptics::make_snapshot(surfaces, std::span<const bool>(is_static.get(), layer->bodies.size()),
                                         std::span<const bool>(closed.get(), layer->bodies.size()), w.config.tree);
    for (std::size_t k = 0; k < layer->bodies.size(); ++k)
      layer->rest.parts[k].body = static_cast<std::int32_t>(layer->bodies[k]);
    // Every slot holds the geometry (the producer then only updates positions in place).
    for (auto* buffer : {&layer->surfaces, &layer->graphics}) {
      buffer->write_slot() = layer->rest;
      buffer->read_mutable() = layer->rest;
      buffer->publish();
      buffer->write_slot() = layer->rest;
    }
    layer->positions = layer->rest.vertices;
    layer->velocities.assign(layer->rest.vertices.size(), Vec3::Zero());
    buffers.push_back(&layer->surfaces);
  }
  return buffers;
}

}  // namespace

bool fem_reaction_step_fits(double dt_s, double rate_hz) { return std::abs(dt_s * rate_hz - 1.0) < 1e-6; }

// A node the tool does not load is in equilibrium (its elastic force is zero) once the tissue
// has settled, so the sum of the elastic forces near the contact point is then minus the load,
// wherever in the patch it was applied; while the contact slides from triangle to triangle the
// last steps' loads stay in the sum, which keeps the force from jumping at every edge.
Vec3 BodyRuntime::fem_reaction(const mesh::Tri& tri, const std::array<double, 3>& bary,
                               std::span<const std::int32_t> triangle_nodes) {
  const auto at = [&](int k) -> const Vec3& { return surface_positions[static_cast<std::size_t>(tri[k])]; };
  const Vec3 point = at(0) * bary[0] + at(1) * bary[1] + at(2) * bary[2];
  double longest = 0.0;
  for (int k = 0; k < 3; ++k) longest = std::max(longest, (at(k) - at((k + 1) % 3)).norm());
  const double radius = std::max(kFemReactionPatchRadius_m, 2.0 * longest);
  // Room is kept for the triangle's own nodes, appended last.
  const std::size_t room = patch_nodes.capacity() - triangle_nodes.size();
  patch_nodes.clear();
  for (std::size_t v = 0;
       v < surface_positions.size() && patch_nodes.size() + SurfaceMapping::kMaxNodesPerVertex <= room; ++v) {
    if ((surface_positions[v] - point).squaredNorm() > radius * radius) continue;
    const std::array<std::int32_t, 1> vertex{static_cast<std::int32_t>(v)};
    const std::array<double, 1> one{1.0};
    std::array<std::int32_t, SurfaceMapping::kMaxNodesPerVertex> vertex_nodes{};
    std::array<double, SurfaceMapping::kMaxNodesPerVertex> vertex_weights{};
    const std::size_t n = body.mapping.point_weights(vertex, one, vertex_nodes, vertex_weights);
    for (std::size_t k = 0; k < n; ++k) {
      // A held node's elastic force is the support's reaction, not the tool's.
      if (!body.model->fixed_dof_mask[3 * static_cast<std::size_t>(vertex_nodes[k])])
        patch_nodes.push_back(vertex_nodes[k]);
    }
  }
  patch_nodes.insert(patch_nodes.end(), triangle_nodes.begin(), triangle_nodes.end());  // always
  patch_weights.assign(patch_nodes.size(), 1.0);
  return mechanics::point_elastic_force(*body.model, state, patch_nodes, patch_weights);
}

void init_world(World& w, std::vector<SessionBody> bodies, std::unique_ptr<haptics::Device> device,
                const SessionConfig& config, std::vector<std::unique_ptr<haptics::Device>> more_devices) {
  w.device = std::move(device);
  w.config = config;
  // Hands without a device (Session::make refuses them) are left out.
  if (more_devices.size() < w.config.more_hands.size()) w.config.more_hands.resize(more_devices.size());
  double dt = std::numeric_limits<double>::infinity();
  for (SessionBody& b : bodies) {
    BodyRuntime r;
    r.body = std::move(b);
    r.report.name = r.body.name;
    r.report.deformable = r.body.deformable();
    if (r.body.deformable()) {
      r.state = mechanics::make_state(*r.body.model);
      r.report.nodes = r.body.model->node_count();
      dt = std::min(dt, r.body.model->dt_s);
      r.next_step_s = r.body.model->dt_s;
    } else {
      r.report.nodes = r.body.surface.vertices.size();
    }
    r.surface_positions = r.body.surface.vertices;
    r.surface_velocities.assign(r.body.surface.vertices.size(), Vec3::Zero());
    r.loads.resize(1 + w.config.more_hands.size());
    w.bodies.push_back(std::move(r));
  }
  w.due.reserve(w.bodies.size());
  if (config.coupling == ContactCoupling::kFemReaction) {
    for (BodyRuntime& r : w.bodies) {
      r.patch_nodes.reserve(kFemReactionPatchCapacity);
      r.patch_weights.reserve(kFemReactionPatchCapacity);
      if (r.body.deformable()) {
        // point_elastic_force's scratch: the elements touching a full patch (a node has a few
        // tens), sized here so that no step allocates.
        mechanics::reserve_point_force_scratch(*r.body.model, r.state, 32 * kFemReactionPatchCapacity);
      }
    }
  }
  w.step_ok.reserve(w.bodies.size());
  w.due_flags.assign(w.bodies.size(), 0);
  w.body_contacts.init(w);
  // A world of rigid shapes (or of force effects only) still steps, to publish and report.
  w.dt = std::isfinite(dt) ? dt : 0.01;
  std::vector<TripleBuffer<haptics::SurfaceSnapshot>*> buffers = build_layers(w);

  w.current_settings.valid = true;
  w.current_settings.renderer = w.config.haptics.renderer;
  w.current_settings.effects = w.config.effects;
  w.current_settings.max_force_n = w.config.haptics.safety.max_force_n;
  w.current_settings.calibration = w.config.haptics.calibration;
  for (const BodyRuntime& r : w.bodies)
    w.current_settings.materials.push_back(r.body.material.value_or(w.config.haptics.material));
  w.loop = std::make_unique<haptics::HapticLoop>(
      *w.device, std::span<TripleBuffer<haptics::SurfaceSnapshot>* const>(buffers), w.config.haptics, &w.settings);
  w.loop->set_tool(w.config.tool.get());
  w.last_device = w.device.get();
  w.first_hand.device = w.config.device.empty() ? std::string(w.device->backend()) : w.config.device;
  // The other hands: each its own loop on its own snapshot buffers (filled by the publisher).
  for (std::size_t h = 0; h < w.config.more_hands.size(); ++h) {
    auto hand = std::make_unique<HandRuntime>();
    hand->config = w.config.more_hands[h];
    hand->device = std::move(more_devices[h]);
    hand->report.device = hand->config.device.empty() ? std::string(hand->device->backend()) : hand->config.device;
    std::vector<TripleBuffer<haptics::SurfaceSnapshot>*> hand_buffers;
    for (const auto& layer : w.layers) {
      auto buffer = std::make_unique<TripleBuffer<haptics::SurfaceSnapshot>>();
      buffer->write_slot() = layer->rest;
      buffer->read_mutable() = layer->rest;
      buffer->publish();
      buffer->write_slot() = layer->rest;
      hand_buffers.push_back(buffer.get());
      hand->surfaces.push_back(std::move(buffer));
    }
    hand->loop = std::make_unique<haptics::HapticLoop>(
        *hand->device, std::span<TripleBuffer<haptics::SurfaceSnapshot>* const>(hand_buffers), hand->config.haptics,
        &hand->settings);
    hand->loop->set_tool(hand->config.tool.get());
    w.more_hands.push_back(std::move(hand));
  }
  publish_settings(w);
}

std::vector<HandReport> hand_reports(World& w) {
  std::vector<HandReport> hands;
  for (std::size_t h = 0; h < hand_count(w); ++h) {
    HandReport figures = h == 0 ? w.first_hand : w.more_hands[h - 1]->report;
    haptics::HapticLoop& loop = hand_loop(w, h);
    figures.safety = loop.safety_counters();
    const double configured =
        h == 0 ? w.current_settings.max_force_n : w.more_hands[h - 1]->config.haptics.safety.max_force_n;
    const double device_limit = loop.device().spec().max_force_n;
    figures.max_force_limit_n = configured > 0.0 ? std::min(configured, device_limit) : device_limit;
    hands.push_back(std::move(figures));
  }
  return hands;
}

void publish_settings(World& w) {
  w.settings.write_slot() = w.current_settings;
  w.settings.publish();
  // The other hands take the surfaces, renderer and effects the commands set, and keep their
  // own force limit and calibration (the commands for those are the first hand's).
  for (auto& hand : w.more_hands) {
    haptics::HapticSettings& slot = hand->settings.write_slot();
    slot = w.current_settings;
    slot.max_force_n = hand->config.haptics.safety.max_force_n;
    slot.calibration = hand->config.haptics.calibration;
    hand->settings.publish();
  }
}

void fit_threads(const World& w, BodyRuntime& r) {
  // (A fresh state from make_state runs on the model's own setting: r.threads is then 0.)
  if (!r.body.deformable()) return;
  // A model that names its threads (`threads` in the scene) keeps them.
  const int wanted = r.body.model->threads > 0 ? r.body.model->threads : w.step_threads;
  if (wanted == r.threads) return;
  mechanics::set_threads(*r.body.model, r.state, wanted);
  r.threads = wanted;
}

void begin_run(World& w) {
  // Each run reports on itself: per-body figures start again, as the session's do.
  for (BodyRuntime& r : w.bodies) {
    r.ticks_at_last_step = 0;
    BodyReport fresh;
    fresh.name = r.report.name;
    fresh.deformable = r.report.deformable;
    fresh.nodes = r.report.nodes;
    r.report = std::move(fresh);
    r.inside_since_start = false;
  }
  const auto fresh_hand = [](HandReport& figures) {
    HandReport fresh;
    fresh.device = figures.device;
    figures = std::move(fresh);
  };
  fresh_hand(w.first_hand);
  for (auto& hand : w.more_hands) fresh_hand(hand->report);
  w.first_reading_seen = false;
  w.contact_ticks_this_step = 0;
}

bool step_world(World& w, CommandSeam& seam, SnapshotPublisher& publisher, SessionReport& report, StateTimer& timer,
                double clock_s) {
  seam.apply(w, report);
  take_contacts(w, report);
  count_fall_through(w, report);
  const bool contact_this_step = w.contact_ticks_this_step > 0;
  w.contact_ticks_this_step = 0;
  // Rigid bodies never step: their contact is not accumulated (it acts on nothing).
  for (BodyRuntime& r : w.bodies) {
    if (r.body.deformable()) continue;
    for (HandLoad& load : r.loads) load.clear();
  }
  w.ticks_since_step = 0;
  const auto step_start = Clock::now();
  const bool stepping = !w.paused || w.single_steps > 0;
  if (stepping) {
    if (w.paused) --w.single_steps;
    if (!advance_bodies(w, report)) {
      // Nothing more is published: the haptic loop fades the force out now rather than
      // rendering the last geometry until it is old enough for the watchdog.
      for (std::size_t h = 0; h < hand_count(w); ++h) hand_loop(w, h).set_simulation_failed(true);
      return false;
    }
    ++report.simulation_steps;
    w.steps_taken.fetch_add(1, std::memory_order_relaxed);
  }
  // Published while paused too: the haptic loop's watchdog sees a live simulation.
  publisher.publish(clock_s);
  // Stepping again after a failure (a reset or a new model took the divergence away): the
  // geometry just published is trusted again, and the force fades back in.
  for (std::size_t h = 0; h < hand_count(w); ++h) {
    haptics::HapticLoop& loop = hand_loop(w, h);
    if (stepping && loop.simulation_failed()) loop.set_simulation_failed(false);
  }
  double moving = 0.0;
  for (const BodyRuntime& r : w.bodies) {
    if (r.body.deformable() && r.state.v.size()) moving = std::max(moving, r.state.v.cwiseAbs().maxCoeff());
  }
  if (stepping) timer.add(contact_this_step, moving > 1e-4, seconds_between(step_start, Clock::now()));
  return true;
}

namespace {

// One hand's contacts since the last step. The first hand's also drive what the world keeps
// of the stylus (the proxies, the last contact for the local model, the report's figures).
void take_hand_contacts(World& w, std::size_t hand, SessionReport& report) {
  const bool first = hand == 0;
  haptics::HapticLoop& loop = hand_loop(w, hand);
  HandReport& figures = first ? w.first_hand : w.more_hands[hand - 1]->report;
  const double period = loop.nominal_period_s();
  haptics::HapticContact c;
  while (loop.contacts().pop(c)) {
    ++figures.haptic_ticks;
    const double force = c.force.norm();
    figures.max_force_n = std::max(figures.max_force_n, force);
    if (first) {
      ++w.ticks_since_step;
      ++report.haptic_ticks;
      w.last_tick_valid = c.valid;
      if (c.valid) {
        for (std::size_t l = 0; l < w.layers.size(); ++l) {
          w.layers[l]->proxy = c.layers[l].proxy;
          w.layers[l]->proxy_triangle = l < c.layer_count && c.layers[l].contact ? c.layers[l].triangle : -1;
        }
        w.last_proxy_valid = true;
      }
      report.max_force_n = std::max(report.max_force_n, force);
    }
    bool any = false;
    if (c.tool.active && c.tool.body >= 0 && static_cast<std::size_t>(c.tool.body) < w.bodies.size()) {
      // The tool in a body: its reaction goes through the tool's coupling at the body's step.
      BodyRuntime& r = w.bodies[static_cast<std::size_t>(c.tool.body)];
      HandLoad& load = r.loads[hand];
      load.tool_force_sum += c.tool.force;
      ++load.tool_ticks;
      load.last_tool = c.tool;
      r.report.contact_time_s += period;
      r.report.max_force_n = std::max(r.report.max_force_n, c.tool.force.norm());
      if (first) w.last_body = c.tool.body;
      any = true;
    }
    for (std::size_t l = 0; l < w.layers.size() && l < c.layer_count; ++l) {
      const haptics::HapticContact::Layer& layer = c.layers[l];
      if (!layer.contact || layer.triangle < 0) continue;
      const haptics::SurfaceSnapshot& rest = w.layers[l]->rest;
      const std::int32_t part = rest.part_of(layer.triangle);
      if (part < 0) continue;
      const auto b = static_cast<std::size_t>(rest.parts[static_cast<std::size_t>(part)].body);
      if (c.tool.active && c.tool.body == static_cast<std::int32_t>(b)) continue;  // the tool's (above)
      BodyRuntime& r = w.bodies[b];
      HandLoad& load = r.loads[hand];
      load.reaction_sum -= layer.load;  // the tissue feels the opposite of what the tool pushes with
      ++load.contact_ticks;
      load.last_triangle = layer.triangle - rest.parts[static_cast<std::size_t>(part)].first_triangle;
      load.last_barycentric = layer.barycentric;
      r.report.contact_time_s += period;
      r.report.max_force_n = std::max(r.report.max_force_n, layer.force.norm());
      if (first) {
        w.last_body = static_cast<std::int32_t>(b);
        w.last_triangle = layer.triangle;
        w.last_barycentric = layer.barycentric;
      }
      any = true;
    }
    if (!any) continue;
    figures.contact_time_s += period;
    if (c.clamped) ++figures.clamped_contact_ticks;
    if (!first) continue;
    ++w.contact_ticks_this_step;
    report.contact_time_s += period;
    if (c.clamped) ++report.clamped_contact_ticks;
    ++w.contact_ticks_since_publish;
  }
}

}  // namespace

void take_contacts(World& w, SessionReport& report) {
  for (std::size_t hand = 0; hand < hand_count(w); ++hand) take_hand_contacts(w, hand, report);
}

void count_fall_through(World& w, SessionReport& report) {
  // Only a proxy the device is driving: after a script ends (or the device is gone) the proxy
  // stays where it was, and a body moving through that spot has not been fallen through.
  if (!w.last_proxy_valid || !w.last_tick_valid) return;
  const bool first = !w.first_reading_seen;
  w.first_reading_seen = true;
  // A proxy outside a layer's bounding box is inside none of its bodies: one pass of minima
  // and maxima instead of the winding number's arctangent per triangle.
  for (auto& layer : w.layers) {
    Eigen::AlignedBox3d box;
    for (const Vec3& v : layer->positions) box.extend(v);
    layer->proxy_outside_box = !box.contains(layer->proxy);
  }
  for (std::size_t i = 0; i < w.bodies.size(); ++i) {
    BodyRuntime& r = w.bodies[i];
    const LayerRuntime& layer = *w.layers[r.layer];
    const haptics::SurfacePart& part = layer.rest.parts[r.part];
    if (!part.closed) continue;  // an open sheet has no inside
    if (layer.proxy_outside_box) {
      r.inside_since_start = false;
      continue;
    }
    // A proxy touching a triangle of the part is on its surface, not deep inside: the winding
    // number (a pass over every triangle, a hundredth of a step) is not needed then, and the
    // answer is the same (deeper_than below would find this triangle near).
    const std::int32_t touched = layer.proxy_triangle;
    if (touched >= part.first_triangle && touched < part.first_triangle + part.triangle_count) {
      const mesh::Tri& tri = layer.rest.triangles[static_cast<std::size_t>(touched)];
      const auto& x = layer.positions;
      if (collision::point_triangle_distance_squared(layer.proxy, x[tri[0]], x[tri[1]], x[tri[2]]) <=
          kFallThroughDepth_m * kFallThroughDepth_m) {
        r.inside_since_start = false;
        continue;
      }
    }
    const bool inside = inside_part(part, layer.rest.triangles, layer.positions, layer.proxy) &&
                        deeper_than(part, layer.rest.triangles, layer.positions, layer.proxy, kFallThroughDepth_m);
    if (first && inside) {
      // A probe that starts inside a body has not fallen through it: it is reported as such.
      r.report.probe_started_inside = true;
      r.inside_since_start = true;
    }
    if (!inside) r.inside_since_start = false;
    if (inside && !r.inside_since_start) {
      ++r.report.fall_through_events;
      ++report.fall_through_events;
    }
  }
}

namespace {

// The contact forces on a due body: the average reaction over its ticks since its last step
// (the force acted only during the contact ticks), and the tool's through its coupling.
void load_contacts(World& w, BodyRuntime& r, std::int64_t haptic_ticks) {
  r.state.external_force.setZero();
  const std::int64_t ticks = std::max<std::int64_t>(1, haptic_ticks - r.ticks_at_last_step);
  std::span<double> forces{r.state.external_force.data(), static_cast<std::size_t>(r.state.external_force.size())};
  // Every hand's load adds up on the body (the first hand's first).
  for (std::size_t hand = 0; hand < r.loads.size(); ++hand) {
    HandLoad& load = r.loads[hand];
    if (load.contact_ticks > 0 && load.last_triangle >= 0) {
      const Vec3 reaction = load.reaction_sum / static_cast<double>(ticks);
      const mesh::Tri& tri = r.body.surface.triangles[static_cast<std::size_t>(load.last_triangle)];
      if (w.config.coupling == ContactCoupling::kClosestVertex) {
        int nearest = 0;
        for (int k = 1; k < 3; ++k) {
          if (load.last_barycentric[k] > load.last_barycentric[nearest]) nearest = k;
        }
        r.body.mapping.add_vertex_force(tri[nearest], reaction, forces);
      } else {
        for (int k = 0; k < 3; ++k)
          r.body.mapping.add_vertex_force(tri[k], load.last_barycentric[k] * reaction, forces);
      }
    }
    ToolTissueCoupling* coupling =
        hand == 0 ? w.config.tool_coupling.get() : w.more_hands[hand - 1]->config.tool_coupling.get();
    if (load.tool_ticks > 0 && coupling) {
      // The tool's force averaged over this body's ticks since its last step (it acted only
      // during the ticks it was in the body), at the tool's latest place.
      haptics::ToolState tool = load.last_tool;
      tool.force = load.tool_force_sum / static_cast<double>(ticks);
      coupling->add_tissue_forces(tool, *r.body.model, r.state, forces);
    }
    load.clear();
  }
  r.ticks_at_last_step = haptic_ticks;
}

}  // namespace

bool advance_bodies(World& w, SessionReport& report) {
  const double dt = w.dt;
  const double next_time = w.time_s + dt;
  std::vector<BodyRuntime*>& due = w.due;  // reserved at construction: a step does not allocate
  due.clear();
  for (BodyRuntime& r : w.bodies) {
    if (r.body.deformable() && r.next_step_s <= next_time + 1e-9 * dt) due.push_back(&r);
  }
  for (BodyRuntime* r : due) load_contacts(w, *r, report.haptic_ticks);
  if (w.body_contacts.active()) {
    // Contact between bodies, from where every body is now. Bodies that step at different dt:
    // the pass runs at every world step (the smallest dt) and a body takes its contact forces
    // at the steps it makes, from the pass of that world step (a penalty force depends on the
    // positions alone); the others' share of that pass is counted in the report only.
    std::fill(w.due_flags.begin(), w.due_flags.end(), 0);
    for (BodyRuntime* r : due) w.due_flags[static_cast<std::size_t>(r - w.bodies.data())] = 1;
    w.body_contacts.apply(w, w.due_flags, report);
  }
  // Every due body steps; several in parallel (each body's own loops are thread-count
  // independent, so results do not depend on how they are spread).
  std::vector<char>& ok = w.step_ok;
  ok.assign(due.size(), 1);
  const auto step_one = [&](std::size_t k) { ok[k] = mechanics::step(*due[k]->body.model, due[k]->state) ? 1 : 0; };
  if (due.size() > 1) {
    tbb::parallel_for(std::size_t{0}, due.size(), step_one);
  } else if (due.size() == 1) {
    step_one(0);
  }
  for (std::size_t k = 0; k < due.size(); ++k) {
    if (ok[k]) {
      // The largest displacement over the run (not only at its end: a press is released).
      const auto& model = *due[k]->body.model;
      double& largest = due[k]->report.max_displacement_m;
      for (std::size_t i = 0; i < model.node_count(); ++i) {
        largest =
            std::max(largest, (due[k]->state.position(static_cast<std::int32_t>(i)) - model.rest_positions[i]).norm());
      }
    }
    if (!ok[k]) {
      const auto& d = due[k]->state.divergence;
      report.diverged = true;
      report.divergence = fmt::format("body '{}': {} at step {}: {}", due[k]->body.name, d.component, d.step, d.reason);
      return false;
    }
    due[k]->next_step_s += due[k]->body.model->dt_s;
  }
  // Friction constraints: the steps just taken were the free motion; the contacts correct it.
  if (w.body_contacts.active()) w.body_contacts.correct(w, w.due_flags, report);
  w.time_s = next_time;
  return true;
}

haptics::LocalContactModel local_contact_model(World& w, std::size_t l) {
  haptics::LocalContactModel local;
  const LayerRuntime& layer = *w.layers[l];
  const bool touched_here = w.last_body >= 0 && w.bodies[static_cast<std::size_t>(w.last_body)].layer == l;
  const bool fem_felt =
      w.config.coupling == ContactCoupling::kCompliance || w.config.coupling == ContactCoupling::kFemReaction;
  if (!fem_felt || !touched_here || w.contact_ticks_since_publish == 0 ||
      !w.bodies[static_cast<std::size_t>(w.last_body)].body.deformable()) {
    return local;
  }
  // The contact point's compliance at the current state (Saupin, Duriez & Cotin 2008).
  BodyRuntime& r = w.bodies[static_cast<std::size_t>(w.last_body)];
  const std::int32_t triangle = w.last_triangle - layer.rest.parts[r.part].first_triangle;
  const mesh::Tri& tri = r.body.surface.triangles[static_cast<std::size_t>(triangle)];
  const std::array<std::int32_t, 3> vertices{tri[0], tri[1], tri[2]};
  const std::array<double, 3> bary{w.last_barycentric[0], w.last_barycentric[1], w.last_barycentric[2]};
  std::array<std::int32_t, SurfaceMapping::kMaxPointWeights> nodes{};
  std::array<double, SurfaceMapping::kMaxPointWeights> weights{};
  const std::size_t count = r.body.mapping.point_weights(vertices, bary, nodes, weights);
  Mat3 compliance;
  if (w.config.coupling == ContactCoupling::kFemReaction) {
    local.valid = true;
    local.direct = true;
    local.triangle = w.last_triangle;
    local.barycentric = w.last_barycentric;
    local.reaction = r.fem_reaction(tri, bary, std::span(nodes.data(), count));
  } else if (mechanics::compute_point_compliance(*r.body.model, r.state, std::span(nodes.data(), count),
                                                 std::span(weights.data(), count), compliance)) {
    const Eigen::FullPivLU<Mat3> lu(compliance);
    if (lu.isInvertible()) {
      local.valid = true;
      local.direct = false;
      local.triangle = w.last_triangle;
      local.barycentric = w.last_barycentric;
      local.compliance = compliance;
      local.stiffness = lu.inverse();
      // The load that holds the tissue in its current shape at that point (minus its elastic
      // force), rather than the force last applied: the local model then stays consistent with
      // the simulated shape even while the simulation is still settling.
      local.applied_force = -mechanics::point_elastic_force(*r.body.model, r.state, std::span(nodes.data(), count),
                                                            std::span(weights.data(), count));
    }
  }
  return local;
}

}  // namespace hof::coupling::detail
