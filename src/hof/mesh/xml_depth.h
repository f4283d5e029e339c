#pragma once
/// @file
/// A limit on how deeply the XML files HoF reads (SOFA scenes, X3D, projects, VTU) may nest
/// their elements. The readers walk the tree recursively, and some output (an indented inline
/// scene) grows with the square of the depth: a file nesting 20,000 elements would overflow
/// the stack or run for minutes. Real scenes nest a few dozen levels.

#include <pugixml.hpp>

namespace hof::mesh {

inline constexpr int kMaxXmlDepth = 256;

/// The first element of `doc` nested deeper than kMaxXmlDepth levels (document order), or an
/// empty node when there is none. pugixml walks the tree without recursion.
[[nodiscard]] inline pugi::xml_node first_too_deep_element(pugi::xml_document& doc) {
  struct Walker final : pugi::xml_tree_walker {
    pugi::xml_node found;
    bool for_each(pugi::xml_node& node) override {
      if (node.type() == pugi::node_element && depth() >= kMaxXmlDepth) {
        found = node;
        return false;  // stop at the first
      }
      return true;
    }
  } walker;
  doc.traverse(walker);
  return walker.found;
}

}  // namespace hof::mesh
