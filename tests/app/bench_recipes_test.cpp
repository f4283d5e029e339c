// The bench's model recipes are built by the builder's SOFA reader (recipes.cpp body_scene):
// each must be the model the bench made by hand before, field by field, so that its cells time
// and measure the same models. The hand-made recipe is kept here as the reference.

#include <gtest/gtest.h>

#include <algorithm>
#include <cstdint>
#include <limits>
#include <string>
#include <vector>

#include "hof/app/bench/recipes.h"
#include "hof/scene/sofa_scene.h"

namespace hof::app::bench {
namespace {

using namespace hof::mechanics;

// The recipe as bench/recipes.cpp wrote it before the builder made it (commit b8031b8).
ModelConfig hand_made(const Body& b, Field field, Settings s) {
  ModelConfig c;
  c.name = "liver";
  c.positions = b.nodes;
  c.tets = b.tets;
  c.hexahedra = b.hexes;
  const bool thesis = s == Settings::kThesis;
  if (thesis) {
    c.mass.kind = MassKind::kUniform;
    c.mass.total_mass_kg = 1.0;
  } else {
    c.mass.kind = MassKind::kDiagonal;
    c.mass.mass_density_kg_per_m3 = 1060.0;
  }
  c.gravity_m_per_s2 = Vec3(0, 0, thesis ? -9.8 : -9.81);
  const double young = thesis ? 100.0 : 5000.0;
  const double poisson = thesis ? 0.4 : 0.45;
  ForceFieldConfig f;
  f.name = field_name(field);
  switch (field) {
    case Field::kSprings: {
      double stiffness = 10000.0, damping = 15.0;
      if (!thesis) {
        double length = 0.0;
        for (const mesh::Tet& t : b.tets)
          length += (b.nodes[static_cast<std::size_t>(t[0])] - b.nodes[static_cast<std::size_t>(t[1])]).norm();
        stiffness = young * length / static_cast<double>(std::max<std::size_t>(b.tets.size(), 1));
        damping = 15.0 * stiffness / 10000.0;
      }
      f.mesh_springs = MeshSpringConfig{stiffness, damping, 1.0};
      break;
    }
    case Field::kSmall:
      f.tetrahedron_fem = TetrahedronFemConfig{young, poisson, FemMethod::kSmall, {}, {}};
      break;
    case Field::kLarge:
      f.tetrahedron_fem = TetrahedronFemConfig{young, poisson, FemMethod::kLarge, {}, {}};
      break;
    case Field::kNeoHookean:
      f.neo_hookean = NeoHookeanConfig{young, poisson, {}, {}};
      break;
    case Field::kHexahedra: {
      HexahedronFemConfig h;
      h.young_modulus_pa = young;
      h.poisson_ratio = poisson;
      h.method = FemMethod::kLarge;
      f.hexahedron_fem = h;
      break;
    }
  }
  c.force_fields.push_back(f);
  double lowest = std::numeric_limits<double>::infinity();
  for (const Vec3& p : b.nodes) lowest = std::min(lowest, p.z());
  FixedConstraintConfig fixed;
  fixed.name = "table";
  for (std::size_t i = 0; i < b.nodes.size(); ++i) {
    if (b.nodes[i].z() < lowest + 0.004) fixed.indices.push_back(static_cast<std::int32_t>(i));
  }
  c.fixed.push_back(fixed);
  c.ode.rayleigh_mass = c.ode.rayleigh_stiffness = 0.1;
  c.ode.newton_iterations = 1;
  c.linear.iterations = 25;
  c.linear.tolerance = c.linear.threshold = 1e-12;
  c.dt_s = 0.02;
  c.threads = 0;
  return c;
}

void expect_same_elastic(const auto& built, const auto& made) {
  EXPECT_EQ(built.young_modulus_pa, made.young_modulus_pa);
  EXPECT_EQ(built.poisson_ratio, made.poisson_ratio);
  EXPECT_EQ(built.element_young_modulus_pa, made.element_young_modulus_pa);
  EXPECT_EQ(built.element_poisson_ratio, made.element_poisson_ratio);
}

void expect_same_field(const ForceFieldConfig& built, const ForceFieldConfig& made) {
  EXPECT_EQ(built.name, made.name);
  ASSERT_EQ(built.mesh_springs.has_value(), made.mesh_springs.has_value());
  ASSERT_EQ(built.tetrahedron_fem.has_value(), made.tetrahedron_fem.has_value());
  ASSERT_EQ(built.neo_hookean.has_value(), made.neo_hookean.has_value());
  ASSERT_EQ(built.hexahedron_fem.has_value(), made.hexahedron_fem.has_value());
  EXPECT_FALSE(built.constant_force || built.triangle_fem);
  if (made.mesh_springs) {
    const MeshSpringConfig &x = *built.mesh_springs, &y = *made.mesh_springs;
    EXPECT_EQ(x.stiffness_n_per_m, y.stiffness_n_per_m);
    EXPECT_EQ(x.damping_n_s_per_m, y.damping_n_s_per_m);
    EXPECT_EQ(x.rest_length_scale, y.rest_length_scale);
    EXPECT_EQ(x.rule, y.rule);
    EXPECT_EQ(x.tangent, y.tangent);
    EXPECT_FALSE(x.triangles || y.triangles || x.tetrahedra || y.tetrahedra);
  }
  if (made.tetrahedron_fem) {
    expect_same_elastic(*built.tetrahedron_fem, *made.tetrahedron_fem);
    EXPECT_EQ(built.tetrahedron_fem->method, made.tetrahedron_fem->method);
  }
  if (made.neo_hookean) expect_same_elastic(*built.neo_hookean, *made.neo_hookean);
  if (made.hexahedron_fem) {
    expect_same_elastic(*built.hexahedron_fem, *made.hexahedron_fem);
    EXPECT_EQ(built.hexahedron_fem->method, made.hexahedron_fem->method);
  }
}

// Every field of ModelConfig (mechanical_model.h), exactly.
void expect_same(const ModelConfig& built, const ModelConfig& made) {
  EXPECT_EQ(built.name, made.name);
  EXPECT_TRUE(built.positions == made.positions);
  EXPECT_TRUE(built.tets == made.tets);
  EXPECT_TRUE(built.hexahedra == made.hexahedra);
  EXPECT_TRUE(built.triangles == made.triangles);
  EXPECT_EQ(built.element_regions, made.element_regions);
  EXPECT_EQ(built.element_fill, made.element_fill);
  EXPECT_EQ(built.fill_scales_mass, made.fill_scales_mass);

  EXPECT_EQ(built.mass.kind, made.mass.kind);
  EXPECT_EQ(built.mass.name, made.mass.name);
  EXPECT_EQ(built.mass.total_mass_kg, made.mass.total_mass_kg);
  EXPECT_EQ(built.mass.vertex_mass_kg, made.mass.vertex_mass_kg);
  EXPECT_EQ(built.mass.mass_density_kg_per_m3, made.mass.mass_density_kg_per_m3);
  EXPECT_EQ(built.mass.diagonal_total_mass_kg, made.mass.diagonal_total_mass_kg);
  EXPECT_EQ(built.mass.element_mass_density_kg_per_m3, made.mass.element_mass_density_kg_per_m3);

  ASSERT_EQ(built.force_fields.size(), made.force_fields.size());
  for (std::size_t i = 0; i < made.force_fields.size(); ++i)
    expect_same_field(built.force_fields[i], made.force_fields[i]);

  ASSERT_EQ(built.fixed.size(), made.fixed.size());
  for (std::size_t i = 0; i < made.fixed.size(); ++i) {
    EXPECT_EQ(built.fixed[i].name, made.fixed[i].name);
    EXPECT_EQ(built.fixed[i].indices, made.fixed[i].indices);
    EXPECT_EQ(built.fixed[i].box.has_value(), made.fixed[i].box.has_value());
    EXPECT_EQ(built.fixed[i].fix_all, made.fixed[i].fix_all);
    EXPECT_EQ(built.fixed[i].directions, made.fixed[i].directions);
  }

  const OdeSolverConfig &o = built.ode, &p = made.ode;
  EXPECT_EQ(o.kind, p.kind);
  EXPECT_EQ(o.name, p.name);
  EXPECT_EQ(o.symplectic, p.symplectic);
  EXPECT_EQ(o.rayleigh_stiffness, p.rayleigh_stiffness);
  EXPECT_EQ(o.rayleigh_mass, p.rayleigh_mass);
  EXPECT_EQ(o.newton_iterations, p.newton_iterations);
  EXPECT_EQ(o.newton_residual_tolerance_n, p.newton_residual_tolerance_n);
  EXPECT_EQ(o.newton_correction_tolerance, p.newton_correction_tolerance);
  EXPECT_EQ(o.matrix_reuse_steps, p.matrix_reuse_steps);

  const LinearSolverConfig &l = built.linear, &m = made.linear;
  EXPECT_EQ(l.kind, m.kind);
  EXPECT_EQ(l.name, m.name);
  EXPECT_EQ(l.iterations, m.iterations);
  EXPECT_EQ(l.tolerance, m.tolerance);
  EXPECT_EQ(l.threshold, m.threshold);
  EXPECT_EQ(l.block_jacobi, m.block_jacobi);
  EXPECT_EQ(l.mixed_precision, m.mixed_precision);
  EXPECT_EQ(l.warm_start, m.warm_start);
  EXPECT_EQ(l.coarse_correction, m.coarse_correction);
  EXPECT_EQ(l.coarse_refresh_steps, m.coarse_refresh_steps);

  EXPECT_TRUE(built.gravity_m_per_s2 == made.gravity_m_per_s2);
  EXPECT_EQ(built.dt_s, made.dt_s);
  EXPECT_EQ(built.max_speed_m_per_s, made.max_speed_m_per_s);
  EXPECT_EQ(built.threads, made.threads);
}

const Body& body(const char* name) {
  static Bodies bodies;
  auto b = bodies.by_name(name);
  EXPECT_TRUE(b.has_value());
  return **b;
}

TEST(BenchRecipes, BodyConfigIsTheHandMadeRecipe) {
  for (const char* mesh : {"simple", "coarse"}) {
    const Body& b = body(mesh);
    for (Settings s : {Settings::kThesis, Settings::kPhysiological}) {
      for (Field f : {Field::kSprings, Field::kSmall, Field::kLarge, Field::kNeoHookean}) {
        SCOPED_TRACE(testing::Message() << mesh << " " << field_name(f) << " " << settings_name(s));
        expect_same(body_config(b, f, s), hand_made(b, f, s));
      }
    }
  }
}

TEST(BenchRecipes, SparseGridConfigIsTheHandMadeRecipe) {
  const Body& b = body("sparse-grid");
  for (Settings s : {Settings::kThesis, Settings::kPhysiological}) {
    SCOPED_TRACE(settings_name(s));
    expect_same(body_config(b, Field::kHexahedra, s), hand_made(b, Field::kHexahedra, s));
  }
}

TEST(BenchRecipes, SolverAndSetUpsAreTheHandMadeRecipes) {
  const Body& b = body("simple");
  for (Solver sv : {Solver::kExplicitEuler, Solver::kSymplecticEuler, Solver::kRungeKutta4, Solver::kStatic,
                    Solver::kImplicitCg, Solver::kImplicitLdlt}) {
    SCOPED_TRACE(solver_name(sv));
    ModelConfig built = body_config(b, Field::kSprings, Settings::kThesis);
    ModelConfig made = hand_made(b, Field::kSprings, Settings::kThesis);
    set_solver(built, sv, 0.002);
    set_solver(made, sv, 0.002);
    expect_same(built, made);
  }
  // The plan's set-ups (plan.cpp).
  for (const CorotationalSetup& setup :
       {CorotationalSetup{0.02}, CorotationalSetup{0.001, 25, false}, CorotationalSetup{0.001, 25, true},
        CorotationalSetup{0.001, 25, true, false}, CorotationalSetup{0.01, 25, false, false},
        CorotationalSetup{0.02, 100, false, false}, CorotationalSetup{0.001, 100, true, false}}) {
    SCOPED_TRACE(testing::Message() << setup.dt_s << " " << setup.iterations << " " << setup.haptic_rate_cg << " "
                                    << setup.gravity);
    ModelConfig made = hand_made(b, Field::kLarge, Settings::kPhysiological);
    set_solver(made, Solver::kImplicitCg, setup.dt_s);
    made.linear.iterations = setup.iterations;
    if (setup.haptic_rate_cg) use_haptic_rate_cg(made);
    if (!setup.gravity) made.gravity_m_per_s2 = Vec3::Zero();
    expect_same(corotational_config(b, setup), made);
  }
  ModelConfig press = hand_made(b, Field::kLarge, Settings::kPhysiological);
  press.gravity_m_per_s2 = Vec3::Zero();
  press.ode.rayleigh_mass = 1.0;
  press.ode.rayleigh_stiffness = 0.1;
  press.linear.iterations = 100;
  press.linear.tolerance = press.linear.threshold = 1e-9;
  expect_same(coupling_press_config(b), press);
}

// The recipes read as a user's scene would, with nothing to warn about: the springs' rule is
// an attribute the reader knows. Only the Neo-Hookean field notes its conversion from (μ, k).
TEST(BenchRecipes, ScenesReadWithoutWarnings) {
  const Body& b = body("simple");
  for (Field f : {Field::kSprings, Field::kSmall, Field::kLarge, Field::kNeoHookean}) {
    SCOPED_TRACE(field_name(f));
    auto scene = scene::read_sofa_scene_text(body_scene(b, f, Settings::kPhysiological), "bench.scn");
    ASSERT_TRUE(scene.has_value()) << scene.error().to_string();
    EXPECT_TRUE(scene->skipped.empty());
    EXPECT_TRUE(scene->ignored.empty());
    EXPECT_EQ(scene->warnings.size(), f == Field::kNeoHookean ? 1U : 0U);
  }
  auto grid =
      scene::read_sofa_scene_text(body_scene(body("sparse-grid"), Field::kHexahedra, Settings::kThesis), "bench.scn");
  ASSERT_TRUE(grid.has_value()) << grid.error().to_string();
  EXPECT_TRUE(grid->warnings.empty());
}

}  // namespace
}  // namespace hof::app::bench
