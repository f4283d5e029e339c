#include "hof/render/gl_renderer.h"

#include <algorithm>
#include <cmath>
#include <numbers>
#include <string>
#include <utility>

namespace hof::render {

namespace {

constexpr const char* kVertexShader = R"(#version 330 core
layout(location = 0) in vec3 position;
layout(location = 1) in vec3 normal;
layout(location = 2) in vec4 colour;
uniform mat4 mvp;
uniform mat4 model;
uniform mat3 normal_matrix;
uniform float point_size;
out vec3 world_position;
out vec3 world_normal;
out vec4 vertex_colour;
void main() {
  gl_Position = mvp * vec4(position, 1.0);
  gl_PointSize = point_size;
  world_position = (model * vec4(position, 1.0)).xyz;
  world_normal = normal_matrix * normal;
  vertex_colour = colour;
}
)";

// Blinn–Phong with a headlight (at the eye) and a directional light (by default a dimmer fill
// light from above), as set by set_lighting(); both faces lit
// (an open sheet is seen from both sides).
constexpr const char* kFragmentShader = R"(#version 330 core
in vec3 world_position;
in vec3 world_normal;
in vec4 vertex_colour;
uniform vec4 colour;
uniform vec3 specular;
uniform float shininess;
uniform int lit;
uniform int vertex_colours;
uniform vec3 eye;
uniform float head_intensity;
uniform vec3 light_towards;
uniform float light_intensity;
uniform float ambient;
out vec4 fragment;
void main() {
  // Vertex colours (displacement, stress) keep the material's transparency.
  vec4 base = vertex_colours != 0 ? vec4(vertex_colour.rgb, vertex_colour.a * colour.a) : colour;
  if (lit == 0) { fragment = base; return; }
  vec3 n = normalize(world_normal);
  vec3 v = normalize(eye - world_position);
  if (dot(n, v) < 0.0) n = -n;
  vec3 head = v;
  vec3 fill = normalize(light_towards);
  float d = head_intensity * max(dot(n, head), 0.0) + light_intensity * max(dot(n, fill), 0.0);
  float power = max(shininess * 128.0, 1.0);
  float s = head_intensity / 0.75 * pow(max(dot(n, head), 0.0), power) +
            light_intensity / 0.75 * pow(max(dot(n, normalize(fill + v)), 0.0), power);
  vec3 c = base.rgb * (ambient + d) + specular * s;
  fragment = vec4(min(c, vec3(1.0)), base.a);
}
)";

Expected<GLuint> compile(GLenum kind, const char* source) {
  const GLuint shader = glCreateShader(kind);
  glShaderSource(shader, 1, &source, nullptr);
  glCompileShader(shader);
  GLint ok = 0;
  glGetShaderiv(shader, GL_COMPILE_STATUS, &ok);
  if (!ok) {
    std::string log(4096, '\0');
    GLsizei length = 0;
    glGetShaderInfoLog(shader, static_cast<GLsizei>(log.size()), &length, log.data());
    log.resize(static_cast<std::size_t>(length));
    glDeleteShader(shader);
    return make_error(ErrorCode::kUnsupported, "OpenGL shader does not compile: " + log);
  }
  return shader;
}

Eigen::Matrix4f to_float(const Eigen::Matrix4d& m) { return m.cast<float>(); }

/// Unit shapes: a UV sphere of radius 1, a cylinder and a cone of radius 1 along +z from 0 to 1.
void build_sphere(MeshBuffer& buffer) {
  constexpr int kRings = 12, kSegments = 20;
  std::vector<Vec3> p;
  std::vector<mesh::Tri> t;
  for (int r = 0; r <= kRings; ++r) {
    const double phi = std::numbers::pi * r / kRings;
    for (int s = 0; s <= kSegments; ++s) {
      const double theta = 2.0 * std::numbers::pi * s / kSegments;
      p.emplace_back(std::sin(phi) * std::cos(theta), std::sin(phi) * std::sin(theta), std::cos(phi));
    }
  }
  for (int r = 0; r < kRings; ++r) {
    for (int s = 0; s < kSegments; ++s) {
      const int a = r * (kSegments + 1) + s, b = a + kSegments + 1;
      t.push_back({a, b, a + 1});
      t.push_back({a + 1, b, b + 1});
    }
  }
  buffer.set_triangles(t);
  buffer.set_positions(p);
  buffer.set_normals(p);
}

void build_cylinder(MeshBuffer& buffer, bool cone) {
  constexpr int kSegments = 16;
  std::vector<Vec3> p, n;
  std::vector<mesh::Tri> t;
  for (int s = 0; s <= kSegments; ++s) {
    const double theta = 2.0 * std::numbers::pi * s / kSegments;
    const Vec3 radial(std::cos(theta), std::sin(theta), 0.0);
    const Vec3 normal = cone ? Vec3(radial + Vec3::UnitZ()).normalized() : radial;
    p.push_back(radial);
    n.push_back(normal);
    p.push_back(cone ? Vec3(0.0, 0.0, 1.0) : Vec3(radial + Vec3::UnitZ()));
    n.push_back(normal);
  }
  for (int s = 0; s < kSegments; ++s) {
    const int a = 2 * s;
    t.push_back({a, a + 2, a + 1});
    t.push_back({a + 1, a + 2, a + 3});
  }
  // The base disc.
  const int centre = static_cast<int>(p.size());
  p.push_back(Vec3::Zero());
  n.push_back(-Vec3::UnitZ());
  for (int s = 0; s <= kSegments; ++s) {
    p.push_back(p[static_cast<std::size_t>(2 * s)]);
    n.push_back(-Vec3::UnitZ());
  }
  for (int s = 0; s < kSegments; ++s) t.push_back({centre, centre + 2 + s, centre + 1 + s});
  buffer.set_triangles(t);
  buffer.set_positions(p);
  buffer.set_normals(n);
}

/// The model matrix that maps the unit +z shape onto the segment from → to with radius r.
Eigen::Matrix4f segment_transform(const Vec3& from, const Vec3& to, double radius) {
  const Vec3 axis = to - from;
  const double length = axis.norm();
  const Vec3 z = length > 0.0 ? Vec3(axis / length) : Vec3(Vec3::UnitZ());
  const Vec3 helper = std::abs(z.x()) < 0.9 ? Vec3::UnitX() : Vec3::UnitY();
  const Vec3 x = z.cross(helper).normalized();
  const Vec3 y = z.cross(x);
  Eigen::Matrix4d m = Eigen::Matrix4d::Identity();
  m.block<3, 1>(0, 0) = x * radius;
  m.block<3, 1>(0, 1) = y * radius;
  m.block<3, 1>(0, 2) = z * length;
  m.block<3, 1>(0, 3) = from;
  return m.cast<float>();
}

}  // namespace

// ---- MeshBuffer

MeshBuffer::MeshBuffer(MeshBuffer&& other) noexcept { *this = std::move(other); }

MeshBuffer& MeshBuffer::operator=(MeshBuffer&& other) noexcept {
  if (this != &other) {
    release();
    vao_ = std::exchange(other.vao_, 0);
    positions_ = std::exchange(other.positions_, 0);
    normals_ = std::exchange(other.normals_, 0);
    colours_ = std::exchange(other.colours_, 0);
    indices_ = std::exchange(other.indices_, 0);
    vertex_count_ = std::exchange(other.vertex_count_, 0);
    index_count_ = std::exchange(other.index_count_, 0);
    has_colours_ = std::exchange(other.has_colours_, false);
  }
  return *this;
}

MeshBuffer::~MeshBuffer() { release(); }

void MeshBuffer::create() {
  if (vao_) return;
  glGenVertexArrays(1, &vao_);
  glGenBuffers(1, &positions_);
  glGenBuffers(1, &normals_);
  glGenBuffers(1, &colours_);
  glGenBuffers(1, &indices_);
  glBindVertexArray(vao_);
  glBindBuffer(GL_ARRAY_BUFFER, positions_);
  glVertexAttribPointer(0, 3, GL_FLOAT, GL_FALSE, 0, nullptr);
  glEnableVertexAttribArray(0);
  glBindBuffer(GL_ARRAY_BUFFER, normals_);
  glVertexAttribPointer(1, 3, GL_FLOAT, GL_FALSE, 0, nullptr);
  glEnableVertexAttribArray(1);
  glBindBuffer(GL_ARRAY_BUFFER, colours_);
  glVertexAttribPointer(2, 4, GL_FLOAT, GL_FALSE, 0, nullptr);
  glBindBuffer(GL_ELEMENT_ARRAY_BUFFER, indices_);
  glBindVertexArray(0);
}

void MeshBuffer::release() {
  if (!vao_) return;
  const GLuint buffers[] = {positions_, normals_, colours_, indices_};
  glDeleteBuffers(4, buffers);
  glDeleteVertexArrays(1, &vao_);
  vao_ = positions_ = normals_ = colours_ = indices_ = 0;
}

void MeshBuffer::set_triangles(std::span<const mesh::Tri> triangles) {
  create();
  std::vector<std::uint32_t> indices;
  indices.reserve(triangles.size() * 3);
  for (const mesh::Tri& t : triangles) {
    for (int k = 0; k < 3; ++k) indices.push_back(static_cast<std::uint32_t>(t[static_cast<std::size_t>(k)]));
  }
  glBindVertexArray(vao_);
  glBindBuffer(GL_ELEMENT_ARRAY_BUFFER, indices_);
  glBufferData(GL_ELEMENT_ARRAY_BUFFER, static_cast<GLsizeiptr>(indices.size() * sizeof(std::uint32_t)), indices.data(),
               GL_STATIC_DRAW);
  glBindVertexArray(0);
  index_count_ = indices.size();
}

namespace {
void upload_vec3(GLuint buffer, std::span<const Vec3> values, std::vector<float>& scratch,
                 GLenum usage = GL_DYNAMIC_DRAW) {
  scratch.resize(values.size() * 3);
  for (std::size_t i = 0; i < values.size(); ++i) {
    scratch[3 * i] = static_cast<float>(values[i].x());
    scratch[3 * i + 1] = static_cast<float>(values[i].y());
    scratch[3 * i + 2] = static_cast<float>(values[i].z());
  }
  glBindBuffer(GL_ARRAY_BUFFER, buffer);
  glBufferData(GL_ARRAY_BUFFER, static_cast<GLsizeiptr>(scratch.size() * sizeof(float)), scratch.data(), usage);
}
}  // namespace

void MeshBuffer::set_positions(std::span<const Vec3> positions) {
  create();
  upload_vec3(positions_, positions, scratch_);
  vertex_count_ = positions.size();
}

void MeshBuffer::set_normals(std::span<const Vec3> normals) {
  create();
  upload_vec3(normals_, normals, scratch_);
}

void MeshBuffer::set_colours(std::span<const Rgba> colours) {
  create();
  glBindVertexArray(vao_);
  if (colours.empty()) {
    glDisableVertexAttribArray(2);
    has_colours_ = false;
  } else {
    glBindBuffer(GL_ARRAY_BUFFER, colours_);
    glBufferData(GL_ARRAY_BUFFER, static_cast<GLsizeiptr>(colours.size() * sizeof(Rgba)), colours.data(),
                 GL_DYNAMIC_DRAW);
    glEnableVertexAttribArray(2);
    has_colours_ = true;
  }
  glBindVertexArray(0);
}

// ---- GlRenderer

GlRenderer::~GlRenderer() {
  if (mesh_program_) glDeleteProgram(mesh_program_);
  if (lines_vbo_) glDeleteBuffers(1, &lines_vbo_);
  if (lines_vao_) glDeleteVertexArrays(1, &lines_vao_);
}

Expected<void> GlRenderer::init() {
  auto vs = compile(GL_VERTEX_SHADER, kVertexShader);
  if (!vs) return std::unexpected(vs.error());
  auto fs = compile(GL_FRAGMENT_SHADER, kFragmentShader);
  if (!fs) return std::unexpected(fs.error());
  mesh_program_ = glCreateProgram();
  glAttachShader(mesh_program_, *vs);
  glAttachShader(mesh_program_, *fs);
  glLinkProgram(mesh_program_);
  glDeleteShader(*vs);
  glDeleteShader(*fs);
  GLint ok = 0;
  glGetProgramiv(mesh_program_, GL_LINK_STATUS, &ok);
  if (!ok) return make_error(ErrorCode::kUnsupported, "OpenGL shader program does not link");
  u_mvp_ = glGetUniformLocation(mesh_program_, "mvp");
  u_model_ = glGetUniformLocation(mesh_program_, "model");
  u_normal_matrix_ = glGetUniformLocation(mesh_program_, "normal_matrix");
  u_colour_ = glGetUniformLocation(mesh_program_, "colour");
  u_specular_ = glGetUniformLocation(mesh_program_, "specular");
  u_shininess_ = glGetUniformLocation(mesh_program_, "shininess");
  u_lit_ = glGetUniformLocation(mesh_program_, "lit");
  u_vertex_colours_ = glGetUniformLocation(mesh_program_, "vertex_colours");
  u_eye_ = glGetUniformLocation(mesh_program_, "eye");
  u_head_intensity_ = glGetUniformLocation(mesh_program_, "head_intensity");
  u_light_towards_ = glGetUniformLocation(mesh_program_, "light_towards");
  u_light_intensity_ = glGetUniformLocation(mesh_program_, "light_intensity");
  u_ambient_ = glGetUniformLocation(mesh_program_, "ambient");
  u_point_size_ = glGetUniformLocation(mesh_program_, "point_size");
  build_sphere(sphere_);
  build_cylinder(cylinder_, false);
  build_cylinder(cone_, true);
  glGenVertexArrays(1, &lines_vao_);
  glGenBuffers(1, &lines_vbo_);
  glBindVertexArray(lines_vao_);
  glBindBuffer(GL_ARRAY_BUFFER, lines_vbo_);
  glVertexAttribPointer(0, 3, GL_FLOAT, GL_FALSE, 0, nullptr);
  glEnableVertexAttribArray(0);
  glBindVertexArray(0);
  return {};
}

void GlRenderer::begin(const OrbitCamera& camera, int x_px, int y_px, int width_px, int height_px,
                       const Rgba& background) {
  glViewport(x_px, y_px, width_px, height_px);
  glEnable(GL_SCISSOR_TEST);
  glScissor(x_px, y_px, width_px, height_px);
  glClearColor(background.x(), background.y(), background.z(), background.w());
  glClear(GL_COLOR_BUFFER_BIT | GL_DEPTH_BUFFER_BIT);
  glDisable(GL_SCISSOR_TEST);
  glEnable(GL_DEPTH_TEST);
  glDepthFunc(GL_LEQUAL);
  glEnable(GL_PROGRAM_POINT_SIZE);
  glDisable(GL_CULL_FACE);
  const double aspect = static_cast<double>(width_px) / std::max(height_px, 1);
  view_projection_ = to_float(camera.projection(aspect) * camera.view());
  eye_ = camera.eye().cast<float>();
}

void GlRenderer::use_mesh_program(const Eigen::Matrix4f& model, const Material& material, bool lit,
                                  bool vertex_colours) {
  glUseProgram(mesh_program_);
  const Eigen::Matrix4f mvp = view_projection_ * model;
  const Eigen::Matrix3f normal_matrix = model.block<3, 3>(0, 0).inverse().transpose();
  glUniformMatrix4fv(u_mvp_, 1, GL_FALSE, mvp.data());
  glUniformMatrix4fv(u_model_, 1, GL_FALSE, model.data());
  glUniformMatrix3fv(u_normal_matrix_, 1, GL_FALSE, normal_matrix.data());
  glUniform4fv(u_colour_, 1, material.diffuse.data());
  glUniform3fv(u_specular_, 1, material.specular.data());
  glUniform1f(u_shininess_, material.shininess);
  glUniform1i(u_lit_, lit ? 1 : 0);
  glUniform1i(u_vertex_colours_, vertex_colours ? 1 : 0);
  glUniform3fv(u_eye_, 1, eye_.data());
  glUniform1f(u_head_intensity_, lighting_.headlight_intensity);
  const Eigen::Vector3f towards =
      lighting_.direction.norm() > 0.0f ? Eigen::Vector3f(-lighting_.direction.normalized()) : Eigen::Vector3f::UnitZ();
  glUniform3fv(u_light_towards_, 1, towards.data());
  glUniform1f(u_light_intensity_, lighting_.intensity);
  glUniform1f(u_ambient_, lighting_.ambient);
  glUniform1f(u_point_size_, 3.0f);
}

void GlRenderer::draw(const MeshBuffer& mesh, const Material& material, RenderMode mode, const Eigen::Matrix4f& model,
                      std::size_t first_triangle, std::size_t triangle_count) {
  if (!mesh.vao() || mesh.index_count() == 0 || 3 * first_triangle >= mesh.index_count()) return;
  triangle_count = std::min(triangle_count, mesh.index_count() / 3 - first_triangle);
  const bool transparent = material.diffuse.w() < 0.999f;
  if (transparent) {
    glEnable(GL_BLEND);
    glBlendFunc(GL_SRC_ALPHA, GL_ONE_MINUS_SRC_ALPHA);
    glDepthMask(GL_FALSE);
  }
  glBindVertexArray(mesh.vao());
  const auto count = static_cast<GLsizei>(3 * triangle_count);
  // NOLINTNEXTLINE(performance-no-int-to-ptr): OpenGL takes a byte offset into the bound index buffer as a pointer.
  const void* offset = reinterpret_cast<const void*>(3 * first_triangle * sizeof(std::uint32_t));
  if (mode == RenderMode::kShaded || mode == RenderMode::kShadedWireframe) {
    use_mesh_program(model, material, true, mesh.has_colours());
    // Push the faces back a little so that the wireframe drawn over them is not hidden.
    glEnable(GL_POLYGON_OFFSET_FILL);
    glPolygonOffset(1.0f, 1.0f);
    if (transparent) {
      // Without depth writes the faces blend in drawing order: the far (back) faces first, then
      // the near ones, so that a closed surface does not show patches of its far side on top.
      glEnable(GL_CULL_FACE);
      glCullFace(GL_FRONT);
      glDrawElements(GL_TRIANGLES, count, GL_UNSIGNED_INT, offset);
      glCullFace(GL_BACK);
      glDrawElements(GL_TRIANGLES, count, GL_UNSIGNED_INT, offset);
      glDisable(GL_CULL_FACE);
    } else {
      glDrawElements(GL_TRIANGLES, count, GL_UNSIGNED_INT, offset);
    }
    glDisable(GL_POLYGON_OFFSET_FILL);
  }
  if (mode == RenderMode::kWireframe || mode == RenderMode::kShadedWireframe) {
    Material edges = material;
    if (mode == RenderMode::kShadedWireframe) edges.diffuse.head<3>() *= 0.45f;
    use_mesh_program(model, edges, mode == RenderMode::kWireframe,
                     mode == RenderMode::kWireframe && mesh.has_colours());
    glPolygonMode(GL_FRONT_AND_BACK, GL_LINE);
    glDrawElements(GL_TRIANGLES, count, GL_UNSIGNED_INT, offset);
    glPolygonMode(GL_FRONT_AND_BACK, GL_FILL);
  }
  if (mode == RenderMode::kPoints) {
    use_mesh_program(model, material, true, mesh.has_colours());
    glDrawElements(GL_POINTS, count, GL_UNSIGNED_INT, offset);
  }
  glBindVertexArray(0);
  if (transparent) {
    glDisable(GL_BLEND);
    glDepthMask(GL_TRUE);
  }
}

void GlRenderer::draw_loose(std::span<const Vec3> points, const Rgba& colour, GLenum primitive, float point_size_px) {
  if (points.empty()) return;
  upload_vec3(lines_vbo_, points, line_scratch_, GL_STREAM_DRAW);
  Material m;
  m.diffuse = colour;
  use_mesh_program(Eigen::Matrix4f::Identity(), m, false, false);
  glUniform1f(u_point_size_, point_size_px);
  glBindVertexArray(lines_vao_);
  glDrawArrays(primitive, 0, static_cast<GLsizei>(points.size()));
  glBindVertexArray(0);
}

void GlRenderer::draw_lines(std::span<const Vec3> segment_points, const Rgba& colour) {
  draw_loose(segment_points, colour, GL_LINES, 1.0f);
}

void GlRenderer::draw_points(std::span<const Vec3> points, const Rgba& colour, float size_px) {
  draw_loose(points, colour, GL_POINTS, size_px);
}

void GlRenderer::draw_sphere(const Vec3& centre, double radius, const Rgba& colour) {
  Eigen::Matrix4f model = Eigen::Matrix4f::Identity();
  model.block<3, 3>(0, 0) *= static_cast<float>(radius);
  model.block<3, 1>(0, 3) = centre.cast<float>();
  Material m;
  m.diffuse = colour;
  m.specular = {0.5f, 0.5f, 0.5f};
  m.shininess = 0.4f;
  draw(sphere_, m, RenderMode::kShaded, model);
}

void GlRenderer::draw_cylinder(const Vec3& from, const Vec3& to, double radius, const Rgba& colour) {
  if (!((to - from).norm() > 0.0)) return;
  Material m;
  m.diffuse = colour;
  draw(cylinder_, m, RenderMode::kShaded, segment_transform(from, to, radius));
}

void GlRenderer::draw_arrow(const Vec3& from, const Vec3& to, double radius, const Rgba& colour) {
  const double length = (to - from).norm();
  if (!(length > 0.0)) return;
  const double head = std::min(length * 0.35, radius * 6.0);
  const Vec3 neck = to - (to - from) * (head / length);
  draw_cylinder(from, neck, radius, colour);
  Material m;
  m.diffuse = colour;
  draw(cone_, m, RenderMode::kShaded, segment_transform(neck, to, radius * 2.5));
}

std::vector<std::uint8_t> GlRenderer::read_pixels(int width_px, int height_px) const {
  const auto w = static_cast<std::size_t>(std::max(width_px, 0)), h = static_cast<std::size_t>(std::max(height_px, 0));
  std::vector<std::uint8_t> bottom_up(w * h * 3), top_down(w * h * 3);
  glPixelStorei(GL_PACK_ALIGNMENT, 1);
  glReadBuffer(GL_BACK);
  glReadPixels(0, 0, width_px, height_px, GL_RGB, GL_UNSIGNED_BYTE, bottom_up.data());
  for (std::size_t row = 0; row < h; ++row) {
    std::copy_n(bottom_up.data() + (h - 1 - row) * w * 3, w * 3, top_down.data() + row * w * 3);
  }
  return top_down;
}

}  // namespace hof::render
