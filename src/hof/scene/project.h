#pragma once
/// @file
/// HoF project files (`.hof`, XML; format in docs/project-format.md): which mechanics scene to
/// simulate (a SOFA `.scn`, path relative to the project), the haptics setup (device,
/// calibration, renderer, surface, coupling, safety, options) and the graphics setup
/// (viewpoint, render mode). Every setting is written out, in a fixed order with shortest
/// round-trip numbers, so save → load → save gives the same bytes.

#include <array>
#include <cstdint>
#include <filesystem>
#include <optional>
#include <string>
#include <string_view>
#include <vector>

#include "hof/core/error.h"
#include "hof/coupling/session.h"
#include "hof/haptics/force_effects.h"
#include "hof/haptics/haptic_renderer.h"
#include "hof/haptics/safety.h"
#include "hof/haptics/surface_material.h"
#include "hof/procedures/needle.h"
#include "hof/procedures/shaped_tool.h"
#include "hof/scene/model_parameters.h"

namespace hof::scene {

/// How the deformable bodies are drawn (the file's renderMode: shaded, wireframe,
/// shaded+wireframe, points).
enum class RenderMode : std::uint8_t { kShaded, kWireframe, kShadedWireframe, kPoints };
/// What colours the deformable bodies (the file's colorBy): their material, their
/// displacement from rest, their surface Green strain, their von Mises stress.
enum class ColorBy : std::uint8_t { kMaterial, kDisplacement, kStrain, kStress };
/// The file's names of a render mode ("shaded", ...) and a colouring ("material", ...).
[[nodiscard]] std::string_view render_mode_name(RenderMode mode);
[[nodiscard]] std::string_view color_by_name(ColorBy colouring);

struct GraphicsSetup {
  Vec3 viewpoint_m{0.0, -0.45, 0.25};
  Vec3 look_at_m{0.0, 0.0, 0.0};
  RenderMode render_mode{RenderMode::kShaded};
  ColorBy color_by{ColorBy::kMaterial};
  /// X3D Material of the deformable bodies; the default is the thesis' liver (§ appearance).
  Vec3 diffuse_color{0.36, 0.11, 0.04};
  Vec3 specular_color{0.7, 0.7, 0.7};
  double shininess{0.2};
  double transparency{0.0};
  /// Lights (X3D's NavigationInfo headlight and one DirectionalLight): written <light>.
  bool headlight{true};
  double headlight_intensity{0.75};
  Vec3 light_direction{-0.3, -0.2, -1.0};  ///< the way the light travels (X3D), world frame
  double light_intensity{0.3};
  double ambient_intensity{0.18};
};

/// Settings of one body of the scene (by its name), written in <bodies>.
struct BodySetup {
  std::string name;
  std::optional<haptics::SurfaceMaterial> surface;  ///< its haptic surface (else the project's)
  /// The body's model, when the project chooses another than the scene's: for a surface
  /// body (an X3D DeformableShape, a SOFA triangle model) "springs" (MeshSpringForceField on
  /// the edges) or "membrane" (co-rotational TriangleFEMForceField); for a volume body
  /// "hexahedra": its surface filled with a coarse hexahedral grid (SOFA's SparseGridTopology
  /// + HexahedronFEMForceField, the same material) that the surface follows trilinearly.
  /// Applied before <set> and <region>, whose component names are then "springs",
  /// "membrane" or "FEM". "" = as the scene has it.
  std::string model;
  /// "hexahedra": nodes per axis of the grid (SOFA's n); 0 = cells of a tenth of the body's
  /// largest extent.
  std::array<int, 3> grid{0, 0, 0};
  /// contact="false": the body takes no part in contact between bodies; "true": it does even
  /// where its scene gives it no collision model. Unset: with <contact>, every body collides
  /// (a SOFA body through the collision models its scene gives, else its whole surface).
  std::optional<bool> contact;
  std::int64_t line{0};  ///< of its <body> element in the project file, for errors (0: not from a file)
};

/// A rigid, fixed obstacle the project adds to the scene (a table, a rib cage): a surface mesh
/// file (OBJ, STL, OFF, or a tetrahedral mesh's boundary), path relative to the project.
struct ObstacleSetup {
  std::string name;
  std::filesystem::path mesh;
  Vec3 translation{Vec3::Zero()};                   ///< m, added to the mesh's coordinates
  std::optional<haptics::SurfaceMaterial> surface;  ///< else the project's
  std::optional<bool> contact;                      ///< as BodySetup::contact
  std::int64_t line{0};                             ///< of its <obstacle> element, for errors (0: none)
};

/// Contact between bodies (<contact>): on for every body with a surface (its triangles, edges
/// and nodes), unless a body says contact="false" or a <pair> is switched off. Replaces the
/// contact settings of the project's SOFA scene (its collision pipeline) when given.
struct ContactSetup {
  /// The world's settings. Lengths in the scene's unit (m unless <mechanics unit>), the
  /// stiffness in N per that unit. `disabled_pairs` stays empty here: pairs go by name below.
  coupling::ContactSettings settings{.enabled = true,
                                     .response = coupling::ContactResponse::kPenalty,
                                     .alarm_distance_m = 0.005,
                                     .contact_distance_m = 0.001,
                                     .stiffness_n_per_m = 1000.0,
                                     .friction = 0.0,
                                     .self_collision = false,
                                     .disabled_pairs = {}};
  /// Pairs of bodies (by name, as <pair a="…" b="…" enabled="false"/>) that do not collide.
  std::vector<std::pair<std::string, std::string>> disabled_pairs;
  std::int64_t line{0};  ///< of the <contact> element in the project file, for errors (0: not from a file)
};

/// A tissue region (a tumour, a stiffer lobe): the elements of a body (tetrahedra; a
/// membrane's triangles) whose centroid lies in a sphere or a box, or that carry a Gmsh
/// physical group, take their own Young's modulus, Poisson ratio and/or mass density (SOFA's
/// per-element lists), applied after the scene and its <set> parameters. Written <region> in
/// <mechanics>; regions apply in order, a later one overriding an earlier one.
struct MaterialRegion {
  enum class Shape : std::uint8_t { kSphere, kBox, kGroup };
  std::string name{"region"};
  std::string body;         ///< the body (its SOFA node name)
  std::string force_field;  ///< the force field ("": every FEM force field of the body)
  Shape shape{Shape::kSphere};
  Vec3 center{Vec3::Zero()};                          ///< sphere centre, m (scene units)
  double radius{0.01};                                ///< sphere radius
  Vec3 box_min{Vec3::Zero()}, box_max{Vec3::Zero()};  ///< box corners
  std::int32_t physical_group{0};                     ///< Gmsh physical tag (shape kGroup)
  std::optional<double> young_modulus_pa;             ///< Pa
  std::optional<double> poisson_ratio;                ///< in (−1, 0.5)
  std::optional<double> mass_density_kg_per_m3;       ///< needs a DiagonalMass (per area on a membrane)
};

/// A hand beyond the first: a <tool device="SPEC"> whose device is not the project's.
struct HandSetup {
  procedures::ShapedToolConfig tool;  ///< `tool.device`: the device spec that carries it
  /// Its own force limit (<tool maxForce>), N; 0: the project's (<safety maxForce>).
  double max_force_n{0.0};
  std::int64_t line{0};  ///< where the project gives it (errors while the world is built)
  bool operator==(const HandSetup&) const = default;
};

struct HofProject {
  std::string name{"untitled"};
  std::filesystem::path mechanics_scene;  ///< as written in the file (relative to it); empty when inline
  /// The scene written inside <mechanics> (a SOFA node tree), kept as XML text; the thesis'
  /// appendix format (<hof><sofa><sg>) is read into it too.
  std::string mechanics_inline;
  /// Device spec (see haptics::open_device); "auto": the builder's default probe, fitted to
  /// the world (scene/world.h).
  std::string device{"auto"};
  /// Parameters of the scene's bodies set by the project (<set> in <mechanics>), applied
  /// after the scene is read — what a session's command seam changed, saved.
  std::vector<ParameterChange> parameters;
  std::vector<MaterialRegion> regions;  ///< material regions (<region> in <mechanics>), in order
  /// The length unit of the scene ("" = metres); stated in reports.
  std::string scene_unit;
  std::vector<BodySetup> bodies;         ///< per-body settings (<bodies><body>)
  std::vector<ObstacleSetup> obstacles;  ///< rigid obstacles (<bodies><obstacle>)
  std::optional<ContactSetup> contact;   ///< contact between bodies (<contact>); unset: the scene's
  std::array<double, 16> position_calibration{1, 0, 0, 0, 0, 1, 0, 0, 0, 0, 1, 0, 0, 0, 0, 1};  ///< row-major 4x4
  double haptic_rate_hz{1000.0};
  haptics::RendererKind renderer{haptics::RendererKind::kRuspini};
  double proxy_radius_m{0.0025};
  bool force_shading{true};
  collision::TouchableFace touchable_face{collision::TouchableFace::kFront};
  coupling::ContactCoupling coupling{coupling::ContactCoupling::kBarycentric};
  haptics::SurfaceMaterial surface;
  haptics::SafetyConfig safety;
  haptics::ForceEffects effects;   ///< H3D SpringEffect, ViscosityEffect, ForceField
  bool use_bound_tree{true};       ///< H3D HapticsOptions.useBoundTree
  int max_triangles_in_leaf{1};    ///< H3D GeometryBoundTreeOptions.maxTrianglesInLeaf
  double stylus_radius_m{0.0025};  ///< drawn stylus tip (graphics)
  double stylus_length_m{0.1};
  /// The needle stylus and its tissue parameters (<needle> in <haptics>); unset: a point or
  /// sphere stylus.
  std::optional<procedures::NeedleConfig> needle;
  /// A rigid tool with a shape on the stylus (<tool> in <haptics>); `mesh` resolved against the
  /// project's folder. Not with a needle.
  std::optional<procedures::ShapedToolConfig> tool;
  /// More hands (two devices at once, issue 37): each <tool device="SPEC"> whose SPEC is not
  /// `device` is a device of its own with that tool, in the order written. A <tool> without
  /// device= (or naming `device`) is the first hand's, `tool` above. A project whose device is
  /// "auto" and whose tools all name devices takes the first one's device as its own.
  std::vector<HandSetup> hands;
  GraphicsSetup graphics;
};

/// Reads a project. Errors name the file, line and attribute.
[[nodiscard]] Expected<HofProject> read_project(const std::filesystem::path& path);
/// A project from its XML text; `path` names it in errors and anchors relative files.
[[nodiscard]] Expected<HofProject> parse_project(const std::string& text, const std::filesystem::path& path);
/// Sets one attribute of <haptics> or <graphics> by the file's own names, e.g.
/// ("haptics/surface", "stiffness", "0.4"), ("haptics", "renderer", "GodObjectRenderer"),
/// ("graphics", "renderMode", "wireframe"), ("haptics/effects/SpringEffect[2]",
/// "springConstant", "200") (the n-th such element): parse_project_edit then apply_edit
/// (scene/project_edit.h), the value checked as when the file is read. Errors name the
/// element and attribute and list the known ones; `project` is unchanged on error.
[[nodiscard]] Expected<void> set_project_attribute(HofProject& project, const std::filesystem::path& path,
                                                   std::string_view element, std::string_view attribute,
                                                   std::string_view value);
/// Checks graphics settings by the checks the reader applies to a file's <graphics>,
/// <material> and <light> (colours and intensities in [0, 1], a light direction, finite
/// numbers): a typed edit of `HofProject::graphics` goes through it. The error names the
/// attribute as the file's reader does.
[[nodiscard]] Expected<void> check_graphics(const GraphicsSetup& graphics);
/// The canonical XML text of a project.
[[nodiscard]] std::string to_xml(const HofProject& project);
/// Writes to_xml(project) to `path` (via a temporary file and a rename: never a half file).
[[nodiscard]] Expected<void> write_project(const HofProject& project, const std::filesystem::path& path);

/// The SOFA scene file of a project: the project file itself when the scene is inline.
[[nodiscard]] std::filesystem::path scene_file(const HofProject& project, const std::filesystem::path& project_file);

/// `project` (read from `from`) as it is to be written at `to`: its scene's path (or, for an
/// inline scene, the files that scene names) re-anchored, since they are relative to the
/// project file.
[[nodiscard]] HofProject moved_project(const HofProject& project, const std::filesystem::path& from,
                                       const std::filesystem::path& to);

/// The haptic-loop configuration a project describes.
[[nodiscard]] coupling::SessionConfig session_config(const HofProject& project);

}  // namespace hof::scene
