// ContactDetector: analytic cases (parallel squares, skew edges, a sphere on a plane, a cube
// on a floor), continuous detection of a vertex pushed through a triangle, the pair filters
// (groups, simulated, self-collision), bad input, determinism, and the tree-based narrow
// phase against brute force over all pairs on random surfaces.

#include "hof/collision/body_contacts.h"

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <limits>
#include <random>
#include <vector>

#include "hof/collision/triangle_queries.h"
#include "hof/mesh/liver_generator.h"

namespace hof::collision {
namespace {

using mesh::Tri;
using mesh::TriMesh;
constexpr double kNan = std::numeric_limits<double>::quiet_NaN();

CollisionBody body_of(const TriMesh& m) {
  CollisionBody b;
  b.surface = {m.vertices, m.triangles};
  return b;
}

// A square [x0, x0+s]×[y0, y0+s] at height z, two triangles, front normal +z (up) or −z.
TriMesh square(double x0, double y0, double s, double z, bool up) {
  TriMesh m;
  m.vertices = {Vec3(x0, y0, z), Vec3(x0 + s, y0, z), Vec3(x0 + s, y0 + s, z), Vec3(x0, y0 + s, z)};
  m.triangles = up ? std::vector<Tri>{{0, 1, 2}, {0, 2, 3}} : std::vector<Tri>{{0, 2, 1}, {0, 3, 2}};
  return m;
}

// The unit cube [x0, x0+1]×[y0, y0+1]×[z0, z0+1], 12 triangles, outward normals.
TriMesh cube(double x0, double y0, double z0) {
  TriMesh m;
  for (int k = 0; k < 8; ++k) {
    m.vertices.emplace_back(x0 + (k & 1), y0 + ((k >> 1) & 1), z0 + ((k >> 2) & 1));
  }
  // Each face as a quad (a, b, c, d) counter-clockwise seen from outside.
  const int quads[6][4] = {{0, 2, 3, 1}, {4, 5, 7, 6}, {0, 1, 5, 4}, {2, 6, 7, 3}, {0, 4, 6, 2}, {1, 3, 7, 5}};
  for (const auto& q : quads) {
    m.triangles.push_back({q[0], q[1], q[2]});
    m.triangles.push_back({q[0], q[2], q[3]});
  }
  return m;
}

bool finite(const BodyContact& c) {
  return c.a.point.allFinite() && c.b.point.allFinite() && c.normal.allFinite() && std::isfinite(c.distance);
}

std::vector<BodyContact> run(ContactDetector& detector, const std::vector<CollisionBody>& bodies, double alarm) {
  std::vector<BodyContact> contacts;
  detector.detect(bodies, DetectionSettings{alarm}, contacts);
  return contacts;
}

TEST(ContactDetector, CubeHasOutwardNormals) {
  // Guards the fixture: every triangle's normal points away from the cube's centre.
  const TriMesh m = cube(0, 0, 0);
  for (const Tri& t : m.triangles) {
    const Vec3 n = (m.vertices[t[1]] - m.vertices[t[0]]).cross(m.vertices[t[2]] - m.vertices[t[0]]);
    EXPECT_GT(n.dot(m.vertices[t[0]] - Vec3(0.5, 0.5, 0.5)), 0.0);
  }
}

TEST(ContactDetector, ParallelSquaresGiveTheGapAndNormal) {
  const TriMesh lower = square(0, 0, 1, 0.0, true);
  for (const double gap : {0.004, 0.0, 0.02}) {
    const TriMesh upper = square(0, 0, 1, gap, false);
    std::vector<CollisionBody> bodies{body_of(lower), body_of(upper)};
    for (auto& b : bodies) b.lines = false;
    ContactDetector detector;
    detector.reset(bodies);
    const auto contacts = run(detector, bodies, 0.01);
    if (gap > 0.01) {
      EXPECT_TRUE(contacts.empty());
      continue;
    }
    ASSERT_EQ(contacts.size(), 8U);  // 4 vertices of each against the other
    for (std::size_t k = 0; k < contacts.size(); ++k) {
      const BodyContact& c = contacts[k];
      EXPECT_NEAR(c.distance, gap, 1e-15);
      // Body 0's vertices first (vertex order), then body 1's.
      EXPECT_EQ(c.a.body, k < 4 ? 0 : 1);
      EXPECT_EQ(c.a.vertices[0], static_cast<std::int32_t>(k % 4));
      EXPECT_EQ(c.a.kind, PrimitiveKind::kVertex);
      EXPECT_EQ(c.b.kind, PrimitiveKind::kTriangle);
      // From b toward a: the lower square's vertices are pushed down, the upper's up.
      const Vec3 expected = k < 4 ? Vec3(-Vec3::UnitZ()) : Vec3(Vec3::UnitZ());
      EXPECT_NEAR((c.normal - expected).norm(), 0.0, 1e-15);
      EXPECT_NEAR((c.a.point - c.b.point).norm(), gap, 1e-15);
      const double weight_sum = c.b.weights[0] + c.b.weights[1] + c.b.weights[2];
      EXPECT_NEAR(weight_sum, 1.0, 1e-15);
    }
  }
}

TEST(ContactDetector, ParallelSquaresEdgesCrossingAtTheGap) {
  // Squares offset by half a side: the edges cross in projection at interior points, each such
  // pair a contact at the gap along ±z.
  const double gap = 0.003;
  const TriMesh lower = square(0, 0, 1, 0.0, true);
  const TriMesh upper = square(0.5, 0.5, 1, gap, false);
  std::vector<CollisionBody> bodies{body_of(lower), body_of(upper)};
  for (auto& b : bodies) b.points = false;
  ContactDetector detector;
  detector.reset(bodies);
  const auto contacts = run(detector, bodies, 0.01);
  // lower's edges x=1 (y∈[0,1]) and y=1 against upper's y=0.5, x=0.5, and diagonals:
  // counted independently below by brute force over all edge pairs.
  ASSERT_FALSE(contacts.empty());
  for (const BodyContact& c : contacts) {
    EXPECT_EQ(c.a.kind, PrimitiveKind::kEdge);
    EXPECT_NEAR(c.distance, gap, 1e-12);
    EXPECT_NEAR((c.normal + Vec3::UnitZ()).norm(), 0.0, 1e-12);  // lower (a) is pushed down
  }
  // Brute force: every edge pair whose closest points are interior and within the alarm.
  std::size_t expected = 0;
  const std::vector<std::array<int, 2>> edges{{0, 1}, {1, 2}, {2, 3}, {0, 3}, {0, 2}};
  for (const auto& e : edges) {
    for (const auto& f : edges) {
      const auto sc = detail::closest_points_segment_segment(lower.vertices[e[0]], lower.vertices[e[1]],
                                                             upper.vertices[f[0]], upper.vertices[f[1]]);
      if (sc.distance_squared <= 1e-4 && sc.s > 0 && sc.s < 1 && sc.t > 0 && sc.t < 1) ++expected;
    }
  }
  EXPECT_EQ(contacts.size(), expected);
}

TEST(ContactDetector, SkewEdgesGiveTheAnalyticDistance) {
  // Edge A: (s, 0, h), s ∈ [−1, 1]; edge B: (0, t, t), t ∈ [−1, 1]. The common perpendicular
  // is (0, −1, 1)/√2 and the lines' distance h/√2, reached at (0, 0, h) and (0, h/2, h/2).
  const double h = 0.05;
  TriMesh a;
  a.vertices = {Vec3(-1, 0, h), Vec3(1, 0, h), Vec3(0, 0, h + 2)};
  a.triangles = {{0, 1, 2}};
  TriMesh b;
  b.vertices = {Vec3(0, -1, -1), Vec3(0, 1, 1), Vec3(0, 1, -1)};
  b.triangles = {{0, 1, 2}};
  std::vector<CollisionBody> bodies{body_of(a), body_of(b)};
  ContactDetector detector;
  detector.reset(bodies);
  const auto contacts = run(detector, bodies, 0.1);
  ASSERT_EQ(contacts.size(), 1U);
  const BodyContact& c = contacts[0];
  EXPECT_EQ(c.a.kind, PrimitiveKind::kEdge);
  EXPECT_EQ(c.b.kind, PrimitiveKind::kEdge);
  EXPECT_NEAR(std::abs(c.distance), h / std::sqrt(2.0), 1e-14);
  EXPECT_NEAR((c.a.point - Vec3(0, 0, h)).norm(), 0.0, 1e-14);
  EXPECT_NEAR((c.b.point - Vec3(0, h / 2, h / 2)).norm(), 0.0, 1e-14);
  EXPECT_NEAR(std::abs(c.normal.dot(Vec3(0, -1, 1).normalized())), 1.0, 1e-14);
  EXPECT_NEAR((c.a.point - c.b.point).dot(c.normal), c.distance, 1e-14);
  EXPECT_NEAR(c.a.weights[1], 0.5, 1e-14);
  EXPECT_NEAR(c.b.weights[1], 0.5 + h / 4, 1e-14);
}

TEST(ContactDetector, EdgeEdgeSignFromAdjacentNormals) {
  // Two cubes whose edges cross: the upper cube's bottom edge y = 0 (x ∈ [−0.5, 0.5], z = 0)
  // and the lower cube's top edge x = 0 (y ∈ [−0.25, 0.75], z = depth) meet over (0, 0) at
  // interior points, each edge inside the other cube: a penetration of −depth along +z
  // (moving the upper cube up separates them).
  const double depth = 0.01;
  const TriMesh upper = cube(-0.5, 0.0, 0.0);
  const TriMesh lower = cube(0.0, -0.25, -1.0 + depth);
  std::vector<CollisionBody> bodies{body_of(upper), body_of(lower)};
  for (auto& b : bodies) b.points = false;
  ContactDetector detector;
  detector.reset(bodies);
  const auto contacts = run(detector, bodies, 0.02);
  const auto it =
      std::find_if(contacts.begin(), contacts.end(), [](const BodyContact& c) { return c.a.point.norm() < 1e-12; });
  ASSERT_NE(it, contacts.end());
  EXPECT_NEAR(it->distance, -depth, 1e-12);
  EXPECT_NEAR((it->normal - Vec3::UnitZ()).norm(), 0.0, 1e-12);  // the upper cube moves up
}

TEST(ContactDetector, SphereOnAPlaneGivesDMinusR) {
  const TriMesh floor = square(-1, -1, 2, 0.0, true);
  const double r = 0.02;
  for (const double d : {0.025, 0.015, -0.005}) {
    const std::vector<Vec3> centers{Vec3(0.1, 0.2, d)};
    const std::vector<double> radii{r};
    CollisionBody ball;
    ball.sphere_centers = centers;
    ball.sphere_radii = radii;
    std::vector<CollisionBody> bodies{ball, body_of(floor)};
    ContactDetector detector;
    detector.reset(bodies);
    const auto contacts = run(detector, bodies, 0.01);
    ASSERT_EQ(contacts.size(), 1U);
    const BodyContact& c = contacts[0];
    EXPECT_EQ(c.a.kind, PrimitiveKind::kSphere);
    EXPECT_EQ(c.a.vertices[0], 0);
    EXPECT_NEAR(c.distance, d - r, 1e-15);
    EXPECT_NEAR((c.normal - Vec3::UnitZ()).norm(), 0.0, 1e-15);
    EXPECT_NEAR((c.a.point - Vec3(0.1, 0.2, d - r)).norm(), 0.0, 1e-15);
    EXPECT_NEAR((c.b.point - Vec3(0.1, 0.2, 0.0)).norm(), 0.0, 1e-15);
  }
  // Beyond the alarm distance: nothing.
  const std::vector<Vec3> centers{Vec3(0.1, 0.2, r + 0.011)};
  const std::vector<double> radii{r};
  CollisionBody ball;
  ball.sphere_centers = centers;
  ball.sphere_radii = radii;
  std::vector<CollisionBody> bodies{ball, body_of(floor)};
  ContactDetector detector;
  detector.reset(bodies);
  EXPECT_TRUE(run(detector, bodies, 0.01).empty());
}

TEST(ContactDetector, SphereAgainstSphere) {
  const std::vector<Vec3> ca{Vec3(0, 0, 0)};
  const std::vector<Vec3> cb{Vec3(0.03, 0.04, 0)};  // 0.05 apart
  const std::vector<double> ra{0.02};
  const std::vector<double> rb{0.025};
  CollisionBody a;
  a.sphere_centers = ca;
  a.sphere_radii = ra;
  CollisionBody b;
  b.sphere_centers = cb;
  b.sphere_radii = rb;
  std::vector<CollisionBody> bodies{a, b};
  ContactDetector detector;
  detector.reset(bodies);
  const auto contacts = run(detector, bodies, 0.01);
  ASSERT_EQ(contacts.size(), 1U);
  EXPECT_NEAR(contacts[0].distance, 0.005, 1e-15);
  EXPECT_NEAR((contacts[0].normal - Vec3(-0.6, -0.8, 0)).norm(), 0.0, 1e-15);
  EXPECT_NEAR((contacts[0].a.point - Vec3(0.012, 0.016, 0)).norm(), 0.0, 1e-15);
  EXPECT_TRUE(run(detector, bodies, 0.004).empty());
}

TEST(ContactDetector, CubeRestingOnAFloorGivesFourVertexContacts) {
  const TriMesh floor = square(-2, -2, 4, 0.0, true);
  const TriMesh box = cube(0.2, 0.3, 0.0);
  std::vector<CollisionBody> bodies{body_of(box), body_of(floor)};
  bodies[1].simulated = false;
  bodies[1].moving = false;
  for (auto& b : bodies) b.lines = false;
  ContactDetector detector;
  detector.reset(bodies);
  const auto contacts = run(detector, bodies, 0.001);
  ASSERT_EQ(contacts.size(), 4U);
  const std::int32_t bottom[4] = {0, 1, 2, 3};  // cube() numbers the z = 0 corners first
  for (std::size_t k = 0; k < 4; ++k) {
    EXPECT_EQ(contacts[k].a.body, 0);
    EXPECT_EQ(contacts[k].a.vertices[0], bottom[k]);
    EXPECT_EQ(contacts[k].distance, 0.0);
    EXPECT_NEAR((contacts[k].normal - Vec3::UnitZ()).norm(), 0.0, 1e-15);
  }
}

TEST(ContactDetector, VertexPushedThroughIsReportedAndRemembered) {
  // A small triangle falls through a floor at 5 m/s with dt 10 ms: 5 cm per pass, far beyond
  // the 1 mm alarm distance. Continuous detection reports its vertices behind the floor.
  const TriMesh floor = square(-1, -1, 2, 0.0, true);
  TriMesh tri;
  tri.triangles = {{0, 1, 2}};
  const std::vector<Vec3> shape{Vec3(0, 0, 0), Vec3(0.1, 0, 0), Vec3(0, 0.1, 0)};
  const auto at = [&](double z) {
    std::vector<Vec3> v;
    for (const Vec3& p : shape) v.push_back(p + Vec3(0.3, 0.3, z));
    return v;
  };
  tri.vertices = at(0.02);
  std::vector<Vec3> previous = tri.vertices;
  std::vector<CollisionBody> bodies{body_of(tri), body_of(floor)};
  bodies[1].simulated = false;
  ContactDetector detector;
  detector.reset(bodies);
  EXPECT_TRUE(run(detector, bodies, 0.001).empty());

  // Pass 2: from z = 0.02 to z = −0.03 (one step at 5 m/s).
  tri.vertices = at(-0.03);
  bodies[0].surface.vertices = tri.vertices;
  bodies[0].previous_vertices = previous;
  auto contacts = run(detector, bodies, 0.001);
  ASSERT_EQ(contacts.size(), 3U);
  for (const BodyContact& c : contacts) {
    EXPECT_NEAR(c.distance, -0.03, 1e-15);
    EXPECT_NEAR((c.normal - Vec3::UnitZ()).norm(), 0.0, 1e-15);
    EXPECT_NEAR(c.b.point.z(), 0.0, 1e-15);
  }
  // Without the previous positions it would have been lost.
  {
    std::vector<CollisionBody> discrete = bodies;
    discrete[0].previous_vertices = {};
    ContactDetector fresh;
    fresh.reset(discrete);
    EXPECT_TRUE(run(fresh, discrete, 0.001).empty());
  }

  // Pass 3: it moves a little deeper; no crossing this pass, but it is still behind.
  previous = tri.vertices;
  tri.vertices = at(-0.035);
  bodies[0].surface.vertices = tri.vertices;
  contacts = run(detector, bodies, 0.001);
  ASSERT_EQ(contacts.size(), 3U);
  for (const BodyContact& c : contacts) EXPECT_NEAR(c.distance, -0.035, 1e-15);

  // Pass 4: pushed back out above the floor beyond the alarm: forgotten.
  previous = tri.vertices;
  tri.vertices = at(0.01);
  bodies[0].surface.vertices = tri.vertices;
  EXPECT_TRUE(run(detector, bodies, 0.001).empty());
  // Pass 5: it stays out (memory cleared).
  previous = tri.vertices;
  EXPECT_TRUE(run(detector, bodies, 0.001).empty());
}

TEST(ContactDetector, TunnellingAtFiveMetresPerSecond) {
  // A cube falling at 5 m/s (dt 10 ms) onto a floor: from the pass its bottom crosses the
  // floor on, every pass reports its four bottom vertices behind the floor (the top ones stay
  // above it).
  const TriMesh floor = square(-2, -2, 4, 0.0, true);
  TriMesh box = cube(0.1, 0.1, 0.012);
  const std::vector<Vec3> start = box.vertices;
  std::vector<CollisionBody> bodies{body_of(box), body_of(floor)};
  bodies[1].simulated = false;
  bodies[1].moving = false;
  bodies[0].lines = false;
  ContactDetector detector;
  detector.reset(bodies);
  std::vector<Vec3> previous = box.vertices;
  for (int step = 1; step <= 4; ++step) {
    previous = box.vertices;
    for (std::size_t k = 0; k < box.vertices.size(); ++k) box.vertices[k] = start[k] - Vec3(0, 0, 0.05 * step);
    bodies[0].surface.vertices = box.vertices;
    bodies[0].previous_vertices = previous;
    const auto contacts = run(detector, bodies, 0.001);
    const double bottom = 0.012 - 0.05 * step;
    ASSERT_EQ(contacts.size(), 4U) << "step " << step;
    for (const BodyContact& c : contacts) {
      EXPECT_LT(c.distance, 0.0);
      EXPECT_NEAR((c.normal - Vec3::UnitZ()).norm(), 0.0, 1e-12);
    }
    EXPECT_NEAR(contacts[0].distance, bottom, 1e-12);
  }
}

TEST(ContactDetector, GroupsAndSimulatedFilterPairs) {
  const TriMesh lower = square(0, 0, 1, 0.0, true);
  const TriMesh upper = square(0, 0, 1, 0.001, false);
  std::vector<CollisionBody> bodies{body_of(lower), body_of(upper)};
  ContactDetector detector;
  detector.reset(bodies);
  EXPECT_FALSE(run(detector, bodies, 0.01).empty());
  bodies[0].group = 3;
  bodies[1].group = 3;
  EXPECT_TRUE(run(detector, bodies, 0.01).empty());
  bodies[1].group = 4;
  EXPECT_FALSE(run(detector, bodies, 0.01).empty());
  bodies[0].group = -1;
  bodies[1].group = -1;
  bodies[0].simulated = false;
  EXPECT_FALSE(run(detector, bodies, 0.01).empty());  // one side still reacts
  bodies[1].simulated = false;
  EXPECT_TRUE(run(detector, bodies, 0.01).empty());
}

TEST(ContactDetector, SelfCollisionOnlyWhenAskedAndNotWithNeighbours) {
  // One body of two separate squares facing each other 2 mm apart, plus a connected strip.
  TriMesh m = square(0, 0, 1, 0.0, true);
  const TriMesh top = square(0, 0, 1, 0.002, false);
  for (const Tri& t : top.triangles) m.triangles.push_back({t[0] + 4, t[1] + 4, t[2] + 4});
  m.vertices.insert(m.vertices.end(), top.vertices.begin(), top.vertices.end());
  std::vector<CollisionBody> bodies{body_of(m)};
  bodies[0].lines = false;
  ContactDetector detector;
  detector.reset(bodies);
  EXPECT_TRUE(run(detector, bodies, 0.01).empty());  // off by default
  bodies[0].self_collision = true;
  const auto contacts = run(detector, bodies, 0.01);
  ASSERT_EQ(contacts.size(), 8U);
  for (const BodyContact& c : contacts) {
    EXPECT_EQ(c.a.body, 0);
    EXPECT_EQ(c.b.body, 0);
    EXPECT_NEAR(c.distance, 0.002, 1e-15);
  }
  // A connected surface: every vertex is on or next to every triangle, so nothing.
  const TriMesh strip = square(0, 0, 1, 0.0, true);
  std::vector<CollisionBody> single{body_of(strip)};
  single[0].self_collision = true;
  ContactDetector d2;
  d2.reset(single);
  EXPECT_TRUE(run(d2, single, 0.01).empty());
  // The cube: no vertex comes near a non-adjacent triangle within 0.5.
  const TriMesh box = cube(0, 0, 0);
  std::vector<CollisionBody> closed{body_of(box)};
  closed[0].self_collision = true;
  ContactDetector d3;
  d3.reset(closed);
  EXPECT_TRUE(run(d3, closed, 0.5).empty());
}

TEST(ContactDetector, BadInputGivesNoCrashAndNoNan) {
  const TriMesh lower = square(0, 0, 1, 0.0, true);
  TriMesh upper = square(0, 0, 1, 0.001, false);
  std::vector<CollisionBody> bodies{body_of(lower), body_of(upper)};
  ContactDetector detector;
  detector.reset(bodies);
  // Negative and NaN alarm distances count as 0: the squares 1 mm apart do not touch.
  EXPECT_TRUE(run(detector, bodies, -1.0).empty());
  EXPECT_TRUE(run(detector, bodies, kNan).empty());
  // A NaN vertex: that body takes no part.
  upper.vertices[2].x() = kNan;
  bodies[1].surface.vertices = upper.vertices;
  EXPECT_TRUE(run(detector, bodies, 0.01).empty());
  // Mismatched sphere spans are ignored; NaN previous positions fall back to discrete.
  upper.vertices[2].x() = 1.0;
  const std::vector<Vec3> centers{Vec3(0.5, 0.5, 0.0)};
  const std::vector<double> radii{0.1, 0.2};
  bodies[1].sphere_centers = centers;
  bodies[1].sphere_radii = radii;
  const std::vector<Vec3> nan_previous(4, Vec3::Constant(kNan));
  bodies[0].previous_vertices = nan_previous;
  auto contacts = run(detector, bodies, 0.01);
  EXPECT_FALSE(contacts.empty());
  for (const BodyContact& c : contacts) {
    EXPECT_TRUE(finite(c));
    EXPECT_NE(c.a.kind, PrimitiveKind::kSphere);
  }
  // NaN sphere radius and centre.
  const std::vector<double> nan_radius{kNan};
  bodies[1].sphere_radii = nan_radius;
  for (const BodyContact& c : run(detector, bodies, 0.01)) EXPECT_TRUE(finite(c));
  // A body count or topology different from reset(): nothing, no crash.
  std::vector<CollisionBody> one{bodies[0]};
  EXPECT_TRUE(run(detector, one, 0.01).empty());
  const TriMesh other = cube(0, 0, 0);
  bodies[1] = body_of(other);
  contacts = run(detector, bodies, 0.01);
  EXPECT_TRUE(contacts.empty());
  // Triangle indices out of range at reset(): that body is left out.
  TriMesh broken = square(0, 0, 1, 0.001, false);
  broken.triangles[1][2] = 7;
  std::vector<CollisionBody> bad{body_of(lower), body_of(broken)};
  ContactDetector d2;
  d2.reset(bad);
  EXPECT_TRUE(run(d2, bad, 0.01).empty());
  // Degenerate triangles (all corners equal) never give a NaN.
  TriMesh flat;
  flat.vertices = {Vec3(0.5, 0.5, 0.001), Vec3(0.5, 0.5, 0.001), Vec3(0.5, 0.5, 0.001)};
  flat.triangles = {{0, 1, 2}};
  std::vector<CollisionBody> degenerate{body_of(lower), body_of(flat)};
  ContactDetector d3;
  d3.reset(degenerate);
  for (const BodyContact& c : run(d3, degenerate, 0.01)) EXPECT_TRUE(finite(c));
}

// Two overlapping liver surfaces, the second shifted and rotated.
struct TwoLivers {
  TriMesh a;
  TriMesh b;
  TwoLivers() : a(mesh::make_liver_surface(6)), b(a) {
    const double c = std::cos(0.3);
    const double s = std::sin(0.3);
    for (Vec3& p : b.vertices) p = Vec3(c * p.x() - s * p.y(), s * p.x() + c * p.y(), p.z()) + Vec3(0.05, 0.02, 0.07);
  }
};

TEST(ContactDetector, DeterministicOutput) {
  TwoLivers livers;
  std::vector<CollisionBody> bodies{body_of(livers.a), body_of(livers.b)};
  ContactDetector detector;
  detector.reset(bodies);
  const auto first = run(detector, bodies, 0.005);
  const auto second = run(detector, bodies, 0.005);
  ASSERT_FALSE(first.empty());
  ASSERT_EQ(first.size(), second.size());
  for (std::size_t k = 0; k < first.size(); ++k) {
    EXPECT_EQ(first[k].a.vertices, second[k].a.vertices);
    EXPECT_EQ(first[k].b.vertices, second[k].b.vertices);
    EXPECT_EQ(first[k].distance, second[k].distance);
    EXPECT_EQ(first[k].normal, second[k].normal);
    EXPECT_TRUE(finite(first[k]));
  }
}

// A random triangle soup in the unit cube: `count` triangles with edges ≤ `size`.
TriMesh random_soup(std::mt19937& gen, int count, double size) {
  std::uniform_real_distribution<double> unit(0.0, 1.0);
  std::uniform_real_distribution<double> offset(-size, size);
  TriMesh m;
  for (int t = 0; t < count; ++t) {
    const double x = unit(gen);
    const double y = unit(gen);
    const double z = unit(gen);
    const Vec3 base(x, y, z);
    m.vertices.push_back(base);
    for (int k = 0; k < 2; ++k) {
      const double dx = offset(gen);
      const double dy = offset(gen);
      const double dz = offset(gen);
      m.vertices.push_back(base + Vec3(dx, dy, dz));
    }
    m.triangles.push_back({3 * t, 3 * t + 1, 3 * t + 2});
  }
  return m;
}

TEST(ContactDetector, TreeAgreesWithBruteForceOnRandomSurfaces) {
  std::mt19937 gen(20261128);
  for (int round = 0; round < 5; ++round) {
    const TriMesh a = random_soup(gen, 300, 0.08);
    const TriMesh b = random_soup(gen, 300, 0.08);
    const double alarm = 0.02;
    std::vector<CollisionBody> bodies{body_of(a), body_of(b)};
    ContactDetector tree_detector;
    tree_detector.reset(bodies, AabbTreeOptions{.max_triangles_in_leaf = 2});
    ContactDetector brute_detector;
    brute_detector.reset(bodies, AabbTreeOptions{.use_bound_tree = false});
    const auto with_tree = run(tree_detector, bodies, alarm);
    const auto brute = run(brute_detector, bodies, alarm);
    ASSERT_EQ(with_tree.size(), brute.size());
    for (std::size_t k = 0; k < brute.size(); ++k) {
      EXPECT_EQ(with_tree[k].a.vertices, brute[k].a.vertices);
      EXPECT_EQ(with_tree[k].b.vertices, brute[k].b.vertices);
      EXPECT_EQ(with_tree[k].distance, brute[k].distance);
    }
    // Independently: each vertex's distance to the other surface over all triangles, and
    // every edge pair with interior closest points within the alarm.
    std::size_t vertex_contacts = 0;
    std::size_t edge_contacts = 0;
    for (const BodyContact& c : with_tree) {
      if (c.a.kind == PrimitiveKind::kVertex) ++vertex_contacts;
      if (c.a.kind == PrimitiveKind::kEdge) ++edge_contacts;
    }
    std::size_t expected_vertex = 0;
    for (int side = 0; side < 2; ++side) {
      const TriMesh& p = side == 0 ? a : b;
      const TriMesh& q = side == 0 ? b : a;
      for (std::size_t v = 0; v < p.vertices.size(); ++v) {
        double best = std::numeric_limits<double>::infinity();
        for (const Tri& t : q.triangles) {
          best = std::min(best, std::sqrt(point_triangle_distance_squared(p.vertices[v], q.vertices[t[0]],
                                                                          q.vertices[t[1]], q.vertices[t[2]])));
        }
        if (best <= alarm) {
          ++expected_vertex;
          const auto it = std::find_if(with_tree.begin(), with_tree.end(), [&](const BodyContact& c) {
            return c.a.kind == PrimitiveKind::kVertex && c.a.body == side &&
                   c.a.vertices[0] == static_cast<std::int32_t>(v);
          });
          ASSERT_NE(it, with_tree.end());
          EXPECT_NEAR(std::abs(it->distance), best, 1e-12);
        }
      }
    }
    EXPECT_EQ(vertex_contacts, expected_vertex);
    std::size_t expected_edge = 0;
    for (const Tri& ta : a.triangles) {
      for (int i = 0; i < 3; ++i) {
        for (const Tri& tb : b.triangles) {
          for (int j = 0; j < 3; ++j) {
            const auto sc = detail::closest_points_segment_segment(a.vertices[ta[i]], a.vertices[ta[(i + 1) % 3]],
                                                                   b.vertices[tb[j]], b.vertices[tb[(j + 1) % 3]]);
            if (sc.distance_squared <= alarm * alarm && sc.s > 0 && sc.s < 1 && sc.t > 0 && sc.t < 1) {
              ++expected_edge;
            }
          }
        }
      }
    }
    EXPECT_EQ(edge_contacts, expected_edge);
    EXPECT_GT(vertex_contacts, 0U);
    EXPECT_GT(edge_contacts, 0U);
  }
}

TEST(ContactDetector, SegmentClosestPointsAnalytic) {
  // Crossing at right angles, 0.3 apart.
  auto sc = detail::closest_points_segment_segment(Vec3(-1, 0, 0), Vec3(1, 0, 0), Vec3(0, -1, 0.3), Vec3(0, 1, 0.3));
  EXPECT_NEAR(sc.s, 0.5, 1e-15);
  EXPECT_NEAR(sc.t, 0.5, 1e-15);
  EXPECT_NEAR(sc.distance_squared, 0.09, 1e-15);
  // Clamped: the second segment ends before reaching the first's line.
  sc = detail::closest_points_segment_segment(Vec3(0, 0, 0), Vec3(1, 0, 0), Vec3(2, 1, 0), Vec3(2, 3, 0));
  EXPECT_EQ(sc.s, 1.0);
  EXPECT_EQ(sc.t, 0.0);
  EXPECT_NEAR(sc.distance_squared, 2.0, 1e-15);
  // Parallel and overlapping: one pair of the many, with one of them at an endpoint.
  sc = detail::closest_points_segment_segment(Vec3(0, 0, 0), Vec3(1, 0, 0), Vec3(0.5, 1, 0), Vec3(1.5, 1, 0));
  EXPECT_TRUE(sc.s == 0.0 || sc.s == 1.0 || sc.t == 0.0 || sc.t == 1.0);
  EXPECT_NEAR(sc.distance_squared, 1.0, 1e-15);
  // NaN: no crash.
  sc = detail::closest_points_segment_segment(Vec3(kNan, 0, 0), Vec3(1, 0, 0), Vec3(0, 1, 0), Vec3(1, 1, 0));
  EXPECT_FALSE(sc.distance_squared <= 0.0);
}

}  // namespace
}  // namespace hof::collision
