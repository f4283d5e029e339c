// Gmsh .msh writing (src/hof/mesh/io_msh_write.cpp): exact round trips through versions 2.2 and 4.1.

#include <gtest/gtest.h>

#include <string>
#include <vector>

#include "hof/mesh/mesh_io.h"
#include "mesh_io_test_support.h"

namespace hof::mesh {
namespace {

using namespace io_test;

TEST_F(MeshIoTest, LiverRoundTripsExactlyThroughGmsh22And41) {
  const auto original = read_mesh(kLiverMsh);
  ASSERT_TRUE(original);
  const Mesh& m0 = original->mesh;

  ASSERT_TRUE(write_msh(m0, file("a.msh"), MshVersion::k2_2));
  const auto a = read_mesh(file("a.msh"));
  ASSERT_TRUE(a) << a.error().to_string();
  EXPECT_EQ(a->report.format, "gmsh-2.2-ascii");

  ASSERT_TRUE(write_msh(a->mesh, file("b.msh"), MshVersion::k4_1));
  const auto b = read_mesh(file("b.msh"));
  ASSERT_TRUE(b) << b.error().to_string();
  EXPECT_EQ(b->report.format, "gmsh-4.1-ascii");

  ASSERT_TRUE(write_msh(b->mesh, file("c.msh"), MshVersion::k2_2));
  const auto c = read_mesh(file("c.msh"));
  ASSERT_TRUE(c) << c.error().to_string();

  for (const auto* r : {&*a, &*b, &*c}) {
    EXPECT_TRUE(same_bits(r->mesh.nodes, m0.nodes));
    EXPECT_EQ(r->mesh.tets, m0.tets);
    EXPECT_EQ(r->mesh.tet_regions, m0.tet_regions);
    EXPECT_EQ(r->mesh, m0);
  }
  // Same mesh, same bytes.
  EXPECT_EQ(slurp(file("a.msh")), slurp(file("c.msh")));
}

TEST_F(MeshIoTest, SampleMeshRoundTripsThroughGmshBothVersions) {
  Mesh m = sample_mesh();
  m.normals.clear();  // Gmsh stores no normals
  for (const auto version : {MshVersion::k2_2, MshVersion::k4_1}) {
    ASSERT_TRUE(write_msh(m, file("s.msh"), version));
    const auto r = read_mesh(file("s.msh"));
    ASSERT_TRUE(r) << r.error().to_string();
    EXPECT_TRUE(same_bits(r->mesh.nodes, m.nodes));
    EXPECT_EQ(r->mesh, m);
  }
}

TEST_F(MeshIoTest, Gmsh41KeepsElementOrderWhenRegionsInterleave) {
  Mesh m = sample_mesh();
  m.normals.clear();
  m.tets = {{0, 1, 2, 3}, {1, 2, 3, 4}, {0, 1, 3, 4}, {0, 2, 3, 4}};
  m.tet_regions = {1, 2, 1, 2};
  ASSERT_TRUE(write_msh(m, file("i.msh"), MshVersion::k4_1));
  const auto r = read_mesh(file("i.msh"));
  ASSERT_TRUE(r) << r.error().to_string();
  EXPECT_EQ(r->mesh.tets, m.tets);
  EXPECT_EQ(r->mesh.tet_regions, m.tet_regions);
}

TEST_F(MeshIoTest, MeshWithoutRegionsRoundTripsWithoutRegions) {
  Mesh m = sample_mesh();
  m.normals.clear();
  m.tet_regions.clear();
  m.triangle_regions.clear();
  for (const auto version : {MshVersion::k2_2, MshVersion::k4_1}) {
    ASSERT_TRUE(write_msh(m, file("n.msh"), version));
    const auto r = read_mesh(file("n.msh"));
    ASSERT_TRUE(r) << r.error().to_string();
    EXPECT_EQ(r->mesh, m);
  }
  ASSERT_TRUE(write_vtu(m, file("n.vtu")));
  const auto v = read_mesh(file("n.vtu"));
  ASSERT_TRUE(v) << v.error().to_string();
  EXPECT_EQ(v->mesh, m);
}

}  // namespace
}  // namespace hof::mesh
