#pragma once
/// @file
/// SOFA's sphere files (`.sph`, read by its SphereLoader for a SphereCollisionModel): a
/// header line `sph 1.0`, then one `sphe INDEX X Y Z RADIUS` line per sphere; `nums N`
/// announces the count (checked when given); `#` starts a comment.

#include <filesystem>
#include <vector>

#include "hof/core/error.h"
#include "hof/core/types.h"

namespace hof::mesh {

/// The spheres of a `.sph` file, in the file's order (its units).
struct SphereSet {
  std::vector<Vec3> centers;
  std::vector<double> radii;  ///< > 0, one per centre
};

/// Reads a `.sph` file. Errors name the file and the line: not found, no `sph 1.0` header, an
/// unknown keyword, a value that is not a finite number, a radius ≤ 0, a `nums` count the
/// spheres do not match, no sphere at all.
[[nodiscard]] Expected<SphereSet> read_sph(const std::filesystem::path& path);
/// The same from text held in memory; `path` names it in errors.
[[nodiscard]] Expected<SphereSet> parse_sph(std::string_view text, const std::filesystem::path& path);

}  // namespace hof::mesh
