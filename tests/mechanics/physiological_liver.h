#pragma once
// The physiological liver of the haptic-rate tests (literature.md §6: E ≈ 5 kPa, ν ≈ 0.45,
// 1060 kg/m³), co-rotational FEM, held at its lowest nodes, implicit Euler at the haptic
// period with SOFA's Rayleigh damping, one thread; a model with its state, and the error of a
// step against an exact one.

#include <gtest/gtest.h>

#include <algorithm>

#include "hof/mechanics/mechanical_model.h"
#include "hof/mechanics/mechanical_state.h"
#include "hof/mesh/mesh.h"

namespace hof::mechanics::testing {

inline ModelConfig physiological_liver_config(const mesh::Mesh& liver) {
  ModelConfig c;
  c.name = "liver";
  c.positions = liver.nodes;
  c.tets = liver.tets;
  c.mass.kind = MassKind::kDiagonal;
  c.mass.mass_density_kg_per_m3 = 1060.0;
  c.gravity_m_per_s2 = Vec3(0, 0, -9.81);
  ForceFieldConfig fem;
  fem.name = "FEM";
  fem.tetrahedron_fem = TetrahedronFemConfig{5000.0, 0.45, FemMethod::kLarge, {}, {}};
  c.force_fields.push_back(fem);
  const double lowest = std::ranges::min(liver.nodes, {}, [](const Vec3& p) { return p.z(); }).z();
  FixedConstraintConfig fixed;
  for (std::size_t i = 0; i < liver.nodes.size(); ++i) {
    if (liver.nodes[i].z() < lowest + 0.004) fixed.indices.push_back(static_cast<std::int32_t>(i));
  }
  c.fixed.push_back(fixed);
  c.ode.kind = OdeSolverKind::kEulerImplicit;
  c.ode.rayleigh_mass = 0.1;
  c.ode.rayleigh_stiffness = 0.1;
  c.dt_s = 1e-3;
  c.threads = 1;
  return c;
}

struct Solver {
  MechanicalModel model;
  MechanicalState state;
};

inline Solver make_solver(const ModelConfig& c) {
  auto model = build_model(c);
  EXPECT_TRUE(model) << model.error().to_string();
  Solver s{std::move(*model), {}};
  s.state = make_state(s.model);
  return s;
}

// Relative error of a step's velocity change (from v0 to v) against the exact one (v_exact).
inline double step_error(const Eigen::VectorXd& v0, const Eigen::VectorXd& v, const Eigen::VectorXd& v_exact) {
  return (v - v_exact).norm() / std::max((v_exact - v0).norm(), 1e-300);
}

}  // namespace hof::mechanics::testing
