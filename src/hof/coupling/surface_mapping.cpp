#include "hof/coupling/surface_mapping.h"

#include <fmt/format.h>

#include <algorithm>
#include <cmath>
#include <limits>
#include <utility>

#include "hof/collision/aabb_tree.h"
#include "hof/mesh/tet_geometry.h"

namespace hof::coupling {

Expected<SurfaceMapping> SurfaceMapping::by_index(std::span<const Vec3> volume_nodes,
                                                  std::span<const Vec3> surface_vertices,
                                                  std::span<const mesh::NodeIndex> surface_to_volume,
                                                  double tolerance_m) {
  if (surface_to_volume.size() != surface_vertices.size()) {
    return make_error(ErrorCode::kInvalidMesh, fmt::format("surface mapping: {} surface vertices but {} volume indices",
                                                           surface_vertices.size(), surface_to_volume.size()));
  }
  SurfaceMapping m;
  m.identity_ = true;
  m.arity_ = 1;
  for (std::size_t i = 0; i < surface_vertices.size(); ++i) {
    const mesh::NodeIndex n = surface_to_volume[i];
    if (n < 0 || static_cast<std::size_t>(n) >= volume_nodes.size()) {
      return make_error(ErrorCode::kInvalidMesh,
                        fmt::format("surface mapping: vertex {} maps to node {} of {}", i, n, volume_nodes.size()));
    }
    const double gap = (volume_nodes[n] - surface_vertices[i]).norm();
    if (!(gap <= tolerance_m)) {
      return make_error(ErrorCode::kInvalidMesh,
                        fmt::format("surface mapping by index: surface vertex {} is {:.3g} m from volume node {} — the "
                                    "surface does not share the volume's nodes; use a barycentric mapping",
                                    i, gap, n));
    }
    std::array<std::int32_t, kMaxNodesPerVertex> nodes{};
    nodes.fill(n);
    m.nodes_.push_back(nodes);
    m.weights_.push_back({1.0});
  }
  return m;
}

Expected<SurfaceMapping> SurfaceMapping::barycentric(std::span<const Vec3> volume_nodes,
                                                     std::span<const mesh::Tet> tets,
                                                     std::span<const Vec3> surface_vertices) {
  if (tets.empty()) return make_error(ErrorCode::kInvalidMesh, "barycentric mapping: the volume has no tetrahedra");
  SurfaceMapping m;
  m.identity_ = false;
  m.arity_ = 4;
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
      return make_error(ErrorCode::kInvalidMesh,
                        fmt::format("barycentric mapping: surface vertex {} has no tetrahedron", v));
    }
    m.nodes_.push_back({tets[best][0], tets[best][1], tets[best][2], tets[best][3]});
    m.weights_.push_back({best_w[0], best_w[1], best_w[2], best_w[3]});
  }
  return m;
}

Expected<SurfaceMapping> SurfaceMapping::onto_triangles(std::span<const Vec3> volume_nodes,
                                                        std::span<const mesh::Tri> triangles,
                                                        std::span<const Vec3> surface_vertices) {
  if (triangles.empty()) {
    return make_error(ErrorCode::kInvalidMesh,
                      "barycentric mapping: the body has neither tetrahedra nor triangles to map onto");
  }
  for (std::size_t t = 0; t < triangles.size(); ++t)
    for (mesh::NodeIndex i : triangles[t])
      if (i < 0 || static_cast<std::size_t>(i) >= volume_nodes.size())
        return make_error(ErrorCode::kInvalidMesh, fmt::format("barycentric mapping: triangle {} uses node {} of {}", t,
                                                               i, volume_nodes.size()));
  const collision::TriangleMeshView view{volume_nodes, triangles};
  const collision::AabbTree tree = collision::AabbTree::build(view);
  SurfaceMapping m;
  m.identity_ = false;
  m.arity_ = 3;
  m.nodes_.reserve(surface_vertices.size());
  m.weights_.reserve(surface_vertices.size());
  for (std::size_t v = 0; v < surface_vertices.size(); ++v) {
    const collision::ClosestPoint c =
        tree.closest_point(view, surface_vertices[v], std::numeric_limits<double>::infinity());
    if (c.triangle < 0 || !c.barycentric.allFinite()) {
      return make_error(ErrorCode::kInvalidMesh,
                        fmt::format("barycentric mapping: surface vertex {} has no triangle", v));
    }
    const mesh::Tri& tri = triangles[static_cast<std::size_t>(c.triangle)];
    std::array<std::int32_t, kMaxNodesPerVertex> nodes{};
    std::array<double, kMaxNodesPerVertex> weights{};
    for (int k = 0; k < 3; ++k) {
      nodes[static_cast<std::size_t>(k)] = tri[static_cast<std::size_t>(k)];
      weights[static_cast<std::size_t>(k)] = c.barycentric[k];
    }
    m.nodes_.push_back(nodes);
    m.weights_.push_back(weights);
  }
  return m;
}

namespace {

// Local coordinates ξ of p in hexahedron `hex` (p = Σ N_c(ξ) x_c), by Newton's method on the
// trilinear map from ξ = 0: one step for a parallelepiped, a few for a distorted cell. ξ is
// kept within [−4, 4]³ so that a far point cannot throw the iteration off. Non-finite when the
// hexahedron is flat.
Vec3 hex_local_coordinates(std::span<const Vec3> nodes, const mesh::Hex& hex, const Vec3& p) {
  Vec3 xi = Vec3::Zero();
  for (int iteration = 0; iteration < 30; ++iteration) {
    const auto n = mesh::hex_shape_functions(xi);
    const Eigen::Matrix<double, 3, 8> d = mesh::hex_shape_derivatives(xi);
    Vec3 x = Vec3::Zero();
    Mat3 jacobian = Mat3::Zero();
    for (int c = 0; c < 8; ++c) {
      const Vec3& corner = nodes[static_cast<std::size_t>(hex[c])];
      x += n[c] * corner;
      jacobian += corner * d.col(c).transpose();
    }
    const Vec3 step = jacobian.fullPivLu().solve(x - p);
    if (!step.allFinite()) return Vec3::Constant(std::numeric_limits<double>::quiet_NaN());
    xi = (xi - step).cwiseMax(-4.0).cwiseMin(4.0);
    if (step.squaredNorm() < 1e-28) break;
  }
  return xi;
}

}  // namespace

Expected<SurfaceMapping> SurfaceMapping::trilinear(std::span<const Vec3> volume_nodes, std::span<const mesh::Hex> hexes,
                                                   std::span<const Vec3> surface_vertices) {
  if (hexes.empty()) return make_error(ErrorCode::kInvalidMesh, "trilinear mapping: the volume has no hexahedra");
  // Each hexahedron's bounding box, and a uniform bin grid over them (about one hexahedron
  // per bin) so that a vertex only tries the few whose box holds it.
  std::vector<std::pair<Vec3, Vec3>> boxes(hexes.size());
  Vec3 lo = Vec3::Constant(std::numeric_limits<double>::infinity()), hi = -lo, extent = Vec3::Zero();
  for (std::size_t h = 0; h < hexes.size(); ++h) {
    Vec3 bmin = Vec3::Constant(std::numeric_limits<double>::infinity()), bmax = -bmin;
    for (mesh::NodeIndex i : hexes[h]) {
      if (i < 0 || static_cast<std::size_t>(i) >= volume_nodes.size()) {
        return make_error(ErrorCode::kInvalidMesh, fmt::format("trilinear mapping: hexahedron {} uses node {} of {}", h,
                                                               i, volume_nodes.size()));
      }
      bmin = bmin.cwiseMin(volume_nodes[static_cast<std::size_t>(i)]);
      bmax = bmax.cwiseMax(volume_nodes[static_cast<std::size_t>(i)]);
    }
    boxes[h] = {bmin, bmax};
    lo = lo.cwiseMin(bmin);
    hi = hi.cwiseMax(bmax);
    extent += (bmax - bmin) / static_cast<double>(hexes.size());
  }
  std::array<int, 3> dims{};
  Vec3 bin_size;
  for (int a = 0; a < 3; ++a) {
    bin_size[a] = std::max(extent[a], 1e-12 * std::max(1.0, (hi - lo).maxCoeff()));
    dims[a] = std::clamp(static_cast<int>(std::ceil((hi[a] - lo[a]) / bin_size[a])), 1, 128);
    bin_size[a] = std::max((hi[a] - lo[a]) / dims[a], bin_size[a] * 1e-3);
  }
  const auto bin_of = [&](double value, int axis) {
    return std::clamp(static_cast<int>(std::floor((value - lo[axis]) / bin_size[axis])), 0, dims[axis] - 1);
  };
  const auto bin_index = [&](int i, int j, int k) {
    return static_cast<std::size_t>(i) +
           static_cast<std::size_t>(dims[0]) * (j + static_cast<std::size_t>(dims[1]) * k);
  };
  std::vector<std::int32_t> bin_start(static_cast<std::size_t>(dims[0]) * dims[1] * dims[2] + 1, 0);
  std::vector<std::int32_t> bin_hexes;
  for (int pass = 0; pass < 2; ++pass) {
    std::vector<std::int32_t> next(bin_start.begin(), bin_start.end() - 1);
    for (std::size_t h = 0; h < hexes.size(); ++h) {
      for (int k = bin_of(boxes[h].first.z(), 2); k <= bin_of(boxes[h].second.z(), 2); ++k) {
        for (int j = bin_of(boxes[h].first.y(), 1); j <= bin_of(boxes[h].second.y(), 1); ++j) {
          for (int i = bin_of(boxes[h].first.x(), 0); i <= bin_of(boxes[h].second.x(), 0); ++i) {
            if (pass == 0)
              ++bin_start[bin_index(i, j, k) + 1];
            else
              bin_hexes[static_cast<std::size_t>(next[bin_index(i, j, k)]++)] = static_cast<std::int32_t>(h);
          }
        }
      }
    }
    if (pass == 0) {
      for (std::size_t b = 1; b < bin_start.size(); ++b) bin_start[b] += bin_start[b - 1];
      bin_hexes.resize(static_cast<std::size_t>(bin_start.back()));
    }
  }

  SurfaceMapping m;
  m.identity_ = false;
  m.arity_ = 8;
  m.nodes_.reserve(surface_vertices.size());
  m.weights_.reserve(surface_vertices.size());
  // How far outside [−1, 1]³ a point's ξ is (0 inside).
  const auto outside = [](const Vec3& xi) {
    return xi.allFinite() ? std::max(0.0, xi.cwiseAbs().maxCoeff() - 1.0) : 1e300;
  };
  for (std::size_t v = 0; v < surface_vertices.size(); ++v) {
    const Vec3& p = surface_vertices[v];
    std::int64_t best = -1;
    Vec3 best_xi = Vec3::Zero();
    double best_score = std::numeric_limits<double>::infinity();
    // The hexahedra whose box holds p (within round-off), first inside wins.
    const bool in_range = (p.array() >= lo.array()).all() && (p.array() <= hi.array()).all();
    if (in_range) {
      const std::size_t b = bin_index(bin_of(p.x(), 0), bin_of(p.y(), 1), bin_of(p.z(), 2));
      for (std::int32_t at = bin_start[b]; at < bin_start[b + 1] && best_score > 1e-9; ++at) {
        const auto h = static_cast<std::size_t>(bin_hexes[static_cast<std::size_t>(at)]);
        const double slack = 1e-9 * (boxes[h].second - boxes[h].first).maxCoeff();
        if (((p.array() < boxes[h].first.array() - slack) || (p.array() > boxes[h].second.array() + slack)).any())
          continue;
        const Vec3 xi = hex_local_coordinates(volume_nodes, hexes[h], p);
        if (outside(xi) < best_score) {
          best_score = outside(xi);
          best = static_cast<std::int64_t>(h);
          best_xi = xi;
        }
      }
    }
    if (best_score > 1e-9) {
      // Not inside any: the nearest hexahedron by box distance, then by how far outside its
      // cell p is (ties between boxes at the same distance).
      double nearest = std::numeric_limits<double>::infinity();
      std::vector<std::pair<double, std::size_t>> candidates;
      for (std::size_t h = 0; h < hexes.size(); ++h) {
        const Vec3 gap = (boxes[h].first - p).cwiseMax(p - boxes[h].second).cwiseMax(0.0);
        candidates.emplace_back(gap.norm(), h);
        nearest = std::min(nearest, gap.norm());
      }
      for (const auto& [distance, h] : candidates) {
        if (distance > nearest + 1e-9 * (boxes[h].second - boxes[h].first).maxCoeff()) continue;
        const Vec3 xi = hex_local_coordinates(volume_nodes, hexes[h], p);
        if (outside(xi) < best_score) {
          best_score = outside(xi);
          best = static_cast<std::int64_t>(h);
          best_xi = xi;
        }
      }
    }
    if (best < 0 || !best_xi.allFinite()) {
      return make_error(ErrorCode::kInvalidMesh, fmt::format("trilinear mapping: surface vertex {} has no hexahedron "
                                                             "(the hexahedra are flat)",
                                                             v));
    }
    const auto n = mesh::hex_shape_functions(best_xi);
    std::array<std::int32_t, kMaxNodesPerVertex> nodes{};
    std::array<double, kMaxNodesPerVertex> weights{};
    for (int c = 0; c < 8; ++c) {
      nodes[c] = hexes[static_cast<std::size_t>(best)][c];
      weights[c] = n[c];
    }
    m.nodes_.push_back(nodes);
    m.weights_.push_back(weights);
  }
  return m;
}

void SurfaceMapping::apply(std::span<const double> volume, std::span<Vec3> surface) const {
  for (std::size_t v = 0; v < nodes_.size(); ++v) {
    Vec3 sum = Vec3::Zero();
    for (int k = 0; k < arity_; ++k) {
      const std::size_t n = 3 * static_cast<std::size_t>(nodes_[v][k]);
      sum += weights_[v][k] * Vec3(volume[n], volume[n + 1], volume[n + 2]);
    }
    surface[v] = sum;
  }
}

void SurfaceMapping::add_vertex_force(std::int32_t surface_vertex, const Vec3& force,
                                      std::span<double> volume_forces) const {
  const auto& nodes = nodes_[static_cast<std::size_t>(surface_vertex)];
  const auto& weights = weights_[static_cast<std::size_t>(surface_vertex)];
  for (int k = 0; k < arity_; ++k) {
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
    for (int k = 0; k < arity_ && count < nodes.size() && count < weights.size(); ++k) {
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
  for (int k = 1; k < arity_; ++k) {
    if (w[k] > w[best]) best = k;
  }
  return nodes_[static_cast<std::size_t>(surface_vertex)][best];
}

}  // namespace hof::coupling
