#include "hof/coupling/command_seam.h"

#include <fmt/format.h>

#include <Eigen/LU>
#include <algorithm>
#include <cmath>
#include <limits>

#include "hof/coupling/detail/world_step.h"
#include "hof/mechanics/model_parameters.h"

namespace hof::coupling {

using detail::BodyRuntime;
using detail::World;

namespace {

/// A body's new model must keep its mesh: the surface follows the nodes through a mapping made
/// for this one.
Expected<void> same_mesh(const std::string& body, const mechanics::ModelConfig& next,
                         const mechanics::ModelConfig& now) {
  if (next.positions == now.positions && next.tets == now.tets) return {};
  return make_error(
      ErrorCode::kInvalidArgument,
      fmt::format("body '{}': the new model has another mesh ({} nodes, {} tetrahedra; the body has {} and {}): "
                  "reopen the project to change the mesh",
                  body, next.positions.size(), next.tets.size(), now.positions.size(), now.tets.size()));
}

// The world's step: the smallest deformable body's dt (unchanged when there is none).
void refresh_dt(World& w) {
  double dt = std::numeric_limits<double>::infinity();
  for (const BodyRuntime& r : w.bodies) {
    if (r.body.deformable()) dt = std::min(dt, r.body.model->dt_s);
  }
  if (std::isfinite(dt)) w.dt.store(dt, std::memory_order_relaxed);
}

// A body takes another model from its current shape and motion (same nodes).
void swap_model(World& w, BodyRuntime& r, mechanics::MechanicalModel&& model, mechanics::ModelConfig config) {
  mechanics::MechanicalState state = mechanics::make_state(model);
  state.x = r.state.x;
  state.v = r.state.v;
  r.body.model.emplace(std::move(model));
  r.body.config = std::move(config);
  r.state = std::move(state);
  r.threads = 0;
  detail::fit_threads(w, r);
  r.next_step_s = w.time_s + r.body.model->dt_s;
}

}  // namespace

/// What apply() hands each command: the world, the report, the step it is applied at.
struct CommandSeam::Applying {
  World& world;
  SessionReport& report;
  std::int64_t at;
  bool settings_changed{false};
  void log(const std::string& what) { report.applied_commands.push_back(fmt::format("step {}: {}", at, what)); }
};

CommandSeam::CommandSeam(const World& world)
    : fem_reaction_(world.config.coupling == ContactCoupling::kFemReaction),
      haptic_rate_hz_(world.config.haptics.rate_hz),
      submitted_calibration_(world.config.haptics.calibration) {
  contacts_enabled_ = world.config.contacts.enabled;
  for (const BodyRuntime& r : world.bodies) {
    names_.push_back(r.body.name);
    collides_.push_back(r.body.collision.enabled ? 1 : 0);
    validated_configs_.push_back(r.body.config.value_or(mechanics::ModelConfig{}));
    has_mechanics_.push_back(r.body.deformable() && r.body.config ? 1 : 0);
  }
}

CommandSeam::~CommandSeam() {
  // No thread is left on either side: what is still in the rings is let go here.
  Queued* queued = nullptr;
  while (queue_.pop(queued)) delete queued;
  delete waiting_;
  Report r;
  while (reports_.pop(r)) delete r.running;
}

std::string CommandSeam::body_names() const {
  std::string names;
  for (const std::string& name : names_) names += (names.empty() ? "" : ", ") + name;
  return names.empty() ? std::string("none") : names;
}

// ---- Submitting (any thread but the simulation's)

Expected<std::size_t> CommandSeam::deformable_body(BodyId body, std::string_view rigid) const {
  const auto i = static_cast<std::size_t>(body);
  if (i >= names_.size()) {
    return make_error(ErrorCode::kInvalidArgument, fmt::format("no body #{} (bodies: {})", i, body_names()));
  }
  // Whether it has mechanics is fixed at construction (the simulation thread may be
  // rebuilding the model right now: its optional is not read here).
  if (!has_mechanics_[i])
    return make_error(ErrorCode::kInvalidArgument, fmt::format("body '{}' is rigid: {}", names_[i], rigid));
  return i;
}

Expected<double> CommandSeam::parameter(BodyId body, mechanics::ParameterRef parameter) const {
  std::lock_guard lock(mutex_);
  take_reports();
  const auto i = deformable_body(body, "it has no mechanical parameters");
  if (!i) return std::unexpected(i.error());
  return mechanics::get_parameter(validated_configs_[*i], parameter);
}

Expected<mechanics::ModelConfig> CommandSeam::body_config(BodyId body) const {
  std::lock_guard lock(mutex_);
  take_reports();
  const auto i = deformable_body(body, "it has no mechanical parameters");
  if (!i) return std::unexpected(i.error());
  return validated_configs_[*i];
}

Expected<void> CommandSeam::submit(const Command& submitted) {
  Command command = submitted;
  if (const auto* set = std::get_if<command::SetParameter>(&command);
      set && fem_reaction_ &&
      set->parameter == mechanics::ParameterRef{{mechanics::ComponentKind::kModel, 0}, mechanics::ParameterId::kDt} &&
      !detail::fem_reaction_step_fits(set->value, haptic_rate_hz_)) {
    return make_error(
        ErrorCode::kInvalidArgument,
        fmt::format(
            "body '{}': dt {:g} s: coupling fem-reaction needs dt equal to the haptic period, {:g} s",
            static_cast<std::size_t>(set->body) < names_.size() ? names_[static_cast<std::size_t>(set->body)] : "?",
            set->value, 1.0 / haptic_rate_hz_));
  }
  if (auto* device = std::get_if<command::SetDevice>(&command); device && !device->opened) {
    // Opened here, on the caller's thread (a network device may wait for its first packet).
    auto opened = haptics::open_device(device->config);
    if (!opened) return std::unexpected(opened.error());
    device->opened = std::shared_ptr<haptics::Device>(std::move(*opened));
  }
  if (auto* model = std::get_if<command::SetModel>(&command)) {
    std::string name;
    // Built here, outside the lock (the simulation thread takes it between steps); the cheap
    // checks come first so that their messages are the ones a user sees.
    {
      std::lock_guard lock(mutex_);
      const auto i = deformable_body(model->body, "it has no model to replace");
      if (!i) return std::unexpected(i.error());
      if (auto same = same_mesh(names_[*i], model->config, validated_configs_[*i]); !same) return same;
      name = names_[*i];
    }
    auto built = mechanics::build_model(model->config);
    if (!built)
      return make_error(ErrorCode::kInvalidArgument, fmt::format("body '{}': {}", name, built.error().message));
    model->built = std::make_shared<mechanics::MechanicalModel>(std::move(*built));
  }
  std::lock_guard lock(mutex_);
  take_reports();
  // Room first: a command refused for want of it has changed nothing. (popped_ trails the
  // ring's own count, so room seen here is room the push finds.)
  if (pushed_ - popped_.load(std::memory_order_acquire) >= queue_.capacity()) {
    return make_error(
        ErrorCode::kInvalidArgument,
        fmt::format("the command queue is full ({} commands wait for the simulation, which is not stepping "
                    "or is slower than the commands come): submit again after a step",
                    queue_.capacity()));
  }
  if (auto ok = std::visit([this](auto& c) { return validate(c); }, command); !ok) return ok;
  const std::uint64_t ticket = next_ticket_++;
  if (const auto* set = std::get_if<command::SetParameter>(&command))
    accepted_.push_back(Accepted{ticket, ParameterChange{set->body, set->parameter, set->value}, false});
  auto* queued = new Queued{ticket, std::move(command)};
  if (!queue_.push(queued)) {  // not reached: the room was checked above, under the same lock
    delete queued;
    return make_error(ErrorCode::kInvalidArgument, "the command queue is full: submit again after a step");
  }
  ++pushed_;
  return {};
}

void CommandSeam::take_reports() const {
  Report r;
  while (reports_.pop(r)) {
    const auto at = [&](const Accepted& a) { return a.ticket == r.ticket; };
    switch (r.outcome) {
      case Outcome::kApplied:
        for (Accepted& a : accepted_) {
          if (at(a)) a.applied = true;
        }
        break;
      case Outcome::kRefused:
        // Back to what runs: the simulation could not build the model the change asked for.
        std::erase_if(accepted_, at);
        validated_configs_[r.body] = std::move(*r.running);
        delete r.running;
        break;
      case Outcome::kModelSwapped:
        // The changes before the new model are part of its config (those queued after it stay).
        std::erase_if(accepted_,
                      [&](const Accepted& a) { return a.ticket < r.ticket && a.change.body == BodyId{r.body}; });
        break;
    }
  }
}

void CommandSeam::tell(const Report& r) {
  // The ring cannot be full: the submitting side takes the reports before every push, and
  // each applied command makes at most one report per body.
  if (!reports_.push(r)) delete r.running;
}

Expected<void> CommandSeam::validate(command::SetParameter& set) {
  const auto i = deformable_body(set.body, "it has no mechanical parameters");
  if (!i) return std::unexpected(i.error());
  mechanics::ModelConfig& config = validated_configs_[*i];
  if (auto ok = mechanics::set_parameter(config, set.parameter, set.value); !ok) {
    return make_error(ErrorCode::kInvalidArgument, fmt::format("body '{}': {}", names_[*i], ok.error().message));
  }
  // Recorded as a change (to be saved) once the simulation has applied it.
  return {};
}

Expected<void> CommandSeam::validate(command::SetModel& model) {
  const auto i = deformable_body(model.body, "it has no model to replace");
  if (!i) return std::unexpected(i.error());
  // Checked again under the lock (the body may have had another model submitted meanwhile).
  if (auto same = same_mesh(names_[*i], model.config, validated_configs_[*i]); !same) return same;
  validated_configs_[*i] = model.config;
  // The caller took the body's changes into `config`: from now on they are not changes
  // (erased again when applied, for a parameter command still queued before this one).
  std::erase_if(accepted_, [&](const Accepted& a) { return a.applied && a.change.body == model.body; });
  return {};
}

Expected<void> CommandSeam::validate(command::SetCalibration& calibration) {
  const Eigen::Matrix4d& m = calibration.calibration.position;
  const double det = m.topLeftCorner<3, 3>().determinant();
  if (!m.allFinite() || !calibration.calibration.orientation.coeffs().allFinite() || !(std::abs(det) > 1e-12) ||
      m.row(3) != Eigen::RowVector4d(0, 0, 0, 1)) {
    return make_error(ErrorCode::kInvalidArgument,
                      "calibration: positionCalibration must be a finite affine 4x4 matrix (last row 0 0 0 1) with an "
                      "invertible linear part");
  }
  submitted_calibration_ = calibration.calibration;
  return {};
}

Expected<void> CommandSeam::validate(command::SingleStep& steps) {
  if (steps.steps < 1 || steps.steps > 1000000) {
    return make_error(ErrorCode::kInvalidArgument,
                      fmt::format("single step: steps must be in [1, 1000000], got {}", steps.steps));
  }
  return {};
}

Expected<void> CommandSeam::validate(command::SetMaterial& material) {
  if (material.body && static_cast<std::size_t>(*material.body) >= names_.size()) {
    return make_error(ErrorCode::kInvalidArgument,
                      fmt::format("no body #{} (bodies: {})", static_cast<std::size_t>(*material.body), body_names()));
  }
  if (auto ok = haptics::validate(material.material); !ok) return std::unexpected(ok.error());
  for (std::size_t i = 0; i < names_.size(); ++i) {
    const auto body = static_cast<BodyId>(i);
    if (!material.body || *material.body == body) material_changes_.push_back(MaterialChange{body, material.material});
  }
  return {};
}

Expected<void> CommandSeam::validate(command::SetEffects& effects) {
  if (auto ok = haptics::validate_effects(effects.effects); !ok) return std::unexpected(ok.error());
  return {};
}

Expected<void> CommandSeam::validate(command::SetForceLimit& limit) {
  if (!(limit.max_force_n >= 0.0 && std::isfinite(limit.max_force_n))) {
    return make_error(
        ErrorCode::kInvalidArgument,
        fmt::format("force limit: maxForce must be >= 0 N (0: the device's own), got {}", limit.max_force_n));
  }
  return {};
}

Expected<void> CommandSeam::validate(command::SetRenderer& renderer) {
  const haptics::RendererConfig& r = renderer.renderer;
  if (!(r.proxy_radius_m >= 0.0 && r.proxy_radius_m < 1.0) || r.max_iterations < 1 || r.max_iterations > 64 ||
      !(r.ride_distance_m >= 0.0 && std::isfinite(r.ride_distance_m)) ||
      !(r.penalty_max_distance_m >= 0.0 && std::isfinite(r.penalty_max_distance_m)) ||
      static_cast<int>(r.kind) > static_cast<int>(haptics::RendererKind::kRuspini) ||
      static_cast<int>(r.touchable_face) > static_cast<int>(collision::TouchableFace::kFrontAndBack)) {
    return make_error(
        ErrorCode::kInvalidArgument,
        fmt::format("renderer: proxyRadius must be in [0, 1) m, iterations in [1, 64], the ride and penalty "
                    "distances finite and >= 0; got {} m, {}, {} m, {} m",
                    r.proxy_radius_m, r.max_iterations, r.ride_distance_m, r.penalty_max_distance_m));
  }
  return {};
}

Expected<void> CommandSeam::validate(command::SetContactPair& pair) {
  if (!contacts_enabled_) {
    return make_error(ErrorCode::kInvalidArgument,
                      "contact pair: contact between bodies is off in this scene (a .hof <contact>, or a SOFA "
                      "collision pipeline, turns it on)");
  }
  if (pair.a == pair.b) {
    return make_error(ErrorCode::kInvalidArgument,
                      "contact pair: a pair needs two different bodies (selfCollision switches a body's contact "
                      "with itself)");
  }
  for (const BodyId id : {pair.a, pair.b}) {
    const auto i = static_cast<std::size_t>(id);
    if (i >= names_.size())
      return make_error(ErrorCode::kInvalidArgument,
                        fmt::format("contact pair: no body #{} (bodies: {})", i, body_names()));
    if (!collides_[i]) {
      return make_error(ErrorCode::kInvalidArgument,
                        fmt::format("contact pair: body '{}' takes no part in contact between bodies (it has no "
                                    "collision model)",
                                    names_[i]));
    }
  }
  return {};
}

std::vector<ParameterChange> CommandSeam::parameter_changes(bool with_queued) const {
  std::lock_guard lock(mutex_);
  take_reports();
  // Applied ones first, in order, then (with_queued) those still on their way, in order.
  std::vector<ParameterChange> changes;
  for (const Accepted& a : accepted_) {
    if (a.applied) changes.push_back(a.change);
  }
  if (with_queued) {
    for (const Accepted& a : accepted_) {
      if (!a.applied) changes.push_back(a.change);
    }
  }
  return changes;
}

std::vector<MaterialChange> CommandSeam::material_changes() const {
  std::lock_guard lock(mutex_);
  return material_changes_;
}

haptics::Calibration CommandSeam::calibration() const {
  std::lock_guard lock(mutex_);
  return submitted_calibration_;
}

// ---- Applying (the simulation's thread, between two steps: it never locks)

void CommandSeam::apply(World& w, SessionReport& report) {
  // A device the haptic loop has switched away from is closed (its threads, its port): the
  // tick let it go at zero force and no longer reads it.
  haptics::Device* current = &w.loop->device();
  if (current != w.last_device) {
    if (w.last_device) w.last_device->close();
    w.last_device = current;
  }
  Applying a{w, report, report.simulation_steps};
  for (;;) {
    Queued* queued = waiting_;
    waiting_ = nullptr;
    if (!queued) {
      if (!queue_.pop(queued)) break;
      popped_.fetch_add(1, std::memory_order_release);
    }
    applying_ticket_ = queued->ticket;
    if (!std::visit([&](const auto& c) { return apply(c, a); }, queued->command)) {
      // This command and the ones after it wait for the next step, in order.
      waiting_ = queued;
      break;
    }
    delete queued;
  }
  if (a.settings_changed) detail::publish_settings(w);
}

bool CommandSeam::apply(const command::SetParameter& set, Applying& a) {
  for (BodyRuntime& r : a.world.bodies) {
    if (&r - a.world.bodies.data() != static_cast<std::ptrdiff_t>(set.body) || !r.body.config) continue;
    mechanics::ModelConfig config = *r.body.config;
    // The log names the parameter as the running configuration does.
    const std::string_view component = mechanics::component_name(config, set.parameter.component);
    const std::string what = fmt::format("{}/{}{}{} = {}", r.body.name, component, component.empty() ? "" : "/",
                                         mechanics::parameter_name(set.parameter.id), set.value);
    auto ok = mechanics::set_parameter(config, set.parameter, set.value);
    auto model =
        ok ? mechanics::build_model(config) : Expected<mechanics::MechanicalModel>(std::unexpected(ok.error()));
    const auto body = static_cast<std::uint32_t>(&r - a.world.bodies.data());
    if (!model) {
      a.log(fmt::format("{} refused: {}", what, model.error().message));
      tell(Report{applying_ticket_, Outcome::kRefused, body, new mechanics::ModelConfig(*r.body.config)});
      continue;
    }
    swap_model(a.world, r, std::move(*model), std::move(config));
    a.log(what);
    tell(Report{applying_ticket_, Outcome::kApplied, body, nullptr});
  }
  refresh_dt(a.world);
  return true;
}

bool CommandSeam::apply(const command::SetModel& model, Applying& a) {
  for (BodyRuntime& r : a.world.bodies) {
    if (&r - a.world.bodies.data() != static_cast<std::ptrdiff_t>(model.body) || !r.body.config) continue;
    swap_model(a.world, r, std::move(*model.built), model.config);
    a.log(fmt::format("{} has a new model", r.body.name));
    tell(Report{applying_ticket_, Outcome::kModelSwapped, static_cast<std::uint32_t>(&r - a.world.bodies.data()),
                nullptr});
  }
  refresh_dt(a.world);
  return true;
}

bool CommandSeam::apply(const command::Pause&, Applying& a) {
  a.world.paused = true;
  a.world.single_steps = 0;
  a.log("pause");
  return true;
}

bool CommandSeam::apply(const command::Resume&, Applying& a) {
  a.world.paused = false;
  a.world.single_steps = 0;
  a.log("resume");
  return true;
}

bool CommandSeam::apply(const command::SingleStep& steps, Applying& a) {
  if (!a.world.paused) {
    a.log("single step ignored (not paused)");
    return true;
  }
  a.world.single_steps += steps.steps;
  a.log(fmt::format("single step x{}", steps.steps));
  return true;
}

bool CommandSeam::apply(const command::Reset&, Applying& a) {
  for (BodyRuntime& r : a.world.bodies) {
    if (!r.body.deformable()) continue;
    r.state = mechanics::make_state(*r.body.model);
    r.threads = 0;
    detail::fit_threads(a.world, r);
    for (detail::HandLoad& load : r.loads) {
      load.reaction_sum.setZero();
      load.contact_ticks = 0;
    }
  }
  a.log("reset");
  return true;
}

bool CommandSeam::apply(const command::SetMaterial& material, Applying& a) {
  for (std::size_t i = 0; i < a.world.bodies.size(); ++i) {
    if (!material.body || *material.body == static_cast<BodyId>(i))
      a.world.current_settings.materials[i] = material.material;
  }
  a.settings_changed = true;
  a.log(fmt::format("surface of {}",
                    material.body ? a.world.bodies[static_cast<std::size_t>(*material.body)].body.name : "every body"));
  return true;
}

bool CommandSeam::apply(const command::SetEffects& effects, Applying& a) {
  a.world.current_settings.effects = effects.effects;
  a.settings_changed = true;
  a.log("force effects");
  return true;
}

bool CommandSeam::apply(const command::SetRenderer& renderer, Applying& a) {
  a.world.current_settings.renderer = renderer.renderer;
  a.settings_changed = true;
  a.log("renderer");
  return true;
}

bool CommandSeam::apply(const command::SetCalibration& calibration, Applying& a) {
  a.world.current_settings.calibration = calibration.calibration;
  a.world.config.haptics.calibration = calibration.calibration;
  a.settings_changed = true;
  a.log("calibration");
  a.world.calibrations_applied.fetch_add(1, std::memory_order_release);
  return true;
}

bool CommandSeam::apply(const command::SetForceLimit& limit, Applying& a) {
  a.world.current_settings.max_force_n = limit.max_force_n;
  a.settings_changed = true;
  a.log(fmt::format("force limit {} N", limit.max_force_n));
  return true;
}

bool CommandSeam::apply(const command::SetDevice& device, Applying& a) {
  // The previous switch has not reached a tick yet: this command waits for the next step.
  if (!a.world.loop->switch_device(*device.opened)) return false;
  a.world.switched_devices.push_back(device.opened);
  a.log(fmt::format("device {}", device.label));
  return true;
}

bool CommandSeam::apply(const command::SetContactPair& pair, Applying& a) {
  // The settings keep the pair (smaller index first, sorted, as the scene builder gives them),
  // and the contact pass takes it from its next pass.
  const auto first = static_cast<std::int32_t>(std::min(pair.a, pair.b));
  const auto second = static_cast<std::int32_t>(std::max(pair.a, pair.b));
  auto& disabled = a.world.config.contacts.disabled_pairs;
  const std::pair<std::int32_t, std::int32_t> key{first, second};
  const auto at = std::lower_bound(disabled.begin(), disabled.end(), key);
  const bool listed = at != disabled.end() && *at == key;
  if (pair.enabled && listed) disabled.erase(at);
  if (!pair.enabled && !listed) disabled.insert(at, key);
  a.world.body_contacts.set_pair_enabled(static_cast<std::size_t>(first), static_cast<std::size_t>(second),
                                         pair.enabled);
  const auto name = [&](std::int32_t i) { return a.world.bodies[static_cast<std::size_t>(i)].body.name; };
  a.log(fmt::format("contact {} - {} {}", name(first), name(second), pair.enabled ? "on" : "off"));
  return true;
}

}  // namespace hof::coupling
