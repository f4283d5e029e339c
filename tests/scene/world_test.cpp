// The one builder: X3D geometry touched where H3D draws it, rigid and deformable bodies,
// effect-only worlds, SOFA scenes with several bodies, project parameters, the default probe.

#include "hof/scene/world.h"
#include "hof/scene/device_config.h"

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <filesystem>
#include <fstream>

#include "hof/haptics/device_backends/scripted_device.h"
#include "hof/procedures/needle.h"
#include "hof/scene/model_parameters.h"

namespace hof::scene {
namespace {

namespace fs = std::filesystem;

fs::path write(const std::string& name, const std::string& text) {
  const fs::path dir = fs::temp_directory_path() / "hof_world_test";
  fs::create_directories(dir);
  const fs::path file = dir / name;
  std::ofstream(file, std::ios::binary) << text;
  return file;
}

std::string x3d(const std::string& body) {
  return "<X3D profile='H3DAPI' version='1.4'><Scene>\n" + body + "\n</Scene></X3D>\n";
}

// A touchable shape's appearance.
const std::string kSurface = "<Appearance><Material/><SmoothSurface stiffness='0.5'/></Appearance>";

struct Touch {
  bool contact{false};
  Vec3 proxy{Vec3::Zero()};
  std::int32_t body{-1};
};

// Presses the world from `start` along `direction` (3 mm past the first surface, god-object
// proxy, device frame = world frame) and reports where the proxy rests during the hold.
Touch touch(const fs::path& file, const Vec3& start, const Vec3& direction, double approach) {
  auto built = build_world(file);
  EXPECT_TRUE(built) << built.error().to_string();
  World world = std::move(*built);
  const haptics::MotionConfig motion = haptics::MotionConfig::poke(start, direction, approach, 0.003, 0.05, 0.3);
  auto scripted = haptics::ScriptedMotion::make(motion);
  EXPECT_TRUE(scripted);
  coupling::SessionConfig config = world.config;
  config.haptics.renderer.kind = haptics::RendererKind::kGodObject;
  config.haptics.calibration = haptics::Calibration{};
  config.haptics.realtime_priority = false;
  auto session =
      coupling::Session::make(std::move(world.bodies), std::make_unique<haptics::ScriptedDevice>(*scripted), config);
  EXPECT_TRUE(session) << session.error().to_string();
  Touch t;
  const double hold_start = (approach + 0.003) / 0.05 + 0.05;
  (*session)->run_virtual(hold_start + 0.2, [&](const haptics::HapticSample& s) {
    if (s.time_s < hold_start || !s.contact) return;
    t.contact = true;
    t.proxy = s.proxy;
    t.body = (*session)->body_of_triangle(s.triangle, s.layer);
  });
  return t;
}

TEST(World, X3dShapeIsRigidAndTouchedWhereTransformAndScalePlaceIt) {
  // A 2 cm box scaled 2x and moved 10 cm along x: top face at y = 0.02 over x in [0.08, 0.12].
  const auto file = write("transform.x3d", x3d("<Transform translation='0.1 0 0' scale='2 2 2'><Shape>" + kSurface +
                                               "<Box size='0.02 0.02 0.02'/></Shape></Transform>"));
  auto world = build_world(file);
  ASSERT_TRUE(world) << world.error().to_string();
  ASSERT_EQ(world->bodies.size(), 1u);
  EXPECT_FALSE(world->bodies[0].deformable()) << "a plain Shape must stay rigid";
  const Touch t = touch(file, Vec3(0.1, 0.1, 0.0), Vec3(0, -1, 0), 0.08);
  ASSERT_TRUE(t.contact);
  EXPECT_NEAR(t.proxy.y(), 0.02, 1e-4);
  EXPECT_NEAR(t.proxy.x(), 0.1, 1e-4);
}

TEST(World, X3dRotationAndCentreAreAppliedAsH3dDoes) {
  // Box rotated half a turn about the z axis through (0.01, 0, 0): its centre goes to x = 0.02.
  const auto file = write("centre.x3d", x3d("<Transform center='0.01 0 0' rotation='0 0 1 3.14159265358979'><Shape>" +
                                            kSurface + "<Box size='0.02 0.02 0.02'/></Shape></Transform>"));
  auto world = build_world(file);
  ASSERT_TRUE(world) << world.error().to_string();
  const Touch hit = touch(file, Vec3(0.025, 0.1, 0.0), Vec3(0, -1, 0), 0.09);
  ASSERT_TRUE(hit.contact);
  EXPECT_NEAR(hit.proxy.y(), 0.01, 1e-4);
  // Where the box was before the rotation there is nothing.
  const Touch miss = touch(file, Vec3(-0.005, 0.1, 0.0), Vec3(0, -1, 0), 0.09);
  EXPECT_FALSE(miss.contact);
}

TEST(World, X3dNestedRotationMovesASphere) {
  // A 1 cm sphere 5 cm along local x, the frame turned a quarter turn about z: centre at
  // (0, 0.05, 0), top at y = 0.06 (the tessellation reaches the local ±x exactly).
  const auto file =
      write("sphere.x3d", x3d("<Transform rotation='0 0 1 1.5707963267949'><Transform translation='0.05 0 0'>"
                              "<Shape>" +
                              kSurface + "<Sphere radius='0.01'/></Shape></Transform></Transform>"));
  auto world = build_world(file);
  ASSERT_TRUE(world) << world.error().to_string();
  const Touch t = touch(file, Vec3(0.0, 0.1, 0.0), Vec3(0, -1, 0), 0.04);
  ASSERT_TRUE(t.contact);
  EXPECT_NEAR(t.proxy.y(), 0.06, 1e-4);
}

TEST(World, X3dPrimitivesAreTouchedOnTheirSurfaces) {
  // Cylinder (height 4 cm: cap at y = 0.02) at x = 0, cone (apex at y = 0.02) at x = 0.1,
  // an IndexedFaceSet quad at y = 0.01 around x = 0.2.
  const auto file = write("primitives.x3d", x3d("<Shape>" + kSurface +
                                                "<Cylinder radius='0.01' height='0.04'/></Shape>"
                                                "<Transform translation='0.1 0 0'><Shape>" +
                                                kSurface +
                                                "<Cone bottomRadius='0.02' height='0.04'/></Shape></Transform>"
                                                "<Shape>" +
                                                kSurface +
                                                "<IndexedFaceSet solid='false' coordIndex='0 1 2 3 -1'>"
                                                "<Coordinate point='0.19 0.01 -0.01  0.19 0.01 0.01  0.21 0.01 0.01  "
                                                "0.21 0.01 -0.01'/></IndexedFaceSet></Shape>"));
  auto world = build_world(file);
  ASSERT_TRUE(world) << world.error().to_string();
  ASSERT_EQ(world->bodies.size(), 3u);
  const Touch cylinder = touch(file, Vec3(0.002, 0.1, 0.0), Vec3(0, -1, 0), 0.08);
  ASSERT_TRUE(cylinder.contact);
  EXPECT_NEAR(cylinder.proxy.y(), 0.02, 1e-4);
  EXPECT_EQ(cylinder.body, 0);
  // The cone's side 5 mm off its axis (y = 0.01 there): the frictionless proxy slides on the
  // slope, and stays on it (radius r from the axis: y = 0.02 − 2r, the 32-gon within 0.5%).
  const Touch cone = touch(file, Vec3(0.105, 0.1, 0.0), Vec3(0, -1, 0), 0.09);
  ASSERT_TRUE(cone.contact);
  const double r = std::hypot(cone.proxy.x() - 0.1, cone.proxy.z());
  EXPECT_NEAR(cone.proxy.y(), 0.02 - 2.0 * r, 3e-4);
  EXPECT_EQ(cone.body, 1);
  const Touch face = touch(file, Vec3(0.2, 0.1, 0.0), Vec3(0, -1, 0), 0.09);
  ASSERT_TRUE(face.contact);
  EXPECT_NEAR(face.proxy.y(), 0.01, 1e-4);
  EXPECT_EQ(face.body, 2);
}

TEST(World, X3dUseOfAShapeIsTouchedInEachPlace) {
  const auto file = write("use.x3d", x3d("<Shape DEF='Block'>" + kSurface +
                                         "<Box size='0.02 0.02 0.02'/></Shape>"
                                         "<Transform translation='0.1 0.05 0'><Shape USE='Block'/></Transform>"));
  auto world = build_world(file);
  ASSERT_TRUE(world) << world.error().to_string();
  ASSERT_EQ(world->bodies.size(), 2u);
  EXPECT_EQ(world->bodies[0].name, "Block");
  EXPECT_EQ(world->bodies[1].name, "Block#2") << "bodies are addressed by name: a USE'd shape gets its own";
  const Touch first = touch(file, Vec3(0.0, 0.1, 0.0), Vec3(0, -1, 0), 0.09);
  ASSERT_TRUE(first.contact);
  EXPECT_NEAR(first.proxy.y(), 0.01, 1e-4);
  const Touch second = touch(file, Vec3(0.1, 0.1, 0.0), Vec3(0, -1, 0), 0.04);
  ASSERT_TRUE(second.contact);
  EXPECT_NEAR(second.proxy.y(), 0.06, 1e-4);
  EXPECT_EQ(second.body, 1);
}

TEST(World, X3dHapticLayersHaveAProxyEachAndTheirForcesAdd) {
  // H3D's layered example, softened: a 10 cm box (60 N/m) over a 3 cm sphere (300 N/m). Pressed
  // 3 cm into the box, the device is 1 cm into the sphere: each layer's proxy rests on its own
  // surface and the force is the sum, 60 × 0.03 + 300 × 0.01 = 4.8 N.
  const auto file =
      write("layers.x3d",
            x3d("<HapticLayeredGroup><Shape><Appearance><SmoothSurface stiffness='60' useRelativeValues='false'/>"
                "</Appearance><Box size='0.1 0.1 0.1'/></Shape><Shape><Appearance><SmoothSurface "
                "stiffness='300' useRelativeValues='false'/></Appearance><Sphere radius='0.03'/></Shape>"
                "</HapticLayeredGroup>"));
  auto world = build_world(file);
  ASSERT_TRUE(world) << world.error().to_string();
  ASSERT_EQ(world->bodies.size(), 2u);
  EXPECT_EQ(world->bodies[0].layer, 0);
  EXPECT_EQ(world->bodies[1].layer, 1);
  const haptics::MotionConfig motion =
      haptics::MotionConfig::poke(Vec3(0.0, 0.1, 0.0), Vec3(0, -1, 0), 0.05, 0.03, 0.05, 0.3);
  coupling::SessionConfig config = world->config;
  config.haptics.renderer.kind = haptics::RendererKind::kGodObject;
  config.haptics.calibration = haptics::Calibration{};
  config.haptics.realtime_priority = false;
  auto session = coupling::Session::make(
      std::move(world->bodies), std::make_unique<haptics::ScriptedDevice>(*haptics::ScriptedMotion::make(motion)),
      config);
  ASSERT_TRUE(session) << session.error().to_string();
  EXPECT_EQ((*session)->layer_count(), 2u);
  int only_box = 0, both = 0;
  (*session)->run_virtual(2.0, [&](const haptics::HapticSample& s) {
    if (!s.valid || !s.contact) return;
    const double y = s.device.y();
    EXPECT_NEAR((*session)->haptic_loop().renderer(0).contact().proxy.y(), 0.05, 1e-4);
    if (y > 0.031 && y < 0.049) {
      ++only_box;
      EXPECT_NEAR(s.force.y(), 60.0 * (0.05 - y), 1e-3) << "y = " << y;
    } else if (y < 0.0205) {
      ++both;
      // 0.05 N: the god-object on the tessellated sphere's pole (a fan of 32 facets, three
      // constraint planes at a time) settles up to 0.1 mm below the exact pole.
      EXPECT_NEAR(s.force.y(), 60.0 * (0.05 - y) + 300.0 * (0.03 - y), 0.05) << "y = " << y;
    }
  });
  EXPECT_GT(only_box, 100);
  EXPECT_GT(both, 200);
}

TEST(World, X3dDeformableShapeIsSimulatedAndItsDefaultsAreListed) {
  const auto file = write("deformable.x3d",
                          x3d("<DeformableShape><CoordinateDeformer/>" + kSurface +
                              "<IndexedFaceSet solid='false' coordIndex='0 1 4 3 -1 1 2 5 4 -1 3 4 7 6 -1 4 5 8 7 -1'>"
                              "<Coordinate point='-0.02 0 -0.02  0 0 -0.02  0.02 0 -0.02  -0.02 0 0  0 0 0  0.02 0 0  "
                              "-0.02 0 0.02  0 0 0.02  0.02 0 0.02'/></IndexedFaceSet></DeformableShape>"));
  auto world = build_world(file);
  ASSERT_TRUE(world) << world.error().to_string();
  ASSERT_EQ(world->bodies.size(), 1u);
  EXPECT_TRUE(world->bodies[0].deformable());
  bool listed = false;
  for (const auto& d : world->defaults) listed = listed || d.find("springs/stiffness = 2000 N/m") != std::string::npos;
  EXPECT_TRUE(listed);
}

TEST(World, EffectOnlyX3dSceneBuildsAWorldWithNoBody) {
  const auto file =
      write("effects.x3d", x3d("<SpringEffect position='0 0.01 0' springConstant='50'/><ViscosityEffect/>"));
  auto world = build_world(file);
  ASSERT_TRUE(world) << world.error().to_string();
  EXPECT_TRUE(world->bodies.empty());
  ASSERT_EQ(world->config.effects.springs.size(), 1u);
  EXPECT_EQ(world->config.effects.springs[0].spring_constant_n_per_m, 50.0);
  EXPECT_NE(world->device.find("scripted:circle"), std::string::npos) << world->device;
}

// Issue 35: a scene with nothing to touch opens (H3DViewer shows it), says why once, and
// names the real cause; one test per cause.
std::string nothing_to_touch(const std::string& name, const std::string& body) {
  auto world = build_world(write(name, x3d(body)));
  EXPECT_TRUE(world) << (world ? "" : world.error().to_string());
  if (!world) return {};
  EXPECT_TRUE(world->bodies.empty());
  const auto said = std::ranges::count_if(
      world->warnings, [](const std::string& w) { return w.find("nothing to touch") != std::string::npos; });
  EXPECT_EQ(said, 1) << name;
  return world->nothing_to_touch;
}

TEST(World, X3dShapesWithoutASurfaceAreASeenOnlyWorld) {
  const auto file =
      write("nothing.x3d", x3d("<PythonScript url='x.py'/><Shape><Box size='0.1 0.1 0.1'/></Shape>"
                               "<Shape><Appearance><Material/></Appearance><Sphere radius='0.05'/></Shape>"));
  auto world = build_world(file);
  ASSERT_TRUE(world) << world.error().to_string();
  EXPECT_EQ(world->visuals.size(), 2u);  // shown in the window
  EXPECT_EQ(world->nothing_to_touch,
            "nothing to touch: 2 shapes are only seen (no haptic surface in their Appearance), and no force effect");
}

TEST(World, X3dNothingToTouchNamesEachCause) {
  EXPECT_EQ(nothing_to_touch("one_seen.x3d", "<Shape><Box/></Shape>"),
            "nothing to touch: 1 shape is only seen (no haptic surface in its Appearance), and no force effect");
  EXPECT_EQ(
      nothing_to_touch("text.x3d",
                       "<Shape DEF='Label'><Appearance><SmoothSurface/></Appearance><Text string='\"a\"'/></Shape>"),
      "nothing to touch: a haptic surface on no triangles: Label (line 2, no geometry HoF draws), and no force effect");
  EXPECT_EQ(
      nothing_to_touch("torque.x3d", "<RotationalSpringEffect desiredAxis='0 1 0'/>"),
      "nothing to touch: haptic nodes HoF does not model: RotationalSpringEffect (a torque: HoF renders forces only) "
      "(line 2); no Shape, and no force effect");
  EXPECT_EQ(nothing_to_touch("empty.x3d", ""), "nothing to touch: no Shape, and no force effect");
}

// H3DViewer opens a settings file (its DeviceInfo becomes the device): HoF opens it too, with
// nothing to touch; only a root that is no X3D node is not an X3D file.
TEST(World, X3dSettingsFileOpensWithNothingToTouch) {
  const fs::path falcon =
      write("FalconDevice.x3d", "<DeviceInfo><FalconDevice><GodObjectRenderer/></FalconDevice></DeviceInfo>");
  auto world = build_world(falcon);
  ASSERT_TRUE(world) << world.error().to_string();
  EXPECT_TRUE(world->bodies.empty());
  EXPECT_EQ(world->nothing_to_touch, "nothing to touch: no Shape, and no force effect");
  EXPECT_EQ(world->project.renderer, haptics::RendererKind::kGodObject);  // the file's device settings hold
  EXPECT_TRUE(std::ranges::any_of(world->warnings, [](const std::string& w) {
    return w.find("the root element is <DeviceInfo>, not <X3D>: read as a scene") != std::string::npos;
  }));
  const fs::path svg = write("picture.x3d", "<svg><rect/></svg>");
  auto refused = build_world(svg);
  ASSERT_FALSE(refused);
  EXPECT_EQ(refused.error().file, svg.string());
  EXPECT_EQ(refused.error().message,
            "not an X3D scene: its root element <svg> is not an X3D node (a scene starts with <X3D> or <Scene>)");
}

TEST(World, X3dGeometryGroupAndDebugOptionsScenesAreTouchable) {
  // Shaped as H3D's GeometryGroup.x3d and DebugOptions.x3d, which were refused with "no haptic surface".
  auto group =
      build_world(write("geometry_group.x3d", x3d("<Shape><Appearance><FrictionalSurface/></Appearance>"
                                                  "<GeometryGroup><Box size='0.1 0.01 0.1'/><Sphere radius='0.02'/>"
                                                  "</GeometryGroup></Shape>")));
  ASSERT_TRUE(group) << group.error().to_string();
  ASSERT_EQ(group->bodies.size(), 1u);
  EXPECT_TRUE(group->nothing_to_touch.empty());
  auto debug =
      build_world(write("debug_options.x3d", x3d("<GlobalSettings><DebugOptions drawBound='true'/></GlobalSettings>"
                                                 "<Shape><Extrusion scale='0.05 0.05'/><Appearance><FrictionalSurface/>"
                                                 "</Appearance></Shape>")));
  ASSERT_TRUE(debug) << debug.error().to_string();
  EXPECT_EQ(debug->bodies.size(), 1u);
}

TEST(World, SofaSceneWithTwoSolvedNodesGivesTwoBodies) {
  const std::string mesh = std::string(HOF_SOURCE_DIR) + "/data/models/liver-simple.msh";
  const std::string node =
      "<EulerImplicitSolver/><CGLinearSolver iterations='25'/><MeshGmshLoader name='l' filename='" + mesh +
      "'/><MechanicalObject src='@l'/><TetrahedronFEMForceField name='FEM' youngModulus='5000' "
      "poissonRatio='0.45'/><DiagonalMass massDensity='1060'/><FixedConstraint indices='0 1 2'/>";
  const auto file = write("two.scn", "<Node name='root' gravity='0 0 0' dt='0.01'><Node name='Left'>" + node +
                                         "</Node><Node name='Right'>" + node + "</Node></Node>");
  auto world = build_world(file);
  ASSERT_TRUE(world) << world.error().to_string();
  ASSERT_EQ(world->bodies.size(), 2u);
  EXPECT_TRUE(world->bodies[0].deformable() && world->bodies[1].deformable());
  EXPECT_NE(world->bodies[0].name, world->bodies[1].name);
  EXPECT_EQ(world->length_unit, "scene units");
}

TEST(World, SofaCollisionModelWithoutASolverIsARigidObstacle) {
  // A table under the liver: a TriangleCollisionModel on a state no solver moves.
  write("table.obj", "v -0.2 -0.2 -0.06\nv 0.2 -0.2 -0.06\nv 0.2 0.2 -0.06\nv -0.2 0.2 -0.06\nf 1 2 3\nf 1 3 4\n");
  const std::string mesh = std::string(HOF_SOURCE_DIR) + "/data/models/liver-simple.msh";
  const auto file =
      write("table.scn",
            "<Node name='root' gravity='0 0 0' dt='0.01'>"
            "<Node name='Liver'><EulerImplicitSolver/><CGLinearSolver/><MeshGmshLoader name='l' filename='" +
                mesh +
                "'/><MechanicalObject src='@l'/><TetrahedronFEMForceField name='FEM'/>"
                "<DiagonalMass massDensity='1060'/><FixedConstraint indices='0 1 2'/></Node>"
                "<Node name='Table'><MeshOBJLoader name='t' filename='table.obj'/><MechanicalObject src='@t'/>"
                "<TriangleCollisionModel moving='0' simulated='0'/></Node></Node>");
  auto world = build_world(file);
  ASSERT_TRUE(world) << world.error().to_string();
  ASSERT_EQ(world->bodies.size(), 2u);
  EXPECT_TRUE(world->bodies[0].deformable());
  EXPECT_EQ(world->bodies[1].name, "Table");
  EXPECT_FALSE(world->bodies[1].deformable());
  EXPECT_EQ(world->bodies[1].surface.triangles.size(), 2u);
  // The table is touched where it lies (beside the liver, x = 0.15).
  const Touch t = touch(file, Vec3(0.15, 0.15, 0.0), Vec3(0, 0, -1), 0.06);
  ASSERT_TRUE(t.contact);
  EXPECT_EQ(t.body, 1);
  EXPECT_NEAR(t.proxy.z(), -0.06, 1e-4);
}

TEST(World, ProjectParametersOverrideTheSceneAndRoundTrip) {
  HofProject p;
  p.name = "override";
  p.mechanics_scene = fs::path(HOF_SOURCE_DIR) / "examples/liver-medium-fem.scn";
  p.parameters.push_back({"Liver", "FEM", "youngModulus", 8000.0});
  p.parameters.push_back({"Liver", "cg", "iterations", 40.0});
  const fs::path file = fs::temp_directory_path() / "hof_world_test" / "override.hof";
  fs::create_directories(file.parent_path());
  ASSERT_TRUE(write_project(p, file));
  auto again = read_project(file);
  ASSERT_TRUE(again) << again.error().to_string();
  ASSERT_EQ(again->parameters.size(), 2u);
  EXPECT_EQ(to_xml(*again), to_xml(p));
  auto world = build_world(file);
  ASSERT_TRUE(world) << world.error().to_string();
  ASSERT_EQ(world->bodies.size(), 1u);
  EXPECT_EQ(*scene::get_parameter(*world->bodies[0].config, "FEM", "youngModulus"), 8000.0);
  EXPECT_EQ(world->bodies[0].config->linear.iterations, 40);
  // A bad override is an error naming the project.
  p.parameters.push_back({"Liver", "FEM", "poissonRatio", 0.5});
  ASSERT_TRUE(write_project(p, file));
  auto bad = build_world(file);
  ASSERT_FALSE(bad);
  EXPECT_NE(bad.error().to_string().find("override.hof"), std::string::npos) << bad.error().to_string();
  EXPECT_NE(bad.error().message.find("poissonRatio"), std::string::npos);
}

TEST(World, ProjectHoldsBodySurfacesAndRigidObstaclesAndRoundTrips) {
  write("plate.obj", "v -0.1 -0.1 0\nv 0.1 -0.1 0\nv 0.1 0.1 0\nv -0.1 0.1 0\nf 1 2 3\nf 1 3 4\n");
  HofProject p;
  p.name = "bodies";
  p.mechanics_scene = fs::path(HOF_SOURCE_DIR) / "examples/liver-medium-fem.scn";
  haptics::SurfaceMaterial soft;
  soft.kind = haptics::SurfaceKind::kFrictional;
  soft.stiffness = 0.25;
  p.bodies.push_back({"Liver", soft, {}, {}, {}});
  haptics::SurfaceMaterial hard;
  hard.stiffness = 0.9;
  p.obstacles.push_back({"Table", "plate.obj", Vec3(0, 0, -0.06), hard, {}});
  const fs::path file = fs::temp_directory_path() / "hof_world_test" / "bodies.hof";
  ASSERT_TRUE(write_project(p, file));
  auto again = read_project(file);
  ASSERT_TRUE(again) << again.error().to_string();
  EXPECT_EQ(to_xml(*again), to_xml(p)) << "save -> load -> save changed the project";
  auto world = build_world(file);
  ASSERT_TRUE(world) << world.error().to_string();
  ASSERT_EQ(world->bodies.size(), 2u);
  ASSERT_TRUE(world->bodies[0].material);
  EXPECT_EQ(world->bodies[0].material->kind, haptics::SurfaceKind::kFrictional);
  EXPECT_EQ(world->bodies[0].material->stiffness, 0.25);
  EXPECT_EQ(world->bodies[1].name, "Table");
  EXPECT_FALSE(world->bodies[1].deformable());
  EXPECT_EQ(world->bodies[1].surface.vertices[0].z(), -0.06);
  EXPECT_EQ(world->bodies[1].material->stiffness, 0.9);
  // An obstacle whose mesh is missing is an error naming it and the project.
  p.obstacles[0].mesh = "nowhere.obj";
  ASSERT_TRUE(write_project(p, file));
  auto bad = build_world(file);
  ASSERT_FALSE(bad);
  EXPECT_NE(bad.error().to_string().find("nowhere.obj"), std::string::npos);
  EXPECT_NE(bad.error().message.find("Table"), std::string::npos) << bad.error().message;
}

TEST(World, ChangesThroughTheCommandSeamAreInTheNextSavedProject) {
  HofProject p;
  p.name = "seam";
  p.mechanics_scene = fs::path(HOF_SOURCE_DIR) / "examples/liver-medium-fem.scn";
  const fs::path file = fs::temp_directory_path() / "hof_world_test" / "seam.hof";
  ASSERT_TRUE(write_project(p, file));
  auto world = build_world(file);
  ASSERT_TRUE(world) << world.error().to_string();
  auto device = scene::open_device(world->device);
  ASSERT_TRUE(device);
  coupling::SessionConfig config = world->config;
  config.haptics.realtime_priority = false;
  auto session = coupling::Session::make(std::move(world->bodies), std::move(*device), config);
  ASSERT_TRUE(session);
  (*session)->run_virtual(0.05, {});
  ASSERT_TRUE((*session)->submit(*parameter_command(**session, "Liver", "FEM", "youngModulus", 7000.0)));
  ASSERT_FALSE((*session)->submit(*parameter_command(**session, "Liver", "FEM", "youngModulus", -7000.0)));
  auto nobody = parameter_command(**session, "Spleen", "FEM", "youngModulus", 1.0);
  ASSERT_FALSE(nobody);
  EXPECT_NE(nobody.error().message.find("no body 'Spleen' (bodies: "), std::string::npos) << nobody.error().message;
  haptics::SurfaceMaterial magnetic;
  magnetic.kind = haptics::SurfaceKind::kMagnetic;
  ASSERT_TRUE((*session)->submit(coupling::command::SetMaterial{*body_id(**session, "Liver"), magnetic}));
  const coupling::SessionReport report = (*session)->run_virtual(0.02, {});
  ASSERT_EQ(report.applied_commands.size(), 2u);
  record_changes(world->project, **session);
  ASSERT_TRUE(write_project(world->project, file));
  const std::string saved = to_xml(world->project);
  EXPECT_NE(saved.find("<set body=\"Liver\" component=\"FEM\" parameter=\"youngModulus\" value=\"7000\"/>"),
            std::string::npos)
      << saved;
  auto reloaded = build_world(file);
  ASSERT_TRUE(reloaded) << reloaded.error().to_string();
  EXPECT_EQ(*scene::get_parameter(*reloaded->bodies[0].config, "FEM", "youngModulus"), 7000.0);
  ASSERT_TRUE(reloaded->bodies[0].material);
  EXPECT_EQ(reloaded->bodies[0].material->kind, haptics::SurfaceKind::kMagnetic);
  EXPECT_EQ(to_xml(reloaded->project), saved);
}

TEST(World, DefaultProbeStartsOutsideAndPressesWhateverTheUpAxis) {
  // The same box, once with y up and once turned so that z is up: the probe presses its top.
  for (const std::string& rotation : {std::string("0 0 1 0"), std::string("1 0 0 1.5707963267949")}) {
    const auto file = write("probe.x3d", x3d("<Transform rotation='" + rotation + "'><Shape>" + kSurface +
                                             "<Box size='0.1 0.04 0.1'/></Shape></Transform>"));
    auto world = build_world(file);
    ASSERT_TRUE(world) << world.error().to_string();
    EXPECT_TRUE(world->default_probe);
    auto device = scene::open_device(world->device);
    ASSERT_TRUE(device) << device.error().to_string();
    auto session = coupling::Session::make(std::move(world->bodies), std::move(*device), world->config);
    ASSERT_TRUE(session);
    const coupling::SessionReport report = (*session)->run_virtual(3.0, {});
    EXPECT_GT(report.contact_time_s, 0.5) << rotation;
    EXPECT_EQ(report.fall_through_events, 0);
    EXPECT_FALSE(report.bodies[0].probe_started_inside);
    EXPECT_LT(report.max_force_n, 8.0);
    EXPECT_EQ(report.clamped_contact_ticks, 0);
  }
}

TEST(World, MissingOrFolderInputsAreClearErrors) {
  auto missing = build_world("/nonexistent/scene.scn");
  ASSERT_FALSE(missing);
  EXPECT_NE(missing.error().to_string().find("/nonexistent/scene.scn"), std::string::npos);
  auto folder = build_world(fs::temp_directory_path());
  ASSERT_FALSE(folder);
  EXPECT_NE(folder.error().message.find("folder"), std::string::npos);
}

TEST(World, X3dShapesWithoutASurfaceAreSeenNotTouchedAndMaterialsAreKept) {
  const fs::path file = write("appearance.x3d", x3d(R"(
    <Shape DEF="TABLE"><Appearance><Material diffuseColor="0.2 0.4 0.6" transparency="0.5"/></Appearance>
      <Box size="0.3 0.01 0.3"/></Shape>
    <Shape DEF="BALL"><Appearance><Material diffuseColor="1 0 0"/><SmoothSurface/></Appearance><Sphere radius="0.03"/></Shape>
    <Shape DEF="PLAIN"><Appearance><SmoothSurface/></Appearance><Sphere radius="0.02"/></Shape>)"));
  auto world = build_world(file);
  ASSERT_TRUE(world) << world.error().to_string();
  ASSERT_EQ(world->bodies.size(), 2u) << "only the shapes with a haptic surface are bodies";
  ASSERT_EQ(world->visuals.size(), 1u);
  EXPECT_EQ(world->visuals[0].name, "TABLE");
  EXPECT_EQ(world->visuals[0].mesh.triangles.size(), 12u);
  EXPECT_EQ(world->visuals[0].appearance.diffuse_color, Vec3(0.2, 0.4, 0.6));
  EXPECT_DOUBLE_EQ(world->visuals[0].appearance.transparency, 0.5);
  ASSERT_EQ(world->appearances.count("BALL"), 1u);
  EXPECT_EQ(world->appearances.at("BALL").diffuse_color, Vec3(1.0, 0.0, 0.0));
  EXPECT_EQ(world->appearances.count("PLAIN"), 0u) << "no Material: the window's own";
}

}  // namespace
}  // namespace hof::scene

namespace hof::scene {
namespace {

TEST(World, ANeedleProjectMountsTheNeedleOnItsBodies) {
  auto world = build_world(HOF_SOURCE_DIR "/examples/needle-liver.hof");
  ASSERT_TRUE(world) << world.error().to_string();
  ASSERT_TRUE(world->config.tool);
  ASSERT_TRUE(world->config.tool_coupling);
  const auto* needle = dynamic_cast<const procedures::NeedleTool*>(world->config.tool.get());
  ASSERT_NE(needle, nullptr);
  EXPECT_TRUE(needle->parameters(0).pierceable);  // the liver, deformable
  EXPECT_EQ(needle->parameters(0).capsule_m, 0.02);
  // A tissue set for a body the scene does not have is an error naming it.
  HofProject project = world->project;
  project.device = "scripted:hold";
  project.needle->bodies.emplace_back("Kidney", project.needle->tissue);
  auto wrong = build_world(project, HOF_SOURCE_DIR "/examples/needle-liver.hof");
  ASSERT_FALSE(wrong);
  EXPECT_NE(wrong.error().message.find("'Kidney'"), std::string::npos) << wrong.error().to_string();
  EXPECT_NE(wrong.error().message.find("Liver"), std::string::npos) << wrong.error().to_string();
}

// H3D's Prototype example: its one Shape draws Text, which HoF does not model. The reason says
// so (it was an empty cause: "nothing to touch: , and no force effect").
TEST(World, AShapeOfAGeometryHoFDoesNotModelIsTheNamedReason) {
  auto world = build_world(std::string(HOF_ANCHORS_DIR) + "/h3d/examples/All/Prototype.x3d");
  ASSERT_TRUE(world) << world.error().to_string();
  EXPECT_EQ(world->nothing_to_touch.find("nothing to touch: ,"), std::string::npos) << world->nothing_to_touch;
  EXPECT_NE(world->nothing_to_touch.find("no shape has a geometry HoF models (not modelled: Text"), std::string::npos)
      << world->nothing_to_touch;
}

// Found on H3D's own examples (issue 35, the survey of 227 scenes): each a message that named
// the wrong cause, or content that was lost or felt where H3D would not.
TEST(World, X3dToggleGroupWithHapticsOffIsSeenNotFelt) {
  EXPECT_EQ(nothing_to_touch("toggle_shape.x3d", "<ToggleGroup hapticsOn='false'><Shape>" + kSurface +
                                                     "<Sphere radius='0.05'/></Shape></ToggleGroup>"),
            "nothing to touch: 1 shape is under a ToggleGroup with hapticsOn false, and no force effect");
  EXPECT_EQ(nothing_to_touch("toggle_effect.x3d", "<ToggleGroup hapticsOn='false'><TimeFunctionEffect/></ToggleGroup>"),
            "nothing to touch: 1 force effect is under a ToggleGroup with hapticsOn false; no Shape");
  // Haptics on (the default): felt as before.
  auto world = build_world(
      write("toggle_on.x3d", x3d("<ToggleGroup><Shape>" + kSurface + "<Sphere radius='0.05'/></Shape></ToggleGroup>")));
  ASSERT_TRUE(world) << world.error().to_string();
  EXPECT_EQ(world->bodies.size(), 1u);
}

TEST(World, X3dGeometryNamedSurfaceIsGeometryNotAHapticNode) {
  EXPECT_EQ(nothing_to_touch("nurbs.x3d", "<Shape><Appearance><Material/></Appearance><NurbsPatchSurface/></Shape>"),
            "nothing to touch: no shape has a geometry HoF models (not modelled: NurbsPatchSurface (line 2)), and no "
            "force effect");
  // A surface HoF does not have, in an Appearance, is the haptic cause.
  EXPECT_EQ(nothing_to_touch("surface.x3d", "<Shape><Appearance><LatexSurface/></Appearance><Box/></Shape>"),
            "nothing to touch: 1 shape is only seen (no haptic surface in its Appearance); haptic nodes HoF does not "
            "model: LatexSurface (line 2), and no force effect");
}

TEST(World, X3dNodesOfAnotherFileAreNamedWithThatFile) {
  write("proto_lib.x3d", x3d("<ProtoDeclare name='Label'><ProtoBody><Group><PythonScript/></Group></ProtoBody>"
                             "</ProtoDeclare>"));
  auto world = build_world(write("proto_use.x3d", x3d("<ExternProtoDeclare name='Label' url='\"proto_lib.x3d#Label\"'/>"
                                                      "<ProtoInstance name='Label'/>")));
  ASSERT_TRUE(world) << world.error().to_string();
  EXPECT_TRUE(std::ranges::any_of(world->skipped, [](const std::string& s) {
    return s == "PythonScript (proto_lib.x3d line 2)";
  })) << world->skipped.size();
}

// H3D's bumpmap, ThreadExample, DynamicTransform examples: a <Group> root is a scene fragment,
// opened and touched as H3DViewer does; a root that is no X3D node names its line.
TEST(World, X3dGroupRootIsAScene) {
  auto world = build_world(write("fragment.x3d", "<?xml version='1.0'?>\n<Group><Shape>" + kSurface +
                                                     "<Sphere radius='0.05'/></Shape></Group>\n"));
  ASSERT_TRUE(world) << world.error().to_string();
  EXPECT_EQ(world->bodies.size(), 1u);
  auto refused = build_world(write("not_x3d.x3d", "<?xml version='1.0'?>\n<html><body/></html>\n"));
  ASSERT_FALSE(refused);
  EXPECT_EQ(refused.error().line, 2);
}

TEST(World, X3dInlineOfAClassicVrmlFileIsNotShownAndTheSceneOpens) {
  write("classic.wrl", "#VRML V2.0 utf8\nShape { geometry Box {} }\n");
  auto world = build_world(write(
      "inline_wrl.x3d", x3d("<Inline url='\"classic.wrl\"'/><Shape>" + kSurface + "<Sphere radius='0.05'/></Shape>")));
  ASSERT_TRUE(world) << world.error().to_string();
  EXPECT_EQ(world->bodies.size(), 1u);
  EXPECT_TRUE(std::ranges::any_of(world->warnings, [](const std::string& w) {
    return w.find("Inline url 'classic.wrl': the classic VRML encoding") != std::string::npos;
  }));
}

TEST(World, X3dDynamicTransformPlacesItsChildrenWhereItStarts) {
  auto world = build_world(write("dynamic.x3d", x3d("<DynamicTransform position='0.2 0 0'><Shape>" + kSurface +
                                                    "<Sphere radius='0.05'/></Shape></DynamicTransform>")));
  ASSERT_TRUE(world) << world.error().to_string();
  ASSERT_EQ(world->bodies.size(), 1u);
  Vec3 centre = Vec3::Zero();
  for (const Vec3& v : world->bodies[0].surface.vertices) centre += v;
  centre /= static_cast<double>(world->bodies[0].surface.vertices.size());
  EXPECT_NEAR(centre.x(), 0.2, 1e-9);
  EXPECT_TRUE(
      std::ranges::any_of(world->warnings, [](const std::string& w) { return w.find("motion") != std::string::npos; }));
}

TEST(World, X3dOpenHapticsSurfaceIsMagneticOnlyWhenItSaysSo) {
  for (const auto& [field, kind] : {std::pair{std::string(""), haptics::SurfaceKind::kFrictional},
                                    std::pair{std::string("magnetic='true'"), haptics::SurfaceKind::kMagnetic}}) {
    auto world = build_world(write("openhaptics.x3d", x3d("<Shape><Appearance><OpenHapticsSurface " + field +
                                                          "/></Appearance><Sphere radius='0.05'/></Shape>")));
    ASSERT_TRUE(world) << world.error().to_string();
    ASSERT_EQ(world->bodies.size(), 1u);
    ASSERT_TRUE(world->bodies[0].material);
    EXPECT_EQ(world->bodies[0].material->kind, kind) << field;
  }
}

TEST(World, X3dDeformableShapeWithOnlyAHapticGeometryIsTouchable) {
  auto world =
      build_world(write("deform_haptic.x3d", x3d("<DeformableShape>" + kSurface +
                                                 "<IndexedTriangleSet containerField='hapticGeometry' "
                                                 "index='0 1 2 0 2 3'><Coordinate point='0 0 0 1 0 0 1 1 0 0 1 0'/>"
                                                 "</IndexedTriangleSet></DeformableShape>")));
  ASSERT_TRUE(world) << world.error().to_string();
  ASSERT_EQ(world->bodies.size(), 1u);
  EXPECT_TRUE(world->bodies[0].deformable());
}

TEST(World, X3dZeroSizeGeometryIsSaid) {
  auto world = build_world(write("zero.x3d", x3d("<Shape>" + kSurface + "<Sphere radius='0'/></Shape>")));
  ASSERT_TRUE(world) << world.error().to_string();
  EXPECT_TRUE(std::ranges::any_of(world->warnings,
                                  [](const std::string& w) { return w.find("has zero size") != std::string::npos; }));
}

}  // namespace
}  // namespace hof::scene
