#include "hof/scene/sofa_scene_edit.h"

#include <fmt/format.h>
#include <pugixml.hpp>

#include <fstream>
#include <optional>
#include <sstream>

namespace hof::scene {

namespace {

namespace fs = std::filesystem;

/// The name a component goes by in the scene tree (as the reader names it).
std::string component_name(const pugi::xml_node& e) {
  if (const auto a = e.attribute("name")) return a.value();
  if (const auto a = e.attribute("pluginName")) return a.value();
  if (std::string_view(e.name()) == "Object") return e.attribute("type").value();
  return e.name();
}

pugi::xml_node find_node(const pugi::xml_node& from, const std::string& name) {
  for (pugi::xml_node n : from.children("Node")) {
    if (n.attribute("name").as_string("Node") == name) return n;
    if (pugi::xml_node inner = find_node(n, name)) return inner;
  }
  return {};
}

std::string print(const pugi::xml_document& doc) {
  std::ostringstream out;
  for (pugi::xml_node n : doc.children()) {
    if (n.type() == pugi::node_element) n.print(out, "  ", pugi::format_indent, pugi::encoding_utf8, 2);
  }
  return out.str();
}

/// A relative file name resolved as SOFA does: the folder, then its parents.
std::optional<fs::path> resolve(const fs::path& folder, const fs::path& relative) {
  std::error_code ec;
  for (fs::path dir = fs::absolute(folder, ec);; dir = dir.parent_path()) {
    if (fs::is_regular_file(dir / relative, ec)) return fs::weakly_canonical(dir / relative, ec);
    if (dir == dir.parent_path() || dir.empty()) break;
  }
  return std::nullopt;
}

void reanchor(pugi::xml_node node, const fs::path& from, const fs::path& to) {
  for (pugi::xml_attribute a : node.attributes()) {
    const std::string key = a.name();
    if (!key.starts_with("file")) continue;  // filename, fileMesh, fileTopology, fileMass, ...
    const fs::path value(a.value());
    if (value.empty() || value.is_absolute()) continue;
    const auto was = resolve(from, value);
    if (!was) continue;
    const auto now = resolve(to, value);
    if (now && *now == *was) continue;  // already resolves to the same file
    std::error_code ec;
    const fs::path folder = fs::weakly_canonical(fs::absolute(to, ec), ec);
    const fs::path relative = fs::relative(*was, folder, ec);
    // Relative when the two share a folder below the root; else absolute (../../../usr/...
    // would break as soon as the project moves).
    std::size_t climbs = 0;
    for (const fs::path& part : relative) climbs += part == ".." ? 1 : 0;
    std::size_t depth = 0;
    for (const fs::path& part : folder.relative_path()) depth += part.empty() ? 0 : 1;
    const bool via_root = climbs >= depth;
    a.set_value((ec || relative.empty() || via_root ? *was : relative).generic_string().c_str());
  }
  for (pugi::xml_node child : node.children()) {
    if (child.type() == pugi::node_element) reanchor(child, from, to);
  }
}

}  // namespace

Expected<std::string> edit_scene(const std::string& scene_xml, const SceneEdit& edit) {
  pugi::xml_document doc;
  if (const auto parsed = doc.load_string(scene_xml.c_str()); !parsed) {
    return make_error(ErrorCode::kParse, fmt::format("the scene is not valid XML: {}", parsed.description()));
  }
  pugi::xml_node root = doc.document_element();
  if (std::string_view(root.name()) != "Node") return make_error(ErrorCode::kParse, "the scene's root is not a <Node>");
  pugi::xml_node node = root.attribute("name").as_string("Node") == edit.node ? root : find_node(root, edit.node);
  if (!node) return make_error(ErrorCode::kInvalidArgument, fmt::format("the scene has no node '{}'", edit.node));
  const bool legacy = doc.find_node([](const pugi::xml_node& n) { return std::string_view(n.name()) == "Object"; });

  // The component: in the node, else in an ancestor (a solver shared by several bodies).
  pugi::xml_node component;
  std::string names;
  for (pugi::xml_node n = node; n && !component; n = n.parent()) {
    if (std::string_view(n.name()) != "Node") break;
    for (pugi::xml_node c : n.children()) {
      if (c.type() != pugi::node_element || std::string_view(c.name()) == "Node") continue;
      if (n == node) names += (names.empty() ? "" : ", ") + component_name(c);
      if (component_name(c) == edit.component) {
        component = c;
        break;
      }
    }
  }
  // A component the file left unnamed goes by its type: its replacement stays unnamed (it then
  // goes by its new type), rather than carrying the old type as a name.
  const bool named = edit.action == SceneEdit::Action::kAdd ||
                     (component && (component.attribute("name") || component.attribute("pluginName")));
  const auto fill = [&](pugi::xml_node e) {
    if (legacy) e.append_attribute("type") = edit.type.c_str();
    if (named) e.append_attribute("name") = edit.component.c_str();
    for (const auto& [key, value] : edit.attributes) {
      if (key == "name" || (legacy && key == "type")) continue;
      e.append_attribute(key.c_str()) = value.c_str();
    }
  };
  const char* tag = legacy ? "Object" : edit.type.c_str();
  switch (edit.action) {
    case SceneEdit::Action::kReplace:
    case SceneEdit::Action::kRemove: {
      if (!component) {
        return make_error(ErrorCode::kInvalidArgument,
                          fmt::format("node '{}' has no component '{}' (it has: {})", edit.node, edit.component,
                                      names.empty() ? std::string("none") : names));
      }
      if (edit.action == SceneEdit::Action::kRemove) {
        component.parent().remove_child(component);
        break;
      }
      if (edit.type.empty()) return make_error(ErrorCode::kInvalidArgument, "a replacement needs a type");
      pugi::xml_node parent = component.parent();
      pugi::xml_node made = parent.insert_child_before(tag, component);
      fill(made);
      parent.remove_child(component);
      break;
    }
    case SceneEdit::Action::kAdd: {
      if (edit.type.empty() || edit.component.empty())
        return make_error(ErrorCode::kInvalidArgument, "a new component needs a type and a name");
      if (component && component.parent() == node) {
        return make_error(ErrorCode::kInvalidArgument,
                          fmt::format("node '{}' already has a component '{}'", edit.node, edit.component));
      }
      // Before the node's child nodes, so the component reads as the node's own.
      pugi::xml_node first_child = node.child("Node");
      pugi::xml_node made = first_child ? node.insert_child_before(tag, first_child) : node.append_child(tag);
      fill(made);
      break;
    }
  }
  return print(doc);
}

Expected<std::string> inline_scene(const fs::path& scene_file, const fs::path& project_folder) {
  std::ifstream in(scene_file, std::ios::binary);
  if (!in)
    return make_error(ErrorCode::kIo, fmt::format("cannot open scene '{}'", scene_file.string()), scene_file.string());
  std::ostringstream text;
  text << in.rdbuf();
  pugi::xml_document doc;
  if (const auto parsed = doc.load_string(text.str().c_str()); !parsed) {
    return make_error(ErrorCode::kParse, fmt::format("malformed XML: {}", parsed.description()), scene_file.string());
  }
  if (std::string_view(doc.document_element().name()) != "Node") {
    return make_error(ErrorCode::kParse, "the scene's root is not a <Node>", scene_file.string());
  }
  reanchor(doc.document_element(), scene_file.parent_path(), project_folder);
  return print(doc);
}

std::string reanchor_scene_files(const std::string& scene_xml, const fs::path& from_folder, const fs::path& to_folder) {
  pugi::xml_document doc;
  if (!doc.load_string(scene_xml.c_str())) return scene_xml;
  reanchor(doc.document_element(), from_folder, to_folder);
  return print(doc);
}

}  // namespace hof::scene
