// Inputs at the limits: files nesting elements thousands deep are refused with a message
// naming the file and line, instead of overflowing the stack (the readers recurse) or running
// for minutes (an indented inline scene grows with the square of the depth).

#include <gtest/gtest.h>
#include <unistd.h>

#include <filesystem>
#include <fstream>
#include <string>

#include "hof/mesh/mesh_io.h"
#include "hof/mesh/xml_depth.h"
#include "hof/scene/project.h"
#include "hof/scene/sofa_scene.h"
#include "hof/scene/x3d_scene.h"

namespace hof::scene {
namespace {

namespace fs = std::filesystem;

std::string nested(const std::string& open, const std::string& close, int depth, const std::string& inner) {
  std::string text;
  for (int i = 0; i < depth; ++i) text += open;
  text += inner;
  for (int i = 0; i < depth; ++i) text += close;
  return text;
}

fs::path write(const std::string& name, const std::string& text) {
  const fs::path dir = fs::temp_directory_path() / ("hof-limits-" + std::to_string(::getpid()));
  fs::create_directories(dir);
  std::ofstream(dir / name) << text;
  return dir / name;
}

void expect_depth_error(const Error& e, const std::string& file, int line) {
  EXPECT_EQ(e.code, ErrorCode::kParse);
  EXPECT_NE(e.message.find("nested deeper than"), std::string::npos) << e.to_string();
  EXPECT_NE(e.file.find(file), std::string::npos) << e.to_string();
  EXPECT_EQ(e.line, line) << e.to_string();
}

constexpr int kDeep = 20000;

TEST(InputLimits, ASofaSceneNestingTwentyThousandNodesIsRefusedByLine) {
  const auto path = write("deep.scn", "<Node name=\"root\">\n" +
                                          nested("<Node>", "</Node>", kDeep, "<MechanicalObject position=\"0 0 0\"/>") +
                                          "\n</Node>\n");
  auto scene = read_sofa_scene(path);
  ASSERT_FALSE(scene);
  expect_depth_error(scene.error(), "deep.scn", 2);
}

TEST(InputLimits, AnX3dSceneNestingTwentyThousandGroupsIsRefused) {
  const auto path =
      write("deep.x3d", "<X3D>\n<Scene>\n" + nested("<Group>", "</Group>", kDeep, "<Shape><Box/></Shape>") +
                            "\n</Scene>\n</X3D>\n");
  auto scene = read_x3d_scene(path);
  ASSERT_FALSE(scene);
  expect_depth_error(scene.error(), "deep.x3d", 3);
}

TEST(InputLimits, AProjectWithADeepInlineSceneIsRefusedQuickly) {
  const auto path = write("deep.hof", "<hof version=\"1\">\n<mechanics>\n" + nested("<Node>", "</Node>", kDeep, "") +
                                          "\n</mechanics>\n</hof>\n");
  auto project = read_project(path);
  ASSERT_FALSE(project);
  expect_depth_error(project.error(), "deep.hof", 3);
}

TEST(InputLimits, AVtuFileNestingDeeplyIsRefused) {
  const auto path = write("deep.vtu", "<VTKFile type=\"UnstructuredGrid\">\n" +
                                          nested("<Piece>", "</Piece>", kDeep, "") + "\n</VTKFile>\n");
  auto read = mesh::read_mesh(path);
  ASSERT_FALSE(read);
  expect_depth_error(read.error(), "deep.vtu", 2);
}

TEST(InputLimits, AnX3dUseInsideTheNodeItNamesIsACycleNamedByLine) {
  const auto path = write(
      "cycle.x3d", "<X3D>\n<Scene>\n<Transform DEF=\"a\">\n<Transform USE=\"a\"/>\n</Transform>\n</Scene>\n</X3D>\n");
  auto scene = read_x3d_scene(path);
  ASSERT_FALSE(scene);
  EXPECT_NE(scene.error().message.find("a cycle"), std::string::npos) << scene.error().to_string();
  EXPECT_EQ(scene.error().line, 4);
}

TEST(InputLimits, AnX3dThatDoublesThroughUseFortyTimesIsRefusedNotExpanded) {
  // Each group USEs the previous one twice: 2^40 shapes from 42 lines ("billion laughs").
  std::string text = "<X3D>\n<Scene>\n<Group DEF=\"g0\"><Shape><Box/></Shape></Group>\n";
  for (int i = 1; i <= 40; ++i) {
    text += "<Group DEF=\"g" + std::to_string(i) + "\"><Group USE=\"g" + std::to_string(i - 1) + "\"/><Group USE=\"g" +
            std::to_string(i - 1) + "\"/></Group>\n";
  }
  text += "</Scene>\n</X3D>\n";
  auto scene = read_x3d_scene(write("laughs.x3d", text));
  ASSERT_FALSE(scene);
  EXPECT_NE(scene.error().message.find("expands to more than"), std::string::npos) << scene.error().to_string();
}

TEST(InputLimits, ScenesJustUnderTheLimitStillRead) {
  // The limit refuses only absurd files: a scene nesting 200 nodes is read.
  const auto path = write(
      "deep-ok.scn", "<Node name=\"root\">\n" +
                         nested("<Node>", "</Node>", 200, "<MechanicalObject position=\"0 0 0\"/>") + "\n</Node>\n");
  auto scene = read_sofa_scene(path);
  EXPECT_TRUE(scene) << scene.error().to_string();
}

}  // namespace
}  // namespace hof::scene

namespace hof::scene {
namespace {

TEST(InputLimits, ProjectCountsOutOfRangeAreErrorsNotConversions) {
  // Found by fuzz_hof: 3.3e85 was cast to int (undefined behaviour) before any check.
  for (const std::string& attribute : {std::string("<options maxTrianglesInLeaf=\"3.3e85\"/>"),
                                       std::string("<safety maxConsecutiveOverruns=\"-1e300\"/>"),
                                       std::string("<options maxTrianglesInLeaf=\"2.5\"/>")}) {
    const std::string text =
        "<hof version=\"1\">\n<mechanics scene=\"x.scn\"/>\n<haptics>\n" + attribute + "\n</haptics>\n</hof>\n";
    auto project = parse_project(text, "counts.hof");
    ASSERT_FALSE(project) << attribute;
    EXPECT_NE(project.error().message.find("whole number"), std::string::npos) << project.error().to_string();
    EXPECT_EQ(project.error().line, 4) << project.error().to_string();
  }
  const std::string grid =
      "<hof version=\"1\">\n<mechanics scene=\"x.scn\"/>\n<bodies>\n<body name=\"b\" model=\"hexahedra\" grid=\"1e300 "
      "4 4\"/>\n</bodies>\n</hof>\n";
  auto project = parse_project(grid, "grid.hof");
  ASSERT_FALSE(project);
  EXPECT_EQ(project.error().line, 4) << project.error().to_string();
}

}  // namespace
}  // namespace hof::scene
