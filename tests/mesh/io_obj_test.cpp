// Wavefront .obj reading and writing (src/hof/mesh/io_obj.cpp): the SOFA livers read in place, round
// trips, every index form, and bad input.

#include <gtest/gtest.h>

#include <string>
#include <vector>

#include "hof/mesh/mesh_io.h"
#include "mesh_io_test_support.h"

namespace hof::mesh {
namespace {

using namespace io_test;

TEST(MeshIoAnchors, LiverObjHas181VerticesAnd274Triangles) {
  const auto r = read_mesh(kLiverObj);  // CRLF line ends
  ASSERT_TRUE(r) << r.error().to_string();
  EXPECT_EQ(r->report.format, "obj");
  EXPECT_EQ(r->mesh.nodes.size(), 181u);
  EXPECT_EQ(r->mesh.triangles.size(), 274u);
  EXPECT_TRUE(r->mesh.normals.empty());
  EXPECT_EQ(r->mesh.triangles.front(), (Tri{0, 1, 2}));
}

TEST(MeshIoAnchors, LiverSmoothObjHasPerVertexNormals) {
  const auto r = read_mesh(kLiverSmoothObj);
  ASSERT_TRUE(r) << r.error().to_string();
  EXPECT_EQ(r->mesh.nodes.size(), 2194u);
  EXPECT_EQ(r->mesh.triangles.size(), 4384u);
  ASSERT_EQ(r->mesh.normals.size(), 2194u);
  // "f 1//1 2194//2 1375//3": vertex 1 first gets vn 1.
  EXPECT_EQ(r->mesh.triangles.front(), (Tri{0, 2193, 1374}));
  EXPECT_EQ(r->mesh.normals[0], Vec3(0.324945, -0.640133, 0.696161));
  EXPECT_EQ(r->mesh.normals[2193], Vec3(0.352111, -0.885083, -0.304377));
  EXPECT_TRUE(r->report.warnings.empty());
}

TEST_F(MeshIoTest, ObjRoundTripKeepsTrianglesAndNormals) {
  Mesh m = sample_mesh();
  m.tets.clear();
  m.tet_regions.clear();
  m.triangle_regions.clear();  // OBJ stores no regions
  ASSERT_TRUE(write_obj(m, file("s.obj")));
  const auto r = read_mesh(file("s.obj"));
  ASSERT_TRUE(r) << r.error().to_string();
  EXPECT_TRUE(same_bits(r->mesh.nodes, m.nodes));
  EXPECT_EQ(r->mesh, m);

  m.normals.clear();
  ASSERT_TRUE(write_obj(m, file("plain.obj")));
  const auto plain = read_mesh(file("plain.obj"));
  ASSERT_TRUE(plain);
  EXPECT_EQ(plain->mesh, m);
}

TEST_F(MeshIoTest, LiverSmoothObjRoundTripsExactly) {
  const auto original = read_mesh(kLiverSmoothObj);
  ASSERT_TRUE(original);
  ASSERT_TRUE(write_mesh(original->mesh, file("smooth.obj")));
  const auto back = read_mesh(file("smooth.obj"));
  ASSERT_TRUE(back) << back.error().to_string();
  EXPECT_EQ(back->mesh, original->mesh);
}

TEST_F(MeshIoTest, ObjAllIndexFormsQuadAndNegativeIndices) {
  const auto path = write("forms.obj",
                          "# all face forms\n"
                          "mtllib forms.mtl\n"
                          "o thing\n"
                          "v 0 0 0\n"
                          "v 1 0 0\n"
                          "v 1 1 0\n"
                          "v 0 1 0\n"
                          "v 0 0 1 1.0\n"  // optional w
                          "vt 0 0\nvt 1 0\nvt 1 1\n"
                          "vn 0 0 1\nvn 0 0 -1\n"
                          "g group\nusemtl red\ns off\n"
                          "f 1 2 3\n"
                          "f 1/1 2/2 3/3\n"
                          "f 1//1 3//1 4//1\n"
                          "f 1/1/2 2/2/2 5/3/2   # comment after a face\n"
                          "f -5 -4 -3 -2\n"  // quad, relative indices
                          "l 1 2\n"
                          "p 1\n"
                          "f -1/-1/-1 -2/-2/-1 -3/-3/-2\n"
                          "f 1 2 \\\n 4\n");  // continued line
  const auto r = read_mesh(path);
  ASSERT_TRUE(r) << r.error().to_string();
  EXPECT_EQ(r->mesh.nodes.size(), 5u);
  EXPECT_EQ(r->mesh.triangles,
            (std::vector<Tri>{{0, 1, 2}, {0, 1, 2}, {0, 2, 3}, {0, 1, 4}, {0, 1, 2}, {0, 2, 3}, {4, 3, 2}, {0, 1, 3}}));
  // The first normal a face gives a vertex wins.
  ASSERT_EQ(r->mesh.normals.size(), 5u);
  EXPECT_EQ(r->mesh.normals[0], Vec3(0, 0, 1));
  EXPECT_EQ(r->mesh.normals[1], Vec3(0, 0, -1));
  EXPECT_EQ(r->mesh.normals[2], Vec3(0, 0, 1));
  EXPECT_EQ(r->mesh.normals[3], Vec3(0, 0, 1));
  EXPECT_EQ(r->mesh.normals[4], Vec3(0, 0, -1));
  EXPECT_EQ(r->report.ignored_lines, 1);
  EXPECT_EQ(r->report.ignored_points, 1);
  EXPECT_TRUE(r->report.warnings.empty());
}

TEST_F(MeshIoTest, ObjVerticesWithoutNormalGetZeroAndAWarning) {
  const auto r = read_mesh(write("partial.obj",
                                 "v 0 0 0\nv 1 0 0\nv 0 1 0\nv 0 0 1\n"
                                 "vn 0 0 1\nf 1//1 2//1 3//1\n"));
  ASSERT_TRUE(r) << r.error().to_string();
  ASSERT_EQ(r->mesh.normals.size(), 4u);
  EXPECT_EQ(r->mesh.normals[3], Vec3::Zero());
  ASSERT_EQ(r->report.warnings.size(), 1u);
  EXPECT_NE(r->report.warnings[0].find("1 vertices have no normal"), std::string::npos);
}

TEST_F(MeshIoTest, ObjBadInput) {
  expect_error_at(read_error("empty.obj", ""), ErrorCode::kParse, "empty.obj", 1, "file is empty");
  expect_error_at(read_error("range.obj", "v 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 4\n"), ErrorCode::kInvalidMesh, "range.obj",
                  4, "vertex index 4 is out of range");
  expect_error_at(read_error("neg.obj", "v 0 0 0\nv 1 0 0\nv 0 1 0\nf -1 -2 -4\n"), ErrorCode::kInvalidMesh, "neg.obj",
                  4, "vertex index -4 is out of range");
  expect_error_at(read_error("zero.obj", "v 0 0 0\nv 1 0 0\nv 0 1 0\nf 0 1 2\n"), ErrorCode::kInvalidMesh, "zero.obj",
                  4, "index 0");
  expect_error_at(read_error("normal.obj", "v 0 0 0\nv 1 0 0\nv 0 1 0\nvn 0 0 1\nf 1//1 2//2 3//1\n"),
                  ErrorCode::kInvalidMesh, "normal.obj", 5, "normal index 2 is out of range");
  expect_error_at(read_error("nan.obj", "v 0 0 0\nv 1 NaN 0\n"), ErrorCode::kInvalidMesh, "nan.obj", 2,
                  "not a finite number");
  expect_error_at(read_error("word.obj", "v 0 0 0\nv 1 x 0\n"), ErrorCode::kParse, "word.obj", 2,
                  "'x' is not a number");
  expect_error_at(read_error("short.obj", "v 0 0\n"), ErrorCode::kParse, "short.obj", 1, "needs 3 values, found 2");
  expect_error_at(read_error("face.obj", "v 0 0 0\nv 1 0 0\nf 1 2\n"), ErrorCode::kInvalidMesh, "face.obj", 3,
                  "face with 2 vertices");
  expect_error_at(read_error("form.obj", "v 0 0 0\nv 1 0 0\nv 0 1 0\nf 1/ 2 3\n"), ErrorCode::kParse, "form.obj", 4,
                  "bad face vertex '1/'");
  expect_error_at(read_error("novert.obj", "# nothing\ng x\n"), ErrorCode::kInvalidMesh, "novert.obj", 2,
                  "no vertices");
  expect_error_at(read_error("unknown.obj", "v 0 0 0\nbogus 1 2\n"), ErrorCode::kParse, "unknown.obj", 2,
                  "unknown OBJ statement 'bogus'");
}

TEST_F(MeshIoTest, ObjBinaryGarbage) {
  for (unsigned seed = 1; seed <= 20; ++seed) {
    const Error e = read_error("garbage.obj", garbage(4096, seed));
    EXPECT_TRUE(e.code == ErrorCode::kParse || e.code == ErrorCode::kInvalidMesh) << e.to_string();
    EXPECT_GE(e.line, 1);
    EXPECT_LE(e.line, 40) << e.to_string();
  }
}

}  // namespace
}  // namespace hof::mesh
