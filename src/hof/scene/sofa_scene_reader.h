#pragma once
/// @file
/// Internals of the SOFA scene reader (hof::scene::detail): the scene graph as written, the
/// geometry a loader/topology/state provides, and the Reader that turns them into models.
/// sofa_scene.cpp builds the graph and resolves links and files; sofa_scene_model.cpp maps a
/// model node's components to mechanics configs.

#include <algorithm>
#include <cstdint>
#include <filesystem>
#include <memory>
#include <optional>
#include <set>
#include <string>
#include <string_view>
#include <unordered_map>
#include <utility>
#include <vector>

#include <fmt/format.h>
#include <pugixml.hpp>

#include "hof/scene/sofa_legacy_formats.h"
#include "hof/scene/sofa_scene.h"

namespace hof::scene::detail {

namespace fs = std::filesystem;
using mechanics::ModelConfig;

// ---- the scene graph as written ---------------------------------------------------------------

struct SceneNode;

/// One component element (`<Foo …/>` or `<Object type="Foo" …/>`).
struct Component {
  std::string type;     ///< SOFA class name after the alias table
  std::string written;  ///< the type as written in the file
  std::string name;
  std::vector<std::pair<std::string, std::string>> attrs;
  std::int64_t line{0};
  SceneNode* node{nullptr};
  std::size_t index{0};  ///< position among the node's components
  bool used{false};

  [[nodiscard]] const std::string* attr(std::string_view key) const {
    for (const auto& [k, v] : attrs)
      if (k == key) return &v;
    return nullptr;
  }
  [[nodiscard]] std::string label() const { return fmt::format("{} '{}' (line {})", written, name, line); }
};

/// One `<Node>`, with dt and gravity inherited from its parent unless set.
struct SceneNode {
  std::string name;
  std::string path;
  SceneNode* parent{nullptr};
  std::vector<std::unique_ptr<Component>> components;
  std::vector<std::unique_ptr<SceneNode>> children;
  double dt_s{0.01};
  Vec3 gravity{0.0, -9.81, 0.0};
  std::int64_t line{0};
  /// Why the node's own state is not simulated (e.g. a rigid instrument's Rigid3d state); empty
  /// when it is, or when the node has no state.
  std::string not_simulated_why;
};

/// Geometry a loader, topology or state provides (a field is "set" when its flag is).
struct MeshData {
  std::vector<Vec3> positions;                 ///< (N) scene units
  std::vector<mesh::Tet> tets;                 ///< (T)
  std::vector<mesh::Tri> triangles;            ///< (F)
  std::vector<std::int32_t> tet_regions;       ///< empty, or (T) Gmsh physical tag per tetrahedron
  std::vector<std::int32_t> triangle_regions;  ///< empty, or (F) Gmsh physical tag per triangle
  bool has_positions{false};
  bool has_tets{false};
  bool has_triangles{false};
  std::optional<fs::path> file;  ///< resolved file the data came from
  std::optional<Xs3File> xs3;    ///< the Xsp file, when positions came from one
};

/// SOFA component categories (after the alias table).
[[nodiscard]] bool is_ode_solver(std::string_view type);
[[nodiscard]] bool is_linear_solver(std::string_view type);
[[nodiscard]] bool is_loader(std::string_view type);
[[nodiscard]] bool is_topology(std::string_view type);
[[nodiscard]] bool is_mapping(std::string_view type);
[[nodiscard]] bool is_vec3_template(std::string_view tmpl);
/// `s` without surrounding blanks; `s` in lower case.
[[nodiscard]] std::string_view trim(std::string_view s);
[[nodiscard]] std::string lower(std::string s);
/// Copies into `d` every field `from` has and `d` lacks.
void fill_missing(MeshData& d, const MeshData& from);

// ---- the reader -------------------------------------------------------------------------------

/// Reads one scene file: graph → links/files → models. Single use: `Reader(path).run()`.
class Reader {
 public:
  explicit Reader(fs::path path) : path_(std::move(path)) {}
  /// A scene held in memory (`text`); `path` names it in errors and anchors relative files.
  Reader(fs::path path, std::string text) : path_(std::move(path)), text_(std::move(text)), have_text_(true) {}

  Expected<SofaScene> run();

 private:
  // Errors and notes.
  std::unexpected<Error> fail(ErrorCode code, std::int64_t line, std::string message) const {
    return make_error(code, std::move(message), path_.string(), line);
  }
  std::unexpected<Error> fail(const Component& c, std::string message, ErrorCode code = ErrorCode::kParse) const {
    return fail(code, c.line, fmt::format("{}: {}", c.label(), message));
  }
  void warn(std::int64_t line, std::string message) {
    scene_.warnings.push_back(fmt::format("{}:{}: {}", path_.string(), line, message));
  }
  [[nodiscard]] std::int64_t line_of(std::ptrdiff_t offset) const {
    if (offset < 0) return 0;
    const auto it = std::ranges::upper_bound(line_starts_, static_cast<std::size_t>(offset));
    return static_cast<std::int64_t>(it - line_starts_.begin());
  }

  // Building the graph.
  Expected<void> build_node(const pugi::xml_node& xml, SceneNode& node);
  /// Unknown component types refused (or, with a plugin from outside SOFA, named); unknown
  /// attributes of the components whose data HoF knows, warned about.
  Expected<void> check_types_and_attributes();
  [[nodiscard]] std::string_view not_simulated_why(const SceneNode& node) const;

  // Attribute values.
  Expected<std::vector<double>> numbers(const Component& c, std::string_view key, const std::string& text) const;
  Expected<std::optional<double>> number(const Component& c, std::string_view key) const;
  Expected<std::optional<Vec3>> vec3(const Component& c, std::string_view key) const;
  Expected<std::optional<std::vector<std::int32_t>>> indices(const Component& c, std::string_view key) const;
  Expected<std::optional<bool>> boolean(const Component& c, std::string_view key) const;

  // Links and data.
  Expected<Component*> resolve_link(const Component& from, std::string_view key, std::string_view link,
                                    std::string& field);
  Expected<fs::path> resolve_file(const Component& c, std::string_view key, const std::string& file) const;
  Expected<const MeshData*> data_of(Component& c);
  /// data_of(), with a surface loader's file read too (a link to a MeshOBJLoader's position or
  /// triangles needs them; otherwise its visual file is only named).
  Expected<const MeshData*> linked_data_of(Component& c);
  Expected<MeshData> compute_data(Component& c);
  Expected<void> read_file_into(Component& c, std::string_view key, MeshData& d);
  struct Transform {
    Vec3 translation{Vec3::Zero()};
    Vec3 rotation_deg{Vec3::Zero()};
    Vec3 scale{Vec3::Ones()};
    [[nodiscard]] bool identity() const {
      return translation.isZero(0.0) && rotation_deg.isZero(0.0) && scale == Vec3::Ones();
    }
  };
  Expected<Transform> read_transform(Component& c, bool legacy);
  Expected<void> transform_loader(Component& c, MeshData& d);
  Expected<void> transform_state(Component& c, MeshData& d);
  Expected<void> read_field(Component& c, std::string_view key, std::string_view field, MeshData& d);

  // Models.
  Expected<void> collect_models(SceneNode& node);
  Expected<SofaSceneModel> make_model(SceneNode& node, Component* state);
  // The stages of make_model().
  Expected<void> read_geometry(SceneNode& node, Component* state, SofaSceneModel& out);
  Expected<void> apply_solvers(SceneNode& node, ModelConfig& m);
  Expected<void> apply_components(SceneNode& node, ModelConfig& m);
  Expected<std::optional<SofaSceneObstacle>> make_obstacle(SceneNode& node, Component* state);
  Expected<void> apply_ode(Component& c, ModelConfig& m, bool& cg_embedded);
  Expected<void> apply_linear(Component& c, ModelConfig& m);
  Expected<void> apply_mass(Component& c, ModelConfig& m, std::size_t n);
  Expected<void> apply_force_field(Component& c, ModelConfig& m);
  // The config of each kind of force field apply_force_field() reads.
  Expected<mechanics::TetrahedronFemConfig> tetrahedron_fem_config(Component& c, const ModelConfig& m);
  Expected<mechanics::NeoHookeanConfig> neo_hookean_config(Component& c);
  Expected<mechanics::HexahedronFemConfig> hexahedron_fem_config(Component& c, const ModelConfig& m);
  Expected<mechanics::TriangleFemConfig> triangle_fem_config(Component& c, const ModelConfig& m);
  Expected<mechanics::MeshSpringConfig> mesh_springs_config(Component& c);
  /// MeshSpringForceField's HoF extensions: `stiffnessRule`, `tangent`.
  Expected<void> spring_rule_extensions(Component& c, mechanics::MeshSpringConfig& s);
  Expected<mechanics::ConstantForceConfig> constant_force_config(Component& c, const ModelConfig& m);
  /// A RegularGridTopology or SparseGridTopology as the model's nodes and hexahedra.
  Expected<void> apply_grid(Component& grid, SofaSceneModel& out);
  Expected<void> elastic_lists(Component& c, double default_young, double default_poisson, std::size_t elements,
                               const char* element_name, double& young, std::vector<double>& young_list,
                               double& poisson, std::vector<double>& poisson_list);
  Expected<void> apply_fixed(Component& c, ModelConfig& m);
  Expected<void> apply_visual(SceneNode& node, SofaSceneModel& model);
  void list_skipped(const SceneNode& node);

  // Contact between bodies (sofa_collision.cpp).
  /// The collision pipeline, intersection method and response anywhere in the scene, as the
  /// world's contact settings (scene_.contacts).
  Expected<void> read_contacts(SceneNode& root);
  /// The collision models of a body: those in its node and in the nodes mapped from it (a
  /// collision surface, SOFA's collision spheres). `has_surface`: the body has a surface to
  /// collide (its volume's boundary, its triangles, a mapped visual surface); `rigid`: an
  /// obstacle (only its own node is read; moving and simulated default to false).
  Expected<coupling::BodyCollision> body_collision(SceneNode& node, bool has_surface, bool rigid);
  /// SphereCollisionModel `model` in `node`: its centres (the node's state, or its SphereLoader)
  /// and radii (listRadius, or radius), into `out`.
  Expected<void> read_spheres(SceneNode& node, Component& model, coupling::BodyCollision& out);

  fs::path path_;
  std::string text_;
  bool have_text_{false};
  std::vector<std::size_t> line_starts_;
  bool thesis_format_{false};  ///< <hof><sofa><sg>: the thesis' appendix format
  bool legacy_{false};         ///< the file uses 2008 syntax (Object tags or 2008-only names)
  std::unique_ptr<SceneNode> root_;
  std::unordered_map<const Component*, MeshData> data_cache_;

  std::set<const Component*> in_progress_;
  std::set<const SceneNode*> simulated_nodes_;  ///< nodes that became a body
  /// Collision models of obstacle nodes with no triangles (make_obstacle skips them): an error
  /// once read_contacts() finds the scene's collision pipeline on (they would collide nothing).
  std::vector<const Component*> models_without_surface_;
  SofaScene scene_;
};

}  // namespace hof::scene::detail
