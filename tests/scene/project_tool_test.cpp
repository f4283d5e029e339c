// The project's <tool> (a rigid tool with a shape on the stylus), the --tool spec and the world
// that mounts it: read, written back, and bad input refused with the file, line and attribute.

#include <gtest/gtest.h>

#include <filesystem>
#include <fstream>

#include "hof/scene/project.h"
#include "hof/scene/world.h"

namespace hof::scene {
namespace {

std::string project_text(const std::string& tool) {
  return "<hof version=\"1\" name=\"t\">\n"
         "  <mechanics scene=\"x.scn\" unit=\"m\"/>\n"
         "  <haptics>\n"
         "    " +
         tool +
         "\n"
         "  </haptics>\n"
         "</hof>\n";
}

std::filesystem::path temp_dir() {
  const auto dir = std::filesystem::temp_directory_path() / "hof_project_tool_test";
  std::filesystem::create_directories(dir);
  return dir;
}

// A unit cube as OBJ; `open` leaves out its last face.
void write_cube(const std::filesystem::path& path, bool open) {
  std::ofstream out(path);
  out << "v 0 0 0\nv 1 0 0\nv 1 1 0\nv 0 1 0\nv 0 0 1\nv 1 0 1\nv 1 1 1\nv 0 1 1\n";
  out << "f 1 4 3\nf 1 3 2\nf 5 6 7\nf 5 7 8\nf 1 2 6\nf 1 6 5\nf 4 8 7\nf 4 7 3\nf 1 5 8\nf 1 8 4\n";
  if (!open) out << "f 2 3 7\nf 2 7 6\n";
}

TEST(ProjectTool, ReadsAndWritesItBack) {
  const auto dir = temp_dir();
  auto p = parse_project(
      project_text(R"(<tool shape="capsule" radius="0.004" length="0.05" orientation="0 1 0 1.5" stiffness="500"/>)"),
      dir / "a.hof");
  ASSERT_TRUE(p) << p.error().to_string();
  ASSERT_TRUE(p->tool);
  EXPECT_EQ(p->tool->shape, procedures::ToolShape::kCapsule);
  EXPECT_EQ(p->tool->radius_m, 0.004);
  EXPECT_EQ(p->tool->length_m, 0.05);
  EXPECT_EQ(p->tool->orientation[3], 1.5);
  EXPECT_EQ(p->tool->stiffness_n_per_m, 500.0);
  ASSERT_TRUE(write_project(*p, dir / "a.hof"));
  auto again = read_project(dir / "a.hof");
  ASSERT_TRUE(again) << again.error().to_string();
  EXPECT_EQ(again->tool, p->tool);
  // Without <tool>: none.
  auto none = parse_project(project_text(""), dir / "b.hof");
  ASSERT_TRUE(none) << none.error().to_string();
  EXPECT_FALSE(none->tool);
}

TEST(ProjectTool, BadInputNamesTheFileLineAndAttribute) {
  const auto dir = temp_dir();
  const auto refused = [&](const std::string& tool, const std::string& words) {
    auto p = parse_project(project_text(tool), dir / "bad.hof");
    ASSERT_FALSE(p) << tool;
    EXPECT_NE(p.error().file.find("bad.hof"), std::string::npos);
    EXPECT_EQ(p.error().line, 4) << p.error().to_string();
    EXPECT_NE(p.error().message.find(words), std::string::npos) << p.error().to_string();
  };
  refused(R"(<tool shape="sphere" radius="-0.001"/>)", "radius");
  refused(R"(<tool shape="capsule" radius="0.004" length="-0.01"/>)", "length");
  refused(R"(<tool shape="cone"/>)", "sphere, capsule or mesh");
  refused(R"(<tool shape="mesh"/>)", "mesh=");
  refused(R"(<tool shape="mesh" mesh="nowhere.obj"/>)", "not found");
  write_cube(dir / "open.obj", true);
  refused(R"(<tool shape="mesh" mesh="open.obj"/>)", "not closed");
  write_cube(dir / "cube.obj", false);
  auto ok = parse_project(project_text(R"(<tool shape="mesh" mesh="cube.obj" radius="0.001"/>)"), dir / "ok.hof");
  EXPECT_TRUE(ok) << ok.error().to_string();
}

TEST(ToolSpec, ParsesTheShapeAndAttributes) {
  auto t = parse_tool_spec("capsule,radius=0.004,length=0.05,orientation=0 1 0 1.5");
  ASSERT_TRUE(t) << t.error().to_string();
  EXPECT_EQ(t->shape, procedures::ToolShape::kCapsule);
  EXPECT_EQ(t->radius_m, 0.004);
  EXPECT_EQ(t->length_m, 0.05);
  EXPECT_EQ(t->orientation[1], 1.0);
  EXPECT_TRUE(parse_tool_spec("sphere"));
  EXPECT_NE(parse_tool_spec("sphere,radius=-1").error().message.find("radius"), std::string::npos);
  EXPECT_NE(parse_tool_spec("sphere,size=1").error().message.find("unknown attribute \"size\""), std::string::npos);
  EXPECT_NE(parse_tool_spec("sphere,0.01").error().message.find("ATTRIBUTE=VALUE"), std::string::npos);
}

TEST(ToolSpec, TheWorldMountsTheToolAndItsTissueCoupling) {
  auto w = build_world(std::filesystem::path(HOF_SOURCE_DIR) / "examples/capsule-liver.hof");
  ASSERT_TRUE(w) << w.error().to_string();
  ASSERT_TRUE(w->project.tool);
  ASSERT_TRUE(w->config.tool);
  ASSERT_TRUE(w->config.tool_coupling);
  const auto* tool = dynamic_cast<const procedures::ShapedTool*>(w->config.tool.get());
  ASSERT_NE(tool, nullptr);
  EXPECT_EQ(tool->primitives().size(), 1u);
  EXPECT_NEAR(tool->primitives().front().b.norm(), 0.05, 1e-15);
  // Mounted in place of it by the spec.
  auto sphere = parse_tool_spec("sphere,radius=0.006");
  ASSERT_TRUE(sphere);
  ASSERT_TRUE(mount_tool(*w, *sphere));
  tool = dynamic_cast<const procedures::ShapedTool*>(w->config.tool.get());
  ASSERT_NE(tool, nullptr);
  EXPECT_EQ(tool->primitives().front().radius, 0.006);
}

// Two hands (<tool device=…>): the first tool without device= is the project device's; each
// other device is one more hand with its tool and its own force limit, written back as read.
TEST(ProjectHands, TwoToolsOnTwoDevicesAreReadIntoTheTypedConfig) {
  const auto dir = temp_dir();
  const std::string tools =
      R"(<tool shape="capsule" radius="0.004" length="0.05"/>)"
      "\n    "
      R"(<tool shape="sphere" radius="0.006" device="scripted:poke,start=0.03;0;0.1" maxForce="2"/>)";
  auto p = parse_project(project_text(tools), dir / "hands.hof");
  ASSERT_TRUE(p) << p.error().to_string();
  ASSERT_TRUE(p->tool);
  EXPECT_EQ(p->tool->shape, procedures::ToolShape::kCapsule);
  ASSERT_EQ(p->hands.size(), 1u);
  EXPECT_EQ(p->hands[0].tool.shape, procedures::ToolShape::kSphere);
  EXPECT_EQ(p->hands[0].tool.radius_m, 0.006);
  EXPECT_EQ(p->hands[0].tool.device, "scripted:poke,start=0.03;0;0.1");
  EXPECT_EQ(p->hands[0].max_force_n, 2.0);
  EXPECT_EQ(p->hands[0].line, 5);
  ASSERT_TRUE(write_project(*p, dir / "hands.hof"));
  auto again = read_project(dir / "hands.hof");
  ASSERT_TRUE(again) << again.error().to_string();
  EXPECT_EQ(again->tool, p->tool);
  ASSERT_EQ(again->hands.size(), 1u);
  EXPECT_EQ(again->hands[0].tool, p->hands[0].tool);
  EXPECT_EQ(again->hands[0].max_force_n, 2.0);

  // A project without a device of its own: the first tool's device is the first hand.
  auto named = parse_project(
      project_text(R"(<tool shape="sphere" device="scripted:poke"/><tool shape="sphere" device="scripted:hold"/>)"),
      dir / "named.hof");
  ASSERT_TRUE(named) << named.error().to_string();
  EXPECT_EQ(named->device, "scripted:poke");
  ASSERT_TRUE(named->tool);
  ASSERT_EQ(named->hands.size(), 1u);
  EXPECT_EQ(named->hands[0].tool.device, "scripted:hold");
}

// The bundled two-hand example: a world with two hands, each with its tool, device and limit.
TEST(ProjectHands, TheWorldOfTheTwoHandExampleHasBothHands) {
  auto w = build_world(std::filesystem::path(HOF_SOURCE_DIR) / "examples/two-hands-liver.hof");
  ASSERT_TRUE(w) << w.error().to_string();
  ASSERT_TRUE(w->config.tool);
  ASSERT_EQ(w->config.more_hands.size(), 1u);
  const coupling::HandConfig& hand = w->config.more_hands[0];
  ASSERT_TRUE(hand.tool);
  ASSERT_TRUE(hand.tool_coupling);
  EXPECT_NE(hand.tool, w->config.tool);
  EXPECT_TRUE(hand.device.starts_with("scripted:"));
  EXPECT_NE(hand.device, w->device);
  EXPECT_GT(hand.haptics.safety.max_force_n, 0.0);
  EXPECT_NE(hand.haptics.safety.max_force_n, w->config.haptics.safety.max_force_n);
  EXPECT_EQ(hand.haptics.rate_hz, w->config.haptics.rate_hz);
}

TEST(ProjectHands, BadInputNamesTheFileAndLine) {
  const auto dir = temp_dir();
  const auto refused = [&](const std::string& tools, std::int64_t line, const std::string& words) {
    auto p = parse_project(project_text(tools), dir / "bad-hands.hof");
    ASSERT_FALSE(p) << tools;
    EXPECT_NE(p.error().file.find("bad-hands.hof"), std::string::npos);
    EXPECT_EQ(p.error().line, line) << p.error().to_string();
    EXPECT_NE(p.error().message.find(words), std::string::npos) << p.error().to_string();
  };
  // An unknown device.
  refused(R"(<tool shape="sphere" device="telepathy"/>)", 4, "device=\"telepathy\"");
  refused(R"(<tool shape="sphere" device="scripted:wave"/>)", 4, "device=\"scripted:wave\"");
  // Two tools on the same device: another hand's, or the first hand's twice.
  refused(
      "<tool shape=\"sphere\"/>\n    <tool shape=\"sphere\" device=\"scripted:hold\"/>\n"
      "    <tool shape=\"capsule\" device=\"scripted:hold\"/>",
      6, "a second <tool> on the device \"scripted:hold\" (the first is at line 5)");
  refused("<tool shape=\"sphere\"/>\n    <tool shape=\"capsule\"/>", 5, "a second <tool> on the device");
  // A force limit that is not a limit.
  refused(R"(<tool shape="sphere" device="scripted:hold" maxForce="-1"/>)", 4, "maxForce");
}

}  // namespace
}  // namespace hof::scene
