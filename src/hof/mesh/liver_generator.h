#pragma once
/// @file
/// The organ-shape generator behind HoF's standard models: a smooth, asymmetric, two-lobed,
/// liver-like closed surface about 0.2 m across (SI units), and its tetrahedral meshes at the
/// four named resolutions the thesis evaluates (Liver Simple, Coarse, Medium, Fine).
/// Deterministic: the same resolution gives the same nodes and elements on every run.

#include <cstdint>
#include <optional>
#include <string_view>

#include "hof/core/error.h"
#include "hof/core/progress.h"
#include "hof/mesh/mesh.h"

namespace hof::mesh {

/// The standard resolutions and their target tetrahedron counts.
enum class LiverResolution : std::uint8_t {
  kSimple,  ///< ≈600 tets, the size of SOFA's liver demo
  kCoarse,  ///< ≈2,500 tets
  kMedium,  ///< ≈10,000 tets
  kFine,    ///< ≈40,000 tets
};

/// Target number of tetrahedra of a resolution (the generated mesh is within ±20% of it).
[[nodiscard]] std::int64_t target_tet_count(LiverResolution resolution);

/// "simple", "coarse", "medium", "fine".
[[nodiscard]] std::string_view to_string(LiverResolution resolution);
[[nodiscard]] std::optional<LiverResolution> parse_liver_resolution(std::string_view name);

/// The closed liver surface sampled by a geodesic sphere of the given frequency
/// (20·frequency² triangles), outward-oriented, in metres.
/// @pre frequency >= 1
[[nodiscard]] TriMesh make_liver_surface(int frequency);

/// The same mesh with nodes renumbered along a Morton curve and tetrahedra sorted by their
/// smallest node (better memory locality for the solvers); triangles are the boundary.
[[nodiscard]] Mesh renumber_for_locality(const Mesh& mesh);

/// The tetrahedral liver at a standard resolution, with its outward boundary as triangles.
/// Meshes with TetGen (quality bound, surface preserved); the count follows from the surface
/// sampling chosen per resolution.
[[nodiscard]] Expected<Mesh> generate_liver(LiverResolution resolution, const ProgressSink& progress = {});

}  // namespace hof::mesh
