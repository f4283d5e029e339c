// X3D (H3D API) reader. One pass over the XML in document order, carrying the accumulated
// local-to-world matrix; USE elements resolve to the last node DEF'd with that name before them,
// a ProtoInstance to a copy of its PROTO's body with the fields substituted, an Inline to the
// file it names (each file, and each PROTO body, with DEF names of its own).
// Failures inside the walk are raised as a private exception and returned as hof::Error at
// the single entry point, so nothing escapes this file.

#include "hof/scene/x3d_scene.h"
#include "hof/mesh/xml_depth.h"
#include "hof/scene/detail/x3d_geometry.h"

#include <fmt/format.h>
#include <pugixml.hpp>

#include <algorithm>
#include <array>
#include <cctype>
#include <memory>
#include <optional>
#include <charconv>
#include <cmath>
#include <fstream>
#include <map>
#include <numbers>
#include <sstream>
#include <string_view>
#include <utility>

namespace hof::scene {
namespace {

namespace fs = std::filesystem;
using Mat4 = Eigen::Matrix4d;
using haptics::SurfaceKind;

struct ParseFailure {
  Error error;
};

bool ends_with(std::string_view s, std::string_view suffix) {
  return s.size() >= suffix.size() && s.substr(s.size() - suffix.size()) == suffix;
}

std::vector<std::string_view> tokens(std::string_view text) {
  std::vector<std::string_view> out;
  std::size_t i = 0;
  auto is_sep = [](char c) { return c == ',' || c == ' ' || c == '\t' || c == '\n' || c == '\r'; };
  while (i < text.size()) {
    while (i < text.size() && is_sep(text[i])) ++i;
    const std::size_t start = i;
    while (i < text.size() && !is_sep(text[i])) ++i;
    if (i > start) out.push_back(text.substr(start, i - start));
  }
  return out;
}

Mat4 axis_angle(const std::vector<double>& r) {
  Mat4 m = Mat4::Identity();
  const Vec3 axis(r[0], r[1], r[2]);
  if (axis.norm() > 1e-12) m.topLeftCorner<3, 3>() = Eigen::AngleAxisd(r[3], axis.normalized()).toRotationMatrix();
  return m;
}

Mat4 translation(const Vec3& t) {
  Mat4 m = Mat4::Identity();
  m.topRightCorner<3, 1>() = t;
  return m;
}

void transform_mesh(mesh::TriMesh& m, const Mat4& X) {
  for (auto& v : m.vertices) v = (X * v.homogeneous()).head<3>();
  if (X.topLeftCorner<3, 3>().determinant() < 0.0)
    for (auto& t : m.triangles) std::swap(t[1], t[2]);
}

// One parsed XML file: the scene, an Inline'd file, or a PROTO body instantiated (whose
// elements carry the line they came from in `hof-line`, since their text is a copy).
struct Document {
  fs::path file;
  std::string text;
  std::vector<std::ptrdiff_t> line_starts{0};
  pugi::xml_document xml;
  std::map<std::string, std::vector<pugi::xml_node>, std::less<>> defs;
  std::map<std::string, pugi::xml_node, std::less<>> protos;  // ProtoDeclare / ExternProtoDeclare by name
  std::vector<pugi::xml_node> routes;
  const Document* scope{nullptr};  // a PROTO body: the document of its declaration
  int proto_depth{0};              // PROTO bodies instantiated inside one another
};

constexpr int kMaxInlineDepth = 16;  // Inline inside Inline, as deep as a sane scene goes
constexpr int kMaxProtoDepth = 16;   // PROTO instances inside PROTO bodies

// The strings of an MFString field: `"a" "b"` (X3D XML encoding), or one unquoted value.
std::vector<std::string> mf_string(std::string_view text) {
  std::vector<std::string> out;
  if (text.find('"') == std::string_view::npos) {
    const auto t = tokens(text);
    if (!t.empty()) out.emplace_back(text.substr(text.find_first_not_of(" \t\r\n")));
    while (!out.empty() && !out.back().empty() && std::isspace(static_cast<unsigned char>(out.back().back()))) out.back().pop_back();
    return out;
  }
  for (std::size_t i = 0; i < text.size(); ++i) {
    if (text[i] != '"') continue;
    std::string value;
    for (++i; i < text.size() && text[i] != '"'; ++i) {
      if (text[i] == '\\' && i + 1 < text.size()) ++i;
      value += text[i];
    }
    out.push_back(std::move(value));
  }
  return out;
}

bool is_remote(std::string_view url) { return url.find("://") != std::string_view::npos || url.starts_with("urn:"); }

class X3dReader {
 public:
  explicit X3dReader(fs::path file) { scene_.file = std::move(file); }

  X3dScene run(std::string text) {
    const std::string_view head = std::string_view(text).substr(0, 64);
    if (head.starts_with("#X3D") || head.starts_with("#VRML")) {
      fail_at(scene_.file, 1, ErrorCode::kUnsupported,
              "the X3D classic VRML encoding (#X3D / #VRML) is not read: only X3D's XML encoding (<X3D>...)");
    }
    Document& doc = parse(scene_.file, std::move(text), nullptr, 0);
    const pugi::xml_node root = doc.xml.document_element();
    if (!root) fail_at(scene_.file, 1, ErrorCode::kParse, "no root element");
    scene_.root_element = root.name();
    inline_stack_.push_back(weakly_canonical(scene_.file));
    visit(root, Mat4::Identity());
    if (!scene_.unsupported.empty()) {
      std::string list;
      for (std::size_t i = 0; i < scene_.unsupported.size() && i < 8; ++i) list += (i ? ", " : "") + scene_.unsupported[i];
      if (scene_.unsupported.size() > 8) list += ", ...";
      scene_.warnings.push_back(fmt::format("{}: {} node(s) not modelled, ignored: {}", scene_.file.string(),
                                            scene_.unsupported.size(), list));
    }
    return std::move(scene_);
  }

 private:
  static fs::path weakly_canonical(const fs::path& p) {
    std::error_code ec;
    fs::path c = fs::weakly_canonical(p, ec);
    return ec ? p : c;
  }

  // ---- documents
  Document& parse(fs::path file, std::string text, const Document* scope, int proto_depth) {
    auto doc = std::make_unique<Document>();
    doc->file = std::move(file);
    doc->text = std::move(text);
    doc->scope = scope;
    doc->proto_depth = proto_depth;
    for (std::size_t i = 0; i < doc->text.size(); ++i)
      if (doc->text[i] == '\n') doc->line_starts.push_back(static_cast<std::ptrdiff_t>(i + 1));
    const auto parsed = doc->xml.load_buffer(doc->text.data(), doc->text.size(), pugi::parse_default);
    if (!parsed) fail_at(doc->file, line_in(*doc, parsed.offset), ErrorCode::kParse, fmt::format("malformed XML: {}", parsed.description()));
    if (const pugi::xml_node deep = mesh::first_too_deep_element(doc->xml)) {
      fail_at(doc->file, line_in(*doc, deep.offset_debug()), ErrorCode::kParse,
              fmt::format("<{}> is nested deeper than {} levels", deep.name(), mesh::kMaxXmlDepth));
    }
    collect(*doc, doc->xml);
    docs_.push_back(std::move(doc));
    return *docs_.back();
  }

  // DEF names and PROTO declarations of a document.
  static void collect(Document& doc, pugi::xml_node n) {
    for (pugi::xml_node c : n.children()) {
      if (c.type() != pugi::node_element) continue;
      if (const char* d = c.attribute("DEF").as_string(); *d) doc.defs[d].push_back(c);
      const std::string_view t = c.name();
      if (t == "ROUTE") doc.routes.push_back(c);
      if (t == "ProtoDeclare" || t == "ExternProtoDeclare") {
        doc.protos.emplace(c.attribute("name").as_string(), c);
        continue;  // a PROTO body's DEF names are its own
      }
      collect(doc, c);
    }
  }

  const Document& doc_of(pugi::xml_node n) const {
    const pugi::xml_node root = n.root();
    for (const auto& d : docs_)
      if (d->xml == root) return *d;
    return *docs_.front();
  }

  static std::int64_t line_in(const Document& d, std::ptrdiff_t offset) {
    return std::upper_bound(d.line_starts.begin(), d.line_starts.end(), offset) - d.line_starts.begin();
  }
  std::int64_t line_of(pugi::xml_node n) const {
    if (const pugi::xml_attribute l = n.attribute("hof-line")) return l.as_llong();
    return line_in(doc_of(n), n.offset_debug());
  }
  std::string where(pugi::xml_node n) const { return fmt::format("{}:{}", doc_of(n).file.string(), line_of(n)); }

  [[noreturn]] static void fail_at(const fs::path& file, std::int64_t line, ErrorCode code, std::string message) {
    throw ParseFailure{Error{code, std::move(message), file.string(), line, -1}};
  }
  [[noreturn]] void fail(pugi::xml_node n, ErrorCode code, std::string message) const {
    fail_at(doc_of(n).file, line_of(n), code, std::move(message));
  }
  void warn(pugi::xml_node n, std::string_view message) { scene_.warnings.push_back(fmt::format("{}: {}", where(n), message)); }

  // ---- DEF/USE and PROTO instances
  // The node a possible USE element stands for: the last node DEF'd with that name before it
  // (in a PROTO body, else in the document it was declared in).
  pugi::xml_node resolve_use(pugi::xml_node n) const {
    const std::string_view use = n.attribute("USE").as_string();
    if (use.empty()) return n;
    pugi::xml_node found;
    for (const Document* d = &doc_of(n); d && !found; d = d->scope) {
      const auto it = d->defs.find(use);
      if (it == d->defs.end()) continue;
      for (pugi::xml_node def : it->second)
        if (d != &doc_of(n) || def.offset_debug() < n.offset_debug()) found = def;
    }
    if (!found) fail(n, ErrorCode::kParse, fmt::format("<{} USE='{}'>: no node DEF'd with that name before", n.name(), use));
    // A USE inside the node it names would contain itself: an endless tree.
    for (pugi::xml_node a = n.parent(); a; a = a.parent()) {
      if (a == found) {
        fail(n, ErrorCode::kParse,
             fmt::format("<{} USE='{}'> is inside the node it names (line {}): a cycle", n.name(), use, line_of(found)));
      }
    }
    return found;
  }

  pugi::xml_node resolve(pugi::xml_node n) {
    n = resolve_use(n);
    if (std::string_view(n.name()) == "ProtoInstance") {
      if (const pugi::xml_node body = instantiate(n)) return body;
    }
    return n;
  }

  // The declaration of PROTO `name` seen from `doc` (an ExternProtoDeclare is followed to the
  // ProtoDeclare in its file). Null when there is none (the instance is then not modelled).
  pugi::xml_node declaration(pugi::xml_node at, std::string_view name) {
    for (const Document* d = &doc_of(at); d; d = d->scope) {
      const auto it = d->protos.find(name);
      if (it == d->protos.end()) continue;
      const pugi::xml_node decl = it->second;
      if (std::string_view(decl.name()) == "ProtoDeclare") return decl;
      // ExternProtoDeclare: the first url found beside the file, "FILE#NAME" (NAME defaults
      // to the extern's own name).
      for (const std::string& url : mf_string(decl.attribute("url").as_string())) {
        if (is_remote(url)) continue;
        const std::size_t hash = url.find('#');
        const fs::path path = d->file.parent_path() / url.substr(0, hash);
        const std::string target = hash == std::string::npos ? std::string(name) : url.substr(hash + 1);
        if (!fs::is_regular_file(path)) continue;
        const Document& ext = load(decl, path);
        const auto found = ext.protos.find(target);
        if (found != ext.protos.end() && std::string_view(found->second.name()) == "ProtoDeclare") return found->second;
      }
      warn(decl, fmt::format("ExternProtoDeclare '{}': no ProtoDeclare found at its url {}", name, decl.attribute("url").as_string()));
      return {};
    }
    return {};
  }

  // A ProtoInstance: a copy of the first node of its PROTO's body, with every IS/connect
  // replaced by the instance's fieldValue (or the interface's default), as 19775-1's prototype semantics say. The
  // other body nodes are not rendered (the spec: only the first node is the instance's type).
  pugi::xml_node instantiate(pugi::xml_node instance) {
    if (const auto it = instances_.find(instance.hash_value()); it != instances_.end()) return it->second;
    const std::string name = instance.attribute("name").as_string();
    const pugi::xml_node decl = declaration(instance, name);
    if (!decl) return {};
    const Document& home = doc_of(decl);
    if (doc_of(instance).proto_depth >= kMaxProtoDepth) {
      fail(instance, ErrorCode::kParse,
           fmt::format("ProtoInstance '{}': PROTOs instantiated more than {} deep (a PROTO whose body instantiates itself?)",
                       name, kMaxProtoDepth));
    }
    pugi::xml_node first;
    for (pugi::xml_node c : decl.child("ProtoBody").children())
      if (c.type() == pugi::node_element) { first = c; break; }
    if (!first) {
      warn(instance, fmt::format("ProtoInstance '{}': its ProtoBody is empty", name));
      instances_[instance.hash_value()] = {};
      return {};
    }
    // Field values: the interface's defaults, then the instance's own.
    std::map<std::string, pugi::xml_node, std::less<>> values;
    for (pugi::xml_node f : decl.child("ProtoInterface").children("field")) values[f.attribute("name").as_string()] = f;
    for (pugi::xml_node f : instance.children("fieldValue")) values[f.attribute("name").as_string()] = f;

    pugi::xml_document copy;
    pugi::xml_node body = copy.append_copy(first);
    mark_lines(first, body);
    substitute(body, values, instance);
    std::ostringstream text;
    copy.save(text, "", pugi::format_raw | pugi::format_no_declaration);
    Document& d = parse(home.file, text.str(), &home, doc_of(instance).proto_depth + 1);
    const pugi::xml_node result = d.xml.document_element();
    instances_[instance.hash_value()] = result;
    return result;
  }

  // Every element of `copy` gets the line of its original (its text is not the file's).
  void mark_lines(pugi::xml_node original, pugi::xml_node copy) const {
    if (!copy.attribute("hof-line")) copy.append_attribute("hof-line") = static_cast<long long>(line_of(original));
    pugi::xml_node c = copy.first_child();
    for (pugi::xml_node o = original.first_child(); o && c; o = o.next_sibling(), c = c.next_sibling())
      if (o.type() == pugi::node_element) mark_lines(o, c);
  }

  void substitute(pugi::xml_node n, const std::map<std::string, pugi::xml_node, std::less<>>& values, pugi::xml_node instance) {
    for (pugi::xml_node is = n.child("IS"); is; is = n.child("IS")) {
      for (pugi::xml_node connect : is.children("connect")) {
        const std::string node_field = connect.attribute("nodeField").as_string();
        const std::string proto_field = connect.attribute("protoField").as_string();
        const auto it = values.find(proto_field);
        if (it == values.end()) continue;  // no value anywhere: the node's own default holds
        const pugi::xml_node v = it->second;
        if (const pugi::xml_attribute a = v.attribute("value")) {
          pugi::xml_attribute target = n.attribute(node_field.c_str());
          if (!target) target = n.append_attribute(node_field.c_str());
          target.set_value(a.value());
        }
        // SFNode / MFNode values: copies of the nodes, in the connected field.
        for (pugi::xml_node c : v.children()) {
          if (c.type() != pugi::node_element) continue;
          const pugi::xml_node source = resolve_use(c);
          pugi::xml_node added = n.append_copy(source);
          mark_lines(source, added);
          added.remove_attribute("DEF");
          pugi::xml_attribute field = added.attribute("containerField");
          if (!field) field = added.append_attribute("containerField");
          field.set_value(node_field.c_str());
        }
      }
      n.remove_child(is);
    }
    for (pugi::xml_node c : n.children())
      if (c.type() == pugi::node_element) substitute(c, values, instance);
  }

  // An Inline'd file, read once (then shared).
  const Document& load(pugi::xml_node at, const fs::path& path) {
    const fs::path key = weakly_canonical(path);
    for (const auto& d : docs_)
      if (d->scope == nullptr && weakly_canonical(d->file) == key) return *d;
    std::ifstream in(path, std::ios::binary);
    if (!in) fail(at, ErrorCode::kIo, fmt::format("cannot open '{}'", path.string()));
    std::ostringstream buffer;
    buffer << in.rdbuf();
    return parse(path, buffer.str(), nullptr, 0);
  }

  void unsupported(pugi::xml_node original, std::string_view extra = {}) {
    const pugi::xml_node n = resolve_use(original);
    std::string def = n.attribute("DEF").as_string();
    std::string entry = def.empty() ? std::string(n.name()) : fmt::format("{} '{}'", n.name(), def);
    if (std::string_view(n.name()) == "ProtoInstance") entry += fmt::format(" '{}'", n.attribute("name").as_string());
    if (!extra.empty()) entry += fmt::format(" {}", extra);
    scene_.unsupported.push_back(fmt::format("{} (line {})", entry, line_of(original)));
  }

  // ---- field values (empty or missing attribute = default)
  std::vector<double> numbers(pugi::xml_node n, const char* field) const {
    std::vector<double> out;
    for (std::string_view tok : tokens(n.attribute(field).as_string())) {
      if (!tok.empty() && tok.front() == '+') tok.remove_prefix(1);
      double v = 0.0;
      const auto [ptr, ec] = std::from_chars(tok.data(), tok.data() + tok.size(), v);
      if (ec != std::errc{} || ptr != tok.data() + tok.size() || !std::isfinite(v))
        fail(n, ErrorCode::kParse, fmt::format("<{}> field {}: '{}' is not a number", n.name(), field, tok));
      out.push_back(v);
    }
    return out;
  }
  std::vector<double> numbers(pugi::xml_node n, const char* field, std::size_t count, std::vector<double> def) const {
    auto v = numbers(n, field);
    if (v.empty()) return def;
    if (v.size() != count)
      fail(n, ErrorCode::kParse, fmt::format("<{}> field {}: expected {} numbers, got {}", n.name(), field, count, v.size()));
    return v;
  }
  double number(pugi::xml_node n, const char* field, double def) const { return numbers(n, field, 1, {def})[0]; }
  Vec3 vec3(pugi::xml_node n, const char* field, const Vec3& def) const {
    const auto v = numbers(n, field, 3, {def.x(), def.y(), def.z()});
    return {v[0], v[1], v[2]};
  }
  // An MF field of `width`-tuples (MFVec2f: 2, MFVec3f: 3, MFRotation: 4); `def` when absent.
  std::vector<double> tuples(pugi::xml_node n, const char* field, std::size_t width, std::vector<double> def) const {
    auto v = numbers(n, field);
    if (v.empty() && !n.attribute(field)) return def;
    if (v.size() % width != 0)
      fail(n, ErrorCode::kParse, fmt::format("<{}> field {}: {} numbers, not a multiple of {}", n.name(), field, v.size(), width));
    return v;
  }
  std::vector<std::int64_t> integers(pugi::xml_node n, const char* field) const {
    std::vector<std::int64_t> out;
    for (double v : numbers(n, field)) {
      if (v != std::floor(v)) fail(n, ErrorCode::kParse, fmt::format("<{}> field {}: {} is not an integer", n.name(), field, v));
      // Past ±2⁶³ the conversion is undefined (found by fuzz_x3d): no index or count is that large.
      if (!(v >= -0x1p63 && v < 0x1p63))
        fail(n, ErrorCode::kParse, fmt::format("<{}> field {}: {} is out of range", n.name(), field, v));
      out.push_back(static_cast<std::int64_t>(v));
    }
    return out;
  }
  std::int64_t integer(pugi::xml_node n, const char* field, std::int64_t def) const {
    const auto v = integers(n, field);
    return v.empty() ? def : v[0];
  }
  bool boolean(pugi::xml_node n, const char* field, bool def) const {
    const std::string_view s = n.attribute(field).as_string();
    if (s.empty()) return def;
    if (s == "true" || s == "TRUE" || s == "True") return true;
    if (s == "false" || s == "FALSE" || s == "False") return false;
    fail(n, ErrorCode::kParse, fmt::format("<{}> field {}: '{}' is not a boolean", n.name(), field, s));
  }
  std::string string(pugi::xml_node n, const char* field, std::string_view def) const {
    std::string s = n.attribute(field).as_string();
    if (s.size() >= 2 && s.front() == '"' && s.back() == '"') s = s.substr(1, s.size() - 2);
    return s.empty() ? std::string(def) : s;
  }
  template <class E>
  E choice(pugi::xml_node n, const char* field, std::initializer_list<std::pair<std::string_view, E>> options, E def) const {
    const std::string s = string(n, field, "");
    if (s.empty()) return def;
    std::string names;
    for (const auto& [name, value] : options) {
      if (name == s) return value;
      names += fmt::format(" {}", name);
    }
    fail(n, ErrorCode::kParse, fmt::format("<{}> field {}: '{}' is not one of{}", n.name(), field, s, names));
  }

  // ---- scene graph
  // Grouping nodes whose children are all drawn and felt (19775-1: Group, StaticGroup,
  // Billboard, Collision, Anchor; H3D's own groups). Billboard
  // turns its children toward the viewer: HoF, with no viewer to face, leaves them unturned.
  static bool is_group(std::string_view t) {
    return t == "X3D" || t == "Scene" || t == "Group" || t == "StaticGroup" || t == "HapticLayeredGroup" ||
           t == "ToggleGroup" || t == "Collision" || t == "Billboard" || t == "Anchor";
  }
  static bool is_geometry(std::string_view t) {
    return t == "Sphere" || t == "Box" || t == "Cylinder" || t == "Cone" || t == "IndexedTriangleSet" ||
           t == "IndexedFaceSet" || t == "Rectangle2D" || t == "Disk2D" || t == "ElevationGrid" || t == "Extrusion" ||
           t == "TriangleSet" || t == "TriangleFanSet" || t == "TriangleStripSet" || t == "IndexedTriangleFanSet" ||
           t == "IndexedTriangleStripSet" || t == "QuadSet" || t == "IndexedQuadSet" || t == "GeometryGroup";
  }
  // A child in the scene graph (not metadata, a Collision's proxy, or a PROTO's IS).
  static bool is_child(pugi::xml_node c) {
    if (c.type() != pugi::node_element) return false;
    const std::string_view t = c.name();
    const std::string_view field = c.attribute("containerField").as_string();
    return t != "IS" && !t.starts_with("Metadata") && field != "metadata" && field != "proxy";
  }

  void visit_children(pugi::xml_node n, const Mat4& X) {
    for (pugi::xml_node c : n.children())
      if (is_child(c)) visit(c, X);
  }

  // The i-th scene-graph child of `n` (null past the end).
  static pugi::xml_node nth_child(pugi::xml_node n, std::int64_t i) {
    for (pugi::xml_node c : n.children()) {
      if (!is_child(c)) continue;
      if (i-- == 0) return c;
    }
    return {};
  }

  void visit(pugi::xml_node original, const Mat4& X) {
    // USE copies subtrees: a chain of nodes each USE'd twice by the next doubles the tree at
    // every link (2^40 nodes from 40 lines). Bounded, so such a file is refused, not a hang.
    if (++visited_ > kMaxVisitedNodes) {
      fail(original, ErrorCode::kParse, fmt::format("the scene expands to more than {} nodes through USE", kMaxVisitedNodes));
    }
    const std::string_view tag = original.name();
    if (tag == "head" || tag == "meta" || tag == "component" || tag == "unit" || tag == "ProtoDeclare" ||
        tag == "ExternProtoDeclare") {
      return;  // PROTO declarations: read where they are instantiated
    }
    const pugi::xml_node n = resolve(original);
    const std::string_view t = n.name();
    if (t == "HapticLayeredGroup") {
      // H3D: each child is a haptic layer, rendered with its own proxy (forces summed).
      const int outer = layer_;
      int index = 0;
      for (pugi::xml_node c : n.children()) {
        if (!is_child(c)) continue;
        layer_ = index++;
        visit(c, X);
      }
      layer_ = outer;
    } else if (is_group(t)) {
      visit_children(n, X);
    } else if (t == "Switch") {
      // 19775-1, Switch: only the child whichChoice names is traversed; −1 (the default) or an
      // index past the children: none.
      if (const pugi::xml_node c = nth_child(n, integer(n, "whichChoice", -1)); c && integer(n, "whichChoice", -1) >= 0) visit(c, X);
    } else if (t == "LOD") {
      // 19775-1, LOD: level 0, the most detailed, is shown nearest the viewer; HoF has no
      // viewer distance, and takes that one.
      if (const pugi::xml_node c = nth_child(n, 0)) visit(c, X);
    } else if (t == "Inline") {
      inline_file(n, X);
    } else if (t == "Transform") {
      visit_children(n, X * transform_matrix(n));
    } else if (t == "MatrixTransform") {
      const auto m = numbers(n, "matrix", 16, {1, 0, 0, 0, 0, 1, 0, 0, 0, 0, 1, 0, 0, 0, 0, 1});
      visit_children(n, X * Eigen::Map<const Eigen::Matrix<double, 4, 4, Eigen::RowMajor>>(m.data()));
    } else if (t == "FitToBoxTransform") {
      fit_to_box(n, X);
    } else if (t == "Shape" || t == "DeformableShape") {
      shape(original, n, X);
    } else if (t == "DeviceInfo") {
      device_info(n);
    } else if (t == "GlobalSettings") {
      global_settings(n);
    } else if (t == "SpringEffect") {
      haptics::SpringEffect s;
      s.position_m = (X * vec3(n, "position", Vec3::Zero()).homogeneous()).head<3>();
      s.spring_constant_n_per_m = number(n, "springConstant", 100.0);
      s.start_distance_m = number(n, "startDistance", 0.01);
      s.escape_distance_m = number(n, "escapeDistance", 0.01);
      s.damping_n_s_per_m = number(n, "damping", 0.0);
      scene_.force_effects.springs.push_back(s);
    } else if (t == "ViscosityEffect") {
      haptics::ViscosityEffect v;
      v.viscosity_pa_s = number(n, "viscosity", 0.01);
      v.radius_m = number(n, "radius", 0.0025);
      v.damping_factor = number(n, "dampingFactor", 0.5);
      v.enabled = boolean(n, "enabled", true);
      scene_.force_effects.viscosities.push_back(v);
    } else if (t == "ForceField") {
      // The force keeps its magnitude and turns with the enclosing transforms.
      const Vec3 f = vec3(n, "force", Vec3::Zero());
      const Vec3 d = X.topLeftCorner<3, 3>() * f;
      scene_.force_effects.constants.push_back({d.norm() > 0.0 ? Vec3(d.normalized() * f.norm()) : Vec3::Zero()});
    } else if (t == "MagneticGeometryEffect") {
      magnetic_geometry_effect(n, X);
    } else if (t == "PositionFunctionEffect" || t == "TimeFunctionEffect") {
      function_effect(n);
    } else if (t == "RotationalSpringEffect") {
      rotational_spring_effect(n);
    } else if (t == "Viewpoint") {
      X3dViewpoint v;
      v.position = vec3(n, "position", v.position);
      const auto o = numbers(n, "orientation", 4, {0, 0, 1, 0});
      std::copy(o.begin(), o.end(), v.orientation.begin());
      v.field_of_view_rad = number(n, "fieldOfView", v.field_of_view_rad);
      scene_.viewpoints.push_back(v);
    } else {
      unsupported(original);
    }
  }

  // Inline (19775-1, Networking): the first of its urls found beside the file that holds it, read as
  // a scene of its own (its DEF names are its own) under the current transform. A url on the
  // network, or none found, is a warning; an Inline that includes itself, directly or through
  // others, or nests past kMaxInlineDepth, is an error (the scene would be endless).
  void inline_file(pugi::xml_node n, const Mat4& X) {
    if (!boolean(n, "load", true)) return;
    const std::vector<std::string> urls = mf_string(n.attribute("url").as_string());
    const fs::path folder = doc_of(n).file.parent_path();
    for (const std::string& url : urls) {
      if (is_remote(url)) continue;
      const fs::path path = folder / url.substr(0, url.find('#'));
      if (!fs::is_regular_file(path)) continue;
      const fs::path key = weakly_canonical(path);
      if (std::ranges::find(inline_stack_, key) != inline_stack_.end()) {
        std::string chain;
        for (const fs::path& p : inline_stack_) chain += p.filename().string() + " → ";
        fail(n, ErrorCode::kParse, fmt::format("Inline url '{}' includes a file that includes it: {}{}", url, chain,
                                               path.filename().string()));
      }
      if (static_cast<int>(inline_stack_.size()) > kMaxInlineDepth)
        fail(n, ErrorCode::kParse, fmt::format("Inline url '{}': Inlines nest deeper than {}", url, kMaxInlineDepth));
      const Document& d = load(n, path);
      if (!d.xml.document_element()) return;
      inline_stack_.push_back(key);
      visit(d.xml.document_element(), X);
      inline_stack_.pop_back();
      return;
    }
    warn(n, urls.empty() ? std::string("Inline without a url")
                         : fmt::format("Inline: none of its urls is a file beside the scene ({}): not shown",
                                       n.attribute("url").as_string()));
  }
  // X3D Transform: T · C · R · SR · S · SR⁻¹ · C⁻¹.
  Mat4 transform_matrix(pugi::xml_node n) const {
    const Vec3 t = vec3(n, "translation", Vec3::Zero());
    const Vec3 c = vec3(n, "center", Vec3::Zero());
    const Vec3 s = vec3(n, "scale", Vec3::Ones());
    const Mat4 R = axis_angle(numbers(n, "rotation", 4, {0, 0, 1, 0}));
    const Mat4 SR = axis_angle(numbers(n, "scaleOrientation", 4, {0, 0, 1, 0}));
    Mat4 S = Mat4::Identity();
    S.diagonal().head<3>() = s;
    return translation(t) * translation(c) * R * SR * S * SR.transpose() * translation(-c);
  }

  // FitToBoxTransform: the children are read in its local frame, their bound is scaled and
  // moved into the box, then everything is taken to the world frame.
  void fit_to_box(pugi::xml_node n, const Mat4& X) {
    const Vec3 box_size = vec3(n, "boxSize", Vec3::Constant(0.1));
    const Vec3 box_center = vec3(n, "boxCenter", Vec3::Zero());
    const bool uniform = boolean(n, "uniformScalingOnly", false);
    const bool active = boolean(n, "active", true);
    const std::size_t first_shape = scene_.shapes.size();
    const std::size_t first_spring = scene_.force_effects.springs.size();
    const std::size_t first_constant = scene_.force_effects.constants.size();
    const std::size_t first_magnet = scene_.force_effects.magnets.size();
    visit_children(n, Mat4::Identity());

    Eigen::AlignedBox3d bound;
    for (std::size_t i = first_shape; i < scene_.shapes.size(); ++i) {
      for (const Vec3& v : scene_.shapes[i].mesh_W.vertices) bound.extend(v);
      for (const Vec3& v : scene_.shapes[i].haptic_mesh_W.vertices) bound.extend(v);
    }
    Mat4 M = Mat4::Identity();
    if (active && !bound.isEmpty()) {
      const Vec3 size = bound.sizes();
      Vec3 s = Vec3::Ones();
      double smallest = std::numeric_limits<double>::infinity();
      for (int k = 0; k < 3; ++k)
        if (size[k] > 1e-12) smallest = std::min(smallest, box_size[k] / size[k]);
      if (!std::isfinite(smallest)) smallest = 1.0;
      for (int k = 0; k < 3; ++k) s[k] = (uniform || size[k] <= 1e-12) ? smallest : box_size[k] / size[k];
      M.diagonal().head<3>() = s;
      M.topRightCorner<3, 1>() = box_center - s.cwiseProduct(bound.center());
    }
    const Mat4 XM = X * M;
    for (std::size_t i = first_shape; i < scene_.shapes.size(); ++i) {
      transform_mesh(scene_.shapes[i].mesh_W, XM);
      transform_mesh(scene_.shapes[i].haptic_mesh_W, XM);
    }
    for (std::size_t i = first_spring; i < scene_.force_effects.springs.size(); ++i) {
      Vec3& p = scene_.force_effects.springs[i].position_m;
      p = (XM * p.homogeneous()).head<3>();
    }
    for (std::size_t i = first_magnet; i < scene_.force_effects.magnets.size(); ++i) {
      auto moved = std::make_shared<mesh::TriMesh>(*scene_.force_effects.magnets[i].surface);
      transform_mesh(*moved, XM);
      scene_.force_effects.magnets[i].surface = std::move(moved);
    }
    for (std::size_t i = first_constant; i < scene_.force_effects.constants.size(); ++i) {
      Vec3& f = scene_.force_effects.constants[i].force_n;
      const Vec3 d = XM.topLeftCorner<3, 3>() * f;
      if (d.norm() > 0.0) f = d.normalized() * f.norm();
    }
  }

  // ---- shapes
  void shape(pugi::xml_node original, pugi::xml_node n, const Mat4& X) {
    X3dShape s;
    s.def = n.attribute("DEF").as_string();
    s.line = line_of(original);
    s.deformable = std::string_view(n.name()) == "DeformableShape";
    for (pugi::xml_node c_orig : n.children()) {
      if (!is_child(c_orig)) continue;
      const pugi::xml_node c = resolve(c_orig);
      const std::string_view t = c.name();
      const std::string_view field = c_orig.attribute("containerField").as_string();
      if (t == "Appearance") {
        appearance(c, s);
      } else if (is_geometry(t) && field == "hapticGeometry") {
        s.haptic_geometry_type = t;
        bool solid = true;
        s.haptic_mesh_W = geometry(c, solid, s);
        transform_mesh(s.haptic_mesh_W, X);
      } else if (is_geometry(t)) {
        s.geometry_type = t;
        s.mesh_W = geometry(c, s.solid, s);
        transform_mesh(s.mesh_W, X);
      } else if (s.deformable && (field == "deformer" || ends_with(t, "Deformer"))) {
        s.deformer_type = t;
      } else {
        unsupported(c_orig);
      }
    }
    s.layer = layer_;
    scene_.shapes.push_back(std::move(s));
  }

  static bool is_surface(std::string_view t) {
    return t == "SmoothSurface" || t == "FrictionalSurface" || t == "MagneticSurface" || t == "OpenHapticsSurface" ||
           t == "DepthMapSurface" || t == "HapticTexturesSurface";
  }

  void appearance(pugi::xml_node n, X3dShape& s) {
    for (pugi::xml_node c_orig : n.children()) {
      if (!is_child(c_orig)) continue;
      const pugi::xml_node c = resolve(c_orig);
      const std::string_view t = c.name();
      if (t == "Material" || t == "TwoSidedMaterial") {
        s.diffuse_color = vec3(c, "diffuseColor", s.diffuse_color);
        s.transparency = std::clamp(c.attribute("transparency").as_double(0.0), 0.0, 1.0);
        s.has_material = true;
      } else if (is_surface(t)) {
        s.touchable = true;
        s.surface_type = t;
        s.surface = surface(c);
      } else if (t == "MultiDeviceSurface") {
        // One surface per device index, the last repeating (h3d-nodes.md): HoF drives one
        // device, index 0, which feels the first.
        pugi::xml_node first;
        for (pugi::xml_node m : c.children()) {
          if (!is_child(m)) continue;
          const pugi::xml_node r = resolve(m);
          if (!first && is_surface(r.name())) first = r;
          else unsupported(m);
        }
        if (first) {
          s.touchable = true;
          s.surface_type = first.name();
          s.surface = surface(first);
        }
      } else {
        unsupported(c_orig);
      }
    }
  }

  haptics::SurfaceMaterial surface(pugi::xml_node n) {
    const std::string_view t = n.name();
    haptics::SurfaceMaterial m;
    const bool magnetic = t == "MagneticSurface" || t == "OpenHapticsSurface";
    m.kind = t == "SmoothSurface" ? SurfaceKind::kSmooth : magnetic ? SurfaceKind::kMagnetic : SurfaceKind::kFrictional;
    m.stiffness = number(n, "stiffness", 0.5);
    m.damping_n_s_per_m = number(n, "damping", 0.0);
    m.use_relative_values = boolean(n, "useRelativeValues", true);
    if (m.kind == SurfaceKind::kSmooth) {
      m.static_friction = 0.0;  // HAPI::FrictionSurface(k, d, 0, 0)
      m.dynamic_friction = 0.0;
    } else {
      m.static_friction = number(n, "staticFriction", 0.1);
      m.dynamic_friction = number(n, "dynamicFriction", 0.4);
    }
    if (magnetic) m.snap_distance_m = number(n, "snapDistance", 0.01);
    for (pugi::xml_node c : n.children())  // texture maps and the like
      if (is_child(c)) unsupported(c);
    return m;
  }

  // Geometry in its local frame; also reads `solid` and the geometry's own option nodes.
  mesh::TriMesh geometry(pugi::xml_node n, bool& solid, X3dShape& s) {
    const std::string_view t = n.name();
    // 19775-1: the Geometry2D nodes are two-sided by default (solid FALSE), the others solid.
    solid = boolean(n, "solid", !(t == "Rectangle2D" || t == "Disk2D"));
    mesh::TriMesh m;
    pugi::xml_node coord;
    std::vector<pugi::xml_node> members;  // a GeometryGroup's geometries
    for (pugi::xml_node c_orig : n.children()) {
      if (!is_child(c_orig)) continue;
      const pugi::xml_node c = resolve(c_orig);
      const std::string_view ct = c.name();
      if (ct == "Coordinate" || ct == "CoordinateDouble") coord = c;
      else if (ct == "HapticsOptions") { if (!s.haptics_options) s.haptics_options = haptics_options(c); }
      else if (ct == "GeometryBoundTreeOptions") { if (!s.bound_tree_options) s.bound_tree_options = bound_tree_options(c); }
      else if (t == "GeometryGroup" && is_geometry(ct)) members.push_back(c);
      else unsupported(c_orig);
    }
    if (t == "Sphere") {
      m = detail::make_sphere(number(n, "radius", 1.0));
    } else if (t == "Box") {
      m = detail::make_box(vec3(n, "size", Vec3::Constant(2.0)));
    } else if (t == "Cylinder") {
      const double r = number(n, "radius", 1.0);
      m = detail::make_round(r, r, number(n, "height", 2.0), boolean(n, "side", true), boolean(n, "bottom", true),
                             boolean(n, "top", true));
    } else if (t == "Cone") {
      m = detail::make_round(number(n, "bottomRadius", 1.0), 0.0, number(n, "height", 2.0), boolean(n, "side", true),
                             boolean(n, "bottom", true), false);
    } else if (t == "Rectangle2D") {
      const auto sz = numbers(n, "size", 2, {2.0, 2.0});
      m = detail::make_rectangle(sz[0], sz[1]);
    } else if (t == "Disk2D") {
      m = detail::make_disk(number(n, "innerRadius", 0.0), number(n, "outerRadius", 1.0));
    } else if (t == "ElevationGrid") {
      m = elevation_grid(n);
    } else if (t == "Extrusion") {
      m = extrusion(n);
    } else if (t == "GeometryGroup") {
      // H3D GeometryGroup: several geometries drawn and felt as one; two-sided if any member is.
      for (pugi::xml_node g : members) {
        bool member_solid = true;
        mesh::TriMesh part = geometry(g, member_solid, s);
        solid = solid && member_solid;
        const auto offset = static_cast<mesh::NodeIndex>(m.vertices.size());
        m.vertices.insert(m.vertices.end(), part.vertices.begin(), part.vertices.end());
        for (mesh::Tri tri : part.triangles) m.triangles.push_back({tri[0] + offset, tri[1] + offset, tri[2] + offset});
      }
    } else {
      composed_set(n, coord, m);
    }
    return m;
  }

  // ElevationGrid (19775-1, Geometry3D): xDimension × zDimension heights (default 0 × 0: empty),
  // spacings 1, ccw TRUE.
  mesh::TriMesh elevation_grid(pugi::xml_node n) {
    const std::int64_t nx = integer(n, "xDimension", 0);
    const std::int64_t nz = integer(n, "zDimension", 0);
    const auto height = numbers(n, "height");
    if (nx < 0 || nz < 0 || nx > 100000 || nz > 100000)
      fail(n, ErrorCode::kParse, fmt::format("<ElevationGrid>: xDimension {} and zDimension {} must be in [0, 100000]", nx, nz));
    if (static_cast<std::int64_t>(height.size()) < nx * nz)
      fail(n, ErrorCode::kInvalidMesh, fmt::format("<ElevationGrid>: {} heights for a {} × {} grid", height.size(), nx, nz));
    mesh::TriMesh m = detail::make_elevation_grid(nx, nz, number(n, "xSpacing", 1.0), number(n, "zSpacing", 1.0), height);
    if (!boolean(n, "ccw", true)) flip(m);
    return m;
  }

  // Extrusion (19775-1, Geometry3D): defaults crossSection the square 1 1, 1 −1, −1 −1, −1 1,
  // 1 1; spine 0 0 0, 0 1 0; scale 1 1; orientation 0 0 1 0; both caps; ccw TRUE.
  mesh::TriMesh extrusion(pugi::xml_node n) {
    const auto cs = tuples(n, "crossSection", 2, {1, 1, 1, -1, -1, -1, -1, 1, 1, 1});
    const auto sp = tuples(n, "spine", 3, {0, 0, 0, 0, 1, 0});
    const auto sc = tuples(n, "scale", 2, {1, 1});
    const auto orient = tuples(n, "orientation", 4, {0, 0, 1, 0});
    std::vector<detail::Vec2> cross_section, scale;
    std::vector<Vec3> spine;
    std::vector<detail::Vec4> orientation;
    for (std::size_t i = 0; i + 1 < cs.size(); i += 2) cross_section.emplace_back(cs[i], cs[i + 1]);
    for (std::size_t i = 0; i + 2 < sp.size(); i += 3) spine.emplace_back(sp[i], sp[i + 1], sp[i + 2]);
    for (std::size_t i = 0; i + 1 < sc.size(); i += 2) scale.emplace_back(sc[i], sc[i + 1]);
    for (std::size_t i = 0; i + 3 < orient.size(); i += 4) orientation.emplace_back(orient[i], orient[i + 1], orient[i + 2], orient[i + 3]);
    if (scale.empty()) scale.emplace_back(1.0, 1.0);
    if (orientation.empty()) orientation.emplace_back(0.0, 0.0, 1.0, 0.0);
    if (cross_section.size() < 2 || spine.size() < 2) {
      warn(n, fmt::format("Extrusion: {} cross-section and {} spine points: no surface", cross_section.size(), spine.size()));
      return {};
    }
    mesh::TriMesh m = detail::make_extrusion(cross_section, spine, scale, orientation, boolean(n, "beginCap", true),
                                             boolean(n, "endCap", true));
    if (!boolean(n, "ccw", true)) flip(m);
    return m;
  }

  static void flip(mesh::TriMesh& m) {
    for (auto& t : m.triangles) std::swap(t[1], t[2]);
  }

  // The points of a Coordinate. One with none, which a ROUTE from a CoordinateInterpolator
  // fills (an animation), is drawn at the interpolator's first key; HoF does not animate.
  std::vector<Vec3> points(pugi::xml_node coord) {
    std::vector<Vec3> out;
    const auto p = numbers(coord, "point");
    if (p.size() % 3 != 0)
      fail(coord, ErrorCode::kParse, fmt::format("<{}> field point: {} numbers, not a multiple of 3", coord.name(), p.size()));
    for (std::size_t i = 0; i + 2 < p.size(); i += 3) out.emplace_back(p[i], p[i + 1], p[i + 2]);
    const std::string_view def = coord.attribute("DEF").as_string();
    if (!out.empty() || def.empty()) return out;
    const Document& d = doc_of(coord);
    for (const pugi::xml_node route : d.routes) {
      const std::string_view to_field = route.attribute("toField").as_string();
      if (def != route.attribute("toNode").as_string() || (to_field != "point" && to_field != "set_point")) continue;
      const std::string_view from = route.attribute("fromNode").as_string();
      pugi::xml_node source;
      if (const auto it = d.defs.find(from); it != d.defs.end()) {
        for (pugi::xml_node candidate : it->second)
          if (std::string_view(candidate.name()) == "CoordinateInterpolator") source = candidate;
        if (!source && !it->second.empty()) source = it->second.back();
      }
      if (source && std::string_view(source.name()) == "CoordinateInterpolator") {
        const auto keys = numbers(source, "key");
        const auto values = tuples(source, "keyValue", 3, {});
        const std::size_t per_key = keys.empty() ? 0 : values.size() / 3 / keys.size();
        for (std::size_t i = 0; i < per_key; ++i) out.emplace_back(values[3 * i], values[3 * i + 1], values[3 * i + 2]);
        warn(coord, fmt::format("Coordinate '{}' has no points: a ROUTE (line {}) animates it from CoordinateInterpolator "
                                "'{}' (line {}); drawn still, at its first key (HoF does not animate)",
                                def, line_of(route), from, line_of(source)));
      } else {
        warn(coord, fmt::format("Coordinate '{}' has no points: they come through a ROUTE (line {}) from {} '{}', which "
                                "HoF does not run; the shape has no surface",
                                def, line_of(route), source ? source.name() : "an unknown node", from));
      }
      return out;
    }
    return out;
  }

  // The triangle and quad sets and IndexedFaceSet (19775-1, Rendering and Geometry3D): the
  // Coordinate's points grouped as the node says; ccw FALSE turns every triangle over.
  void composed_set(pugi::xml_node n, pugi::xml_node coord, mesh::TriMesh& m) {
    using detail::VertexGrouping;
    const std::string_view t = n.name();
    if (coord) m.vertices = points(coord);
    const bool indexed = t.starts_with("Indexed");
    const VertexGrouping grouping = t.ends_with("TriangleSet")      ? VertexGrouping::kTriangles
                                    : t.ends_with("QuadSet")        ? VertexGrouping::kQuads
                                    : t.ends_with("TriangleFanSet") ? VertexGrouping::kFans
                                    : t.ends_with("StripSet")       ? VertexGrouping::kStrips
                                                                    : VertexGrouping::kPolygons;
    const bool separated = grouping != VertexGrouping::kTriangles && grouping != VertexGrouping::kQuads;
    std::vector<std::vector<mesh::NodeIndex>> runs(1);
    const std::int64_t count = static_cast<std::int64_t>(m.vertices.size());
    if (indexed) {
      // Fans, strips and faces end at −1 (the last one may omit it); triangles and quads run on.
      for (std::int64_t i : integers(n, t == "IndexedFaceSet" ? "coordIndex" : "index")) {
        if (i == -1 && separated) {
          runs.emplace_back();
          continue;
        }
        if (i < 0 || i >= count)
          fail(n, ErrorCode::kInvalidMesh, fmt::format("<{}>: index {} out of range (the Coordinate has {} points)", t, i, count));
        runs.back().push_back(static_cast<mesh::NodeIndex>(i));
      }
    } else if (separated) {
      // fanCount / stripCount: how many of the points, in order, each fan or strip takes.
      const char* field = grouping == VertexGrouping::kFans ? "fanCount" : "stripCount";
      std::int64_t next = 0;
      runs.clear();
      for (std::int64_t c : integers(n, field)) {
        if (c < 0 || next + c > count) {
          warn(n, fmt::format("{}: {} {} past the {} points: the rest ignored", t, field, c, count));
          break;
        }
        runs.emplace_back();
        for (std::int64_t k = 0; k < c; ++k) runs.back().push_back(static_cast<mesh::NodeIndex>(next++));
      }
    } else {
      for (std::int64_t i = 0; i < count; ++i) runs.back().push_back(static_cast<mesh::NodeIndex>(i));
    }
    const std::size_t left_out = detail::append_grouped(m.triangles, grouping, runs);
    if (left_out > 0) {
      warn(n, fmt::format("{}: {} {} left over (not a whole {}): ignored", t, left_out, indexed ? "indices" : "points",
                          grouping == VertexGrouping::kQuads       ? "quad"
                          : grouping == VertexGrouping::kTriangles ? "triangle"
                                                                   : "triangle (fewer than 3)"));
    }
    if (!boolean(n, "ccw", true)) flip(m);
  }

  // ---- force effects beyond springs, viscosity and constant forces
  // MagneticGeometryEffect (H3D): a spring of springConstant toward the closest point of its
  // geometry, caught within startDistance and let go past escapeDistance. H3D's constructor
  // sets springConstant 100 (its header says 300): the constructor's value is the default.
  void magnetic_geometry_effect(pugi::xml_node n, const Mat4& X) {
    haptics::MagneticGeometryEffect e;
    e.enabled = boolean(n, "enabled", true);
    e.start_distance_m = number(n, "startDistance", 0.01);
    e.escape_distance_m = number(n, "escapeDistance", 0.01);
    e.spring_constant_n_per_m = number(n, "springConstant", 100.0);
    X3dShape scratch;
    auto surface = std::make_shared<mesh::TriMesh>();
    for (pugi::xml_node c_orig : n.children()) {
      if (!is_child(c_orig)) continue;
      const pugi::xml_node c = resolve(c_orig);
      if (!is_geometry(c.name())) {
        unsupported(c_orig);
        continue;
      }
      bool solid = true;
      *surface = geometry(c, solid, scratch);
      transform_mesh(*surface, X);
      break;  // an SFNode: the first geometry
    }
    if (surface->triangles.empty()) {
      warn(n, "MagneticGeometryEffect without a geometry (or with an empty one): no force");
      return;
    }
    e.surface = std::move(surface);
    scene_.force_effects.magnets.push_back(std::move(e));
  }

  // PositionFunctionEffect / TimeFunctionEffect (H3D): the force's x, y, z are functions of
  // the device position (world frame, m) or of time (s); GeneralFunction gives them as text.
  void function_effect(pugi::xml_node n) {
    const bool of_time = std::string_view(n.name()) == "TimeFunctionEffect";
    std::array<std::optional<haptics::FunctionExpression>, 3> f;
    const std::array<std::string_view, 3> fields{"xFunction", "yFunction", "zFunction"};
    for (pugi::xml_node c_orig : n.children()) {
      if (!is_child(c_orig)) continue;
      const pugi::xml_node c = resolve(c_orig);
      const std::string_view field = c_orig.attribute("containerField").as_string();
      const auto slot = std::ranges::find(fields, field);
      if (std::string_view(c.name()) != "GeneralFunction" || slot == fields.end()) {
        unsupported(c_orig);
        continue;
      }
      std::vector<std::string> params;
      for (std::string_view p : tokens(c.attribute("params").as_string())) params.emplace_back(p);
      const std::size_t wanted = of_time ? 1 : 3;
      if (params.size() != wanted) {
        // H3D ignores the effect then (it prints a warning): so does HoF.
        warn(c, fmt::format("{}: GeneralFunction params '{}' must name {} variable(s): the effect is ignored", n.name(),
                            c.attribute("params").as_string(), wanted));
        return;
      }
      auto expression = haptics::FunctionExpression::make(c.attribute("function").as_string(), params);
      if (!expression) fail(c, ErrorCode::kParse, fmt::format("<GeneralFunction> function: {}", expression.error().message));
      f[static_cast<std::size_t>(slot - fields.begin())] = *expression;
    }
    if (!f[0] || !f[1] || !f[2]) {
      warn(n, fmt::format("{}: xFunction, yFunction and zFunction are all needed (H3D ignores the effect otherwise): ignored",
                          n.name()));
      return;
    }
    if (of_time) scene_.force_effects.time_functions.push_back({*f[0], *f[1], *f[2]});
    else scene_.force_effects.position_functions.push_back({*f[0], *f[1], *f[2]});
  }

  // RotationalSpringEffect (H3D): a torque toward desiredAxis. HoF's devices render force
  // only (their torque output is zero), so it is read, and said to be not felt.
  void rotational_spring_effect(pugi::xml_node n) {
    unsupported(n, "(a torque: HoF renders forces only)");
  }

  // ---- options
  X3dHapticsOptions haptics_options(pugi::xml_node n) const {
    X3dHapticsOptions o;
    o.touchable_face = choice<X3dTouchableFace>(n, "touchableFace",
                                                {{"AS_GRAPHICS", X3dTouchableFace::kAsGraphics},
                                                 {"FRONT", X3dTouchableFace::kFront},
                                                 {"BACK", X3dTouchableFace::kBack},
                                                 {"FRONT_AND_BACK", X3dTouchableFace::kFrontAndBack}},
                                                o.touchable_face);
    o.max_distance_m = number(n, "maxDistance", o.max_distance_m);
    o.look_ahead_factor = number(n, "lookAheadFactor", o.look_ahead_factor);
    o.use_bound_tree = boolean(n, "useBoundTree", o.use_bound_tree);
    o.interpolate_force_effects = boolean(n, "interpolateForceEffects", o.interpolate_force_effects);
    o.dynamic_mode = choice<X3dDynamicMode>(n, "dynamicMode",
                                            {{"TRANSFORM_CHANGED", X3dDynamicMode::kTransformChanged},
                                             {"ALWAYS", X3dDynamicMode::kAlways},
                                             {"NEVER", X3dDynamicMode::kNever}},
                                            o.dynamic_mode);
    return o;
  }

  X3dBoundTreeOptions bound_tree_options(pugi::xml_node n) const {
    X3dBoundTreeOptions o;
    o.bound_type = choice<X3dBoundType>(
        n, "boundType", {{"AABB", X3dBoundType::kAabb}, {"OBB", X3dBoundType::kObb}, {"SPHERE", X3dBoundType::kSphere}},
        o.bound_type);
    const auto leaf = integers(n, "maxTrianglesInLeaf");
    if (!leaf.empty()) o.max_triangles_in_leaf = static_cast<std::int32_t>(leaf[0]);
    return o;
  }

  void global_settings(pugi::xml_node n) {
    if (!scene_.global_settings) scene_.global_settings.emplace();
    X3dGlobalSettings& g = *scene_.global_settings;
    for (pugi::xml_node c_orig : n.children()) {
      if (c_orig.type() != pugi::node_element) continue;
      const pugi::xml_node c = resolve(c_orig);
      const std::string_view t = c.name();
      if (t == "HapticsOptions") {
        if (!g.haptics) g.haptics = haptics_options(c);
      } else if (t == "GeometryBoundTreeOptions") {
        if (!g.bound_tree) g.bound_tree = bound_tree_options(c);
      } else if (t == "DebugOptions") {
        if (g.debug) continue;
        X3dDebugOptions d;
        d.draw_bound = boolean(c, "drawBound", false);
        const auto depth = integers(c, "drawBoundTree");
        if (!depth.empty()) d.draw_bound_tree = static_cast<std::int32_t>(depth[0]);
        d.draw_haptic_triangles = boolean(c, "drawHapticTriangles", false);
        d.print_shader_warnings = boolean(c, "printShaderWarnings", false);
        g.debug = d;
      } else {
        unsupported(c_orig);
      }
    }
  }

  // ---- devices
  void device_info(pugi::xml_node n) {
    for (pugi::xml_node c_orig : n.children()) {
      if (c_orig.type() != pugi::node_element) continue;
      const pugi::xml_node c = resolve(c_orig);
      if (!ends_with(c.name(), "Device")) {
        unsupported(c_orig);
        continue;
      }
      X3dDevice d;
      d.type = c.name();
      d.def = c.attribute("DEF").as_string();
      d.device_name = string(c, "deviceName", "");
      const auto pc = numbers(c, "positionCalibration", 16, {d.position_calibration.begin(), d.position_calibration.end()});
      std::copy(pc.begin(), pc.end(), d.position_calibration.begin());
      const auto oc = numbers(c, "orientationCalibration", 4, {1, 0, 0, 0});
      std::copy(oc.begin(), oc.end(), d.orientation_calibration.begin());
      d.force_limit_n = number(c, "forceLimit", -1.0);
      for (pugi::xml_node r_orig : c.children()) {
        if (r_orig.type() != pugi::node_element) continue;
        const pugi::xml_node r = resolve(r_orig);
        const std::string_view rt = r.name();
        const std::string_view field = r_orig.attribute("containerField").as_string();
        if (field == "stylus") continue;  // the drawn stylus: graphics only
        if (!ends_with(rt, "Renderer")) {
          unsupported(r_orig);
          continue;
        }
        if (d.renderer) continue;
        X3dRenderer renderer;
        renderer.type = rt;
        if (rt == "GodObjectRenderer") renderer.kind = haptics::RendererKind::kGodObject;
        if (rt == "RuspiniRenderer") {
          renderer.kind = haptics::RendererKind::kRuspini;
          renderer.proxy_radius_m = number(r, "proxyRadius", 0.0025);
        }
        d.renderer = renderer;
      }
      scene_.devices.push_back(std::move(d));
    }
  }

  std::vector<std::unique_ptr<Document>> docs_;  // [0] the scene; then Inlines and PROTO bodies
  std::map<std::size_t, pugi::xml_node> instances_;  // ProtoInstance → its body, made once
  std::vector<fs::path> inline_stack_;  // the files being read, outermost first
  static constexpr std::int64_t kMaxVisitedNodes = 200000;
  std::int64_t visited_{0};
  X3dScene scene_;
  int layer_{0};  // haptic layer of the shapes being visited
};

}  // namespace

Expected<X3dScene> read_x3d_scene(const std::filesystem::path& path) {
  std::ifstream in(path, std::ios::binary);
  if (!in) return make_error(ErrorCode::kIo, "cannot open X3D file", path.string());
  std::ostringstream buffer;
  buffer << in.rdbuf();
  try {
    X3dReader reader(path);
    return reader.run(buffer.str());
  } catch (const ParseFailure& f) {
    return std::unexpected(f.error);
  }
}

}  // namespace hof::scene
