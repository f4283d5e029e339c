#pragma once
/// @file
/// X3D scenes written for the H3D API (H3DViewer): the haptic subset of them. Shapes become
/// world-frame triangle meshes (after Transform / MatrixTransform / FitToBoxTransform), with
/// their H3D surface (SmoothSurface, FrictionalSurface, MagneticSurface and the surfaces
/// derived from them), DeformableShape's deformer, DeviceInfo devices with their calibration
/// and haptics renderer, GlobalSettings options, force effects and viewpoints. Field names and
/// defaults follow shared/reference/h3d-nodes.md, and ISO/IEC 19775-1 for the X3D nodes.
/// Grouping nodes are looked into (Group, StaticGroup, Billboard, Anchor, Collision, Switch's
/// chosen child, LOD's first level, Inline'd files beside the scene, PROTO instances with their
/// fields substituted). Nodes HoF does not model (PythonScript, ROUTE, textures, Text, ...)
/// are listed in `unsupported` with one warning, never an error. Strings end here: the rest of
/// HoF sees enums and SI values.

#include <array>
#include <cstdint>
#include <filesystem>
#include <optional>
#include <string>
#include <vector>

#include "hof/core/error.h"
#include "hof/core/types.h"
#include "hof/haptics/force_effects.h"
#include "hof/haptics/haptic_renderer.h"
#include "hof/haptics/surface_material.h"
#include "hof/mesh/mesh.h"

namespace hof::scene {

/// H3D HapticsOptions.touchableFace.
enum class X3dTouchableFace : std::uint8_t { kAsGraphics, kFront, kBack, kFrontAndBack };
/// H3D HapticsOptions.dynamicMode.
enum class X3dDynamicMode : std::uint8_t { kTransformChanged, kAlways, kNever };
/// H3D GeometryBoundTreeOptions.boundType.
enum class X3dBoundType : std::uint8_t { kAabb, kObb, kSphere };

struct X3dHapticsOptions {
  X3dTouchableFace touchable_face{X3dTouchableFace::kAsGraphics};
  double max_distance_m{0.01};
  double look_ahead_factor{3.0};
  bool use_bound_tree{true};
  bool interpolate_force_effects{true};
  X3dDynamicMode dynamic_mode{X3dDynamicMode::kTransformChanged};
};

struct X3dBoundTreeOptions {
  X3dBoundType bound_type{X3dBoundType::kAabb};
  std::int32_t max_triangles_in_leaf{1};
};

struct X3dDebugOptions {
  bool draw_bound{false};
  std::int32_t draw_bound_tree{-1};
  bool draw_haptic_triangles{false};
  bool print_shader_warnings{false};
};

/// GlobalSettings: the first option node of each type (unset when absent).
struct X3dGlobalSettings {
  std::optional<X3dHapticsOptions> haptics;
  std::optional<X3dBoundTreeOptions> bound_tree;
  std::optional<X3dDebugOptions> debug;
};

/// One Shape or DeformableShape, in the world frame.
struct X3dShape {
  std::string def;                    ///< DEF name of the Shape ("" if none)
  std::int64_t line{0};               ///< line of the Shape element
  std::string geometry_type;          ///< "Sphere", "IndexedTriangleSet", ... ("" if none)
  mesh::TriMesh mesh_W;               ///< geometry, world frame, m, counter-clockwise from outside
  std::string haptic_geometry_type;   ///< Shape.hapticGeometry node type ("" if none)
  mesh::TriMesh haptic_mesh_W;        ///< hapticGeometry, world frame (empty if none)
  bool solid{true};                   ///< X3D `solid` of the geometry
  bool touchable{false};              ///< has an Appearance.surface (and haptics on: ToggleGroup hapticsOn)
  bool haptics_switched_off{false};   ///< has a surface, under a ToggleGroup with hapticsOn false
  std::string surface_type;           ///< "SmoothSurface", ... ("" if none)
  haptics::SurfaceMaterial surface;   ///< meaningful when touchable
  bool deformable{false};             ///< a DeformableShape
  int layer{0};                       ///< haptic layer: index of its HapticLayeredGroup child (0 outside one)
  std::string deformer_type;          ///< e.g. "CoordinateDeformer" ("" = no deformation)
  Vec3 diffuse_color{0.8, 0.8, 0.8};  ///< Material.diffuseColor (X3D default 0.8 0.8 0.8)
  double transparency{0.0};           ///< Material.transparency (X3D default 0)
  bool has_material{false};           ///< an Appearance.material was given
  std::optional<X3dHapticsOptions> haptics_options;       ///< from the geometry's `options`
  std::optional<X3dBoundTreeOptions> bound_tree_options;  ///< from the geometry's `options`
};

struct X3dRenderer {
  std::string type;                           ///< "GodObjectRenderer", "RuspiniRenderer", "OpenHapticsRenderer", ...
  std::optional<haptics::RendererKind> kind;  ///< set for GodObject and Ruspini
  double proxy_radius_m{0.0025};              ///< RuspiniRenderer.proxyRadius
};

struct X3dDevice {
  std::string type;  ///< "AnyDevice", "FalconDevice", "PhantomDevice", ...
  std::string def;
  std::string device_name;  ///< deviceName ("" if not given)
  /// positionCalibration, row-major as written in the file (identity by default).
  std::array<double, 16> position_calibration{1, 0, 0, 0, 0, 1, 0, 0, 0, 0, 1, 0, 0, 0, 0, 1};
  /// orientationCalibration: axis x y z, angle rad.
  std::array<double, 4> orientation_calibration{1, 0, 0, 0};
  double force_limit_n{-1.0};  ///< −1: no limit
  std::optional<X3dRenderer> renderer;
};

struct X3dViewpoint {
  Vec3 position{0.0, 0.0, 10.0};                  ///< local frame of the Viewpoint, m
  std::array<double, 4> orientation{0, 0, 1, 0};  ///< axis x y z, angle rad
  double field_of_view_rad{0.785398};
};

struct X3dScene {
  std::filesystem::path file;
  std::string root_element;   ///< "X3D" or "Scene" for a scene (a settings file: "DeviceInfo", ...)
  std::int64_t root_line{1};  ///< line of the root element
  bool root_known{true};      ///< the root is a node HoF reads (false: <svg>, <html>, ...)
  std::vector<X3dShape> shapes;
  std::vector<X3dDevice> devices;  ///< DeviceInfo.device, in order (= device index)
  std::optional<X3dGlobalSettings> global_settings;
  haptics::ForceEffects force_effects;  ///< positions and forces in the world frame
  std::vector<X3dViewpoint> viewpoints;
  std::vector<std::string> unsupported;  ///< "TYPE 'DEF' (line N)" of every node not modelled
                                         ///< ("(FILE line N)" when in an Inline'd or PROTO file)
  /// Of those, the ones in a Shape's geometry slot (Text, NurbsPatchSurface, ...) and the
  /// haptic ones (an Appearance's surface, a force effect, a deformer): what a scene with
  /// nothing to touch names as the cause.
  std::vector<std::string> unsupported_geometry, unsupported_haptic;
  int effects_switched_off{0};        ///< force effects under a ToggleGroup with hapticsOn false
  std::vector<std::string> warnings;  ///< "FILE:LINE: ..." notes
};

/// Reads an X3D file (with or without the <X3D><Scene> wrapper). Errors carry the file and
/// line: malformed XML, the classic VRML encoding, an index out of range in an indexed set, a
/// non-numeric field value, USE of a name not DEF'd before, an Inline that includes itself,
/// PROTOs or Inlines nested too deep.
[[nodiscard]] Expected<X3dScene> read_x3d_scene(const std::filesystem::path& path);

}  // namespace hof::scene
