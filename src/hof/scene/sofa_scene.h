#pragma once
/// @file
/// SOFA scene files (`.scn`) in both syntaxes — 2008's `<Object type="…"/>` and today's tag
/// names — for the components HoF's mechanics has, with the loaders that bring their data
/// (MeshGmshLoader, MeshOBJLoader, MeshTopology/`Mesh` with a file, the old `MeshLoader`,
/// `MechanicalObject filename=….xs3`), `@link` references and `src="@loader"`. Components
/// HoF does not simulate (RequiredPlugin, visual style, …) are listed in one warning and
/// skipped; the collision pipeline and the bodies' collision models become contact settings
/// (sofa_collision.cpp); nothing the user wrote is silently lost (`skipped` names them).
/// File paths resolve as SOFA's data repository does: the scene's folder (then its parent
/// folders), then each folder of `SOFA_DATA_PATH`, then `share/` and `examples/` under
/// `SOFA_ROOT` (sofa_data_folders()).

#include <filesystem>
#include <optional>
#include <string>
#include <vector>

#include "hof/core/error.h"
#include "hof/coupling/contact_settings.h"
#include "hof/mechanics/mechanical_model.h"
#include "hof/mesh/mesh.h"

namespace hof::scene {

/// One simulated body: a SOFA node with an ODE solver and a mechanical state.
struct SofaSceneModel {
  std::string node_path;                             ///< e.g. "lroot/Liver"
  mechanics::ModelConfig config;                     ///< ready for mechanics::build_model()
  std::optional<std::filesystem::path> visual_mesh;  ///< OglModel file (resolved), if any
  bool visual_barycentric{false};                    ///< a BarycentricMapping maps the volume to it
  /// A hexahedral grid's fine surface (the closed surface a SparseGridTopology was built
  /// from), to touch when the node has no mapped visual model: it follows the grid trilinearly.
  std::optional<mesh::TriMesh> fine_surface;
  /// Its collision models (Triangle/Line/Point/SphereCollisionModel in its node or in a node
  /// mapped from it); `enabled` false when it has none.
  coupling::BodyCollision collision;
};

/// A rigid, fixed obstacle: a node with a triangle collision model on a state (or loader) that
/// no ODE solver moves — SOFA's floors, tables and fixed organs.
struct SofaSceneObstacle {
  std::string node_path;
  std::string name;
  mesh::TriMesh surface;              ///< scene units
  coupling::BodyCollision collision;  ///< its collision models (a floor collides with the bodies)
};

struct SofaScene {
  std::filesystem::path file;
  std::vector<SofaSceneModel> models;
  std::vector<SofaSceneObstacle> obstacles;
  /// Contact between bodies: the collision pipeline, intersection method and response
  /// (`enabled` when the scene has a pipeline and a response). Distances and stiffnesses are in
  /// scene units.
  coupling::ContactSettings contacts;
  std::vector<std::string> skipped;  ///< "TYPE 'name' (line N)" of every component not simulated
  /// Components HoF needs no counterpart of (plugins, display, the default loops, collision
  /// detection without a response): read, not simulated, changing nothing.
  std::vector<std::string> ignored;
  std::vector<std::string> warnings;  ///< "FILE:LINE: ..." notes (defaults assumed, aliases used)
};

/// Reads and validates a scene. Errors name the file, the line and the component
/// (malformed XML, a missing mesh, a bad attribute value, an unresolved @link).
[[nodiscard]] Expected<SofaScene> read_sofa_scene(const std::filesystem::path& path);

/// The folders a relative file named by a scene in `scene_folder` is looked up in, in order:
/// the scene's folder and its parents (HoF's bundled layout, where `mesh/` sits beside or above
/// the scene), then SOFA's data repository: each entry of the environment's `SOFA_DATA_PATH`
/// (separated by ':' as SOFA's FileRepository splits it on Unix), then `$SOFA_ROOT/share` and
/// `$SOFA_ROOT/examples`. Folders that do not exist are left out.
[[nodiscard]] std::vector<std::filesystem::path> sofa_data_folders(const std::filesystem::path& scene_folder);
/// A scene held in memory (a project's inline scene, as edited in the window): `path` names
/// it in errors and its folder anchors the scene's relative files.
[[nodiscard]] Expected<SofaScene> read_sofa_scene_text(const std::string& text, const std::filesystem::path& path);

}  // namespace hof::scene
