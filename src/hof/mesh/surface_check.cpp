#include "hof/mesh/surface_check.h"

#include <algorithm>
#include <numeric>

namespace hof::mesh {

namespace {

class UnionFind {
 public:
  explicit UnionFind(std::size_t n) : parent_(n) { std::iota(parent_.begin(), parent_.end(), 0); }
  std::size_t find(std::size_t x) {
    while (parent_[x] != x) {
      parent_[x] = parent_[parent_[x]];
      x = parent_[x];
    }
    return x;
  }
  void unite(std::size_t a, std::size_t b) {
    a = find(a);
    b = find(b);
    if (a != b) parent_[std::max(a, b)] = std::min(a, b);
  }

 private:
  std::vector<std::size_t> parent_;
};

struct HalfEdge {
  NodeIndex lo, hi;  // undirected key
  bool forward;      // traversed lo→hi by its triangle
  std::int32_t tri;
  std::int8_t corner;  // local index of `lo`'s corner... unused for orientation
};

}  // namespace

SurfaceCheck check_surface(const std::vector<Vec3>& vertices, const std::vector<Tri>& triangles) {
  SurfaceCheck out;
  out.triangles = static_cast<std::int64_t>(triangles.size());
  const std::size_t nf = triangles.size();

  std::vector<HalfEdge> half_edges;
  half_edges.reserve(nf * 3);
  std::vector<char> used(vertices.size(), 0);
  for (std::size_t t = 0; t < nf; ++t) {
    const Tri& tri = triangles[t];
    const Vec3& a = vertices[tri[0]];
    const Vec3& b = vertices[tri[1]];
    const Vec3& c = vertices[tri[2]];
    const Vec3 area_vector = 0.5 * (b - a).cross(c - a);
    out.area_m2 += area_vector.norm();
    // Divergence theorem: V = Σ a·((b-a)×(c-a)) / 6 over outward-wound triangles.
    out.signed_volume_m3 += a.dot(b.cross(c)) / 6.0;
    if (tri[0] == tri[1] || tri[1] == tri[2] || tri[0] == tri[2] || !(area_vector.norm() > 0.0)) {
      ++out.degenerate_triangles;
    }
    for (int i = 0; i < 3; ++i) {
      const NodeIndex u = tri[i], v = tri[(i + 1) % 3];
      used[u] = 1;
      half_edges.push_back(
          {std::min(u, v), std::max(u, v), u < v, static_cast<std::int32_t>(t), static_cast<std::int8_t>(i)});
    }
  }
  out.vertices_used = std::count(used.begin(), used.end(), 1);

  std::sort(half_edges.begin(), half_edges.end(), [](const HalfEdge& x, const HalfEdge& y) {
    return x.lo != y.lo ? x.lo < y.lo : (x.hi != y.hi ? x.hi < y.hi : x.tri < y.tri);
  });

  // Corners (triangle, vertex) are joined across manifold edges; a vertex whose corners end
  // up in more than one group is a pinch point (several fans meeting at one vertex).
  UnionFind corners(nf * 3);
  UnionFind pieces(vertices.size());
  auto corner_of = [&](std::int32_t t, NodeIndex v) {
    const Tri& tri = triangles[t];
    const std::size_t local = tri[0] == v ? 0 : (tri[1] == v ? 1 : 2);
    return static_cast<std::size_t>(t) * 3 + local;
  };
  auto note_bad = [&](NodeIndex a, NodeIndex b) {
    if (!out.first_bad_edge) out.first_bad_edge = std::array<NodeIndex, 2>{a, b};
  };
  for (std::size_t i = 0; i < half_edges.size();) {
    std::size_t j = i + 1;
    while (j < half_edges.size() && half_edges[j].lo == half_edges[i].lo && half_edges[j].hi == half_edges[i].hi) {
      ++j;
    }
    const HalfEdge& e = half_edges[i];
    ++out.edges;
    pieces.unite(static_cast<std::size_t>(e.lo), static_cast<std::size_t>(e.hi));
    const std::size_t count = j - i;
    if (count == 1) {
      ++out.boundary_edges;
      note_bad(e.lo, e.hi);
    } else if (count > 2) {
      ++out.non_manifold_edges;
      note_bad(e.lo, e.hi);
    } else {
      const HalfEdge& f = half_edges[i + 1];
      if (e.forward == f.forward) {
        ++out.misoriented_edges;
        note_bad(e.lo, e.hi);
      }
      if (e.tri != f.tri) {
        corners.unite(corner_of(e.tri, e.lo), corner_of(f.tri, e.lo));
        corners.unite(corner_of(e.tri, e.hi), corner_of(f.tri, e.hi));
      }
    }
    i = j;
  }

  std::vector<std::int64_t> first_group(vertices.size(), -1);
  std::vector<char> pinched(vertices.size(), 0);
  for (std::size_t t = 0; t < nf; ++t) {
    for (std::size_t k = 0; k < 3; ++k) {
      const NodeIndex v = triangles[t][k];
      const auto group = static_cast<std::int64_t>(corners.find(t * 3 + k));
      if (first_group[v] < 0) {
        first_group[v] = group;
      } else if (first_group[v] != group) {
        pinched[v] = 1;
      }
    }
  }
  out.non_manifold_vertices = std::count(pinched.begin(), pinched.end(), 1);

  for (std::size_t v = 0; v < vertices.size(); ++v) {
    if (used[v] && pieces.find(v) == v) ++out.components;
  }
  out.euler_characteristic = out.vertices_used - out.edges + out.triangles;
  return out;
}

}  // namespace hof::mesh
