// SOFA scene reader: the four anchor liver scenes (today's syntax, the tutorial, and two
// 2008 versions) load into the expected configs, build and run; malformed scenes fail with
// the file, the line and the component in the message.

#include <gtest/gtest.h>

#include <algorithm>
#include <cstdlib>
#include <fstream>

#include "hof/mechanics/step.h"
#include "hof/scene/model_parameters.h"
#include "hof/scene/sofa_scene.h"

namespace hof::scene {
namespace {

namespace fs = std::filesystem;
using mechanics::FemMethod;
using mechanics::LinearSolverKind;
using mechanics::MassKind;
using mechanics::OdeSolverKind;

const std::string kAnchors = HOF_ANCHORS_DIR "/sofa";

SofaScene load(const std::string& path) {
  auto s = read_sofa_scene(path);
  EXPECT_TRUE(s.has_value()) << (s ? "" : s.error().to_string());
  return s ? std::move(*s) : SofaScene{};
}

bool contains(const std::vector<std::string>& v, std::string_view needle) {
  return std::ranges::any_of(v, [&](const std::string& s) { return s.find(needle) != std::string::npos; });
}

// Builds the model and runs 10 steps; returns the largest displacement.
double run_ten_steps(const mechanics::ModelConfig& config) {
  auto model = mechanics::build_model(config);
  EXPECT_TRUE(model.has_value()) << (model ? "" : model.error().message);
  if (!model) return -1.0;
  auto state = mechanics::make_state(*model);
  for (int i = 0; i < 10; ++i) EXPECT_TRUE(mechanics::step(*model, state)) << "step " << i;
  double max_disp = 0.0;
  for (std::size_t i = 0; i < model->node_count(); ++i)
    max_disp = std::max(max_disp, (state.position(static_cast<std::int32_t>(i)) - model->rest_positions[i]).norm());
  EXPECT_TRUE(std::isfinite(max_disp));
  return max_disp;
}

const mechanics::TetrahedronFemConfig& fem_of(const mechanics::ModelConfig& c) {
  for (const auto& f : c.force_fields)
    if (f.tetrahedron_fem) return *f.tetrahedron_fem;
  ADD_FAILURE() << "no FEM force field";
  static const mechanics::TetrahedronFemConfig none;
  return none;
}

TEST(SofaScene, LiverScn) {
  const SofaScene s = load(kAnchors + "/liver.scn");
  ASSERT_EQ(s.models.size(), 1u);
  const SofaSceneModel& model = s.models[0];
  const auto& c = model.config;
  EXPECT_EQ(model.node_path, "lroot/Liver");
  EXPECT_EQ(c.positions.size(), 181u);
  EXPECT_EQ(c.tets.size(), 596u);
  EXPECT_DOUBLE_EQ(c.dt_s, 0.02);
  EXPECT_EQ(c.gravity_m_per_s2, Vec3(0, -9.81, 0));
  EXPECT_EQ(c.ode.kind, OdeSolverKind::kEulerImplicit);
  EXPECT_EQ(c.ode.name, "cg_odesolver");
  EXPECT_DOUBLE_EQ(c.ode.rayleigh_stiffness, 0.1);
  EXPECT_DOUBLE_EQ(c.ode.rayleigh_mass, 0.1);
  EXPECT_EQ(c.linear.kind, LinearSolverKind::kConjugateGradient);
  EXPECT_EQ(c.linear.iterations, 25);
  EXPECT_DOUBLE_EQ(c.linear.tolerance, 1e-9);
  EXPECT_DOUBLE_EQ(c.linear.threshold, 1e-9);
  ASSERT_EQ(c.force_fields.size(), 1u);
  EXPECT_EQ(c.force_fields[0].name, "FEM");
  EXPECT_DOUBLE_EQ(fem_of(c).young_modulus_pa, 3000.0);
  EXPECT_DOUBLE_EQ(fem_of(c).poisson_ratio, 0.3);
  EXPECT_EQ(fem_of(c).method, FemMethod::kLarge);
  EXPECT_EQ(c.mass.kind, MassKind::kDiagonal);
  EXPECT_DOUBLE_EQ(c.mass.mass_density_kg_per_m3, 1.0);
  ASSERT_EQ(c.fixed.size(), 1u);
  EXPECT_EQ(c.fixed[0].indices, (std::vector<std::int32_t>{3, 39, 64}));
  ASSERT_TRUE(model.visual_mesh.has_value());
  EXPECT_EQ(model.visual_mesh->filename(), "liver-smooth.obj");
  EXPECT_TRUE(fs::exists(*model.visual_mesh));
  EXPECT_TRUE(model.visual_barycentric);
  // Plugins need no counterpart; the collision pipeline, the response and the collision
  // spheres are contact settings now (sofa_collision_test.cpp): neither ignored nor skipped.
  EXPECT_TRUE(contains(s.ignored, "RequiredPlugin"));
  EXPECT_FALSE(contains(s.ignored, "CollisionPipeline"));
  EXPECT_FALSE(contains(s.ignored, "CollisionResponse"));
  EXPECT_FALSE(contains(s.skipped, "SphereCollisionModel 'CollisionModel'"));
  EXPECT_FALSE(contains(s.ignored, "SphereLoader"));
  EXPECT_FALSE(contains(s.skipped, "LiverSurface"));  // used by the OglModel
  EXPECT_FALSE(contains(s.skipped, "'dofs'"));
  EXPECT_TRUE(s.skipped.empty()) << s.skipped.front();
  EXPECT_TRUE(s.contacts.enabled);
  EXPECT_TRUE(s.models[0].collision.enabled);
  EXPECT_GT(run_ten_steps(c), 0.0);
}

TEST(SofaScene, TutorialForceFieldLiverFem) {
  const SofaScene s = load(kAnchors + "/TutorialForceFieldLiverFEM.scn");
  ASSERT_EQ(s.models.size(), 1u);
  const auto& c = s.models[0].config;
  EXPECT_EQ(c.positions.size(), 181u);
  EXPECT_EQ(c.tets.size(), 596u);
  EXPECT_DOUBLE_EQ(fem_of(c).young_modulus_pa, 50.0);
  EXPECT_DOUBLE_EQ(fem_of(c).poisson_ratio, 0.45);
  EXPECT_EQ(c.mass.kind, MassKind::kUniform);
  EXPECT_DOUBLE_EQ(c.mass.total_mass_kg, 1.0);
  EXPECT_FALSE(c.mass.vertex_mass_kg.has_value());
  EXPECT_EQ(c.fixed[0].indices, (std::vector<std::int32_t>{3, 39, 64}));
  EXPECT_TRUE(s.models[0].visual_barycentric);
  EXPECT_EQ(s.models[0].visual_mesh->filename(), "liver-smooth.obj");
  EXPECT_TRUE(contains(s.ignored, "VisualStyle"));
  EXPECT_GT(run_ten_steps(c), 0.0);
}

TEST(SofaScene, History2008ObjectSyntaxWithMeshAndXs3) {
  const SofaScene s = load(kAnchors + "/history/2008-07-30_14f43fd649/liver.scn");
  ASSERT_EQ(s.models.size(), 1u);
  const auto& c = s.models[0].config;
  EXPECT_EQ(c.positions.size(), 181u);  // from BehaviorModels/liver.xs3
  EXPECT_EQ(c.tets.size(), 597u);       // from mesh/liver.mesh
  EXPECT_DOUBLE_EQ(c.dt_s, 0.02);
  EXPECT_EQ(c.ode.kind, OdeSolverKind::kEulerImplicit);
  EXPECT_DOUBLE_EQ(c.ode.rayleigh_stiffness, 0.1);  // 2008 defaults
  EXPECT_DOUBLE_EQ(c.ode.rayleigh_mass, 0.1);
  EXPECT_TRUE(contains(s.warnings, "Rayleigh defaults"));
  EXPECT_EQ(c.linear.iterations, 25);
  EXPECT_DOUBLE_EQ(c.linear.tolerance, 1e-9);
  EXPECT_DOUBLE_EQ(fem_of(c).young_modulus_pa, 500.0);
  EXPECT_DOUBLE_EQ(fem_of(c).poisson_ratio, 0.3);
  EXPECT_EQ(c.mass.kind, MassKind::kUniform);  // xs3 masses, all 0.05
  ASSERT_TRUE(c.mass.vertex_mass_kg.has_value());
  EXPECT_DOUBLE_EQ(*c.mass.vertex_mass_kg, 0.05);
  EXPECT_EQ(c.fixed[0].indices, (std::vector<std::int32_t>{3, 39, 64}));
  EXPECT_TRUE(s.models[0].visual_barycentric);
  EXPECT_EQ(s.models[0].visual_mesh->filename(), "liver-smooth.obj");
  // 2008's Sphere model with its .sph file: the body's collision spheres.
  EXPECT_FALSE(contains(s.skipped, "Sphere 'CollisionModel'"));
  EXPECT_FALSE(s.models[0].collision.sphere_centers.empty());
  EXPECT_GT(run_ten_steps(c), 0.0);
}

TEST(SofaScene, History2008MeshLoader) {
  const SofaScene s = load(kAnchors + "/history/2008-10-17_ceddbfd360/liver.scn");
  ASSERT_EQ(s.models.size(), 1u);
  const auto& c = s.models[0].config;
  EXPECT_EQ(c.positions.size(), 181u);
  EXPECT_EQ(c.tets.size(), 596u);
  EXPECT_DOUBLE_EQ(c.ode.rayleigh_stiffness, 0.1);
  EXPECT_DOUBLE_EQ(fem_of(c).young_modulus_pa, 500.0);
  EXPECT_EQ(c.mass.kind, MassKind::kDiagonal);
  EXPECT_DOUBLE_EQ(c.mass.mass_density_kg_per_m3, 1.0);
  EXPECT_TRUE(s.models[0].visual_barycentric);
  EXPECT_GT(run_ten_steps(c), 0.0);
}

// ---- small scenes written to a temporary folder ------------------------------------------------

class SofaSceneFiles : public ::testing::Test {
 protected:
  void SetUp() override {
    dir_ = fs::temp_directory_path() / fmt_name(::testing::UnitTest::GetInstance()->current_test_info()->name());
    fs::create_directories(dir_);
    // One tetrahedron as a Gmsh v2 file.
    write("tet.msh",
          "$MeshFormat\n2.2 0 8\n$EndMeshFormat\n$Nodes\n4\n1 0 0 0\n2 1 0 0\n3 0 1 0\n4 0 0 1\n$EndNodes\n"
          "$Elements\n1\n1 4 2 0 1 1 2 3 4\n$EndElements\n");
  }
  void TearDown() override { fs::remove_all(dir_); }
  static std::string fmt_name(const char* test) { return std::string("hof_sofa_scene_") + test; }
  fs::path write(const std::string& name, const std::string& text) {
    std::ofstream(dir_ / name) << text;
    return dir_ / name;
  }
  Error read_error(const std::string& scene) {
    auto s = read_sofa_scene(write("scene.scn", scene));
    EXPECT_FALSE(s.has_value());
    return s ? Error{} : s.error();
  }
  fs::path dir_;
};

TEST_F(SofaSceneFiles, MalformedXmlReportsTheLine) {
  const Error e = read_error(
      "<Node name=\"root\">\n  <EulerImplicitSolver/>\n  <MechanicalObject position=\"0 0 0\"\n"
      "  <UniformMass/>\n</Node>\n");
  EXPECT_EQ(e.code, ErrorCode::kParse);
  EXPECT_EQ(e.line, 4);
  EXPECT_NE(e.message.find("malformed XML"), std::string::npos) << e.message;
  EXPECT_NE(e.file.find("scene.scn"), std::string::npos);
}

TEST_F(SofaSceneFiles, MissingMeshNamesThePath) {
  const Error e = read_error(
      "<Node name=\"root\">\n<Node name=\"body\">\n  <EulerImplicitSolver/>\n"
      "  <MeshGmshLoader name=\"loader\" filename=\"nowhere/missing.msh\"/>\n"
      "  <MechanicalObject src=\"@loader\"/>\n</Node>\n</Node>\n");
  EXPECT_EQ(e.code, ErrorCode::kIo);
  EXPECT_EQ(e.line, 4);
  EXPECT_NE(e.message.find("MeshGmshLoader 'loader'"), std::string::npos) << e.message;
  EXPECT_NE(e.message.find((dir_ / "nowhere/missing.msh").string()), std::string::npos) << e.message;
}

TEST_F(SofaSceneFiles, BadNumberNamesTheAttribute) {
  const Error e = read_error(
      "<Node name=\"root\">\n  <EulerImplicitSolver/>\n  <MeshGmshLoader name=\"l\" filename=\"tet.msh\"/>\n"
      "  <MechanicalObject src=\"@l\"/>\n"
      "  <TetrahedronFEMForceField name=\"FEM\" youngModulus=\"3e3x\"/>\n</Node>\n");
  EXPECT_EQ(e.line, 5);
  EXPECT_NE(e.message.find("TetrahedronFEMForceField 'FEM'"), std::string::npos) << e.message;
  EXPECT_NE(e.message.find("youngModulus"), std::string::npos) << e.message;
  EXPECT_NE(e.message.find("'3e3x'"), std::string::npos) << e.message;
}

TEST_F(SofaSceneFiles, UnknownLinkIsAnError) {
  const Error e = read_error(
      "<Node name=\"root\">\n  <EulerImplicitSolver/>\n  <MeshGmshLoader name=\"l\" filename=\"tet.msh\"/>\n"
      "  <MechanicalObject name=\"dofs\" position=\"@nothere.position\"/>\n</Node>\n");
  EXPECT_EQ(e.line, 4);
  EXPECT_NE(e.message.find("MechanicalObject 'dofs'"), std::string::npos) << e.message;
  EXPECT_NE(e.message.find("@nothere.position"), std::string::npos) << e.message;
}

TEST_F(SofaSceneFiles, FixedIndexOutOfRange) {
  const Error e = read_error(
      "<Node name=\"root\">\n  <EulerImplicitSolver/>\n  <MeshGmshLoader name=\"l\" filename=\"tet.msh\"/>\n"
      "  <MechanicalObject src=\"@l\"/>\n  <FixedProjectiveConstraint indices=\"0 4\"/>\n</Node>\n");
  EXPECT_EQ(e.line, 5);
  EXPECT_NE(e.message.find("node 4 out of range"), std::string::npos) << e.message;
}

TEST_F(SofaSceneFiles, ModelWithoutPositions) {
  const Error e =
      read_error("<Node name=\"root\">\n  <EulerImplicitSolver/>\n  <MechanicalObject name=\"dofs\"/>\n</Node>\n");
  EXPECT_EQ(e.line, 3);
  EXPECT_NE(e.message.find("no positions"), std::string::npos) << e.message;
}

TEST_F(SofaSceneFiles, LinksLoaderTransformAndSolvers) {
  auto s = read_sofa_scene(write(
      "scene.scn",
      "<Node name=\"root\" dt=\"0.005\" gravity=\"0 0 -9.81\">\n"
      "  <Node name=\"body\">\n"
      "    <StaticSolver newton_iterations=\"3\"/>\n"
      "    <SparseLDLSolver name=\"ldl\"/>\n"
      "    <MeshGmshLoader name=\"l\" filename=\"tet.msh\" translation=\"1 2 3\" rotation=\"0 0 90\" scale=\"2\"/>\n"
      "    <TetrahedronSetTopologyContainer name=\"topo\" tetrahedra=\"@l.tetrahedra\"/>\n"
      "    <MechanicalObject name=\"dofs\" position=\"@l.position\"/>\n"
      "    <UniformMass vertexMass=\"0.5\"/>\n"
      "    <MeshSpringForceField name=\"springs\" tetrasStiffness=\"100\" tetrasDamping=\"1\"/>\n"
      "    <ConstantForceField indices=\"1\" forces=\"0 0 1\"/>\n"
      "    <PartialFixedConstraint indices=\"0 2 3\" fixedDirections=\"1 1 1\"/>\n"
      "    <PartialFixedProjectiveConstraint indices=\"1\" fixedDirections=\"0 1 1\"/>\n"
      "  </Node>\n"
      "</Node>\n"));
  ASSERT_TRUE(s.has_value()) << s.error().to_string();
  ASSERT_EQ(s->models.size(), 1u);
  const auto& c = s->models[0].config;
  EXPECT_DOUBLE_EQ(c.dt_s, 0.005);  // inherited
  EXPECT_EQ(c.gravity_m_per_s2, Vec3(0, 0, -9.81));
  EXPECT_EQ(c.ode.kind, OdeSolverKind::kStatic);
  EXPECT_EQ(c.ode.newton_iterations, 3);
  EXPECT_EQ(c.linear.kind, LinearSolverKind::kSparseLdlt);
  ASSERT_EQ(c.positions.size(), 4u);
  // Node 2 (1,0,0): scaled to (2,0,0), turned 90° about z to (0,2,0), moved to (1,4,3).
  EXPECT_NEAR((c.positions[1] - Vec3(1, 4, 3)).norm(), 0.0, 1e-12);
  EXPECT_EQ(c.tets.size(), 1u);
  EXPECT_EQ(c.mass.kind, MassKind::kUniform);
  EXPECT_DOUBLE_EQ(*c.mass.vertex_mass_kg, 0.5);
  ASSERT_EQ(c.force_fields.size(), 2u);
  // tetrasStiffness (the older name of tetrahedraStiffness) sets the tetrahedra's kind, read
  // with SOFA's rule (each spring k/l, c/l) and its exact tangent.
  const mechanics::MeshSpringConfig& springs = *c.force_fields[0].mesh_springs;
  ASSERT_TRUE(springs.tetrahedra.has_value());
  EXPECT_DOUBLE_EQ(springs.tetrahedra->stiffness, 100.0);
  EXPECT_DOUBLE_EQ(springs.tetrahedra->damping, 1.0);
  EXPECT_EQ(springs.rule, mechanics::SpringStiffnessRule::kDividedByRestLength);
  EXPECT_EQ(springs.tangent, mechanics::SpringTangent::kExact);
  EXPECT_EQ(c.force_fields[1].constant_force->forces.at(0), Vec3(0, 0, 1));
  ASSERT_EQ(c.fixed.size(), 2u);
  EXPECT_EQ(c.fixed[1].directions, (std::array<bool, 3>{false, true, true}));
  EXPECT_TRUE(s->skipped.empty());
  EXPECT_TRUE(mechanics::build_model(c).has_value());
}

// HoF's extensions of CGLinearSolver: the two-level preconditioner and its refresh, read
// with the same checks as SOFA's own attributes.
TEST_F(SofaSceneFiles, TheCgsTwoLevelPreconditionerIsReadAndABadRefreshNamed) {
  auto scene = [](const std::string& cg) {
    return "<Node name=\"root\">\n  <EulerImplicitSolver/>\n  " + cg +
           "\n  <MeshGmshLoader name=\"l\" filename=\"tet.msh\"/>\n  <MechanicalObject src=\"@l\"/>\n</Node>\n";
  };
  auto s = read_sofa_scene(
      write("on.scn", scene("<CGLinearSolver name=\"cg\" coarseCorrection=\"true\" coarseRefreshSteps=\"40\"/>")));
  ASSERT_TRUE(s.has_value()) << s.error().to_string();
  EXPECT_TRUE(s->models.at(0).config.linear.coarse_correction);
  EXPECT_EQ(s->models.at(0).config.linear.coarse_refresh_steps, 40);
  auto plain = read_sofa_scene(write("off.scn", scene("<CGLinearSolver name=\"cg\"/>")));
  ASSERT_TRUE(plain.has_value()) << plain.error().to_string();
  EXPECT_FALSE(plain->models.at(0).config.linear.coarse_correction);  // SOFA's CG is unpreconditioned
  for (const char* bad : {"coarseRefreshSteps=\"0\"", "coarseRefreshSteps=\"2.5\"", "coarseCorrection=\"maybe\""}) {
    const Error e = read_error(scene(std::string("<CGLinearSolver name=\"cg\" ") + bad + "/>"));
    EXPECT_EQ(e.line, 3) << bad;
    EXPECT_NE(e.message.find("CGLinearSolver 'cg'"), std::string::npos) << e.message;
    const std::string attribute(bad, std::string_view(bad).find('='));
    EXPECT_NE(e.message.find(attribute), std::string::npos) << e.message;
  }
}

TEST_F(SofaSceneFiles, APlaceholderPositionTakesTheTopologysNodes) {
  // SOFA resizes a MechanicalObject to its node's topology: position="0 0 0" is a placeholder.
  auto s = read_sofa_scene(
      write("scene.scn",
            "<Node name=\"root\">\n  <Node name=\"body\">\n    <EulerImplicitSolver/>\n"
            "    <MeshGmshLoader name=\"l\" filename=\"tet.msh\"/>\n"
            "    <MeshTopology name=\"topo\" src=\"@l\"/>\n"
            "    <MechanicalObject name=\"dofs\" position=\"0 0 0\"/>\n"
            "    <TetrahedronFEMForceField youngModulus=\"1000\" poissonRatio=\"0.3\"/>\n  </Node>\n</Node>\n"));
  ASSERT_TRUE(s.has_value()) << s.error().to_string();
  ASSERT_EQ(s->models.size(), 1u);
  EXPECT_EQ(s->models[0].config.positions.size(), 4u);
  EXPECT_EQ(s->models[0].config.positions[3], Vec3(0, 0, 1));
  EXPECT_TRUE(mechanics::build_model(s->models[0].config).has_value());
}

TEST_F(SofaSceneFiles, LinksToAnObjLoadersOutputsReadItsFile) {
  write("tet.obj", "v 0 0 0\nv 1 0 0\nv 0 1 0\nv 0 0 1\nf 1 3 2\nf 1 2 4\nf 1 4 3\nf 2 3 4\n");
  auto s = read_sofa_scene(
      write("scene.scn",
            "<Node name=\"root\">\n  <Node name=\"body\">\n    <EulerImplicitSolver/>\n"
            "    <MeshGmshLoader name=\"l\" filename=\"tet.msh\"/>\n"
            "    <MeshOBJLoader name=\"ObjLoader\" filename=\"tet.obj\" translation=\"0 0 1\"/>\n"
            "    <MeshTopology name=\"topo\" tetrahedra=\"@l.tetrahedra\" edges=\"@l.edges\"/>\n"
            "    <MechanicalObject name=\"dofs\" position=\"@ObjLoader.position\"/>\n"
            "    <TetrahedronFEMForceField youngModulus=\"1000\" poissonRatio=\"0.3\"/>\n  </Node>\n</Node>\n"));
  ASSERT_TRUE(s.has_value()) << s.error().to_string();
  ASSERT_EQ(s->models.size(), 1u);
  ASSERT_EQ(s->models[0].config.positions.size(), 4u);
  EXPECT_EQ(s->models[0].config.positions[1], Vec3(1, 0, 1));  // the loader's translation applied
}

TEST_F(SofaSceneFiles, RelativeAndAbsoluteLinksResolveAsInSofa) {
  // The loader in a sibling node, reached by "@../", "@/root/..." and "@/..."; "@[-1]" is the
  // component just before.
  for (const std::string& link : {std::string("@../Data/l"), std::string("@/root/Data/l"), std::string("@/Data/l")}) {
    auto s = read_sofa_scene(
        write("scene.scn",
              "<Node name=\"root\">\n  <Node name=\"Data\">\n    <MeshGmshLoader name=\"l\" filename=\"tet.msh\"/>\n"
              "  </Node>\n  <Node name=\"body\">\n    <EulerImplicitSolver/>\n"
              "    <MeshTopology name=\"topo\" src=\"" +
                  link +
                  "\"/>\n"
                  "    <MechanicalObject name=\"dofs\" position=\"@[-1].position\"/>\n"
                  "    <TetrahedronFEMForceField youngModulus=\"1000\"/>\n  </Node>\n</Node>\n"));
    ASSERT_TRUE(s.has_value()) << link << ": " << s.error().to_string();
    ASSERT_EQ(s->models.size(), 1u);
    EXPECT_EQ(s->models[0].config.positions.size(), 4u) << link;
    EXPECT_EQ(s->models[0].config.tets.size(), 1u) << link;
  }
  // A link to a loader output that does not exist names the component, the attribute and data.
  const Error e = read_error(
      "<Node name=\"root\">\n  <EulerImplicitSolver/>\n  <MeshGmshLoader name=\"l\" filename=\"tet.msh\"/>\n"
      "  <MechanicalObject name=\"dofs\" position=\"@l.nosuchdata\"/>\n</Node>\n");
  EXPECT_EQ(e.line, 4);
  EXPECT_NE(e.message.find("MechanicalObject 'dofs'"), std::string::npos) << e.message;
  EXPECT_NE(e.message.find("nosuchdata"), std::string::npos) << e.message;
}

TEST_F(SofaSceneFiles, AMechanicalObjectTransformsItsPositions) {
  // rotation (degrees about x, then y, then z), then scale, then translation; and the legacy dx.
  auto s = read_sofa_scene(
      write("scene.scn",
            "<Node name=\"root\">\n  <Node name=\"body\">\n    <EulerImplicitSolver/>\n"
            "    <MeshGmshLoader name=\"l\" filename=\"tet.msh\"/>\n"
            "    <MechanicalObject name=\"dofs\" src=\"@l\" rotation=\"0 0 90\" scale3d=\"2 3 4\" "
            "translation=\"1 0 0\" dy=\"5\"/>\n"
            "    <TetrahedronFEMForceField youngModulus=\"1000\" poissonRatio=\"0.3\"/>\n  </Node>\n</Node>\n"));
  ASSERT_TRUE(s.has_value()) << s.error().to_string();
  const auto& x = s->models[0].config.positions;
  // (1,0,0) turned 90° about z: (0,1,0); scaled: (0,3,0); moved by (1,5,0): (1,8,0).
  EXPECT_NEAR((x[1] - Vec3(1, 8, 0)).norm(), 0.0, 1e-12);
  // (0,0,1): (0,0,1) → (0,0,4) → (1,5,4).
  EXPECT_NEAR((x[3] - Vec3(1, 5, 4)).norm(), 0.0, 1e-12);
  EXPECT_TRUE(s->warnings.empty() || std::none_of(s->warnings.begin(), s->warnings.end(), [](const std::string& w) {
                return w.find("ignored") != std::string::npos;
              }));
}

TEST_F(SofaSceneFiles, HexahedralGridsAreReadWithTheirFineSurfaceAndTheirErrorsNamed) {
  // A closed cube surface [0, 1]³, filled by a 4×4×4-node sparse grid inside the box
  // [0, 1]³ (27 cells), held by a BoxROI at z = 0.
  write("cube.obj",
        "v 0 0 0\nv 1 0 0\nv 1 1 0\nv 0 1 0\nv 0 0 1\nv 1 0 1\nv 1 1 1\nv 0 1 1\n"
        "f 1 3 2\nf 1 4 3\nf 5 6 7\nf 5 7 8\nf 1 2 6\nf 1 6 5\nf 2 3 7\nf 2 7 6\nf 3 4 8\nf 3 8 7\nf 4 1 5\nf 4 5 8\n");
  const auto scene = [&](const std::string& grid, const std::string& fem) {
    return "<Node name=\"root\" gravity=\"0 0 0\">\n  <Node name=\"Block\">\n    <EulerImplicitSolver/>\n    "
           "<CGLinearSolver/>\n" +
           grid +
           "\n    <MechanicalObject name=\"dofs\" position=\"0 0 0\"/>\n    <DiagonalMass massDensity=\"1000\"/>\n" +
           fem +
           "\n    <BoxROI name=\"roi\" box=\"-1 -1 -0.01 2 2 0.01\"/>\n"
           "    <FixedProjectiveConstraint indices=\"@roi.indices\"/>\n  </Node>\n</Node>\n";
  };
  auto s = read_sofa_scene(write(
      "scene.scn", scene("    <SparseGridTopology n=\"4 4 4\" fileTopology=\"cube.obj\" min=\"0 0 0\" max=\"1 1 1\"/>",
                         "    <HexahedronFEMForceField name=\"FEM\" youngModulus=\"3000\" method=\"polar\"/>")));
  ASSERT_TRUE(s.has_value()) << s.error().to_string();
  const mechanics::ModelConfig& c = s->models[0].config;
  EXPECT_EQ(c.positions.size(), 64u);  // the placeholder position gives way to the grid's
  EXPECT_EQ(c.hexahedra.size(), 27u);
  ASSERT_TRUE(c.force_fields[0].hexahedron_fem);
  EXPECT_EQ(c.force_fields[0].hexahedron_fem->method, mechanics::FemMethod::kPolar);
  ASSERT_TRUE(s->models[0].fine_surface);
  EXPECT_EQ(s->models[0].fine_surface->triangles.size(), 12u);
  ASSERT_EQ(c.fixed.size(), 1u);
  EXPECT_EQ(c.fixed[0].indices.size(), 16u);
  auto model = mechanics::build_model(c);
  ASSERT_TRUE(model.has_value()) << model.error().to_string();
  EXPECT_EQ(model->fixed_dofs.size(), 3u * 16u);      // the 16 nodes of the bottom face
  EXPECT_NEAR(model->total_mass_kg(), 1000.0, 1e-9);  // the cube's volume: no cell is cut by the surface

  // fillWeighted (SOFA's default): in the grid's own box (the surface's, 1% larger) the outer
  // cells are cut by the surface and count half (their stiffness).
  s = read_sofa_scene(write("scene.scn", scene("    <SparseGridTopology n=\"5 5 5\" fileTopology=\"cube.obj\"/>",
                                               "    <HexahedronFEMForceField name=\"FEM\" youngModulus=\"3000\"/>")));
  ASSERT_TRUE(s.has_value()) << s.error().to_string();
  const mechanics::ModelConfig& weighted = s->models[0].config;
  ASSERT_EQ(weighted.element_fill.size(), weighted.hexahedra.size());
  const auto halved = std::count(weighted.element_fill.begin(), weighted.element_fill.end(), 0.5);
  EXPECT_GT(halved, 0);
  EXPECT_EQ(halved + std::count(weighted.element_fill.begin(), weighted.element_fill.end(), 1.0),
            static_cast<std::ptrdiff_t>(weighted.hexahedra.size()));
  // The fill scales whatever modulus the field gets later: a <set> halves there too.
  mechanics::ModelConfig changed = weighted;
  ASSERT_TRUE(scene::set_parameter(changed, "FEM", "youngModulus", 1000.0));
  auto full = mechanics::build_model(changed);
  changed.element_fill.clear();
  auto unweighted = mechanics::build_model(changed);
  ASSERT_TRUE(full && unweighted);
  // SOFA's DiagonalMass lumps each whole cell (ρV/8 per corner): the fill weights stiffness
  // only (HexahedronFEMForceField's getStiffnessCoef), not the mass.
  EXPECT_NEAR(full->total_mass_kg(), unweighted->total_mass_kg(), 1e-12 * unweighted->total_mass_kg());

  // A regular grid: the box cut into (n − 1) cells per axis.
  s = read_sofa_scene(write("scene.scn", scene("    <RegularGridTopology n=\"3 2 2\" min=\"0 0 0\" max=\"2 1 1\"/>",
                                               "    <HexahedronFEMForceField/>")));
  ASSERT_TRUE(s.has_value()) << s.error().to_string();
  EXPECT_EQ(s->models[0].config.hexahedra.size(), 2u);
  EXPECT_EQ(s->models[0].config.positions.size(), 12u);
  EXPECT_FALSE(s->models[0].fine_surface);
  // The state's transform moves the grid (and a sparse grid's fine surface with it).
  std::string moved =
      scene("    <SparseGridTopology n=\"4 4 4\" fileTopology=\"cube.obj\"/>", "    <HexahedronFEMForceField/>");
  moved.replace(moved.find("position=\"0 0 0\""), 16, "translation=\"0 0 10\"");
  s = read_sofa_scene(write("scene.scn", moved));
  ASSERT_TRUE(s.has_value()) << s.error().to_string();
  double lowest = 1e9, lowest_surface = 1e9;
  for (const Vec3& p : s->models[0].config.positions) lowest = std::min(lowest, p.z());
  for (const Vec3& p : s->models[0].fine_surface->vertices) lowest_surface = std::min(lowest_surface, p.z());
  EXPECT_GT(lowest, 9.9);
  EXPECT_NEAR(lowest_surface, 10.0, 1e-12);
  EXPECT_TRUE(s->models[0].config.fixed.empty());  // the BoxROI at z = 0 holds nothing now...
  EXPECT_TRUE(std::ranges::any_of(s->warnings,
                                  [](const std::string& w) { return w.find("holds nothing") != std::string::npos; }));

  // Errors name the component and its line: a grid with no cell inside the surface, a
  // per-element list of the wrong length, a hexahedral force field without a grid.
  Error e = read_error(
      scene("    <SparseGridTopology name=\"grid\" n=\"4 4 4\" fileTopology=\"cube.obj\" min=\"5 5 5\" max=\"6 6 6\"/>",
            "    <HexahedronFEMForceField/>"));
  EXPECT_EQ(e.line, 5);
  EXPECT_NE(e.message.find("SparseGridTopology 'grid'"), std::string::npos) << e.message;
  EXPECT_NE(e.message.find("no cell inside the surface"), std::string::npos) << e.message;
  e = read_error(scene("    <SparseGridTopology n=\"4 4 4\" fileTopology=\"cube.obj\"/>",
                       "    <HexahedronFEMForceField name=\"FEM\" youngModulus=\"1 2 3\"/>"));
  EXPECT_EQ(e.line, 8);
  EXPECT_NE(e.message.find("3 values; one per hexahedron (27)"), std::string::npos) << e.message;
  e = read_error(
      "<Node name=\"root\">\n  <Node name=\"Liver\">\n    <EulerImplicitSolver/>\n"
      "    <MeshGmshLoader name=\"l\" filename=\"tet.msh\"/>\n    <MechanicalObject src=\"@l\"/>\n"
      "    <HexahedronFEMForceField youngModulus=\"3000\"/>\n  </Node>\n</Node>\n");
  EXPECT_EQ(e.code, ErrorCode::kUnsupported);
  EXPECT_EQ(e.line, 6);
  EXPECT_NE(e.message.find("needs a hexahedral topology"), std::string::npos) << e.message;
}

TEST_F(SofaSceneFiles, AMembraneIsReadWithSofasDefaultsAndItsPerElementLists) {
  write("quad.obj", "v 0 0 0\nv 1 0 0\nv 1 1 0\nv 0 1 0\nf 1 2 3\nf 1 3 4\n");
  auto s = read_sofa_scene(
      write("scene.scn",
            "<Node name=\"root\">\n  <Node name=\"Membrane\">\n    <EulerImplicitSolver/>\n"
            "    <MeshOBJLoader name=\"l\" filename=\"quad.obj\"/>\n"
            "    <TriangleSetTopologyContainer src=\"@l\"/>\n    <MechanicalObject src=\"@l\"/>\n"
            "    <DiagonalMass massDensity=\"2\"/>\n"
            "    <TriangleFEMForceField name=\"membrane\" thickness=\"0.002\" poissonRatio=\"0.3 0.4\"/>\n"
            "    <TriangularFEMForceField name=\"other\" method=\"small\"/>\n  </Node>\n</Node>\n"));
  ASSERT_TRUE(s.has_value()) << s.error().to_string();
  const mechanics::ModelConfig& c = s->models[0].config;
  ASSERT_EQ(c.triangles.size(), 2u);
  ASSERT_EQ(c.force_fields.size(), 2u);
  const auto& membrane = *c.force_fields[0].triangle_fem;
  EXPECT_EQ(membrane.sofa_type, "TriangleFEMForceField");
  EXPECT_DOUBLE_EQ(membrane.young_modulus_pa, 1000.0);  // SOFA's TriangleFEMForceField default
  EXPECT_DOUBLE_EQ(membrane.thickness_m, 0.002);
  EXPECT_EQ(membrane.element_poisson_ratio.size(), 2u);  // a list: per triangle
  const auto& other = *c.force_fields[1].triangle_fem;
  EXPECT_DOUBLE_EQ(other.young_modulus_pa, 5000.0);  // TriangularFEMForceField's
  EXPECT_DOUBLE_EQ(other.poisson_ratio, 0.45);
  EXPECT_EQ(other.method, mechanics::FemMethod::kSmall);
  auto model = mechanics::build_model(c);
  ASSERT_TRUE(model.has_value()) << model.error().to_string();
  EXPECT_NEAR(model->total_mass_kg(), 2.0, 1e-12);  // DiagonalMass on triangles: density × area

  const Error e = read_error(
      "<Node name=\"root\">\n  <Node name=\"Membrane\">\n    <EulerImplicitSolver/>\n"
      "    <MeshOBJLoader name=\"l\" filename=\"quad.obj\"/>\n    <MechanicalObject src=\"@l\"/>\n"
      "    <TriangleFEMForceField name=\"membrane\" youngModulus=\"1 2 3\"/>\n  </Node>\n</Node>\n");
  EXPECT_EQ(e.line, 6);
  EXPECT_NE(e.message.find("TriangleFEMForceField 'membrane'"), std::string::npos) << e.message;
  EXPECT_NE(e.message.find("3 values; one per triangle (2)"), std::string::npos) << e.message;
}

TEST_F(SofaSceneFiles, AComponentThatChangesTheResultIsAWarningOfItsOwnAndEachIsNamedOnce) {
  const std::string body =
      "    <EulerImplicitSolver/>\n    <MeshGmshLoader name=\"l\" filename=\"tet.msh\"/>\n"
      "    <MechanicalObject src=\"@l\"/>\n    <TetrahedronFEMForceField youngModulus=\"1000\"/>\n";
  auto s = read_sofa_scene(write("scene.scn",
                                 "<Node name=\"root\">\n  <RequiredPlugin name=\"p\"/>\n"
                                 "  <CollisionResponse name=\"response\"/>\n  <Node name=\"a\">\n" +
                                     body +
                                     "    <RestShapeSpringsForceField name=\"anchor\"/>\n  </Node>\n"
                                     "  <Node name=\"b\">\n" +
                                     body + "    <Mystery name=\"m\"/>\n  </Node>\n</Node>\n"));
  ASSERT_TRUE(s) << s.error().to_string();
  ASSERT_EQ(s->models.size(), 2u);
  // A collision response without a pipeline detects nothing (as in SOFA), said once; a force
  // field left out changes the result.
  const auto count = [&](const std::string& what) {
    return std::ranges::count_if(s->warnings, [&](const std::string& w) { return w.find(what) != std::string::npos; });
  };
  EXPECT_EQ(count("CollisionResponse 'response' (line 3): no CollisionPipeline in the scene"), 1);
  EXPECT_FALSE(s->contacts.enabled);
  EXPECT_EQ(count("RestShapeSpringsForceField 'anchor' (line 9) changes SOFA's result"), 1);
  // The others not simulated are listed together, each once; plugins only counted.
  EXPECT_EQ(count("Mystery 'm' (line 16)"), 1);
  EXPECT_EQ(count("CollisionResponse"), 1);
  EXPECT_EQ(count("RequiredPlugin"), 0);
  EXPECT_TRUE(contains(s->ignored, "RequiredPlugin 'p' (line 2)"));
}

// SOFA refuses a type its factory does not know; so does HoF, naming the line and the closest
// names (before: listed among "components not simulated", and the liver fell with no forces).
TEST_F(SofaSceneFiles, AMisspeltComponentIsRefusedWithTheLineAndTheClosestNames) {
  const Error e = read_error(
      "<Node name=\"root\">\n  <EulerImplicitSolver/>\n  <MeshGmshLoader name=\"l\" filename=\"tet.msh\"/>\n"
      "  <MechanicalObject src=\"@l\"/>\n"
      "  <TetrahedronFEMForceFeild name=\"FEM\" youngModulus=\"3000\"/>\n</Node>\n");
  EXPECT_EQ(e.code, ErrorCode::kParse);
  EXPECT_EQ(e.line, 5);
  EXPECT_NE(e.message.find("unknown component type 'TetrahedronFEMForceFeild'"), std::string::npos) << e.message;
  EXPECT_NE(e.message.find("did you mean TetrahedronFEMForceField"), std::string::npos) << e.message;
  // The 2008 syntax too.
  const Error old = read_error(
      "<Node name=\"root\">\n  <Object type=\"EulerImplicit\"/>\n  <Object type=\"MechanicalObjekt\"/>\n</Node>\n");
  EXPECT_EQ(old.line, 3);
  EXPECT_NE(old.message.find("did you mean MechanicalObject"), std::string::npos) << old.message;
  // Every component of the bundled and anchor scenes is known (none refused).
  for (const char* scene :
       {"/liver.scn", "/TutorialForceFieldLiverFEM.scn", "/history/2008-07-30_14f43fd649/liver.scn"}) {
    if (!fs::exists(kAnchors + scene)) continue;
    auto ok = read_sofa_scene(kAnchors + scene);
    EXPECT_TRUE(ok) << scene << ": " << (ok ? "" : ok.error().to_string());
  }
}

// A scene that requires a plugin from outside SOFA may use that plugin's components: they are
// named in a warning, not refused; a component of SOFA HoF does not simulate is listed as before.
TEST_F(SofaSceneFiles, AnUnknownTypeFromARequiredPluginIsAWarningNamingThePlugin) {
  auto s =
      read_sofa_scene(write("scene.scn",
                            "<Node name=\"root\">\n  <RequiredPlugin name=\"Geomagic\"/>\n"
                            "  <GeomagicDriver name=\"device\"/>\n  <EulerImplicitSolver/>\n"
                            "  <MeshGmshLoader name=\"l\" filename=\"tet.msh\"/>\n  <MechanicalObject src=\"@l\"/>\n"
                            "  <TetrahedronFEMForceField/>\n</Node>\n"));
  ASSERT_TRUE(s) << s.error().to_string();
  EXPECT_TRUE(contains(s->warnings, "presumably from the plugin(s) the scene requires (Geomagic)"))
      << s->warnings.front();
  EXPECT_TRUE(contains(s->warnings, "GeomagicDriver 'device' (line 3)"));
  // Without the plugin, the same type is refused.
  const Error e = read_error("<Node name=\"root\">\n  <GeomagicDriver name=\"device\"/>\n</Node>\n");
  EXPECT_EQ(e.line, 2);
  EXPECT_NE(e.message.find("unknown component type 'GeomagicDriver'"), std::string::npos) << e.message;
}

// SOFA warns about an attribute no data of the component takes; so does HoF, with the closest
// data name. The Triangle FEM tutorial writes totalmass (the data is totalMass).
TEST_F(SofaSceneFiles, AnUnknownAttributeIsAWarningNamingTheClosestData) {
  auto s = read_sofa_scene(
      write("scene.scn",
            "<Node name=\"root\">\n  <EulerImplicitSolver/>\n"
            "  <MeshGmshLoader name=\"l\" filename=\"tet.msh\"/>\n  <MechanicalObject src=\"@l\"/>\n"
            "  <UniformMass name=\"mass\" totalmass=\"0.5\"/>\n"
            "  <TetrahedronFEMForceField youngModulus=\"3000\" poissonRatio=\"0.3\" method=\"large\"/>\n</Node>\n"));
  ASSERT_TRUE(s) << s.error().to_string();
  EXPECT_TRUE(contains(s->warnings,
                       "scene.scn:5: UniformMass 'mass' (line 5): attribute 'totalmass' is not a data of "
                       "UniformMass and is ignored (SOFA ignores it too); did you mean 'totalMass'?"));
  // Ignored indeed: SOFA's default total mass of 1 kg.
  ASSERT_EQ(s->models.size(), 1u);
  EXPECT_DOUBLE_EQ(s->models[0].config.mass.total_mass_kg, 1.0);
  // The data the components take (and src, name, template) raise no warning.
  EXPECT_FALSE(contains(s->warnings, "youngModulus"));
  EXPECT_FALSE(contains(s->warnings, "'src'"));
  EXPECT_EQ(std::ranges::count_if(s->warnings,
                                  [](const std::string& w) { return w.find("is not a data of") != std::string::npos; }),
            1);
}

// A file the scene names is found as SOFA finds it: the scene's folder (and its parents), then
// SOFA_DATA_PATH, then share/ and examples/ under SOFA_ROOT; the error says where it looked.
TEST_F(SofaSceneFiles, FilesAreFoundThroughSofasDataPathAndTheErrorSaysWhereItLooked) {
  const std::string scene =
      "<Node name=\"root\">\n  <EulerImplicitSolver/>\n"
      "  <MeshGmshLoader name=\"l\" filename=\"mesh/liver.msh\"/>\n  <MechanicalObject src=\"@l\"/>\n"
      "  <TetrahedronFEMForceField/>\n</Node>\n";
  ::unsetenv("SOFA_DATA_PATH");
  ::unsetenv("SOFA_ROOT");
  Error e = read_error(scene);
  EXPECT_EQ(e.code, ErrorCode::kIo);
  EXPECT_NE(e.message.find("looked for " + (dir_ / "mesh/liver.msh").string()), std::string::npos) << e.message;
  EXPECT_NE(e.message.find("set SOFA_DATA_PATH or SOFA_ROOT"), std::string::npos) << e.message;
  // SOFA_DATA_PATH: a list of folders; the anchors' SOFA data folder holds mesh/liver.msh.
  const fs::path elsewhere = dir_ / "elsewhere";
  fs::create_directories(elsewhere);
  ::setenv("SOFA_DATA_PATH", (elsewhere.string() + ":" + kAnchors).c_str(), 1);
  auto s = read_sofa_scene(write("scene.scn", scene));
  ASSERT_TRUE(s) << s.error().to_string();
  EXPECT_EQ(s->models.at(0).config.positions.size(), 181u);
  // SOFA_ROOT: its share/ folder.
  ::unsetenv("SOFA_DATA_PATH");
  fs::create_directories(dir_ / "sofa/share/mesh");
  fs::copy_file(kAnchors + "/mesh/liver.msh", dir_ / "sofa/share/mesh/liver.msh");
  ::setenv("SOFA_ROOT", (dir_ / "sofa").c_str(), 1);
  s = read_sofa_scene(write("scene.scn", scene));
  ASSERT_TRUE(s) << s.error().to_string();
  EXPECT_EQ(s->models.at(0).config.positions.size(), 181u);
  // The error lists the data folders too.
  fs::remove(dir_ / "sofa/share/mesh/liver.msh");
  e = read_error(scene);
  EXPECT_NE(e.message.find((dir_ / "sofa/share").string()), std::string::npos) << e.message;
  ::unsetenv("SOFA_ROOT");
}

// SofaCUDA's templates hold the same 3D points: the scene is the CPU scene, with no warning.
TEST_F(SofaSceneFiles, ACudaTemplateIsSimulatedAsTheCpuSceneWithoutAWarning) {
  const auto scene = [&](const std::string& tmpl) {
    return "<Node name=\"root\">\n  <EulerImplicitSolver/>\n  <MeshGmshLoader name=\"l\" filename=\"tet.msh\"/>\n"
           "  <MechanicalObject template=\"" +
           tmpl + "\" src=\"@l\"/>\n  <UniformMass template=\"" + tmpl +
           "\" totalMass=\"2\"/>\n  <TetrahedronFEMForceField template=\"" + tmpl +
           "\" youngModulus=\"3000\"/>\n"
           "  <FixedProjectiveConstraint indices=\"0\"/>\n</Node>\n";
  };
  auto cpu = read_sofa_scene(write("cpu.scn", scene("Vec3d")));
  auto cuda = read_sofa_scene(write("cuda.scn", scene("CudaVec3f")));
  ASSERT_TRUE(cpu) << cpu.error().to_string();
  ASSERT_TRUE(cuda) << cuda.error().to_string();
  EXPECT_FALSE(contains(cuda->warnings, "CudaVec3f")) << (cuda->warnings.empty() ? "" : cuda->warnings.front());
  ASSERT_EQ(cuda->models.size(), 1u);
  EXPECT_EQ(cuda->models[0].config.positions, cpu->models.at(0).config.positions);
  EXPECT_EQ(cuda->models[0].config.tets, cpu->models.at(0).config.tets);
  EXPECT_DOUBLE_EQ(run_ten_steps(cuda->models[0].config), run_ten_steps(cpu->models[0].config));
  // A rigid state is not a body, and says so.
  auto rigid = read_sofa_scene(write("rigid.scn", scene("Rigid3d")));
  ASSERT_TRUE(rigid) << rigid.error().to_string();
  EXPECT_TRUE(contains(rigid->warnings, "template Rigid3d is not simulated"));
}

// A mass in a node that is not a body of HoF's (SOFA's Geomagic scene's instrument, a rigid
// state) is not "a second mass": no such warning, the instrument's state says why once.
TEST_F(SofaSceneFiles, TheInstrumentsMassIsNotCalledASecondMass) {
  auto s =
      read_sofa_scene(write("scene.scn",
                            "<Node name=\"root\">\n  <Node name=\"Liver\">\n  <EulerImplicitSolver/>\n"
                            "  <MeshGmshLoader name=\"l\" filename=\"tet.msh\"/>\n  <MechanicalObject src=\"@l\"/>\n"
                            "  <DiagonalMass massDensity=\"1\"/>\n  <TetrahedronFEMForceField/>\n  </Node>\n"
                            "  <Node name=\"Instrument\">\n  <EulerImplicitSolver/>\n"
                            "  <MechanicalObject name=\"instrumentState\" template=\"Rigid3d\"/>\n"
                            "  <UniformMass name=\"mass\" totalMass=\"0.5\"/>\n  </Node>\n</Node>\n"));
  ASSERT_TRUE(s) << s.error().to_string();
  EXPECT_EQ(s->models.size(), 1u);
  EXPECT_FALSE(contains(s->warnings, "second mass"));
  EXPECT_TRUE(contains(s->warnings, "template Rigid3d is not simulated"));
  EXPECT_TRUE(contains(s->skipped, "UniformMass 'mass' (line 12)"));
  // A second mass in a body's own node is one, and is said.
  auto twice =
      read_sofa_scene(write("twice.scn",
                            "<Node name=\"root\">\n  <EulerImplicitSolver/>\n"
                            "  <MeshGmshLoader name=\"l\" filename=\"tet.msh\"/>\n  <MechanicalObject src=\"@l\"/>\n"
                            "  <DiagonalMass massDensity=\"1\"/>\n  <UniformMass name=\"extra\"/>\n"
                            "  <TetrahedronFEMForceField/>\n</Node>\n"));
  ASSERT_TRUE(twice) << twice.error().to_string();
  EXPECT_TRUE(contains(twice->warnings, "second mass"));
}

TEST_F(SofaSceneFiles, CgImplicitOf2008IsImplicitEulerWithCg) {
  auto s = read_sofa_scene(write("scene.scn",
                                 "<Node name=\"root\" dt=\"0.02\">\n"
                                 "  <Object type=\"CGImplicit\" iterations=\"10\"/>\n"
                                 "  <Object type=\"Mesh\" name=\"m\" filename=\"tet.msh\"/>\n"
                                 "  <Object type=\"MechanicalObject\"/>\n"
                                 "  <Object type=\"UniformMass\" totalMass=\"2\"/>\n"
                                 "  <Object type=\"FixedConstraint\" fixAll=\"1\"/>\n"
                                 "</Node>\n"));
  ASSERT_TRUE(s.has_value()) << s.error().to_string();
  ASSERT_EQ(s->models.size(), 1u);
  const auto& c = s->models[0].config;
  EXPECT_EQ(c.ode.kind, OdeSolverKind::kEulerImplicit);
  EXPECT_DOUBLE_EQ(c.ode.rayleigh_stiffness, 0.1);
  EXPECT_DOUBLE_EQ(c.ode.rayleigh_mass, 0.1);
  EXPECT_EQ(c.linear.kind, LinearSolverKind::kConjugateGradient);
  EXPECT_EQ(c.linear.iterations, 10);
  EXPECT_DOUBLE_EQ(c.linear.tolerance, 1e-5);
  EXPECT_EQ(c.tets.size(), 1u);
  EXPECT_TRUE(c.fixed.at(0).fix_all);
  EXPECT_TRUE(contains(s->warnings, "Rayleigh defaults"));
}

// HoF's extensions of MeshSpringForceField: its own spring rule (the same stiffness for every
// spring, the clamped tangent) read without a warning; a value outside the two is named.
TEST(SofaScene, SpringsTakeHofsRuleAsAnExtension) {
  auto scene = [](const std::string& extra) {
    return "<Node name=\"root\">\n  <EulerImplicitSolver/>\n  <CGLinearSolver/>\n"
           "  <MechanicalObject position=\"0 0 0 1 0 0 0 1 0 0 0 1\"/>\n  <MeshTopology tetrahedra=\"0 1 2 3\"/>\n"
           "  <UniformMass/>\n  <MeshSpringForceField stiffness=\"10\" " +
           extra + "/>\n</Node>\n";
  };
  auto hof =
      read_sofa_scene_text(scene("stiffnessRule=\"sameForEverySpring\" tangent=\"clampedTransverse\""), "hof.scn");
  ASSERT_TRUE(hof.has_value()) << hof.error().to_string();
  EXPECT_TRUE(hof->warnings.empty());
  const mechanics::MeshSpringConfig& springs = *hof->models.at(0).config.force_fields.at(0).mesh_springs;
  EXPECT_EQ(springs.rule, mechanics::SpringStiffnessRule::kSameForEverySpring);
  EXPECT_EQ(springs.tangent, mechanics::SpringTangent::kClampedTransverse);
  auto sofa = read_sofa_scene_text(scene("stiffnessRule=\"dividedByRestLength\" tangent=\"exact\""), "sofa.scn");
  ASSERT_TRUE(sofa.has_value()) << sofa.error().to_string();
  EXPECT_EQ(sofa->models.at(0).config.force_fields.at(0).mesh_springs->rule,
            mechanics::SpringStiffnessRule::kDividedByRestLength);
  EXPECT_EQ(sofa->models.at(0).config.force_fields.at(0).mesh_springs->tangent, mechanics::SpringTangent::kExact);
  auto bad = read_sofa_scene_text(scene("stiffnessRule=\"perSpring\""), "bad.scn");
  ASSERT_FALSE(bad.has_value());
  EXPECT_NE(bad.error().message.find("stiffnessRule: 'perSpring'"), std::string::npos) << bad.error().message;
}

}  // namespace
}  // namespace hof::scene
