#pragma once
/// @file
/// OpenGL 3.3 core drawing of what the window shows: triangle meshes (shaded with per-vertex
/// normals, wireframe, points; optional per-vertex colours), lines, spheres, cylinders and
/// arrows. The caller owns the window and makes its context current; every call here runs on
/// that (the window's) thread. Lighting: a headlight and a fill light (Blinn–Phong), as
/// H3D's default headlight.

#include <epoxy/gl.h>

#include <Eigen/Core>
#include <cstdint>
#include <span>
#include <string>
#include <vector>

#include "hof/core/error.h"
#include "hof/core/types.h"
#include "hof/mesh/mesh.h"
#include "hof/render/camera.h"

namespace hof::render {

using Rgba = Eigen::Vector4f;

enum class RenderMode : std::uint8_t { kShaded, kWireframe, kPoints, kShadedWireframe };

/// X3D Material fields (H3D names), colours in [0, 1].
struct Material {
  Rgba diffuse{0.8f, 0.8f, 0.8f, 1.0f};  ///< diffuseColor, alpha = 1 − transparency
  Eigen::Vector3f specular{0.2f, 0.2f, 0.2f};
  float shininess{0.2f};  ///< X3D shininess in [0, 1] (× 128)
};

/// A triangle mesh on the GPU. Positions and normals change every frame for a deforming body;
/// the triangles once.
class MeshBuffer {
 public:
  MeshBuffer() = default;
  MeshBuffer(const MeshBuffer&) = delete;
  MeshBuffer& operator=(const MeshBuffer&) = delete;
  MeshBuffer(MeshBuffer&& other) noexcept;
  MeshBuffer& operator=(MeshBuffer&& other) noexcept;
  ~MeshBuffer();

  void set_triangles(std::span<const mesh::Tri> triangles);
  void set_positions(std::span<const Vec3> positions);
  void set_normals(std::span<const Vec3> normals);
  /// Per-vertex colours (empty: the material's colour).
  void set_colours(std::span<const Rgba> colours);
  [[nodiscard]] bool has_colours() const { return has_colours_; }
  [[nodiscard]] std::size_t vertex_count() const { return vertex_count_; }
  [[nodiscard]] std::size_t index_count() const { return index_count_; }
  [[nodiscard]] GLuint vao() const { return vao_; }

 private:
  void create();
  void release();
  GLuint vao_{0}, positions_{0}, normals_{0}, colours_{0}, indices_{0};
  std::size_t vertex_count_{0}, index_count_{0};
  bool has_colours_{false};
  std::vector<float> scratch_;
};

/// The lights (X3D's headlight and one DirectionalLight).
struct Lighting {
  float headlight_intensity{0.75f};                ///< 0: no headlight
  Eigen::Vector3f direction{-0.3f, -0.2f, -1.0f};  ///< the way the light travels, world frame
  float intensity{0.3f};
  float ambient{0.18f};
};

class GlRenderer {
 public:
  GlRenderer() = default;
  GlRenderer(const GlRenderer&) = delete;
  GlRenderer& operator=(const GlRenderer&) = delete;
  ~GlRenderer();

  /// Compiles the shaders and builds the unit shapes (context current). Errors carry the
  /// compiler's log.
  Expected<void> init();

  /// Sets the viewport (x, y from the bottom left, pixels), clears it and sets the camera for
  /// the draws that follow.
  void begin(const OrbitCamera& camera, int x_px, int y_px, int width_px, int height_px, const Rgba& background);

  /// The lights of the draws that follow.
  void set_lighting(const Lighting& lighting) { lighting_ = lighting; }

  /// Draws `triangle_count` triangles from `first_triangle` (all by default).
  void draw(const MeshBuffer& mesh, const Material& material, RenderMode mode,
            const Eigen::Matrix4f& model = Eigen::Matrix4f::Identity(), std::size_t first_triangle = 0,
            std::size_t triangle_count = static_cast<std::size_t>(-1));
  /// Line segments: pairs of points.
  void draw_lines(std::span<const Vec3> segment_points, const Rgba& colour);
  void draw_points(std::span<const Vec3> points, const Rgba& colour, float size_px);
  void draw_sphere(const Vec3& centre, double radius, const Rgba& colour);
  void draw_cylinder(const Vec3& from, const Vec3& to, double radius, const Rgba& colour);
  /// A shaft and a cone head from `from` to `to`.
  void draw_arrow(const Vec3& from, const Vec3& to, double radius, const Rgba& colour);

  /// The viewport's pixels, RGB, rows from the top (read before the buffer swap).
  [[nodiscard]] std::vector<std::uint8_t> read_pixels(int width_px, int height_px) const;

 private:
  void use_mesh_program(const Eigen::Matrix4f& model, const Material& material, bool lit, bool vertex_colours);
  // Lines or points straight from world positions (unlit).
  void draw_loose(std::span<const Vec3> points, const Rgba& colour, GLenum primitive, float point_size_px);
  GLuint mesh_program_{0};
  GLint u_mvp_{-1}, u_model_{-1}, u_normal_matrix_{-1}, u_colour_{-1}, u_specular_{-1}, u_shininess_{-1}, u_lit_{-1},
      u_vertex_colours_{-1}, u_eye_{-1}, u_point_size_{-1}, u_head_intensity_{-1}, u_light_towards_{-1},
      u_light_intensity_{-1}, u_ambient_{-1};
  Lighting lighting_;
  Eigen::Matrix4f view_projection_{Eigen::Matrix4f::Identity()};
  Eigen::Vector3f eye_{Eigen::Vector3f::Zero()};
  MeshBuffer sphere_, cylinder_, cone_;
  GLuint lines_vao_{0}, lines_vbo_{0};
  std::vector<float> line_scratch_;
};

}  // namespace hof::render
