// SOFA's collision pipeline and collision models as contact settings: SOFA's liver.scn (its
// collision spheres from liver.sph), a liver on a rigid floor, and each bad input an error
// naming the file and the line.

#include <gtest/gtest.h>

#include <algorithm>
#include <cstdlib>
#include <fstream>

#include "hof/mesh/sphere_file.h"
#include "hof/scene/sofa_scene.h"
#include "hof/scene/world.h"

namespace hof::scene {
namespace {

namespace fs = std::filesystem;

const std::string kAnchors = HOF_ANCHORS_DIR "/sofa";
const std::string kLiverMesh = HOF_SOURCE_DIR "/data/models/liver-simple.msh";

bool contains(const std::vector<std::string>& v, std::string_view needle) {
  return std::ranges::any_of(v, [&](const std::string& s) { return s.find(needle) != std::string::npos; });
}

TEST(SofaCollision, SofasLiverCollidesThroughItsSpheres) {
  auto s = read_sofa_scene(kAnchors + "/liver.scn");
  ASSERT_TRUE(s) << s.error().to_string();
  // CollisionPipeline + CollisionResponse (PenalityContactForceField) + DiscreteIntersection.
  EXPECT_TRUE(s->contacts.enabled);
  EXPECT_EQ(s->contacts.response, coupling::ContactResponse::kPenalty);
  EXPECT_EQ(s->contacts.alarm_distance_m, 0.0);  // DiscreteIntersection: overlaps only
  EXPECT_EQ(s->contacts.contact_distance_m, 0.0);
  EXPECT_EQ(s->contacts.stiffness_n_per_m, 10.0);  // SOFA's CollisionModel contactStiffness
  EXPECT_EQ(s->contacts.friction, 0.0);
  ASSERT_EQ(s->models.size(), 1u);
  // The 'Surf' node: SphereLoader mesh/liver.sph, a MechanicalObject at its positions, the
  // SphereCollisionModel with its radii, mapped barycentrically from the volume.
  const coupling::BodyCollision& c = s->models[0].collision;
  EXPECT_TRUE(c.enabled);
  EXPECT_FALSE(c.triangles || c.lines || c.points);
  auto file = mesh::read_sph(kAnchors + "/mesh/liver.sph");
  ASSERT_TRUE(file);
  ASSERT_EQ(c.sphere_centers.size(), 34u);
  EXPECT_EQ(c.sphere_centers, file->centers);
  EXPECT_EQ(c.sphere_radii, file->radii);
  EXPECT_DOUBLE_EQ(c.sphere_radii[2], 0.35);
  EXPECT_TRUE(c.moving && c.simulated);
  EXPECT_EQ(c.group, -1);
  EXPECT_FALSE(c.self_collision.has_value());
  EXPECT_FALSE(c.stiffness_n_per_m.has_value());
  // Simulated now: neither skipped nor "needing no counterpart"; no warning says bodies do not collide.
  EXPECT_FALSE(contains(s->skipped, "Sphere"));
  EXPECT_FALSE(contains(s->skipped, "sphere mapping"));
  EXPECT_FALSE(contains(s->ignored, "CollisionPipeline"));
  EXPECT_FALSE(contains(s->ignored, "CollisionResponse"));
  EXPECT_FALSE(contains(s->ignored, "DiscreteIntersection"));
  EXPECT_FALSE(contains(s->warnings, "do not collide"));
  // The world carries them into the session's configuration.
  auto world = build_world(kAnchors + "/liver.scn");
  ASSERT_TRUE(world) << world.error().to_string();
  EXPECT_TRUE(world->config.contacts.enabled);
  ASSERT_EQ(world->bodies.size(), 1u);
  EXPECT_EQ(world->bodies[0].collision.sphere_radii.size(), 34u);
}

class SofaCollisionFiles : public ::testing::Test {
 protected:
  void SetUp() override {
    dir_ = fs::temp_directory_path() /
           (std::string("hof_sofa_collision_") + ::testing::UnitTest::GetInstance()->current_test_info()->name());
    fs::create_directories(dir_);
    write("floor.obj", "v -1 -0.1 -1\nv 1 -0.1 -1\nv 1 -0.1 1\nv -1 -0.1 1\nf 1 3 2\nf 1 4 3\n");
  }
  void TearDown() override { fs::remove_all(dir_); }
  fs::path write(const std::string& name, const std::string& text) {
    std::ofstream(dir_ / name) << text;
    return dir_ / name;
  }
  // A scene: `pipeline` in the root (line 2 on), a liver body whose children are `liver`, a floor.
  static std::string scene(const std::string& pipeline, const std::string& liver, const std::string& floor = {}) {
    return "<Node name='root' gravity='0 -9.81 0' dt='0.01'>\n" + pipeline +
           "<Node name='Liver'>\n<EulerImplicitSolver/>\n<CGLinearSolver/>\n"
           "<MeshGmshLoader name='l' filename='" +
           kLiverMesh +
           "'/>\n<TetrahedronSetTopologyContainer name='topo' src='@l'/>\n<MechanicalObject name='dofs' src='@l'/>\n"
           "<TetrahedronFEMForceField name='FEM'/>\n<DiagonalMass massDensity='1060'/>\n" +
           liver + "</Node>\n" + floor + "</Node>\n";
  }
  Error error_of(const std::string& text) {
    auto s = read_sofa_scene(write("scene.scn", text));
    EXPECT_FALSE(s.has_value());
    return s ? Error{} : s.error();
  }
  fs::path dir_;
};

// SOFA's pipeline with a proximity method and friction, a liver with a collision surface made by
// Tetra2TriangleTopologicalMapping, and a floor: a node with a collision mesh and no solver.
const std::string kPipeline =
    "<CollisionPipeline/>\n<BruteForceBroadPhase/>\n<BVHNarrowPhase/>\n"
    "<MinProximityIntersection alarmDistance='0.005' contactDistance='0.002'/>\n"
    "<CollisionResponse name='response' response='FrictionContactConstraint' responseParams='mu=0.3'/>\n";
const std::string kLiverSurface =
    "<Node name='Collision'>\n<TriangleSetTopologyContainer name='surface'/>\n"
    "<Tetra2TriangleTopologicalMapping input='@../topo' output='@surface'/>\n"
    "<TriangleCollisionModel contactStiffness='500' group='1' selfCollision='1'/>\n<LineCollisionModel/>\n"
    "<PointCollisionModel/>\n</Node>\n";
const std::string kFloor =
    "<Node name='Floor'>\n<MeshOBJLoader name='f' filename='floor.obj'/>\n<MechanicalObject src='@f'/>\n"
    "<TriangleCollisionModel moving='0' simulated='0'/>\n<LineCollisionModel moving='0' simulated='0'/>\n"
    "<PointCollisionModel moving='0' simulated='0'/>\n</Node>\n";

TEST_F(SofaCollisionFiles, ALiverOnARigidFloorCollides) {
  auto s = read_sofa_scene(write("floor.scn", scene(kPipeline, kLiverSurface, kFloor)));
  ASSERT_TRUE(s) << s.error().to_string();
  EXPECT_TRUE(s->contacts.enabled);
  EXPECT_EQ(s->contacts.response, coupling::ContactResponse::kFrictionConstraint);
  EXPECT_DOUBLE_EQ(s->contacts.friction, 0.3);
  EXPECT_DOUBLE_EQ(s->contacts.alarm_distance_m, 0.005);
  EXPECT_DOUBLE_EQ(s->contacts.contact_distance_m, 0.002);
  // Friction constraints are solved as penalty contacts for now, and the warning says so.
  EXPECT_TRUE(contains(s->warnings, "solved as penalty contacts"));
  EXPECT_TRUE(contains(s->warnings, "constraint contacts are next"));
  EXPECT_TRUE(s->skipped.empty()) << s->skipped.front();
  ASSERT_EQ(s->models.size(), 1u);
  const coupling::BodyCollision& liver = s->models[0].collision;
  EXPECT_TRUE(liver.enabled && liver.triangles && liver.lines && liver.points);
  EXPECT_TRUE(liver.sphere_centers.empty());
  EXPECT_EQ(liver.stiffness_n_per_m, 500.0);
  EXPECT_EQ(liver.group, 1);
  EXPECT_EQ(liver.self_collision, true);
  EXPECT_TRUE(liver.moving && liver.simulated);
  ASSERT_EQ(s->obstacles.size(), 1u);
  const coupling::BodyCollision& floor = s->obstacles[0].collision;
  EXPECT_TRUE(floor.enabled && floor.triangles && floor.lines && floor.points);
  EXPECT_FALSE(floor.moving || floor.simulated);
  // In the world: a deformable liver and a rigid floor, both colliding.
  auto world = build_world(dir_ / "floor.scn");
  ASSERT_TRUE(world) << world.error().to_string();
  ASSERT_EQ(world->bodies.size(), 2u);
  EXPECT_TRUE(world->bodies[0].deformable() && world->bodies[0].collision.enabled);
  EXPECT_EQ(world->bodies[1].name, "Floor");
  EXPECT_FALSE(world->bodies[1].deformable());
  EXPECT_TRUE(world->bodies[1].collision.enabled);
  EXPECT_TRUE(world->config.contacts.enabled);
  EXPECT_DOUBLE_EQ(world->config.contacts.friction, 0.3);
}

TEST_F(SofaCollisionFiles, ConstraintSolversOfFrictionContactsAreNamedAsUnused) {
  auto s = read_sofa_scene(
      write("lcp.scn", scene("<FreeMotionAnimationLoop/>\n<GenericConstraintSolver name='gcs'/>\n" + kPipeline,
                             kLiverSurface + "<UncoupledConstraintCorrection name='ucc'/>\n")));
  ASSERT_TRUE(s) << s.error().to_string();
  EXPECT_TRUE(contains(s->warnings,
                       "GenericConstraintSolver 'gcs' (line 3) is not used by HoF: the contacts are solved "
                       "as penalty contacts"));
  EXPECT_TRUE(contains(s->warnings, "UncoupledConstraintCorrection 'ucc'"));
  EXPECT_FALSE(contains(s->warnings, "constraint-based contacts and constraints are not solved"));
}

TEST_F(SofaCollisionFiles, ProximityMethodsTakeSofasDefaultDistances) {
  auto s = read_sofa_scene(write("defaults.scn", scene("<DefaultPipeline/>\n<NewProximityIntersection/>\n"
                                                       "<DefaultContactManager/>\n",
                                                       kLiverSurface)));
  ASSERT_TRUE(s) << s.error().to_string();
  EXPECT_TRUE(s->contacts.enabled);
  EXPECT_EQ(s->contacts.response, coupling::ContactResponse::kPenalty);  // "default"
  EXPECT_DOUBLE_EQ(s->contacts.alarm_distance_m, 1.0);
  EXPECT_DOUBLE_EQ(s->contacts.contact_distance_m, 0.5);
}

TEST_F(SofaCollisionFiles, NoPipelineNoContact) {
  // Collision models without a pipeline: SOFA detects nothing, and neither does HoF.
  auto s = read_sofa_scene(write("none.scn", scene("", kLiverSurface)));
  ASSERT_TRUE(s) << s.error().to_string();
  EXPECT_FALSE(s->contacts.enabled);
  EXPECT_TRUE(s->models[0].collision.enabled);
}

TEST_F(SofaCollisionFiles, UnsupportedShapesAreNamed) {
  auto s = read_sofa_scene(write("cube.scn", scene(kPipeline,
                                                   "<Node name='c'>\n<MechanicalObject/>\n"
                                                   "<CubeCollisionModel name='cube'/>\n"
                                                   "<BarycentricMapping/>\n</Node>\n")));
  ASSERT_TRUE(s) << s.error().to_string();
  EXPECT_TRUE(contains(s->warnings, "CubeCollisionModel 'cube' (line 17) changes SOFA's result"));
  EXPECT_TRUE(contains(s->skipped, "CubeCollisionModel 'cube' (line 17)"));
}

TEST_F(SofaCollisionFiles, ACollisionModelOnABodyWithNoSurfaceNamesItsLine) {
  const Error e = error_of(scene(kPipeline,
                                 "<Node name='c'>\n<MechanicalObject/>\n<TriangleCollisionModel name='t'/>\n"
                                 "<BarycentricMapping/>\n</Node>\n"));
  EXPECT_EQ(e.line, 17);
  EXPECT_NE(e.file.find("scene.scn"), std::string::npos);
  EXPECT_NE(e.message.find("TriangleCollisionModel 't' (line 17)"), std::string::npos) << e.message;
  EXPECT_NE(e.message.find("a collision model on a body with no surface"), std::string::npos) << e.message;
}

TEST_F(SofaCollisionFiles, AnObstacleCollisionModelWithNoTrianglesIsAnErrorWhenContactIsOn) {
  // A rigid node with points but no triangles: with the scene's pipeline on, its collision
  // models would collide nothing (it used to be a warning); without a pipeline it is not
  // touchable and said so.
  const std::string points =
      "<Node name='Floor'>\n<MechanicalObject position='-1 -0.1 -1  1 -0.1 -1  1 -0.1 1'/>\n"
      "<TriangleCollisionModel name='t' moving='0' simulated='0'/>\n<PointCollisionModel moving='0' "
      "simulated='0'/>\n</Node>\n";
  const Error e = error_of(scene(kPipeline, "", points));
  EXPECT_EQ(e.line, 18);
  EXPECT_NE(e.file.find("scene.scn"), std::string::npos) << e.file;
  EXPECT_NE(e.message.find("TriangleCollisionModel 't' (line 18)"), std::string::npos) << e.message;
  EXPECT_NE(e.message.find("a collision model on a body with no surface"), std::string::npos) << e.message;
  auto s = read_sofa_scene(write("no_pipeline.scn", scene("", "", points)));
  ASSERT_TRUE(s) << s.error().to_string();
  EXPECT_TRUE(contains(s->warnings, "node 'root/Floor' has no triangles to touch; skipped"));
}

TEST_F(SofaCollisionFiles, ACollisionNodeNotMappedFromTheBodyIsNamedAsCollidingNothing) {
  // The body's collision node without its Tetra2TriangleTopologicalMapping: not part of the body.
  auto s = read_sofa_scene(write("unmapped.scn", scene(kPipeline,
                                                       "<Node name='Collision'>\n<TriangleSetTopologyContainer/>\n"
                                                       "<TriangleCollisionModel name='t'/>\n</Node>\n")));
  ASSERT_TRUE(s) << s.error().to_string();
  EXPECT_TRUE(contains(s->warnings, "TriangleCollisionModel 't' (line 17)"));
  EXPECT_TRUE(contains(s->warnings, "not a body, an obstacle with triangles, or a node mapped from a body"));
}

TEST_F(SofaCollisionFiles, SpheresMissingOrMiscountedNameTheirLine) {
  Error e = error_of(scene(kPipeline,
                           "<Node name='s'>\n<SphereCollisionModel name='balls'/>\n"
                           "<BarycentricMapping/>\n</Node>\n"));
  EXPECT_EQ(e.line, 16);
  EXPECT_NE(e.message.find("a SphereCollisionModel with no spheres"), std::string::npos) << e.message;
  e = error_of(scene(kPipeline,
                     "<Node name='s'>\n<MechanicalObject position='0 0 0 0.01 0 0'/>\n"
                     "<SphereCollisionModel name='balls' listRadius='0.1 0.2 0.3'/>\n"
                     "<BarycentricMapping/>\n</Node>\n"));
  EXPECT_EQ(e.line, 17);
  EXPECT_NE(e.message.find("3 radii for 2 spheres"), std::string::npos) << e.message;
}

TEST_F(SofaCollisionFiles, AMissingOrMalformedSphereFileNamesItsLine) {
  const std::string spheres =
      "<Node name='s'>\n<SphereLoader name='load' filename='{}'/>\n<MechanicalObject position='@[-1].position'/>\n"
      "<SphereCollisionModel listRadius='@[-2].listRadius'/>\n<BarycentricMapping/>\n</Node>\n";
  const auto with = [&](const std::string& file) {
    std::string text = spheres;
    text.replace(text.find("{}"), 2, file);
    return scene(kPipeline, text);
  };
  Error e = error_of(with("nowhere.sph"));
  EXPECT_EQ(e.code, ErrorCode::kIo);
  EXPECT_EQ(e.line, 16);
  EXPECT_NE(e.message.find("nowhere.sph"), std::string::npos) << e.message;
  write("bad.sph", "sph 1.0\nsphe 1 0 0 0 0.1\nsphe 2 0 0 0.1\n");
  e = error_of(with("bad.sph"));
  EXPECT_EQ(e.line, 3);  // the sphere file's line
  EXPECT_NE(e.file.find("bad.sph"), std::string::npos) << e.file;
  EXPECT_NE(e.message.find("SphereLoader 'load' (line 16)"), std::string::npos) << e.message;
  // A good one: its spheres and radii.
  write("good.sph", "sph 1.0\nsphe 1 0 0 0 0.01\nsphe 2 0.02 0 0 0.015\n");
  auto s = read_sofa_scene(write("scene.scn", with("good.sph")));
  ASSERT_TRUE(s) << s.error().to_string();
  EXPECT_EQ(s->models[0].collision.sphere_radii, (std::vector<double>{0.01, 0.015}));
}

TEST_F(SofaCollisionFiles, BadDistancesAndStiffnessNameTheirLine) {
  struct Case {
    std::string pipeline;
    std::string says;
  };
  for (const Case& c :
       {Case{"<CollisionPipeline/>\n<MinProximityIntersection name='i' alarmDistance='-1'/>\n<CollisionResponse/>\n",
             "alarmDistance -1 is negative"},
        Case{"<CollisionPipeline/>\n<LocalMinDistance name='i' contactDistance='-0.1'/>\n<CollisionResponse/>\n",
             "contactDistance -0.1 is negative"},
        Case{"<CollisionPipeline/>\n<MinProximityIntersection name='i' alarmDistance='0.1' "
             "contactDistance='0.2'/>\n<CollisionResponse/>\n",
             "contactDistance 0.2 is larger than alarmDistance 0.1"}}) {
    const Error e = error_of(scene(c.pipeline, kLiverSurface));
    EXPECT_EQ(e.line, 3) << c.says;
    EXPECT_NE(e.message.find(c.says), std::string::npos) << e.message;
  }
  std::string negative = kLiverSurface;
  negative.replace(negative.find("contactStiffness='500'"), 22, "contactStiffness='-5'");
  const Error e = error_of(scene(kPipeline, negative));
  EXPECT_EQ(e.line, 18);
  EXPECT_NE(e.message.find("contactStiffness -5 is negative"), std::string::npos) << e.message;
}

TEST_F(SofaCollisionFiles, AnUnknownResponseNamesTheClosestKnownOnes) {
  const Error e =
      error_of(scene("<CollisionPipeline/>\n<CollisionResponse name='r' "
                     "response='PenalityContactForceFeild'/>\n",
                     kLiverSurface));
  EXPECT_EQ(e.line, 3);
  EXPECT_NE(e.message.find("unknown response 'PenalityContactForceFeild'"), std::string::npos) << e.message;
  EXPECT_NE(e.message.find("did you mean PenalityContactForceField"), std::string::npos) << e.message;
}

}  // namespace
}  // namespace hof::scene
