/// @file
/// STL reading, ASCII or binary. STL stores every triangle with its own three corners;
/// corners at exactly the same position are welded into one node, numbered in order of
/// first appearance, so the result is deterministic and shares nodes like the other formats.
///
/// Binary is recognised by its size (84 + 50 × the count in the header) rather than by the
/// absence of "solid", because some binary exporters start the header with "solid" too.

#include <bit>
#include <cstring>
#include <string>
#include <unordered_map>

#include "hof/mesh/detail/text_reader.h"
#include "hof/mesh/mesh_io.h"

namespace hof::mesh {

namespace {

using detail::quoted;

constexpr std::size_t kHeaderBytes = 80;
constexpr std::size_t kBinaryPrefix = kHeaderBytes + 4;
constexpr std::size_t kBinaryTriangleBytes = 50;

/// Exact-position key; +0.0 is added so -0.0 and 0.0 weld (they are the same point).
struct PositionKey {
  std::array<std::uint64_t, 3> bits;
  friend bool operator==(const PositionKey&, const PositionKey&) = default;
};

struct PositionHash {
  std::size_t operator()(const PositionKey& k) const {
    std::uint64_t h = 0x9e3779b97f4a7c15ull;
    for (const std::uint64_t b : k.bits) h = (h ^ b) * 0x100000001b3ull + (h >> 29);
    return static_cast<std::size_t>(h);
  }
};

/// Collects triangle corners and welds equal positions.
class Welder {
 public:
  explicit Welder(Mesh& mesh) : mesh_(mesh) {}

  NodeIndex add(const Vec3& p) {
    const PositionKey key{{std::bit_cast<std::uint64_t>(p.x() + 0.0), std::bit_cast<std::uint64_t>(p.y() + 0.0),
                           std::bit_cast<std::uint64_t>(p.z() + 0.0)}};
    const auto [it, inserted] = index_.try_emplace(key, static_cast<NodeIndex>(mesh_.nodes.size()));
    if (inserted) mesh_.nodes.push_back(p);
    return it->second;
  }

  void triangle(const Tri& t) {
    if (t[0] == t[1] || t[1] == t[2] || t[0] == t[2]) ++degenerate_;
    mesh_.triangles.push_back(t);
  }

  [[nodiscard]] std::int64_t degenerate() const { return degenerate_; }

 private:
  Mesh& mesh_;
  std::unordered_map<PositionKey, NodeIndex, PositionHash> index_;
  std::int64_t degenerate_{0};
};

std::uint32_t read_le32(const char* p) {
  std::uint32_t v = 0;
  std::memcpy(&v, p, sizeof v);
  if constexpr (std::endian::native == std::endian::big) v = std::byteswap(v);
  return v;
}

float read_le_float(const char* p) { return std::bit_cast<float>(read_le32(p)); }

Expected<ReadResult> read_binary(std::string_view bytes, const std::string& file) {
  ReadResult result;
  result.report.format = "stl-binary";
  const std::size_t count = read_le32(bytes.data() + kHeaderBytes);
  Mesh& mesh = result.mesh;
  mesh.triangles.reserve(count);
  Welder welder(mesh);
  for (std::size_t i = 0; i < count; ++i) {
    // 12 floats: normal (ignored, recomputable), then three corners; then 2 attribute bytes.
    const std::size_t offset = kBinaryPrefix + i * kBinaryTriangleBytes;
    Tri tri{};
    for (std::size_t c = 0; c < 3; ++c) {
      const std::size_t at = offset + 12 + 12 * c;
      const Vec3 p(read_le_float(bytes.data() + at), read_le_float(bytes.data() + at + 4),
                   read_le_float(bytes.data() + at + 8));
      if (!p.allFinite()) {
        return detail::make_byte_error(ErrorCode::kInvalidMesh,
                                       "triangle " + std::to_string(i) + " has a NaN or infinite vertex coordinate",
                                       file, static_cast<std::int64_t>(at));
      }
      tri[c] = welder.add(p);
    }
    welder.triangle(tri);
  }
  if (count == 0) {
    return detail::make_byte_error(ErrorCode::kInvalidMesh, "binary STL holds no triangles", file,
                                   static_cast<std::int64_t>(kHeaderBytes));
  }
  if (welder.degenerate() > 0) {
    result.report.warnings.push_back(file + ": " + std::to_string(welder.degenerate()) +
                                     " triangles have repeated vertices after welding");
  }
  return result;
}

Expected<ReadResult> read_ascii(std::string_view text, const std::string& file) {
  ReadResult result;
  result.report.format = "stl-ascii";
  Mesh& mesh = result.mesh;
  Welder welder(mesh);
  detail::Scanner sc(text, file);
  sc.expect("solid");
  sc.skip_line();  // the solid's name
  while (!sc.failed()) {
    const std::string_view token = sc.next();
    if (detail::iequals(token, "endsolid")) {
      sc.skip_line();  // the name again
      if (sc.at_end()) break;
      // Some files hold several solids one after another.
      sc.expect("solid");
      sc.skip_line();
      continue;
    }
    if (!detail::iequals(token, "facet")) {
      sc.fail(ErrorCode::kParse, token.empty() ? std::string("unexpected end of file: no 'endsolid'")
                                               : "expected 'facet' or 'endsolid', found " + quoted(token));
      break;
    }
    sc.expect("normal");
    // The stored normal is not kept (and some exporters write "nan" there).
    for (int k = 0; k < 3 && !sc.failed(); ++k) {
      if (sc.next().empty()) sc.fail(ErrorCode::kParse, "unexpected end of file in 'facet normal'");
    }
    sc.expect("outer");
    sc.expect("loop");
    Tri tri{};
    for (std::size_t c = 0; c < 3; ++c) {
      sc.expect("vertex");
      const double x = sc.real("vertex x");
      const double y = sc.real("vertex y");
      const double z = sc.real("vertex z");
      if (sc.failed()) break;
      tri[c] = welder.add(Vec3(x, y, z));
    }
    sc.expect("endloop");
    sc.expect("endfacet");
    if (!sc.failed()) welder.triangle(tri);
  }
  if (sc.failed()) return sc.unexpected_error();
  if (mesh.triangles.empty()) {
    return make_error(ErrorCode::kInvalidMesh, "ASCII STL holds no facets", file, sc.line());
  }
  if (welder.degenerate() > 0) {
    result.report.warnings.push_back(file + ": " + std::to_string(welder.degenerate()) +
                                     " triangles have repeated vertices after welding");
  }
  return result;
}

}  // namespace

Expected<ReadResult> read_stl(const std::filesystem::path& path) {
  auto bytes = detail::read_whole_file(path);
  if (!bytes) return std::unexpected(bytes.error());
  const std::string file = path.string();
  const std::string_view data = *bytes;
  if (data.empty()) return make_error(ErrorCode::kParse, "file is empty", file, 1);

  if (data.size() >= kBinaryPrefix) {
    const std::uint64_t count = read_le32(data.data() + kHeaderBytes);
    if (kBinaryPrefix + kBinaryTriangleBytes * count == data.size()) return read_binary(data, file);
  }
  const std::size_t first = data.find_first_not_of(" \t\r\n\v\f");
  if (first == std::string_view::npos) return make_error(ErrorCode::kParse, "file is empty", file, 1);
  const std::string_view start = data.substr(first, 5);
  if (detail::iequals(start, "solid")) return read_ascii(data, file);
  if (data.size() >= kBinaryPrefix) {
    const std::uint64_t count = read_le32(data.data() + kHeaderBytes);
    return detail::make_byte_error(ErrorCode::kParse,
                                   "not an STL file: it does not start with 'solid' (ASCII) and its size " +
                                       std::to_string(data.size()) + " does not match a binary STL of " +
                                       std::to_string(count) + " triangles (" +
                                       std::to_string(kBinaryPrefix + kBinaryTriangleBytes * count) + " bytes)",
                                   file, static_cast<std::int64_t>(kHeaderBytes));
  }
  return make_error(ErrorCode::kParse,
                    "not an STL file: it does not start with 'solid' and is too short (" + std::to_string(data.size()) +
                        " bytes) for a binary STL",
                    file, 1);
}

}  // namespace hof::mesh
