#include "hof/coupling/detail/body_contact_constraints.h"

#include <algorithm>
#include <array>
#include <cmath>
#include <limits>

#include "hof/coupling/detail/body_contact_detection.h"
#include "hof/coupling/detail/world_step.h"
#include "hof/mechanics/point_compliance.h"
#include "hof/mechanics/step.h"

namespace hof::coupling::detail {

namespace {

// The nodes a contact acts on, room kept per contact at the start (the lists grow past it
// only when a pass has more).
constexpr std::size_t kInitialEntriesPerContact = 8;

// Rows n, t1, t2: an orthonormal frame whose tangents depend only on n (deterministic). The
// tangents are built from the axis least aligned with n, so they never degenerate.
Mat3 contact_frame(const Vec3& n) {
  const Vec3 axis = std::abs(n.x()) < 0.57 ? Vec3::UnitX() : (std::abs(n.y()) < 0.57 ? Vec3::UnitY() : Vec3::UnitZ());
  const Vec3 t1 = n.cross(axis).normalized();
  const Vec3 t2 = n.cross(t1);
  Mat3 frame;
  frame.row(0) = n.transpose();
  frame.row(1) = t1.transpose();
  frame.row(2) = t2.transpose();
  return frame;
}

// The force of one contact given the violation b it would have without its own force
// (b = δ − W λ) and its Delassus block W: the solution of the local problem with Signorini's
// condition on the normal and Coulomb's disk on the tangents (Duriez et al. 2006 §4.2: the
// stick solution when it lies inside the friction cone, else a slip on the cone's rim in the
// stick solution's tangential direction; the normal force then solves the normal row with
// that tangential force).
Vec3 local_solve(const Mat3& w, const Mat3& w_inverse, const Vec3& b, double mu) {
  Vec3 lambda = -(w_inverse * b);
  if (!(lambda[0] > 0.0)) return Vec3::Zero();  // separating: no force
  const double tangential = std::hypot(lambda[1], lambda[2]);
  if (tangential <= mu * lambda[0]) return lambda;  // sticking
  const double d1 = lambda[1] / tangential, d2 = lambda[2] / tangential;
  // Normal row with λt = μ λn d: W_nn λn + μ λn (W_nt1 d1 + W_nt2 d2) + b_n = 0.
  const double denominator = w(0, 0) + mu * (w(0, 1) * d1 + w(0, 2) * d2);
  double normal = denominator > 0.0 ? -b[0] / denominator : -1.0;
  if (!(normal > 0.0)) normal = std::max(0.0, -b[0] / w(0, 0));
  return {normal, mu * normal * d1, mu * normal * d2};
}

}  // namespace

void BodyContactConstraints::init(World& w) {
  const std::size_t n = w.bodies.size();
  bodies_.assign(n, BodyScratch{});
  for (std::size_t i = 0; i < n; ++i) {
    const BodyRuntime& r = w.bodies[i];
    if (!r.body.deformable() || !r.body.collision.enabled) continue;
    const std::size_t nodes = r.body.model->node_count();
    bodies_[i].compliance.assign(nodes, Mat3::Zero());
    bodies_[i].displacement.assign(nodes, Vec3::Zero());
    bodies_[i].stamp.assign(nodes, -1);
    bodies_[i].x0 = r.state.x;
    bodies_[i].v0 = r.state.v;
    bodies_[i].f0 = r.state.external_force;
    bodies_[i].extra = Eigen::VectorXd::Zero(r.state.x.size());
    bodies_[i].x_free = r.state.x;
  }
  due_.assign(n, 0);
  force_sum_.assign(n, Vec3::Zero());
  contact_count_.assign(n, 0);
  detected_.reserve(kInitialContactCapacity);
  rows_.reserve(kInitialContactCapacity);
  entries_.reserve(kInitialContactCapacity * kInitialEntriesPerContact);
  touched_.reserve(kInitialContactCapacity * kInitialEntriesPerContact);
}

void BodyContactConstraints::touch(World& w, std::size_t body, std::int32_t node) {
  BodyScratch& s = bodies_[body];
  const auto i = static_cast<std::size_t>(node);
  if (s.stamp[i] == pass_) return;
  s.stamp[i] = pass_;
  s.displacement[i].setZero();
  const BodyRuntime& r = w.bodies[body];
  const mechanics::MechanicalModel& model = *r.body.model;
  const double h = model.dt_s;
  std::array<bool, 3> held{};
  for (std::size_t q = 0; q < 3; ++q) held[q] = model.fixed_dof_mask[3 * i + q] != 0;
  Mat3 a;
  Mat3 c;
  if (w.config.contacts.constraint_compliance == ConstraintCompliance::kSystemDiagonal &&
      mechanics::system_diagonal_block(model, r.state, node, a)) {
    // Implicit Euler: the step's response at this node alone to a constant force F over the
    // step is Δv = h A_ii⁻¹ F, Δx = h Δv (SOFA's UncoupledConstraintCorrection, with the
    // node's block of the system the step solved for its compliance). Held dofs: the block
    // restricted to the free ones.
    for (std::size_t q = 0; q < 3; ++q) {
      if (!held[q]) continue;
      a.row(static_cast<Eigen::Index>(q)).setZero();
      a.col(static_cast<Eigen::Index>(q)).setZero();
      a(static_cast<Eigen::Index>(q), static_cast<Eigen::Index>(q)) = 1.0;
    }
    c = h * h * a.inverse();
  } else {
    // Explicit Euler (and the others): a force F over the step moves the node by h² F / m.
    const double m = model.node_mass_kg[i];
    c = m > 0.0 ? Mat3((h * h / m) * Mat3::Identity()) : Mat3::Zero();
  }
  for (std::size_t q = 0; q < 3; ++q) {
    if (!held[q]) continue;
    c.row(static_cast<Eigen::Index>(q)).setZero();
    c.col(static_cast<Eigen::Index>(q)).setZero();
  }
  if (!c.allFinite()) c.setZero();
  s.compliance[i] = c;
  touched_.push_back({static_cast<std::int32_t>(body), node, 0.0, true});
}

void BodyContactConstraints::save_start(World& w, std::span<const char> due) {
  for (std::size_t b = 0; b < bodies_.size() && b < due.size(); ++b) {
    BodyScratch& s = bodies_[b];
    if (!due[b] || s.compliance.empty()) continue;
    const mechanics::MechanicalState& state = w.bodies[b].state;
    s.x0 = state.x;  // same sizes every step: no allocation
    s.v0 = state.v;
    s.f0 = state.external_force;
    s.steps0 = state.steps;
    s.time0 = state.time_s;
  }
}

void BodyContactConstraints::build_rows(World& w, BodyContactDetection& detection) {
  const ContactSettings& settings = w.config.contacts;
  // Detection on the positions the step left: the due bodies' surfaces follow their nodes.
  detection.for_each_body([&](std::size_t b) {
    BodyRuntime& r = w.bodies[b];
    if (r.body.deformable() && due_[b])
      r.body.mapping.apply({r.state.x.data(), static_cast<std::size_t>(r.state.x.size())}, r.surface_positions);
  });
  detection.detect(w, std::numeric_limits<double>::infinity(), detected_);

  // The rows, the nodes they act on, their compliances and Delassus blocks.
  ++pass_;
  rows_.clear();
  entries_.clear();
  touched_.clear();
  for (std::size_t k = 0; k < detected_.size(); ++k) {
    const collision::BodyContact& contact = detected_[k];
    // Edge–edge contacts are left to the vertex–triangle ones. Their normal is the direction
    // between the two edges' closest points, which for an edge lying in a flat part of a
    // surface (a floor's diagonal) can point anywhere in that plane: a penalty spring along it
    // pushes a little, a hard constraint throws the body sideways.
    if (contact.a.kind == collision::PrimitiveKind::kEdge && contact.b.kind == collision::PrimitiveKind::kEdge)
      continue;
    Row row;
    row.frame = contact_frame(contact.normal);
    row.first = static_cast<std::uint32_t>(entries_.size());
    row.mu = settings.friction;
    Vec3 slip = Vec3::Zero();  // relative displacement over the step: h·v at the end of it
    bool any = false;
    for (const auto& [side, sign] : {std::pair{&contact.a, 1.0}, std::pair{&contact.b, -1.0}}) {
      const auto b = static_cast<std::size_t>(side->body);
      const BodyRuntime& r = w.bodies[b];
      // A rigid body, and a body that does not step this world step, do not move now.
      if (!r.body.deformable() || !due_[b]) continue;
      std::array<std::int32_t, SurfaceMapping::kMaxPointWeights> nodes{};
      std::array<double, SurfaceMapping::kMaxPointWeights> weights{};
      const std::size_t count = detection.point_weights(w, *side, nodes, weights);
      const bool correctable = r.body.collision.simulated;  // SOFA simulated="0": moves, does not react
      const double h = r.body.model->dt_s;
      for (std::size_t e = 0; e < count; ++e) {
        if (weights[e] == 0.0) continue;
        entries_.push_back({static_cast<std::int32_t>(b), nodes[e], sign * weights[e], correctable});
        slip += sign * weights[e] * h * r.state.velocity(nodes[e]);
        if (correctable) {
          touch(w, b, nodes[e]);
          any = true;
        }
      }
    }
    row.count = static_cast<std::uint32_t>(entries_.size()) - row.first;
    if (!any) {  // nothing this contact could move
      entries_.resize(row.first);
      continue;
    }
    // W's block: Σ over pairs of entries on the same node of s_e s_f C_node (Duriez et al.
    // 2006: W = Σ_bodies H C Hᵀ), in the contact's frame.
    Mat3 m = Mat3::Zero();
    for (std::uint32_t e = row.first; e < row.first + row.count; ++e) {
      const Entry& x = entries_[e];
      if (!x.correctable) continue;
      for (std::uint32_t f = row.first; f < row.first + row.count; ++f) {
        const Entry& y = entries_[f];
        if (y.correctable && y.body == x.body && y.node == x.node)
          m += x.weight * y.weight *
               bodies_[static_cast<std::size_t>(x.body)].compliance[static_cast<std::size_t>(x.node)];
      }
    }
    row.delassus = row.frame * m * row.frame.transpose();
    if (!(row.delassus(0, 0) > 0.0)) {  // held along the normal: nothing to solve
      entries_.resize(row.first);
      continue;
    }
    // A tangent the nodes cannot move along (held dofs) leaves W singular: a vanishing
    // regularisation keeps its inverse finite and the force along it zero.
    row.delassus_inverse = (row.delassus + 1e-12 * row.delassus.trace() * Mat3::Identity()).inverse();
    const Vec3 tangential = row.frame * slip;
    row.gap = contact.distance - settings.contact_distance_m;
    row.free = Vec3(row.gap, tangential[1], tangential[2]);
    row.lambda.setZero();
    rows_.push_back(row);
    // The contact itself, for the report: detected_ is compacted in place, detected_[r] is
    // rows_[r]'s contact (r ≤ k: only contacts already read are overwritten).
    detected_[rows_.size() - 1] = contact;
  }
}

void BodyContactConstraints::sweep(const ContactSettings& settings) {
  // Projected Gauss–Seidel from the rows' current forces (their displacements start at zero:
  // `free` holds the violation with those forces already acting).
  for (const Entry& t : touched_)
    bodies_[static_cast<std::size_t>(t.body)].displacement[static_cast<std::size_t>(t.node)].setZero();
  last_sweeps_ = 0;
  last_change_m_ = 0.0;
  const int max_sweeps = std::max(1, settings.constraint_max_iterations);
  for (int sweep = 0; sweep < max_sweeps && !rows_.empty(); ++sweep) {
    double change = 0.0;
    for (Row& row : rows_) {
      Vec3 moved = Vec3::Zero();  // Σ s_e Δx_e: the relative correction of the two points
      for (std::uint32_t e = row.first; e < row.first + row.count; ++e) {
        const Entry& x = entries_[e];
        if (x.correctable)
          moved += x.weight * bodies_[static_cast<std::size_t>(x.body)].displacement[static_cast<std::size_t>(x.node)];
      }
      const Vec3 violation = row.free + row.frame * moved;
      const Vec3 without = violation - row.delassus * row.lambda;
      const Vec3 lambda = local_solve(row.delassus, row.delassus_inverse, without, row.mu);
      const Vec3 step = lambda - row.lambda;
      if (step.isZero(0.0)) continue;
      row.lambda = lambda;
      const Vec3 force = row.frame.transpose() * step;  // on side a, world frame
      for (std::uint32_t e = row.first; e < row.first + row.count; ++e) {
        const Entry& x = entries_[e];
        if (!x.correctable) continue;
        BodyScratch& s = bodies_[static_cast<std::size_t>(x.body)];
        s.displacement[static_cast<std::size_t>(x.node)] +=
            s.compliance[static_cast<std::size_t>(x.node)] * (x.weight * force);
      }
      change = std::max(change, (row.delassus * step).cwiseAbs().maxCoeff());
    }
    last_sweeps_ = sweep + 1;
    last_change_m_ = change;
    if (change <= settings.constraint_tolerance_m) break;
  }
}

void BodyContactConstraints::apply(World& w, BodyContactDetection& detection, std::span<const char> due,
                                   SessionReport& report, std::vector<collision::BodyContact>& pushing) {
  const ContactSettings& settings = w.config.contacts;
  std::fill(due_.begin(), due_.end(), 0);
  std::copy(due.begin(), due.begin() + static_cast<std::ptrdiff_t>(std::min(due.size(), due_.size())), due_.begin());
  std::fill(force_sum_.begin(), force_sum_.end(), Vec3::Zero());
  detection.begin_pass(w);
  build_rows(w, detection);
  for (std::size_t b = 0; b < bodies_.size(); ++b) {
    if (due_[b] && !bodies_[b].compliance.empty()) bodies_[b].x_free = w.bodies[b].state.x;
  }
  const int passes = std::max(1, settings.constraint_force_passes);
  for (int pass = 0;; ++pass) {
    sweep(settings);
    if (pass + 1 >= passes || rows_.empty()) break;
    // The forces into the implicit solve: each due body that was pushed steps again from
    // where it started, with Hᵀλ added to its load, so that its whole volume answers the
    // contact within this step (LinearSolverConstraintCorrection's coupled compliance
    // h² A⁻¹, applied by the step itself instead of being formed). The rows stay those
    // detected on the free motion; their violations follow the nodes.
    for (BodyScratch& s : bodies_) {
      if (!s.compliance.empty()) s.extra.setZero();
    }
    bool pushed = false;
    for (const Row& row : rows_) {
      if (!(row.lambda[0] > 0.0)) continue;
      pushed = true;
      const Vec3 force = row.frame.transpose() * row.lambda;
      for (std::uint32_t e = row.first; e < row.first + row.count; ++e) {
        const Entry& x = entries_[e];
        if (x.correctable)
          bodies_[static_cast<std::size_t>(x.body)].extra.segment<3>(3 * static_cast<Eigen::Index>(x.node)) +=
              x.weight * force;
      }
    }
    if (!pushed) break;
    for (std::size_t b = 0; b < bodies_.size(); ++b) {
      BodyScratch& s = bodies_[b];
      if (!due_[b] || s.compliance.empty()) continue;
      BodyRuntime& r = w.bodies[b];
      r.state.x = s.x0;
      r.state.v = s.v0;
      r.state.steps = s.steps0;
      r.state.time_s = s.time0;
      r.state.external_force = s.f0 + s.extra;
      // A step that fails leaves the divergence in the state; the world's next step reports it.
      if (!mechanics::step(*r.body.model, r.state)) return;
    }
    for (Row& row : rows_) {
      Vec3 moved = Vec3::Zero();  // the points' relative motion since the free positions
      Vec3 slip = Vec3::Zero();
      for (std::uint32_t e = row.first; e < row.first + row.count; ++e) {
        const Entry& x = entries_[e];
        const BodyRuntime& r = w.bodies[static_cast<std::size_t>(x.body)];
        const BodyScratch& s = bodies_[static_cast<std::size_t>(x.body)];
        const auto at = 3 * static_cast<Eigen::Index>(x.node);
        if (!s.x_free.size()) continue;
        moved += x.weight * (r.state.x.segment<3>(at) - s.x_free.segment<3>(at));
        slip += x.weight * r.body.model->dt_s * r.state.v.segment<3>(at);
      }
      const Vec3 local_moved = row.frame * moved, local_slip = row.frame * slip;
      row.free = Vec3(row.gap + local_moved[0], local_slip[1], local_slip[2]);
    }
  }

  // The last pass's correction: positions by Δx, velocities by Δx/h (x_{n+1} = x_n + h v_{n+1}).
  for (const Entry& t : touched_) {
    BodyRuntime& r = w.bodies[static_cast<std::size_t>(t.body)];
    const Vec3& dx = bodies_[static_cast<std::size_t>(t.body)].displacement[static_cast<std::size_t>(t.node)];
    const auto at = 3 * static_cast<Eigen::Index>(t.node);
    r.state.x.segment<3>(at) += dx;
    r.state.v.segment<3>(at) += dx / r.body.model->dt_s;
  }
  detection.for_each_body([&](std::size_t b) {
    BodyRuntime& r = w.bodies[b];
    if (r.body.deformable() && due_[b])
      r.body.mapping.apply({r.state.x.data(), static_cast<std::size_t>(r.state.x.size())}, r.surface_positions);
  });
  detection.end_pass(w);

  // The report: the contacts that pushed, +Hᵀλ on side a and −Hᵀλ on side b, N.
  std::fill(contact_count_.begin(), contact_count_.end(), 0);
  pushing.clear();
  for (std::size_t k = 0; k < rows_.size(); ++k) {
    if (!(rows_[k].lambda[0] > 0.0)) continue;
    const collision::BodyContact& contact = detected_[k];
    const Vec3 force = rows_[k].frame.transpose() * rows_[k].lambda;
    force_sum_[static_cast<std::size_t>(contact.a.body)] += force;
    force_sum_[static_cast<std::size_t>(contact.b.body)] -= force;
    ++contact_count_[static_cast<std::size_t>(contact.a.body)];
    ++contact_count_[static_cast<std::size_t>(contact.b.body)];
    pushing.push_back(contact);
  }
  detection.report_pass(w, contact_count_, force_sum_, pushing.size(), report);
}

}  // namespace hof::coupling::detail
