// AabbTree: analytic single-triangle and unit-cube cases, then the tree against brute force
// (and against an independent distance formula) on the SOFA liver, the generated liver and
// a triangle soup; refit, leaf sizes, triangles_near, degenerate input, and queries and refit
// that allocate nothing (global operator new is replaced to count).

#include "hof/collision/aabb_tree.h"

#include <gtest/gtest.h>

#include "support/allocation_counter.h"

#include <algorithm>
#include <atomic>
#include <cmath>
#include <cstdlib>
#include <limits>
#include <new>
#include <random>
#include <vector>

#include "hof/mesh/liver_generator.h"
#include "hof/mesh/mesh_io.h"

namespace hof::collision {
namespace {

using mesh::TriMesh;
constexpr double kInf = std::numeric_limits<double>::infinity();

TriangleMeshView view(const TriMesh& m) { return {m.vertices, m.triangles}; }

const TriMesh& sofa_liver() {
  static const TriMesh surface = [] {
    auto r = mesh::read_mesh(HOF_ANCHORS_DIR "/sofa/mesh/liver-smooth.obj");
    EXPECT_TRUE(r.has_value()) << r.error().to_string();
    return r ? TriMesh{r->mesh.nodes, r->mesh.triangles} : TriMesh{};
  }();
  return surface;
}

const TriMesh& generated_liver() {
  static const TriMesh surface = mesh::make_liver_surface(8);
  return surface;
}

// 2000 random triangles (edges up to 0.1) in the unit box: sharp edges, corners and both
// sides everywhere, where the smooth livers give mostly face contacts.
const TriMesh& triangle_soup() {
  static const TriMesh soup = [] {
    TriMesh m;
    std::mt19937 gen(2024);
    std::uniform_real_distribution<double> u(0.0, 1.0), e(-0.05, 0.05);
    for (mesh::NodeIndex t = 0; t < 2000; ++t) {
      const Vec3 c(u(gen), u(gen), u(gen));
      for (int k = 0; k < 3; ++k) m.vertices.push_back(c + Vec3(e(gen), e(gen), e(gen)));
      m.triangles.push_back({3 * t, 3 * t + 1, 3 * t + 2});
    }
    return m;
  }();
  return soup;
}

TriMesh single_triangle() { return {{Vec3(0, 0, 0), Vec3(1, 0, 0), Vec3(0, 1, 0)}, {mesh::Tri{0, 1, 2}}}; }

// Unit cube [0,1]³, two outward triangles per face (corners o, o+u, o+u+v, o+v with u×v out).
TriMesh unit_cube() {
  TriMesh m;
  const Vec3 x(1, 0, 0), y(0, 1, 0), z(0, 0, 1), o(0, 0, 0);
  const Vec3 faces[6][3] = {{o, y, x}, {z, x, y}, {o, z, y}, {x, y, z}, {o, x, z}, {y, z, x}};
  for (const auto& f : faces) {
    const auto base = static_cast<mesh::NodeIndex>(m.vertices.size());
    m.vertices.insert(m.vertices.end(), {f[0], f[0] + f[1], f[0] + f[1] + f[2], f[0] + f[2]});
    m.triangles.push_back({base, base + 1, base + 2});
    m.triangles.push_back({base, base + 2, base + 3});
  }
  return m;
}

// Distance to a triangle by a route independent of Ericson's region tests: the projection
// onto the plane when it lies inside (same-side tests), else the nearest edge segment.
double segment_distance(const Vec3& p, const Vec3& a, const Vec3& b) {
  const double s = std::clamp((p - a).dot(b - a) / (b - a).squaredNorm(), 0.0, 1.0);
  return (p - (a + s * (b - a))).norm();
}
double reference_distance(const Vec3& p, const Vec3& a, const Vec3& b, const Vec3& c) {
  const Vec3 n = (b - a).cross(c - a);
  const Vec3 q = p - (p - a).dot(n) / n.squaredNorm() * n;
  if ((b - a).cross(q - a).dot(n) >= 0 && (c - b).cross(q - b).dot(n) >= 0 && (a - c).cross(q - c).dot(n) >= 0) {
    return (p - q).norm();
  }
  return std::min({segment_distance(p, a, b), segment_distance(p, b, c), segment_distance(p, c, a)});
}
double reference_mesh_distance(const TriMesh& m, const Vec3& p) {
  double best = kInf;
  for (const auto& t : m.triangles) {
    best = std::min(best, reference_distance(p, m.vertices[t[0]], m.vertices[t[1]], m.vertices[t[2]]));
  }
  return best;
}

struct Bounds {
  Vec3 lo, hi;
  [[nodiscard]] double diagonal() const { return (hi - lo).norm(); }
};
Bounds bounds(const TriMesh& m) {
  Bounds b{Vec3::Constant(kInf), Vec3::Constant(-kInf)};
  for (const Vec3& v : m.vertices) b.lo = b.lo.cwiseMin(v), b.hi = b.hi.cwiseMax(v);
  return b;
}

// Deterministic query points: half uniform in the box grown by 20 %, half near the surface
// (a random point of a random triangle, moved along its normal by up to 5 % of the size).
class QueryPoints {
 public:
  QueryPoints(const TriMesh& m, unsigned seed) : mesh_(m), box_(bounds(m)), gen_(seed) {}
  Vec3 next() {
    const double size = box_.diagonal();
    if (std::uniform_int_distribution<int>(0, 1)(gen_) == 0) {
      Vec3 p;
      for (int i = 0; i < 3; ++i) p[i] = uniform(box_.lo[i] - 0.2 * size, box_.hi[i] + 0.2 * size);
      return p;
    }
    const auto& t = mesh_.triangles[std::uniform_int_distribution<std::size_t>(0, mesh_.triangles.size() - 1)(gen_)];
    double u = uniform(0, 1), v = uniform(0, 1);
    if (u + v > 1) u = 1 - u, v = 1 - v;
    const Vec3 &a = mesh_.vertices[t[0]], &b = mesh_.vertices[t[1]], &c = mesh_.vertices[t[2]];
    const Vec3 n = (b - a).cross(c - a).normalized();
    return a + u * (b - a) + v * (c - a) + uniform(-0.05, 0.05) * size * n;
  }
  Vec3 direction(double length) {
    Vec3 d(uniform(-1, 1), uniform(-1, 1), uniform(-1, 1));
    return d.normalized() * length;
  }
  double uniform(double lo, double hi) { return std::uniform_real_distribution<double>(lo, hi)(gen_); }

 private:
  const TriMesh& mesh_;
  Bounds box_;
  std::mt19937 gen_;
};

void expect_same(const SweepHit& x, const SweepHit& y) {
  ASSERT_EQ(x.triangle < 0, y.triangle < 0);
  if (x.triangle < 0) return;
  EXPECT_NEAR(x.t, y.t, 1e-12);
  if (x.triangle != y.triangle) {
    EXPECT_EQ(x.t, y.t) << "different triangles without a tie";
  }
  EXPECT_EQ(x.front, y.front);
}

constexpr TouchableFace kFaces[] = {TouchableFace::kFront, TouchableFace::kBack, TouchableFace::kFrontAndBack};

// ---------------------------------------------------------------------------------------
// Analytic cases

TEST(AabbTreeAnalytic, ClosestPointRegionsOfOneTriangle) {
  const TriMesh m = single_triangle();
  const AabbTree tree = AabbTree::build(view(m));
  struct Case {
    Vec3 p, point, barycentric;
  };
  const Case cases[] = {
      {Vec3(0.2, 0.3, 0.5), Vec3(0.2, 0.3, 0), Vec3(0.5, 0.2, 0.3)},  // face
      {Vec3(0.5, -1, 0.2), Vec3(0.5, 0, 0), Vec3(0.5, 0.5, 0)},       // edge ab
      {Vec3(1, 1, 0), Vec3(0.5, 0.5, 0), Vec3(0, 0.5, 0.5)},          // edge bc
      {Vec3(-1, 0.5, -0.3), Vec3(0, 0.5, 0), Vec3(0.5, 0, 0.5)},      // edge ca
      {Vec3(-1, -1, -1), Vec3(0, 0, 0), Vec3(1, 0, 0)},               // vertex a
      {Vec3(2, -0.5, 0), Vec3(1, 0, 0), Vec3(0, 1, 0)},               // vertex b
      {Vec3(-0.5, 3, 0.1), Vec3(0, 1, 0), Vec3(0, 0, 1)},             // vertex c
  };
  for (const Case& c : cases) {
    const ClosestPoint r = tree.closest_point(view(m), c.p, kInf);
    ASSERT_EQ(r.triangle, 0);
    EXPECT_LT((r.point - c.point).norm(), 1e-14) << c.p.transpose();
    EXPECT_LT((r.barycentric - c.barycentric).norm(), 1e-14) << c.p.transpose();
    EXPECT_NEAR(r.distance, (c.p - c.point).norm(), 1e-14);
  }
  // max_distance is inclusive; the side filter follows the sign of (p − a)·n.
  EXPECT_EQ(tree.closest_point(view(m), Vec3(0.2, 0.3, 0.5), 0.4).triangle, -1);
  EXPECT_EQ(tree.closest_point(view(m), Vec3(0.25, 0.25, 0.5), 0.5).triangle, 0);
  EXPECT_EQ(tree.closest_point(view(m), Vec3(0.2, 0.3, 0.5), 1, TouchableFace::kFront).triangle, 0);
  EXPECT_EQ(tree.closest_point(view(m), Vec3(0.2, 0.3, 0.5), 1, TouchableFace::kBack).triangle, -1);
  EXPECT_EQ(tree.closest_point(view(m), Vec3(0.2, 0.3, -0.5), 1, TouchableFace::kFront).triangle, -1);
  EXPECT_EQ(tree.closest_point(view(m), Vec3(0.2, 0.3, -0.5), 1, TouchableFace::kBack).triangle, 0);
}

TEST(AabbTreeAnalytic, SegmentThroughUnitCube) {
  const TriMesh cube = unit_cube();
  for (const auto& t : cube.triangles) {  // the fixture really is outward
    const Vec3 n = (cube.vertices[t[1]] - cube.vertices[t[0]]).cross(cube.vertices[t[2]] - cube.vertices[t[0]]);
    ASSERT_GT(n.dot(cube.vertices[t[0]] - Vec3::Constant(0.5)), 0);
  }
  const AabbTree tree = AabbTree::build(view(cube));
  // From below into the bottom face (z = 0) at t = 1/3.
  SweepHit h = tree.first_hit_segment(view(cube), Vec3(0.3, 0.4, -1), Vec3(0.3, 0.4, 2));
  ASSERT_GE(h.triangle, 0);
  EXPECT_NEAR(h.t, 1.0 / 3.0, 1e-15);
  EXPECT_LT((h.point - Vec3(0.3, 0.4, 0)).norm(), 1e-15);
  EXPECT_LT((h.normal - Vec3(0, 0, -1)).norm(), 1e-15);
  EXPECT_TRUE(h.front);
  EXPECT_NEAR((h.barycentric[0] * cube.vertices[cube.triangles[h.triangle][0]] +
               h.barycentric[1] * cube.vertices[cube.triangles[h.triangle][1]] +
               h.barycentric[2] * cube.vertices[cube.triangles[h.triangle][2]] - h.point)
                  .norm(),
              0, 1e-15);
  // Oblique, through x = 0 at t = 1/4.
  h = tree.first_hit_segment(view(cube), Vec3(-1, 0.25, 0.3), Vec3(3, 0.75, 0.7));
  EXPECT_NEAR(h.t, 0.25, 1e-15);
  EXPECT_LT((h.point - Vec3(0, 0.375, 0.4)).norm(), 1e-15);
  EXPECT_LT((h.normal - Vec3(-1, 0, 0)).norm(), 1e-15);
  // Ending exactly on the face: t = 1 counts. Parallel to a face, outside: no hit.
  EXPECT_NEAR(tree.first_hit_segment(view(cube), Vec3(0.3, 0.4, -1), Vec3(0.3, 0.4, 0)).t, 1.0, 1e-15);
  EXPECT_EQ(tree.first_hit_segment(view(cube), Vec3(-1, 0.5, 1.5), Vec3(2, 0.5, 1.5)).triangle, -1);
  // Through the diagonal shared by the two top triangles: both at t = 1/3, lower index wins.
  h = tree.first_hit_segment(view(cube), Vec3(0.5, 0.5, 2), Vec3(0.5, 0.5, -1));
  EXPECT_NEAR(h.t, 1.0 / 3.0, 1e-15);
  EXPECT_EQ(h.triangle, 2);
}

TEST(AabbTreeAnalytic, TouchableFaceFiltersSegmentsFromInside) {
  const TriMesh cube = unit_cube();
  const AabbTree tree = AabbTree::build(view(cube));
  const Vec3 a(0.3, 0.6, 0.5), b(0.3, 0.6, 2);  // from inside out through the top face
  EXPECT_EQ(tree.first_hit_segment(view(cube), a, b, TouchableFace::kFront).triangle, -1);
  for (TouchableFace face : {TouchableFace::kBack, TouchableFace::kFrontAndBack}) {
    const SweepHit h = tree.first_hit_segment(view(cube), a, b, face);
    ASSERT_GE(h.triangle, 2);
    EXPECT_LE(h.triangle, 3);
    EXPECT_NEAR(h.t, 1.0 / 3.0, 1e-15);
    EXPECT_FALSE(h.front);
    EXPECT_LT((h.normal - Vec3(0, 0, -1)).norm(), 1e-15);  // toward the moving point
  }
  // From outside in: FRONT hits the top, BACK passes it and meets the bottom from inside.
  EXPECT_NEAR(tree.first_hit_segment(view(cube), b, a - Vec3(0, 0, 2), TouchableFace::kFront).t, 1.0 / 3.5, 1e-15);
  const SweepHit back = tree.first_hit_segment(view(cube), b, a - Vec3(0, 0, 2), TouchableFace::kBack);
  EXPECT_NEAR(back.t, 2.0 / 3.5, 1e-15);
  EXPECT_LT((back.point - Vec3(0.3, 0.6, 0)).norm(), 1e-15);
}

TEST(AabbTreeAnalytic, SphereTouchesFaceEdgeAndVertexAtAnalyticTime) {
  const TriMesh m = single_triangle();
  const AabbTree tree = AabbTree::build(view(m));
  const double r = 0.1;
  // Face, from the front and (BACK only) from behind.
  SweepHit h = tree.first_hit_swept_sphere(view(m), Vec3(0.2, 0.2, 1), Vec3(0.2, 0.2, -1), r);
  ASSERT_EQ(h.triangle, 0);
  EXPECT_NEAR(h.t, 0.45, 1e-15);
  EXPECT_LT((h.point - Vec3(0.2, 0.2, 0)).norm(), 1e-15);
  EXPECT_LT((h.normal - Vec3(0, 0, 1)).norm(), 1e-15);
  EXPECT_TRUE(h.front);
  EXPECT_EQ(tree.first_hit_swept_sphere(view(m), Vec3(0.2, 0.2, -1), Vec3(0.2, 0.2, 1), r).triangle, -1);
  h = tree.first_hit_swept_sphere(view(m), Vec3(0.2, 0.2, -1), Vec3(0.2, 0.2, 1), r, TouchableFace::kBack);
  EXPECT_NEAR(h.t, 0.45, 1e-15);
  EXPECT_LT((h.normal - Vec3(0, 0, -1)).norm(), 1e-15);
  EXPECT_FALSE(h.front);
  // Edge ab (y = 0), approached sideways 0.05 above the plane: |(y, 0.05)| = r.
  const double y = std::sqrt(r * r - 0.05 * 0.05);
  h = tree.first_hit_swept_sphere(view(m), Vec3(0.5, -1, 0.05), Vec3(0.5, 1, 0.05), r);
  ASSERT_EQ(h.triangle, 0);
  EXPECT_NEAR(h.t, (1 - y) / 2, 1e-14);
  EXPECT_LT((h.point - Vec3(0.5, 0, 0)).norm(), 1e-14);
  EXPECT_LT((h.barycentric - Vec3(0.5, 0.5, 0)).norm(), 1e-14);
  EXPECT_LT((h.normal - Vec3(0, -y, 0.05) / r).norm(), 1e-12);
  EXPECT_TRUE(h.front);
  EXPECT_EQ(
      tree.first_hit_swept_sphere(view(m), Vec3(0.5, -1, 0.05), Vec3(0.5, 1, 0.05), r, TouchableFace::kBack).triangle,
      -1);
  // Vertex a, approached along u = (−1, −1, 1)/√3 from 2u to −u: |c| = 2 − 3t = r.
  const Vec3 u = Vec3(-1, -1, 1).normalized();
  h = tree.first_hit_swept_sphere(view(m), 2 * u, -u, r);
  ASSERT_EQ(h.triangle, 0);
  EXPECT_NEAR(h.t, (2 - r) / 3, 1e-14);
  EXPECT_LT(h.point.norm(), 1e-15);
  EXPECT_LT((h.normal - u).norm(), 1e-12);
  // Overlapping at the start: t = 0 when approaching; nothing when leaving or sliding.
  h = tree.first_hit_swept_sphere(view(m), Vec3(0.2, 0.2, 0.05), Vec3(0.2, 0.2, -0.5), r);
  EXPECT_EQ(h.t, 0.0);
  EXPECT_LT((h.point - Vec3(0.2, 0.2, 0)).norm(), 1e-15);
  EXPECT_EQ(tree.first_hit_swept_sphere(view(m), Vec3(0.2, 0.2, 0.05), Vec3(0.2, 0.2, 0.5), r).triangle, -1);
  EXPECT_EQ(tree.first_hit_swept_sphere(view(m), Vec3(0.2, 0.2, 0.05), Vec3(0.3, 0.2, 0.05), r).triangle, -1);
  EXPECT_EQ(tree.first_hit_swept_sphere(view(m), Vec3(0.2, 0.2, r), Vec3(0.4, 0.2, r), r).triangle, -1);
  // Radius 0 is the segment query; a negative radius hits nothing.
  h = tree.first_hit_swept_sphere(view(m), Vec3(0.2, 0.2, 1), Vec3(0.2, 0.2, -1), 0.0);
  EXPECT_NEAR(h.t, 0.5, 1e-15);
  EXPECT_EQ(tree.first_hit_swept_sphere(view(m), Vec3(0.2, 0.2, 1), Vec3(0.2, 0.2, -1), -1.0).triangle, -1);
}

// ---------------------------------------------------------------------------------------
// Tree against brute force on the liver surfaces and a triangle soup

class LiverSurfaceTest : public ::testing::TestWithParam<int> {
 protected:
  static const TriMesh& surface() {
    return GetParam() == 0 ? sofa_liver() : GetParam() == 1 ? generated_liver() : triangle_soup();
  }
};

TEST_P(LiverSurfaceTest, ClosestPointMatchesBruteForceAndReference) {
  const TriMesh& m = surface();
  ASSERT_GT(m.triangles.size(), 1000u);
  const AabbTree tree = AabbTree::build(view(m));
  const AabbTree brute = AabbTree::build(view(m), {.use_bound_tree = false});
  const double size = bounds(m).diagonal();
  QueryPoints q(m, 1234);
  for (int i = 0; i < 3000; ++i) {
    const Vec3 p = q.next();
    const ClosestPoint t = tree.closest_point(view(m), p, kInf);
    const ClosestPoint b = brute.closest_point(view(m), p, kInf);
    ASSERT_GE(t.triangle, 0);
    EXPECT_EQ(t.triangle, b.triangle);
    EXPECT_EQ(t.distance, b.distance);
    EXPECT_NEAR(t.distance, reference_mesh_distance(m, p), 1e-12 * size);
    const auto& tri = m.triangles[t.triangle];
    const Vec3 from_weights = t.barycentric[0] * m.vertices[tri[0]] + t.barycentric[1] * m.vertices[tri[1]] +
                              t.barycentric[2] * m.vertices[tri[2]];
    EXPECT_LT((from_weights - t.point).norm(), 1e-12 * size);
    EXPECT_NEAR(t.barycentric.sum(), 1.0, 1e-12);
    EXPECT_GE(t.barycentric.minCoeff(), -1e-12);
  }
  // A search radius and the side filters.
  for (int i = 0; i < 1500; ++i) {
    const Vec3 p = q.next();
    for (TouchableFace face : kFaces) {
      const ClosestPoint t = tree.closest_point(view(m), p, 0.03 * size, face);
      const ClosestPoint b = brute.closest_point(view(m), p, 0.03 * size, face);
      EXPECT_EQ(t.triangle, b.triangle);
      EXPECT_EQ(t.distance, b.distance);
      EXPECT_LE(t.distance, 0.03 * size);
    }
  }
}

TEST_P(LiverSurfaceTest, SegmentMatchesBruteForce) {
  const TriMesh& m = surface();
  const AabbTree tree = AabbTree::build(view(m));
  const AabbTree brute = AabbTree::build(view(m), {.use_bound_tree = false});
  const double size = bounds(m).diagonal();
  QueryPoints q(m, 99);
  int hits = 0;
  for (int i = 0; i < 3000; ++i) {
    const Vec3 a = q.next();
    const Vec3 b = i % 2 == 0 ? q.next() : Vec3(a + q.direction(0.1 * size));
    for (TouchableFace face : kFaces) {
      const SweepHit t = tree.first_hit_segment(view(m), a, b, face);
      expect_same(t, brute.first_hit_segment(view(m), a, b, face));
      if (t.triangle < 0) continue;
      ++hits;
      EXPECT_LT((a + t.t * (b - a) - t.point).norm(), 1e-12 * size);
      EXPECT_LT(t.normal.dot(b - a), 0.0);  // the normal faces the moving point
      EXPECT_NEAR(t.normal.norm(), 1.0, 1e-12);
    }
  }
  EXPECT_GT(hits, 1000);
}

TEST_P(LiverSurfaceTest, SweptSphereMatchesBruteForceAndIsTheFirstContact) {
  const TriMesh& m = surface();
  const AabbTree tree = AabbTree::build(view(m));
  const AabbTree brute = AabbTree::build(view(m), {.use_bound_tree = false});
  const double size = bounds(m).diagonal();
  QueryPoints q(m, 7);
  int hits = 0;
  for (int i = 0; i < 1500; ++i) {
    const double r = (i % 3 == 0 ? 0.01 : i % 3 == 1 ? 0.0025 : 0.04) * size;
    const Vec3 a = q.next();
    const Vec3 b = i % 2 == 0 ? q.next() : Vec3(a + q.direction(0.1 * size));
    for (TouchableFace face : kFaces) {
      const SweepHit t = tree.first_hit_swept_sphere(view(m), a, b, r, face);
      expect_same(t, brute.first_hit_swept_sphere(view(m), a, b, r, face));
      if (t.triangle >= 0) ++hits;
    }
    // Both sides: starting free, the sphere is nowhere closer than r before t, and at t
    // it touches the reported point (the distance function of the whole mesh is checked).
    const SweepHit t = tree.first_hit_swept_sphere(view(m), a, b, r, TouchableFace::kFrontAndBack);
    if (tree.closest_point(view(m), a, kInf).distance < r) continue;
    const double t_end = t.triangle >= 0 ? t.t : 1.0;
    for (int k = 0; k < 16; ++k) {
      const Vec3 c = a + (t_end * k / 16.0) * (b - a);
      EXPECT_GE(tree.closest_point(view(m), c, kInf).distance, r * (1 - 1e-9));
    }
    if (t.triangle < 0) continue;
    const Vec3 c = a + t.t * (b - a);
    EXPECT_NEAR((c - t.point).norm(), r, 1e-9 * size);
    EXPECT_NEAR(tree.closest_point(view(m), c, kInf).distance, r, 1e-9 * size);
    EXPECT_LT((c - t.point - r * t.normal).norm(), 1e-9 * size);
    EXPECT_LE(t.normal.dot(b - a), 0.0);
  }
  EXPECT_GT(hits, 500);
}

TEST_P(LiverSurfaceTest, LeafSizesGiveIdenticalResults) {
  const TriMesh& m = surface();
  const AabbTree reference = AabbTree::build(view(m), {.use_bound_tree = false});
  const double size = bounds(m).diagonal();
  std::size_t previous_nodes = std::numeric_limits<std::size_t>::max();
  for (int leaf : {1, 4, 16, 0}) {  // 0: the whole tree is one leaf (H3D: < 0)
    const AabbTree tree = AabbTree::build(view(m), {.max_triangles_in_leaf = leaf});
    EXPECT_LT(tree.node_count(), previous_nodes);
    previous_nodes = tree.node_count();
    EXPECT_LE(tree.depth(), static_cast<int>(std::ceil(std::log2(static_cast<double>(m.triangles.size())))) + 1);
    QueryPoints q(m, 5);
    for (int i = 0; i < 500; ++i) {
      const Vec3 a = q.next();
      const Vec3 b = a + q.direction(0.2 * size);
      const ClosestPoint c = tree.closest_point(view(m), a, kInf);
      EXPECT_EQ(c.triangle, reference.closest_point(view(m), a, kInf).triangle);
      expect_same(tree.first_hit_segment(view(m), a, b), reference.first_hit_segment(view(m), a, b));
      expect_same(tree.first_hit_swept_sphere(view(m), a, b, 0.01 * size),
                  reference.first_hit_swept_sphere(view(m), a, b, 0.01 * size));
    }
  }
}

TEST_P(LiverSurfaceTest, TrianglesNearIsASupersetOfTheTrianglesWithinTheRadius) {
  const TriMesh& m = surface();
  const double size = bounds(m).diagonal();
  std::vector<std::int32_t> out(m.triangles.size());
  for (int leaf : {1, 4}) {
    const AabbTree tree = AabbTree::build(view(m), {.max_triangles_in_leaf = leaf});
    QueryPoints q(m, 11);
    for (int i = 0; i < 200; ++i) {
      const Vec3 c = q.next();
      const double radius = 0.02 * size;
      const std::size_t n = tree.triangles_near(c, radius, out);
      ASSERT_LE(n, out.size());
      std::vector<std::int32_t> found(out.begin(), out.begin() + static_cast<std::ptrdiff_t>(n));
      std::sort(found.begin(), found.end());
      EXPECT_EQ(std::adjacent_find(found.begin(), found.end()), found.end());  // no repeats
      for (std::size_t t = 0; t < m.triangles.size(); ++t) {
        const auto& tri = m.triangles[t];
        if (reference_distance(c, m.vertices[tri[0]], m.vertices[tri[1]], m.vertices[tri[2]]) <= radius) {
          EXPECT_TRUE(std::binary_search(found.begin(), found.end(), static_cast<std::int32_t>(t)));
        }
      }
      // A short buffer still reports the full count.
      std::int32_t two[2];
      EXPECT_EQ(tree.triangles_near(c, radius, two), n);
    }
  }
}

INSTANTIATE_TEST_SUITE_P(Surfaces, LiverSurfaceTest, ::testing::Values(0, 1, 2), [](const auto& param_info) {
  return param_info.param == 0 ? "SofaLiver" : param_info.param == 1 ? "GeneratedLiver" : "TriangleSoup";
});

// ---------------------------------------------------------------------------------------
// Refit, determinism, degenerate input

// A smooth displacement of about `amplitude` metres.
TriMesh deformed(const TriMesh& m, double amplitude) {
  TriMesh d = m;
  for (Vec3& v : d.vertices) {
    v += amplitude * Vec3(std::sin(20 * v.y()), std::cos(15 * v.z()), std::sin(10 * v.x() + 1));
  }
  return d;
}

TEST(AabbTreeRefit, MatchesAFreshBuildAfterDeformation) {
  const TriMesh& rest = generated_liver();
  AabbTree tree = AabbTree::build(view(rest));
  const TriMesh moved = deformed(rest, 0.01);
  EXPECT_FALSE(tree.refit(view(moved)));  // 1 cm on a 20 cm organ: no rebuild needed
  const AabbTree fresh = AabbTree::build(view(moved));
  QueryPoints q(moved, 3);
  for (int i = 0; i < 1000; ++i) {
    const Vec3 a = q.next();
    const Vec3 b = a + q.direction(0.05);
    const ClosestPoint x = tree.closest_point(view(moved), a, kInf);
    const ClosestPoint y = fresh.closest_point(view(moved), a, kInf);
    EXPECT_EQ(x.triangle, y.triangle);
    EXPECT_EQ(x.distance, y.distance);
    expect_same(tree.first_hit_segment(view(moved), a, b), fresh.first_hit_segment(view(moved), a, b));
    expect_same(tree.first_hit_swept_sphere(view(moved), a, b, 0.0025),
                fresh.first_hit_swept_sphere(view(moved), a, b, 0.0025));
  }
}

TEST(AabbTreeRefit, ReportsDegradationAfterALargeStretchAndStaysCorrect) {
  const TriMesh& rest = generated_liver();
  AabbTree tree = AabbTree::build(view(rest));
  EXPECT_FALSE(tree.refit(view(rest)));
  TriMesh stretched = rest;
  for (Vec3& v : stretched.vertices) v.x() *= 4.0;
  EXPECT_TRUE(tree.refit(view(stretched)));
  const AabbTree brute = AabbTree::build(view(stretched), {.use_bound_tree = false});
  QueryPoints q(stretched, 17);
  for (int i = 0; i < 500; ++i) {
    const Vec3 a = q.next();
    EXPECT_EQ(tree.closest_point(view(stretched), a, kInf).triangle,
              brute.closest_point(view(stretched), a, kInf).triangle);
  }
}

TEST(AabbTreeBuild, DeterministicAndShallow) {
  const TriMesh& m = sofa_liver();
  const AabbTree x = AabbTree::build(view(m));
  const AabbTree y = AabbTree::build(view(m));
  EXPECT_EQ(x.node_count(), y.node_count());
  EXPECT_EQ(x.node_count(), 2 * m.triangles.size() - 1);  // one triangle per leaf
  EXPECT_EQ(x.depth(), y.depth());
  EXPECT_LE(x.depth(), static_cast<int>(std::ceil(std::log2(static_cast<double>(m.triangles.size())))) + 1);
  QueryPoints q(m, 21);
  for (int i = 0; i < 200; ++i) {
    const Vec3 p = q.next();
    const ClosestPoint cx = x.closest_point(view(m), p, kInf);
    const ClosestPoint cy = y.closest_point(view(m), p, kInf);
    EXPECT_EQ(cx.triangle, cy.triangle);
    EXPECT_EQ(cx.point, cy.point);
  }
  const AabbTree empty = AabbTree::build({});
  EXPECT_EQ(empty.closest_point({}, Vec3::Zero(), kInf).triangle, -1);
  EXPECT_EQ(empty.first_hit_segment({}, Vec3::Zero(), Vec3::Ones()).triangle, -1);
}

TEST(AabbTreeQueries, QueriesAndRefitAllocateNothing) {
  HOF_SKIP_UNLESS_COUNTING_ALLOCATIONS();
  const TriMesh& m = generated_liver();
  const TriMesh moved = deformed(m, 0.005);
  for (int leaf : {1, 8}) {
    AabbTree tree = AabbTree::build(view(m), {.max_triangles_in_leaf = leaf});
    const AabbTree brute = AabbTree::build(view(m), {.use_bound_tree = false});
    QueryPoints q(m, 8);
    std::vector<Vec3> points(400);
    for (Vec3& p : points) p = q.next();
    std::vector<std::int32_t> out(64);
    double sink = 0.0;
    const long before = hof::testing::allocation_count();
    for (std::size_t i = 0; i + 1 < points.size(); ++i) {
      const Vec3& a = points[i];
      const Vec3& b = points[i + 1];
      sink += tree.closest_point(view(m), a, kInf).distance + brute.closest_point(view(m), a, 0.01).distance;
      sink += tree.first_hit_segment(view(m), a, b).t + brute.first_hit_segment(view(m), a, b).t;
      sink += tree.first_hit_swept_sphere(view(m), a, b, 0.0025).t;
      sink += static_cast<double>(tree.triangles_near(a, 0.01, out));
    }
    sink += tree.refit(view(moved)) ? 1.0 : 0.0;
    EXPECT_EQ(hof::testing::allocation_count() - before, 0);
    EXPECT_TRUE(std::isfinite(sink));
  }
}

bool finite(const SweepHit& h) {
  return std::isfinite(h.t) && h.point.allFinite() && h.normal.allFinite() && h.barycentric.allFinite();
}

TEST(AabbTreeDegenerate, DegenerateTrianglesAreSkippedWithoutNaN) {
  const double nan = std::numeric_limits<double>::quiet_NaN();
  TriMesh m;
  m.vertices = {Vec3(0, 0, 0),       Vec3(1, 0, 0),   Vec3(0, 1, 0),    // 0: a good triangle
                Vec3(0, 0, 0.5),     Vec3(1, 0, 0.5), Vec3(2, 0, 0.5),  // 1: collinear
                Vec3(0, 0, 1),       Vec3(0, 0, 1),   Vec3(1, 1, 1),    // 2: repeated vertex
                Vec3(0.3, 0.3, 1.5),                                    // 3: a point
                Vec3(nan, 0, 0)};                                       // 4: not finite
  m.triangles = {{0, 1, 2}, {3, 4, 5}, {6, 7, 8}, {9, 9, 9}, {10, 1, 2}};
  for (bool use_tree : {true, false}) {
    const AabbTree tree = AabbTree::build(view(m), {.use_bound_tree = use_tree});
    std::mt19937 gen(42);
    std::uniform_real_distribution<double> u(-1.0, 2.0);
    for (int i = 0; i < 500; ++i) {
      const Vec3 a(u(gen), u(gen), u(gen));
      const Vec3 b(u(gen), u(gen), u(gen));
      const ClosestPoint c = tree.closest_point(view(m), a, kInf);
      EXPECT_EQ(c.triangle, 0);
      EXPECT_TRUE(std::isfinite(c.distance) && c.point.allFinite());
      for (TouchableFace face : kFaces) {
        const SweepHit s = tree.first_hit_segment(view(m), a, b, face);
        EXPECT_TRUE(s.triangle == -1 || s.triangle == 0);
        EXPECT_TRUE(finite(s));
        for (double r : {0.0, 0.05, 0.5}) {
          const SweepHit h = tree.first_hit_swept_sphere(view(m), a, b, r, face);
          EXPECT_TRUE(h.triangle == -1 || h.triangle == 0);
          EXPECT_TRUE(finite(h));
        }
      }
    }
    // Motions straight through the degenerate ones.
    EXPECT_EQ(
        tree.first_hit_segment(view(m), Vec3(0.5, -1, 0.5), Vec3(0.5, 1, 0.5), TouchableFace::kFrontAndBack).triangle,
        -1);
    EXPECT_EQ(
        tree.first_hit_swept_sphere(view(m), Vec3(0.3, 0.3, 2), Vec3(0.3, 0.3, 1.2), 0.1, TouchableFace::kFrontAndBack)
            .triangle,
        -1);
    std::int32_t out[8];
    EXPECT_GE(tree.triangles_near(Vec3(0.2, 0.2, 0), 0.1, out), 1u);
  }
  // A mesh of degenerate triangles only.
  TriMesh only = m;
  only.triangles = {{3, 4, 5}, {6, 7, 8}, {9, 9, 9}, {10, 1, 2}};
  AabbTree tree = AabbTree::build(view(only));
  EXPECT_EQ(tree.closest_point(view(only), Vec3(0.2, 0.2, 0.2), kInf).triangle, -1);
  EXPECT_EQ(tree.first_hit_swept_sphere(view(only), Vec3(0, 0, 3), Vec3(0, 0, -3), 0.5, TouchableFace::kFrontAndBack)
                .triangle,
            -1);
  EXPECT_FALSE(tree.refit(view(only)));
}

}  // namespace
}  // namespace hof::collision
