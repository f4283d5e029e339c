// .stl reading (src/hof/mesh/io_stl.cpp): ASCII welding, binary detection and bad input.

#include <gtest/gtest.h>

#include <string>
#include <vector>

#include "hof/mesh/mesh_io.h"
#include "mesh_io_test_support.h"

namespace hof::mesh {
namespace {

using namespace io_test;

TEST_F(MeshIoTest, StlAsciiWeldsByExactPositionInOrderOfAppearance) {
  const auto r = read_mesh(write("two.stl",
                                 "solid two\n"
                                 "  facet normal 0 0 1\n    outer loop\n"
                                 "      vertex 0 0 0\n      vertex 1 0 0\n      vertex 1 1 0\n"
                                 "    endloop\n  endfacet\n"
                                 "  facet normal nan nan nan\n    outer loop\n"
                                 "      vertex -0 0 0\n      vertex 1 1 0\n      vertex 0 1 0\n"
                                 "    endloop\n  endfacet\n"
                                 "endsolid two\n"));
  ASSERT_TRUE(r) << r.error().to_string();
  EXPECT_EQ(r->report.format, "stl-ascii");
  EXPECT_EQ(r->mesh.nodes, (std::vector<Vec3>{Vec3(0, 0, 0), Vec3(1, 0, 0), Vec3(1, 1, 0), Vec3(0, 1, 0)}));
  EXPECT_EQ(r->mesh.triangles, (std::vector<Tri>{{0, 1, 2}, {0, 2, 3}}));
}

TEST_F(MeshIoTest, StlBinaryIsDetectedBySizeEvenWhenHeaderSaysSolid) {
  const auto r = read_mesh(write("bin.stl", binary_stl({{0, 0, 0, 1, 0, 0, 1, 1, 0}, {0, 0, 0, 1, 1, 0, 0, 1, 0.1f}})));
  ASSERT_TRUE(r) << r.error().to_string();
  EXPECT_EQ(r->report.format, "stl-binary");
  ASSERT_EQ(r->mesh.nodes.size(), 4u);
  EXPECT_EQ(r->mesh.nodes[3], Vec3(0, 1, static_cast<double>(0.1f)));
  EXPECT_EQ(r->mesh.triangles, (std::vector<Tri>{{0, 1, 2}, {0, 2, 3}}));
}

TEST_F(MeshIoTest, StlBadInput) {
  expect_error_at(read_error("empty.stl", ""), ErrorCode::kParse, "empty.stl", 1, "file is empty");
  expect_error_at(read_error("open.stl", "solid x\nfacet normal 0 0 1\nouter loop\nvertex 0 0 0\n"), ErrorCode::kParse,
                  "open.stl", 4, "unexpected end of file");
  expect_error_at(read_error("word.stl", "solid x\nfacet normal 0 0 1\nouter loop\nvertex 0 a 0\n"), ErrorCode::kParse,
                  "word.stl", 4, "found 'a'");
  expect_error_at(read_error("four.stl",
                             "solid x\nfacet normal 0 0 1\nouter loop\n"
                             "vertex 0 0 0\nvertex 1 0 0\nvertex 0 1 0\nvertex 1 1 0\n"
                             "endloop\nendfacet\nendsolid x\n"),
                  ErrorCode::kParse, "four.stl", 7, "expected 'endloop'");
  const Error nan = read_error("nan.stl", binary_stl({{0, 0, 0, 1, 0, std::nanf(""), 1, 1, 0}}));
  EXPECT_EQ(nan.code, ErrorCode::kInvalidMesh);
  EXPECT_NE(nan.to_string().find("nan.stl: byte 108: "), std::string::npos) << nan.to_string();
  for (unsigned seed = 1; seed <= 20; ++seed) {
    const Error e = read_error("garbage.stl", garbage(4096, seed));
    EXPECT_EQ(e.code, ErrorCode::kParse) << e.to_string();
    EXPECT_NE(e.to_string().find("garbage.stl: byte 80: not an STL file"), std::string::npos) << e.to_string();
  }
  // A binary file one byte short of what its count says.
  std::string cut = binary_stl({{0, 0, 0, 1, 0, 0, 1, 1, 0}, {0, 0, 0, 1, 1, 0, 0, 1, 0}}, "binary");
  cut.pop_back();
  const Error c = read_error("cut.stl", cut);
  EXPECT_NE(c.to_string().find("does not match a binary STL of 2 triangles"), std::string::npos) << c.to_string();
}

}  // namespace
}  // namespace hof::mesh
