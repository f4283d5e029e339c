#include "hof/mesh/mesh_report.h"

#include <fmt/format.h>
#include <algorithm>
#include <cmath>
#include <limits>
#include <numbers>

#include "hof/mesh/boundary.h"
#include "hof/mesh/tet_geometry.h"

namespace hof::mesh {

namespace {

constexpr double kRadToDeg = 180.0 / std::numbers::pi;

double mean_edge_length(const std::array<Vec3, 4>& c) {
  double sum = 0.0;
  for (int i = 0; i < 4; ++i) {
    for (int j = i + 1; j < 4; ++j) sum += (c[i] - c[j]).norm();
  }
  return sum / 6.0;
}

bool is_degenerate(const std::array<Vec3, 4>& c, double signed_volume) {
  const double h = mean_edge_length(c);
  return !(std::abs(signed_volume) > 1e-12 * h * h * h);
}

}  // namespace

QualitySummary summarize_quality(const std::vector<Vec3>& nodes, const std::vector<Tet>& tets) {
  QualitySummary q;
  if (tets.empty()) return q;
  q.min_dihedral_deg = std::numeric_limits<double>::infinity();
  q.min_radius_ratio = std::numeric_limits<double>::infinity();
  q.min_volume_m3 = std::numeric_limits<double>::infinity();
  q.max_volume_m3 = -std::numeric_limits<double>::infinity();
  double sum_min_dihedral = 0.0, sum_ratio = 0.0;
  for (const Tet& t : tets) {
    const auto c = tet_corners(nodes, t);
    const double v = tet_signed_volume(c[0], c[1], c[2], c[3]);
    const auto angles = tet_dihedral_angles(c[0], c[1], c[2], c[3]);
    const double lo = *std::min_element(angles.begin(), angles.end()) * kRadToDeg;
    const double hi = *std::max_element(angles.begin(), angles.end()) * kRadToDeg;
    const double ratio = tet_radius_ratio(c[0], c[1], c[2], c[3]);
    q.min_dihedral_deg = std::min(q.min_dihedral_deg, lo);
    q.max_dihedral_deg = std::max(q.max_dihedral_deg, hi);
    q.min_radius_ratio = std::min(q.min_radius_ratio, ratio);
    q.min_volume_m3 = std::min(q.min_volume_m3, v);
    q.max_volume_m3 = std::max(q.max_volume_m3, v);
    sum_min_dihedral += lo;
    sum_ratio += ratio;
    if (is_degenerate(c, v)) {
      ++q.degenerate;
    } else if (v < 0.0) {
      ++q.inverted;
    }
  }
  const auto n = static_cast<double>(tets.size());
  q.mean_min_dihedral_deg = sum_min_dihedral / n;
  q.mean_radius_ratio = sum_ratio / n;
  return q;
}

std::vector<std::int32_t> find_inverted_tets(const std::vector<Vec3>& nodes, const std::vector<Tet>& tets) {
  std::vector<std::int32_t> out;
  for (std::size_t i = 0; i < tets.size(); ++i) {
    const auto c = tet_corners(nodes, tets[i]);
    const double v = tet_signed_volume(c[0], c[1], c[2], c[3]);
    if (v < 0.0 || is_degenerate(c, v)) out.push_back(static_cast<std::int32_t>(i));
  }
  return out;
}

MeshReport make_mesh_report(const Mesh& mesh) {
  MeshReport r;
  r.nodes = static_cast<std::int64_t>(mesh.nodes.size());
  r.tets = static_cast<std::int64_t>(mesh.tets.size());
  r.file_triangles = static_cast<std::int64_t>(mesh.triangles.size());
  if (!mesh.nodes.empty()) {
    r.bbox_min = r.bbox_max = mesh.nodes.front();
    for (const Vec3& p : mesh.nodes) {
      r.bbox_min = r.bbox_min.cwiseMin(p);
      r.bbox_max = r.bbox_max.cwiseMax(p);
    }
  }

  std::vector<char> used(mesh.nodes.size(), 0);
  for (const Tet& t : mesh.tets) {
    for (NodeIndex n : t) used[n] = 1;
  }
  for (const Tri& t : mesh.triangles) {
    for (NodeIndex n : t) used[n] = 1;
  }
  r.unused_nodes = std::count(used.begin(), used.end(), 0);

  if (!mesh.tets.empty()) {
    r.edges = static_cast<std::int64_t>(tet_edges(mesh.tets).size());
    r.quality = summarize_quality(mesh.nodes, mesh.tets);
    for (const Tet& t : mesh.tets) {
      const auto c = tet_corners(mesh.nodes, t);
      r.volume_m3 += tet_signed_volume(c[0], c[1], c[2], c[3]);
    }
    const BoundarySurface boundary = extract_boundary(mesh.nodes, mesh.tets);
    r.surface = check_surface(boundary.surface);
    r.surface_triangles = static_cast<std::int64_t>(boundary.surface.triangles.size());
    r.surface_vertices = static_cast<std::int64_t>(boundary.surface.vertices.size());
    if (r.quality.inverted > 0) {
      r.problems.push_back(fmt::format("{} inverted tetrahedra (negative volume)", r.quality.inverted));
    }
    if (r.quality.degenerate > 0) {
      r.problems.push_back(fmt::format("{} degenerate tetrahedra (zero volume)", r.quality.degenerate));
    }
    if (boundary.non_manifold_faces > 0) {
      r.problems.push_back(fmt::format("{} faces shared by more than two tetrahedra", boundary.non_manifold_faces));
    }
  } else {
    r.edges = static_cast<std::int64_t>(triangle_edges(mesh.triangles).size());
    r.surface = check_surface(mesh.nodes, mesh.triangles);
    r.surface_triangles = r.file_triangles;
    r.surface_vertices = r.surface.vertices_used;
    r.volume_m3 = r.surface.signed_volume_m3;
  }

  const SurfaceCheck& s = r.surface;
  if (s.triangles == 0) {
    r.problems.push_back("no tetrahedra and no triangles");
  } else {
    if (s.boundary_edges > 0) {
      r.problems.push_back(fmt::format("surface is open: {} boundary edges", s.boundary_edges));
    }
    if (s.non_manifold_edges > 0) {
      r.problems.push_back(fmt::format("{} non-manifold edges", s.non_manifold_edges));
    }
    if (s.non_manifold_vertices > 0) {
      r.problems.push_back(fmt::format("{} non-manifold vertices", s.non_manifold_vertices));
    }
    if (s.misoriented_edges > 0) {
      r.problems.push_back(fmt::format("{} edges with inconsistent triangle orientation", s.misoriented_edges));
    }
    if (s.degenerate_triangles > 0) {
      r.problems.push_back(fmt::format("{} degenerate triangles", s.degenerate_triangles));
    }
    if (s.closed_manifold() && !(s.signed_volume_m3 > 0.0)) {
      r.problems.push_back("surface normals point inward (negative enclosed volume)");
    }
  }
  if (r.unused_nodes > 0) {
    r.problems.push_back(fmt::format("{} nodes used by no element", r.unused_nodes));
  }
  return r;
}

}  // namespace hof::mesh
