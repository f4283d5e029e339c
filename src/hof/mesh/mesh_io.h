#pragma once
/// @file
/// Reading and writing mesh files. The format is chosen from the file extension:
///   .msh  Gmsh: read v1 ($NOD/$ELM), v2 ASCII and binary, v4.1 ASCII; write v2 or v4.1 ASCII
///   .obj  Wavefront OBJ: read v/vn/vt/f (all index forms, negative indices, polygons are
///         fan-triangulated); write v/vn/f
///   .stl  STL ASCII or binary (detected), vertices welded by exact position; read only
///   .off  OFF; read and write
///   .vtu  VTK XML UnstructuredGrid, ASCII; write (opens in ParaView) and read back
/// Every failure names the file and the line (text formats) or byte offset (binary) and
/// what is wrong. Readers never crash or hang on malformed input.

#include <cstdint>
#include <filesystem>
#include <string>
#include <vector>

#include "hof/core/error.h"
#include "hof/core/progress.h"
#include "hof/mesh/mesh.h"

namespace hof::mesh {

/// What a reader met besides what it kept.
struct ReadReport {
  std::string format;                 ///< e.g. "gmsh-1", "gmsh-2.2-ascii", "gmsh-4.1-ascii", "obj"
  std::int64_t ignored_points{0};     ///< point elements skipped
  std::int64_t ignored_lines{0};      ///< line elements skipped
  std::int64_t ignored_other{0};      ///< other element types skipped (quads, hexahedra, ...)
  std::vector<std::string> warnings;  ///< one line each, "FILE:LINE: ..." where known
};

struct ReadResult {
  Mesh mesh;
  ReadReport report;
};

/// Gmsh file-format version written by write_msh.
enum class MshVersion : std::uint8_t { k2_2, k4_1 };

/// Reads any supported format, chosen by extension (case-insensitive).
[[nodiscard]] Expected<ReadResult> read_mesh(const std::filesystem::path& path, const ProgressSink& progress = {});
[[nodiscard]] Expected<ReadResult> read_msh(const std::filesystem::path& path, const ProgressSink& progress = {});
[[nodiscard]] Expected<ReadResult> read_obj(const std::filesystem::path& path);
[[nodiscard]] Expected<ReadResult> read_stl(const std::filesystem::path& path);
[[nodiscard]] Expected<ReadResult> read_off(const std::filesystem::path& path);
[[nodiscard]] Expected<ReadResult> read_vtu(const std::filesystem::path& path);

/// Writes by extension (.msh → v4.1 unless `msh_version` says otherwise, .obj, .off, .vtu).
/// OBJ and OFF hold only the triangles; writing a mesh with tetrahedra but no triangles to
/// them is an error (extract the boundary first).
[[nodiscard]] Expected<void> write_mesh(const Mesh& mesh, const std::filesystem::path& path,
                                        MshVersion msh_version = MshVersion::k4_1);
[[nodiscard]] Expected<void> write_msh(const Mesh& mesh, const std::filesystem::path& path, MshVersion version);
[[nodiscard]] Expected<void> write_obj(const Mesh& mesh, const std::filesystem::path& path);
[[nodiscard]] Expected<void> write_off(const Mesh& mesh, const std::filesystem::path& path);
[[nodiscard]] Expected<void> write_vtu(const Mesh& mesh, const std::filesystem::path& path);

}  // namespace hof::mesh
