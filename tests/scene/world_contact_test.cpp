// Contact between bodies in a world: a project's <contact> makes X3D shapes and obstacles
// collide (their whole surface), its pairs and the bodies' contact="…" switch some off, and
// what cannot be is an error naming the project.

#include <gtest/gtest.h>

#include <filesystem>
#include <fstream>

#include "hof/scene/world.h"

namespace hof::scene {
namespace {

namespace fs = std::filesystem;

fs::path write(const std::string& name, const std::string& text) {
  const fs::path dir = fs::temp_directory_path() / "hof_world_contact_test";
  fs::create_directories(dir);
  std::ofstream(dir / name, std::ios::binary) << text;
  return dir / name;
}

// A deformable sheet over a rigid block (X3D), and a plate the project adds.
const std::string kScene =
    "<X3D profile='H3DAPI' version='1.4'><Scene>\n"
    "<DeformableShape DEF='Sheet'><CoordinateDeformer/><Appearance><Material/><SmoothSurface/></Appearance>"
    "<IndexedFaceSet solid='false' coordIndex='0 1 4 3 -1 1 2 5 4 -1 3 4 7 6 -1 4 5 8 7 -1'>"
    "<Coordinate point='-0.02 0.01 -0.02  0 0.01 -0.02  0.02 0.01 -0.02  -0.02 0.01 0  0 0.01 0  0.02 0.01 0  "
    "-0.02 0.01 0.02  0 0.01 0.02  0.02 0.01 0.02'/></IndexedFaceSet></DeformableShape>\n"
    "<Shape DEF='Block'><Appearance><Material/><SmoothSurface/></Appearance><Box size='0.04 0.01 0.04'/></Shape>\n"
    "</Scene></X3D>\n";

std::string project(const std::string& bodies, const std::string& contact) {
  return "<hof version=\"1\" name=\"contact\">\n  <mechanics scene=\"sheet.x3d\" unit=\"m\"/>\n" + bodies + contact +
         "</hof>\n";
}

const std::string kPlate = "v -0.1 -0.02 -0.1\nv 0.1 -0.02 -0.1\nv 0.1 -0.02 0.1\nv -0.1 -0.02 0.1\nf 1 3 2\nf 1 4 3\n";

TEST(WorldContact, WithoutContactNothingCollides) {
  write("sheet.x3d", kScene);
  auto world = build_world(write("none.hof", project("", "")));
  ASSERT_TRUE(world) << world.error().to_string();
  EXPECT_FALSE(world->config.contacts.enabled);
  for (const auto& b : world->bodies) EXPECT_FALSE(b.collision.enabled) << b.name;
}

TEST(WorldContact, ContactMakesEveryBodyCollideButThoseSwitchedOff) {
  write("sheet.x3d", kScene);
  write("plate.obj", kPlate);
  const std::string bodies =
      "  <bodies>\n    <obstacle name=\"Plate\" mesh=\"plate.obj\" translation=\"0 0 0\"/>\n  </bodies>\n";
  auto world = build_world(
      write("contact.hof", project(bodies,
                                   "  <contact stiffness=\"800\" friction=\"0.2\" alarmDistance=\"0.003\" "
                                   "contactDistance=\"0.001\">\n    <pair a=\"Plate\" b=\"Sheet\" enabled=\"false\"/>\n"
                                   "  </contact>\n")));
  ASSERT_TRUE(world) << world.error().to_string();
  const coupling::ContactSettings& s = world->config.contacts;
  EXPECT_TRUE(s.enabled);
  EXPECT_EQ(s.response, coupling::ContactResponse::kPenalty);
  EXPECT_EQ(s.stiffness_n_per_m, 800.0);
  EXPECT_EQ(s.friction, 0.2);
  EXPECT_EQ(s.alarm_distance_m, 0.003);
  EXPECT_EQ(s.contact_distance_m, 0.001);
  ASSERT_EQ(world->bodies.size(), 3u);
  std::int32_t sheet = -1, plate = -1;
  for (std::size_t i = 0; i < world->bodies.size(); ++i) {
    const coupling::SessionBody& b = world->bodies[i];
    // Each collides with its whole surface: triangles, edges and nodes; only the sheet moves.
    EXPECT_TRUE(b.collision.enabled && b.collision.triangles && b.collision.lines && b.collision.points) << b.name;
    EXPECT_EQ(b.collision.moving, b.deformable()) << b.name;
    if (b.name == "Sheet") sheet = static_cast<std::int32_t>(i);
    if (b.name == "Plate") plate = static_cast<std::int32_t>(i);
  }
  ASSERT_GE(sheet, 0);
  ASSERT_GE(plate, 0);
  EXPECT_TRUE(world->bodies[static_cast<std::size_t>(sheet)].deformable());
  // The pair switched off, by index, smaller first.
  ASSERT_EQ(s.disabled_pairs.size(), 1u);
  EXPECT_EQ(s.disabled_pairs[0], std::make_pair(std::min(sheet, plate), std::max(sheet, plate)));
}

TEST(WorldContact, ABodyOptsOutOrIn) {
  write("sheet.x3d", kScene);
  write("plate.obj", kPlate);
  // contact="false" on a body and on an obstacle: they take no part.
  auto world = build_world(write(
      "optout.hof",
      project(
          "  <bodies>\n    <body name=\"Block\" contact=\"false\"/>\n"
          "    <obstacle name=\"Plate\" mesh=\"plate.obj\" translation=\"0 0 0\" contact=\"false\"/>\n  </bodies>\n",
          "  <contact/>\n")));
  ASSERT_TRUE(world) << world.error().to_string();
  for (const auto& b : world->bodies) EXPECT_EQ(b.collision.enabled, b.name == "Sheet") << b.name;
}

TEST(WorldContact, PairsAndBodiesNotInTheWorldAreErrorsNamingTheProject) {
  write("sheet.x3d", kScene);
  auto world = build_world(
      write("badpair.hof",
            project("", "  <contact>\n    <pair a=\"Sheet\" b=\"Kidney\" enabled=\"false\"/>\n  </contact>\n")));
  ASSERT_FALSE(world);
  EXPECT_NE(world.error().to_string().find("badpair.hof"), std::string::npos) << world.error().to_string();
  EXPECT_NE(world.error().message.find("no body 'Kidney' in the world (bodies: Sheet, Block)"), std::string::npos)
      << world.error().message;
  world = build_world(
      write("selfpair.hof",
            project("", "  <contact>\n    <pair a=\"Sheet\" b=\"Sheet\" enabled=\"false\"/>\n  </contact>\n")));
  ASSERT_FALSE(world);
  EXPECT_NE(world.error().message.find("a pair needs two different bodies"), std::string::npos)
      << world.error().message;
}

TEST(WorldContact, BodiesAndPairsThatCannotCollideNameTheProjectsLine) {
  write("sheet.x3d", kScene);
  // contact="true" on a body the world does not have: the <body> element's line.
  auto world = build_world(
      write("optin.hof", project("  <bodies>\n    <body name=\"Kidney\" contact=\"true\"/>\n  </bodies>\n", "")));
  ASSERT_FALSE(world);
  EXPECT_NE(world.error().file.find("optin.hof"), std::string::npos) << world.error().to_string();
  EXPECT_EQ(world.error().line, 4) << world.error().to_string();
  EXPECT_NE(world.error().message.find("no body of that name"), std::string::npos) << world.error().message;
  // A pair naming a body the world does not have: the <contact> element's line.
  world =
      build_world(write("pairline.hof", project("",
                                                "  <contact>\n    <pair a=\"Sheet\" b=\"Kidney\" enabled=\"false\"/>\n"
                                                "  </contact>\n")));
  ASSERT_FALSE(world);
  EXPECT_EQ(world.error().line, 3) << world.error().to_string();
  EXPECT_NE(world.error().to_string().find("pairline.hof:3:"), std::string::npos) << world.error().to_string();
  // An obstacle whose mesh has no triangles (points only): the <obstacle> element's line.
  write("points.obj", "v 0 0 0\nv 1 0 0\nv 0 1 0\n");
  world = build_world(write("points.hof", project("  <bodies>\n    <obstacle name=\"Dots\" mesh=\"points.obj\"/>\n"
                                                  "  </bodies>\n",
                                                  "  <contact/>\n")));
  ASSERT_FALSE(world);
  EXPECT_NE(world.error().to_string().find("points.hof:4:"), std::string::npos) << world.error().to_string();
  EXPECT_NE(world.error().message.find("no triangles"), std::string::npos) << world.error().message;
}

// Over a SOFA scene: the scene's pipeline turns contact on and its bodies keep their own
// collision models; the project's obstacles collide with them; a <contact> replaces the
// scene's settings; contact="true" gives a body without models its whole surface.
TEST(WorldContact, OverASofaSceneTheProjectAddsAndReplaces) {
  write("plate.obj", kPlate);
  const std::string scene = std::string(HOF_SOURCE_DIR) + "/examples/organs-in-contact.scn";
  const std::string obstacle =
      "  <bodies>\n    <obstacle name=\"Tray\" mesh=\"plate.obj\" translation=\"0 0 -0.2\"/>\n  </bodies>\n";
  const auto with = [&](const std::string& bodies, const std::string& contact) {
    return "<hof version=\"1\" name=\"sofa\">\n  <mechanics scene=\"" + scene + "\" unit=\"m\"/>\n" + bodies + contact +
           "</hof>\n";
  };
  auto world = build_world(write("sofa_scene.hof", with(obstacle, "")));
  ASSERT_TRUE(world) << world.error().to_string();
  const coupling::ContactSettings& s = world->config.contacts;
  EXPECT_TRUE(s.enabled);
  EXPECT_DOUBLE_EQ(s.alarm_distance_m, 0.005);  // MinProximityIntersection in the scene
  EXPECT_DOUBLE_EQ(s.contact_distance_m, 0.0015);
  ASSERT_EQ(world->bodies.size(), 4u);  // Stomach, Liver, Support, Tray
  for (const auto& b : world->bodies) EXPECT_TRUE(b.collision.enabled) << b.name;
  EXPECT_EQ(world->bodies[0].collision.stiffness_n_per_m, 5000.0);  // its contactStiffness
  EXPECT_EQ(world->bodies[3].name, "Tray");
  EXPECT_FALSE(world->bodies[3].collision.moving);
  // <contact> replaces the scene's settings; the SOFA bodies keep their models.
  world = build_world(write("sofa_replaced.hof", with(obstacle,
                                                      "  <contact stiffness=\"300\" alarmDistance=\"0.01\" "
                                                      "contactDistance=\"0.002\"/>\n")));
  ASSERT_TRUE(world) << world.error().to_string();
  EXPECT_DOUBLE_EQ(world->config.contacts.alarm_distance_m, 0.01);
  EXPECT_DOUBLE_EQ(world->config.contacts.stiffness_n_per_m, 300.0);
  EXPECT_EQ(world->bodies[0].collision.stiffness_n_per_m, 5000.0);
  // A SOFA scene without collision models: contact="true" gives the body its whole surface.
  world = build_world(write("opt_in.hof", "<hof version=\"1\" name=\"in\">\n  <mechanics scene=\"" +
                                              std::string(HOF_SOURCE_DIR) +
                                              "/examples/liver-medium-fem.scn\" unit=\"m\"/>\n  <bodies>\n"
                                              "    <body name=\"Liver\" contact=\"true\"/>\n  </bodies>\n</hof>\n"));
  ASSERT_TRUE(world) << world.error().to_string();
  EXPECT_FALSE(world->config.contacts.enabled);  // no pipeline, no <contact>: nothing to collide with
  EXPECT_TRUE(world->bodies[0].collision.enabled && world->bodies[0].collision.triangles);
}

}  // namespace
}  // namespace hof::scene
