// The X3D files of a scene and their nodes' field values (detail/x3d_source.h): parsing with
// lines kept, DEF/USE, PROTO instances (19775-1 clause 4.4.4: the first node of the body, IS
// connections substituted), Inlines read once.

#include "hof/scene/detail/x3d_source.h"

#include <algorithm>
#include <cctype>
#include <charconv>
#include <cmath>
#include <fstream>
#include <sstream>

#include "hof/mesh/xml_depth.h"

namespace hof::scene::detail {

namespace fs = std::filesystem;

std::vector<std::string_view> x3d_tokens(std::string_view text) {
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

std::vector<std::string> x3d_mf_string(std::string_view text) {
  std::vector<std::string> out;
  if (text.find('"') == std::string_view::npos) {
    const auto t = x3d_tokens(text);
    if (!t.empty()) out.emplace_back(text.substr(text.find_first_not_of(" \t\r\n")));
    while (!out.empty() && !out.back().empty() && std::isspace(static_cast<unsigned char>(out.back().back())))
      out.back().pop_back();
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

bool x3d_is_remote(std::string_view url) {
  return url.find("://") != std::string_view::npos || url.starts_with("urn:");
}

std::filesystem::path X3dSource::weakly_canonical(const std::filesystem::path& p) {
  std::error_code ec;
  fs::path c = fs::weakly_canonical(p, ec);
  return ec ? p : c;
}

X3dDocument& X3dSource::parse(fs::path file, std::string text, const X3dDocument* scope, int proto_depth) {
  auto doc = std::make_unique<X3dDocument>();
  doc->file = std::move(file);
  doc->text = std::move(text);
  doc->scope = scope;
  doc->proto_depth = proto_depth;
  for (std::size_t i = 0; i < doc->text.size(); ++i)
    if (doc->text[i] == '\n') doc->line_starts.push_back(static_cast<std::ptrdiff_t>(i + 1));
  const auto parsed = doc->xml.load_buffer(doc->text.data(), doc->text.size(), pugi::parse_default);
  if (!parsed)
    fail_at(doc->file, line_in(*doc, parsed.offset), ErrorCode::kParse,
            fmt::format("malformed XML: {}", parsed.description()));
  if (const pugi::xml_node deep = mesh::first_too_deep_element(doc->xml)) {
    fail_at(doc->file, line_in(*doc, deep.offset_debug()), ErrorCode::kParse,
            fmt::format("<{}> is nested deeper than {} levels", deep.name(), mesh::kMaxXmlDepth));
  }
  collect(*doc, doc->xml);
  docs_.push_back(std::move(doc));
  return *docs_.back();
}

// DEF names and PROTO declarations of a document.
void X3dSource::collect(X3dDocument& doc, pugi::xml_node n) {
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

const X3dDocument& X3dSource::doc_of(pugi::xml_node n) const {
  const pugi::xml_node root = n.root();
  for (const auto& d : docs_)
    if (d->xml == root) return *d;
  return *docs_.front();
}

std::int64_t X3dSource::line_in(const X3dDocument& d, std::ptrdiff_t offset) {
  return std::upper_bound(d.line_starts.begin(), d.line_starts.end(), offset) - d.line_starts.begin();
}

std::int64_t X3dSource::line_of(pugi::xml_node n) const {
  if (const pugi::xml_attribute l = n.attribute("hof-line")) return l.as_llong();
  return line_in(doc_of(n), n.offset_debug());
}

std::string X3dSource::where(pugi::xml_node n) const {
  return fmt::format("{}:{}", doc_of(n).file.string(), line_of(n));
}

void X3dSource::fail_at(const std::filesystem::path& file, std::int64_t line, ErrorCode code, std::string message) {
  throw X3dParseFailure{Error{code, std::move(message), file.string(), line, -1}};
}

void X3dSource::fail(pugi::xml_node n, ErrorCode code, std::string message) const {
  fail_at(doc_of(n).file, line_of(n), code, std::move(message));
}

void X3dSource::warn(pugi::xml_node n, std::string_view message) {
  warnings_.push_back(fmt::format("{}: {}", where(n), message));
}

// ---- DEF/USE and PROTO instances
// The node a possible USE element stands for: the last node DEF'd with that name before it
// (in a PROTO body, else in the document it was declared in).
pugi::xml_node X3dSource::resolve_use(pugi::xml_node n) const {
  const std::string_view use = n.attribute("USE").as_string();
  if (use.empty()) return n;
  pugi::xml_node found;
  for (const X3dDocument* d = &doc_of(n); d && !found; d = d->scope) {
    const auto it = d->defs.find(use);
    if (it == d->defs.end()) continue;
    for (pugi::xml_node def : it->second)
      if (d != &doc_of(n) || def.offset_debug() < n.offset_debug()) found = def;
  }
  if (!found)
    fail(n, ErrorCode::kParse, fmt::format("<{} USE='{}'>: no node DEF'd with that name before", n.name(), use));
  // A USE inside the node it names would contain itself: an endless tree.
  for (pugi::xml_node a = n.parent(); a; a = a.parent()) {
    if (a == found) {
      fail(n, ErrorCode::kParse,
           fmt::format("<{} USE='{}'> is inside the node it names (line {}): a cycle", n.name(), use, line_of(found)));
    }
  }
  return found;
}

pugi::xml_node X3dSource::resolve(pugi::xml_node n) {
  n = resolve_use(n);
  if (std::string_view(n.name()) == "ProtoInstance") {
    if (const pugi::xml_node body = instantiate(n)) return body;
  }
  return n;
}

// The declaration of PROTO `name` seen from `doc` (an ExternProtoDeclare is followed to the
// ProtoDeclare in its file). Null when there is none (the instance is then not modelled).
pugi::xml_node X3dSource::declaration(pugi::xml_node at, std::string_view name) {
  for (const X3dDocument* d = &doc_of(at); d; d = d->scope) {
    const auto it = d->protos.find(name);
    if (it == d->protos.end()) continue;
    const pugi::xml_node decl = it->second;
    if (std::string_view(decl.name()) == "ProtoDeclare") return decl;
    // ExternProtoDeclare: the first url found beside the file, "FILE#NAME" (NAME defaults
    // to the extern's own name).
    for (const std::string& url : x3d_mf_string(decl.attribute("url").as_string())) {
      if (x3d_is_remote(url)) continue;
      const std::size_t hash = url.find('#');
      const fs::path path = d->file.parent_path() / url.substr(0, hash);
      const std::string target = hash == std::string::npos ? std::string(name) : url.substr(hash + 1);
      if (!fs::is_regular_file(path)) continue;
      const X3dDocument& ext = load(decl, path);
      const auto found = ext.protos.find(target);
      if (found != ext.protos.end() && std::string_view(found->second.name()) == "ProtoDeclare") return found->second;
    }
    warn(decl, fmt::format("ExternProtoDeclare '{}': no ProtoDeclare found at its url {}", name,
                           decl.attribute("url").as_string()));
    return {};
  }
  return {};
}

// A ProtoInstance: a copy of the first node of its PROTO's body, with every IS/connect
// replaced by the instance's fieldValue (or the interface's default), as 19775-1's prototype semantics say. The
// other body nodes are not rendered (the spec: only the first node is the instance's type).
pugi::xml_node X3dSource::instantiate(pugi::xml_node instance) {
  if (const auto it = instances_.find(instance.hash_value()); it != instances_.end()) return it->second;
  const std::string name = instance.attribute("name").as_string();
  const pugi::xml_node decl = declaration(instance, name);
  if (!decl) return {};
  const X3dDocument& home = doc_of(decl);
  if (doc_of(instance).proto_depth >= kMaxProtoDepth) {
    fail(instance, ErrorCode::kParse,
         fmt::format(
             "ProtoInstance '{}': PROTOs instantiated more than {} deep (a PROTO whose body instantiates itself?)",
             name, kMaxProtoDepth));
  }
  pugi::xml_node first;
  for (pugi::xml_node c : decl.child("ProtoBody").children())
    if (c.type() == pugi::node_element) {
      first = c;
      break;
    }
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
  X3dDocument& d = parse(home.file, text.str(), &home, doc_of(instance).proto_depth + 1);
  const pugi::xml_node result = d.xml.document_element();
  instances_[instance.hash_value()] = result;
  return result;
}

// Every element of `copy` gets the line of its original (its text is not the file's).
void X3dSource::mark_lines(pugi::xml_node original, pugi::xml_node copy) const {
  if (!copy.attribute("hof-line")) copy.append_attribute("hof-line") = static_cast<long long>(line_of(original));
  pugi::xml_node c = copy.first_child();
  for (pugi::xml_node o = original.first_child(); o && c; o = o.next_sibling(), c = c.next_sibling())
    if (o.type() == pugi::node_element) mark_lines(o, c);
}

void X3dSource::substitute(pugi::xml_node n, const std::map<std::string, pugi::xml_node, std::less<>>& values,
                           pugi::xml_node instance) {
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
const X3dDocument& X3dSource::load(pugi::xml_node at, const std::filesystem::path& path) {
  const fs::path key = weakly_canonical(path);
  for (const auto& d : docs_)
    if (d->scope == nullptr && weakly_canonical(d->file) == key) return *d;
  std::ifstream in(path, std::ios::binary);
  if (!in) fail(at, ErrorCode::kIo, fmt::format("cannot open '{}'", path.string()));
  std::ostringstream buffer;
  buffer << in.rdbuf();
  return parse(path, buffer.str(), nullptr, 0);
}

// ---- field values (empty or missing attribute = default)
std::vector<double> X3dSource::numbers(pugi::xml_node n, const char* field) const {
  std::vector<double> out;
  for (std::string_view tok : x3d_tokens(n.attribute(field).as_string())) {
    if (!tok.empty() && tok.front() == '+') tok.remove_prefix(1);
    double v = 0.0;
    const auto [ptr, ec] = std::from_chars(tok.data(), tok.data() + tok.size(), v);
    if (ec != std::errc{} || ptr != tok.data() + tok.size() || !std::isfinite(v))
      fail(n, ErrorCode::kParse, fmt::format("<{}> field {}: '{}' is not a number", n.name(), field, tok));
    out.push_back(v);
  }
  return out;
}

std::vector<double> X3dSource::numbers(pugi::xml_node n, const char* field, std::size_t count,
                                       std::vector<double> def) const {
  auto v = numbers(n, field);
  if (v.empty()) return def;
  if (v.size() != count)
    fail(n, ErrorCode::kParse,
         fmt::format("<{}> field {}: expected {} numbers, got {}", n.name(), field, count, v.size()));
  return v;
}

Vec3 X3dSource::vec3(pugi::xml_node n, const char* field, const Vec3& def) const {
  const auto v = numbers(n, field, 3, {def.x(), def.y(), def.z()});
  return {v[0], v[1], v[2]};
}

std::vector<double> X3dSource::tuples(pugi::xml_node n, const char* field, std::size_t width,
                                      std::vector<double> def) const {
  auto v = numbers(n, field);
  if (v.empty() && !n.attribute(field)) return def;
  if (v.size() % width != 0)
    fail(n, ErrorCode::kParse,
         fmt::format("<{}> field {}: {} numbers, not a multiple of {}", n.name(), field, v.size(), width));
  return v;
}

std::vector<std::int64_t> X3dSource::integers(pugi::xml_node n, const char* field) const {
  std::vector<std::int64_t> out;
  for (double v : numbers(n, field)) {
    if (v != std::floor(v))
      fail(n, ErrorCode::kParse, fmt::format("<{}> field {}: {} is not an integer", n.name(), field, v));
    // Past ±2⁶³ the conversion is undefined (found by fuzz_x3d): no index or count is that large.
    if (!(v >= -0x1p63 && v < 0x1p63))
      fail(n, ErrorCode::kParse, fmt::format("<{}> field {}: {} is out of range", n.name(), field, v));
    out.push_back(static_cast<std::int64_t>(v));
  }
  return out;
}

std::int64_t X3dSource::integer(pugi::xml_node n, const char* field, std::int64_t def) const {
  const auto v = integers(n, field);
  return v.empty() ? def : v[0];
}

bool X3dSource::boolean(pugi::xml_node n, const char* field, bool def) const {
  const std::string_view s = n.attribute(field).as_string();
  if (s.empty()) return def;
  if (s == "true" || s == "TRUE" || s == "True") return true;
  if (s == "false" || s == "FALSE" || s == "False") return false;
  fail(n, ErrorCode::kParse, fmt::format("<{}> field {}: '{}' is not a boolean", n.name(), field, s));
}

std::string X3dSource::string(pugi::xml_node n, const char* field, std::string_view def) const {
  std::string s = n.attribute(field).as_string();
  if (s.size() >= 2 && s.front() == '"' && s.back() == '"') s = s.substr(1, s.size() - 2);
  return s.empty() ? std::string(def) : s;
}

}  // namespace hof::scene::detail
