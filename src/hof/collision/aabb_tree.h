#pragma once
/// @file
/// A bounding-volume hierarchy of axis-aligned boxes over the triangles of a surface (H3D's
/// GeometryBoundTreeOptions boundType "AABB", maxTrianglesInLeaf), with bottom-up refit after
/// deformation, and the queries the haptic renderers need. Build and refit happen outside the
/// haptic tick; queries are const, allocation-free and bounded (explicit stack of fixed depth).
/// `use_bound_tree = false` (H3D HapticsOptions.useBoundTree) answers the same queries by brute
/// force over all triangles, for comparison and tests.

#include <cstdint>
#include <span>
#include <utility>
#include <vector>

#include "hof/collision/triangle_mesh_view.h"

namespace hof::collision {

struct AabbTreeOptions {
  /// H3D default 1; a value < 1 makes the whole tree one leaf (H3D: maxTrianglesInLeaf < 0).
  int max_triangles_in_leaf{1};
  /// refit() reports that a rebuild is due when the summed surface area of the boxes has
  /// grown past this factor of its value at build time (boxes inflated by deformation).
  double rebuild_area_ratio{2.0};
  bool use_bound_tree{true};  ///< false: brute force over all triangles
};

class AabbTree {
 public:
  AabbTree() = default;

  /// Builds the hierarchy (top-down median split on the longest axis of triangle centroids).
  /// Deterministic. Triangle indices must be valid for `mesh`.
  static AabbTree build(const TriangleMeshView& mesh, const AabbTreeOptions& options = {});

  /// Recomputes all boxes for moved vertices (same topology), bottom-up, O(F). Returns true
  /// when the tree has degraded enough that a rebuild is advisable.
  bool refit(const TriangleMeshView& mesh);

  /// Closest point on a touchable triangle within `max_distance` of `p` (inclusive).
  /// `face` filters triangles by the side `p` is on. Triangles listed in `skip` (sorted
  /// ascending) are ignored (self-collision: a vertex's own and adjacent triangles).
  [[nodiscard]] ClosestPoint closest_point(const TriangleMeshView& mesh, const Vec3& p, double max_distance,
                                           TouchableFace face = TouchableFace::kFrontAndBack,
                                           std::span<const std::int32_t> skip = {}) const;

  /// First triangle crossed by the segment a→b from a touchable side (a segment leaving a
  /// triangle from its non-touchable side passes). Ties broken by lowest triangle index.
  [[nodiscard]] SweepHit first_hit_segment(const TriangleMeshView& mesh, const Vec3& a, const Vec3& b,
                                           TouchableFace face = TouchableFace::kFront) const;

  /// First contact of a sphere of `radius` moving from a to b with any triangle (faces,
  /// edges and vertices), approached from a touchable side. t is the fraction of the motion
  /// at contact; `point` the contact point on the triangle; `normal` points from it to the
  /// sphere centre. A sphere already overlapping a triangle at `a` and moving toward it
  /// reports t = 0. The side of an edge or vertex contact is the side of the triangle's
  /// plane the centre is on at contact (for a face contact: the motion enters from the front,
  /// d·n < 0); contacts that do not approach (d·normal ≥ 0, e.g. sliding) are ignored.
  /// Ties broken by lowest triangle index. A negative or NaN radius hits nothing.
  [[nodiscard]] SweepHit first_hit_swept_sphere(const TriangleMeshView& mesh, const Vec3& a, const Vec3& b,
                                                double radius, TouchableFace face = TouchableFace::kFront) const;

  /// Indices of triangles whose box comes within `radius` of `center`, written to `out`
  /// (up to out.size()); returns how many there are in all (may exceed out.size()). With
  /// several triangles per leaf, all triangles of a leaf whose box is near are returned; with
  /// use_bound_tree = false (one leaf) that is every triangle when the mesh's box is near.
  std::size_t triangles_near(const Vec3& center, double radius, std::span<std::int32_t> out) const;

  /// Calls visit(triangle) for the triangles of every leaf whose box overlaps the box
  /// [lo − inflate, hi + inflate] (boundaries inclusive), depth first, left child first: the
  /// order depends only on the tree. Allocation-free (fixed stack). With use_bound_tree =
  /// false (one leaf) every triangle is visited when the mesh's box overlaps.
  template <class Visit>
  void visit_overlapping(const Vec3& lo, const Vec3& hi, double inflate, Visit&& visit) const {
    if (nodes_.empty()) return;
    const Vec3 qlo = lo - Vec3::Constant(inflate);
    const Vec3 qhi = hi + Vec3::Constant(inflate);
    // NaN fails both comparisons, so a NaN query box overlaps nothing.
    const auto overlaps = [&](const Node& n) {
      return (n.lo.array() <= qhi.array()).all() && (qlo.array() <= n.hi.array()).all();
    };
    std::int32_t stack[kStackSize];
    int top = 0;
    if (!overlaps(nodes_[0])) return;
    stack[top++] = 0;
    while (top > 0) {
      const Node& node = nodes_[static_cast<std::size_t>(stack[--top])];
      if (node.count > 0) {
        for (std::int32_t i = node.first; i < node.first + node.count; ++i) {
          visit(triangle_order_[static_cast<std::size_t>(i)]);
        }
        continue;
      }
      // Right pushed first so the left subtree is visited first. The stack holds at most one
      // pending right sibling per level: top <= depth_ + 1 < kStackSize.
      if (overlaps(nodes_[static_cast<std::size_t>(node.first) + 1])) stack[top++] = node.first + 1;
      if (overlaps(nodes_[static_cast<std::size_t>(node.first)])) stack[top++] = node.first;
    }
  }

  [[nodiscard]] const AabbTreeOptions& options() const { return options_; }
  [[nodiscard]] std::size_t node_count() const { return nodes_.size(); }
  [[nodiscard]] int depth() const { return depth_; }
  /// The boxes (lo, hi) of the nodes down to `max_depth` (0 = the root), for drawing.
  [[nodiscard]] std::vector<std::pair<Vec3, Vec3>> boxes(int max_depth) const;

 private:
  // Nodes are stored parents before children, so a reverse loop over nodes_ visits children
  // first (refit). An inner node's children are consecutive: `first` and `first + 1`.
  struct Node {
    Vec3 lo{Vec3::Zero()};  // box, padded by a relative 1e-10 of its coordinates, m
    Vec3 hi{Vec3::Zero()};
    std::int32_t first{0};  // leaf: first index into triangle_order_; inner: left child
    std::int32_t count{0};  // leaf: triangle count (>= 1); inner: 0
  };
  // Entries of the fixed traversal stack. A median split gives depth <= ceil(log2 F) + 1
  // <= 33 for any int32 triangle count, and nearest-first traversal keeps at most one
  // pending sibling per level, so 64 entries always suffice.
  static constexpr int kStackSize = 64;

  // Recomputes every box bottom-up from `mesh`; returns the summed box surface area, m².
  double fit_boxes(const TriangleMeshView& mesh);
  // Calls visit(triangle) for the triangles of every leaf whose box lies within
  // sqrt(bound_d2) of p, nearest box first; re-reads `bound_d2` (which visit may shrink).
  template <class Visit>
  void visit_near(const Vec3& p, const double& bound_d2, Visit&& visit) const;
  // Calls visit(triangle) for the triangles of every leaf whose box, inflated by `inflate`,
  // the segment a → a + d enters at t <= best_t, nearest entry first; re-reads `best_t`.
  template <class Visit>
  void visit_along(const Vec3& a, const Vec3& d, double inflate, const double& best_t, Visit&& visit) const;

  std::vector<Node> nodes_;
  std::vector<std::int32_t> triangle_order_;
  AabbTreeOptions options_;
  double build_area_{0.0};
  int depth_{0};
};

}  // namespace hof::collision
