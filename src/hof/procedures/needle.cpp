#include "hof/procedures/needle.h"

#include <fmt/format.h>

#include <algorithm>
#include <cmath>

namespace hof::procedures {

std::string_view axis_name(NeedleAxis axis) {
  switch (axis) {
    case NeedleAxis::kMotion:
      return "motion";
    case NeedleAxis::kNormal:
      return "normal";
    case NeedleAxis::kStylus:
      return "stylus";
  }
  return "motion";
}

Expected<void> validate(const NeedleConfig& config) {
  const NeedleGeometry& g = config.geometry;
  for (double v : {g.length_m, g.shaft_diameter_m, g.tip_diameter_m, g.syringe_diameter_m, g.syringe_length_m}) {
    if (!(v > 0.0 && std::isfinite(v))) {
      return make_error(
          ErrorCode::kInvalidArgument,
          fmt::format(
              "needle: length, shaftDiameter, tipDiameter, syringeDiameter and syringeLength must be > 0 m, got {}",
              v));
    }
  }
  if (!(g.tip_length_m >= 0.0 && g.tip_length_m <= g.length_m)) {
    return make_error(
        ErrorCode::kInvalidArgument,
        fmt::format("needle: tipLength must be in [0, length] = [0, {}] m, got {}", g.length_m, g.tip_length_m));
  }
  if (!(config.velocity_filter_s >= 0.0 && config.velocity_filter_s <= 1.0)) {
    return make_error(ErrorCode::kInvalidArgument,
                      fmt::format("needle: velocityFilter must be in [0, 1] s, got {}", config.velocity_filter_s));
  }
  if (auto ok = validate(config.tissue, "needle tissue"); !ok) return ok;
  for (const auto& [name, set] : config.bodies) {
    if (auto ok = validate(set, fmt::format("needle tissue of body '{}'", name)); !ok) return ok;
  }
  return {};
}

std::vector<TissueNeedleParameters> parameters_by_body(const NeedleConfig& config,
                                                       const std::vector<std::string>& body_names,
                                                       const std::vector<bool>& deformable) {
  std::vector<TissueNeedleParameters> out;
  for (std::size_t i = 0; i < body_names.size(); ++i) {
    const auto own = std::find_if(config.bodies.begin(), config.bodies.end(),
                                  [&](const auto& b) { return b.first == body_names[i]; });
    if (own != config.bodies.end()) {
      out.push_back(own->second);
    } else {
      out.push_back(config.tissue);
      out.back().pierceable = config.tissue.pierceable && i < deformable.size() && deformable[i];
    }
  }
  return out;
}

Expected<std::shared_ptr<NeedleTool>> NeedleTool::make(const NeedleConfig& config, std::vector<std::string> body_names,
                                                       std::vector<bool> deformable, double metres_per_unit) {
  if (auto ok = validate(config); !ok) return std::unexpected(ok.error());
  if (!(metres_per_unit > 0.0 && std::isfinite(metres_per_unit))) {
    return make_error(ErrorCode::kInvalidArgument,
                      fmt::format("needle: the length unit must be > 0 m, got {}", metres_per_unit));
  }
  for (const auto& [name, set] : config.bodies) {
    if (std::find(body_names.begin(), body_names.end(), name) == body_names.end()) {
      std::string names;
      for (const auto& n : body_names) names += (names.empty() ? "" : ", ") + n;
      return make_error(ErrorCode::kInvalidArgument, fmt::format("needle: no body '{}' for its tissue (bodies: {})",
                                                                 name, names.empty() ? "none" : names));
    }
  }
  return std::shared_ptr<NeedleTool>(
      new NeedleTool(config, std::move(body_names), std::move(deformable), metres_per_unit));
}

NeedleTool::NeedleTool(const NeedleConfig& config, std::vector<std::string> body_names, std::vector<bool> deformable,
                       double metres_per_unit)
    : config_(config),
      body_names_(std::move(body_names)),
      deformable_(std::move(deformable)),
      metres_per_unit_(metres_per_unit) {
  spread_radius_ = std::make_unique<std::atomic<double>[]>(std::max<std::size_t>(1, body_names_.size()));
  resolve();
  // Every slot the tick may read holds the settings.
  settings_.write_slot() = producer_resolved_;
  settings_.publish();
  settings_.acquire();
  settings_.write_slot() = producer_resolved_;
}

void NeedleTool::resolve() {
  producer_resolved_.axis = config_.axis;
  producer_resolved_.velocity_filter_s = config_.velocity_filter_s;
  producer_resolved_.bodies = parameters_by_body(config_, body_names_, deformable_);
  for (std::size_t i = 0; i < body_names_.size(); ++i)
    spread_radius_[i].store(producer_resolved_.bodies[i].spread_radius_m / metres_per_unit_);
  if (body_names_.empty()) spread_radius_[0].store(config_.tissue.spread_radius_m / metres_per_unit_);
}

Expected<void> NeedleTool::configure(const NeedleConfig& config) {
  if (auto ok = validate(config); !ok) return ok;
  for (const auto& [name, set] : config.bodies) {
    if (std::find(body_names_.begin(), body_names_.end(), name) == body_names_.end()) {
      return make_error(ErrorCode::kInvalidArgument, fmt::format("needle: no body '{}' for its tissue", name));
    }
  }
  config_ = config;
  resolve();
  settings_.write_slot() = producer_resolved_;
  settings_.publish();
  return {};
}

const TissueNeedleParameters& NeedleTool::parameters(std::size_t body) const {
  return producer_resolved_.bodies.at(body);
}

double NeedleTool::spread_radius(std::size_t body) const {
  return spread_radius_[body < body_names_.size() ? body : 0].load(std::memory_order_relaxed);
}

void NeedleTool::restart() {
  disengage(NeedlePhase::kFree);
  rearmed_ = true;
  have_velocity_ = false;
}

void NeedleTool::disengage(NeedlePhase phase) {
  engaged_ = false;
  broken_ = false;
  phase_ = phase;
  body_ = -1;
  layer_ = -1;
  held_n_ = 0.0;
}

namespace {

// The body the contact of layer `l` touches (the part's body, or the part itself when the
// surface has no bodies), or -1 when the layer is not in contact.
std::int32_t touched_body(const haptics::ToolTickInput& in, std::size_t l) {
  if (l >= in.contacts.size() || l >= in.surfaces.size() || !in.surfaces[l]) return -1;
  const haptics::ContactState& c = in.contacts[l];
  if (!c.in_contact || c.triangle < 0) return -1;
  const std::int32_t part = in.surfaces[l]->part_of(c.triangle);
  if (part < 0) return -1;
  const std::int32_t body = in.surfaces[l]->parts[static_cast<std::size_t>(part)].body;
  return body >= 0 ? body : part;
}

}  // namespace

// The tick in stages: filter the tip's velocity, re-enter or re-arm after a withdrawal,
// engage on a first contact, then the axial force of the phase the needle is in and the
// lateral hold of the tissue. No stage allocates (the tick runs in the haptic loop).
Vec3 NeedleTool::tick(const haptics::ToolTickInput& in, std::span<Vec3> layer_forces, haptics::ToolState& st) {
  settings_.acquire();
  const Resolved& settings = settings_.read();
  const double to_m = metres_per_unit_;
  filter_velocity(in, settings);
  if (!engaged_ && !rearmed_) reenter_or_rearm(in, layer_forces);
  if (!engaged_ && rearmed_) engage(in, settings);
  if (!engaged_) return publish(in, st, 0.0, 0.0, 0.0, Vec3::Zero());

  const TissueNeedleParameters& p = settings.bodies[static_cast<std::size_t>(body_)];
  // Depth and axial velocity in SI (the model's units), whatever the world's.
  double d = (in.position - entry_).dot(axis_) * to_m;
  const double v = velocity_.dot(axis_) * to_m;
  Vec3 off_axis = (in.position - entry_) - (d / to_m) * axis_;
  // The zero-force surface: the pierced body's surface lets the tip pass.
  const bool on_surface = touched_body(in, static_cast<std::size_t>(layer_)) == body_;
  if (on_surface) layer_forces[static_cast<std::size_t>(layer_)].setZero();

  double f = 0.0;
  if (!broken_) {
    // The capsule is intact: the needle is not in yet, and its dimple slides with the tip (no
    // lateral hold before the puncture).
    entry_ += off_axis;
    off_axis.setZero();
    if (d <= 0.0 && !on_surface) {
      disengage(NeedlePhase::kFree);
      return publish(in, st, 0.0, v, 0.0, Vec3::Zero());
    }
    f = capsule_force(p, d, v);
  } else {
    // Out past the entry, or torn sideways out of the path (a rigid needle cannot cross the
    // tissue): withdrawn.
    if (d <= 0.0 || off_axis.norm() * to_m > p.path_tolerance_m) {
      withdrawn_from_ = body_;
      withdrawn_layer_ = layer_;
      disengage(NeedlePhase::kOut);
      rearmed_ = false;
      return publish(in, st, 0.0, v, 0.0, Vec3::Zero());
    }
    f = inserted_force(p, d, v, in.time_s);
  }
  held_n_ = f;

  // Inside, the tissue holds the shaft on its path: a lateral spring toward the axis line.
  Vec3 lateral = Vec3::Zero();
  if (broken_ && d > 0.0) {
    const Vec3 lateral_velocity = velocity_ - velocity_.dot(axis_) * axis_;
    const double k = std::min(p.lateral_stiffness_n_per_m * to_m, in.max_stiffness_n_per_m);  // N per world unit
    lateral = -k * off_axis - p.lateral_damping_n_s_per_m * to_m * lateral_velocity;
  }
  d = std::max(0.0, d);
  return publish(in, st, d, v, f, -f * axis_ + lateral);
}

// The tip's velocity, low-pass filtered (first order, time constant velocity_filter_s).
void NeedleTool::filter_velocity(const haptics::ToolTickInput& in, const Resolved& settings) {
  if (!have_velocity_ || !(settings.velocity_filter_s > 0.0)) {
    velocity_ = in.velocity;
    have_velocity_ = true;
  } else {
    velocity_ += (1.0 - std::exp(-in.dt_s / settings.velocity_filter_s)) * (in.velocity - velocity_);
  }
}

// Just withdrawn: the stylus is still at the surface, which stays force-free (the tissue
// dragged out with the needle has the tip under its surface: it must not spring the hand
// back). Pushed back in there, the needle re-enters the hole it made; once the stylus has
// left the surface, the next contact starts a new insertion.
void NeedleTool::reenter_or_rearm(const haptics::ToolTickInput& in, std::span<Vec3> layer_forces) {
  bool touching = false;
  for (std::size_t l = 0; l < in.contacts.size(); ++l) {
    if (touched_body(in, l) != withdrawn_from_) continue;
    touching = true;
    layer_forces[l].setZero();
  }
  if ((in.position - entry_).dot(axis_) > 0.0 && touching) {
    engaged_ = true;
    broken_ = true;
    body_ = withdrawn_from_;
    layer_ = withdrawn_layer_;
    phase_ = NeedlePhase::kPunctured;
    held_n_ = 0.0;
    rearmed_ = true;
  } else {
    rearmed_ = !touching;
  }
}

// First contact with a body the needle can enter: the entry point and the axis are fixed.
void NeedleTool::engage(const haptics::ToolTickInput& in, const Resolved& settings) {
  for (std::size_t l = 0; l < in.contacts.size(); ++l) {
    const std::int32_t b = touched_body(in, l);
    if (b < 0 || static_cast<std::size_t>(b) >= settings.bodies.size() ||
        !settings.bodies[static_cast<std::size_t>(b)].pierceable) {
      continue;
    }
    const haptics::ContactState& c = in.contacts[l];
    const TissueNeedleParameters& p = settings.bodies[static_cast<std::size_t>(b)];
    const double still = std::max(1e-9, 0.5 * p.friction.velocity_band_m_per_s) / metres_per_unit_;  // world units/s
    normal_ = c.normal.norm() > 0.0 ? c.normal.normalized() : Vec3(0.0, 0.0, 1.0);
    const Vec3 inward = -normal_;
    axis_ = inward;
    if (settings.axis == NeedleAxis::kMotion) {
      const double speed = velocity_.norm();
      if (speed > still && velocity_.dot(inward) > 0.2 * speed) axis_ = velocity_ / speed;
    } else if (settings.axis == NeedleAxis::kStylus) {
      const Vec3 stylus = in.orientation * Vec3(0.0, 0.0, -1.0);
      if (stylus.dot(inward) > 0.0) axis_ = stylus.normalized();
    }
    entry_ = c.point;
    engaged_ = true;
    broken_ = false;
    body_ = b;
    layer_ = static_cast<std::int32_t>(l);
    phase_ = NeedlePhase::kTouching;
    held_n_ = 0.0;
    max_depth_m_ = 0.0;
    break;
  }
}

// The axial force while the capsule holds (depth d, axial velocity v, SI): touching at or
// above the entry, pressing the capsule in, or puncturing it this tick.
double NeedleTool::capsule_force(const TissueNeedleParameters& p, double d, double v) {
  if (d <= 0.0) {
    phase_ = NeedlePhase::kTouching;
    return 0.0;
  }
  const double f = pre_puncture_force(p, d);
  if (d >= p.capsule_m || f >= p.puncture_force_n) {
    broken_ = true;  // the capsule gives way: the post-puncture model from this tick on
    phase_ = NeedlePhase::kPunctured;
    max_depth_m_ = d;
    return post_puncture_force(p, d, v, held_n_);
  }
  phase_ = NeedlePhase::kPrePuncture;
  return f;
}

// The axial force once through the capsule: the phase follows the axial velocity (inserting,
// withdrawing, or stopped and relaxing), and each phase has its law.
double NeedleTool::inserted_force(const TissueNeedleParameters& p, double d, double v, double time_s) {
  const double still = std::max(1e-9, 0.5 * p.friction.velocity_band_m_per_s);
  NeedlePhase next = phase_;
  if (v >= still) {
    next = NeedlePhase::kPunctured;
  } else if (v <= -still) {
    next = NeedlePhase::kExtraction;
  } else if (phase_ == NeedlePhase::kPunctured) {
    next = NeedlePhase::kRelaxation;  // stopped while inserting; a stop while withdrawing sticks
  }
  if (next == NeedlePhase::kRelaxation && phase_ != NeedlePhase::kRelaxation) {
    relax_start_s_ = time_s;
    relax_force_n_ = held_n_;
  }
  phase_ = next;
  switch (phase_) {
    case NeedlePhase::kRelaxation:
      return relaxation_force(p, relax_force_n_, time_s - relax_start_s_);
    case NeedlePhase::kExtraction:
      return extraction_force(p, d, v, held_n_);
    default: {
      // New tissue is cut beyond the deepest point so far; before it the path exists.
      const double f = d >= max_depth_m_ ? post_puncture_force(p, d, v, held_n_) : reinsertion_force(p, d, v, held_n_);
      max_depth_m_ = std::max(max_depth_m_, d);
      return f;
    }
  }
}

// Writes the tick's state for the rest of the loop and returns the force on the hand.
Vec3 NeedleTool::publish(const haptics::ToolTickInput& in, haptics::ToolState& st, double depth_m, double v_m, double f,
                         const Vec3& force) const {
  st.phase = static_cast<std::uint8_t>(phase_);
  st.touched = engaged_;
  st.broken = broken_;
  st.body = engaged_ ? body_ : -1;
  st.layer = engaged_ ? layer_ : -1;
  st.depth_m = depth_m;
  st.axial_force_n = f;
  st.axial_velocity_m_per_s = v_m;
  st.tip = in.position;
  st.entry = entry_;
  st.axis = axis_;
  st.normal = normal_;
  st.force = force;
  return force;
}

// ---- The reaction in the tissue

void NeedleTissueCoupling::add_tissue_forces(const haptics::ToolState& tool, const mechanics::MechanicalModel& model,
                                             const mechanics::MechanicalState& state, std::span<double> forces) {
  const Vec3 reaction = -tool.force;  // the tissue feels the opposite of what the hand feels
  const std::size_t nodes = model.node_count();
  if (nodes == 0 || !reaction.allFinite() || reaction.squaredNorm() == 0.0 || !tool.axis.allFinite()) return;
  const double radius = tool_ ? tool_->spread_radius(static_cast<std::size_t>(std::max(0, tool.body))) : 0.01;
  const double depth = std::max(0.0, tool.depth_m) / (tool_ ? tool_->metres_per_unit() : 1.0);  // world units
  const auto phase = static_cast<NeedlePhase>(tool.phase);
  if (phase == NeedlePhase::kTouching || phase == NeedlePhase::kPrePuncture || depth <= 0.0) {
    // The capsule is intact: pushed ahead of the tip.
    spread(tool.entry + tool.axis * depth, reaction, radius, state, nodes, forces);
    return;
  }
  // Through the capsule: along the shaft, entry to tip, in equal shares.
  const int points = std::clamp(static_cast<int>(std::ceil(depth / radius)), 1, 16);
  for (int k = 0; k < points; ++k) {
    const Vec3 at = tool.entry + tool.axis * (depth * (k + 1) / points);
    spread(at, reaction / points, radius, state, nodes, forces);
  }
}

void NeedleTissueCoupling::spread(const Vec3& point, const Vec3& force, double radius,
                                  const mechanics::MechanicalState& state, std::size_t nodes,
                                  std::span<double> forces) {
  near_.clear();
  double reach2 = radius * radius;
  for (std::size_t i = 0; i < nodes; ++i) {
    const double d2 = (state.position(static_cast<std::int32_t>(i)) - point).squaredNorm();
    if (d2 < reach2) near_.emplace_back(d2, static_cast<std::int32_t>(i));
  }
  constexpr std::size_t kAtLeast = 4;
  if (near_.size() < kAtLeast) {
    // A coarse mesh or a small radius: the four nearest nodes, reach widened to include them.
    near_.clear();
    for (std::size_t i = 0; i < nodes; ++i) {
      near_.emplace_back((state.position(static_cast<std::int32_t>(i)) - point).squaredNorm(),
                         static_cast<std::int32_t>(i));
    }
    const std::size_t keep = std::min(kAtLeast, near_.size());
    std::nth_element(near_.begin(), near_.begin() + static_cast<std::ptrdiff_t>(keep - 1), near_.end());
    near_.resize(keep);
    double farthest = 0.0;
    for (const auto& [d2, i] : near_) farthest = std::max(farthest, d2);
    reach2 = 2.0 * farthest + 1e-30;
  }
  // Wendland-like weights (1 − r²/ρ²)²: smooth, largest at the point, zero at the reach.
  double total = 0.0;
  for (auto& [d2, i] : near_) {
    const double w = (1.0 - d2 / reach2) * (1.0 - d2 / reach2);
    d2 = w;  // reuse the slot for the weight
    total += w;
  }
  for (const auto& [w, i] : near_) {
    const double share = total > 0.0 ? w / total : 1.0 / static_cast<double>(near_.size());
    for (int c = 0; c < 3; ++c) forces[3 * static_cast<std::size_t>(i) + c] += share * force[c];
  }
}

}  // namespace hof::procedures
