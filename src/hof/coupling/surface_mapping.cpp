#include "hof/coupling/surface_mapping.h"

#include <fmt/format.h>

#include <cmath>
#include <limits>

#include "hof/mesh/tet_geometry.h"

namespace hof::coupling {

Expected<SurfaceMapping> SurfaceMapping::by_index(std::span<const Vec3> volume_nodes, std::span<const Vec3> surface_vertices,
                                                  std::span<const mesh::NodeIndex> surface_to_volume, double tolerance_m) {
  if (surface_to_volume.size() != surface_vertices.size()) {
    return make_error(ErrorCode::kInvalidMesh, fmt::format("surface mapping: {} surface vertices but {} volume indices",
                                                           surface_vertices.size(), surface_to_volume.size()));
  }
  SurfaceMapping m;
  m.identity_ = true;
  for (std::size_t i = 0; i < surface_vertices.size(); ++i) {
    const mesh::NodeIndex n = surface_to_volume[i];
    if (n < 0 || static_cast<std::size_t>(n) >= volume_nodes.size()) {
      return make_error(ErrorCode::kInvalidMesh, fmt::format("surface mapping: vertex {} maps to node {} of {}", i, n,
                                                             volume_nodes.size()));
    }
    const double gap = (volume_nodes[n] - surface_vertices[i]).norm();
    if (!(gap <= tolerance_m)) {
      return make_error(ErrorCode::kInvalidMesh,
                        fmt::format("surface mapping by index: surface vertex {} is {:.3g} m from volume node {} — the "
                                    "surface does not share the volume's nodes; use a barycentric mapping",
                                    i, gap, n));
    }
    m.nodes_.push_back({n, n, n, n});
    m.weights_.push_back({1.0, 0.0, 0.0, 0.0});
  }
  return m;
}

Expected<SurfaceMapping> SurfaceMapping::barycentric(std::span<const Vec3> volume_nodes, std::span<const mesh::Tet> tets,
                                                     std::span<const Vec3> surface_vertices) {
  if (tets.empty()) return make_error(ErrorCode::kInvalidMesh, "barycentric mapping: the volume has no tetrahedra");
  SurfaceMapping m;
  m.identity_ = false;
  // Barycentric weights of p in tet t: solve [b−a c−a d−a] w' = p − a.
  auto weights_in = [&](const mesh::Tet& t, const Vec3& p, std::array<double, 4>& w) {
    Mat3 d;
    d.col(0) = volume_nodes[t[1]] - volume_nodes[t[0]];
    d.col(1) = volume_nodes[t[2]] - volume_nodes[t[0]];
    d.col(2) = volume_nodes[t[3]] - volume_nodes[t[0]];
    const Vec3 x = d.fullPivLu().solve(p - volume_nodes[t[0]]);
    w = {1.0 - x.sum(), x[0], x[1], x[2]};
    return x.allFinite();
  };
  for (std::size_t v = 0; v < surface_vertices.size(); ++v) {
    const Vec3& p = surface_vertices[v];
    // Containing tet (smallest negative weight ≥ −tol), else the one with the least-negative
    // minimum weight (the nearest in barycentric terms).
    std::size_t best = 0;
    double best_score = -std::numeric_limits<double>::infinity();
    std::array<double, 4> best_w{};
    for (std::size_t t = 0; t < tets.size(); ++t) {
      std::array<double, 4> w{};
      if (!weights_in(tets[t], p, w)) continue;
      const double score = std::min(std::min(w[0], w[1]), std::min(w[2], w[3]));
      if (score > best_score) {
        best_score = score;
        best = t;
        best_w = w;
        if (score >= 0.0) break;
      }
    }
    if (!std::isfinite(best_score)) {
      return make_error(ErrorCode::kInvalidMesh, fmt::format("barycentric mapping: surface vertex {} has no tetrahedron", v));
    }
    m.nodes_.push_back({tets[best][0], tets[best][1], tets[best][2], tets[best][3]});
    m.weights_.push_back(best_w);
  }
  return m;
}

void SurfaceMapping::apply(std::span<const double> volume, std::span<Vec3> surface) const {
  for (std::size_t v = 0; v < nodes_.size(); ++v) {
    Vec3 sum = Vec3::Zero();
    const int count = identity_ ? 1 : 4;
    for (int k = 0; k < count; ++k) {
      const std::size_t n = 3 * static_cast<std::size_t>(nodes_[v][k]);
      sum += weights_[v][k] * Vec3(volume[n], volume[n + 1], volume[n + 2]);
    }
    surface[v] = sum;
  }
}

void SurfaceMapping::add_vertex_force(std::int32_t surface_vertex, const Vec3& force, std::span<double> volume_forces) const {
  const auto& nodes = nodes_[static_cast<std::size_t>(surface_vertex)];
  const auto& weights = weights_[static_cast<std::size_t>(surface_vertex)];
  const int count = identity_ ? 1 : 4;
  for (int k = 0; k < count; ++k) {
    const std::size_t n = 3 * static_cast<std::size_t>(nodes[k]);
    for (int a = 0; a < 3; ++a) volume_forces[n + static_cast<std::size_t>(a)] += weights[k] * force[a];
  }
}

std::size_t SurfaceMapping::point_weights(std::span<const std::int32_t> surface_vertices,
                                         std::span<const double> surface_weights, std::span<std::int32_t> nodes,
                                         std::span<double> weights) const {
  std::size_t count = 0;
  for (std::size_t v = 0; v < surface_vertices.size(); ++v) {
    const auto& n = nodes_[static_cast<std::size_t>(surface_vertices[v])];
    const auto& w = weights_[static_cast<std::size_t>(surface_vertices[v])];
    for (int k = 0; k < (identity_ ? 1 : 4) && count < nodes.size(); ++k) {
      nodes[count] = n[k];
      weights[count] = surface_weights[v] * w[k];
      ++count;
    }
  }
  return count;
}

std::int32_t SurfaceMapping::dominant_node(std::int32_t surface_vertex) const {
  const auto& w = weights_[static_cast<std::size_t>(surface_vertex)];
  int best = 0;
  for (int k = 1; k < (identity_ ? 1 : 4); ++k) {
    if (w[k] > w[best]) best = k;
  }
  return nodes_[static_cast<std::size_t>(surface_vertex)][best];
}

}  // namespace hof::coupling
