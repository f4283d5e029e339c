// The exact per-triangle queries (src/hof/collision/triangle_queries.cpp) on their own, against
// brute force written differently (the plane projection and the three edge segments for the
// closest point; the plane crossing and a sub-area test for segments; the distance sampled along
// the motion for swept spheres), with every Voronoi region, hits and misses, the side filters,
// and degenerate triangles that must never yield a contact or a NaN that counts.

#include "hof/collision/triangle_queries.h"

#include <gtest/gtest.h>

#include <algorithm>
#include <array>
#include <cmath>
#include <limits>
#include <random>

namespace hof::collision {
namespace {

using detail::box_distance_squared;
using detail::closest_point_counts;
using detail::closest_point_on_triangle;
using detail::intersect_segment_triangle;
using detail::slab_entry;
using detail::SlabSegment;
using detail::sweep_sphere_triangle;
using detail::TriangleContact;

constexpr double kNaN = std::numeric_limits<double>::quiet_NaN();

// A scalene triangle in a tilted plane: no coordinate or symmetry makes a wrong region right.
const Vec3 kP0(0.1, -0.2, 0.05);
const Vec3 kP1(0.9, 0.1, -0.15);
const Vec3 kP2(0.3, 0.7, 0.4);

Vec3 closest_on_segment(const Vec3& p, const Vec3& a, const Vec3& b) {
  const double s = std::clamp((p - a).dot(b - a) / (b - a).squaredNorm(), 0.0, 1.0);
  return a + s * (b - a);
}

// Brute force: the projection onto the plane when it falls inside, else the nearest of the
// three edges' nearest points.
Vec3 brute_closest(const Vec3& p, const Vec3& a, const Vec3& b, const Vec3& c) {
  const Vec3 n = (b - a).cross(c - a);
  const Vec3 q = p - (p - a).dot(n) / n.squaredNorm() * n;
  const bool inside =
      n.dot((b - a).cross(q - a)) >= 0 && n.dot((c - b).cross(q - b)) >= 0 && n.dot((a - c).cross(q - c)) >= 0;
  if (inside) return q;
  Vec3 best = closest_on_segment(p, a, b);
  for (const Vec3& candidate : {closest_on_segment(p, b, c), closest_on_segment(p, c, a)}) {
    if ((candidate - p).squaredNorm() < (best - p).squaredNorm()) best = candidate;
  }
  return best;
}

TEST(ClosestPointOnTriangle, MatchesBruteForceInEveryVoronoiRegion) {
  std::mt19937 rng(5);
  std::uniform_real_distribution<double> coordinate(-1.5, 2.0);
  // Regions by the zeros of the weights: 3 vertices, 3 edges, the face.
  std::array<int, 7> seen{};
  for (int i = 0; i < 20000; ++i) {
    const Vec3 p(coordinate(rng), coordinate(rng), coordinate(rng));
    Vec3 w;
    const Vec3 c = closest_point_on_triangle(p, kP0, kP1, kP2, w);
    const Vec3 expected = brute_closest(p, kP0, kP1, kP2);
    ASSERT_LT((c - expected).norm(), 1e-12) << p.transpose();
    ASSERT_NEAR(point_triangle_distance_squared(p, kP0, kP1, kP2), (expected - p).squaredNorm(), 1e-12);
    // The weights are the point's, sum to one, and none is negative.
    ASSERT_NEAR(w.sum(), 1.0, 1e-12);
    ASSERT_GE(w.minCoeff(), -1e-12);
    ASSERT_LT((w[0] * kP0 + w[1] * kP1 + w[2] * kP2 - c).norm(), 1e-12);
    const int zeros = (w[0] == 0.0) + (w[1] == 0.0) + (w[2] == 0.0);
    if (zeros == 2)
      ++seen[w[0] == 1.0 ? 0 : w[1] == 1.0 ? 1 : 2];
    else if (zeros == 1)
      ++seen[w[2] == 0.0 ? 3 : w[1] == 0.0 ? 4 : 5];
    else
      ++seen[6];
  }
  for (int region = 0; region < 7; ++region) EXPECT_GT(seen[region], 100) << "region " << region;
}

TEST(ClosestPointOnTriangle, APointOfTheTriangleIsItsOwnClosestPoint) {
  for (const Vec3& w : {Vec3(0.2, 0.3, 0.5), Vec3(1, 0, 0), Vec3(0, 0.25, 0.75), Vec3(1.0 / 3, 1.0 / 3, 1.0 / 3)}) {
    const Vec3 p = w[0] * kP0 + w[1] * kP1 + w[2] * kP2;
    Vec3 weights;
    EXPECT_LT((closest_point_on_triangle(p, kP0, kP1, kP2, weights) - p).norm(), 1e-15);
    EXPECT_LT((weights - w).norm(), 1e-12);
  }
}

TEST(ClosestPointOnTriangle, ADegenerateTriangleNeverCrashesAndNeverCounts) {
  const Vec3 p(0.3, 0.4, 0.5);
  const Vec3 a(0, 0, 0), b(1, 1, 1);
  const std::array<std::array<Vec3, 3>, 4> degenerate{{
      {a, b, Vec3(0.5, 0.5, 0.5)},  // collinear
      {a, a, b},                    // a repeated vertex
      {a, a, a},                    // a point
      {a, b, Vec3(kNaN, 0, 0)},     // not a number
  }};
  for (const auto& t : degenerate) {
    Vec3 w;
    (void)closest_point_on_triangle(p, t[0], t[1], t[2], w);  // may be NaN; must return
    for (const TouchableFace face : {TouchableFace::kFront, TouchableFace::kBack, TouchableFace::kFrontAndBack}) {
      EXPECT_FALSE(closest_point_counts(p, t[0], t[1], t[2], face));
    }
  }
  // A sliver just above the degeneracy threshold (sine of the smallest angle ~1e-9) counts.
  EXPECT_TRUE(closest_point_counts(p, a, Vec3(1, 0, 0), Vec3(0.5, 1e-9, 0), TouchableFace::kFrontAndBack));
  EXPECT_FALSE(closest_point_counts(p, a, Vec3(1, 0, 0), Vec3(0.5, 1e-13, 0), TouchableFace::kFrontAndBack));
}

TEST(ClosestPointOnTriangle, CountsOnlyFromTheSidesTheFaceAllows) {
  const Vec3 a(0, 0, 0), b(1, 0, 0), c(0, 1, 0);  // normal +z
  const Vec3 above(0.2, 0.2, 0.3), below(0.2, 0.2, -0.3), on(0.2, 0.2, 0.0);
  EXPECT_TRUE(closest_point_counts(above, a, b, c, TouchableFace::kFront));
  EXPECT_FALSE(closest_point_counts(above, a, b, c, TouchableFace::kBack));
  EXPECT_FALSE(closest_point_counts(below, a, b, c, TouchableFace::kFront));
  EXPECT_TRUE(closest_point_counts(below, a, b, c, TouchableFace::kBack));
  EXPECT_TRUE(closest_point_counts(on, a, b, c, TouchableFace::kFront));  // the plane is the front's
  EXPECT_TRUE(closest_point_counts(below, a, b, c, TouchableFace::kFrontAndBack));
  // Reversing the winding swaps the sides.
  EXPECT_TRUE(closest_point_counts(below, a, c, b, TouchableFace::kFront));
}

TEST(SegmentTriangle, HitsAtTheAnalyticTimePointWeightsAndNormal) {
  const Vec3 a(0, 0, 0), b(2, 0, 0), c(0, 4, 0);  // normal +z
  TriangleContact hit;
  // From z = 1 down to z = −3: crosses the plane at t = 1/4, at (0.5, 1, 0).
  ASSERT_TRUE(intersect_segment_triangle(Vec3(0.5, 1, 1), Vec3(0, 0, -4), a, b, c, TouchableFace::kFront, hit));
  EXPECT_DOUBLE_EQ(hit.t, 0.25);
  EXPECT_LT((hit.point - Vec3(0.5, 1, 0)).norm(), 1e-15);
  EXPECT_LT((hit.barycentric - Vec3(0.5, 0.25, 0.25)).norm(), 1e-15);
  EXPECT_EQ(hit.normal, Vec3(0, 0, 1));  // toward where the segment came from
  EXPECT_TRUE(hit.front);
  // From behind: only a back or two-sided face is touched, and the normal points down.
  EXPECT_FALSE(intersect_segment_triangle(Vec3(0.5, 1, -1), Vec3(0, 0, 4), a, b, c, TouchableFace::kFront, hit));
  ASSERT_TRUE(intersect_segment_triangle(Vec3(0.5, 1, -1), Vec3(0, 0, 4), a, b, c, TouchableFace::kBack, hit));
  EXPECT_DOUBLE_EQ(hit.t, 0.25);
  EXPECT_EQ(hit.normal, Vec3(0, 0, -1));
  EXPECT_FALSE(hit.front);
  EXPECT_FALSE(intersect_segment_triangle(Vec3(0.5, 1, 1), Vec3(0, 0, -4), a, b, c, TouchableFace::kBack, hit));
}

TEST(SegmentTriangle, MissesBesideShortOfBehindAndParallel) {
  const Vec3 a(0, 0, 0), b(1, 0, 0), c(0, 1, 0);
  TriangleContact hit;
  const TouchableFace both = TouchableFace::kFrontAndBack;
  EXPECT_FALSE(
      intersect_segment_triangle(Vec3(0.6, 0.6, 1), Vec3(0, 0, -2), a, b, c, both, hit));  // beside (u + v > 1)
  EXPECT_FALSE(intersect_segment_triangle(Vec3(0.2, 0.2, 1), Vec3(0, 0, -0.5), a, b, c, both, hit));   // stops short
  EXPECT_FALSE(intersect_segment_triangle(Vec3(0.2, 0.2, 1), Vec3(0, 0, 0.5), a, b, c, both, hit));    // moving away
  EXPECT_FALSE(intersect_segment_triangle(Vec3(0.2, 0.2, 0), Vec3(0.1, 0.1, 0), a, b, c, both, hit));  // in the plane
  EXPECT_FALSE(intersect_segment_triangle(Vec3(0.2, 0.2, 1), Vec3(1, 0, 0), a, b, c, both, hit));      // parallel
  // Both endpoints are inclusive.
  ASSERT_TRUE(intersect_segment_triangle(Vec3(0.2, 0.2, 1), Vec3(0, 0, -1), a, b, c, both, hit));
  EXPECT_EQ(hit.t, 1.0);
  ASSERT_TRUE(intersect_segment_triangle(Vec3(0.2, 0.2, 0), Vec3(0, 0, -1), a, b, c, both, hit));
  EXPECT_EQ(hit.t, 0.0);
  // So is the boundary: through an edge's midpoint and through a vertex.
  EXPECT_TRUE(intersect_segment_triangle(Vec3(0.5, 0.5, 1), Vec3(0, 0, -2), a, b, c, both, hit));
  EXPECT_TRUE(intersect_segment_triangle(Vec3(1, 0, 1), Vec3(0, 0, -2), a, b, c, both, hit));
  EXPECT_LT((hit.barycentric - Vec3(0, 1, 0)).norm(), 1e-12);
}

TEST(SegmentTriangle, MatchesThePlaneCrossingOnRandomSegments) {
  std::mt19937 rng(11);
  std::uniform_real_distribution<double> coordinate(-1.0, 2.0);
  const Vec3 n = (kP1 - kP0).cross(kP2 - kP0);
  int hits = 0;
  for (int i = 0; i < 20000; ++i) {
    const Vec3 a(coordinate(rng), coordinate(rng), coordinate(rng));
    const Vec3 d = Vec3(coordinate(rng), coordinate(rng), coordinate(rng)) - a;
    if (std::abs(d.dot(n)) < 1e-3 * d.norm() * n.norm()) continue;  // grazing the plane: ill-conditioned
    // Brute force: where the line crosses the plane, and whether that point is inside.
    const double t = (kP0 - a).dot(n) / d.dot(n);
    const Vec3 q = a + t * d;
    const double s0 = n.dot((kP1 - kP0).cross(q - kP0)), s1 = n.dot((kP2 - kP1).cross(q - kP1)),
                 s2 = n.dot((kP0 - kP2).cross(q - kP2));
    const double margin = 1e-8 * n.squaredNorm();  // the query accepts 1e-9 past an edge
    const double edge = std::min({s0, s1, s2});
    if (std::abs(edge) < margin || std::abs(t) < 1e-9 || std::abs(t - 1) < 1e-9) continue;  // too close to call
    const bool expected = t >= 0 && t <= 1 && edge > 0;
    TriangleContact hit;
    const bool got = intersect_segment_triangle(a, d, kP0, kP1, kP2, TouchableFace::kFrontAndBack, hit);
    ASSERT_EQ(got, expected) << "a " << a.transpose() << " d " << d.transpose();
    if (!got) continue;
    ++hits;
    EXPECT_NEAR(hit.t, t, 1e-12);
    EXPECT_LT((hit.point - q).norm(), 1e-12);
    EXPECT_EQ(hit.front, d.dot(n) < 0);
    EXPECT_NEAR(hit.normal.norm(), 1.0, 1e-15);
    EXPECT_LT(hit.normal.dot(d), 0.0);  // toward where the segment came from
  }
  EXPECT_GT(hits, 500);
}

TEST(SegmentTriangle, ADegenerateTriangleIsNeverHit) {
  const Vec3 a(0, 0, 0), b(1, 0, 0);
  TriangleContact hit;
  const TouchableFace both = TouchableFace::kFrontAndBack;
  EXPECT_FALSE(intersect_segment_triangle(Vec3(0.5, 0, 1), Vec3(0, 0, -2), a, b, Vec3(0.5, 0, 0), both, hit));
  EXPECT_FALSE(intersect_segment_triangle(Vec3(0.5, 0, 1), Vec3(0, 0, -2), a, b, Vec3(0.5, 1e-14, 0), both, hit));
  EXPECT_FALSE(intersect_segment_triangle(Vec3(0.5, 0, 1), Vec3(0, 0, -2), a, a, a, both, hit));
  EXPECT_FALSE(intersect_segment_triangle(Vec3(0.1, 0.1, 1), Vec3(0, 0, -2), a, b, Vec3(0, kNaN, 0), both, hit));
  EXPECT_FALSE(intersect_segment_triangle(Vec3(kNaN, 0.1, 1), Vec3(0, 0, -2), a, b, Vec3(0, 1, 0), both, hit));
}

// The first time the sphere's distance to the triangle reaches the radius, by sampling.
double sampled_first_contact(const Vec3& a, const Vec3& d, double radius, int samples) {
  for (int i = 0; i <= samples; ++i) {
    const double t = static_cast<double>(i) / samples;
    if (std::sqrt(point_triangle_distance_squared(a + t * d, kP0, kP1, kP2)) <= radius) return t;
  }
  return std::numeric_limits<double>::infinity();
}

TEST(SweepSphereTriangle, FirstContactMatchesTheSampledDistance) {
  std::mt19937 rng(13);
  std::uniform_real_distribution<double> coordinate(-1.0, 2.0);
  std::uniform_real_distribution<double> radii(0.01, 0.3);
  constexpr int kSamples = 4000;
  int hits = 0, misses = 0;
  for (int i = 0; i < 3000; ++i) {
    const Vec3 a(coordinate(rng), coordinate(rng), coordinate(rng));
    const Vec3 d = Vec3(coordinate(rng), coordinate(rng), coordinate(rng)) - a;
    const double r = radii(rng);
    if (std::sqrt(point_triangle_distance_squared(a, kP0, kP1, kP2)) <= r + 1e-6) continue;  // starts touching
    const double sampled = sampled_first_contact(a, d, r, kSamples);
    // The sampling cannot tell a graze from a near miss: leave out what passes within a hair.
    double closest = std::numeric_limits<double>::infinity();
    for (int k = 0; k <= kSamples; ++k) {
      closest =
          std::min(closest, std::sqrt(point_triangle_distance_squared(a + (double(k) / kSamples) * d, kP0, kP1, kP2)));
    }
    if (std::abs(closest - r) < 1e-3 * d.norm()) continue;
    TriangleContact hit;
    const bool got = sweep_sphere_triangle(a, d, r, kP0, kP1, kP2, TouchableFace::kFrontAndBack, hit);
    ASSERT_EQ(got, std::isfinite(sampled)) << "a " << a.transpose() << " d " << d.transpose() << " r " << r;
    if (!got) {
      ++misses;
      continue;
    }
    ++hits;
    // The contact time is the first sample inside, to within one sample step.
    EXPECT_LE(hit.t, sampled + 1e-12);
    EXPECT_GE(hit.t, sampled - 1.0 / kSamples - 1e-12);
    // At the contact the centre is exactly one radius from the contact point, which is the
    // triangle's closest point, along the contact normal.
    const Vec3 centre = a + hit.t * d;
    EXPECT_NEAR((centre - hit.point).norm(), r, 1e-9);
    EXPECT_NEAR(std::sqrt(point_triangle_distance_squared(centre, kP0, kP1, kP2)), r, 1e-9);
    EXPECT_LT((hit.normal - (centre - hit.point) / r).norm(), 1e-7);
    EXPECT_LT(hit.normal.dot(d), 0.0);
    EXPECT_LT((hit.barycentric[0] * kP0 + hit.barycentric[1] * kP1 + hit.barycentric[2] * kP2 - hit.point).norm(),
              1e-12);
  }
  EXPECT_GT(hits, 100);
  EXPECT_GT(misses, 100);
}

TEST(SweepSphereTriangle, FaceContactAtTheAnalyticTimeAndRadiusZeroIsTheSegment) {
  const Vec3 a(0, 0, 0), b(1, 0, 0), c(0, 1, 0);
  TriangleContact hit;
  // Centre from z = 1 to z = −1, radius 0.25: touches when z = 0.25, t = 0.375.
  ASSERT_TRUE(sweep_sphere_triangle(Vec3(0.2, 0.3, 1), Vec3(0, 0, -2), 0.25, a, b, c, TouchableFace::kFront, hit));
  EXPECT_DOUBLE_EQ(hit.t, 0.375);
  EXPECT_LT((hit.point - Vec3(0.2, 0.3, 0)).norm(), 1e-15);
  EXPECT_EQ(hit.normal, Vec3(0, 0, 1));
  EXPECT_TRUE(hit.front);
  TriangleContact segment;
  ASSERT_TRUE(sweep_sphere_triangle(Vec3(0.2, 0.3, 1), Vec3(0, 0, -2), 0.0, a, b, c, TouchableFace::kFront, hit));
  ASSERT_TRUE(intersect_segment_triangle(Vec3(0.2, 0.3, 1), Vec3(0, 0, -2), a, b, c, TouchableFace::kFront, segment));
  EXPECT_DOUBLE_EQ(hit.t, segment.t);
  EXPECT_LT((hit.point - segment.point).norm(), 1e-15);
}

TEST(SweepSphereTriangle, NoContactForABadRadiusADegenerateTriangleOrAnOverlapThatLeaves) {
  const Vec3 a(0, 0, 0), b(1, 0, 0), c(0, 1, 0);
  TriangleContact hit;
  const TouchableFace both = TouchableFace::kFrontAndBack;
  EXPECT_FALSE(sweep_sphere_triangle(Vec3(0.2, 0.3, 1), Vec3(0, 0, -2), -0.1, a, b, c, both, hit));
  EXPECT_FALSE(sweep_sphere_triangle(Vec3(0.2, 0.3, 1), Vec3(0, 0, -2), kNaN, a, b, c, both, hit));
  EXPECT_FALSE(sweep_sphere_triangle(Vec3(0.2, 0, 1), Vec3(0, 0, -2), 0.1, a, b, Vec3(0.5, 0, 0), both, hit));
  EXPECT_FALSE(sweep_sphere_triangle(Vec3(0.2, 0.3, 1), Vec3(0, 0, -2), 0.1, a, b, Vec3(0.5, kNaN, 0), both, hit));
  // Overlapping at the start: touching now when approaching, never when leaving.
  ASSERT_TRUE(sweep_sphere_triangle(Vec3(0.2, 0.3, 0.05), Vec3(0, 0, -1), 0.1, a, b, c, both, hit));
  EXPECT_EQ(hit.t, 0.0);
  EXPECT_FALSE(sweep_sphere_triangle(Vec3(0.2, 0.3, 0.05), Vec3(0, 0, 1), 0.1, a, b, c, both, hit));
  // Out of reach: farther than radius + |d|.
  EXPECT_FALSE(sweep_sphere_triangle(Vec3(0.2, 0.3, 1), Vec3(0, 0, -0.5), 0.1, a, b, c, both, hit));
}

TEST(BoxDistance, ZeroInsideAndTheSquaredGapOutside) {
  const Vec3 lo(-1, 0, 2), hi(1, 3, 4);
  EXPECT_EQ(box_distance_squared(Vec3(0, 1, 3), lo, hi), 0.0);
  EXPECT_EQ(box_distance_squared(Vec3(1, 3, 4), lo, hi), 0.0);           // on a corner
  EXPECT_DOUBLE_EQ(box_distance_squared(Vec3(0, 1, 6), lo, hi), 4.0);    // beside a face
  EXPECT_DOUBLE_EQ(box_distance_squared(Vec3(3, 5, 3), lo, hi), 8.0);    // beside an edge
  EXPECT_DOUBLE_EQ(box_distance_squared(Vec3(-2, -1, 1), lo, hi), 3.0);  // beyond a corner
  EXPECT_TRUE(std::isnan(box_distance_squared(Vec3(kNaN, 0, 3), lo, hi)));
}

TEST(SlabEntry, EntryTimeOfASegmentIntoAnInflatedBox) {
  const Vec3 lo(0, 0, 0), hi(1, 1, 1);
  double t = -1;
  // Along x from −1 to 3 (d = 4): enters x = 0 at t = 1/4.
  ASSERT_TRUE(slab_entry(SlabSegment(Vec3(-1, 0.5, 0.5), Vec3(4, 0, 0)), lo, hi, 0.0, 1.0, t));
  EXPECT_DOUBLE_EQ(t, 0.25);
  // Inflated by 0.5: enters x = −0.5 at t = 1/8.
  ASSERT_TRUE(slab_entry(SlabSegment(Vec3(-1, 0.5, 0.5), Vec3(4, 0, 0)), lo, hi, 0.5, 1.0, t));
  EXPECT_DOUBLE_EQ(t, 0.125);
  // Starting inside: t = 0.
  ASSERT_TRUE(slab_entry(SlabSegment(Vec3(0.5, 0.5, 0.5), Vec3(4, 0, 0)), lo, hi, 0.0, 1.0, t));
  EXPECT_EQ(t, 0.0);
  // Stopping short of the box, or before t_max reaches it.
  EXPECT_FALSE(slab_entry(SlabSegment(Vec3(-1, 0.5, 0.5), Vec3(0.5, 0, 0)), lo, hi, 0.0, 1.0, t));
  EXPECT_FALSE(slab_entry(SlabSegment(Vec3(-1, 0.5, 0.5), Vec3(4, 0, 0)), lo, hi, 0.0, 0.2, t));
  // A flat axis: inside its slab (boundary included) or never.
  EXPECT_TRUE(slab_entry(SlabSegment(Vec3(-1, 1.0, 0.5), Vec3(4, 0, 0)), lo, hi, 0.0, 1.0, t));
  EXPECT_FALSE(slab_entry(SlabSegment(Vec3(-1, 1.5, 0.5), Vec3(4, 0, 0)), lo, hi, 0.0, 1.0, t));
  EXPECT_TRUE(slab_entry(SlabSegment(Vec3(-1, 1.5, 0.5), Vec3(4, 0, 0)), lo, hi, 0.5, 1.0, t));
  // Diagonal, missing the box by passing over a corner.
  EXPECT_FALSE(slab_entry(SlabSegment(Vec3(-1, 0.5, 0.5), Vec3(1.2, 2.0, 0)), lo, hi, 0.0, 1.0, t));
}

}  // namespace
}  // namespace hof::collision
