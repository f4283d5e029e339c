// .off reading and writing (src/hof/mesh/io_off.cpp): round trips, reader features and bad input.

#include <gtest/gtest.h>

#include <string>
#include <vector>

#include "hof/mesh/mesh_io.h"
#include "mesh_io_test_support.h"

namespace hof::mesh {
namespace {

using namespace io_test;

TEST_F(MeshIoTest, OffRoundTripKeepsTriangles) {
  Mesh m = sample_mesh();
  m.tets.clear();
  m.tet_regions.clear();
  m.triangle_regions.clear();
  m.normals.clear();
  ASSERT_TRUE(write_off(m, file("s.off")));
  const auto r = read_mesh(file("s.off"));
  ASSERT_TRUE(r) << r.error().to_string();
  EXPECT_EQ(r->report.format, "off");
  EXPECT_TRUE(same_bits(r->mesh.nodes, m.nodes));
  EXPECT_EQ(r->mesh, m);
}

TEST_F(MeshIoTest, OffWithCommentsColoursAndAQuad) {
  const auto r = read_mesh(write("quad.off",
                                 "COFF # coloured\n"
                                 "# counts follow\n"
                                 "4 1 0\n"
                                 "0 0 0 255 0 0 255\n"
                                 "1 0 0 255 0 0 255\n"
                                 "1 1 0 255 0 0 255\n"
                                 "0 1 0 255 0 0 255\n"
                                 "4 0 1 2 3 0.5 0.5 0.5\n"));
  ASSERT_TRUE(r) << r.error().to_string();
  EXPECT_EQ(r->mesh.nodes.size(), 4u);
  EXPECT_EQ(r->mesh.triangles, (std::vector<Tri>{{0, 1, 2}, {0, 2, 3}}));
}

TEST_F(MeshIoTest, OffBadInput) {
  expect_error_at(read_error("empty.off", ""), ErrorCode::kParse, "empty.off", 1, "file is empty");
  expect_error_at(read_error("header.off", "PLY\n3 1 0\n"), ErrorCode::kParse, "header.off", 1, "not an OFF file");
  // One vertex short: the face line is taken as vertex 4, then the face is missing.
  expect_error_at(read_error("few.off", "OFF\n4 1 0\n0.25 0.25 0.25\n1.25 0.25 0.25\n0.25 1.25 0.25\n3 0 1 2\n"),
                  ErrorCode::kParse, "few.off", 6, "face 1 of 1");
  expect_error_at(read_error("short.off", "OFF\n4 1 0\n0 0 0\n1 0 0\n0 1 0\n3 0 1 2\n"), ErrorCode::kParse, "short.off",
                  2, "face count 1 is impossible");
  expect_error_at(read_error("more.off", "OFF\n3 1 0\n0 0 0\n1 0 0\n0 1 0\n3 0 1 2\n3 0 1 2\n"), ErrorCode::kParse,
                  "more.off", 7, "face count is wrong");
  expect_error_at(read_error("range.off", "OFF\n3 1 0\n0 0 0\n1 0 0\n0 1 0\n3 0 1 3\n"), ErrorCode::kInvalidMesh,
                  "range.off", 6, "vertex index 3 is out of range");
  expect_error_at(read_error("nan.off", "OFF\n3 1 0\n0 0 0\n1 0 inf\n0 1 0\n3 0 1 2\n"), ErrorCode::kInvalidMesh,
                  "nan.off", 4, "not a finite number");
  expect_error_at(read_error("huge.off", "OFF\n99999999999 1 0\n0 0 0\n"), ErrorCode::kParse, "huge.off", 2,
                  "vertex count 99999999999 is impossible");
  for (unsigned seed = 1; seed <= 20; ++seed) {
    const Error e = read_error("garbage.off", garbage(4096, seed));
    EXPECT_EQ(e.code, ErrorCode::kParse) << e.to_string();
    EXPECT_LE(e.line, 40) << e.to_string();
  }
}

}  // namespace
}  // namespace hof::mesh
