#include "hof/collision/aabb_tree.h"

#include <algorithm>
#include <cmath>
#include <limits>
#include <numeric>
#include <utility>

#include "hof/collision/triangle_queries.h"
#include "hof/core/assert.h"

namespace hof::collision {
namespace {

constexpr double kInf = std::numeric_limits<double>::infinity();

// Boxes are padded by this fraction of their largest coordinate magnitude, far above the
// rounding of the per-triangle tests (~1e-16 relative) and far below any feature size: a
// point the exact tests put on a triangle is always inside the triangle's box, so pruning
// never changes a result and the tree agrees with brute force.
constexpr double kRelativePad = 1e-10;

struct StackEntry {
  std::int32_t node;
  double key;  // squared box distance or box entry time: the pruning key
};

const Vec3& corner(const TriangleMeshView& mesh, std::int32_t triangle, int k) {
  return mesh.vertices[mesh.triangles[triangle][k]];
}

double surface_area(const Vec3& lo, const Vec3& hi) {
  const Vec3 e = (hi - lo).cwiseMax(0.0);
  return 2.0 * (e.x() * e.y() + e.y() * e.z() + e.z() * e.x());
}

// Whether (value, triangle) beats the best so far: smaller value, ties to the lower index.
// The same rule in the tree and in brute force makes both return the same triangle.
bool better(double value, std::int32_t triangle, double best_value, std::int32_t best_triangle) {
  return value < best_value || (value == best_value && (best_triangle < 0 || triangle < best_triangle));
}

}  // namespace

AabbTree AabbTree::build(const TriangleMeshView& mesh, const AabbTreeOptions& options) {
  AabbTree tree;
  tree.options_ = options;
  const std::size_t f = mesh.triangles.size();
  if (f == 0) return tree;
  HOF_CHECK(f <= static_cast<std::size_t>(std::numeric_limits<std::int32_t>::max()),
            "AabbTree: more triangles than int32 indices");
  const auto count = static_cast<std::int32_t>(f);
  const std::int32_t leaf_size =
      options.use_bound_tree && options.max_triangles_in_leaf >= 1 ? options.max_triangles_in_leaf : count;

  std::vector<Vec3> centroids(f);
  for (std::int32_t t = 0; t < count; ++t) {
    centroids[t] = (corner(mesh, t, 0) + corner(mesh, t, 1) + corner(mesh, t, 2)) / 3.0;
  }
  std::vector<std::int32_t>& order = tree.triangle_order_;
  order.resize(f);
  std::iota(order.begin(), order.end(), 0);

  // Top-down, with an explicit work list: a node covering order[begin, end) either becomes a
  // leaf or is split at the median centroid along the longest axis of its centroids' box.
  // Both children are appended together, after their parent (reverse order = children first).
  // Median splits halve the count, so depth <= ceil(log2(F / leaf_size)) + 1.
  struct Work {
    std::int32_t node, begin, end, depth;
  };
  std::vector<Work> work;
  tree.nodes_.reserve(2 * (f / static_cast<std::size_t>(leaf_size)) + 1);
  tree.nodes_.push_back(Node{});
  work.push_back({0, 0, count, 1});
  while (!work.empty()) {
    const Work w = work.back();
    work.pop_back();
    tree.depth_ = std::max(tree.depth_, static_cast<int>(w.depth));
    const std::int32_t n = w.end - w.begin;
    if (n <= leaf_size) {
      tree.nodes_[w.node].first = w.begin;
      tree.nodes_[w.node].count = n;
      continue;
    }
    Vec3 lo = Vec3::Constant(kInf);
    Vec3 hi = Vec3::Constant(-kInf);
    for (std::int32_t k = w.begin; k < w.end; ++k) {
      lo = lo.cwiseMin(centroids[order[k]]);
      hi = hi.cwiseMax(centroids[order[k]]);
    }
    const Vec3 extent = hi - lo;
    int axis = 0;
    if (extent[1] > extent[axis]) axis = 1;
    if (extent[2] > extent[axis]) axis = 2;
    // A strict total order (coordinate, then index; NaN last) makes the halves unique.
    const auto key = [&](std::int32_t t) {
      const double c = centroids[t][axis];
      return std::isnan(c) ? kInf : c;
    };
    const std::int32_t mid = w.begin + n / 2;
    std::nth_element(order.begin() + w.begin, order.begin() + mid, order.begin() + w.end,
                     [&](std::int32_t i, std::int32_t j) {
                       const double ki = key(i);
                       const double kj = key(j);
                       return ki < kj || (ki == kj && i < j);
                     });
    const auto left = static_cast<std::int32_t>(tree.nodes_.size());
    tree.nodes_.push_back(Node{});
    tree.nodes_.push_back(Node{});
    tree.nodes_[w.node].first = left;
    tree.nodes_[w.node].count = 0;
    work.push_back({left + 1, mid, w.end, w.depth + 1});
    work.push_back({left, w.begin, mid, w.depth + 1});  // left first: depth-first layout
  }
  // The traversals' fixed stacks hold a path's far children: the depth bounds them.
  HOF_CHECK(tree.depth_ < kStackSize, "AabbTree deeper than the traversal stack");
  tree.build_area_ = tree.fit_boxes(mesh);
  return tree;
}

double AabbTree::fit_boxes(const TriangleMeshView& mesh) {
  double area = 0.0;
  for (std::size_t k = nodes_.size(); k-- > 0;) {
    Node& node = nodes_[k];
    if (node.count > 0) {
      Vec3 lo = Vec3::Constant(kInf);
      Vec3 hi = Vec3::Constant(-kInf);
      for (std::int32_t i = node.first; i < node.first + node.count; ++i) {
        const Vec3& a = corner(mesh, triangle_order_[i], 0);
        const Vec3& b = corner(mesh, triangle_order_[i], 1);
        const Vec3& c = corner(mesh, triangle_order_[i], 2);
        // One finiteness test per triangle (the refit runs after every simulation step):
        // the sum of the corners is finite only when every coordinate is.
        if ((a + b + c).allFinite()) {
          lo = lo.cwiseMin(a).cwiseMin(b).cwiseMin(c);
          hi = hi.cwiseMax(a).cwiseMax(b).cwiseMax(c);
          continue;
        }
        for (const Vec3* p : {&a, &b, &c}) {
          // A non-finite vertex makes its triangle degenerate (never hit): leave it out
          // rather than let a NaN box hide the other triangles.
          if (!p->allFinite()) continue;
          lo = lo.cwiseMin(*p);
          hi = hi.cwiseMax(*p);
        }
      }
      if (lo.allFinite() && hi.allFinite()) {  // else the box stays empty (lo > hi)
        const double pad = kRelativePad * std::fmax(lo.cwiseAbs().maxCoeff(), hi.cwiseAbs().maxCoeff());
        lo -= Vec3::Constant(pad);
        hi += Vec3::Constant(pad);
      }
      node.lo = lo;
      node.hi = hi;
    } else {
      const Node& l = nodes_[node.first];
      const Node& r = nodes_[node.first + 1];
      node.lo = l.lo.cwiseMin(r.lo);
      node.hi = l.hi.cwiseMax(r.hi);
    }
    area += surface_area(node.lo, node.hi);
  }
  return area;
}

bool AabbTree::refit(const TriangleMeshView& mesh) {
  HOF_CHECK(mesh.triangles.size() == triangle_order_.size(),
            "AabbTree::refit() with a different triangle count than build()");
  const double area = fit_boxes(mesh);
  return area > options_.rebuild_area_ratio * build_area_;
}

// Depth-first with an explicit stack, nearer child first; a popped entry is dropped when the
// bound has shrunk below its key since it was pushed (branch and bound).
template <class Visit>
void AabbTree::visit_near(const Vec3& p, const double& bound_d2, Visit&& visit) const {
  if (nodes_.empty()) return;
  StackEntry stack[kStackSize];
  int top = 0;
  const double root_d2 = detail::box_distance_squared(p, nodes_[0].lo, nodes_[0].hi);
  if (!(root_d2 <= bound_d2)) return;
  stack[top++] = {0, root_d2};
  while (top > 0) {
    const StackEntry entry = stack[--top];
    if (entry.key > bound_d2) continue;
    const Node& node = nodes_[entry.node];
    if (node.count > 0) {
      for (std::int32_t i = node.first; i < node.first + node.count; ++i) visit(triangle_order_[i]);
      continue;
    }
    std::int32_t near_child = node.first;
    std::int32_t far_child = node.first + 1;
    double near_d2 = detail::box_distance_squared(p, nodes_[near_child].lo, nodes_[near_child].hi);
    double far_d2 = detail::box_distance_squared(p, nodes_[far_child].lo, nodes_[far_child].hi);
    if (far_d2 < near_d2) {
      std::swap(near_child, far_child);
      std::swap(near_d2, far_d2);
    }
    // Each level adds at most one pending entry: top <= depth_ + 1 < kStackSize.
    if (far_d2 <= bound_d2) stack[top++] = {far_child, far_d2};
    if (near_d2 <= bound_d2) stack[top++] = {near_child, near_d2};
  }
}

// The same traversal keyed by the time the motion enters each (inflated) box.
template <class Visit>
void AabbTree::visit_along(const Vec3& a, const Vec3& d, double inflate, const double& best_t, Visit&& visit) const {
  if (nodes_.empty()) return;
  const detail::SlabSegment segment(a, d);
  StackEntry stack[kStackSize];
  int top = 0;
  double t_root = 0.0;
  if (!detail::slab_entry(segment, nodes_[0].lo, nodes_[0].hi, inflate, best_t, t_root)) return;
  stack[top++] = {0, t_root};
  while (top > 0) {
    const StackEntry entry = stack[--top];
    if (entry.key > best_t) continue;
    const Node& node = nodes_[entry.node];
    if (node.count > 0) {
      for (std::int32_t i = node.first; i < node.first + node.count; ++i) visit(triangle_order_[i]);
      continue;
    }
    std::int32_t near_child = node.first;
    std::int32_t far_child = node.first + 1;
    double near_t = 0.0;
    double far_t = 0.0;
    const bool near_hit =
        detail::slab_entry(segment, nodes_[near_child].lo, nodes_[near_child].hi, inflate, best_t, near_t);
    const bool far_hit =
        detail::slab_entry(segment, nodes_[far_child].lo, nodes_[far_child].hi, inflate, best_t, far_t);
    if (near_hit && far_hit) {
      if (far_t < near_t) {
        std::swap(near_child, far_child);
        std::swap(near_t, far_t);
      }
      stack[top++] = {far_child, far_t};
      stack[top++] = {near_child, near_t};
    } else if (near_hit) {
      stack[top++] = {near_child, near_t};
    } else if (far_hit) {
      stack[top++] = {far_child, far_t};
    }
  }
}

ClosestPoint AabbTree::closest_point(const TriangleMeshView& mesh, const Vec3& p, double max_distance,
                                     TouchableFace face, std::span<const std::int32_t> skip) const {
  ClosestPoint best;
  if (!(max_distance >= 0.0)) return best;
  double best_d2 = max_distance * max_distance;  // inclusive: `better` accepts equality
  const auto visit = [&](std::int32_t triangle) {
    const Vec3& p0 = corner(mesh, triangle, 0);
    const Vec3& p1 = corner(mesh, triangle, 1);
    const Vec3& p2 = corner(mesh, triangle, 2);
    Vec3 weights;
    const Vec3 point = detail::closest_point_on_triangle(p, p0, p1, p2, weights);
    const double d2 = (p - point).squaredNorm();
    if (!better(d2, triangle, best_d2, best.triangle) || !detail::closest_point_counts(p, p0, p1, p2, face) ||
        (!skip.empty() && std::binary_search(skip.begin(), skip.end(), triangle))) {
      return;
    }
    best_d2 = d2;
    best.triangle = triangle;
    best.point = point;
    best.barycentric = weights;
  };
  if (options_.use_bound_tree) {
    visit_near(p, best_d2, visit);
  } else {
    for (std::size_t t = 0; t < mesh.triangles.size(); ++t) visit(static_cast<std::int32_t>(t));
  }
  if (best.triangle >= 0) best.distance = std::sqrt(best_d2);
  return best;
}

namespace {

void store(const detail::TriangleContact& c, std::int32_t triangle, SweepHit& hit) {
  hit.triangle = triangle;
  hit.t = c.t;
  hit.point = c.point;
  hit.barycentric = c.barycentric;
  hit.normal = c.normal;
  hit.front = c.front;
}

}  // namespace

SweepHit AabbTree::first_hit_segment(const TriangleMeshView& mesh, const Vec3& a, const Vec3& b,
                                     TouchableFace face) const {
  const Vec3 d = b - a;
  SweepHit best;
  double best_t = 1.0;  // inclusive: `better` accepts t = 1
  const auto visit = [&](std::int32_t triangle) {
    detail::TriangleContact c;
    if (!detail::intersect_segment_triangle(a, d, corner(mesh, triangle, 0), corner(mesh, triangle, 1),
                                            corner(mesh, triangle, 2), face, c) ||
        !better(c.t, triangle, best_t, best.triangle)) {
      return;
    }
    best_t = c.t;
    store(c, triangle, best);
  };
  if (options_.use_bound_tree) {
    visit_along(a, d, 0.0, best_t, visit);
  } else {
    for (std::size_t t = 0; t < mesh.triangles.size(); ++t) visit(static_cast<std::int32_t>(t));
  }
  return best;
}

SweepHit AabbTree::first_hit_swept_sphere(const TriangleMeshView& mesh, const Vec3& a, const Vec3& b, double radius,
                                          TouchableFace face) const {
  SweepHit best;
  if (!(radius >= 0.0)) return best;
  const Vec3 d = b - a;
  double best_t = 1.0;
  const auto visit = [&](std::int32_t triangle) {
    detail::TriangleContact c;
    if (!detail::sweep_sphere_triangle(a, d, radius, corner(mesh, triangle, 0), corner(mesh, triangle, 1),
                                       corner(mesh, triangle, 2), face, c) ||
        !better(c.t, triangle, best_t, best.triangle)) {
      return;
    }
    best_t = c.t;
    store(c, triangle, best);
  };
  // A box inflated by the radius contains the box's Minkowski sum with the sphere.
  if (options_.use_bound_tree) {
    visit_along(a, d, radius, best_t, visit);
  } else {
    for (std::size_t t = 0; t < mesh.triangles.size(); ++t) visit(static_cast<std::int32_t>(t));
  }
  return best;
}

std::size_t AabbTree::triangles_near(const Vec3& center, double radius, std::span<std::int32_t> out) const {
  if (!(radius >= 0.0)) return 0;
  const double bound_d2 = radius * radius;
  std::size_t n = 0;
  visit_near(center, bound_d2, [&](std::int32_t triangle) {
    if (n < out.size()) out[n] = triangle;
    ++n;
  });
  return n;
}

std::vector<std::pair<Vec3, Vec3>> AabbTree::boxes(int max_depth) const {
  std::vector<std::pair<Vec3, Vec3>> out;
  if (nodes_.empty()) return out;
  std::vector<std::pair<std::int32_t, int>> stack{{0, 0}};
  while (!stack.empty()) {
    const auto [index, level] = stack.back();
    stack.pop_back();
    const Node& n = nodes_[static_cast<std::size_t>(index)];
    out.emplace_back(n.lo, n.hi);
    if (n.count == 0 && level < max_depth) {
      stack.emplace_back(n.first, level + 1);
      stack.emplace_back(n.first + 1, level + 1);
    }
  }
  return out;
}

}  // namespace hof::collision
