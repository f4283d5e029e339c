#include "hof/coupling/session.h"

#include <tbb/task_arena.h>

#include <fmt/format.h>
#include <tbb/parallel_for.h>

#include <Eigen/Geometry>
#include <Eigen/LU>
#include <array>
#include <chrono>
#include <cmath>
#include <numbers>

#include "hof/collision/triangle_queries.h"
#include "hof/mechanics/model_parameters.h"
#include "hof/mechanics/step.h"
#include "hof/mesh/surface_check.h"

namespace hof::coupling {

namespace {

// The FEM-reaction coupling's patch: the surface within this radius of the contact (or twice the
// contact triangle's longest edge, when larger), at most this many nodes.
constexpr double kFemReactionPatchRadius_m = 0.01;
constexpr std::size_t kFemReactionPatchCapacity = 4096;

// The FEM-reaction coupling needs one simulation step per haptic tick.
bool fem_reaction_step_fits(double dt_s, double rate_hz) { return std::abs(dt_s * rate_hz - 1.0) < 1e-6; }

using Clock = std::chrono::steady_clock;

// How often the publisher thread looks for a shape staged by the simulation.
constexpr std::chrono::microseconds kPublisherPoll{200};

// Real time: how far the simulation may fall behind the clock and still catch up (steps
// without sleeping until it is back); farther behind, it gives the time up and goes on from
// now. A step's cost varies by a tenth from step to step: without catching up, every step
// slower than dt would be lost for good while a faster one waits, and the simulation would
// keep real time only if its slowest steps did.
constexpr double kMaxCatchUp_s = 0.02;

double seconds_between(Clock::time_point a, Clock::time_point b) { return std::chrono::duration<double>(b - a).count(); }

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
    total += 2.0 * static_cast<double>(std::atan2(static_cast<float>(a.dot(b.cross(c))),
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

}  // namespace

struct Session::BodyRuntime {
  SessionBody body;
  mechanics::MechanicalState state;  // deformable bodies
  std::vector<Vec3> surface_positions, surface_velocities;
  // Contact since this body last stepped.
  Vec3 reaction_sum{Vec3::Zero()};
  int contact_ticks{0};
  std::int64_t ticks_at_last_step{0};
  std::int32_t last_triangle{-1};  // local to the body's surface
  Vec3 last_barycentric{Vec3::Zero()};
  // The tool in or on this body since it last stepped: its force summed, its latest state.
  Vec3 tool_force_sum{Vec3::Zero()};
  int tool_ticks{0};
  haptics::ToolState last_tool;
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
  // carried by `triangle_nodes`), felt at the next tick: the elastic force summed over the
  // free nodes near the contact point. A node the tool does not load is in equilibrium (its
  // elastic force is zero) once the tissue has settled, so the sum is then minus the load,
  // wherever in the patch it was applied; while the contact slides from triangle to triangle
  // the last steps' loads stay in the sum, which keeps the force from jumping at every edge.
  Vec3 fem_reaction(const mesh::Tri& tri, const std::array<double, 3>& bary, std::span<const std::int32_t> triangle_nodes) {
    const auto at = [&](int k) -> const Vec3& { return surface_positions[static_cast<std::size_t>(tri[k])]; };
    const Vec3 point = at(0) * bary[0] + at(1) * bary[1] + at(2) * bary[2];
    double longest = 0.0;
    for (int k = 0; k < 3; ++k) longest = std::max(longest, (at(k) - at((k + 1) % 3)).norm());
    const double radius = std::max(kFemReactionPatchRadius_m, 2.0 * longest);
    // Room is kept for the triangle's own nodes, appended last.
    const std::size_t room = patch_nodes.capacity() - triangle_nodes.size();
    patch_nodes.clear();
    for (std::size_t v = 0; v < surface_positions.size() && patch_nodes.size() + SurfaceMapping::kMaxNodesPerVertex <= room; ++v) {
      if ((surface_positions[v] - point).squaredNorm() > radius * radius) continue;
      const std::array<std::int32_t, 1> vertex{static_cast<std::int32_t>(v)};
      const std::array<double, 1> one{1.0};
      std::array<std::int32_t, SurfaceMapping::kMaxNodesPerVertex> vertex_nodes{};
      std::array<double, SurfaceMapping::kMaxNodesPerVertex> vertex_weights{};
      const std::size_t n = body.mapping.point_weights(vertex, one, vertex_nodes, vertex_weights);
      for (std::size_t k = 0; k < n; ++k) {
        // A held node's elastic force is the support's reaction, not the tool's.
        if (!body.model->fixed_dof_mask[3 * static_cast<std::size_t>(vertex_nodes[k])]) patch_nodes.push_back(vertex_nodes[k]);
      }
    }
    patch_nodes.insert(patch_nodes.end(), triangle_nodes.begin(), triangle_nodes.end());  // always
    patch_weights.assign(patch_nodes.size(), 1.0);
    return mechanics::point_elastic_force(*body.model, state, patch_nodes, patch_weights);
  }
};

struct Session::LayerRuntime {
  std::vector<std::size_t> bodies;           // indices into bodies_, in part order
  haptics::SurfaceSnapshot rest;             // the layer's surfaces at rest (parts name bodies)
  TripleBuffer<haptics::SurfaceSnapshot> surfaces;  // to the haptic loop
  TripleBuffer<haptics::SurfaceSnapshot> graphics;  // to a reader (the window)
  std::vector<Vec3> positions, velocities;   // the layer's vertices now
  Vec3 proxy{Vec3::Zero()};                  // this layer's proxy at the last tick
  std::int32_t proxy_triangle{-1};           // the triangle it touched at that tick (-1: none)
  bool proxy_outside_box{false};             // outside the box of `positions` (fall-through test)
};

struct Session::StateTimer {
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

Session::Session(std::vector<SessionBody> bodies, std::unique_ptr<haptics::Device> device, const SessionConfig& config)
    : device_(std::move(device)), config_(config) {
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
    validated_configs_.push_back(r.body.config.value_or(mechanics::ModelConfig{}));
    has_mechanics_.push_back(r.body.deformable() && r.body.config ? 1 : 0);
    bodies_.push_back(std::move(r));
  }
  due_.reserve(bodies_.size());
  if (config.coupling == ContactCoupling::kFemReaction) {
    for (BodyRuntime& r : bodies_) {
      r.patch_nodes.reserve(kFemReactionPatchCapacity);
      r.patch_weights.reserve(kFemReactionPatchCapacity);
      if (r.body.deformable()) {
        // point_elastic_force's scratch: the elements touching a full patch (a node has a few
        // tens), sized here so that no step allocates.
        mechanics::reserve_point_force_scratch(*r.body.model, r.state, 32 * kFemReactionPatchCapacity);
      }
    }
  }
  step_ok_.reserve(bodies_.size());
  // A world of rigid shapes (or of force effects only) still steps, to publish and report.
  dt_ = std::isfinite(dt) ? dt : 0.01;

  // Haptic layers (H3D HapticLayeredGroup): the bodies' layer numbers, in order, become
  // layers 0, 1, ... (at most kMaxLayers; deeper ones join the last).
  std::vector<int> numbers;
  for (const BodyRuntime& r : bodies_) numbers.push_back(r.body.layer);
  std::sort(numbers.begin(), numbers.end());
  numbers.erase(std::unique(numbers.begin(), numbers.end()), numbers.end());
  if (numbers.empty()) numbers.push_back(0);
  const std::size_t layer_count = std::min(numbers.size(), haptics::kMaxLayers);
  for (std::size_t l = 0; l < layer_count; ++l) layers_.push_back(std::make_unique<LayerRuntime>());
  for (std::size_t i = 0; i < bodies_.size(); ++i) {
    const auto at = static_cast<std::size_t>(std::lower_bound(numbers.begin(), numbers.end(), bodies_[i].body.layer) - numbers.begin());
    bodies_[i].layer = std::min(at, layer_count - 1);
    bodies_[i].part = layers_[bodies_[i].layer]->bodies.size();
    layers_[bodies_[i].layer]->bodies.push_back(i);
  }
  std::vector<TripleBuffer<haptics::SurfaceSnapshot>*> buffers;
  for (auto& layer : layers_) {
    std::vector<mesh::TriMesh> surfaces;
    std::unique_ptr<bool[]> is_static(new bool[std::max<std::size_t>(1, layer->bodies.size())]);
    std::unique_ptr<bool[]> closed(new bool[std::max<std::size_t>(1, layer->bodies.size())]);
    for (std::size_t k = 0; k < layer->bodies.size(); ++k) {
      const SessionBody& body = bodies_[layer->bodies[k]].body;
      surfaces.push_back(body.surface);
      is_static[k] = !body.deformable();
      closed[k] = mesh::check_surface(body.surface).closed_manifold();
    }
    layer->rest = haptics::make_snapshot(surfaces, std::span<const bool>(is_static.get(), layer->bodies.size()),
                                         std::span<const bool>(closed.get(), layer->bodies.size()), config_.tree);
    for (std::size_t k = 0; k < layer->bodies.size(); ++k) layer->rest.parts[k].body = static_cast<std::int32_t>(layer->bodies[k]);
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

  current_settings_.valid = true;
  current_settings_.renderer = config_.haptics.renderer;
  current_settings_.effects = config_.effects;
  current_settings_.max_force_n = config_.haptics.safety.max_force_n;
  current_settings_.calibration = config_.haptics.calibration;
  submitted_calibration_ = config_.haptics.calibration;
  for (const BodyRuntime& r : bodies_) current_settings_.materials.push_back(r.body.material.value_or(config_.haptics.material));
  loop_ = std::make_unique<haptics::HapticLoop>(*device_, std::span<TripleBuffer<haptics::SurfaceSnapshot>* const>(buffers),
                                                config_.haptics, &settings_);
  loop_->set_tool(config_.tool.get());
  last_device_ = device_.get();
  publish_settings();
}

Session::~Session() { stop_realtime(); }

Expected<std::unique_ptr<Session>> Session::make(SessionBody body, std::unique_ptr<haptics::Device> device,
                                                 const SessionConfig& config) {
  std::vector<SessionBody> bodies;
  bodies.push_back(std::move(body));
  return make(std::move(bodies), std::move(device), config);
}

Expected<std::unique_ptr<Session>> Session::make(std::vector<SessionBody> bodies, std::unique_ptr<haptics::Device> device,
                                                 const SessionConfig& config) {
  if (!device) return make_error(ErrorCode::kInvalidArgument, "session: no device");
  for (const SessionBody& body : bodies) {
    if (body.deformable() && body.mapping.surface_vertex_count() != body.surface.vertices.size()) {
      return make_error(ErrorCode::kInvalidArgument,
                        fmt::format("session: body '{}': the surface has {} vertices but the mapping {}", body.name,
                                    body.surface.vertices.size(), body.mapping.surface_vertex_count()));
    }
    if (body.material) {
      if (auto ok = haptics::validate(*body.material); !ok) {
        return make_error(ErrorCode::kInvalidArgument, fmt::format("session: body '{}': {}", body.name, ok.error().message));
      }
    }
  }
  if (!(config.haptics.rate_hz >= 100.0 && config.haptics.rate_hz <= 20000.0)) {
    return make_error(ErrorCode::kInvalidArgument,
                      fmt::format("session: haptic rate must be in [100, 20000] Hz, got {}", config.haptics.rate_hz));
  }
  if (auto ok = haptics::validate_effects(config.effects); !ok) return std::unexpected(ok.error());
  if (config.coupling == ContactCoupling::kFemReaction) {
    for (const SessionBody& body : bodies) {
      if (body.deformable() && !fem_reaction_step_fits(body.model->dt_s, config.haptics.rate_hz)) {
        return make_error(ErrorCode::kInvalidArgument,
                          fmt::format("session: coupling fem-reaction steps the simulation once per haptic tick: body '{}' has dt "
                                      "{:g} s, the haptic period is {:g} s (set dt to it, or use another coupling)",
                                      body.name, body.model->dt_s, 1.0 / config.haptics.rate_hz));
      }
    }
  }
  auto session = std::unique_ptr<Session>(new Session(std::move(bodies), std::move(device), config));
  session->publish(0.0);
  return session;
}

std::size_t Session::body_count() const { return bodies_.size(); }
const SessionBody& Session::body(std::size_t i) const { return bodies_[i].body; }
const mechanics::MechanicalState& Session::state(std::size_t i) const { return bodies_[i].state; }

std::int32_t Session::body_of_triangle(std::int32_t triangle, std::int32_t layer) const {
  if (layer < 0 || static_cast<std::size_t>(layer) >= layers_.size()) return -1;
  const haptics::SurfaceSnapshot& rest = layers_[static_cast<std::size_t>(layer)]->rest;
  const std::int32_t part = rest.part_of(triangle);
  return part < 0 ? -1 : rest.parts[static_cast<std::size_t>(part)].body;
}

Vec3 Session::rest_point(std::int32_t triangle, const Vec3& weights, std::int32_t layer) const {
  if (layer < 0 || static_cast<std::size_t>(layer) >= layers_.size()) return Vec3::Zero();
  const haptics::SurfaceSnapshot& rest = layers_[static_cast<std::size_t>(layer)]->rest;
  if (triangle < 0 || static_cast<std::size_t>(triangle) >= rest.triangles.size()) return Vec3::Zero();
  return rest.point(triangle, weights);
}

std::size_t Session::layer_count() const { return layers_.size(); }

TripleBuffer<haptics::SurfaceSnapshot>& Session::graphics_surfaces(std::size_t layer) {
  graphics_wanted_.store(true, std::memory_order_release);
  return layers_[std::min(layer, layers_.size() - 1)]->graphics;
}

haptics::Calibration Session::calibration() const {
  std::lock_guard lock(commands_mutex_);
  return submitted_calibration_;
}

TripleBuffer<std::vector<std::vector<double>>>& Session::graphics_states() {
  states_wanted_.store(true, std::memory_order_release);
  return graphics_states_;
}

// ---- The command seam

namespace {

/// A body's new model must keep its mesh: the surface follows the nodes through a mapping made
/// for this one.
Expected<void> same_mesh(const std::string& body, const mechanics::ModelConfig& next, const mechanics::ModelConfig& now) {
  if (next.positions == now.positions && next.tets == now.tets) return {};
  return make_error(ErrorCode::kInvalidArgument,
                    fmt::format("body '{}': the new model has another mesh ({} nodes, {} tetrahedra; the body has {} and {}): "
                                "reopen the project to change the mesh",
                                body, next.positions.size(), next.tets.size(), now.positions.size(), now.tets.size()));
}

}  // namespace

Expected<double> Session::parameter(std::string_view body, std::string_view component, std::string_view parameter) const {
  std::lock_guard lock(commands_mutex_);
  for (std::size_t i = 0; i < bodies_.size(); ++i) {
    if (bodies_[i].body.name != body) continue;
    if (!has_mechanics_[i]) return make_error(ErrorCode::kInvalidArgument, fmt::format("body '{}' has no mechanics (a rigid shape)", body));
    return mechanics::get_parameter(validated_configs_[i], component, parameter);
  }
  std::string names;
  for (const BodyRuntime& r : bodies_) names += (names.empty() ? "" : ", ") + r.body.name;
  return make_error(ErrorCode::kInvalidArgument, fmt::format("no body '{}' (the bodies: {})", body, names));
}

Expected<void> Session::submit(const Command& submitted) {
  Command command = submitted;
  if (const auto* set = std::get_if<command::SetParameter>(&command);
      set && config_.coupling == ContactCoupling::kFemReaction && set->component.empty() && set->parameter == "dt" &&
      !fem_reaction_step_fits(set->value, config_.haptics.rate_hz)) {
    return make_error(ErrorCode::kInvalidArgument,
                      fmt::format("body '{}': dt {:g} s: coupling fem-reaction needs dt equal to the haptic period, {:g} s", set->body,
                                  set->value, 1.0 / config_.haptics.rate_hz));
  }
  if (auto* device = std::get_if<command::SetDevice>(&command); device && !device->opened) {
    // Opened here, on the caller's thread (a network device may wait for its first packet).
    auto opened = haptics::open_device(device->spec);
    if (!opened) return std::unexpected(opened.error());
    device->opened = std::shared_ptr<haptics::Device>(std::move(*opened));
  }
  if (auto* model = std::get_if<command::SetModel>(&command)) {
    // Built here, outside the lock (the simulation thread takes it between steps); the cheap
    // checks come first so that their messages are the ones a user sees.
    {
      std::lock_guard lock(commands_mutex_);
      for (std::size_t i = 0; i < bodies_.size(); ++i) {
        if (bodies_[i].body.name != model->body || !has_mechanics_[i]) continue;
        if (auto same = same_mesh(model->body, model->config, validated_configs_[i]); !same) return same;
      }
    }
    auto built = mechanics::build_model(model->config);
    if (!built) return make_error(ErrorCode::kInvalidArgument, fmt::format("body '{}': {}", model->body, built.error().message));
    model->built = std::make_shared<mechanics::MechanicalModel>(std::move(*built));
  }
  std::lock_guard lock(commands_mutex_);
  const auto find_body = [&](const std::string& name) -> std::int32_t {
    for (std::size_t i = 0; i < bodies_.size(); ++i) {
      if (bodies_[i].body.name == name) return static_cast<std::int32_t>(i);
    }
    return -1;
  };
  const auto body_names = [&] {
    std::string names;
    for (const BodyRuntime& r : bodies_) names += (names.empty() ? "" : ", ") + r.body.name;
    return names.empty() ? std::string("none") : names;
  };
  if (const auto* set = std::get_if<command::SetParameter>(&command)) {
    const std::int32_t i = find_body(set->body);
    if (i < 0) return make_error(ErrorCode::kInvalidArgument, fmt::format("no body '{}' (bodies: {})", set->body, body_names()));
    // Whether it has mechanics is fixed at construction (the simulation thread may be
    // rebuilding the model right now: its optional is not read here).
    if (!has_mechanics_[static_cast<std::size_t>(i)]) {
      return make_error(ErrorCode::kInvalidArgument, fmt::format("body '{}' is rigid: it has no mechanical parameters", set->body));
    }
    mechanics::ModelConfig& config = validated_configs_[static_cast<std::size_t>(i)];
    if (auto ok = mechanics::set_parameter(config, set->component, set->parameter, set->value); !ok) {
      return make_error(ErrorCode::kInvalidArgument, fmt::format("body '{}': {}", set->body, ok.error().message));
    }
    // Recorded as a change (to be saved) once the simulation has applied it.
  } else if (auto* model = std::get_if<command::SetModel>(&command)) {
    const std::int32_t i = find_body(model->body);
    if (i < 0) return make_error(ErrorCode::kInvalidArgument, fmt::format("no body '{}' (bodies: {})", model->body, body_names()));
    if (!has_mechanics_[static_cast<std::size_t>(i)]) {
      return make_error(ErrorCode::kInvalidArgument, fmt::format("body '{}' is rigid: it has no model to replace", model->body));
    }
    // Checked again under the lock (the body may have had another model submitted meanwhile).
    if (auto same = same_mesh(model->body, model->config, validated_configs_[static_cast<std::size_t>(i)]); !same) return same;
    validated_configs_[static_cast<std::size_t>(i)] = model->config;
    // The caller took the body's changes into `config`: from now on they are not changes
    // (erased again when applied, for a parameter command still queued before this one).
    std::erase_if(changes_, [&](const ParameterChange& c) { return c.body == model->body; });
  } else if (const auto* calibration = std::get_if<command::SetCalibration>(&command)) {
    const Eigen::Matrix4d& m = calibration->calibration.position;
    const double det = m.topLeftCorner<3, 3>().determinant();
    if (!m.allFinite() || !calibration->calibration.orientation.coeffs().allFinite() || !(std::abs(det) > 1e-12) ||
        m.row(3) != Eigen::RowVector4d(0, 0, 0, 1)) {
      return make_error(ErrorCode::kInvalidArgument,
                        "calibration: positionCalibration must be a finite affine 4x4 matrix (last row 0 0 0 1) with an "
                        "invertible linear part");
    }
    submitted_calibration_ = calibration->calibration;
  } else if (const auto* steps = std::get_if<command::SingleStep>(&command)) {
    if (steps->steps < 1 || steps->steps > 1000000) {
      return make_error(ErrorCode::kInvalidArgument, fmt::format("single step: steps must be in [1, 1000000], got {}", steps->steps));
    }
  } else if (const auto* material = std::get_if<command::SetMaterial>(&command)) {
    if (!material->body.empty() && find_body(material->body) < 0) {
      return make_error(ErrorCode::kInvalidArgument, fmt::format("no body '{}' (bodies: {})", material->body, body_names()));
    }
    if (auto ok = haptics::validate(material->material); !ok) return std::unexpected(ok.error());
    for (const BodyRuntime& r : bodies_) {
      if (material->body.empty() || r.body.name == material->body) material_changes_.emplace_back(r.body.name, material->material);
    }
  } else if (const auto* effects = std::get_if<command::SetEffects>(&command)) {
    if (auto ok = haptics::validate_effects(effects->effects); !ok) return std::unexpected(ok.error());
  } else if (const auto* limit = std::get_if<command::SetForceLimit>(&command)) {
    if (!(limit->max_force_n >= 0.0 && std::isfinite(limit->max_force_n))) {
      return make_error(ErrorCode::kInvalidArgument,
                        fmt::format("force limit: maxForce must be >= 0 N (0: the device's own), got {}", limit->max_force_n));
    }
  } else if (const auto* renderer = std::get_if<command::SetRenderer>(&command)) {
    const haptics::RendererConfig& r = renderer->renderer;
    if (!(r.proxy_radius_m >= 0.0 && r.proxy_radius_m < 1.0) || r.max_iterations < 1 || r.max_iterations > 64 ||
        !(r.ride_distance_m >= 0.0 && std::isfinite(r.ride_distance_m)) ||
        !(r.penalty_max_distance_m >= 0.0 && std::isfinite(r.penalty_max_distance_m)) ||
        static_cast<int>(r.kind) > static_cast<int>(haptics::RendererKind::kRuspini) ||
        static_cast<int>(r.touchable_face) > static_cast<int>(collision::TouchableFace::kFrontAndBack)) {
      return make_error(ErrorCode::kInvalidArgument,
                        fmt::format("renderer: proxyRadius must be in [0, 1) m, iterations in [1, 64], the ride and penalty "
                                    "distances finite and >= 0; got {} m, {}, {} m, {} m",
                                    r.proxy_radius_m, r.max_iterations, r.ride_distance_m, r.penalty_max_distance_m));
    }
  }
  pending_.push_back(command);
  return {};
}

std::vector<ParameterChange> Session::parameter_changes(bool with_queued) const {
  std::lock_guard lock(commands_mutex_);
  std::vector<ParameterChange> changes = changes_;
  if (with_queued) {
    for (const Command& c : pending_) {
      if (const auto* set = std::get_if<command::SetParameter>(&c)) changes.push_back({set->body, set->component, set->parameter, set->value});
    }
  }
  return changes;
}

std::vector<std::pair<std::string, haptics::SurfaceMaterial>> Session::material_changes() const {
  std::lock_guard lock(commands_mutex_);
  return material_changes_;
}

void Session::publish_settings() {
  settings_.write_slot() = current_settings_;
  settings_.publish();
}

void Session::apply_commands(SessionReport& report) {
  // A device the haptic loop has switched away from is closed (its threads, its port): the
  // tick let it go at zero force and no longer reads it.
  haptics::Device* current = &loop_->device();
  if (current != last_device_) {
    if (last_device_) last_device_->close();
    last_device_ = current;
  }
  std::vector<Command> commands;
  {
    std::lock_guard lock(commands_mutex_);
    if (pending_.empty()) return;
    commands.swap(pending_);
  }
  const std::int64_t at = report.simulation_steps;
  bool settings_changed = false;
  for (std::size_t index = 0; index < commands.size(); ++index) {
    const Command& command = commands[index];
    if (const auto* set = std::get_if<command::SetParameter>(&command)) {
      for (BodyRuntime& r : bodies_) {
        if (r.body.name != set->body || !r.body.config) continue;
        mechanics::ModelConfig config = *r.body.config;
        auto ok = mechanics::set_parameter(config, set->component, set->parameter, set->value);
        auto model = ok ? mechanics::build_model(config) : Expected<mechanics::MechanicalModel>(std::unexpected(ok.error()));
        const std::string what = fmt::format("{}/{}{}{} = {}", set->body, set->component, set->component.empty() ? "" : "/",
                                             set->parameter, set->value);
        if (!model) {
          report.applied_commands.push_back(fmt::format("step {}: {} refused: {}", at, what, model.error().message));
          std::lock_guard lock(commands_mutex_);
          validated_configs_[static_cast<std::size_t>(&r - bodies_.data())] = *r.body.config;  // back to what runs
          continue;
        }
        // The new model starts from the current shape and motion.
        mechanics::MechanicalState state = mechanics::make_state(*model);
        state.x = r.state.x;
        state.v = r.state.v;
        r.body.model.emplace(std::move(*model));
        r.body.config = std::move(config);
        r.state = std::move(state);
        r.threads = 0;
        fit_threads(r);
        r.next_step_s = time_s_ + r.body.model->dt_s;
        report.applied_commands.push_back(fmt::format("step {}: {}", at, what));
        std::lock_guard lock(commands_mutex_);
        changes_.push_back(ParameterChange{set->body, set->component, set->parameter, set->value});
      }
      double dt = std::numeric_limits<double>::infinity();
      for (const BodyRuntime& r : bodies_) {
        if (r.body.deformable()) dt = std::min(dt, r.body.model->dt_s);
      }
      if (std::isfinite(dt)) dt_.store(dt, std::memory_order_relaxed);
    } else if (const auto* model = std::get_if<command::SetModel>(&command)) {
      for (BodyRuntime& r : bodies_) {
        if (r.body.name != model->body || !r.body.config) continue;
        // The new model starts from the current shape and motion (same nodes).
        mechanics::MechanicalState state = mechanics::make_state(*model->built);
        state.x = r.state.x;
        state.v = r.state.v;
        r.body.model.emplace(std::move(*model->built));
        r.body.config = model->config;
        r.state = std::move(state);
        r.threads = 0;
        fit_threads(r);
        r.next_step_s = time_s_ + r.body.model->dt_s;
        report.applied_commands.push_back(fmt::format("step {}: {} has a new model", at, model->body));
        std::lock_guard lock(commands_mutex_);
        std::erase_if(changes_, [&](const ParameterChange& c) { return c.body == model->body; });
      }
      double dt = std::numeric_limits<double>::infinity();
      for (const BodyRuntime& r : bodies_) {
        if (r.body.deformable()) dt = std::min(dt, r.body.model->dt_s);
      }
      if (std::isfinite(dt)) dt_.store(dt, std::memory_order_relaxed);
    } else if (std::holds_alternative<command::Pause>(command)) {
      paused_ = true;
      single_steps_ = 0;
      report.applied_commands.push_back(fmt::format("step {}: pause", at));
    } else if (std::holds_alternative<command::Resume>(command)) {
      paused_ = false;
      single_steps_ = 0;
      report.applied_commands.push_back(fmt::format("step {}: resume", at));
    } else if (const auto* steps = std::get_if<command::SingleStep>(&command)) {
      if (!paused_) {
        report.applied_commands.push_back(fmt::format("step {}: single step ignored (not paused)", at));
        continue;
      }
      single_steps_ += steps->steps;
      report.applied_commands.push_back(fmt::format("step {}: single step x{}", at, steps->steps));
    } else if (std::holds_alternative<command::Reset>(command)) {
      for (BodyRuntime& r : bodies_) {
        if (!r.body.deformable()) continue;
        r.state = mechanics::make_state(*r.body.model);
        r.threads = 0;
        fit_threads(r);
        r.reaction_sum.setZero();
        r.contact_ticks = 0;
      }
      report.applied_commands.push_back(fmt::format("step {}: reset", at));
    } else if (const auto* material = std::get_if<command::SetMaterial>(&command)) {
      for (std::size_t i = 0; i < bodies_.size(); ++i) {
        if (material->body.empty() || bodies_[i].body.name == material->body) current_settings_.materials[i] = material->material;
      }
      settings_changed = true;
      report.applied_commands.push_back(fmt::format("step {}: surface of {}", at, material->body.empty() ? "every body" : material->body));
    } else if (const auto* effects = std::get_if<command::SetEffects>(&command)) {
      current_settings_.effects = effects->effects;
      settings_changed = true;
      report.applied_commands.push_back(fmt::format("step {}: force effects", at));
    } else if (const auto* renderer = std::get_if<command::SetRenderer>(&command)) {
      current_settings_.renderer = renderer->renderer;
      settings_changed = true;
      report.applied_commands.push_back(fmt::format("step {}: renderer", at));
    } else if (const auto* calibration = std::get_if<command::SetCalibration>(&command)) {
      current_settings_.calibration = calibration->calibration;
      config_.haptics.calibration = calibration->calibration;
      settings_changed = true;
      report.applied_commands.push_back(fmt::format("step {}: calibration", at));
      calibrations_applied_.fetch_add(1, std::memory_order_release);
    } else if (const auto* limit = std::get_if<command::SetForceLimit>(&command)) {
      current_settings_.max_force_n = limit->max_force_n;
      settings_changed = true;
      report.applied_commands.push_back(fmt::format("step {}: force limit {} N", at, limit->max_force_n));
    } else if (const auto* device = std::get_if<command::SetDevice>(&command)) {
      if (!loop_->switch_device(*device->opened)) {
        // The previous switch has not reached a tick yet: this command and the ones after it
        // wait for the next step, in order.
        std::lock_guard lock(commands_mutex_);
        pending_.insert(pending_.begin(), commands.begin() + static_cast<std::ptrdiff_t>(index), commands.end());
        break;
      }
      switched_devices_.push_back(device->opened);
      report.applied_commands.push_back(fmt::format("step {}: device {}", at, device->spec));
    }
  }
  if (settings_changed) publish_settings();
}

// ---- Stepping

void Session::take_contacts(SessionReport& report) {
  const double period = loop_->nominal_period_s();
  haptics::HapticContact c;
  while (loop_->contacts().pop(c)) {
    ++ticks_since_step_;
    ++report.haptic_ticks;
    last_tick_valid_ = c.valid;
    if (c.valid) {
      for (std::size_t l = 0; l < layers_.size(); ++l) {
        layers_[l]->proxy = c.layers[l].proxy;
        layers_[l]->proxy_triangle = l < c.layer_count && c.layers[l].contact ? c.layers[l].triangle : -1;
      }
      last_proxy_valid_ = true;
    }
    const double force = c.force.norm();
    report.max_force_n = std::max(report.max_force_n, force);
    bool any = false;
    if (c.tool.active && c.tool.body >= 0 && static_cast<std::size_t>(c.tool.body) < bodies_.size()) {
      // The tool in a body: its reaction goes through the tool's coupling at the body's step.
      BodyRuntime& r = bodies_[static_cast<std::size_t>(c.tool.body)];
      r.tool_force_sum += c.tool.force;
      ++r.tool_ticks;
      r.last_tool = c.tool;
      r.report.contact_time_s += period;
      r.report.max_force_n = std::max(r.report.max_force_n, c.tool.force.norm());
      last_body_ = c.tool.body;
      any = true;
    }
    for (std::size_t l = 0; l < layers_.size() && l < c.layer_count; ++l) {
      const haptics::HapticContact::Layer& layer = c.layers[l];
      if (!layer.contact || layer.triangle < 0) continue;
      const haptics::SurfaceSnapshot& rest = layers_[l]->rest;
      const std::int32_t part = rest.part_of(layer.triangle);
      if (part < 0) continue;
      const auto b = static_cast<std::size_t>(rest.parts[static_cast<std::size_t>(part)].body);
      if (c.tool.active && c.tool.body == static_cast<std::int32_t>(b)) continue;  // the tool's (above)
      BodyRuntime& r = bodies_[b];
      r.reaction_sum -= layer.load;  // the tissue feels the opposite of what the tool pushes with
      ++r.contact_ticks;
      r.last_triangle = layer.triangle - rest.parts[static_cast<std::size_t>(part)].first_triangle;
      r.last_barycentric = layer.barycentric;
      r.report.contact_time_s += period;
      r.report.max_force_n = std::max(r.report.max_force_n, layer.force.norm());
      last_body_ = static_cast<std::int32_t>(b);
      last_triangle_ = layer.triangle;
      last_barycentric_ = layer.barycentric;
      any = true;
    }
    if (!any) continue;
    ++contact_ticks_this_step_;
    report.contact_time_s += period;
    if (c.clamped) ++report.clamped_contact_ticks;
    ++contact_ticks_since_publish_;
  }
}

void Session::count_fall_through(SessionReport& report) {
  // Only a proxy the device is driving: after a script ends (or the device is gone) the proxy
  // stays where it was, and a body moving through that spot has not been fallen through.
  if (!last_proxy_valid_ || !last_tick_valid_) return;
  const bool first = !first_reading_seen_;
  first_reading_seen_ = true;
  // A proxy outside a layer's bounding box is inside none of its bodies: one pass of minima
  // and maxima instead of the winding number's arctangent per triangle.
  for (auto& layer : layers_) {
    Eigen::AlignedBox3d box;
    for (const Vec3& v : layer->positions) box.extend(v);
    layer->proxy_outside_box = !box.contains(layer->proxy);
  }
  for (std::size_t i = 0; i < bodies_.size(); ++i) {
    BodyRuntime& r = bodies_[i];
    const LayerRuntime& layer = *layers_[r.layer];
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

bool Session::advance_bodies(SessionReport& report) {
  const double next_time = time_s_ + dt_;
  std::vector<BodyRuntime*>& due = due_;  // reserved at construction: a step does not allocate
  due.clear();
  for (BodyRuntime& r : bodies_) {
    if (r.body.deformable() && r.next_step_s <= next_time + 1e-9 * dt_) due.push_back(&r);
  }
  for (BodyRuntime* r : due) {
    // Contact forces: the average reaction over this body's ticks since its last step (the
    // force acted only during the contact ticks).
    r->state.external_force.setZero();
    const std::int64_t ticks = std::max<std::int64_t>(1, report.haptic_ticks - r->ticks_at_last_step);
    if (r->contact_ticks > 0 && r->last_triangle >= 0) {
      const Vec3 reaction = r->reaction_sum / static_cast<double>(ticks);
      const mesh::Tri& tri = r->body.surface.triangles[static_cast<std::size_t>(r->last_triangle)];
      std::span<double> forces{r->state.external_force.data(), static_cast<std::size_t>(r->state.external_force.size())};
      if (config_.coupling == ContactCoupling::kClosestVertex) {
        int nearest = 0;
        for (int k = 1; k < 3; ++k) {
          if (r->last_barycentric[k] > r->last_barycentric[nearest]) nearest = k;
        }
        r->body.mapping.add_vertex_force(tri[nearest], reaction, forces);
      } else {
        for (int k = 0; k < 3; ++k) r->body.mapping.add_vertex_force(tri[k], r->last_barycentric[k] * reaction, forces);
      }
    }
    if (r->tool_ticks > 0 && config_.tool_coupling) {
      // The tool's force averaged over this body's ticks since its last step (it acted only
      // during the ticks it was in the body), at the tool's latest place.
      haptics::ToolState tool = r->last_tool;
      tool.force = r->tool_force_sum / static_cast<double>(ticks);
      std::span<double> forces{r->state.external_force.data(), static_cast<std::size_t>(r->state.external_force.size())};
      config_.tool_coupling->add_tissue_forces(tool, *r->body.model, r->state, forces);
    }
    r->tool_force_sum.setZero();
    r->tool_ticks = 0;
    r->reaction_sum.setZero();
    r->contact_ticks = 0;
    r->ticks_at_last_step = report.haptic_ticks;
  }
  // Every due body steps; several in parallel (each body's own loops are thread-count
  // independent, so results do not depend on how they are spread).
  std::vector<char>& ok = step_ok_;
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
        largest = std::max(largest, (due[k]->state.position(static_cast<std::int32_t>(i)) - model.rest_positions[i]).norm());
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
  time_s_ = next_time;
  return true;
}

void Session::publish(double clock_s) {
  // The shape is staged here, on the simulation's thread (the mapping to the surface, the
  // contact's local model: they read the state); the snapshot itself (normals, the tree's
  // refit, about a tenth of a medium liver's step) is made by the publisher thread in real
  // time, on the core the haptic loop leaves idle, and here in virtual time (the same result).
  PublishJob& job = publisher_.joinable() ? publish_jobs_->write_slot() : inline_job_;
  job.clock_s = clock_s;
  job.layers.resize(layers_.size());
  for (std::size_t l = 0; l < layers_.size(); ++l) {
    LayerRuntime& layer = *layers_[l];
    for (const std::size_t i : layer.bodies) {
      BodyRuntime& r = bodies_[i];
      if (!r.body.deformable()) continue;
      const haptics::SurfacePart& part = layer.rest.parts[r.part];
      r.body.mapping.apply({r.state.x.data(), static_cast<std::size_t>(r.state.x.size())}, r.surface_positions);
      r.body.mapping.apply({r.state.v.data(), static_cast<std::size_t>(r.state.v.size())}, r.surface_velocities);
      std::copy(r.surface_positions.begin(), r.surface_positions.end(), layer.positions.begin() + part.first_vertex);
      std::copy(r.surface_velocities.begin(), r.surface_velocities.end(), layer.velocities.begin() + part.first_vertex);
    }
    LayerJob& staged = job.layers[l];
    staged.local = local_contact_model(l);
    if (publisher_.joinable()) {
      // Sized when the publisher started: the copy reuses the slot's storage.
      staged.positions.assign(layer.positions.begin(), layer.positions.end());
      staged.velocities.assign(layer.velocities.begin(), layer.velocities.end());
    }
  }
  if (publisher_.joinable()) {
    publish_jobs_->publish();
  } else {
    for (std::size_t l = 0; l < layers_.size(); ++l) {
      make_snapshot_of(l, layers_[l]->positions, layers_[l]->velocities, job.layers[l].local, clock_s);
    }
  }
  if (states_wanted_.load(std::memory_order_acquire)) {
    std::vector<std::vector<double>>& slot = graphics_states_.write_slot();
    slot.resize(bodies_.size());
    for (std::size_t i = 0; i < bodies_.size(); ++i) {
      if (!bodies_[i].body.deformable()) {
        slot[i].clear();
        continue;
      }
      const Eigen::VectorXd& x = bodies_[i].state.x;
      slot[i].assign(x.data(), x.data() + x.size());
    }
    graphics_states_.publish();
  }
  contact_ticks_since_publish_ = 0;
}

haptics::LocalContactModel Session::local_contact_model(std::size_t l) {
  haptics::LocalContactModel local;
  const LayerRuntime& layer = *layers_[l];
  const bool touched_here = last_body_ >= 0 && bodies_[static_cast<std::size_t>(last_body_)].layer == l;
  const bool fem_felt = config_.coupling == ContactCoupling::kCompliance || config_.coupling == ContactCoupling::kFemReaction;
  if (!fem_felt || !touched_here || contact_ticks_since_publish_ == 0 || !bodies_[static_cast<std::size_t>(last_body_)].body.deformable()) {
    return local;
  }
  // The contact point's compliance at the current state (Saupin, Duriez & Cotin 2008).
  BodyRuntime& r = bodies_[static_cast<std::size_t>(last_body_)];
  const std::int32_t triangle = last_triangle_ - layer.rest.parts[r.part].first_triangle;
  const mesh::Tri& tri = r.body.surface.triangles[static_cast<std::size_t>(triangle)];
  const std::array<std::int32_t, 3> vertices{tri[0], tri[1], tri[2]};
  const std::array<double, 3> bary{last_barycentric_[0], last_barycentric_[1], last_barycentric_[2]};
  std::array<std::int32_t, SurfaceMapping::kMaxPointWeights> nodes{};
  std::array<double, SurfaceMapping::kMaxPointWeights> weights{};
  const std::size_t count = r.body.mapping.point_weights(vertices, bary, nodes, weights);
  Mat3 compliance;
  if (config_.coupling == ContactCoupling::kFemReaction) {
    local.valid = true;
    local.direct = true;
    local.triangle = last_triangle_;
    local.barycentric = last_barycentric_;
    local.reaction = r.fem_reaction(tri, bary, std::span(nodes.data(), count));
  } else if (mechanics::compute_point_compliance(*r.body.model, r.state, std::span(nodes.data(), count),
                                                 std::span(weights.data(), count), compliance)) {
    const Eigen::FullPivLU<Mat3> lu(compliance);
    if (lu.isInvertible()) {
      local.valid = true;
      local.direct = false;
      local.triangle = last_triangle_;
      local.barycentric = last_barycentric_;
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

void Session::make_snapshot_of(std::size_t l, std::span<const Vec3> positions, std::span<const Vec3> velocities,
                               const haptics::LocalContactModel& local, double clock_s) {
  LayerRuntime& layer = *layers_[l];
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
  layer.surfaces.publish();
}

void Session::publisher_loop() {
  for (;;) {
    const bool stopping = stop_publisher_.load(std::memory_order_acquire);
    // The latest shape only: one staged while the last was being made replaces the older.
    if (publish_jobs_->acquire()) {
      const PublishJob& job = publish_jobs_->read();
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

void Session::start_publisher() {
  PublishJob sized;
  for (const auto& layer : layers_) sized.layers.push_back(LayerJob{layer->positions, layer->velocities, {}});
  publish_jobs_ = std::make_unique<TripleBuffer<PublishJob>>(sized);
  stop_publisher_.store(false, std::memory_order_release);
  publisher_ = std::thread([this] {
    // Beside the haptic loop, which sleeps most of each millisecond: off the simulation's CPUs.
    if (cpu_plan_.pinned()) pin_current_thread(std::array<int, 1>{cpu_plan_.haptic});
    publisher_loop();
  });
}

void Session::stop_publisher() {
  if (!publisher_.joinable()) return;
  // The last shape staged is made before the thread ends (it runs the loop once more).
  stop_publisher_.store(true, std::memory_order_release);
  publisher_.join();
  publish_jobs_.reset();
}

bool Session::step_world(SessionReport& report, StateTimer& timer, double clock_s) {
  apply_commands(report);
  take_contacts(report);
  count_fall_through(report);
  const bool contact_this_step = contact_ticks_this_step_ > 0;
  contact_ticks_this_step_ = 0;
  // Rigid bodies never step: their contact is not accumulated (it acts on nothing).
  for (BodyRuntime& r : bodies_) {
    if (r.body.deformable()) continue;
    r.reaction_sum.setZero();
    r.contact_ticks = 0;
    r.tool_force_sum.setZero();
    r.tool_ticks = 0;
  }
  ticks_since_step_ = 0;
  const auto step_start = Clock::now();
  const bool stepping = !paused_ || single_steps_ > 0;
  if (stepping) {
    if (paused_) --single_steps_;
    if (!advance_bodies(report)) {
      // Nothing more is published: the haptic loop fades the force out now rather than
      // rendering the last geometry until it is old enough for the watchdog.
      loop_->set_simulation_failed(true);
      return false;
    }
    ++report.simulation_steps;
    steps_taken_.fetch_add(1, std::memory_order_relaxed);
  }
  // Published while paused too: the haptic loop's watchdog sees a live simulation.
  publish(clock_s);
  // Stepping again after a failure (a reset or a new model took the divergence away): the
  // geometry just published is trusted again, and the force fades back in.
  if (stepping && loop_->simulation_failed()) loop_->set_simulation_failed(false);
  double moving = 0.0;
  for (const BodyRuntime& r : bodies_) {
    if (r.body.deformable() && r.state.v.size()) moving = std::max(moving, r.state.v.cwiseAbs().maxCoeff());
  }
  if (stepping) timer.add(contact_this_step, moving > 1e-4, seconds_between(step_start, Clock::now()));
  return true;
}

void Session::finish_report(SessionReport& report, const StateTimer& timer, double wall_s) const {
  report.wall_s = wall_s;
  report.simulated_s = time_s_;
  report.simulation_steps_per_s = wall_s > 0.0 ? static_cast<double>(report.simulation_steps) / wall_s : 0.0;
  report.rate_untouched = StateTimer::rate(timer.untouched, timer.untouched_s);
  report.rate_deforming = StateTimer::rate(timer.deforming, timer.deforming_s);
  report.rate_in_contact = StateTimer::rate(timer.contact, timer.contact_s);
  report.haptic_periods = loop_->period_stats();
  report.safety = loop_->safety_counters();
  report.bodies.clear();
  for (const BodyRuntime& r : bodies_) {
    BodyReport b = r.report;
    report.max_displacement_m = std::max(report.max_displacement_m, b.max_displacement_m);
    report.bodies.push_back(std::move(b));
  }
}

SessionReport Session::run_virtual(double seconds, const std::function<void(const haptics::HapticSample&)>& on_sample,
                                   const ProgressSink& progress) {
  SessionReport report;
  begin_run();
  const double tick_period = 1.0 / config_.haptics.rate_hz;
  const auto start = Clock::now();
  StateTimer timer;
  haptics::HapticSample sample;
  std::int64_t tick = 0;
  const auto total_ticks = static_cast<std::int64_t>(std::ceil(seconds / tick_period - 1e-6));
  std::int64_t steps = 0;
  while (tick < total_ticks && !stop_requested_.load(std::memory_order_relaxed)) {
    // N haptic ticks per simulation step (dt may change through a command).
    const auto ticks_per_step = std::max<std::int64_t>(1, std::llround(dt_ / tick_period));
    for (std::int64_t k = 0; k < ticks_per_step; ++k, ++tick) {
      loop_->tick(static_cast<double>(virtual_ticks_ + tick) * tick_period);
      while (loop_->telemetry().pop(sample)) {
        if (on_sample) on_sample(sample);
      }
    }
    const bool stepped = step_world(report, timer, static_cast<double>(virtual_ticks_ + tick) * tick_period);
    // A device that has failed (unplugged, its SDK in error) gives no reading: the force fades
    // as for a divergence, and the run ends, saying why.
    const bool device_failed = loop_->device().health() == haptics::DeviceHealth::kFailed;
    if (device_failed && report.device_failure.empty()) {
      const std::string why = loop_->device().failure();
      report.device_failure = why.empty() ? std::string("the device stopped working") : why;
    }
    if (!stepped || device_failed) {
      // The simulation has stopped (diverged): as the haptic thread does in real time, the
      // loop goes on ticking without it until the safety filter has faded the force to zero,
      // so that the run leaves the device at rest rather than holding the last force. The
      // fade takes fade_out_s, then the slew limit brings what is left to zero; the count
      // bounds it should a device's spec make the force never settle.
      const haptics::SafetyConfig& safety = config_.haptics.safety;
      const haptics::DeviceSpec& spec = loop_->device().spec();
      const double slew_s = spec.max_force_rate_n_per_s > 0.0 ? spec.max_force_n / spec.max_force_rate_n_per_s : 0.0;
      const auto fade_ticks = static_cast<std::int64_t>(std::ceil((safety.fade_out_s + slew_s) / tick_period)) + 2;
      for (std::int64_t k = 0; k < fade_ticks; ++k, ++tick) {
        loop_->tick(static_cast<double>(virtual_ticks_ + tick) * tick_period);
        bool at_rest = false;
        while (loop_->telemetry().pop(sample)) {
          at_rest = sample.force.isZero(0.0);
          if (on_sample) on_sample(sample);
        }
        if (at_rest) {
          ++tick;
          break;
        }
      }
      // Their contacts act on nothing (the bodies no longer step).
      haptics::HapticContact c;
      while (loop_->contacts().pop(c)) {
      }
      break;
    }
    ++steps;
    if (progress && (steps % 16 == 0 || tick >= total_ticks)) {
      progress("haptic session (virtual time)", std::min(1.0, static_cast<double>(tick) / static_cast<double>(total_ticks)));
    }
  }
  report.haptic_ticks = tick;
  virtual_ticks_ += tick;  // a next run goes on from here (the device's clock does not restart)
  finish_report(report, timer, seconds_between(start, Clock::now()));
  return report;
}

void Session::fit_threads(BodyRuntime& r) const {
  // (A fresh state from make_state runs on the model's own setting: r.threads is then 0.)
  if (!r.body.deformable()) return;
  // A model that names its threads (`threads` in the scene) keeps them.
  const int wanted = r.body.model->threads > 0 ? r.body.model->threads : step_threads_;
  if (wanted == r.threads) return;
  mechanics::set_threads(*r.body.model, r.state, wanted);
  r.threads = wanted;
}

void Session::begin_run() {
  // Each run reports on itself: per-body figures start again, as the session's do.
  for (BodyRuntime& r : bodies_) {
    r.ticks_at_last_step = 0;
    r.report = BodyReport{r.report.name, r.report.deformable, r.report.nodes, 0.0, 0.0, 0.0, 0, false};
    r.inside_since_start = false;
  }
  first_reading_seen_ = false;
  contact_ticks_this_step_ = 0;
  stop_requested_.store(false, std::memory_order_relaxed);
}

void Session::simulation_thread(double) {
  // (A body's steps on several threads: its workers are placed by the system.)
  if (cpu_plan_.pinned()) pin_current_thread(cpu_plan_.simulation);
  // Each body steps in its own arena of simulation_threads() (start_realtime set them); this
  // one runs several bodies' steps side by side.
  tbb::task_arena arena(simulation_threads());
  arena.execute([this] { simulation_loop(); });
}

int Session::simulation_threads() const {
  if (config_.simulation_threads > 0) return config_.simulation_threads;
  // Automatic: every core the process may use but one, which the haptic loop (and the
  // window) share.
  const std::size_t allowed = allowed_cpus().size();
  const std::size_t cores = allowed > 0 ? allowed : std::max(1u, std::thread::hardware_concurrency());
  return static_cast<int>(std::max<std::size_t>(1, cores - 1));
}

void Session::simulation_loop() {
  // Fixed-rate simulation on its own thread: sleep to the next step unless already late.
  auto next = Clock::now();
  while (!stop_sim_.load(std::memory_order_acquire)) {
    if (!step_world(rt_report_, *rt_timer_, seconds_between(rt_start_, Clock::now()))) break;
    next += std::chrono::duration_cast<Clock::duration>(std::chrono::duration<double>(dt_));
    const auto now = Clock::now();
    if (!paced_.load(std::memory_order_relaxed)) {
      next = now;
      std::this_thread::yield();
    } else if (next > now) {
      std::this_thread::sleep_until(next);
    } else if (seconds_between(next, now) > kMaxCatchUp_s) {
      next = now;  // too far behind to catch up (kMaxCatchUp_s)
    }
  }
  sim_finished_.store(true, std::memory_order_release);
}

void Session::start_realtime() {
  if (sim_thread_.joinable()) return;
  SessionReport fresh;
  rt_report_ = std::move(fresh);
  begin_run();
  rt_timer_ = std::make_unique<StateTimer>();
  stop_sim_.store(false);
  sim_finished_.store(false);
  // The simulation's threads: every core but one by default. On 2 cores that is one, and the
  // step then never wakes TBB's workers, which spin in sched_yield between a step's many short
  // loops and so took time from the haptic thread's core and delayed its wake-ups (the medium
  // liver at dt 1 ms, 2-core VM: haptic max period 5–10 ms with 2 threads, under 2 ms with 1;
  // the simulation's rate the same).
  step_threads_ = simulation_threads();
  rt_report_.simulation_threads = step_threads_;
  for (BodyRuntime& r : bodies_) {
    fit_threads(r);
    // What the bodies' steps will really run on (a model with threads of its own keeps them).
    if (r.body.deformable()) rt_report_.simulation_threads = mechanics::thread_count(r.state);
  }
  rt_start_ = Clock::now();
  cpu_plan_ = config_.pin_threads ? plan_cpus(allowed_cpus()) : CpuPlan{};
  rt_report_.cpu_placement = config_.pin_threads ? cpu_plan_.describe() : "not pinned (asked)";
  loop_->set_cpu(cpu_plan_.haptic);
  start_publisher();
  loop_->start();
  sim_thread_ = std::thread([this] { simulation_thread(dt_); });
}

void Session::poll(const std::function<void(const haptics::HapticSample&)>& on_sample) {
  haptics::HapticSample sample;
  while (loop_->telemetry().pop(sample)) {
    if (on_sample) on_sample(sample);
  }
}

SessionReport Session::stop_realtime(const std::function<void(const haptics::HapticSample&)>& on_sample) {
  if (!sim_thread_.joinable()) return rt_report_;
  stop_sim_.store(true, std::memory_order_release);
  sim_thread_.join();
  stop_publisher();
  loop_->stop();
  poll(on_sample);
  // Contacts of the ticks after the last step are not applied.
  haptics::HapticContact c;
  while (loop_->contacts().pop(c)) {
  }
  rt_report_.haptic_ticks = static_cast<std::int64_t>(loop_->ticks());
  // Virtual-time runs step on the caller's thread with every core again.
  step_threads_ = 0;
  for (BodyRuntime& r : bodies_) fit_threads(r);
  finish_report(rt_report_, *rt_timer_, seconds_between(rt_start_, Clock::now()));
  return rt_report_;
}

SessionReport Session::run_realtime(double seconds, const std::function<void(const haptics::HapticSample&)>& on_sample,
                                    const ProgressSink& progress) {
  start_realtime();
  const auto start = Clock::now();
  std::int64_t polls = 0;
  std::optional<double> device_failed_at;
  std::string device_failure;
  for (;;) {
    const double elapsed = seconds_between(start, Clock::now());
    if (elapsed >= seconds || sim_finished_.load(std::memory_order_acquire) || stop_requested_.load(std::memory_order_relaxed)) break;
    // A device that has failed: the haptic loop fades its force out (it gives no reading);
    // once that has had its time, the run ends, saying why.
    if (loop_->device().health() == haptics::DeviceHealth::kFailed) {
      if (!device_failed_at) device_failed_at = elapsed;
      const haptics::SafetyConfig& safety = config_.haptics.safety;
      const haptics::DeviceSpec& spec = loop_->device().spec();
      const double fade_s = safety.fade_out_s + (spec.max_force_rate_n_per_s > 0.0 ? spec.max_force_n / spec.max_force_rate_n_per_s : 0.0);
      if (elapsed - *device_failed_at > fade_s + 0.01) {
        const std::string why = loop_->device().failure();
        device_failure = why.empty() ? std::string("the device stopped working") : why;
        break;
      }
    }
    poll(on_sample);
    if (progress && ++polls % 16 == 0) progress("haptic session (real time)", std::min(1.0, elapsed / seconds));
    std::this_thread::sleep_for(std::chrono::milliseconds(5));
  }
  SessionReport report = stop_realtime(on_sample);
  report.device_failure = device_failure;
  if (progress) progress("haptic session (real time)", 1.0);
  return report;
}

}  // namespace hof::coupling
