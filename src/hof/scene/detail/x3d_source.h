#pragma once
/// @file
/// The X3D files a scene is read from, as the reader sees them: the scene's XML, the files its
/// Inlines name and the PROTO bodies it instantiates, each a parsed document with its own DEF
/// names; what a USE or a ProtoInstance stands for; and field values read from a node, every
/// failure raised with the file and line of the node it concerns (X3dParseFailure, turned
/// into an hof::Error by read_x3d_scene, the single entry point).

#include <filesystem>
#include <initializer_list>
#include <map>
#include <memory>
#include <string>
#include <string_view>
#include <utility>
#include <vector>

#include <fmt/format.h>
#include <pugixml.hpp>

#include "hof/core/error.h"
#include "hof/core/types.h"

namespace hof::scene::detail {

/// How a failure deep in the reader reaches read_x3d_scene.
struct X3dParseFailure {
  Error error;
};

/// Whitespace- or comma-separated tokens (X3D's MF field encoding).
[[nodiscard]] std::vector<std::string_view> x3d_tokens(std::string_view text);
/// The strings of an MFString field: `"a" "b"` (X3D XML encoding), or one unquoted value.
[[nodiscard]] std::vector<std::string> x3d_mf_string(std::string_view text);
/// A url HoF does not fetch (a network address or a urn).
[[nodiscard]] bool x3d_is_remote(std::string_view url);

/// One parsed XML file: the scene, an Inline'd file, or a PROTO body instantiated (whose
/// elements carry the line they came from in `hof-line`, since their text is a copy).
struct X3dDocument {
  std::filesystem::path file;
  std::string text;
  std::vector<std::ptrdiff_t> line_starts{0};
  pugi::xml_document xml;
  std::map<std::string, std::vector<pugi::xml_node>, std::less<>> defs;
  std::map<std::string, pugi::xml_node, std::less<>> protos;  // ProtoDeclare / ExternProtoDeclare by name
  std::vector<pugi::xml_node> routes;
  const X3dDocument* scope{nullptr};  // a PROTO body: the document of its declaration
  int proto_depth{0};                 // PROTO bodies instantiated inside one another
};

constexpr int kMaxInlineDepth = 16;  ///< Inline inside Inline, as deep as a sane scene goes
constexpr int kMaxProtoDepth = 16;   ///< PROTO instances inside PROTO bodies

class X3dSource {
 public:
  /// Warnings (ExternProto not found, empty PROTO bodies) go to `warnings`, which must outlive this.
  explicit X3dSource(std::vector<std::string>& warnings) : warnings_(warnings) {}

  // ---- documents
  /// Parses `text` as the document of `file` (refused: malformed XML, nesting too deep).
  X3dDocument& parse(std::filesystem::path file, std::string text, const X3dDocument* scope, int proto_depth);
  /// An Inline'd file, read once (then shared).
  const X3dDocument& load(pugi::xml_node at, const std::filesystem::path& path);
  [[nodiscard]] const X3dDocument& doc_of(pugi::xml_node n) const;
  [[nodiscard]] std::int64_t line_of(pugi::xml_node n) const;
  /// "file:line" of a node.
  [[nodiscard]] std::string where(pugi::xml_node n) const;
  [[nodiscard]] static std::filesystem::path weakly_canonical(const std::filesystem::path& p);

  [[noreturn]] static void fail_at(const std::filesystem::path& file, std::int64_t line, ErrorCode code,
                                   std::string message);
  [[noreturn]] void fail(pugi::xml_node n, ErrorCode code, std::string message) const;
  void warn(pugi::xml_node n, std::string_view message);

  // ---- DEF/USE and PROTO instances
  /// The node a possible USE element stands for: the last node DEF'd with that name before it
  /// (in a PROTO body, else in the document it was declared in).
  [[nodiscard]] pugi::xml_node resolve_use(pugi::xml_node n) const;
  /// resolve_use, then a ProtoInstance to its body (itself when its PROTO is not found).
  pugi::xml_node resolve(pugi::xml_node n);

  // ---- field values (empty or missing attribute = default)
  [[nodiscard]] std::vector<double> numbers(pugi::xml_node n, const char* field) const;
  [[nodiscard]] std::vector<double> numbers(pugi::xml_node n, const char* field, std::size_t count,
                                            std::vector<double> def) const;
  [[nodiscard]] double number(pugi::xml_node n, const char* field, double def) const {
    return numbers(n, field, 1, {def})[0];
  }
  [[nodiscard]] Vec3 vec3(pugi::xml_node n, const char* field, const Vec3& def) const;
  /// An MF field of `width`-tuples (MFVec2f: 2, MFVec3f: 3, MFRotation: 4); `def` when absent.
  [[nodiscard]] std::vector<double> tuples(pugi::xml_node n, const char* field, std::size_t width,
                                           std::vector<double> def) const;
  [[nodiscard]] std::vector<std::int64_t> integers(pugi::xml_node n, const char* field) const;
  [[nodiscard]] std::int64_t integer(pugi::xml_node n, const char* field, std::int64_t def) const;
  [[nodiscard]] bool boolean(pugi::xml_node n, const char* field, bool def) const;
  [[nodiscard]] std::string string(pugi::xml_node n, const char* field, std::string_view def) const;
  /// A field whose value is one of `options` (refused otherwise, listing them).
  template <class E>
  [[nodiscard]] E choice(pugi::xml_node n, const char* field,
                         std::initializer_list<std::pair<std::string_view, E>> options, E def) const {
    const std::string s = string(n, field, "");
    if (s.empty()) return def;
    std::string names;
    for (const auto& [name, value] : options) {
      if (name == s) return value;
      names += fmt::format(" {}", name);
    }
    fail(n, ErrorCode::kParse, fmt::format("<{}> field {}: '{}' is not one of{}", n.name(), field, s, names));
  }

 private:
  static void collect(X3dDocument& doc, pugi::xml_node n);
  static std::int64_t line_in(const X3dDocument& d, std::ptrdiff_t offset);
  pugi::xml_node declaration(pugi::xml_node at, std::string_view name);
  pugi::xml_node instantiate(pugi::xml_node instance);
  void mark_lines(pugi::xml_node original, pugi::xml_node copy) const;
  void substitute(pugi::xml_node n, const std::map<std::string, pugi::xml_node, std::less<>>& values,
                  pugi::xml_node instance);

  std::vector<std::string>& warnings_;
  std::vector<std::unique_ptr<X3dDocument>> docs_;   // [0] the scene; then Inlines and PROTO bodies
  std::map<std::size_t, pugi::xml_node> instances_;  // ProtoInstance → its body, made once
};

}  // namespace hof::scene::detail
