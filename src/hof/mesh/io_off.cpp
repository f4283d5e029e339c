/// @file
/// OFF (Geomview Object File Format) reading and writing. The header keyword may carry the
/// ST/C/N prefixes (texture, colour, normal per vertex); those extra values, and optional
/// face colours, are skipped to the end of their line. Faces with more than 3 vertices are
/// fan-triangulated. '#' starts a comment.

#include <string>
#include <vector>

#include "hof/mesh/detail/text_reader.h"
#include "hof/mesh/mesh_io.h"

namespace hof::mesh {

namespace {

using detail::quoted;

/// Whether `keyword` is OFF with optional ST, C, N prefixes (in that order); `dimensional`
/// is set for the 4OFF / nOFF variants, which are not supported.
bool is_off_keyword(std::string_view keyword, bool& dimensional) {
  dimensional = false;
  if (!keyword.ends_with("OFF")) return false;
  std::string_view prefix = keyword.substr(0, keyword.size() - 3);
  for (const std::string_view p : {"ST", "C", "N"}) {
    if (prefix.starts_with(p)) prefix.remove_prefix(p.size());
  }
  if (prefix == "4" || prefix == "n") {
    dimensional = true;
    return true;
  }
  return prefix.empty();
}

}  // namespace

Expected<ReadResult> read_off(const std::filesystem::path& path) {
  auto text = detail::read_whole_file(path);
  if (!text) return std::unexpected(text.error());
  const std::string file = path.string();
  if (detail::is_blank(*text)) return make_error(ErrorCode::kParse, "file is empty", file, 1);

  ReadResult result;
  result.report.format = "off";
  Mesh& mesh = result.mesh;
  detail::Scanner sc(*text, file, '#');

  std::string_view keyword = sc.next();
  if (keyword.starts_with("\xEF\xBB\xBF")) keyword.remove_prefix(3);
  bool dimensional = false;
  if (keyword.empty()) {
    return make_error(ErrorCode::kParse, "file is empty (comments only)", file, sc.line());
  }
  if (!is_off_keyword(keyword, dimensional)) {
    sc.fail(ErrorCode::kParse, "not an OFF file: expected the 'OFF' header, found " + quoted(keyword));
    return sc.unexpected_error();
  }
  if (dimensional || detail::iequals(sc.peek(), "BINARY")) {
    sc.fail(ErrorCode::kUnsupported,
            "only 3-D ASCII OFF is supported, not " + quoted(keyword) + (dimensional ? "" : " BINARY"));
    return sc.unexpected_error();
  }

  const std::int64_t vertex_count = sc.integer("vertex count");
  const std::int64_t face_count = sc.integer("face count");
  if (!sc.failed() && sc.line_has_more()) sc.integer("edge count");
  if (sc.failed()) return sc.unexpected_error();
  sc.skip_line();
  // Shortest vertex line "0 0 0\n", shortest face line "3 0 1 2\n".
  if (!detail::count_fits(vertex_count, 6, sc.bytes_left()) || vertex_count > INT32_MAX) {
    sc.fail(ErrorCode::kParse, detail::impossible_count("vertex count", vertex_count, 6, sc.bytes_left()));
    return sc.unexpected_error();
  }
  const std::size_t face_bytes = sc.bytes_left() - static_cast<std::size_t>(6 * vertex_count);
  if (!detail::count_fits(face_count, 8, face_bytes)) {
    sc.fail(ErrorCode::kParse, detail::impossible_count("face count", face_count, 8, face_bytes));
    return sc.unexpected_error();
  }
  if (vertex_count == 0) {
    return make_error(ErrorCode::kInvalidMesh, "the file holds no vertices", file, sc.line());
  }

  mesh.nodes.reserve(static_cast<std::size_t>(vertex_count));
  for (std::int64_t i = 0; i < vertex_count; ++i) {
    const double x = sc.real("vertex x");
    const double y = sc.real("vertex y");
    const double z = sc.real("vertex z");
    if (sc.failed()) {
      sc.add_context("vertex " + std::to_string(i + 1) + " of " + std::to_string(vertex_count));
      return sc.unexpected_error();
    }
    mesh.nodes.emplace_back(x, y, z);
    sc.skip_line();  // colour, normal, texture coordinates
  }

  std::vector<NodeIndex> polygon;
  for (std::int64_t f = 0; f < face_count; ++f) {
    const std::int64_t n = sc.integer("number of face vertices");
    if (!sc.failed() && (n < 3 || !detail::count_fits(n, 2, sc.bytes_left()))) {
      sc.fail(ErrorCode::kInvalidMesh, "face with " + std::to_string(n) + " vertices");
    }
    polygon.clear();
    for (std::int64_t k = 0; k < n && !sc.failed(); ++k) {
      const std::int64_t v = sc.integer("vertex index");
      if (!sc.failed() && (v < 0 || v >= vertex_count)) {
        sc.fail(ErrorCode::kInvalidMesh, "vertex index " + std::to_string(v) + " is out of range (" +
                                             std::to_string(vertex_count) + " vertices)");
      }
      polygon.push_back(static_cast<NodeIndex>(v));
    }
    if (sc.failed()) {
      sc.add_context("face " + std::to_string(f + 1) + " of " + std::to_string(face_count));
      return sc.unexpected_error();
    }
    for (std::size_t k = 1; k + 1 < polygon.size(); ++k) {
      mesh.triangles.push_back({polygon[0], polygon[k], polygon[k + 1]});
    }
    sc.skip_line();  // optional face colour
  }
  if (!sc.at_end()) {
    sc.next();
    sc.fail(ErrorCode::kParse,
            "data after the last of the " + std::to_string(face_count) + " faces: the face count is wrong");
    return sc.unexpected_error();
  }
  return result;
}

Expected<void> write_off(const Mesh& mesh, const std::filesystem::path& path) {
  if (auto ok = detail::check_mesh_for_write(mesh, path); !ok) return ok;
  if (mesh.triangles.empty() && !mesh.tets.empty()) {
    return make_error(ErrorCode::kInvalidArgument,
                      "OFF holds only triangles and the mesh has " + std::to_string(mesh.tets.size()) +
                          " tetrahedra but no triangles; extract the boundary first",
                      path.string());
  }
  std::string out;
  out.reserve(72 * mesh.nodes.size() + 40 * mesh.triangles.size() + 32);
  out += "OFF\n";
  detail::append_int(out, static_cast<std::int64_t>(mesh.nodes.size()));
  out += ' ';
  detail::append_int(out, static_cast<std::int64_t>(mesh.triangles.size()));
  out += " 0\n";
  for (const Vec3& p : mesh.nodes) {
    detail::append_real(out, p.x());
    out += ' ';
    detail::append_real(out, p.y());
    out += ' ';
    detail::append_real(out, p.z());
    out += '\n';
  }
  for (const Tri& t : mesh.triangles) {
    out += '3';
    for (const NodeIndex v : t) {
      out += ' ';
      detail::append_int(out, v);
    }
    out += '\n';
  }
  return detail::write_whole_file(path, out);
}

}  // namespace hof::mesh
