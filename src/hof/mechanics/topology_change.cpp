#include "hof/mechanics/topology_change.h"
#include "hof/mechanics/detail/solver_workspace.h"

#include <fmt/format.h>

#include <algorithm>
#include <cmath>
#include <utility>

#include "hof/mechanics/detail/tetrahedron_fem_force_field.h"
#include "hof/mechanics/detail/workspace_setup.h"
#include "hof/mesh/tet_geometry.h"

namespace hof::mechanics {

namespace {

bool same_pattern(const BlockSparseMatrix& a, const BlockSparseMatrix& b) {
  return a.row_start() == b.row_start() && a.columns() == b.columns();
}

// The physical state of `next` from `before`: surviving nodes keep their motion and their
// coupling input, added ones start at rest where the new config puts them.
MechanicalState map_physical_state(const MechanicalModel& next, const MechanicalState& before,
                                   const std::vector<std::int32_t>& old_node) {
  MechanicalState s;
  const Eigen::Index dofs = 3 * static_cast<Eigen::Index>(next.node_count());
  s.x.resize(dofs);
  s.v = Eigen::VectorXd::Zero(dofs);
  s.f = Eigen::VectorXd::Zero(dofs);
  s.external_force = Eigen::VectorXd::Zero(dofs);
  for (std::size_t i = 0; i < next.node_count(); ++i) {
    const Eigen::Index k = 3 * static_cast<Eigen::Index>(i);
    if (const std::int32_t o = old_node[i]; o >= 0) {
      const Eigen::Index ko = 3 * static_cast<Eigen::Index>(o);
      s.x.segment<3>(k) = before.x.segment<3>(ko);
      s.v.segment<3>(k) = before.v.segment<3>(ko);
      s.external_force.segment<3>(k) = before.external_force.segment<3>(ko);
    } else {
      s.x.segment<3>(k) = next.rest_positions[i];
    }
  }
  s.time_s = before.time_s;
  s.steps = before.steps;
  s.divergence = before.divergence;
  // Per-field element data (rotations, tangents) is refreshed by the next force evaluation;
  // only the polar decomposition's warm start is lost, which costs an iteration, not accuracy.
  for (const auto& field : next.force_fields) s.field_states.push_back(field->make_state());
  return s;
}

// Whether the incremental path knows the body: tetrahedra only, every force field a
// tetrahedral FEM over all of them (one field per configured one: no per-element Poisson
// ratio, which splits a field), lumped mass without a rescaled total, or uniform mass.
bool incremental_path_applies(const MechanicalModel& model, const TopologyChange& change) {
  const ModelConfig& c = change.config;
  if (change.old_tet.size() != c.tets.size() || c.tets.empty() || !c.hexahedra.empty() || !model.hexahedra.empty()) {
    return false;
  }
  if (c.mass.kind == MassKind::kDiagonal && c.mass.diagonal_total_mass_kg) return false;
  if (c.force_fields.size() != model.force_fields.size()) return false;
  for (std::size_t k = 0; k < c.force_fields.size(); ++k) {
    const ForceFieldConfig& f = c.force_fields[k];
    if (!f.tetrahedron_fem || !f.tetrahedron_fem->element_poisson_ratio.empty()) return false;
    const auto* field = dynamic_cast<const TetrahedronFemForceField*>(model.force_fields[k].get());
    if (field == nullptr || field->element_count() != model.tets.size()) return false;
  }
  return true;
}

// The change's element map, checked: each old tetrahedron kept at most once, with the same
// corners renumbered. Also the new ids of the old nodes (−1: removed).
Expected<std::vector<std::int32_t>> check_element_map(const MechanicalModel& model, const TopologyChange& change) {
  std::vector<std::int32_t> new_of_old(model.node_count(), -1);
  for (std::size_t i = 0; i < change.old_node.size(); ++i) {
    if (change.old_node[i] >= 0)
      new_of_old[static_cast<std::size_t>(change.old_node[i])] = static_cast<std::int32_t>(i);
  }
  std::vector<std::uint8_t> taken(model.tets.size(), 0);
  for (std::size_t t = 0; t < change.old_tet.size(); ++t) {
    const std::int32_t o = change.old_tet[t];
    if (o == -1) continue;
    if (o < -1 || o >= static_cast<std::int64_t>(model.tets.size()) || taken[static_cast<std::size_t>(o)]) {
      return make_error(ErrorCode::kInvalidArgument, fmt::format("model '{}': a topology change maps tetrahedron {} to "
                                                                 "tetrahedron {} of {} (out of range or twice)",
                                                                 model.name, t, o, model.tets.size()));
    }
    taken[static_cast<std::size_t>(o)] = 1;
    for (int corner = 0; corner < 4; ++corner) {
      if (new_of_old[static_cast<std::size_t>(model.tets[static_cast<std::size_t>(o)][corner])] !=
          change.config.tets[t][corner]) {
        return make_error(ErrorCode::kInvalidArgument,
                          fmt::format("model '{}': a topology change keeps tetrahedron {} as {} with other corners",
                                      model.name, o, t));
      }
    }
  }
  return new_of_old;
}

// Lumped masses after the change: a node no removed or added element touches keeps its mass;
// a touched one is summed anew over its elements, in element order as build_model sums (so
// the result is that of a full rebuild, bit for bit). Only the elements around touched nodes
// have their volume taken. Uniform mass: totalMass/N (or vertexMass) again.
Expected<std::vector<double>> incremental_masses(const MechanicalModel& model, const TopologyChange& change,
                                                 const std::vector<std::int32_t>& new_of_old, std::size_t& remassed) {
  const ModelConfig& c = change.config;
  const std::size_t n = c.positions.size();
  std::vector<double> mass(n, 0.0);
  if (c.mass.kind == MassKind::kUniform) {
    const double each = c.mass.vertex_mass_kg ? *c.mass.vertex_mass_kg : c.mass.total_mass_kg / static_cast<double>(n);
    if (!(each > 0.0) || !std::isfinite(each)) {
      return make_error(ErrorCode::kInvalidArgument,
                        fmt::format("UniformMass '{}': the node mass must be > 0 kg", c.mass.name));
    }
    std::fill(mass.begin(), mass.end(), each);
    return mass;
  }
  std::vector<std::uint8_t> touched(n, 0);
  std::vector<std::uint8_t> kept(model.tets.size(), 0);
  for (std::size_t t = 0; t < c.tets.size(); ++t) {
    if (change.old_tet[t] >= 0) {
      kept[static_cast<std::size_t>(change.old_tet[t])] = 1;
    } else {
      for (mesh::NodeIndex i : c.tets[t]) touched[static_cast<std::size_t>(i)] = 1;
    }
  }
  for (std::size_t o = 0; o < model.tets.size(); ++o) {
    if (kept[o]) continue;
    for (mesh::NodeIndex i : model.tets[o]) {
      if (const std::int32_t j = new_of_old[static_cast<std::size_t>(i)]; j >= 0)
        touched[static_cast<std::size_t>(j)] = 1;
    }
  }
  for (std::size_t i = 0; i < n; ++i) {
    if (change.old_node[i] < 0) touched[i] = 1;
    if (!touched[i]) mass[i] = model.node_mass_kg[static_cast<std::size_t>(change.old_node[i])];
  }
  const std::vector<double>& densities = c.mass.element_mass_density_kg_per_m3;
  if (!densities.empty() && densities.size() != c.tets.size()) {
    return make_error(ErrorCode::kInvalidArgument,
                      fmt::format("DiagonalMass '{}': massDensity has {} values for {} tetrahedra", c.mass.name,
                                  densities.size(), c.tets.size()));
  }
  for (std::size_t t = 0; t < c.tets.size(); ++t) {
    const mesh::Tet& tet = c.tets[t];
    if (!std::any_of(tet.begin(), tet.end(),
                     [&](mesh::NodeIndex i) { return touched[static_cast<std::size_t>(i)] != 0; }))
      continue;
    const double rho = densities.empty() || densities[t] == 0.0 ? c.mass.mass_density_kg_per_m3 : densities[t];
    const auto p = mesh::tet_corners(c.positions, tet);
    const double quarter = rho * std::abs(mesh::tet_signed_volume(p[0], p[1], p[2], p[3])) / 4.0;
    for (mesh::NodeIndex i : tet) {
      if (touched[static_cast<std::size_t>(i)]) mass[static_cast<std::size_t>(i)] += quarter;
    }
  }
  for (std::size_t i = 0; i < n; ++i) {
    remassed += touched[i];
    if (!(mass[i] > 0.0)) {
      return make_error(ErrorCode::kInvalidMesh,
                        fmt::format("DiagonalMass '{}': node {} belongs to no element after the change "
                                    "and gets no mass; remove it with its last element",
                                    c.mass.name, i));
    }
  }
  return mass;
}

// The supports after the change: a kept node keeps its fixed axes; an added node gets those
// of the config's constraints (fix_all, its index, or a box around its rest position).
void incremental_supports(const MechanicalModel& model, const TopologyChange& change, MechanicalModel& next) {
  const std::size_t n = change.config.positions.size();
  next.fixed_dof_mask.assign(3 * n, 0);
  for (std::size_t i = 0; i < n; ++i) {
    if (const std::int32_t o = change.old_node[i]; o >= 0) {
      for (std::size_t a = 0; a < 3; ++a)
        next.fixed_dof_mask[3 * i + a] = model.fixed_dof_mask[3 * static_cast<std::size_t>(o) + a];
      continue;
    }
    const Vec3& p = change.config.positions[i];
    for (const FixedConstraintConfig& fixed : change.config.fixed) {
      const bool named =
          std::find(fixed.indices.begin(), fixed.indices.end(), static_cast<std::int32_t>(i)) != fixed.indices.end();
      const bool boxed =
          fixed.box && (p.array() >= fixed.box->first.array()).all() && (p.array() <= fixed.box->second.array()).all();
      if (!(fixed.fix_all || named || boxed)) continue;
      for (std::size_t a = 0; a < 3; ++a) {
        if (fixed.directions[a]) next.fixed_dof_mask[3 * i + a] = 1;
      }
    }
  }
  for (std::size_t d = 0; d < 3 * n; ++d) {
    if (next.fixed_dof_mask[d]) next.fixed_dofs.push_back(static_cast<std::int32_t>(d));
  }
}

// The model after the change, rebuilding only what it touched (see the header).
Expected<MechanicalModel> incremental_model(const MechanicalModel& model, const TopologyChange& change,
                                            TopologyChangeReport& report) {
  auto new_of_old = check_element_map(model, change);
  if (!new_of_old) return std::unexpected(new_of_old.error());
  const ModelConfig& c = change.config;
  MechanicalModel next;
  next.name = model.name;
  next.rest_positions = c.positions;
  next.tets = c.tets;
  next.triangles = c.triangles;
  next.mass_name = model.mass_name;
  next.ode = model.ode;
  next.linear = model.linear;
  next.gravity_m_per_s2 = model.gravity_m_per_s2;
  next.dt_s = model.dt_s;
  next.max_speed_m_per_s = model.max_speed_m_per_s;
  next.threads = model.threads;
  next.needs_matrix = model.needs_matrix;
  auto masses = incremental_masses(model, change, *new_of_old, report.nodes_remassed);
  if (!masses) return std::unexpected(masses.error());
  next.node_mass_kg = std::move(*masses);
  for (std::size_t k = 0; k < model.force_fields.size(); ++k) {
    const auto& field = static_cast<const TetrahedronFemForceField&>(*model.force_fields[k]);
    auto remade = field.remade(c.positions, c.tets, change.old_tet, *new_of_old, *c.force_fields[k].tetrahedron_fem,
                               report.elements_rebuilt);
    if (!remade) return std::unexpected(remade.error());
    next.force_fields.push_back(std::move(*remade));
  }
  incremental_supports(model, change, next);
  // The pattern is formed again from the fields' coupled pairs (node ids only: no element
  // data is read) and the fields bound to it.
  std::vector<std::pair<std::int32_t, std::int32_t>> pairs;
  for (const auto& f : next.force_fields) f->collect_couplings(pairs);
  next.pattern = BlockSparseMatrix::from_pairs(static_cast<std::int32_t>(next.node_count()), pairs);
  for (auto& f : next.force_fields) f->bind(next.pattern);
  report.incremental = true;
  return next;
}

}  // namespace

std::vector<std::int32_t> surviving_node_map(const std::vector<bool>& kept) {
  std::vector<std::int32_t> old_node;
  for (std::size_t i = 0; i < kept.size(); ++i) {
    if (kept[i]) old_node.push_back(static_cast<std::int32_t>(i));
  }
  return old_node;
}

namespace {

// The entries of a per-element list that follow the kept elements, the added ones at 0 (the
// default); a list of another length (empty: the default everywhere) is left as it is.
template <class T>
void follow_elements(std::vector<T>& list, std::size_t old_count, const std::vector<std::int32_t>& old_tet) {
  if (list.size() != old_count) return;
  std::vector<T> next;
  next.reserve(old_tet.size());
  for (const std::int32_t o : old_tet) next.push_back(o >= 0 ? list[static_cast<std::size_t>(o)] : T{});
  list = std::move(next);
}

// Node indices renumbered, those of removed nodes dropped.
void renumber(std::vector<std::int32_t>& indices, const std::vector<std::int32_t>& new_of_old) {
  std::vector<std::int32_t> next;
  for (const std::int32_t i : indices) {
    if (i >= 0 && static_cast<std::size_t>(i) < new_of_old.size() && new_of_old[static_cast<std::size_t>(i)] >= 0) {
      next.push_back(new_of_old[static_cast<std::size_t>(i)]);
    }
  }
  indices = std::move(next);
}

}  // namespace

TopologyChange tetrahedra_change(const ModelConfig& before, const std::vector<std::int32_t>& removed,
                                 const std::vector<Vec3>& added_nodes, const std::vector<mesh::Tet>& added_tets) {
  const std::size_t old_n = before.positions.size();
  std::vector<std::uint8_t> gone(before.tets.size(), 0);
  for (const std::int32_t t : removed) {
    if (t >= 0 && static_cast<std::size_t>(t) < gone.size()) gone[static_cast<std::size_t>(t)] = 1;
  }
  // Nodes survive while a kept or added element uses them.
  std::vector<bool> used(old_n + added_nodes.size(), false);
  TopologyChange change;
  for (std::size_t t = 0; t < before.tets.size(); ++t) {
    if (gone[t]) continue;
    for (const mesh::NodeIndex i : before.tets[t]) used[static_cast<std::size_t>(i)] = true;
    change.old_tet.push_back(static_cast<std::int32_t>(t));
  }
  for (const mesh::Tet& t : added_tets) {
    for (const mesh::NodeIndex i : t) {
      if (i >= 0 && static_cast<std::size_t>(i) < used.size()) used[static_cast<std::size_t>(i)] = true;
    }
    change.old_tet.push_back(-1);
  }
  std::vector<std::int32_t> new_of_old(used.size(), -1);
  ModelConfig& c = change.config;
  c = before;
  c.positions.clear();
  for (std::size_t i = 0; i < used.size(); ++i) {
    if (!used[i]) continue;
    new_of_old[i] = static_cast<std::int32_t>(c.positions.size());
    change.old_node.push_back(i < old_n ? static_cast<std::int32_t>(i) : -1);
    c.positions.push_back(i < old_n ? before.positions[i] : added_nodes[i - old_n]);
  }
  c.tets.clear();
  for (const std::int32_t o : change.old_tet) {
    if (o >= 0) c.tets.push_back(before.tets[static_cast<std::size_t>(o)]);
  }
  c.tets.insert(c.tets.end(), added_tets.begin(), added_tets.end());
  for (mesh::Tet& t : c.tets) {
    for (mesh::NodeIndex& i : t) i = new_of_old[static_cast<std::size_t>(i)];
  }
  // Surface triangles go with their nodes; the faces a cut opens are the caller's to add.
  c.triangles.clear();
  for (mesh::Tri t : before.triangles) {
    if (std::all_of(t.begin(), t.end(),
                    [&](mesh::NodeIndex i) { return new_of_old[static_cast<std::size_t>(i)] >= 0; })) {
      for (mesh::NodeIndex& i : t) i = new_of_old[static_cast<std::size_t>(i)];
      c.triangles.push_back(t);
    }
  }
  const std::size_t old_tets = before.tets.size();
  follow_elements(c.element_regions, old_tets, change.old_tet);
  follow_elements(c.mass.element_mass_density_kg_per_m3, old_tets, change.old_tet);
  for (ForceFieldConfig& f : c.force_fields) {
    if (f.tetrahedron_fem) {
      follow_elements(f.tetrahedron_fem->element_young_modulus_pa, old_tets, change.old_tet);
      follow_elements(f.tetrahedron_fem->element_poisson_ratio, old_tets, change.old_tet);
    }
    if (f.neo_hookean) {
      follow_elements(f.neo_hookean->element_young_modulus_pa, old_tets, change.old_tet);
      follow_elements(f.neo_hookean->element_poisson_ratio, old_tets, change.old_tet);
    }
    if (f.constant_force) {
      // One force per index: a removed node's goes with it.
      ConstantForceConfig& constant = *f.constant_force;
      if (constant.forces.size() == constant.indices.size() && constant.indices.size() > 1) {
        std::vector<Vec3> forces;
        for (std::size_t k = 0; k < constant.indices.size(); ++k) {
          const std::int32_t i = constant.indices[k];
          if (i >= 0 && static_cast<std::size_t>(i) < new_of_old.size() &&
              new_of_old[static_cast<std::size_t>(i)] >= 0) {
            forces.push_back(constant.forces[k]);
          }
        }
        constant.forces = std::move(forces);
      }
      renumber(constant.indices, new_of_old);
    }
  }
  for (FixedConstraintConfig& fixed : c.fixed) renumber(fixed.indices, new_of_old);
  return change;
}

Expected<TopologyChangeReport> apply_topology_change(MechanicalModel& model, MechanicalState& state,
                                                     const TopologyChange& change) {
  const std::size_t old_n = model.node_count();
  const std::size_t new_n = change.config.positions.size();
  if (change.old_node.size() != new_n) {
    return make_error(ErrorCode::kInvalidArgument,
                      fmt::format("model '{}': a topology change maps {} nodes but the new mesh has {}", model.name,
                                  change.old_node.size(), new_n));
  }
  TopologyChangeReport report;
  std::vector<std::uint8_t> taken(old_n, 0);
  bool identity = new_n == old_n;
  for (std::size_t i = 0; i < new_n; ++i) {
    const std::int32_t o = change.old_node[i];
    if (o < -1 || o >= static_cast<std::int64_t>(old_n)) {
      return make_error(
          ErrorCode::kInvalidArgument,
          fmt::format("model '{}': a topology change maps node {} to node {} of {}", model.name, i, o, old_n));
    }
    if (o == -1) {
      ++report.added_nodes;
      identity = false;
      continue;
    }
    if (taken[static_cast<std::size_t>(o)]) {
      return make_error(ErrorCode::kInvalidArgument,
                        fmt::format("model '{}': a topology change maps node {} twice", model.name, o));
    }
    taken[static_cast<std::size_t>(o)] = 1;
    ++report.surviving_nodes;
    identity = identity && o == static_cast<std::int32_t>(i);
  }
  report.removed_nodes = old_n - report.surviving_nodes;

  // Incremental when the change says where its elements were and the body is one that path
  // knows; else the force fields' element data, the lumped masses, the supports and the
  // pattern are those of the new mesh built whole (build_model: each a pass over its elements).
  auto built =
      incremental_path_applies(model, change) ? incremental_model(model, change, report) : build_model(change.config);
  if (!built) return std::unexpected(built.error());
  MechanicalModel& next = *built;
  if (!report.incremental) {
    report.elements_rebuilt =
        change.config.tets.size() + change.config.hexahedra.size() + change.config.triangles.size();
  }

  MechanicalState mapped = map_physical_state(next, state, change.old_node);
  // The solver's workspace depends on the nodes' numbering and the matrix pattern only: when
  // neither changed (a change of elements that couples the same nodes) the symbolic
  // factorisation, the CG's thread plan and the coarse space's aggregates are kept; only what
  // was formed from the old values is marked stale.
  report.pattern_changed = !(identity && next.needs_matrix == model.needs_matrix &&
                             next.linear.kind == model.linear.kind && same_pattern(next.pattern, model.pattern));
  if (report.pattern_changed) {
    mapped.work = std::make_unique<detail::SolverWorkspace>();
    mapped.work->arena = std::move(state.work->arena);  // the thread setting stays the body's
    detail::size_workspace(next, mapped);
  } else {
    mapped.work = std::move(state.work);
    mapped.work->system_assembled_step = -1;
    mapped.work->coarse.built_step = -1;
  }
  model = std::move(next);
  state = std::move(mapped);
  return report;
}

}  // namespace hof::mechanics
