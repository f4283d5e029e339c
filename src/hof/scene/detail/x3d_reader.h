#pragma once
/// @file
/// The X3D reader's walk (x3d_scene.cpp: the scene graph, shapes and geometry) and its haptic
/// nodes (x3d_haptic_nodes.cpp: surfaces, force effects, options, settings, devices), one
/// class over the files of detail/x3d_source.h. Used by read_x3d_scene only.

#include <cstdint>
#include <filesystem>
#include <set>
#include <string>
#include <string_view>
#include <vector>

#include <pugixml.hpp>

#include "hof/scene/detail/x3d_source.h"
#include "hof/scene/x3d_scene.h"

namespace hof::scene::detail {

using Mat4 = Eigen::Matrix4d;

[[nodiscard]] inline bool ends_with(std::string_view s, std::string_view suffix) {
  return s.size() >= suffix.size() && s.substr(s.size() - suffix.size()) == suffix;
}
/// A rotation (x y z angle, rad) as a 4×4 matrix.
[[nodiscard]] Mat4 axis_angle(const std::vector<double>& r);
[[nodiscard]] Mat4 translation(const Vec3& t);
/// `m` moved by X (its triangles turned over when X mirrors).
void transform_mesh(mesh::TriMesh& m, const Mat4& X);

class X3dReader {
 public:
  explicit X3dReader(std::filesystem::path file) { scene_.file = std::move(file); }

  X3dScene run(std::string text);

 private:
  enum class Slot : std::uint8_t { kOther, kGeometry, kHaptic };
  // A node not modelled, named with its line — and its file when that is not the scene's (an
  // Inline'd file, the file of a PROTO's declaration), so the line can be found.
  void unsupported(pugi::xml_node original, std::string_view extra = {}, Slot slot = Slot::kOther);

  // ---- scene graph
  // Grouping nodes whose children are all drawn and felt (19775-1: Group, StaticGroup,
  // Billboard, Collision, Anchor; H3D's own groups). Billboard
  // turns its children toward the viewer: HoF, with no viewer to face, leaves them unturned.
  static bool is_group(std::string_view t);
  static bool is_geometry(std::string_view t);
  // A child in the scene graph (not metadata, a Collision's proxy, or a PROTO's IS).
  static bool is_child(pugi::xml_node c);

  void visit_children(pugi::xml_node n, const Mat4& X);

  // The i-th scene-graph child of `n` (null past the end).
  static pugi::xml_node nth_child(pugi::xml_node n, std::int64_t i);

  void visit(pugi::xml_node original, const Mat4& X);

  // Inline (19775-1, Networking): the first of its urls found beside the file that holds it, read as
  // a scene of its own (its DEF names are its own) under the current transform. A url on the
  // network, or none found, is a warning; an Inline that includes itself, directly or through
  // others, or nests past kMaxInlineDepth, is an error (the scene would be endless).
  void inline_file(pugi::xml_node n, const Mat4& X);
  // A file in X3D's classic (VRML) encoding: by its extension or its header line.
  static bool is_classic_vrml(const std::filesystem::path& path);

  // X3D Transform: T · C · R · SR · S · SR⁻¹ · C⁻¹.
  Mat4 transform_matrix(pugi::xml_node n) const;

  // FitToBoxTransform: the children are read in its local frame, their bound is scaled and
  // moved into the box, then everything is taken to the world frame.
  void fit_to_box(pugi::xml_node n, const Mat4& X);

  // ---- shapes
  void shape(pugi::xml_node original, pugi::xml_node n, const Mat4& X);

  // A geometry scaled to nothing (radius 0, a Transform's scale 0) has no surface to touch.
  void warn_if_zero_size(pugi::xml_node original, const X3dShape& s);

  static bool is_surface(std::string_view t);

  void appearance(pugi::xml_node n, X3dShape& s);

  haptics::SurfaceMaterial surface(pugi::xml_node n);

  // Geometry in its local frame; also reads `solid` and the geometry's own option nodes.
  mesh::TriMesh geometry(pugi::xml_node n, bool& solid, X3dShape& s);

  // ElevationGrid (19775-1, Geometry3D): xDimension × zDimension heights (default 0 × 0: empty),
  // spacings 1, ccw TRUE.
  mesh::TriMesh elevation_grid(pugi::xml_node n);

  // Extrusion (19775-1, Geometry3D): defaults crossSection the square 1 1, 1 −1, −1 −1, −1 1,
  // 1 1; spine 0 0 0, 0 1 0; scale 1 1; orientation 0 0 1 0; both caps; ccw TRUE.
  mesh::TriMesh extrusion(pugi::xml_node n);

  static void flip(mesh::TriMesh& m);

  // The points of a Coordinate. One with none, which a ROUTE from a CoordinateInterpolator
  // fills (an animation), is drawn at the interpolator's first key; HoF does not animate.
  std::vector<Vec3> points(pugi::xml_node coord);

  // The triangle and quad sets and IndexedFaceSet (19775-1, Rendering and Geometry3D): the
  // Coordinate's points grouped as the node says; ccw FALSE turns every triangle over.
  void composed_set(pugi::xml_node n, pugi::xml_node coord, mesh::TriMesh& m);

  // ---- force effects beyond springs, viscosity and constant forces
  // MagneticGeometryEffect (H3D): a spring of springConstant toward the closest point of its
  // geometry, caught within startDistance and let go past escapeDistance. H3D's constructor
  // sets springConstant 100 (its header says 300): the constructor's value is the default.
  void magnetic_geometry_effect(pugi::xml_node n, const Mat4& X);

  // PositionFunctionEffect / TimeFunctionEffect (H3D): the force's x, y, z are functions of
  // the device position (world frame, m) or of time (s); GeneralFunction gives them as text.
  void function_effect(pugi::xml_node n);

  // RotationalSpringEffect (H3D): a torque toward desiredAxis. HoF's devices render force
  // only (their torque output is zero), so it is read, and said to be not felt.
  void rotational_spring_effect(pugi::xml_node n);

  // ---- options
  X3dHapticsOptions haptics_options(pugi::xml_node n) const;

  X3dBoundTreeOptions bound_tree_options(pugi::xml_node n) const;

  void global_settings(pugi::xml_node n);

  // ---- devices
  void device_info(pugi::xml_node n);

  std::vector<std::filesystem::path> inline_stack_;  // the files being read, outermost first
  static constexpr std::int64_t kMaxVisitedNodes = 200000;
  std::int64_t visited_{0};
  X3dScene scene_;
  X3dSource source_{scene_.warnings};  // after scene_: it writes scene_.warnings
  pugi::xml_node root_;                // the file's root element
  int layer_{0};                       // haptic layer of the shapes being visited
  int haptics_off_{0};                 // ToggleGroups with hapticsOn false around the nodes being visited
  bool dynamic_transform_noted_{false};
  std::set<std::string, std::less<>> approximated_;  // surface types already said to be approximated
};

}  // namespace hof::scene::detail
