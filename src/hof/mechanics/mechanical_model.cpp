#include "hof/mechanics/mechanical_model.h"
#include "hof/mechanics/detail/solver_workspace.h"

#include <fmt/format.h>

#include <algorithm>
#include <cmath>
#include <numeric>

#include "hof/mechanics/detail/constant_force_field.h"
#include "hof/mechanics/detail/hexahedron_fem_force_field.h"
#include "hof/mechanics/detail/linear_solve.h"
#include "hof/mechanics/detail/mesh_spring_force_field.h"
#include "hof/mechanics/detail/neo_hookean_force_field.h"
#include "hof/mechanics/detail/tetrahedron_fem_force_field.h"
#include "hof/mechanics/detail/triangle_fem_force_field.h"
#include "hof/mechanics/detail/workspace_setup.h"
#include "hof/mechanics/mechanical_state.h"
#include "hof/mesh/hex_grid.h"
#include "hof/mesh/tet_geometry.h"

namespace hof::mechanics {

namespace {

const char* mass_type(MassKind kind) { return kind == MassKind::kUniform ? "UniformMass" : "DiagonalMass"; }

Expected<std::vector<double>> build_masses(const ModelConfig& c) {
  const std::size_t n = c.positions.size();
  const std::string who = fmt::format("{} '{}'", mass_type(c.mass.kind), c.mass.name);
  std::vector<double> mass(n, 0.0);
  if (c.mass.kind == MassKind::kUniform) {
    if (c.mass.vertex_mass_kg) {
      if (!(*c.mass.vertex_mass_kg > 0.0)) {
        return make_error(ErrorCode::kInvalidArgument,
                          fmt::format("{}: vertexMass must be > 0 kg, got {}", who, *c.mass.vertex_mass_kg));
      }
      std::fill(mass.begin(), mass.end(), *c.mass.vertex_mass_kg);
    } else {
      if (!(c.mass.total_mass_kg > 0.0) || !std::isfinite(c.mass.total_mass_kg)) {
        return make_error(ErrorCode::kInvalidArgument,
                          fmt::format("{}: totalMass must be > 0 kg, got {}", who, c.mass.total_mass_kg));
      }
      std::fill(mass.begin(), mass.end(), c.mass.total_mass_kg / static_cast<double>(n));
    }
    return mass;
  }
  // DiagonalMass: each tetrahedron gives ρV/4 to each of its nodes (lumped mass); on a
  // triangle model (a membrane) each triangle gives ρA/3, massDensity then being per area, as
  // SOFA's DiagonalMass does on a triangle topology.
  // On a hexahedral model (no tetrahedra) each hexahedron gives ρV/8 to each of its nodes.
  const bool on_hexahedra = c.tets.empty() && !c.hexahedra.empty();
  const bool on_triangles = c.tets.empty() && !on_hexahedra && !c.triangles.empty();
  if (c.tets.empty() && !on_triangles && !on_hexahedra) {
    return make_error(ErrorCode::kInvalidArgument,
                      fmt::format("{}: needs tetrahedra (or hexahedra or triangles) to compute volumes", who));
  }
  if (!(c.mass.mass_density_kg_per_m3 > 0.0) || !std::isfinite(c.mass.mass_density_kg_per_m3)) {
    return make_error(ErrorCode::kInvalidArgument,
                      fmt::format("{}: massDensity must be > 0 kg/m^3, got {}", who, c.mass.mass_density_kg_per_m3));
  }
  const std::vector<double>& densities = c.mass.element_mass_density_kg_per_m3;
  const std::size_t elements = on_hexahedra ? c.hexahedra.size() : on_triangles ? c.triangles.size() : c.tets.size();
  if (!densities.empty() && densities.size() != elements) {
    return make_error(ErrorCode::kInvalidArgument,
                      fmt::format("{}: massDensity has {} values for {} {} (give one, or one per element)", who,
                                  densities.size(), elements,
                                  on_hexahedra   ? "hexahedra"
                                  : on_triangles ? "triangles"
                                                 : "tetrahedra"));
  }
  auto density = [&](std::size_t e) -> Expected<double> {
    if (densities.empty() || densities[e] == 0.0) return c.mass.mass_density_kg_per_m3;
    if (!(densities[e] > 0.0) || !std::isfinite(densities[e])) {
      return make_error(ErrorCode::kInvalidArgument,
                        fmt::format("{}: massDensity of element {} must be > 0, got {}", who, e, densities[e]));
    }
    return densities[e];
  };
  if (!c.element_fill.empty() && (!on_hexahedra || c.element_fill.size() != elements)) {
    return make_error(ErrorCode::kInvalidArgument,
                      fmt::format("model '{}': a fill fraction per hexahedron is needed ({} for {} elements)", c.name,
                                  c.element_fill.size(), elements));
  }
  for (std::size_t e = 0; e < elements; ++e) {
    auto rho = density(e);
    if (!rho) return std::unexpected(rho.error());
    if (on_hexahedra) {
      // ρV/8 of the part of the cell the body fills — or, for a SOFA scene (fill_scales_mass
      // false), of the whole cell: SOFA's DiagonalMass::computeVertexMass lumps each
      // hexahedron's full volume and never reads the sparse grid's mass coefficient (only
      // HexahedronFEMForceFieldAndMass does).
      const mesh::Hex& h = c.hexahedra[e];
      const double fill = c.element_fill.empty() || !c.fill_scales_mass ? 1.0 : c.element_fill[e];
      const double eighth = fill * *rho * std::abs(mesh::hex_volume(c.positions, h)) / 8.0;
      for (mesh::NodeIndex i : h) mass[static_cast<std::size_t>(i)] += eighth;
    } else if (on_triangles) {
      const mesh::Tri& t = c.triangles[e];
      const double third =
          *rho * 0.5 *
          (c.positions[static_cast<std::size_t>(t[1])] - c.positions[static_cast<std::size_t>(t[0])])
              .cross(c.positions[static_cast<std::size_t>(t[2])] - c.positions[static_cast<std::size_t>(t[0])])
              .norm() /
          3.0;
      for (mesh::NodeIndex i : t) mass[static_cast<std::size_t>(i)] += third;
    } else {
      const auto p = mesh::tet_corners(c.positions, c.tets[e]);
      const double quarter = *rho * std::abs(mesh::tet_signed_volume(p[0], p[1], p[2], p[3])) / 4.0;
      for (mesh::NodeIndex i : c.tets[e]) mass[static_cast<std::size_t>(i)] += quarter;
    }
  }
  if (c.mass.diagonal_total_mass_kg) {
    const double total = std::accumulate(mass.begin(), mass.end(), 0.0);
    const double target = *c.mass.diagonal_total_mass_kg;
    if (!(target > 0.0))
      return make_error(ErrorCode::kInvalidArgument, fmt::format("{}: totalMass must be > 0 kg", who));
    for (double& m : mass) m *= target / total;
  }
  for (std::size_t i = 0; i < n; ++i) {
    if (!(mass[i] > 0.0)) {
      return make_error(ErrorCode::kInvalidMesh,
                        fmt::format("{}: node {} belongs to no element and gets no mass; remove unused nodes "
                                    "or use UniformMass",
                                    who, i));
    }
  }
  return mass;
}

// A tetrahedral field whose Poisson ratio varies by element (a tissue region) as one field per
// distinct ratio over its elements: the fields' fast assembly shares one λ/μ ratio, and the
// sum of the parts is the whole (each element belongs to exactly one part).
template <class Config>
Expected<std::vector<std::pair<Config, std::vector<mesh::Tet>>>> split_by_poisson_ratio(
    const Config& config, const std::vector<mesh::Tet>& tets, const std::string& who) {
  std::vector<std::pair<Config, std::vector<mesh::Tet>>> parts;
  if (config.element_poisson_ratio.empty()) {
    parts.emplace_back(config, tets);
    return parts;
  }
  if (config.element_poisson_ratio.size() != tets.size()) {
    return make_error(ErrorCode::kInvalidArgument,
                      fmt::format("{}: poissonRatio has {} values for {} tetrahedra (give one, or one per tetrahedron)",
                                  who, config.element_poisson_ratio.size(), tets.size()));
  }
  if (!config.element_young_modulus_pa.empty() && config.element_young_modulus_pa.size() != tets.size()) {
    return make_error(ErrorCode::kInvalidArgument,
                      fmt::format("{}: youngModulus has {} values for {} tetrahedra (give one, or one per tetrahedron)",
                                  who, config.element_young_modulus_pa.size(), tets.size()));
  }
  for (std::size_t t = 0; t < tets.size(); ++t) {
    const double nu = config.element_poisson_ratio[t] == 0.0 ? config.poisson_ratio : config.element_poisson_ratio[t];
    if (!(nu > -1.0 && nu < 0.5)) {
      return make_error(ErrorCode::kInvalidArgument,
                        fmt::format("{}: poissonRatio of tetrahedron {} must be in (-1, 0.5), got {}", who, t, nu));
    }
    auto part = std::find_if(parts.begin(), parts.end(), [&](const auto& p) { return p.first.poisson_ratio == nu; });
    if (part == parts.end()) {
      Config sub = config;
      sub.poisson_ratio = nu;
      sub.element_poisson_ratio.clear();
      sub.element_young_modulus_pa.clear();
      parts.emplace_back(std::move(sub), std::vector<mesh::Tet>{});
      part = std::prev(parts.end());
    }
    part->second.push_back(tets[t]);
    if (!config.element_young_modulus_pa.empty())
      part->first.element_young_modulus_pa.push_back(config.element_young_modulus_pa[t]);
  }
  return parts;
}

// What build_model checks before it builds anything: nodes, element corners in range, the
// step and the solvers' settings.
Expected<void> check_config(const ModelConfig& c) {
  const std::size_t n = c.positions.size();
  if (n == 0) return make_error(ErrorCode::kInvalidArgument, fmt::format("model '{}': no nodes", c.name));
  for (std::size_t i = 0; i < n; ++i) {
    if (!c.positions[i].allFinite()) {
      return make_error(ErrorCode::kInvalidMesh,
                        fmt::format("model '{}': node {} has a non-finite position", c.name, i));
    }
  }
  for (std::size_t t = 0; t < c.tets.size(); ++t) {
    for (mesh::NodeIndex i : c.tets[t]) {
      if (i < 0 || static_cast<std::size_t>(i) >= n) {
        return make_error(ErrorCode::kInvalidMesh,
                          fmt::format("model '{}': tetrahedron {} refers to node {} of {}", c.name, t, i, n));
      }
    }
  }
  for (std::size_t t = 0; t < c.triangles.size(); ++t) {
    for (mesh::NodeIndex i : c.triangles[t]) {
      if (i < 0 || static_cast<std::size_t>(i) >= n) {
        return make_error(ErrorCode::kInvalidMesh,
                          fmt::format("model '{}': triangle {} refers to node {} of {}", c.name, t, i, n));
      }
    }
  }
  for (std::size_t h = 0; h < c.hexahedra.size(); ++h) {
    for (mesh::NodeIndex i : c.hexahedra[h]) {
      if (i < 0 || static_cast<std::size_t>(i) >= n) {
        return make_error(ErrorCode::kInvalidMesh,
                          fmt::format("model '{}': hexahedron {} refers to node {} of {}", c.name, h, i, n));
      }
    }
  }
  if (!(c.dt_s > 0.0) || !std::isfinite(c.dt_s)) {
    return make_error(ErrorCode::kInvalidArgument, fmt::format("model '{}': dt must be > 0 s, got {}", c.name, c.dt_s));
  }
  if (!c.gravity_m_per_s2.allFinite()) {
    return make_error(ErrorCode::kInvalidArgument, fmt::format("model '{}': gravity is not finite", c.name));
  }
  if (c.ode.rayleigh_mass < 0.0 || c.ode.rayleigh_stiffness < 0.0) {
    return make_error(
        ErrorCode::kInvalidArgument,
        fmt::format("EulerImplicitSolver '{}': rayleighStiffness and rayleighMass must be >= 0", c.ode.name));
  }
  if (c.ode.kind == OdeSolverKind::kStatic && c.ode.newton_iterations < 1) {
    return make_error(ErrorCode::kInvalidArgument,
                      fmt::format("StaticSolver '{}': newton_iterations must be >= 1", c.ode.name));
  }
  if (c.linear.kind == LinearSolverKind::kConjugateGradient &&
      (c.linear.iterations < 1 || !(c.linear.tolerance >= 0.0) || !(c.linear.threshold >= 0.0))) {
    return make_error(
        ErrorCode::kInvalidArgument,
        fmt::format("CGLinearSolver '{}': iterations must be >= 1, tolerance and threshold >= 0", c.linear.name));
  }

  return {};
}

// The force fields of the config, each made from the rest shape (its element precomputation).
Expected<void> build_force_fields(const ModelConfig& c, MechanicalModel& m) {
  const std::size_t n = c.positions.size();
  for (const ForceFieldConfig& f : c.force_fields) {
    if (f.tetrahedron_fem) {
      auto parts =
          split_by_poisson_ratio(*f.tetrahedron_fem, c.tets, fmt::format("TetrahedronFEMForceField '{}'", f.name));
      if (!parts) return std::unexpected(parts.error());
      for (const auto& [config, tets] : *parts) {
        auto field = TetrahedronFemForceField::make(c.positions, tets, config, f.name);
        if (!field) return std::unexpected(field.error());
        m.force_fields.push_back(std::move(*field));
      }
    } else if (f.mesh_springs) {
      auto field = MeshSpringForceField::make(c.positions, c.tets, c.triangles, *f.mesh_springs, f.name);
      if (!field) return std::unexpected(field.error());
      m.force_fields.push_back(std::move(*field));
    } else if (f.neo_hookean) {
      auto parts = split_by_poisson_ratio(*f.neo_hookean, c.tets, fmt::format("NeoHookean '{}'", f.name));
      if (!parts) return std::unexpected(parts.error());
      for (const auto& [config, tets] : *parts) {
        auto field = NeoHookeanForceField::make(c.positions, tets, config, f.name);
        if (!field) return std::unexpected(field.error());
        m.force_fields.push_back(std::move(*field));
      }
    } else if (f.hexahedron_fem) {
      // A partly filled cell (element_fill) is that fraction as stiff, at whatever modulus.
      HexahedronFemConfig hex = *f.hexahedron_fem;
      if (!c.element_fill.empty()) {
        if (hex.element_young_modulus_pa.size() != c.hexahedra.size())
          hex.element_young_modulus_pa.assign(c.hexahedra.size(), 0.0);
        for (std::size_t e = 0; e < c.hexahedra.size(); ++e) {
          const double fill = c.element_fill[e];
          if (!(fill > 0.0 && fill <= 1.0)) {
            return make_error(
                ErrorCode::kInvalidArgument,
                fmt::format("model '{}': fill of hexahedron {} must be in (0, 1], got {}", c.name, e, fill));
          }
          double& young = hex.element_young_modulus_pa[e];
          young = (young == 0.0 ? hex.young_modulus_pa : young) * fill;
        }
      }
      auto field = HexahedronFemForceField::make(c.positions, c.hexahedra, hex, f.name);
      if (!field) return std::unexpected(field.error());
      m.force_fields.push_back(std::move(*field));
    } else if (f.triangle_fem) {
      auto field = TriangleFemForceField::make(c.positions, c.triangles, *f.triangle_fem, f.name);
      if (!field) return std::unexpected(field.error());
      m.force_fields.push_back(std::move(*field));
    } else if (f.constant_force) {
      auto field = ConstantForceField::make(n, *f.constant_force, f.name);
      if (!field) return std::unexpected(field.error());
      m.force_fields.push_back(std::move(*field));
    } else {
      return make_error(ErrorCode::kInvalidArgument,
                        fmt::format("model '{}': force field '{}' has no type", c.name, f.name));
    }
  }

  return {};
}

// The fixed degrees of freedom, from indices and boxes (projective constraints).
Expected<void> build_supports(const ModelConfig& c, MechanicalModel& m) {
  const std::size_t n = c.positions.size();
  m.fixed_dof_mask.assign(3 * n, 0);
  for (const FixedConstraintConfig& fixed : c.fixed) {
    auto hold = [&](std::size_t node) {
      for (std::size_t a = 0; a < 3; ++a) {
        if (fixed.directions[a]) m.fixed_dof_mask[3 * node + a] = 1;
      }
    };
    if (fixed.fix_all) {
      for (std::size_t i = 0; i < n; ++i) hold(i);
    }
    for (std::int32_t i : fixed.indices) {
      if (i < 0 || static_cast<std::size_t>(i) >= n) {
        return make_error(
            ErrorCode::kInvalidArgument,
            fmt::format("FixedProjectiveConstraint '{}': index {} is out of range (the model has {} nodes)", fixed.name,
                        i, n));
      }
      hold(static_cast<std::size_t>(i));
    }
    if (fixed.box) {
      const auto& [lo, hi] = *fixed.box;
      if (!(lo.array() <= hi.array()).all()) {
        return make_error(ErrorCode::kInvalidArgument,
                          fmt::format("FixedProjectiveConstraint '{}': box min must not exceed max", fixed.name));
      }
      std::size_t inside = 0;
      for (std::size_t i = 0; i < n; ++i) {
        if ((c.positions[i].array() >= lo.array()).all() && (c.positions[i].array() <= hi.array()).all()) {
          hold(i);
          ++inside;
        }
      }
      if (inside == 0) {
        return make_error(ErrorCode::kInvalidArgument,
                          fmt::format("FixedProjectiveConstraint '{}': the box contains no node", fixed.name));
      }
    }
  }
  for (std::size_t d = 0; d < 3 * n; ++d) {
    if (m.fixed_dof_mask[d]) m.fixed_dofs.push_back(static_cast<std::int32_t>(d));
  }

  return {};
}

}  // namespace

std::string MechanicalModel::element_summary() const {
  if (!hexahedra.empty()) return fmt::format("{} hexahedra", hexahedra.size());
  if (!tets.empty() || triangles.empty()) return fmt::format("{} tetrahedra", tets.size());
  return fmt::format("{} triangles", triangles.size());
}

double MechanicalModel::total_mass_kg() const { return std::accumulate(node_mass_kg.begin(), node_mass_kg.end(), 0.0); }

Expected<MechanicalModel> build_model(const ModelConfig& c) {
  if (auto checked = check_config(c); !checked) return std::unexpected(checked.error());
  const std::size_t n = c.positions.size();
  MechanicalModel m;
  m.name = c.name;
  m.rest_positions = c.positions;
  m.tets = c.tets;
  m.hexahedra = c.hexahedra;
  m.triangles = c.triangles;
  m.mass_name = c.mass.name;
  m.ode = c.ode;
  m.linear = c.linear;
  m.gravity_m_per_s2 = c.gravity_m_per_s2;
  m.dt_s = c.dt_s;
  m.max_speed_m_per_s = c.max_speed_m_per_s;
  m.threads = c.threads;
  m.needs_matrix = c.ode.kind == OdeSolverKind::kEulerImplicit || c.ode.kind == OdeSolverKind::kStatic;

  auto masses = build_masses(c);
  if (!masses) return std::unexpected(masses.error());
  m.node_mass_kg = std::move(*masses);

  if (auto fields = build_force_fields(c, m); !fields) return std::unexpected(fields.error());
  if (auto supports = build_supports(c, m); !supports) return std::unexpected(supports.error());
  std::vector<std::pair<std::int32_t, std::int32_t>> pairs;
  for (const auto& field : m.force_fields) field->collect_couplings(pairs);
  m.pattern = BlockSparseMatrix::from_pairs(static_cast<std::int32_t>(n), pairs);
  for (auto& field : m.force_fields) field->bind(m.pattern);
  return m;
}

// ---- state ------------------------------------------------------------------------------------

MechanicalState::MechanicalState() = default;
MechanicalState::MechanicalState(MechanicalState&&) noexcept = default;
MechanicalState& MechanicalState::operator=(MechanicalState&&) noexcept = default;
MechanicalState::~MechanicalState() = default;

void detail::size_workspace(const MechanicalModel& model, MechanicalState& s) {
  const Eigen::Index dofs = 3 * static_cast<Eigen::Index>(model.node_count());
  if (!s.work) s.work = std::make_unique<detail::SolverWorkspace>();
  detail::SolverWorkspace& w = *s.work;
  for (Eigen::VectorXd* vec :
       {&w.b,   &w.dv,  &w.cg_previous, &w.r,   &w.p,   &w.z,   &w.ap,  &w.az,  &w.diag_inv, &w.x_saved, &w.v_saved,
        &w.k1x, &w.k1v, &w.k2x,         &w.k2v, &w.k3x, &w.k3v, &w.k4x, &w.k4v, &w.xt,       &w.vt}) {
    *vec = Eigen::VectorXd::Zero(dofs);
  }
  w.partials.assign(1024, 0.0);
  w.p_single.assign(4 * model.node_count() + 4, 0.0f);
  w.block_jacobi.assign(model.node_count(), Mat3::Identity());
  if (model.needs_matrix) {
    w.system = model.pattern;
    detail::prepare_linear_solver(model, s, s.work->arena->max_concurrency());
  }
}

MechanicalState make_state(const MechanicalModel& model) {
  MechanicalState s;
  const Eigen::Index dofs = 3 * static_cast<Eigen::Index>(model.node_count());
  s.x.resize(dofs);
  s.v = Eigen::VectorXd::Zero(dofs);
  s.f = Eigen::VectorXd::Zero(dofs);
  s.external_force = Eigen::VectorXd::Zero(dofs);
  for (std::size_t i = 0; i < model.node_count(); ++i)
    s.x.segment<3>(3 * static_cast<Eigen::Index>(i)) = model.rest_positions[i];
  for (const auto& field : model.force_fields) s.field_states.push_back(field->make_state());
  s.work = std::make_unique<detail::SolverWorkspace>();
  s.work->arena =
      std::make_unique<tbb::task_arena>(model.threads > 0 ? model.threads : int{tbb::task_arena::automatic});
  detail::size_workspace(model, s);
  return s;
}

void set_threads(const MechanicalModel& model, MechanicalState& state, int threads) {
  const int wanted = threads > 0 ? threads : model.threads > 0 ? model.threads : int{tbb::task_arena::automatic};
  state.work->arena = std::make_unique<tbb::task_arena>(wanted);
  detail::prepare_cg_threads(model, state, state.work->arena->max_concurrency());
}

int thread_count(const MechanicalState& state) { return state.work->arena->max_concurrency(); }

void reserve_point_force_scratch(const MechanicalModel& model, MechanicalState& state, std::size_t elements) {
  state.work->node_marks.assign(model.node_count(), 0);
  state.work->element_scratch.reserve(elements);
}

void reset(const MechanicalModel& model, MechanicalState& state) {
  for (std::size_t i = 0; i < model.node_count(); ++i) {
    state.x.segment<3>(3 * static_cast<Eigen::Index>(i)) = model.rest_positions[i];
  }
  state.v.setZero();
  state.f.setZero();
  state.external_force.setZero();
  state.external_stiffness.clear();  // keeps its capacity
  state.time_s = 0.0;
  state.steps = 0;
  state.divergence = {};
  state.stats = {};
  // As a fresh state: no warm-start guess, no assembled matrix to reuse.
  state.work->cg_previous.setZero();
  state.work->system_assembled_step = -1;
  state.work->coarse.built_step = -1;
  for (std::size_t k = 0; k < model.force_fields.size(); ++k) {
    ForceFieldState fresh = model.force_fields[k]->make_state();
    state.field_states[k] = std::move(fresh);
  }
}

}  // namespace hof::mechanics
