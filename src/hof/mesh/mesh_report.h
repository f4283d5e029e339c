#pragma once
/// @file
/// A summary of a mesh for users and for validation: sizes, bounding box, volume, element
/// quality and every problem found (inverted or degenerate elements, an open or
/// non-manifold boundary, unused nodes). This is what `hof mesh info` prints.

#include <cstdint>
#include <string>
#include <vector>

#include "hof/mesh/mesh.h"
#include "hof/mesh/surface_check.h"

namespace hof::mesh {

/// Element quality over all tetrahedra. Angles in degrees.
struct QualitySummary {
  double min_dihedral_deg{0.0};       ///< smallest dihedral angle of any tet
  double max_dihedral_deg{0.0};       ///< largest dihedral angle of any tet
  double mean_min_dihedral_deg{0.0};  ///< mean over tets of each tet's smallest angle
  double min_radius_ratio{0.0};       ///< worst normalised radius ratio (1 = regular)
  double mean_radius_ratio{0.0};
  double min_volume_m3{0.0};
  double max_volume_m3{0.0};
  std::int64_t inverted{0};    ///< tets with negative signed volume
  std::int64_t degenerate{0};  ///< tets with |volume| below 1e-12 of the mean edge length cubed
};

/// Per-tet quality for a histogram or a colour map.
[[nodiscard]] QualitySummary summarize_quality(const std::vector<Vec3>& nodes, const std::vector<Tet>& tets);

/// Indices of tetrahedra whose signed volume is negative (inverted) or whose volume is
/// negligible compared with their size (degenerate).
[[nodiscard]] std::vector<std::int32_t> find_inverted_tets(const std::vector<Vec3>& nodes,
                                                           const std::vector<Tet>& tets);

struct MeshReport {
  std::int64_t nodes{0};
  std::int64_t tets{0};
  std::int64_t file_triangles{0};     ///< triangles stored in the file
  std::int64_t edges{0};              ///< unique edges of the tets (or of the triangles)
  std::int64_t surface_triangles{0};  ///< boundary triangles (tets) or file triangles
  std::int64_t surface_vertices{0};
  std::int64_t unused_nodes{0};  ///< nodes referenced by no element
  Vec3 bbox_min{Vec3::Zero()};
  Vec3 bbox_max{Vec3::Zero()};
  double volume_m3{0.0};              ///< sum of tet volumes, or enclosed by the triangles
  QualitySummary quality;             ///< meaningful when tets > 0
  SurfaceCheck surface;               ///< of the boundary (tets) or of the triangles
  std::vector<std::string> problems;  ///< one sentence each; empty when the mesh is sound
};

/// Computes the report. For a mesh with tetrahedra, the surface is the extracted boundary;
/// otherwise it is the mesh's own triangles.
[[nodiscard]] MeshReport make_mesh_report(const Mesh& mesh);

}  // namespace hof::mesh
