// SOFA scenes as worlds, as a new user meets them: SOFA's membrane tutorial (a visual model
// mapped onto triangles), the default probe on every bundled and anchor scene (under the
// device's limit), and the bundled needle example (the force a hand must feel).

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <cstdlib>
#include <filesystem>
#include <fstream>

#include "hof/coupling/session.h"
#include "hof/haptics/device.h"
#include "hof/mesh/mesh_io.h"
#include "hof/procedures/needle_model.h"
#include "hof/scene/device_config.h"
#include "hof/scene/project.h"
#include "hof/scene/world.h"

namespace hof::scene {
namespace {

namespace fs = std::filesystem;
const std::string kAnchors = HOF_ANCHORS_DIR;
const fs::path kExamples = fs::path(HOF_SOURCE_DIR) / "examples";

fs::path write(const std::string& name, const std::string& text) {
  const fs::path dir = fs::temp_directory_path() / "hof_sofa_world_test";
  fs::create_directories(dir);
  std::ofstream(dir / name, std::ios::binary) << text;
  return dir / name;
}

// SOFA's TutorialForceFieldLiverTriangleFEM.scn, as SOFA ships it (its mesh files from SOFA's
// data repository, here the anchors' copy through SOFA_DATA_PATH).
const char* kTriangleTutorial = R"(<?xml version="1.0" ?>
<Node name="root" gravity="0 -9.81 0" dt="0.02">
    <VisualStyle displayFlags="showForceFields" />
    <DefaultPipeline name="CollisionPipeline" verbose="0" />
    <BruteForceDetection name="N2" />
    <DefaultContactManager name="collision response" response="default" />
    <Node name="LiverTriangles" gravity="0 -9.81 0" depend="topo dofs">
        <EulerImplicitSolver name="cg_odesolver" printLog="0" />
        <CGLinearSolver template="GraphScattered" name="linear solver" iterations="25" tolerance="1e-09" threshold="1e-09" />
        <MeshTopology name="mesh" fileTopology="mesh/liver-smooth.obj" />
        <MechanicalObject template="Vec3d" name="dofs" />
        <TriangleFEMForceField template="Vec3d" />
        <UniformMass template="Vec3d" name="mass" totalmass="0.5" />
        <FixedConstraint template="Vec3d" name="FixedConstraint" indices="3 39 64" />
        <Node name="Visu" gravity="0 -9.81 0">
            <OglModel template="ExtVec3f" name="VisualModel" fileMesh="mesh/liver-smooth.obj" />
            <BarycentricMapping template="Mapping&lt;Vec3d,ExtVec3f&gt;" name="visual mapping" object1="../.." object2="VisualModel" />
        </Node>
        <Node name="Surf" gravity="0 -9.81 0">
            <SphereLoader filename="mesh/liver.sph" />
            <MechanicalObject position="@[-1].position" />
            <SphereModel name="CollisionModel" listRadius="@[-2].listRadius" />
            <BarycentricMapping name="sphere mapping" />
        </Node>
    </Node>
</Node>
)";

TEST(SofaWorld, SofasMembraneTutorialMapsItsVisualModelOntoTheTriangles) {
  ::setenv("SOFA_DATA_PATH", (kAnchors + "/sofa").c_str(), 1);
  auto world = build_world(write("TutorialForceFieldLiverTriangleFEM.scn", kTriangleTutorial));
  ::unsetenv("SOFA_DATA_PATH");
  ASSERT_TRUE(world) << world.error().to_string();
  // Every warning true: totalmass is ignored (as SOFA does); the collision spheres' mapping is
  // part of the collision model, not a mapping whose loss changes the result.
  EXPECT_TRUE(std::ranges::any_of(world->warnings,
                                  [](const std::string& w) { return w.find("'totalmass'") != std::string::npos; }));
  EXPECT_FALSE(std::ranges::any_of(world->warnings, [](const std::string& w) {
    return w.find("sphere mapping' (line 24) changes") != std::string::npos;
  }));
  ASSERT_EQ(world->bodies.size(), 1u);
  const coupling::SessionBody& body = world->bodies[0];
  ASSERT_TRUE(body.deformable());
  EXPECT_TRUE(body.model->tets.empty());
  EXPECT_FALSE(body.model->triangles.empty());
  // The visual surface is the same file as the topology: every vertex maps onto itself.
  auto visual = mesh::read_mesh(kAnchors + "/sofa/mesh/liver-smooth.obj");
  ASSERT_TRUE(visual);
  ASSERT_EQ(body.surface.vertices.size(), visual->mesh.nodes.size());
  std::vector<Vec3> mapped(body.surface.vertices.size());
  std::vector<double> rest;
  for (const Vec3& p : body.model->rest_positions) rest.insert(rest.end(), {p.x(), p.y(), p.z()});
  body.mapping.apply(rest, mapped);
  double worst = 0.0;
  for (std::size_t v = 0; v < mapped.size(); ++v) worst = std::max(worst, (mapped[v] - visual->mesh.nodes[v]).norm());
  EXPECT_LT(worst, 1e-9);
  // The mapping follows the membrane: move one node and the vertices on it move with it.
  rest[0] += 0.5;
  body.mapping.apply(rest, mapped);
  EXPECT_NEAR(mapped[0].x() - visual->mesh.nodes[0].x(), 0.5, 1e-9);
}

// The default probe presses to a force as well as to a depth: on every bundled and anchor
// scene it never rides the device's safety clamp (before: 42% of the contact on SOFA's
// Geomagic liver, 92% on a 2008 anchor scene).
TEST(SofaWorld, TheDefaultProbeStaysUnderTheDeviceLimitOnEveryBundledAndAnchorScene) {
  std::vector<fs::path> scenes{kAnchors + "/sofa/liver.scn", kAnchors + "/sofa/TutorialForceFieldLiverFEM.scn",
                               kAnchors + "/sofa/history/2008-07-30_14f43fd649/liver.scn",
                               kAnchors + "/sofa/history/2008-10-17_ceddbfd360/liver.scn"};
  for (const char* example : {"liver-simple-springs.scn", "liver-coarse-springs.scn", "liver-medium-fem.scn",
                              "liver-medium-sparse-grid.scn", "liver-medium-springs.scn", "needle-cube.scn"})
    scenes.push_back(kExamples / example);
  int pressed = 0;
  for (const fs::path& scene : scenes) {
    SCOPED_TRACE(scene.string());
    auto world = build_world(scene);
    ASSERT_TRUE(world) << world.error().to_string();
    ASSERT_TRUE(world->default_probe);
    auto device = scene::open_device(world->device);
    ASSERT_TRUE(device) << device.error().to_string();
    const double limit = (*device)->spec().max_force_n;
    coupling::SessionConfig config = world->config;
    config.haptics.realtime_priority = false;
    auto session = coupling::Session::make(std::move(world->bodies), std::move(*device), config);
    ASSERT_TRUE(session) << session.error().to_string();
    double peak = 0.0;
    const coupling::SessionReport report = (*session)->run_virtual(
        world->probe_press_s, [&](const haptics::HapticSample& s) { peak = std::max(peak, s.requested_force.norm()); });
    EXPECT_GT(report.contact_time_s, 0.5) << "the probe must touch";
    EXPECT_EQ(report.clamped_contact_ticks, 0);
    EXPECT_LT(peak, limit);
    pressed += report.contact_time_s > 0.5 ? 1 : 0;
  }
  EXPECT_EQ(pressed, static_cast<int>(scenes.size()));
}

// examples/needle-liver.hof as a user runs it: after the capsule breaks the hand is pushed
// back (before: -3.37 N drew the needle in, eight times the puncture force).
TEST(SofaWorld, TheBundledNeedleResistsInsertionAfterThePuncture) {
  auto world = build_world(kExamples / "needle-liver.hof");
  ASSERT_TRUE(world) << world.error().to_string();
  auto device = scene::open_device(world->device);
  ASSERT_TRUE(device) << device.error().to_string();
  coupling::SessionConfig config = world->config;
  config.haptics.realtime_priority = false;
  auto session = coupling::Session::make(std::move(world->bodies), std::move(*device), config);
  ASSERT_TRUE(session) << session.error().to_string();
  double last_pre = 0.0, first_post = -1.0, min_post = 1e9;
  int post = 0;
  procedures::NeedlePhase previous = procedures::NeedlePhase::kFree;
  (*session)->run_virtual(6.0, [&](const haptics::HapticSample& s) {
    const auto phase = static_cast<procedures::NeedlePhase>(s.tool.phase);
    if (phase == procedures::NeedlePhase::kPrePuncture) last_pre = s.tool.axial_force_n;
    if (phase == procedures::NeedlePhase::kPunctured) {
      if (previous == procedures::NeedlePhase::kPrePuncture) first_post = s.tool.axial_force_n;
      min_post = std::min(min_post, s.tool.axial_force_n);
      ++post;
    }
    previous = phase;
  });
  ASSERT_GT(post, 100);
  EXPECT_GT(last_pre, 0.05);
  EXPECT_LT(first_post, 0.7 * last_pre);  // the drop at the puncture
  EXPECT_GT(min_post, 0.0);               // resisting, never drawing the needle in
}

// A project states its scene's unit; unstated, a SOFA scene is in "scene units" whether bare
// or under a project (before: a project over SOFA's liver, 6 units across, reported "604 mm").
TEST(SofaWorld, AProjectStatesItsUnitAndASofaSceneIsNeverPresumedMetres) {
  auto poke = build_world(kExamples / "sofa-liver-poke.hof");
  ASSERT_TRUE(poke) << poke.error().to_string();
  EXPECT_EQ(poke->length_unit, "scene units");
  auto bare = build_world(kExamples / "liver-medium-fem.scn");
  ASSERT_TRUE(bare) << bare.error().to_string();
  EXPECT_EQ(bare->length_unit, "scene units");
  auto stated = build_world(kExamples / "liver-palpation-medium-fem.hof");
  ASSERT_TRUE(stated) << stated.error().to_string();
  EXPECT_EQ(stated->length_unit, "m");
  // The same project without its unit: scene units, and saved with what it states.
  HofProject project = *read_project(kExamples / "liver-palpation-medium-fem.hof");
  EXPECT_EQ(project.scene_unit, "m");
  project.scene_unit.clear();
  auto unstated = build_world(project, kExamples / "liver-palpation-medium-fem.hof");
  ASSERT_TRUE(unstated) << unstated.error().to_string();
  EXPECT_EQ(unstated->length_unit, "scene units");
  // An X3D scene is in metres (the X3D standard's unit).
  auto x3d = build_world(
      write("box.x3d", "<X3D><Scene><Shape><Appearance><SmoothSurface/></Appearance><Box/></Shape></Scene></X3D>"));
  ASSERT_TRUE(x3d) << x3d.error().to_string();
  EXPECT_EQ(x3d->length_unit, "m");
}

}  // namespace
}  // namespace hof::scene
