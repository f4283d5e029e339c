#pragma once
/// @file
/// How much a triangulated surface is stretched or compressed: the Green–Lagrange membrane
/// strain of each triangle, E = ½ (FᵀF − I), from its rest and current shapes (Bonet & Wood,
/// Nonlinear Continuum Mechanics for FEA, 2nd ed., §3.5; in a triangle's own rest edge basis,
/// the mixed tensor G₀⁻¹(G − G₀)/2 of the edge metrics has the principal strains as
/// eigenvalues). Drawn by the window as a colour ("colorBy strain").

#include <span>
#include <vector>

#include "hof/core/types.h"
#include "hof/mesh/mesh.h"

namespace hof::mesh {

/// The principal Green strain of largest magnitude (signed: > 0 stretched, < 0 compressed)
/// of the triangle (a0, a1, a2) at rest now at (b0, b1, b2); 0 for a degenerate rest triangle.
[[nodiscard]] double triangle_green_strain(const Vec3& a0, const Vec3& a1, const Vec3& a2, const Vec3& b0,
                                           const Vec3& b1, const Vec3& b2);

/// Per vertex: the mean magnitude of its triangles' strains (written to `out`, resized).
void vertex_strain_magnitude(std::span<const Vec3> rest, std::span<const Vec3> current, std::span<const Tri> triangles,
                             std::vector<double>& out);

}  // namespace hof::mesh
