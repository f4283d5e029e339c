// A mechanics step allocates no memory once the state is made (MuJoCo/Drake practice: the
// hot loop runs from storage sized up front). Counted by replacing global operator new.

#include <gtest/gtest.h>

#include "support/allocation_counter.h"

#include <atomic>
#include <cstdlib>
#include <new>

#include "hof/mechanics/step.h"
#include "hof/mesh/boundary.h"
#include "hof/mesh/hex_grid.h"
#include "hof/mesh/liver_generator.h"

namespace hof::mechanics {
namespace {

struct Case {
  const char* name;
  ForceFieldConfig field;
  OdeSolverKind solver;
  LinearSolverKind linear;
  bool warm_start{false};
};

std::vector<Case> cases() {
  ForceFieldConfig springs;
  springs.name = "springs";
  springs.mesh_springs = MeshSpringConfig{5000.0, 25.0, 1.0};
  ForceFieldConfig large;
  large.name = "fem";
  large.tetrahedron_fem = TetrahedronFemConfig{5400.0, 0.45, FemMethod::kLarge, {}, {}};
  ForceFieldConfig polar;
  polar.name = "fem";
  polar.tetrahedron_fem = TetrahedronFemConfig{5400.0, 0.45, FemMethod::kPolar, {}, {}};
  ForceFieldConfig neo;
  neo.name = "neo";
  neo.neo_hookean = NeoHookeanConfig{5400.0, 0.45, {}, {}};
  return {{"springs/implicit-cg", springs, OdeSolverKind::kEulerImplicit, LinearSolverKind::kConjugateGradient},
          {"large/implicit-cg", large, OdeSolverKind::kEulerImplicit, LinearSolverKind::kConjugateGradient},
          {"large/implicit-cg-warm", large, OdeSolverKind::kEulerImplicit, LinearSolverKind::kConjugateGradient, true},
          {"polar/implicit-ldlt", polar, OdeSolverKind::kEulerImplicit, LinearSolverKind::kSparseLdlt},
          {"neo/static-cg", neo, OdeSolverKind::kStatic, LinearSolverKind::kConjugateGradient},
          {"large/explicit", large, OdeSolverKind::kEulerExplicit, LinearSolverKind::kConjugateGradient},
          {"large/rk4", large, OdeSolverKind::kRungeKutta4, LinearSolverKind::kConjugateGradient}};
}

TEST(NoAllocation, StepsAllocateNothingAfterMakeState) {
  HOF_SKIP_UNLESS_COUNTING_ALLOCATIONS();
  const mesh::Mesh liver = *mesh::generate_liver(mesh::LiverResolution::kMedium);  // parallel paths run
  for (const Case& c : cases()) {
    ModelConfig config;
    config.positions = liver.nodes;
    config.tets = liver.tets;
    config.mass.kind = MassKind::kDiagonal;
    config.mass.mass_density_kg_per_m3 = 1060.0;
    config.gravity_m_per_s2 = Vec3(0, 0, -9.81);
    config.force_fields = {c.field};
    config.fixed.push_back(FixedConstraintConfig{"fixed", {0, 1, 2}, std::nullopt, false, {true, true, true}});
    config.ode.kind = c.solver;
    config.ode.newton_iterations = 2;
    config.linear.kind = c.linear;
    config.linear.block_jacobi = true;
    config.linear.warm_start = c.warm_start;
    config.ode.matrix_reuse_steps = c.warm_start ? 2 : 1;
    // The haptic-rate mode's two-level preconditioner, its coarse matrix formed again within
    // the counted steps.
    config.linear.coarse_correction = c.warm_start;
    config.linear.coarse_refresh_steps = 2;
    config.dt_s = c.solver == OdeSolverKind::kEulerImplicit || c.solver == OdeSolverKind::kStatic ? 0.02 : 1e-5;
    auto model = build_model(config);
    ASSERT_TRUE(model) << model.error().to_string();
    MechanicalState state = make_state(*model);
    for (int i = 0; i < 3; ++i) ASSERT_TRUE(step(*model, state));  // warm-up (thread pool start)
    const long before = hof::testing::allocation_count();
    for (int i = 0; i < 5; ++i) ASSERT_TRUE(step(*model, state)) << c.name << ": " << state.divergence.reason;
    EXPECT_EQ(hof::testing::allocation_count() - before, 0) << c.name;
  }
}

TEST(NoAllocation, HexahedralAndMembraneStepsAllocateNothing) {
  HOF_SKIP_UNLESS_COUNTING_ALLOCATIONS();
  const mesh::Mesh liver = *mesh::generate_liver(mesh::LiverResolution::kMedium);
  const mesh::BoundarySurface surface = mesh::extract_boundary(liver.nodes, liver.tets);
  auto grid = mesh::sparse_grid(surface.surface, {12, 8, 6});
  ASSERT_TRUE(grid) << grid.error().to_string();
  for (const bool hexahedral : {true, false}) {
    ModelConfig config;
    config.mass.kind = MassKind::kDiagonal;
    config.mass.mass_density_kg_per_m3 = hexahedral ? 1060.0 : 1.06;
    config.gravity_m_per_s2 = Vec3(0, 0, -9.81);
    ForceFieldConfig field;
    field.name = "fem";
    if (hexahedral) {
      config.positions = grid->nodes;
      config.hexahedra = grid->hexes;
      config.element_fill.assign(grid->hexes.size(), 1.0);
      field.hexahedron_fem = HexahedronFemConfig{5400.0, 0.45, FemMethod::kLarge, {}, {}};
    } else {
      config.positions = surface.surface.vertices;
      config.triangles = surface.surface.triangles;
      TriangleFemConfig membrane;
      membrane.young_modulus_pa = 5400.0;
      membrane.thickness_m = 0.001;
      field.triangle_fem = membrane;
    }
    config.force_fields = {field};
    config.fixed.push_back(FixedConstraintConfig{"fixed", {0, 1, 2}, std::nullopt, false, {true, true, true}});
    config.dt_s = 0.01;
    auto model = build_model(config);
    ASSERT_TRUE(model) << model.error().to_string();
    MechanicalState state = make_state(*model);
    for (int i = 0; i < 3; ++i) ASSERT_TRUE(step(*model, state));
    const long before = hof::testing::allocation_count();
    for (int i = 0; i < 5; ++i) ASSERT_TRUE(step(*model, state)) << state.divergence.reason;
    EXPECT_EQ(hof::testing::allocation_count() - before, 0) << (hexahedral ? "hexahedra" : "membrane");
  }
}

TEST(NoAllocation, TheCounterCounts) {
  HOF_SKIP_UNLESS_COUNTING_ALLOCATIONS();
  const long before = hof::testing::allocation_count();
  auto* p = new std::vector<int>(100);
  delete p;
  EXPECT_GE(hof::testing::allocation_count() - before, 2);
}

}  // namespace
}  // namespace hof::mechanics
