#pragma once
/// @file
/// Readers for the two 2008 SOFA data formats that old scenes reference and no other tool
/// reads: the text mesh `.mesh` (`tetra a b c d`, `triangle a b c`, `line a b` lines, 0-based,
/// no coordinates) and the Xsp mass-spring file `.xs3` (`numm`, `mass a s x y z vx vy vz m
/// fixed`, `lspg i j …`). Internal to hof::scene.

#include <cstdint>
#include <filesystem>
#include <vector>

#include "hof/core/error.h"
#include "hof/mesh/mesh.h"

namespace hof::scene::detail {

/// A `.mesh` file: elements only (the format carries no node positions).
struct LegacyMesh {
  std::vector<mesh::Tet> tets;       ///< (T) 0-based node indices
  std::vector<mesh::Tri> triangles;  ///< (F) 0-based node indices
  std::int64_t ignored_lines{0};     ///< `line`/`quad`/other element lines not kept
};

/// Reads a `.mesh` file. Errors name the file and line (unknown numbers, short lines).
[[nodiscard]] Expected<LegacyMesh> read_legacy_mesh(const std::filesystem::path& path);

/// An `.xs3` (Xsp 3.0) file: the masses (nodes); springs are not kept.
struct Xs3File {
  std::vector<Vec3> positions;   ///< (N) scene units
  std::vector<Vec3> velocities;  ///< (N) scene units per second
  std::vector<double> masses;    ///< (N) mass per node
  std::vector<bool> fixed;       ///< (N) the node's `fixed` flag
  std::int64_t springs{0};       ///< number of `lspg` lines (not used by HoF)
};

/// Reads an `.xs3` file. Errors name the file and line; `numm` must match the `mass` lines.
[[nodiscard]] Expected<Xs3File> read_xs3(const std::filesystem::path& path);

}  // namespace hof::scene::detail
