/// @file
/// Wavefront OBJ reading (v, vn, vt, f in every index form, negative indices, polygons
/// fan-triangulated) and writing (v, vn, f).
///
/// OBJ is line-oriented, so the reader goes line by line. Statements that carry nothing a
/// mesh keeps (groups, materials, smoothing, free-form geometry) are skipped by name; any
/// other first word is a parse error, which is what makes binary garbage fail on its first
/// line instead of being silently skipped.

#include <algorithm>
#include <array>
#include <string>
#include <string_view>
#include <vector>

#include "hof/mesh/detail/text_reader.h"
#include "hof/mesh/mesh_io.h"

namespace hof::mesh {

namespace {

using detail::quoted;

/// OBJ statements that are valid but hold nothing HoF keeps.
constexpr std::array<std::string_view, 30> kIgnoredStatements = {
    "vp",    "o",        "g",        "s",          "mg",        "usemtl", "mtllib", "usemap", "maplib", "lod",
    "bevel", "c_interp", "d_interp", "shadow_obj", "trace_obj", "ctech",  "stech",  "cstype", "deg",    "bmat",
    "step",  "curv",     "curv2",    "surf",       "parm",      "trim",   "hole",   "scrv",   "sp",     "end",
};

/// One corner of a face: vertex index and normal index (-1 when absent), 0-based.
struct Corner {
  NodeIndex vertex{-1};
  std::int32_t normal{-1};
};

class ObjReader {
 public:
  explicit ObjReader(std::string file) : file_(std::move(file)) {}

  Expected<ReadResult> run(std::string_view text);

 private:
  Expected<void> statement(std::string_view line);
  Expected<void> read_vector(detail::Tokens& tokens, std::string_view keyword, int min_values, int max_values,
                             Vec3* out);
  Expected<Corner> corner(std::string_view token);
  Expected<std::int64_t> resolve(std::string_view text, std::int64_t defined, const char* what);

  std::unexpected<Error> fail(ErrorCode code, std::string message) const {
    return make_error(code, std::move(message), file_, line_);
  }

  std::string file_;
  std::int64_t line_{0};
  ReadResult result_;
  std::vector<Vec3> normals_;                // every vn in order
  std::vector<std::int32_t> vertex_normal_;  // per vertex: first vn a face gave it, or -1
  std::int64_t texture_coordinates_{0};
  std::vector<Corner> polygon_;
};

Expected<ReadResult> ObjReader::run(std::string_view text) {
  result_.report.format = "obj";
  detail::LineReader lines(text);
  std::string_view line;
  std::string joined;  // a statement continued over lines with a trailing backslash
  std::int64_t first_line = 0;
  while (lines.next(line)) {
    if (joined.empty()) first_line = lines.line_number();
    const std::size_t hash = line.find('#');
    if (hash != std::string_view::npos) line = line.substr(0, hash);
    const std::size_t last = line.find_last_not_of(" \t\r\v\f");
    if (last != std::string_view::npos && line[last] == '\\') {
      joined.append(line.substr(0, last));
      joined += ' ';
      continue;
    }
    line_ = first_line;
    if (!joined.empty()) {
      joined.append(line);
      line = joined;
    }
    if (auto ok = statement(line); !ok) return std::unexpected(ok.error());
    joined.clear();
  }
  line_ = lines.line_number();
  if (!joined.empty()) {
    return fail(ErrorCode::kParse, "unexpected end of file after a line continuation '\\'");
  }
  Mesh& mesh = result_.mesh;
  if (mesh.nodes.empty()) return fail(ErrorCode::kInvalidMesh, "the file holds no vertices ('v')");

  // Per-vertex normals exist only if some face gave a vertex one; vertices no face gave a
  // normal get zero, which is reported.
  if (std::any_of(vertex_normal_.begin(), vertex_normal_.end(), [](std::int32_t k) { return k >= 0; })) {
    mesh.normals.resize(mesh.nodes.size(), Vec3::Zero());
    std::int64_t missing = 0;
    for (std::size_t v = 0; v < vertex_normal_.size(); ++v) {
      if (vertex_normal_[v] >= 0) {
        mesh.normals[v] = normals_[static_cast<std::size_t>(vertex_normal_[v])];
      } else {
        ++missing;
      }
    }
    if (missing > 0) {
      result_.report.warnings.push_back(file_ + ": " + std::to_string(missing) +
                                        " vertices have no normal from any face; set to zero");
    }
  }
  return std::move(result_);
}

Expected<void> ObjReader::statement(std::string_view line) {
  detail::Tokens tokens(line);
  const std::string_view keyword = tokens.next();
  if (keyword.empty()) return {};
  Mesh& mesh = result_.mesh;

  if (keyword == "v") {
    Vec3 p;
    // x y z, then optionally w or an r g b colour: read, checked, not kept.
    if (auto ok = read_vector(tokens, keyword, 3, 7, &p); !ok) return ok;
    if (mesh.nodes.size() >= static_cast<std::size_t>(INT32_MAX)) {
      return fail(ErrorCode::kInvalidMesh, "too many vertices");
    }
    mesh.nodes.push_back(p);
    vertex_normal_.push_back(-1);
    return {};
  }
  if (keyword == "vn") {
    Vec3 n;
    if (auto ok = read_vector(tokens, keyword, 3, 3, &n); !ok) return ok;
    if (normals_.size() >= static_cast<std::size_t>(INT32_MAX)) {
      return fail(ErrorCode::kInvalidMesh, "too many normals");
    }
    normals_.push_back(n);
    return {};
  }
  if (keyword == "vt") {
    if (auto ok = read_vector(tokens, keyword, 1, 3, nullptr); !ok) return ok;
    ++texture_coordinates_;
    return {};
  }
  if (keyword == "f" || keyword == "l" || keyword == "p") {
    polygon_.clear();
    for (std::string_view token = tokens.next(); !token.empty(); token = tokens.next()) {
      auto c = corner(token);
      if (!c) return std::unexpected(c.error());
      polygon_.push_back(*c);
    }
    if (keyword == "p") {
      if (polygon_.empty()) return fail(ErrorCode::kParse, "'p' statement without vertices");
      result_.report.ignored_points += static_cast<std::int64_t>(polygon_.size());
      return {};
    }
    if (keyword == "l") {
      if (polygon_.size() < 2) return fail(ErrorCode::kParse, "'l' statement with fewer than 2 vertices");
      ++result_.report.ignored_lines;
      return {};
    }
    if (polygon_.size() < 3) {
      return fail(ErrorCode::kInvalidMesh,
                  "face with " + std::to_string(polygon_.size()) + " vertices (at least 3 needed)");
    }
    for (const Corner& c : polygon_) {
      if (c.normal >= 0 && vertex_normal_[static_cast<std::size_t>(c.vertex)] < 0) {
        vertex_normal_[static_cast<std::size_t>(c.vertex)] = c.normal;
      }
    }
    // Fan around the first corner: exact for convex polygons, which is what exporters write.
    for (std::size_t k = 1; k + 1 < polygon_.size(); ++k) {
      mesh.triangles.push_back({polygon_[0].vertex, polygon_[k].vertex, polygon_[k + 1].vertex});
    }
    return {};
  }
  if (std::find(kIgnoredStatements.begin(), kIgnoredStatements.end(), keyword) != kIgnoredStatements.end()) {
    return {};
  }
  return fail(ErrorCode::kParse, "unknown OBJ statement " + quoted(keyword));
}

Expected<void> ObjReader::read_vector(detail::Tokens& tokens, std::string_view keyword, int min_values, int max_values,
                                      Vec3* out) {
  int count = 0;
  for (std::string_view token = tokens.next(); !token.empty(); token = tokens.next()) {
    if (count == max_values) {
      return fail(ErrorCode::kParse,
                  "'" + std::string(keyword) + "' has more than " + std::to_string(max_values) + " values");
    }
    double value = 0.0;
    switch (detail::parse_real(token, value)) {
      case detail::RealParse::kOk:
        break;
      case detail::RealParse::kNotFinite:
        return fail(ErrorCode::kInvalidMesh,
                    "'" + std::string(keyword) + "' value " + quoted(token) + " is not a finite number");
      case detail::RealParse::kNotANumber:
        return fail(ErrorCode::kParse, "'" + std::string(keyword) + "' value " + quoted(token) + " is not a number");
    }
    if (out != nullptr && count < 3) (*out)[count] = value;
    ++count;
  }
  if (count < min_values) {
    return fail(ErrorCode::kParse, "'" + std::string(keyword) + "' needs " + std::to_string(min_values) +
                                       " values, found " + std::to_string(count));
  }
  return {};
}

/// 1-based (or negative, counted back from the last defined) index → 0-based index.
Expected<std::int64_t> ObjReader::resolve(std::string_view text, std::int64_t defined, const char* what) {
  std::int64_t index = 0;
  if (!detail::parse_int(text, index)) {
    return fail(ErrorCode::kParse, std::string(what) + " index " + quoted(text) + " is not an integer");
  }
  if (index == 0) return fail(ErrorCode::kInvalidMesh, std::string(what) + " index 0 (OBJ counts from 1)");
  const std::int64_t resolved = index > 0 ? index - 1 : defined + index;
  if (resolved < 0 || resolved >= defined) {
    return fail(ErrorCode::kInvalidMesh, std::string(what) + " index " + std::to_string(index) +
                                             " is out of range: " + std::to_string(defined) + " defined so far");
  }
  return resolved;
}

/// A face corner: `v`, `v/t`, `v//n` or `v/t/n`.
Expected<Corner> ObjReader::corner(std::string_view token) {
  const std::size_t slash1 = token.find('/');
  const std::string_view v_text = token.substr(0, slash1);
  std::string_view t_text;
  std::string_view n_text;
  if (slash1 != std::string_view::npos) {
    const std::size_t slash2 = token.find('/', slash1 + 1);
    t_text = token.substr(slash1 + 1, slash2 == std::string_view::npos ? std::string_view::npos : slash2 - slash1 - 1);
    if (slash2 != std::string_view::npos) {
      n_text = token.substr(slash2 + 1);
      if (n_text.empty() || n_text.find('/') != std::string_view::npos) {
        return fail(ErrorCode::kParse, "bad face vertex " + quoted(token));
      }
    } else if (t_text.empty()) {
      return fail(ErrorCode::kParse, "bad face vertex " + quoted(token));
    }
  }
  Corner c;
  auto v = resolve(v_text, static_cast<std::int64_t>(result_.mesh.nodes.size()), "vertex");
  if (!v) return std::unexpected(v.error());
  c.vertex = static_cast<NodeIndex>(*v);
  if (!t_text.empty()) {
    auto t = resolve(t_text, texture_coordinates_, "texture coordinate");
    if (!t) return std::unexpected(t.error());
  }
  if (!n_text.empty()) {
    auto n = resolve(n_text, static_cast<std::int64_t>(normals_.size()), "normal");
    if (!n) return std::unexpected(n.error());
    c.normal = static_cast<std::int32_t>(*n);
  }
  return c;
}

void append_vec(std::string& out, const char* keyword, const Vec3& p) {
  out += keyword;
  for (int k = 0; k < 3; ++k) {
    out += ' ';
    detail::append_real(out, p[k]);
  }
  out += '\n';
}

}  // namespace

Expected<ReadResult> read_obj(const std::filesystem::path& path) {
  auto text = detail::read_whole_file(path);
  if (!text) return std::unexpected(text.error());
  if (detail::is_blank(*text)) return make_error(ErrorCode::kParse, "file is empty", path.string(), 1);
  return ObjReader(path.string()).run(*text);
}

Expected<void> write_obj(const Mesh& mesh, const std::filesystem::path& path) {
  if (auto ok = detail::check_mesh_for_write(mesh, path); !ok) return ok;
  if (mesh.triangles.empty() && !mesh.tets.empty()) {
    return make_error(ErrorCode::kInvalidArgument,
                      "OBJ holds only triangles and the mesh has " + std::to_string(mesh.tets.size()) +
                          " tetrahedra but no triangles; extract the boundary first",
                      path.string());
  }
  std::string out;
  out.reserve(72 * mesh.nodes.size() * (mesh.normals.empty() ? 1 : 2) + 40 * mesh.triangles.size() + 64);
  out += "# HoF mesh: ";
  detail::append_int(out, static_cast<std::int64_t>(mesh.nodes.size()));
  out += " vertices, ";
  detail::append_int(out, static_cast<std::int64_t>(mesh.triangles.size()));
  out += " triangles\n";
  for (const Vec3& p : mesh.nodes) append_vec(out, "v", p);
  for (const Vec3& n : mesh.normals) append_vec(out, "vn", n);
  // Normals are per vertex, so a corner's normal index equals its vertex index.
  const bool with_normals = !mesh.normals.empty();
  for (const Tri& t : mesh.triangles) {
    out += 'f';
    for (const NodeIndex v : t) {
      out += ' ';
      detail::append_int(out, std::int64_t{v} + 1);
      if (with_normals) {
        out += "//";
        detail::append_int(out, std::int64_t{v} + 1);
      }
    }
    out += '\n';
  }
  return detail::write_whole_file(path, out);
}

}  // namespace hof::mesh
