// The surface the haptic loop touches (src/hof/haptics/surface_snapshot.cpp): area-weighted
// vertex normals, face and Phong-shaded normals, several bodies in one snapshot with their
// parts, and updates that move the geometry, its normals and its tree together.

#include "hof/haptics/surface_snapshot.h"

#include <gtest/gtest.h>

#include <array>
#include <cmath>
#include <limits>
#include <vector>

namespace hof::haptics {
namespace {

// A roof: two planes meeting at 90° along the ridge y = 0, z = 1 (x from 0 to 1), two
// triangles each. Left normal (0, −1, 1)/√2, right (0, 1, 1)/√2.
mesh::TriMesh roof() {
  mesh::TriMesh m;
  m.vertices = {Vec3(0, -1, 0), Vec3(1, -1, 0), Vec3(1, 0, 1), Vec3(0, 0, 1), Vec3(0, 1, 0), Vec3(1, 1, 0)};
  m.triangles = {{0, 1, 2}, {0, 2, 3}, {3, 2, 5}, {3, 5, 4}};
  return m;
}

mesh::TriMesh square(double z) {
  mesh::TriMesh m;
  m.vertices = {Vec3(0, 0, z), Vec3(1, 0, z), Vec3(1, 1, z), Vec3(0, 1, z)};
  m.triangles = {{0, 1, 2}, {0, 2, 3}};
  return m;
}

TEST(SurfaceSnapshot, VertexNormalsAreAreaWeightedFaceNormals) {
  const SurfaceSnapshot s = make_snapshot(roof());
  const double r2 = std::sqrt(2.0), r10 = std::sqrt(10.0);
  EXPECT_LT((s.face_normal(0) - Vec3(0, -1, 1) / r2).norm(), 1e-15);
  EXPECT_LT((s.face_normal(3) - Vec3(0, 1, 1) / r2).norm(), 1e-15);
  // Vertex 2 is in two left triangles and one right one (equal areas); vertex 3 the reverse.
  EXPECT_LT((s.vertex_normals[2] - Vec3(0, -1, 3) / r10).norm(), 1e-15);
  EXPECT_LT((s.vertex_normals[3] - Vec3(0, 1, 3) / r10).norm(), 1e-15);
  EXPECT_LT((s.vertex_normals[0] - Vec3(0, -1, 1) / r2).norm(), 1e-15);  // one plane only
  for (const Vec3& n : s.vertex_normals) EXPECT_NEAR(n.norm(), 1.0, 1e-15);
}

TEST(SurfaceSnapshot, ShadedNormalsInterpolateTheVertexNormals) {
  const SurfaceSnapshot s = make_snapshot(roof());
  // At a vertex, its normal; halfway along the ridge, straight up.
  EXPECT_LT((s.shaded_normal(1, Vec3(0, 1, 0)) - s.vertex_normals[2]).norm(), 1e-15);
  EXPECT_LT((s.shaded_normal(1, Vec3(0, 0.5, 0.5)) - Vec3(0, 0, 1)).norm(), 1e-15);
  EXPECT_NEAR(s.shaded_normal(0, Vec3(0.2, 0.3, 0.5)).norm(), 1.0, 1e-15);
}

TEST(SurfaceSnapshot, ADegenerateTriangleHasNoFaceNormalAndShadingFallsBackToTheFace) {
  mesh::TriMesh m;
  m.vertices = {Vec3(0, 0, 0), Vec3(1, 0, 0), Vec3(2, 0, 0)};
  m.triangles = {{0, 1, 2}};
  SurfaceSnapshot s = make_snapshot(m);
  EXPECT_EQ(s.face_normal(0), Vec3::Zero());
  EXPECT_EQ(s.vertex_normals[1], Vec3::Zero());
  EXPECT_EQ(s.shaded_normal(0, Vec3(1, 0, 0)), Vec3::Zero());
  // Opposite vertex normals cancel: the face normal stands in.
  SurfaceSnapshot flat = make_snapshot(square(0.0));
  flat.vertex_normals[0] = Vec3(0, 0, 1);
  flat.vertex_normals[1] = Vec3(0, 0, -1);
  EXPECT_EQ(flat.shaded_normal(0, Vec3(0.5, 0.5, 0)), Vec3(0, 0, 1));
}

TEST(SurfaceSnapshot, SeveralSurfacesShareOneSnapshotAsParts) {
  const std::array<mesh::TriMesh, 2> surfaces{square(0.0), roof()};
  const std::array<bool, 2> is_static{true, false};
  const std::array<bool, 2> closed{false, true};
  const SurfaceSnapshot s = make_snapshot(surfaces, is_static, closed);
  ASSERT_EQ(s.vertices.size(), 10u);
  ASSERT_EQ(s.triangles.size(), 6u);
  ASSERT_EQ(s.parts.size(), 2u);
  EXPECT_EQ(s.parts[1].first_vertex, 4);
  EXPECT_EQ(s.parts[1].vertex_count, 6);
  EXPECT_EQ(s.parts[1].first_triangle, 2);
  EXPECT_EQ(s.parts[1].triangle_count, 4);
  EXPECT_TRUE(s.parts[0].is_static);
  EXPECT_FALSE(s.parts[1].is_static);
  EXPECT_TRUE(s.parts[1].closed);
  EXPECT_FALSE(s.is_static);  // one body is simulated
  // The second surface's triangles index its own vertices, moved past the first's.
  EXPECT_EQ(s.triangles[2], (mesh::Tri{4, 5, 6}));
  EXPECT_EQ(s.point(2, Vec3(0, 0, 1)), Vec3(1, 0, 1));
  EXPECT_EQ(s.part_of(0), 0);
  EXPECT_EQ(s.part_of(1), 0);
  EXPECT_EQ(s.part_of(2), 1);
  EXPECT_EQ(s.part_of(5), 1);
  EXPECT_EQ(s.part_of(6), -1);
  EXPECT_EQ(s.part_of(-1), -1);
  // All rigid, or nothing at all: never stale.
  const std::array<bool, 2> both{true, true};
  EXPECT_TRUE(make_snapshot(surfaces, both, closed).is_static);
  EXPECT_TRUE(make_snapshot(std::span<const mesh::TriMesh>{}, {}, {}).is_static);
}

TEST(SurfaceSnapshot, AnUpdateMovesPositionsNormalsVelocitiesAndTheTree) {
  SurfaceSnapshot s = make_snapshot(square(0.0));
  const std::uint64_t sequence = s.sequence;
  // Tilted: z = x. The normal becomes (−1, 0, 1)/√2.
  const std::vector<Vec3> tilted{Vec3(0, 0, 0), Vec3(1, 0, 1), Vec3(1, 1, 1), Vec3(0, 1, 0)};
  const std::vector<Vec3> velocities{Vec3(0, 0, 0), Vec3(0, 0, 2), Vec3(0, 0, 2), Vec3(0, 0, 0)};
  update_snapshot(s, tilted, velocities, 0.25);
  EXPECT_EQ(s.sequence, sequence + 1);
  EXPECT_EQ(s.time_s, 0.25);
  for (const Vec3& n : s.vertex_normals) EXPECT_LT((n - Vec3(-1, 0, 1) / std::sqrt(2.0)).norm(), 1e-15);
  EXPECT_EQ(s.velocity(0, Vec3(0.5, 0.5, 0)), Vec3(0, 0, 1));
  // The tree answers for the new geometry: (1, 0.5, 0) is 1/√2 from the plane z = x.
  const collision::ClosestPoint c = s.tree.closest_point(s.view(), Vec3(1, 0.5, 0), 10.0);
  ASSERT_GE(c.triangle, 0);
  EXPECT_NEAR(c.distance, 1.0 / std::sqrt(2.0), 1e-12);
  // No velocities given: at rest.
  update_snapshot(s, tilted, {}, 0.5);
  for (const Vec3& v : s.velocities) EXPECT_EQ(v, Vec3::Zero());
}

TEST(SurfaceSnapshot, ACopyOfTheGeometryIsWhatTheUpdateWouldGive) {
  SurfaceSnapshot from = make_snapshot(square(0.0));
  const std::vector<Vec3> raised{Vec3(0, 0, 1), Vec3(1, 0, 1), Vec3(1, 1, 1), Vec3(0, 1, 1)};
  update_snapshot(from, raised, {}, 1.5);
  SurfaceSnapshot to = make_snapshot(square(0.0));
  const std::uint64_t sequence = to.sequence;
  copy_snapshot_geometry(to, from);
  EXPECT_EQ(to.vertices, from.vertices);
  EXPECT_EQ(to.vertex_normals, from.vertex_normals);
  EXPECT_EQ(to.time_s, 1.5);
  EXPECT_EQ(to.sequence, sequence + 1);
  EXPECT_EQ(to.refit_s, 0.0);
  EXPECT_NEAR(to.tree.closest_point(to.view(), Vec3(0.5, 0.5, 3), 10.0).distance, 2.0, 1e-15);
}

}  // namespace
}  // namespace hof::haptics
