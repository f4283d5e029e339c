/// @file
/// VTK XML UnstructuredGrid (.vtu), ASCII. The writer emits tetrahedra (VTK type 10) then
/// triangles (type 5), Float64 points written to round-trip exactly, a CellData "region"
/// array when the mesh has regions and a PointData "normals" array when it has normals; the
/// reader takes such files back (and any ASCII .vtu with one piece), ignoring other cells.

#include <map>
#include <string>
#include <vector>

#include <pugixml.hpp>

#include "hof/mesh/detail/text_reader.h"
#include "hof/mesh/mesh_io.h"
#include "hof/mesh/xml_depth.h"

namespace hof::mesh {

namespace {

using detail::quoted;

constexpr std::int64_t kVtkVertex = 1;
constexpr std::int64_t kVtkPolyVertex = 2;
constexpr std::int64_t kVtkLine = 3;
constexpr std::int64_t kVtkPolyLine = 4;
constexpr std::int64_t kVtkTriangle = 5;
constexpr std::int64_t kVtkTetra = 10;

class VtuReader {
 public:
  VtuReader(std::string_view text, std::string file) : text_(text), file_(std::move(file)) {}

  Expected<ReadResult> run();

 private:
  // The cells' three DataArrays and their values.
  struct Cells {
    pugi::xml_node offsets_array, types_array, connectivity_array;
    std::vector<std::int64_t> offsets, types, connectivity;
  };
  // The stages of run().
  Expected<pugi::xml_node> find_piece(pugi::xml_document& doc) const;
  Expected<void> read_points(const pugi::xml_node& piece, std::int64_t point_count, Mesh& mesh) const;
  Expected<Cells> read_cells(const pugi::xml_node& piece, std::int64_t cell_count) const;
  Expected<std::vector<std::int64_t>> read_regions(const pugi::xml_node& piece, std::int64_t cell_count) const;
  Expected<void> read_normals(const pugi::xml_node& piece, std::int64_t point_count, Mesh& mesh) const;
  Expected<void> keep_cells(const Cells& cells, const std::vector<std::int64_t>& regions, std::int64_t point_count,
                            ReadResult& result) const;

  /// 1-based line of a byte offset in the original text (pugixml's offset_debug()).
  std::int64_t line_at(std::ptrdiff_t offset) const {
    if (offset < 0) return 0;
    const auto end = text_.begin() + std::min(static_cast<std::size_t>(offset), text_.size());
    return 1 + static_cast<std::int64_t>(std::count(text_.begin(), end, '\n'));
  }
  std::unexpected<Error> fail_at(const pugi::xml_node& node, ErrorCode code, std::string message) const {
    return make_error(code, std::move(message), file_, line_at(node.offset_debug()));
  }
  Expected<void> read_values(const pugi::xml_node& array, std::int64_t expected, bool integers,
                             std::vector<double>& reals, std::vector<std::int64_t>& ints) const;
  Expected<std::int64_t> count_attribute(const pugi::xml_node& node, const char* name) const;
  std::int64_t value_line(const pugi::xml_node& array, std::int64_t index) const;
  std::unexpected<Error> fail_at_value(const pugi::xml_node& array, std::int64_t index, ErrorCode code,
                                       std::string message) const {
    return make_error(code, std::move(message), file_, value_line(array, index));
  }

  std::string_view text_;
  std::string file_;
};

Expected<std::int64_t> VtuReader::count_attribute(const pugi::xml_node& node, const char* name) const {
  const pugi::xml_attribute attribute = node.attribute(name);
  std::int64_t value = 0;
  if (!attribute) return fail_at(node, ErrorCode::kParse, std::string("missing attribute ") + name);
  if (!detail::parse_int(attribute.value(), value) || value < 0) {
    return fail_at(node, ErrorCode::kParse,
                   std::string("attribute ") + name + "=" + quoted(attribute.value()) + " is not a count");
  }
  // Each value needs at least two characters of text: a bound on any honest count.
  if (!detail::count_fits(value, 2, text_.size())) {
    return fail_at(
        node, ErrorCode::kParse,
        std::string("attribute ") + name + "=" + std::to_string(value) + " is impossible for the file's size");
  }
  return value;
}

/// The first text child of a DataArray (its values), or an empty node.
pugi::xml_node text_child(const pugi::xml_node& array) {
  pugi::xml_node data = array.first_child();
  while (data && data.type() != pugi::node_pcdata && data.type() != pugi::node_cdata) {
    data = data.next_sibling();
  }
  return data;
}

/// The line of the value number `index` (0-based) of a DataArray; only for error messages,
/// so it simply scans the text again.
std::int64_t VtuReader::value_line(const pugi::xml_node& array, std::int64_t index) const {
  const pugi::xml_node data = text_child(array);
  if (!data) return line_at(array.offset_debug());
  detail::Scanner sc(data.value(), file_, '\0', line_at(data.offset_debug()));
  for (std::int64_t i = 0; i <= index; ++i) sc.next();
  return sc.line();
}

/// Parses the text of one DataArray: exactly `expected` numbers, integers or finite reals.
Expected<void> VtuReader::read_values(const pugi::xml_node& array, std::int64_t expected, bool integers,
                                      std::vector<double>& reals, std::vector<std::int64_t>& ints) const {
  const std::string name = array.attribute("Name").value();
  const std::string_view format = array.attribute("format").value();
  if (!format.empty() && format != "ascii") {
    return fail_at(array, ErrorCode::kUnsupported,
                   "DataArray '" + name + "' has format=" + quoted(format) + "; only ascii is supported");
  }
  // Scan the first text child in place, so line numbers count from where it starts.
  const pugi::xml_node data = text_child(array);
  const std::string_view values = data ? data.value() : "";
  detail::Scanner sc(values, file_, '\0', data ? line_at(data.offset_debug()) : line_at(array.offset_debug()));
  if (!detail::count_fits(expected, 2, values.size() + 1)) {
    return fail_at(array, ErrorCode::kParse,
                   "DataArray '" + name + "' should hold " + std::to_string(expected) +
                       " values but its text has only " + std::to_string(values.size()) + " characters");
  }
  if (integers) {
    ints.reserve(static_cast<std::size_t>(expected));
  } else {
    reals.reserve(static_cast<std::size_t>(expected));
  }
  const std::string what = "value of DataArray '" + name + "'";
  for (std::int64_t i = 0; i < expected; ++i) {
    if (sc.at_end()) {
      return fail_at(
          array, ErrorCode::kParse,
          "DataArray '" + name + "' holds " + std::to_string(i) + " values, expected " + std::to_string(expected));
    }
    if (integers) {
      ints.push_back(sc.integer(what));
    } else {
      reals.push_back(sc.real(what));
    }
    if (sc.failed()) {
      sc.add_context("value " + std::to_string(i + 1) + " of " + std::to_string(expected));
      return sc.unexpected_error();
    }
  }
  if (!sc.at_end()) {
    sc.next();
    sc.fail(ErrorCode::kParse,
            "DataArray '" + name + "' holds more than the " + std::to_string(expected) + " values expected");
    return sc.unexpected_error();
  }
  return {};
}

/// The DataArray child of `parent` named `name`, or the first one when `name` is empty.
pugi::xml_node data_array(const pugi::xml_node& parent, const char* name) {
  for (const pugi::xml_node child : parent.children("DataArray")) {
    if (name[0] == '\0' || std::string_view(child.attribute("Name").value()) == name) return child;
  }
  return {};
}

// Reads the file in stages: the document down to its one <Piece>, the points, the cells'
// arrays, the optional regions and normals, then the tetrahedra and triangles kept.
Expected<ReadResult> VtuReader::run() {
  pugi::xml_document doc;
  auto piece = find_piece(doc);
  if (!piece) return std::unexpected(piece.error());
  auto point_count = count_attribute(*piece, "NumberOfPoints");
  if (!point_count) return std::unexpected(point_count.error());
  auto cell_count = count_attribute(*piece, "NumberOfCells");
  if (!cell_count) return std::unexpected(cell_count.error());
  if (*point_count == 0 || *point_count > INT32_MAX) {
    return fail_at(*piece, ErrorCode::kInvalidMesh,
                   "NumberOfPoints=" + std::to_string(*point_count) + " is not usable");
  }

  ReadResult result;
  result.report.format = "vtu";
  if (auto ok = read_points(*piece, *point_count, result.mesh); !ok) return std::unexpected(ok.error());
  auto cells = read_cells(*piece, *cell_count);
  if (!cells) return std::unexpected(cells.error());
  auto regions = read_regions(*piece, *cell_count);
  if (!regions) return std::unexpected(regions.error());
  if (auto ok = read_normals(*piece, *point_count, result.mesh); !ok) return std::unexpected(ok.error());
  if (auto ok = keep_cells(*cells, *regions, *point_count, result); !ok) return std::unexpected(ok.error());
  // The writer stores 0 for "no region"; all zeros means the mesh had none.
  const auto all_zero = [](const std::vector<std::int32_t>& v) {
    return std::all_of(v.begin(), v.end(), [](std::int32_t r) { return r == 0; });
  };
  if (all_zero(result.mesh.tet_regions)) result.mesh.tet_regions.clear();
  if (all_zero(result.mesh.triangle_regions)) result.mesh.triangle_regions.clear();
  return result;
}

// Parses the text into `doc` and finds its one <Piece> of an UnstructuredGrid.
Expected<pugi::xml_node> VtuReader::find_piece(pugi::xml_document& doc) const {
  // Without parse_eol pugixml leaves the text bytes where they were, so offset_debug()
  // gives true positions for line numbers.
  const pugi::xml_parse_result parsed =
      doc.load_buffer(text_.data(), text_.size(), pugi::parse_default & ~pugi::parse_eol, pugi::encoding_utf8);
  if (!parsed) {
    return make_error(ErrorCode::kParse, std::string("not valid XML: ") + parsed.description(), file_,
                      line_at(parsed.offset));
  }
  if (const pugi::xml_node deep = first_too_deep_element(doc)) {
    return make_error(
        ErrorCode::kParse,
        "<" + std::string(deep.name()) + "> is nested deeper than " + std::to_string(kMaxXmlDepth) + " levels", file_,
        line_at(deep.offset_debug()));
  }
  const pugi::xml_node root = doc.child("VTKFile");
  if (!root) {
    return make_error(ErrorCode::kParse, "not a VTK XML file: no <VTKFile> element", file_,
                      line_at(doc.first_child().offset_debug()));
  }
  if (std::string_view(root.attribute("type").value()) != "UnstructuredGrid") {
    return fail_at(root, ErrorCode::kUnsupported,
                   "VTKFile type=" + quoted(root.attribute("type").value()) + "; only UnstructuredGrid is supported");
  }
  const pugi::xml_node grid = root.child("UnstructuredGrid");
  if (!grid) return fail_at(root, ErrorCode::kParse, "no <UnstructuredGrid> element");
  if (grid.child("Piece").next_sibling("Piece")) {
    return fail_at(grid, ErrorCode::kUnsupported, "more than one <Piece>; only one is supported");
  }
  const pugi::xml_node piece = grid.child("Piece");
  if (!piece) return fail_at(grid, ErrorCode::kParse, "no <Piece> element");
  return piece;
}

Expected<void> VtuReader::read_points(const pugi::xml_node& piece, std::int64_t point_count, Mesh& mesh) const {
  const pugi::xml_node points = data_array(piece.child("Points"), "");
  if (!points) return fail_at(piece, ErrorCode::kParse, "no <Points> DataArray");
  if (points.attribute("NumberOfComponents").as_int(1) != 3) {
    return fail_at(points, ErrorCode::kUnsupported, "Points must have NumberOfComponents=\"3\"");
  }
  std::vector<double> reals;
  std::vector<std::int64_t> ints;
  if (auto ok = read_values(points, 3 * point_count, false, reals, ints); !ok) return ok;
  mesh.nodes.resize(static_cast<std::size_t>(point_count));
  for (std::size_t i = 0; i < mesh.nodes.size(); ++i) {
    mesh.nodes[i] = Vec3(reals[3 * i], reals[3 * i + 1], reals[3 * i + 2]);
  }
  return {};
}

// Offsets and types first, since connectivity's length is the last offset.
Expected<VtuReader::Cells> VtuReader::read_cells(const pugi::xml_node& piece, std::int64_t cell_count) const {
  const pugi::xml_node cells = piece.child("Cells");
  Cells out;
  out.offsets_array = data_array(cells, "offsets");
  out.types_array = data_array(cells, "types");
  out.connectivity_array = data_array(cells, "connectivity");
  if (!out.offsets_array || !out.types_array || !out.connectivity_array) {
    return fail_at(cells ? cells : piece, ErrorCode::kParse,
                   "<Cells> needs DataArrays 'connectivity', 'offsets' and 'types'");
  }
  std::vector<double> reals;  // unused: the cells' arrays are integers
  if (auto ok = read_values(out.offsets_array, cell_count, true, reals, out.offsets); !ok)
    return std::unexpected(ok.error());
  if (auto ok = read_values(out.types_array, cell_count, true, reals, out.types); !ok)
    return std::unexpected(ok.error());
  std::int64_t previous = 0;
  for (std::size_t c = 0; c < out.offsets.size(); ++c) {
    if (out.offsets[c] < previous) {
      return fail_at_value(out.offsets_array, static_cast<std::int64_t>(c), ErrorCode::kInvalidMesh,
                           "offsets decrease at cell " + std::to_string(c));
    }
    previous = out.offsets[c];
  }
  if (auto ok = read_values(out.connectivity_array, previous, true, reals, out.connectivity); !ok) {
    return std::unexpected(ok.error());
  }
  return out;
}

// The optional per-cell regions (empty without a CellData "region" array).
Expected<std::vector<std::int64_t>> VtuReader::read_regions(const pugi::xml_node& piece,
                                                            std::int64_t cell_count) const {
  std::vector<std::int64_t> regions;
  if (const pugi::xml_node region_array = data_array(piece.child("CellData"), "region")) {
    std::vector<double> reals;  // unused: regions are integers
    if (auto ok = read_values(region_array, cell_count, true, reals, regions); !ok) {
      return std::unexpected(ok.error());
    }
    for (const std::int64_t r : regions) {
      if (r < INT32_MIN || r > INT32_MAX) {
        const auto index = static_cast<std::int64_t>(&r - regions.data());
        return fail_at_value(region_array, index, ErrorCode::kInvalidMesh,
                             "region " + std::to_string(r) + " does not fit in 32 bits");
      }
    }
  }
  return regions;
}

// The optional per-point normals (a PointData "normals" array).
Expected<void> VtuReader::read_normals(const pugi::xml_node& piece, std::int64_t point_count, Mesh& mesh) const {
  const pugi::xml_node normals_array = data_array(piece.child("PointData"), "normals");
  if (!normals_array) return {};
  if (normals_array.attribute("NumberOfComponents").as_int(1) != 3) {
    return fail_at(normals_array, ErrorCode::kUnsupported, "normals must have NumberOfComponents=\"3\"");
  }
  std::vector<double> reals;
  std::vector<std::int64_t> ints;
  if (auto ok = read_values(normals_array, 3 * point_count, false, reals, ints); !ok) return ok;
  mesh.normals.resize(mesh.nodes.size());
  for (std::size_t i = 0; i < mesh.normals.size(); ++i) {
    mesh.normals[i] = Vec3(reals[3 * i], reals[3 * i + 1], reals[3 * i + 2]);
  }
  return {};
}

// Keeps the tetrahedra and triangles (with their regions) and counts the cells of other
// types, with a warning per type that is neither a point nor a line.
Expected<void> VtuReader::keep_cells(const Cells& cells, const std::vector<std::int64_t>& regions,
                                     std::int64_t point_count, ReadResult& result) const {
  Mesh& mesh = result.mesh;
  std::map<std::int64_t, std::int64_t> other_types;
  std::int64_t begin = 0;
  for (std::size_t c = 0; c < cells.types.size(); ++c) {
    const std::int64_t size = cells.offsets[c] - begin;
    const std::int64_t type = cells.types[c];
    const std::int64_t expected_size = type == kVtkTetra ? 4 : type == kVtkTriangle ? 3 : -1;
    if (expected_size > 0 && size != expected_size) {
      return fail_at_value(cells.offsets_array, static_cast<std::int64_t>(c), ErrorCode::kInvalidMesh,
                           "cell " + std::to_string(c) + " of type " + std::to_string(type) + " has " +
                               std::to_string(size) + " points instead of " + std::to_string(expected_size));
    }
    if (expected_size > 0) {
      std::array<NodeIndex, 4> v{};
      for (std::int64_t k = 0; k < size; ++k) {
        const std::int64_t index = cells.connectivity[static_cast<std::size_t>(begin + k)];
        if (index < 0 || index >= point_count) {
          return fail_at_value(cells.connectivity_array, begin + k, ErrorCode::kInvalidMesh,
                               "cell " + std::to_string(c) + " refers to point " + std::to_string(index) +
                                   ", but there are " + std::to_string(point_count) + " points");
        }
        v[static_cast<std::size_t>(k)] = static_cast<NodeIndex>(index);
      }
      const auto region = static_cast<std::int32_t>(regions.empty() ? 0 : regions[c]);
      if (type == kVtkTetra) {
        mesh.tets.push_back({v[0], v[1], v[2], v[3]});
        mesh.tet_regions.push_back(region);
      } else {
        mesh.triangles.push_back({v[0], v[1], v[2]});
        mesh.triangle_regions.push_back(region);
      }
    } else if (type == kVtkVertex || type == kVtkPolyVertex) {
      ++result.report.ignored_points;
    } else if (type == kVtkLine || type == kVtkPolyLine) {
      ++result.report.ignored_lines;
    } else {
      ++result.report.ignored_other;
      ++other_types[type];
    }
    begin = cells.offsets[c];
  }
  for (const auto& [type, count] : other_types) {
    result.report.warnings.push_back(file_ + ":" + std::to_string(line_at(cells.types_array.offset_debug())) +
                                     ": ignored " + std::to_string(count) + " cell(s) of VTK type " +
                                     std::to_string(type) + "; only tetrahedra (10) and triangles (5) are kept");
  }
  return {};
}

void append_vectors(std::string& out, const std::vector<Vec3>& vectors) {
  for (const Vec3& p : vectors) {
    out += "          ";
    detail::append_real(out, p.x());
    out += ' ';
    detail::append_real(out, p.y());
    out += ' ';
    detail::append_real(out, p.z());
    out += '\n';
  }
}

}  // namespace

Expected<ReadResult> read_vtu(const std::filesystem::path& path) {
  auto text = detail::read_whole_file(path);
  if (!text) return std::unexpected(text.error());
  if (detail::is_blank(*text)) return make_error(ErrorCode::kParse, "file is empty", path.string(), 1);
  return VtuReader(*text, path.string()).run();
}

Expected<void> write_vtu(const Mesh& mesh, const std::filesystem::path& path) {
  if (auto ok = detail::check_mesh_for_write(mesh, path); !ok) return ok;
  const std::size_t cells = mesh.tets.size() + mesh.triangles.size();
  std::string out;
  out.reserve(80 * mesh.nodes.size() * (mesh.normals.empty() ? 1 : 2) + 48 * cells + 1024);
  out +=
      "<?xml version=\"1.0\"?>\n"
      "<VTKFile type=\"UnstructuredGrid\" version=\"1.0\" byte_order=\"LittleEndian\" "
      "header_type=\"UInt64\">\n"
      "  <UnstructuredGrid>\n"
      "    <Piece NumberOfPoints=\"";
  detail::append_int(out, static_cast<std::int64_t>(mesh.nodes.size()));
  out += "\" NumberOfCells=\"";
  detail::append_int(out, static_cast<std::int64_t>(cells));
  out += "\">\n";

  // VTK's schema orders a Piece as PointData, CellData, Points, Cells.
  if (!mesh.normals.empty()) {
    out +=
        "      <PointData Normals=\"normals\">\n"
        "        <DataArray type=\"Float64\" Name=\"normals\" NumberOfComponents=\"3\" format=\"ascii\">\n";
    append_vectors(out, mesh.normals);
    out += "        </DataArray>\n      </PointData>\n";
  }
  if (!mesh.tet_regions.empty() || !mesh.triangle_regions.empty()) {
    out +=
        "      <CellData Scalars=\"region\">\n"
        "        <DataArray type=\"Int32\" Name=\"region\" format=\"ascii\">\n";
    for (std::size_t i = 0; i < mesh.tets.size(); ++i) {
      out += "          ";
      detail::append_int(out, mesh.tet_regions.empty() ? 0 : mesh.tet_regions[i]);
      out += '\n';
    }
    for (std::size_t i = 0; i < mesh.triangles.size(); ++i) {
      out += "          ";
      detail::append_int(out, mesh.triangle_regions.empty() ? 0 : mesh.triangle_regions[i]);
      out += '\n';
    }
    out += "        </DataArray>\n      </CellData>\n";
  }
  out +=
      "      <Points>\n"
      "        <DataArray type=\"Float64\" Name=\"Points\" NumberOfComponents=\"3\" format=\"ascii\">\n";
  append_vectors(out, mesh.nodes);
  out +=
      "        </DataArray>\n      </Points>\n"
      "      <Cells>\n"
      "        <DataArray type=\"Int64\" Name=\"connectivity\" format=\"ascii\">\n";
  const auto append_cell = [&](const NodeIndex* nodes, int n) {
    out += "          ";
    for (int k = 0; k < n; ++k) {
      if (k > 0) out += ' ';
      detail::append_int(out, nodes[k]);
    }
    out += '\n';
  };
  for (const Tet& t : mesh.tets) append_cell(t.data(), 4);
  for (const Tri& t : mesh.triangles) append_cell(t.data(), 3);
  out +=
      "        </DataArray>\n"
      "        <DataArray type=\"Int64\" Name=\"offsets\" format=\"ascii\">\n";
  std::int64_t offset = 0;
  const auto append_offset = [&](std::int64_t size) {
    offset += size;
    out += "          ";
    detail::append_int(out, offset);
    out += '\n';
  };
  for (std::size_t i = 0; i < mesh.tets.size(); ++i) append_offset(4);
  for (std::size_t i = 0; i < mesh.triangles.size(); ++i) append_offset(3);
  out +=
      "        </DataArray>\n"
      "        <DataArray type=\"UInt8\" Name=\"types\" format=\"ascii\">\n";
  for (std::size_t i = 0; i < mesh.tets.size(); ++i) out += "          10\n";
  for (std::size_t i = 0; i < mesh.triangles.size(); ++i) out += "          5\n";
  out +=
      "        </DataArray>\n"
      "      </Cells>\n"
      "    </Piece>\n"
      "  </UnstructuredGrid>\n"
      "</VTKFile>\n";
  return detail::write_whole_file(path, out);
}

}  // namespace hof::mesh
