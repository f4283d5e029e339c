#pragma once
/// @file
/// Quality tetrahedral meshing of a closed triangle surface with TetGen (Si, "TetGen, a
/// Delaunay-based quality tetrahedral mesh generator", ACM TOMS 41(2), 2015).

#include <string>

#include "hof/core/error.h"
#include "hof/mesh/mesh.h"

namespace hof::mesh {

struct TetrahedralizeOptions {
  /// Upper bound on tetrahedron volume (m^3); 0 leaves volume unconstrained (TetGen `-a`).
  double max_volume_m3{0.0};
  /// Upper bound on the radius-edge ratio (TetGen `-q`); 0 turns quality refinement off.
  /// TetGen guarantees termination for bounds ≥ 1.0; 1.414 is its default.
  double radius_edge_ratio{1.414};
  /// Lower bound on dihedral angles in degrees, enforced by TetGen's mesh optimisation
  /// (the second value of `-q`); 0 leaves it to the default.
  double min_dihedral_deg{0.0};
  /// Keep the input surface triangles unsplit (TetGen `-Y`).
  bool preserve_surface{false};
};

/// Tetrahedralizes the volume enclosed by `surface`, which must be a closed, consistently
/// oriented 2-manifold. The result holds positively oriented tetrahedra and, as triangles,
/// the outward boundary in volume-node indices. `source_name` names the input in errors.
/// Errors: kInvalidArgument for bad options; kMeshing for an open, non-manifold or
/// self-intersecting surface, with the offending edge or TetGen's own diagnosis.
[[nodiscard]] Expected<Mesh> tetrahedralize(const TriMesh& surface, const TetrahedralizeOptions& options,
                                            const std::string& source_name = "surface");

}  // namespace hof::mesh
