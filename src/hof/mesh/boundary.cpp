#include "hof/mesh/boundary.h"

#include <algorithm>

#include "hof/mesh/tet_geometry.h"

namespace hof::mesh {

namespace {

// Faces of a positively oriented tet (0,1,2,3), wound so their normals point outward.
constexpr std::array<std::array<int, 3>, 4> kOutwardFaces = {{{1, 2, 3}, {0, 3, 2}, {0, 1, 3}, {0, 2, 1}}};

struct FaceRecord {
  std::array<NodeIndex, 3> key;  // sorted node indices
  std::int32_t tet;
  std::int8_t local_face;
};

}  // namespace

BoundarySurface extract_boundary(const std::vector<Vec3>& nodes, const std::vector<Tet>& tets) {
  // Sort all 4T faces by their sorted node triple; a face seen once is on the boundary.
  // Sorting (rather than hashing) keeps the result independent of hash seeds and platforms.
  std::vector<FaceRecord> faces;
  faces.reserve(tets.size() * 4);
  for (std::size_t t = 0; t < tets.size(); ++t) {
    for (std::int8_t f = 0; f < 4; ++f) {
      std::array<NodeIndex, 3> key = {tets[t][kOutwardFaces[f][0]], tets[t][kOutwardFaces[f][1]],
                                      tets[t][kOutwardFaces[f][2]]};
      std::sort(key.begin(), key.end());
      faces.push_back({key, static_cast<std::int32_t>(t), f});
    }
  }
  std::sort(faces.begin(), faces.end(), [](const FaceRecord& a, const FaceRecord& b) {
    return a.key != b.key ? a.key < b.key : (a.tet != b.tet ? a.tet < b.tet : a.local_face < b.local_face);
  });

  BoundarySurface out;
  std::vector<std::pair<std::int32_t, std::int8_t>> boundary;  // (tet, local face)
  for (std::size_t i = 0; i < faces.size();) {
    std::size_t j = i + 1;
    while (j < faces.size() && faces[j].key == faces[i].key) ++j;
    if (j - i == 1) boundary.emplace_back(faces[i].tet, faces[i].local_face);
    if (j - i > 2) ++out.non_manifold_faces;
    i = j;
  }
  std::sort(boundary.begin(), boundary.end());

  out.volume_to_surface.assign(nodes.size(), -1);
  out.volume_triangles.reserve(boundary.size());
  out.triangle_tet.reserve(boundary.size());
  for (const auto& [t, f] : boundary) {
    const Tet& tet = tets[t];
    Tri tri = {tet[kOutwardFaces[f][0]], tet[kOutwardFaces[f][1]], tet[kOutwardFaces[f][2]]};
    const auto c = tet_corners(nodes, tet);
    if (tet_signed_volume(c[0], c[1], c[2], c[3]) < 0.0) std::swap(tri[1], tri[2]);
    out.volume_triangles.push_back(tri);
    out.triangle_tet.push_back(t);
    for (NodeIndex n : tri) out.volume_to_surface[n] = 0;  // mark; numbered below
  }
  number_boundary_vertices(nodes, out);
  return out;
}

void number_boundary_vertices(const std::vector<Vec3>& nodes, BoundarySurface& out) {
  // Surface vertices in increasing volume-node order.
  for (std::size_t n = 0; n < nodes.size(); ++n) {
    if (out.volume_to_surface[n] < 0) continue;
    out.volume_to_surface[n] = static_cast<std::int32_t>(out.surface_to_volume.size());
    out.surface_to_volume.push_back(static_cast<NodeIndex>(n));
    out.surface.vertices.push_back(nodes[n]);
  }
  out.surface.triangles.reserve(out.volume_triangles.size());
  for (const Tri& tri : out.volume_triangles) {
    out.surface.triangles.push_back(
        {out.volume_to_surface[tri[0]], out.volume_to_surface[tri[1]], out.volume_to_surface[tri[2]]});
  }
}

std::vector<Edge> tet_edges(const std::vector<Tet>& tets) {
  std::vector<Edge> edges;
  edges.reserve(tets.size() * 6);
  for (const Tet& t : tets) {
    for (int i = 0; i < 4; ++i) {
      for (int j = i + 1; j < 4; ++j) {
        edges.push_back({std::min(t[i], t[j]), std::max(t[i], t[j])});
      }
    }
  }
  std::sort(edges.begin(), edges.end());
  edges.erase(std::unique(edges.begin(), edges.end()), edges.end());
  return edges;
}

std::vector<Edge> triangle_edges(const std::vector<Tri>& triangles) {
  std::vector<Edge> edges;
  edges.reserve(triangles.size() * 3);
  for (const Tri& t : triangles) {
    for (int i = 0; i < 3; ++i) {
      const NodeIndex a = t[i], b = t[(i + 1) % 3];
      edges.push_back({std::min(a, b), std::max(a, b)});
    }
  }
  std::sort(edges.begin(), edges.end());
  edges.erase(std::unique(edges.begin(), edges.end()), edges.end());
  return edges;
}

}  // namespace hof::mesh
