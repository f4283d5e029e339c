/// @file
/// Gmsh .msh reading (v1 `$NOD`/`$ELM`, v2.x ASCII and binary, v4.1 ASCII); the writers
/// (v2.2 and v4.1 ASCII) are in io_msh_write.cpp.
///
/// The whole file is read into memory and scanned token by token. Node tags are mapped to
/// 0-based indices in the order the nodes appear. Linear tetrahedra (type 4) and triangles
/// (type 2) are kept with their region (v1: reg-phys, v2: first tag, v4: entity tag); points
/// and lines are counted; other known types are counted with one warning per type; an
/// unknown type number is an error. Every count is checked against the bytes left in the
/// file before it sizes anything.

#include <algorithm>
#include <array>
#include <bit>
#include <climits>
#include <cstring>
#include <limits>
#include <map>
#include <string>
#include <utility>
#include <vector>

#include "hof/mesh/detail/msh_element_types.h"
#include "hof/mesh/detail/msh_tag_map.h"
#include "hof/mesh/detail/text_reader.h"
#include "hof/mesh/mesh_io.h"

namespace hof::mesh {

namespace {

using detail::count_fits;
using detail::element_info;
using detail::ElementInfo;
using detail::ElementKind;
using detail::iequals;
using detail::kMaxElementNodes;
using detail::quoted;
using detail::Scanner;
using detail::TagMap;

// ---------------------------------------------------------------------------------------
// Reader

enum class Flavor : std::uint8_t { kV1, kV2Ascii, kV2Binary, kV41Ascii };

/// Where the first ignored element of one type was, and how many there were.
struct IgnoredType {
  std::int64_t count{0};
  std::int64_t line{0};
  std::int64_t byte_offset{-1};
};

class MshReader {
 public:
  MshReader(std::string_view text, std::string file, const ProgressSink& progress)
      : sc_(text, std::move(file)), progress_(progress), task_("Reading " + sc_.file()) {}

  Expected<ReadResult> run();

 private:
  void read_format();
  void handle_section(std::string_view name);
  void skip_section(std::string_view name);
  void read_nodes_v12(std::string_view end_marker);
  void read_nodes_v2_binary();
  void read_nodes_v41();
  void read_elements_v1();
  void read_elements_v2();
  void read_elements_v2_binary();
  void read_elements_v41();
  void finish_nodes(std::string_view end_marker, std::int64_t section_line);
  void expect_end(std::string_view end_marker, const std::string& what);
  ElementInfo check_type(std::int64_t type, std::size_t byte_offset);
  void add_element(std::int64_t type, const ElementInfo& info, std::int64_t region, const std::int64_t* node_tags,
                   std::size_t byte_offset);
  void add_count_context(std::int64_t index, std::int64_t count, const char* what, const char* section);
  void tick();

  std::int32_t read_i32(std::size_t pos) const {
    std::uint32_t raw = 0;
    std::memcpy(&raw, sc_.text().data() + pos, sizeof raw);
    if (swap_) raw = std::byteswap(raw);
    return static_cast<std::int32_t>(raw);
  }
  double read_f64(std::size_t pos) const {
    std::uint64_t raw = 0;
    std::memcpy(&raw, sc_.text().data() + pos, sizeof raw);
    if (swap_) raw = std::byteswap(raw);
    return std::bit_cast<double>(raw);
  }

  /// Continues scanning at `pos` after a binary block, counting the newline bytes it held so
  /// line numbers mentioned in later messages stay physical lines.
  void jump_over_binary(std::size_t pos) {
    const auto begin = sc_.text().begin();
    sc_.jump_to(pos, std::count(begin + static_cast<std::ptrdiff_t>(sc_.pos()),
                                begin + static_cast<std::ptrdiff_t>(pos), '\n'));
  }

  static constexpr std::size_t kNoByte = static_cast<std::size_t>(-1);

  Scanner sc_;
  const ProgressSink& progress_;
  std::string task_;
  Flavor flavor_{Flavor::kV1};
  bool swap_{false};
  ReadResult result_;
  std::vector<std::int64_t> node_tags_;
  TagMap tag_map_;
  bool have_nodes_{false};
  bool have_elements_{false};
  std::map<std::int64_t, IgnoredType> ignored_;
  std::vector<std::int64_t> element_nodes_ = std::vector<std::int64_t>(kMaxElementNodes);
  std::uint32_t ticks_{0};
};

void MshReader::tick() {
  // A progress call per 64k entries keeps its cost invisible next to the parsing.
  if (progress_ && (++ticks_ & 0xffffu) == 0) {
    progress_(task_, static_cast<double>(sc_.pos()) / static_cast<double>(sc_.text().size()));
  }
}

void MshReader::add_count_context(std::int64_t index, std::int64_t count, const char* what, const char* section) {
  std::string context =
      std::string(what) + " " + std::to_string(index + 1) + " of " + std::to_string(count) + " in " + section;
  // A section marker where data was expected means the section is shorter than its count.
  if (sc_.token_start() < sc_.text().size() && sc_.text()[sc_.token_start()] == '$') {
    context += "; the section ends early, so its count is wrong";
  }
  sc_.add_context(context);
}

Expected<ReadResult> MshReader::run() {
  if (progress_) progress_(task_, 0.0);
  std::string_view first = sc_.next();
  if (first.starts_with("\xEF\xBB\xBF")) first.remove_prefix(3);  // UTF-8 byte-order mark
  if (first == "$NOD") {
    flavor_ = Flavor::kV1;
    result_.report.format = "gmsh-1";
    handle_section(first);
  } else if (first == "$MeshFormat") {
    read_format();
  } else {
    sc_.fail(ErrorCode::kParse, "not a Gmsh mesh file: expected $MeshFormat or $NOD, found " + quoted(first));
  }
  while (!sc_.failed()) {
    const std::string_view name = sc_.next();
    if (name.empty()) break;
    if (name.front() != '$') {
      sc_.fail(ErrorCode::kParse, "expected a section such as $Nodes or $Elements, found " + quoted(name));
      break;
    }
    handle_section(name);
  }
  if (sc_.failed()) return sc_.unexpected_error();
  if (!have_nodes_) {
    return make_error(ErrorCode::kInvalidMesh,
                      flavor_ == Flavor::kV1 ? "no $NOD section: the file holds no nodes"
                                             : "no $Nodes section: the file holds no nodes",
                      sc_.file(), sc_.line());
  }

  Mesh& mesh = result_.mesh;
  // Gmsh writes tag 0 for "no physical group": all zeros means the file has no regions.
  const auto all_zero = [](const std::vector<std::int32_t>& v) {
    return std::all_of(v.begin(), v.end(), [](std::int32_t r) { return r == 0; });
  };
  if (all_zero(mesh.tet_regions)) mesh.tet_regions.clear();
  if (all_zero(mesh.triangle_regions)) mesh.triangle_regions.clear();

  for (const auto& [type, ignored] : ignored_) {
    std::string where = sc_.file();
    where +=
        ignored.byte_offset >= 0 ? ": byte " + std::to_string(ignored.byte_offset) : ":" + std::to_string(ignored.line);
    result_.report.warnings.push_back(
        where + ": ignored " + std::to_string(ignored.count) + " element(s) of Gmsh type " + std::to_string(type) +
        " (" + std::to_string(element_info(type).nodes) +
        " nodes); only 3-node triangles (type 2) and 4-node tetrahedra (type 4) are kept");
  }
  if (progress_) progress_(task_, 1.0);
  return std::move(result_);
}

void MshReader::read_format() {
  const std::int64_t format_line = sc_.line();
  const std::string_view version_token = sc_.next();
  double version = 0.0;
  if (detail::parse_real(version_token, version) != detail::RealParse::kOk) {
    sc_.fail(ErrorCode::kParse, "expected the Gmsh format version (e.g. 2.2 or 4.1), found " + quoted(version_token));
    return;
  }
  const std::int64_t file_type = sc_.integer("file type (0 = ASCII, 1 = binary)");
  const std::int64_t data_size = sc_.integer("data size");
  if (sc_.failed()) return;
  if (file_type != 0 && file_type != 1) {
    sc_.fail(ErrorCode::kParse, "file type must be 0 (ASCII) or 1 (binary), found " + std::to_string(file_type));
    return;
  }
  const bool binary = file_type == 1;
  if (version >= 2.0 && version < 3.0) {
    flavor_ = binary ? Flavor::kV2Binary : Flavor::kV2Ascii;
  } else if (version == 4.1) {
    flavor_ = Flavor::kV41Ascii;
    if (binary) {
      sc_.fail(ErrorCode::kUnsupported,
               "binary Gmsh 4.1 files are not supported; save the mesh as ASCII (Mesh.Binary = 0)");
      return;
    }
  } else {
    sc_.fail(ErrorCode::kUnsupported,
             "Gmsh format version " + std::string(version_token) + " is not supported (readable: 1, 2.x, 4.1)");
    return;
  }
  if (data_size != 8) {
    sc_.fail(ErrorCode::kUnsupported,
             "data size " + std::to_string(data_size) + " is not supported (only 8-byte doubles)");
    return;
  }
  result_.report.format = "gmsh-" + std::string(version_token) + (binary ? "-binary" : "-ascii");

  if (binary) {
    // A binary int 1 follows the header line; read back swapped it reveals the byte order.
    sc_.skip_line();
    const std::size_t pos = sc_.pos();
    if (sc_.bytes_left() < 4) {
      sc_.fail_at_byte(ErrorCode::kParse, "unexpected end of file in $MeshFormat", pos);
      return;
    }
    const std::int32_t one = read_i32(pos);
    if (one == std::byteswap(std::int32_t{1})) {
      swap_ = true;
    } else if (one != 1) {
      sc_.fail_at_byte(ErrorCode::kParse, "bad byte-order marker in binary $MeshFormat", pos);
      return;
    }
    sc_.jump_to(pos + 4, 0);
    sc_.set_binary(true);
  }
  expect_end("$EndMeshFormat", "$MeshFormat section (line " + std::to_string(format_line) + ")");
}

void MshReader::handle_section(std::string_view name) {
  const bool is_nodes = flavor_ == Flavor::kV1 ? name == "$NOD" : name == "$Nodes";
  const bool is_elements = flavor_ == Flavor::kV1 ? name == "$ELM" : name == "$Elements";
  if (is_nodes) {
    if (have_nodes_) {
      sc_.fail(ErrorCode::kUnsupported, "a second node section: only one is supported");
      return;
    }
    switch (flavor_) {
      case Flavor::kV1:
        read_nodes_v12("$ENDNOD");
        break;
      case Flavor::kV2Ascii:
        read_nodes_v12("$EndNodes");
        break;
      case Flavor::kV2Binary:
        read_nodes_v2_binary();
        break;
      case Flavor::kV41Ascii:
        read_nodes_v41();
        break;
    }
    have_nodes_ = !sc_.failed();
  } else if (is_elements) {
    if (!have_nodes_) {
      sc_.fail(ErrorCode::kParse, std::string(name) + " comes before the node section");
      return;
    }
    if (have_elements_) {
      sc_.fail(ErrorCode::kUnsupported, "a second element section: only one is supported");
      return;
    }
    switch (flavor_) {
      case Flavor::kV1:
        read_elements_v1();
        break;
      case Flavor::kV2Ascii:
        read_elements_v2();
        break;
      case Flavor::kV2Binary:
        read_elements_v2_binary();
        break;
      case Flavor::kV41Ascii:
        read_elements_v41();
        break;
    }
    have_elements_ = true;
  } else {
    // $Entities, $PhysicalNames, $NodeData, ...: nothing HoF keeps.
    skip_section(name);
  }
}

void MshReader::skip_section(std::string_view name) {
  const std::string end_marker = "$End" + std::string(name.substr(1));
  const std::string_view text = sc_.text();
  const std::int64_t section_line = sc_.line();
  // Find the end marker at the start of a line; the content may be binary, so search the
  // bytes rather than tokenizing them.
  std::size_t p = sc_.pos();
  while (true) {
    const std::size_t newline = text.find('\n', p);
    if (newline == std::string_view::npos) break;
    const std::size_t start = newline + 1;
    const std::size_t end = start + end_marker.size();
    if (end <= text.size() && iequals(text.substr(start, end_marker.size()), end_marker) &&
        (end == text.size() || detail::is_space(text[end]))) {
      const auto newlines = std::count(text.begin() + static_cast<std::ptrdiff_t>(sc_.pos()),
                                       text.begin() + static_cast<std::ptrdiff_t>(end), '\n');
      sc_.jump_to(end, static_cast<std::int64_t>(newlines));
      return;
    }
    p = start;
  }
  sc_.fail(ErrorCode::kParse, "unexpected end of file: section " + std::string(name) + " (line " +
                                  std::to_string(section_line) + ") is not closed by " + end_marker);
}

void MshReader::expect_end(std::string_view end_marker, const std::string& what) {
  if (sc_.failed()) return;
  const std::string_view token = sc_.next();
  if (iequals(token, end_marker)) return;
  if (token.empty()) {
    sc_.fail(ErrorCode::kParse, "unexpected end of file: " + what + " is not closed by " + std::string(end_marker));
  } else {
    sc_.fail(ErrorCode::kParse, "expected " + std::string(end_marker) + " to close " + what + ", found " +
                                    quoted(token) + "; the count is wrong");
  }
}

void MshReader::finish_nodes(std::string_view end_marker, std::int64_t section_line) {
  expect_end(end_marker, "the node section (line " + std::to_string(section_line) + ")");
  if (sc_.failed()) return;
  std::int64_t duplicate = 0;
  if (!tag_map_.build(node_tags_, duplicate)) {
    sc_.fail(ErrorCode::kInvalidMesh, "node tag " + std::to_string(duplicate) +
                                          " appears more than once in the node section (line " +
                                          std::to_string(section_line) + ")");
  }
}

/// v1 `$NOD` and v2 ASCII `$Nodes`: a count, then "tag x y z" per node.
void MshReader::read_nodes_v12(std::string_view end_marker) {
  const std::int64_t section_line = sc_.line();
  const std::int64_t count = sc_.integer("node count");
  if (sc_.failed()) return;
  // Shortest node line: "1 0 0 0\n".
  if (!count_fits(count, 8, sc_.bytes_left()) || count > INT32_MAX) {
    sc_.fail(ErrorCode::kParse, detail::impossible_count("node count", count, 8, sc_.bytes_left()));
    return;
  }
  auto& nodes = result_.mesh.nodes;
  nodes.reserve(static_cast<std::size_t>(count));
  node_tags_.reserve(static_cast<std::size_t>(count));
  for (std::int64_t i = 0; i < count; ++i) {
    const std::int64_t tag = sc_.integer("node tag");
    const double x = sc_.real("x coordinate");
    const double y = sc_.real("y coordinate");
    const double z = sc_.real("z coordinate");
    if (!sc_.failed() && tag < 0) {
      sc_.fail(ErrorCode::kInvalidMesh, "node tag " + std::to_string(tag) + " is negative");
    }
    if (sc_.failed()) {
      add_count_context(i, count, "node", "the node section");
      return;
    }
    node_tags_.push_back(tag);
    nodes.emplace_back(x, y, z);
    tick();
  }
  finish_nodes(end_marker, section_line);
}

/// v2 binary `$Nodes`: an ASCII count line, then per node int32 tag + 3 doubles.
void MshReader::read_nodes_v2_binary() {
  const std::int64_t section_line = sc_.line();
  const std::int64_t count = sc_.integer("node count");
  if (sc_.failed()) return;
  constexpr std::int64_t kNodeBytes = 4 + 3 * 8;
  sc_.skip_line();
  const std::size_t start = sc_.pos();
  if (!count_fits(count, kNodeBytes, sc_.bytes_left()) || count > INT32_MAX) {
    sc_.fail(ErrorCode::kParse, detail::impossible_count("node count", count, kNodeBytes, sc_.bytes_left()));
    return;
  }
  auto& nodes = result_.mesh.nodes;
  nodes.reserve(static_cast<std::size_t>(count));
  node_tags_.reserve(static_cast<std::size_t>(count));
  std::size_t pos = start;
  for (std::int64_t i = 0; i < count; ++i, pos += kNodeBytes) {
    const std::int32_t tag = read_i32(pos);
    const Vec3 p(read_f64(pos + 4), read_f64(pos + 12), read_f64(pos + 20));
    if (tag < 0) {
      sc_.fail_at_byte(ErrorCode::kInvalidMesh, "node tag " + std::to_string(tag) + " is negative", pos);
      return;
    }
    if (!p.allFinite()) {
      sc_.fail_at_byte(ErrorCode::kInvalidMesh, "node " + std::to_string(tag) + " has a NaN or infinite coordinate",
                       pos);
      return;
    }
    node_tags_.push_back(tag);
    nodes.push_back(p);
    tick();
  }
  jump_over_binary(pos);
  finish_nodes("$EndNodes", section_line);
}

/// v4.1 `$Nodes`: a header, then per entity block all its tags followed by all its
/// coordinates (plus parametric coordinates when the block says so).
void MshReader::read_nodes_v41() {
  const std::int64_t section_line = sc_.line();
  const std::int64_t blocks = sc_.integer("number of node entity blocks");
  const std::int64_t count = sc_.integer("number of nodes");
  sc_.integer("minimum node tag");
  sc_.integer("maximum node tag");
  if (sc_.failed()) return;
  // Shortest block header "0 1 0 1\n"; shortest node "1\n" + "0 0 0\n".
  if (!count_fits(blocks, 8, sc_.bytes_left())) {
    sc_.fail(ErrorCode::kParse, detail::impossible_count("node block count", blocks, 8, sc_.bytes_left()));
    return;
  }
  if (!count_fits(count, 8, sc_.bytes_left()) || count > INT32_MAX) {
    sc_.fail(ErrorCode::kParse, detail::impossible_count("node count", count, 8, sc_.bytes_left()));
    return;
  }
  auto& nodes = result_.mesh.nodes;
  nodes.reserve(static_cast<std::size_t>(count));
  node_tags_.reserve(static_cast<std::size_t>(count));
  std::int64_t read = 0;
  for (std::int64_t b = 0; b < blocks; ++b) {
    const std::int64_t dim = sc_.integer("entity dimension");
    sc_.integer("entity tag");
    const std::int64_t parametric = sc_.integer("parametric flag");
    const std::int64_t in_block = sc_.integer("number of nodes in block");
    if (!sc_.failed() && (dim < 0 || dim > 3 || parametric < 0 || parametric > 1)) {
      sc_.fail(ErrorCode::kParse, "bad node block header: dimension " + std::to_string(dim) + ", parametric " +
                                      std::to_string(parametric));
    }
    if (!sc_.failed() && (in_block < 0 || in_block > count - read)) {
      sc_.fail(ErrorCode::kParse, "node blocks hold more than the " + std::to_string(count) +
                                      " nodes the $Nodes header announces; the count is wrong");
    }
    if (sc_.failed()) {
      add_count_context(b, blocks, "node block", "$Nodes");
      return;
    }
    for (std::int64_t i = 0; i < in_block; ++i) {
      const std::int64_t tag = sc_.integer("node tag");
      if (!sc_.failed() && tag < 0) {
        sc_.fail(ErrorCode::kInvalidMesh, "node tag " + std::to_string(tag) + " is negative");
      }
      if (sc_.failed()) {
        add_count_context(read + i, count, "node tag", "$Nodes");
        return;
      }
      node_tags_.push_back(tag);
    }
    const std::int64_t extra = parametric == 1 ? dim : 0;
    for (std::int64_t i = 0; i < in_block; ++i) {
      const double x = sc_.real("x coordinate");
      const double y = sc_.real("y coordinate");
      const double z = sc_.real("z coordinate");
      for (std::int64_t k = 0; k < extra; ++k) sc_.real("parametric coordinate");
      if (sc_.failed()) {
        add_count_context(read + i, count, "node coordinates", "$Nodes");
        return;
      }
      nodes.emplace_back(x, y, z);
      tick();
    }
    read += in_block;
  }
  if (read != count) {
    sc_.fail(ErrorCode::kParse, "node blocks hold " + std::to_string(read) + " nodes but the $Nodes header announces " +
                                    std::to_string(count) + "; the count is wrong");
    return;
  }
  finish_nodes("$EndNodes", section_line);
}

ElementInfo MshReader::check_type(std::int64_t type, std::size_t byte_offset) {
  const ElementInfo info = element_info(type);
  std::string message;
  ErrorCode code = ErrorCode::kParse;
  if (info.kind == ElementKind::kUnknown) {
    message = "unknown Gmsh element type " + std::to_string(type);
  } else if (info.kind == ElementKind::kUnsupported) {
    code = ErrorCode::kUnsupported;
    message = "Gmsh element type " + std::to_string(type) + " (polygon, polyhedron or sub-element) is not supported";
  } else {
    return info;
  }
  if (byte_offset == kNoByte) {
    sc_.fail(code, message);
  } else {
    sc_.fail_at_byte(code, message, byte_offset);
  }
  return {};
}

void MshReader::add_element(std::int64_t type, const ElementInfo& info, std::int64_t region,
                            const std::int64_t* node_tags, std::size_t byte_offset) {
  const auto fail = [&](ErrorCode code, std::string message) {
    if (byte_offset == kNoByte) {
      sc_.fail(code, std::move(message));
    } else {
      sc_.fail_at_byte(code, std::move(message), byte_offset);
    }
  };
  // Node tags → indices; false (after failing) when a tag names no node.
  const auto map_nodes = [&](NodeIndex* out, int n) {
    for (int k = 0; k < n; ++k) {
      out[k] = tag_map_.find(node_tags[k]);
      if (out[k] < 0) {
        fail(ErrorCode::kInvalidMesh,
             "element refers to node tag " + std::to_string(node_tags[k]) + ", which is not in the node section");
        return false;
      }
    }
    return true;
  };
  if ((info.kind == ElementKind::kTet || info.kind == ElementKind::kTriangle) &&
      (region < INT32_MIN || region > INT32_MAX)) {
    fail(ErrorCode::kInvalidMesh, "region tag " + std::to_string(region) + " does not fit in 32 bits");
    return;
  }
  Mesh& mesh = result_.mesh;
  switch (info.kind) {
    case ElementKind::kTet: {
      Tet tet{};
      if (!map_nodes(tet.data(), 4)) return;
      mesh.tets.push_back(tet);
      mesh.tet_regions.push_back(static_cast<std::int32_t>(region));
      break;
    }
    case ElementKind::kTriangle: {
      Tri tri{};
      if (!map_nodes(tri.data(), 3)) return;
      mesh.triangles.push_back(tri);
      mesh.triangle_regions.push_back(static_cast<std::int32_t>(region));
      break;
    }
    case ElementKind::kPoint:
      ++result_.report.ignored_points;
      break;
    case ElementKind::kLine:
      ++result_.report.ignored_lines;
      break;
    case ElementKind::kOther: {
      ++result_.report.ignored_other;
      IgnoredType& ignored = ignored_[type];
      if (ignored.count++ == 0) {
        ignored.line = byte_offset == kNoByte ? sc_.line() : 0;
        ignored.byte_offset = byte_offset == kNoByte ? -1 : static_cast<std::int64_t>(byte_offset);
      }
      break;
    }
    case ElementKind::kUnknown:
    case ElementKind::kUnsupported:
      break;  // rejected by check_type
  }
}

/// v1 `$ELM`: "number type reg-phys reg-elem node-count nodes..." per element.
void MshReader::read_elements_v1() {
  const std::int64_t section_line = sc_.line();
  const std::int64_t count = sc_.integer("element count");
  if (sc_.failed()) return;
  // Shortest element line: "1 15 0 0 1 1\n".
  if (!count_fits(count, 12, sc_.bytes_left())) {
    sc_.fail(ErrorCode::kParse, detail::impossible_count("element count", count, 12, sc_.bytes_left()));
    return;
  }
  for (std::int64_t i = 0; i < count; ++i) {
    sc_.integer("element number");
    const std::int64_t type = sc_.integer("element type");
    const std::int64_t physical = sc_.integer("physical region");
    sc_.integer("elementary region");
    const std::int64_t node_count = sc_.integer("number of nodes");
    ElementInfo info;
    if (!sc_.failed()) info = check_type(type, kNoByte);
    if (!sc_.failed() && node_count != info.nodes) {
      sc_.fail(ErrorCode::kParse, "element of type " + std::to_string(type) + " has " + std::to_string(info.nodes) +
                                      " nodes, the line says " + std::to_string(node_count));
    }
    for (int k = 0; k < info.nodes && !sc_.failed(); ++k) {
      element_nodes_[static_cast<std::size_t>(k)] = sc_.integer("node number");
    }
    if (!sc_.failed()) add_element(type, info, physical, element_nodes_.data(), kNoByte);
    if (sc_.failed()) {
      add_count_context(i, count, "element", "$ELM");
      return;
    }
    tick();
  }
  expect_end("$ENDELM", "$ELM section (line " + std::to_string(section_line) + ")");
}

/// v2 ASCII `$Elements`: "number type tag-count tags... nodes..." per element.
void MshReader::read_elements_v2() {
  const std::int64_t section_line = sc_.line();
  const std::int64_t count = sc_.integer("element count");
  if (sc_.failed()) return;
  // Shortest element line: "1 15 0 1\n".
  if (!count_fits(count, 8, sc_.bytes_left())) {
    sc_.fail(ErrorCode::kParse, detail::impossible_count("element count", count, 8, sc_.bytes_left()));
    return;
  }
  for (std::int64_t i = 0; i < count; ++i) {
    sc_.integer("element number");
    const std::int64_t type = sc_.integer("element type");
    const std::int64_t tag_count = sc_.integer("number of tags");
    ElementInfo info;
    if (!sc_.failed()) info = check_type(type, kNoByte);
    if (!sc_.failed() && (tag_count < 0 || !count_fits(tag_count, 2, sc_.bytes_left()))) {
      sc_.fail(ErrorCode::kParse, "impossible number of tags " + std::to_string(tag_count));
    }
    std::int64_t region = 0;
    for (std::int64_t t = 0; t < tag_count && !sc_.failed(); ++t) {
      const std::int64_t value = sc_.integer("element tag");
      if (t == 0) region = value;
    }
    for (int k = 0; k < info.nodes && !sc_.failed(); ++k) {
      element_nodes_[static_cast<std::size_t>(k)] = sc_.integer("node tag");
    }
    if (!sc_.failed()) add_element(type, info, region, element_nodes_.data(), kNoByte);
    if (sc_.failed()) {
      add_count_context(i, count, "element", "$Elements");
      return;
    }
    tick();
  }
  expect_end("$EndElements", "$Elements section (line " + std::to_string(section_line) + ")");
}

/// v2 binary `$Elements`: an ASCII count line, then blocks of one type, each a header
/// (type, element count, tag count) followed by per element: number, tags, node tags.
void MshReader::read_elements_v2_binary() {
  const std::int64_t section_line = sc_.line();
  const std::int64_t count = sc_.integer("element count");
  if (sc_.failed()) return;
  sc_.skip_line();
  const std::string_view text = sc_.text();
  // Smallest element: number + one node, 8 bytes.
  if (!count_fits(count, 8, sc_.bytes_left())) {
    sc_.fail(ErrorCode::kParse, detail::impossible_count("element count", count, 8, sc_.bytes_left()));
    return;
  }
  std::size_t pos = sc_.pos();
  std::int64_t read = 0;
  while (read < count) {
    if (text.size() - pos < 12) {
      sc_.fail_at_byte(ErrorCode::kParse, "unexpected end of file in a binary element block header", pos);
      return;
    }
    const std::int64_t type = read_i32(pos);
    const std::int64_t in_block = read_i32(pos + 4);
    const std::int64_t tag_count = read_i32(pos + 8);
    const ElementInfo info = check_type(type, pos);
    if (sc_.failed()) return;
    if (in_block <= 0 || in_block > count - read || tag_count < 0) {
      sc_.fail_at_byte(ErrorCode::kParse,
                       "bad binary element block header: " + std::to_string(in_block) + " elements with " +
                           std::to_string(tag_count) + " tags (" + std::to_string(count - read) +
                           " elements left to read)",
                       pos);
      return;
    }
    pos += 12;
    const std::int64_t element_bytes = 4 * (1 + tag_count + info.nodes);
    if (!count_fits(in_block, element_bytes, text.size() - pos)) {
      sc_.fail_at_byte(
          ErrorCode::kParse,
          "unexpected end of file: a binary element block of " + std::to_string(in_block) + " elements is cut off",
          pos);
      return;
    }
    for (std::int64_t e = 0; e < in_block; ++e) {
      const std::size_t element_start = pos;
      pos += 4;  // element number
      const std::int64_t region = tag_count > 0 ? read_i32(pos) : 0;
      pos += static_cast<std::size_t>(4 * tag_count);
      for (int k = 0; k < info.nodes; ++k, pos += 4) {
        element_nodes_[static_cast<std::size_t>(k)] = read_i32(pos);
      }
      add_element(type, info, region, element_nodes_.data(), element_start);
      if (sc_.failed()) return;
      tick();
    }
    read += in_block;
  }
  jump_over_binary(pos);
  expect_end("$EndElements", "$Elements section (line " + std::to_string(section_line) + ")");
}

/// v4.1 `$Elements`: a header, then per entity block "dim tag type count" and per element
/// "tag nodes...". The entity tag is the region.
void MshReader::read_elements_v41() {
  const std::int64_t section_line = sc_.line();
  const std::int64_t blocks = sc_.integer("number of element entity blocks");
  const std::int64_t count = sc_.integer("number of elements");
  sc_.integer("minimum element tag");
  sc_.integer("maximum element tag");
  if (sc_.failed()) return;
  // Shortest block header "0 1 15 1\n"; shortest element "1 1\n".
  if (!count_fits(blocks, 8, sc_.bytes_left())) {
    sc_.fail(ErrorCode::kParse, detail::impossible_count("element block count", blocks, 8, sc_.bytes_left()));
    return;
  }
  if (!count_fits(count, 4, sc_.bytes_left())) {
    sc_.fail(ErrorCode::kParse, detail::impossible_count("element count", count, 4, sc_.bytes_left()));
    return;
  }
  std::int64_t read = 0;
  for (std::int64_t b = 0; b < blocks; ++b) {
    const std::int64_t dim = sc_.integer("entity dimension");
    const std::int64_t entity = sc_.integer("entity tag");
    const std::int64_t type = sc_.integer("element type");
    const std::int64_t in_block = sc_.integer("number of elements in block");
    ElementInfo info;
    if (!sc_.failed()) info = check_type(type, kNoByte);
    if (!sc_.failed() && (dim < 0 || dim > 3)) {
      sc_.fail(ErrorCode::kParse, "bad element block header: dimension " + std::to_string(dim));
    }
    if (!sc_.failed() && (in_block < 0 || in_block > count - read)) {
      sc_.fail(ErrorCode::kParse, "element blocks hold more than the " + std::to_string(count) +
                                      " elements the $Elements header announces; the count is wrong");
    }
    if (sc_.failed()) {
      add_count_context(b, blocks, "element block", "$Elements");
      return;
    }
    for (std::int64_t e = 0; e < in_block; ++e) {
      sc_.integer("element tag");
      for (int k = 0; k < info.nodes && !sc_.failed(); ++k) {
        element_nodes_[static_cast<std::size_t>(k)] = sc_.integer("node tag");
      }
      if (!sc_.failed()) add_element(type, info, entity, element_nodes_.data(), kNoByte);
      if (sc_.failed()) {
        add_count_context(read + e, count, "element", "$Elements");
        return;
      }
      tick();
    }
    read += in_block;
  }
  if (read != count) {
    sc_.fail(ErrorCode::kParse, "element blocks hold " + std::to_string(read) +
                                    " elements but the $Elements header announces " + std::to_string(count) +
                                    "; the count is wrong");
    return;
  }
  expect_end("$EndElements", "$Elements section (line " + std::to_string(section_line) + ")");
}

}  // namespace

Expected<ReadResult> read_msh(const std::filesystem::path& path, const ProgressSink& progress) {
  auto text = detail::read_whole_file(path);
  if (!text) return std::unexpected(text.error());
  if (detail::is_blank(*text)) return make_error(ErrorCode::kParse, "file is empty", path.string(), 1);
  return MshReader(*text, path.string(), progress).run();
}

}  // namespace hof::mesh
