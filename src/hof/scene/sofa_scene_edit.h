#pragma once
/// @file
/// Structural edits of a SOFA scene held as text (the window's scene tree: switch a force
/// field or a solver, add or remove a component), and moving a scene into a project. The
/// result is a scene again, in the file's own syntax (2008 `<Object type>` or today's tags),
/// so that what a user builds in the window is what SOFA and the next session read.

#include <filesystem>
#include <string>
#include <utility>
#include <vector>

#include "hof/core/error.h"

namespace hof::scene {

struct SceneEdit {
  enum class Action : std::uint8_t {
    kReplace,  ///< `component` of `node` becomes a `type` with `attributes` (keeps its place and name)
    kAdd,      ///< a `type` named `component` with `attributes` is added to `node`
    kRemove,   ///< `component` of `node` is removed
  };
  Action action{Action::kReplace};
  std::string node;       ///< the body: its node's name (a component in an ancestor node is found too)
  std::string component;  ///< the component's name as the scene tree shows it (its `name`, else its type)
  std::string type;       ///< SOFA type (replace, add)
  std::vector<std::pair<std::string, std::string>> attributes;  ///< of the new component (name excluded)
};

/// `scene_xml` (a `<Node>` tree) with `edit` made. Errors name the node or component that is
/// not there (listing those that are), or an unparsable scene; the text is unchanged then.
[[nodiscard]] Expected<std::string> edit_scene(const std::string& scene_xml, const SceneEdit& edit);

/// The scene of `scene_file` as text to hold inline in a project that lives in `project_folder`:
/// the XML declaration and comments dropped, every relative file name (`filename`,
/// `fileMesh`, ...) rewritten to resolve from the project's folder as it did from the scene's.
[[nodiscard]] Expected<std::string> inline_scene(const std::filesystem::path& scene_file,
                                                 const std::filesystem::path& project_folder);

/// `scene_xml` with its relative file names re-anchored from `from_folder` to `to_folder`
/// (a project with an inline scene saved elsewhere). Names that do not resolve are kept.
[[nodiscard]] std::string reanchor_scene_files(const std::string& scene_xml, const std::filesystem::path& from_folder,
                                               const std::filesystem::path& to_folder);

}  // namespace hof::scene
