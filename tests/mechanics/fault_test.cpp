// Faults as data and their words (src/hof/mechanics/fault.cpp): the text of every kind, the
// one the reports have always printed.

#include <gtest/gtest.h>

#include "hof/mechanics/fault.h"
#include "hof/mechanics/mechanical_model.h"
#include "test_meshes.h"

namespace hof::mechanics {
namespace {

MechanicalModel small_model(OdeSolverKind ode, LinearSolverKind linear) {
  const auto box = testing::box_mesh(1, 1, 1, Vec3(0.1, 0.1, 0.1));
  ModelConfig c;
  c.positions = box.nodes;
  c.tets = box.tets;
  ForceFieldConfig fem;
  fem.name = "FEM";
  fem.tetrahedron_fem = TetrahedronFemConfig{10000.0, 0.3, FemMethod::kSmall, {}, {}};
  c.force_fields.push_back(fem);
  c.ode.kind = ode;
  c.ode.name = "ode";
  c.linear.kind = linear;
  c.linear.name = "lin";
  c.max_speed_m_per_s = 100.0;
  auto model = build_model(c);
  EXPECT_TRUE(model);
  return std::move(*model);
}

TEST(Fault, EveryKindInWords) {
  const MechanicalModel model = small_model(OdeSolverKind::kEulerExplicit, LinearSolverKind::kSparseLdlt);
  FaultText t = describe_fault(model, {FaultKind::kLinearSolveFailed, -1, -1, 0.0});
  EXPECT_EQ(t.component, "SparseLDLSolver 'lin'");
  EXPECT_EQ(t.reason, "the linear solve broke down (singular or non-finite system)");
  t = describe_fault(model, {FaultKind::kNonFiniteNode, 3, -1, 0.0});
  EXPECT_EQ(t.component, "EulerExplicitSolver 'ode'");
  EXPECT_EQ(t.reason, "node 3 has a non-finite position or velocity");
  t = describe_fault(model, {FaultKind::kInvertedElement, 4, 0, 0.0});
  EXPECT_EQ(t.component, "TetrahedronFEMForceField 'FEM'");
  EXPECT_EQ(t.reason,
            "tetrahedron 4 is inverted: linear (small) FEM cannot recover; use method \"large\" or \"polar\", or a "
            "Neo-Hookean material");
  t = describe_fault(model, {FaultKind::kRunawayNode, 7, -1, 123.456});
  EXPECT_EQ(t.reason,
            "node 7 moves at 123 m/s, above the 100 m/s limit: the simulation is unstable (reduce dt, raise damping or "
            "use an implicit solver)");
  EXPECT_TRUE(describe_fault(model, {}).reason.empty());
}

TEST(Fault, TheSolverNamedIsTheModels) {
  EXPECT_EQ(describe_fault(small_model(OdeSolverKind::kEulerImplicit, LinearSolverKind::kConjugateGradient),
                           {FaultKind::kLinearSolveFailed, -1, -1, 0.0})
                .component,
            "CGLinearSolver 'lin'");
  EXPECT_EQ(describe_fault(small_model(OdeSolverKind::kRungeKutta4, LinearSolverKind::kSparseLdlt),
                           {FaultKind::kNonFiniteNode, 0, -1, 0.0})
                .component,
            "RungeKutta4Solver 'ode'");
  EXPECT_EQ(describe_fault(small_model(OdeSolverKind::kStatic, LinearSolverKind::kSparseLdlt),
                           {FaultKind::kNonFiniteNode, 0, -1, 0.0})
                .component,
            "StaticSolver 'ode'");
}

}  // namespace
}  // namespace hof::mechanics
