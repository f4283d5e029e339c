#pragma once
/// @file
/// Triangle meshes of the X3D geometry nodes, in the node's local frame, metres, each triangle
/// counter-clockwise seen from the side its normal points to (the front face of X3D's `ccw`
/// TRUE). Field meanings and defaults follow ISO/IEC 19775-1 (X3D Architecture), cited per
/// function. Malformed counts are the caller's to report: these builders take what fits and
/// say how much they left out (`ignored`), so a reader can warn with the file and line.

#include <cstdint>
#include <span>
#include <vector>

#include "hof/core/types.h"
#include "hof/mesh/mesh.h"

namespace hof::scene::detail {

using Vec2 = Eigen::Vector2d;
using Vec4 = Eigen::Vector4d;

constexpr int kRoundSlices = 32;  ///< segments of a circle (Cylinder, Cone, Disk2D)

/// Sphere (19775-1 clause 13, Geometry3D): centred at the origin.
[[nodiscard]] mesh::TriMesh make_sphere(double radius);
/// Box (clause 13): centred at the origin, `size` along x, y, z.
[[nodiscard]] mesh::TriMesh make_box(const Vec3& size);
/// Cylinder (clause 13, top_radius = bottom_radius) or Cone (top_radius = 0): axis y,
/// centred at the origin, `height` along y.
[[nodiscard]] mesh::TriMesh make_round(double bottom_radius, double top_radius, double height, bool side, bool bottom,
                                       bool top);
/// Rectangle2D (clause 14, Geometry2D): `size` x × y, centred at the origin in the z = 0 plane, facing +z.
[[nodiscard]] mesh::TriMesh make_rectangle(double size_x, double size_y);
/// Disk2D (clause 14): the annulus innerRadius ≤ r ≤ outerRadius (a disc when innerRadius is 0)
/// in the z = 0 plane, facing +z. Empty when inner ≥ outer (the spec draws a circle then).
[[nodiscard]] mesh::TriMesh make_disk(double inner_radius, double outer_radius);

/// ElevationGrid (clause 13): vertex (i, j) at (xSpacing·i, height[i + j·xDimension], zSpacing·j),
/// i < xDimension, j < zDimension; quads between neighbours, facing +y (ccw TRUE).
/// @pre height.size() ≥ x_dimension·z_dimension (the caller checks).
[[nodiscard]] mesh::TriMesh make_elevation_grid(std::int64_t x_dimension, std::int64_t z_dimension, double x_spacing,
                                                double z_spacing, std::span<const double> height);

/// Extrusion (clause 13): the 2D `cross_section` (x, z pairs) scaled by `scale[i]`, rotated by
/// `orientation[i]` (axis-angle) and placed in the spine-aligned cross-section plane (SCP) of
/// spine point i (the spec's SCP construction); sides between successive spine points, and caps (fans, the
/// cross-section taken as convex) at the two ends when asked. A scale or orientation list
/// shorter than the spine repeats its last value (one value applies to every point).
/// @pre cross_section.size() ≥ 2, spine.size() ≥ 2, scale and orientation not empty.
[[nodiscard]] mesh::TriMesh make_extrusion(std::span<const Vec2> cross_section, std::span<const Vec3> spine,
                                           std::span<const Vec2> scale, std::span<const Vec4> orientation,
                                           bool begin_cap, bool end_cap);

/// How a vertex list is read into triangles (19775-1 clause 11, Rendering: the triangle and quad sets).
enum class VertexGrouping : std::uint8_t {
  kTriangles,  ///< TriangleSet / IndexedTriangleSet: three at a time
  kQuads,      ///< QuadSet / IndexedQuadSet: four at a time, each quad split into two triangles
  kFans,       ///< TriangleFanSet / IndexedTriangleFanSet: (v0, vk, vk+1) in each fan
  kStrips,     ///< TriangleStripSet / IndexedTriangleStripSet: alternate windings kept ccw
  kPolygons,   ///< IndexedFaceSet: each polygon fan-triangulated (convex assumed)
};

/// Triangles of `runs` (each a list of vertex indices: one fan, strip or polygon; the whole
/// list for triangles and quads) grouped as `grouping`. Returns how many vertices were left
/// out (a run too short, a remainder that is not a whole triangle or quad).
std::size_t append_grouped(std::vector<mesh::Tri>& out, VertexGrouping grouping,
                           std::span<const std::vector<mesh::NodeIndex>> runs);

/// Flips every triangle so its normal points away from the origin (convex shapes centred there).
void orient_outward(mesh::TriMesh& m);

}  // namespace hof::scene::detail
