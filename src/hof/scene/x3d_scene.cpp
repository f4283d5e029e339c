// X3D (H3D API) reader. One pass over the XML in document order, carrying the accumulated
// local-to-world matrix; USE elements resolve to the last node DEF'd with that name before them.
// Failures inside the walk are raised as a private exception and returned as hof::Error at
// the single entry point, so nothing escapes this file.

#include "hof/scene/x3d_scene.h"
#include "hof/mesh/xml_depth.h"

#include <fmt/format.h>
#include <pugixml.hpp>

#include <algorithm>
#include <charconv>
#include <cmath>
#include <fstream>
#include <map>
#include <numbers>
#include <sstream>
#include <string_view>
#include <utility>

namespace hof::scene {
namespace {

namespace fs = std::filesystem;
using Mat4 = Eigen::Matrix4d;
using haptics::SurfaceKind;

constexpr int kSphereStacks = 16;
constexpr int kSphereSlices = 32;   // multiple of 4: the tessellation reaches ±r on x and z
constexpr int kRoundSlices = 32;    // Cylinder and Cone

struct ParseFailure {
  Error error;
};

bool ends_with(std::string_view s, std::string_view suffix) {
  return s.size() >= suffix.size() && s.substr(s.size() - suffix.size()) == suffix;
}

std::vector<std::string_view> tokens(std::string_view text) {
  std::vector<std::string_view> out;
  std::size_t i = 0;
  auto is_sep = [](char c) { return c == ',' || c == ' ' || c == '\t' || c == '\n' || c == '\r'; };
  while (i < text.size()) {
    while (i < text.size() && is_sep(text[i])) ++i;
    const std::size_t start = i;
    while (i < text.size() && !is_sep(text[i])) ++i;
    if (i > start) out.push_back(text.substr(start, i - start));
  }
  return out;
}

Mat4 axis_angle(const std::vector<double>& r) {
  Mat4 m = Mat4::Identity();
  const Vec3 axis(r[0], r[1], r[2]);
  if (axis.norm() > 1e-12) m.topLeftCorner<3, 3>() = Eigen::AngleAxisd(r[3], axis.normalized()).toRotationMatrix();
  return m;
}

Mat4 translation(const Vec3& t) {
  Mat4 m = Mat4::Identity();
  m.topRightCorner<3, 1>() = t;
  return m;
}

// Flips every triangle so its normal points away from the origin (convex primitives centred
// at the origin, as X3D defines Sphere, Box, Cylinder and Cone).
void orient_outward(mesh::TriMesh& m) {
  for (auto& t : m.triangles) {
    const Vec3& a = m.vertices[t[0]];
    const Vec3 n = (m.vertices[t[1]] - a).cross(m.vertices[t[2]] - a);
    if (n.dot(a + m.vertices[t[1]] + m.vertices[t[2]]) < 0.0) std::swap(t[1], t[2]);
  }
}

void add_quad(mesh::TriMesh& m, mesh::NodeIndex a, mesh::NodeIndex b, mesh::NodeIndex c, mesh::NodeIndex d) {
  m.triangles.push_back({a, b, c});
  m.triangles.push_back({a, c, d});
}

mesh::TriMesh make_sphere(double r) {
  mesh::TriMesh m;
  m.vertices.emplace_back(0.0, r, 0.0);
  for (int i = 1; i < kSphereStacks; ++i) {
    const double phi = std::numbers::pi * i / kSphereStacks;
    for (int j = 0; j < kSphereSlices; ++j) {
      const double theta = 2.0 * std::numbers::pi * j / kSphereSlices;
      m.vertices.emplace_back(r * std::sin(phi) * std::sin(theta), r * std::cos(phi), r * std::sin(phi) * std::cos(theta));
    }
  }
  m.vertices.emplace_back(0.0, -r, 0.0);
  const auto ring = [](int i, int j) { return static_cast<mesh::NodeIndex>(1 + (i - 1) * kSphereSlices + j % kSphereSlices); };
  const auto south = static_cast<mesh::NodeIndex>(m.vertices.size() - 1);
  for (int j = 0; j < kSphereSlices; ++j) {
    m.triangles.push_back({0, ring(1, j), ring(1, j + 1)});
    for (int i = 1; i + 1 < kSphereStacks; ++i) add_quad(m, ring(i, j), ring(i + 1, j), ring(i + 1, j + 1), ring(i, j + 1));
    m.triangles.push_back({south, ring(kSphereStacks - 1, j + 1), ring(kSphereStacks - 1, j)});
  }
  orient_outward(m);
  return m;
}

mesh::TriMesh make_box(const Vec3& size) {
  mesh::TriMesh m;
  const Vec3 h = 0.5 * size;
  for (int i = 0; i < 8; ++i) m.vertices.emplace_back((i & 1) ? h.x() : -h.x(), (i & 2) ? h.y() : -h.y(), (i & 4) ? h.z() : -h.z());
  add_quad(m, 0, 2, 3, 1);  // z−
  add_quad(m, 4, 5, 7, 6);  // z+
  add_quad(m, 0, 1, 5, 4);  // y−
  add_quad(m, 2, 6, 7, 3);  // y+
  add_quad(m, 0, 4, 6, 2);  // x−
  add_quad(m, 1, 3, 7, 5);  // x+
  orient_outward(m);
  return m;
}

// Cylinder (top_radius = bottom_radius) or Cone (top_radius = 0: one apex vertex).
mesh::TriMesh make_round(double bottom_radius, double top_radius, double height, bool side, bool bottom, bool top) {
  mesh::TriMesh m;
  constexpr int n = kRoundSlices;  // a constant: the lambdas below need not capture it
  for (int j = 0; j < n; ++j) {
    const double t = 2.0 * std::numbers::pi * j / n;
    m.vertices.emplace_back(bottom_radius * std::sin(t), -0.5 * height, bottom_radius * std::cos(t));
  }
  const bool cone = top_radius <= 0.0;
  if (cone) {
    m.vertices.emplace_back(0.0, 0.5 * height, 0.0);
  } else {
    for (int j = 0; j < n; ++j) {
      const double t = 2.0 * std::numbers::pi * j / n;
      m.vertices.emplace_back(top_radius * std::sin(t), 0.5 * height, top_radius * std::cos(t));
    }
  }
  const auto b = [](int j) { return static_cast<mesh::NodeIndex>(j % n); };
  const auto tp = [cone](int j) { return static_cast<mesh::NodeIndex>(cone ? n : n + j % n); };
  for (int j = 0; j < n && side; ++j) {
    if (cone) m.triangles.push_back({b(j), b(j + 1), tp(j)});
    else add_quad(m, b(j), b(j + 1), tp(j + 1), tp(j));
  }
  if (bottom) {
    const auto c = static_cast<mesh::NodeIndex>(m.vertices.size());
    m.vertices.emplace_back(0.0, -0.5 * height, 0.0);
    for (int j = 0; j < n; ++j) m.triangles.push_back({c, b(j + 1), b(j)});
  }
  if (top && !cone) {
    const auto c = static_cast<mesh::NodeIndex>(m.vertices.size());
    m.vertices.emplace_back(0.0, 0.5 * height, 0.0);
    for (int j = 0; j < n; ++j) m.triangles.push_back({c, tp(j), tp(j + 1)});
  }
  orient_outward(m);
  return m;
}

void transform_mesh(mesh::TriMesh& m, const Mat4& X) {
  for (auto& v : m.vertices) v = (X * v.homogeneous()).head<3>();
  if (X.topLeftCorner<3, 3>().determinant() < 0.0)
    for (auto& t : m.triangles) std::swap(t[1], t[2]);
}

class X3dReader {
 public:
  X3dReader(fs::path file, std::string text) : file_(std::move(file)), text_(std::move(text)) {
    scene_.file = file_;
    line_starts_.push_back(0);
    for (std::size_t i = 0; i < text_.size(); ++i)
      if (text_[i] == '\n') line_starts_.push_back(static_cast<std::ptrdiff_t>(i + 1));
  }

  X3dScene run() {
    pugi::xml_document doc;
    const auto parsed = doc.load_buffer(text_.data(), text_.size(), pugi::parse_default);
    if (!parsed) fail(ErrorCode::kParse, line_at(parsed.offset), fmt::format("malformed XML: {}", parsed.description()));
    if (const pugi::xml_node deep = mesh::first_too_deep_element(doc)) {
      fail(ErrorCode::kParse, line_at(deep.offset_debug()),
           fmt::format("<{}> is nested deeper than {} levels", deep.name(), mesh::kMaxXmlDepth));
    }
    collect_defs(doc);
    const pugi::xml_node root = doc.document_element();
    if (!root) fail(ErrorCode::kParse, 1, "no root element");
    visit(root, Mat4::Identity());
    if (!scene_.unsupported.empty()) {
      std::string list;
      for (std::size_t i = 0; i < scene_.unsupported.size() && i < 8; ++i) list += (i ? ", " : "") + scene_.unsupported[i];
      if (scene_.unsupported.size() > 8) list += ", ...";
      scene_.warnings.push_back(fmt::format("{}: {} node(s) not modelled, ignored: {}", file_.string(),
                                            scene_.unsupported.size(), list));
    }
    return std::move(scene_);
  }

 private:
  // ---- positions, errors, DEF/USE
  std::int64_t line_at(std::ptrdiff_t offset) const {
    return std::upper_bound(line_starts_.begin(), line_starts_.end(), offset) - line_starts_.begin();
  }
  std::int64_t line_of(pugi::xml_node n) const { return line_at(n.offset_debug()); }

  [[noreturn]] void fail(ErrorCode code, std::int64_t line, std::string message) const {
    throw ParseFailure{Error{code, std::move(message), file_.string(), line, -1}};
  }

  void collect_defs(pugi::xml_node n) {
    for (pugi::xml_node c : n.children()) {
      if (c.type() != pugi::node_element) continue;
      if (const char* d = c.attribute("DEF").as_string(); *d) defs_[d].push_back(c);
      collect_defs(c);
    }
  }

  // The node a possible USE element stands for.
  pugi::xml_node resolve(pugi::xml_node n) const {
    const std::string_view use = n.attribute("USE").as_string();
    if (use.empty()) return n;
    const auto it = defs_.find(std::string(use));
    pugi::xml_node found;
    if (it != defs_.end())
      for (pugi::xml_node d : it->second)
        if (d.offset_debug() < n.offset_debug()) found = d;
    if (!found) fail(ErrorCode::kParse, line_of(n), fmt::format("<{} USE='{}'>: no node DEF'd with that name before", n.name(), use));
    // A USE inside the node it names would contain itself: an endless tree.
    for (pugi::xml_node a = n.parent(); a; a = a.parent()) {
      if (a == found) {
        fail(ErrorCode::kParse, line_of(n),
             fmt::format("<{} USE='{}'> is inside the node it names (line {}): a cycle", n.name(), use, line_of(found)));
      }
    }
    return found;
  }

  void unsupported(pugi::xml_node original, std::string_view extra = {}) {
    const pugi::xml_node n = resolve(original);
    std::string def = n.attribute("DEF").as_string();
    std::string entry = def.empty() ? std::string(n.name()) : fmt::format("{} '{}'", n.name(), def);
    if (!extra.empty()) entry += fmt::format(" {}", extra);
    scene_.unsupported.push_back(fmt::format("{} (line {})", entry, line_of(original)));
  }

  // ---- field values (empty or missing attribute = default)
  std::vector<double> numbers(pugi::xml_node n, const char* field) const {
    std::vector<double> out;
    for (std::string_view tok : tokens(n.attribute(field).as_string())) {
      if (!tok.empty() && tok.front() == '+') tok.remove_prefix(1);
      double v = 0.0;
      const auto [ptr, ec] = std::from_chars(tok.data(), tok.data() + tok.size(), v);
      if (ec != std::errc{} || ptr != tok.data() + tok.size() || !std::isfinite(v))
        fail(ErrorCode::kParse, line_of(n), fmt::format("<{}> field {}: '{}' is not a number", n.name(), field, tok));
      out.push_back(v);
    }
    return out;
  }
  std::vector<double> numbers(pugi::xml_node n, const char* field, std::size_t count, std::vector<double> def) const {
    auto v = numbers(n, field);
    if (v.empty()) return def;
    if (v.size() != count)
      fail(ErrorCode::kParse, line_of(n), fmt::format("<{}> field {}: expected {} numbers, got {}", n.name(), field, count, v.size()));
    return v;
  }
  double number(pugi::xml_node n, const char* field, double def) const { return numbers(n, field, 1, {def})[0]; }
  Vec3 vec3(pugi::xml_node n, const char* field, const Vec3& def) const {
    const auto v = numbers(n, field, 3, {def.x(), def.y(), def.z()});
    return {v[0], v[1], v[2]};
  }
  std::vector<std::int64_t> integers(pugi::xml_node n, const char* field) const {
    std::vector<std::int64_t> out;
    for (double v : numbers(n, field)) {
      if (v != std::floor(v)) fail(ErrorCode::kParse, line_of(n), fmt::format("<{}> field {}: {} is not an integer", n.name(), field, v));
      // Past ±2⁶³ the conversion is undefined (found by fuzz_x3d): no index or count is that large.
      if (!(v >= -0x1p63 && v < 0x1p63))
        fail(ErrorCode::kParse, line_of(n), fmt::format("<{}> field {}: {} is out of range", n.name(), field, v));
      out.push_back(static_cast<std::int64_t>(v));
    }
    return out;
  }
  bool boolean(pugi::xml_node n, const char* field, bool def) const {
    const std::string_view s = n.attribute(field).as_string();
    if (s.empty()) return def;
    if (s == "true" || s == "TRUE" || s == "True") return true;
    if (s == "false" || s == "FALSE" || s == "False") return false;
    fail(ErrorCode::kParse, line_of(n), fmt::format("<{}> field {}: '{}' is not a boolean", n.name(), field, s));
  }
  std::string string(pugi::xml_node n, const char* field, std::string_view def) const {
    std::string s = n.attribute(field).as_string();
    if (s.size() >= 2 && s.front() == '"' && s.back() == '"') s = s.substr(1, s.size() - 2);
    return s.empty() ? std::string(def) : s;
  }
  template <class E>
  E choice(pugi::xml_node n, const char* field, std::initializer_list<std::pair<std::string_view, E>> options, E def) const {
    const std::string s = string(n, field, "");
    if (s.empty()) return def;
    std::string names;
    for (const auto& [name, value] : options) {
      if (name == s) return value;
      names += fmt::format(" {}", name);
    }
    fail(ErrorCode::kParse, line_of(n), fmt::format("<{}> field {}: '{}' is not one of{}", n.name(), field, s, names));
  }

  // ---- scene graph
  static bool is_group(std::string_view t) {
    return t == "X3D" || t == "Scene" || t == "Group" || t == "StaticGroup" || t == "HapticLayeredGroup" ||
           t == "ToggleGroup" || t == "Collision";
  }
  static bool is_geometry(std::string_view t) {
    return t == "Sphere" || t == "Box" || t == "Cylinder" || t == "Cone" || t == "IndexedTriangleSet" ||
           t == "IndexedFaceSet" || t == "Rectangle2D";
  }

  void visit_children(pugi::xml_node n, const Mat4& X) {
    for (pugi::xml_node c : n.children())
      if (c.type() == pugi::node_element) visit(c, X);
  }

  void visit(pugi::xml_node original, const Mat4& X) {
    // USE copies subtrees: a chain of nodes each USE'd twice by the next doubles the tree at
    // every link (2^40 nodes from 40 lines). Bounded, so such a file is refused, not a hang.
    if (++visited_ > kMaxVisitedNodes) {
      fail(ErrorCode::kParse, line_of(original),
           fmt::format("the scene expands to more than {} nodes through USE", kMaxVisitedNodes));
    }
    const std::string_view tag = original.name();
    if (tag == "head" || tag == "meta" || tag == "component" || tag == "unit") return;
    const pugi::xml_node n = resolve(original);
    const std::string_view t = n.name();
    if (t == "HapticLayeredGroup") {
      // H3D: each child is a haptic layer, rendered with its own proxy (forces summed).
      const int outer = layer_;
      int index = 0;
      for (pugi::xml_node c : n.children()) {
        if (c.type() != pugi::node_element) continue;
        layer_ = index++;
        visit(c, X);
      }
      layer_ = outer;
    } else if (is_group(t)) {
      visit_children(n, X);
    } else if (t == "Transform") {
      visit_children(n, X * transform_matrix(n));
    } else if (t == "MatrixTransform") {
      const auto m = numbers(n, "matrix", 16, {1, 0, 0, 0, 0, 1, 0, 0, 0, 0, 1, 0, 0, 0, 0, 1});
      visit_children(n, X * Eigen::Map<const Eigen::Matrix<double, 4, 4, Eigen::RowMajor>>(m.data()));
    } else if (t == "FitToBoxTransform") {
      fit_to_box(n, X);
    } else if (t == "Shape" || t == "DeformableShape") {
      shape(original, n, X);
    } else if (t == "DeviceInfo") {
      device_info(n);
    } else if (t == "GlobalSettings") {
      global_settings(n);
    } else if (t == "SpringEffect") {
      haptics::SpringEffect s;
      s.position_m = (X * vec3(n, "position", Vec3::Zero()).homogeneous()).head<3>();
      s.spring_constant_n_per_m = number(n, "springConstant", 100.0);
      s.start_distance_m = number(n, "startDistance", 0.01);
      s.escape_distance_m = number(n, "escapeDistance", 0.01);
      s.damping_n_s_per_m = number(n, "damping", 0.0);
      scene_.force_effects.springs.push_back(s);
    } else if (t == "ViscosityEffect") {
      haptics::ViscosityEffect v;
      v.viscosity_pa_s = number(n, "viscosity", 0.01);
      v.radius_m = number(n, "radius", 0.0025);
      v.damping_factor = number(n, "dampingFactor", 0.5);
      v.enabled = boolean(n, "enabled", true);
      scene_.force_effects.viscosities.push_back(v);
    } else if (t == "ForceField") {
      // The force keeps its magnitude and turns with the enclosing transforms.
      const Vec3 f = vec3(n, "force", Vec3::Zero());
      const Vec3 d = X.topLeftCorner<3, 3>() * f;
      scene_.force_effects.constants.push_back({d.norm() > 0.0 ? Vec3(d.normalized() * f.norm()) : Vec3::Zero()});
    } else if (t == "Viewpoint") {
      X3dViewpoint v;
      v.position = vec3(n, "position", v.position);
      const auto o = numbers(n, "orientation", 4, {0, 0, 1, 0});
      std::copy(o.begin(), o.end(), v.orientation.begin());
      v.field_of_view_rad = number(n, "fieldOfView", v.field_of_view_rad);
      scene_.viewpoints.push_back(v);
    } else if (t == "Inline") {
      unsupported(original, fmt::format("url={}", n.attribute("url").as_string()));
    } else {
      unsupported(original);
    }
  }

  // X3D Transform: T · C · R · SR · S · SR⁻¹ · C⁻¹.
  Mat4 transform_matrix(pugi::xml_node n) const {
    const Vec3 t = vec3(n, "translation", Vec3::Zero());
    const Vec3 c = vec3(n, "center", Vec3::Zero());
    const Vec3 s = vec3(n, "scale", Vec3::Ones());
    const Mat4 R = axis_angle(numbers(n, "rotation", 4, {0, 0, 1, 0}));
    const Mat4 SR = axis_angle(numbers(n, "scaleOrientation", 4, {0, 0, 1, 0}));
    Mat4 S = Mat4::Identity();
    S.diagonal().head<3>() = s;
    return translation(t) * translation(c) * R * SR * S * SR.transpose() * translation(-c);
  }

  // FitToBoxTransform: the children are read in its local frame, their bound is scaled and
  // moved into the box, then everything is taken to the world frame.
  void fit_to_box(pugi::xml_node n, const Mat4& X) {
    const Vec3 box_size = vec3(n, "boxSize", Vec3::Constant(0.1));
    const Vec3 box_center = vec3(n, "boxCenter", Vec3::Zero());
    const bool uniform = boolean(n, "uniformScalingOnly", false);
    const bool active = boolean(n, "active", true);
    const std::size_t first_shape = scene_.shapes.size();
    const std::size_t first_spring = scene_.force_effects.springs.size();
    const std::size_t first_constant = scene_.force_effects.constants.size();
    visit_children(n, Mat4::Identity());

    Eigen::AlignedBox3d bound;
    for (std::size_t i = first_shape; i < scene_.shapes.size(); ++i) {
      for (const Vec3& v : scene_.shapes[i].mesh_W.vertices) bound.extend(v);
      for (const Vec3& v : scene_.shapes[i].haptic_mesh_W.vertices) bound.extend(v);
    }
    Mat4 M = Mat4::Identity();
    if (active && !bound.isEmpty()) {
      const Vec3 size = bound.sizes();
      Vec3 s = Vec3::Ones();
      double smallest = std::numeric_limits<double>::infinity();
      for (int k = 0; k < 3; ++k)
        if (size[k] > 1e-12) smallest = std::min(smallest, box_size[k] / size[k]);
      if (!std::isfinite(smallest)) smallest = 1.0;
      for (int k = 0; k < 3; ++k) s[k] = (uniform || size[k] <= 1e-12) ? smallest : box_size[k] / size[k];
      M.diagonal().head<3>() = s;
      M.topRightCorner<3, 1>() = box_center - s.cwiseProduct(bound.center());
    }
    const Mat4 XM = X * M;
    for (std::size_t i = first_shape; i < scene_.shapes.size(); ++i) {
      transform_mesh(scene_.shapes[i].mesh_W, XM);
      transform_mesh(scene_.shapes[i].haptic_mesh_W, XM);
    }
    for (std::size_t i = first_spring; i < scene_.force_effects.springs.size(); ++i) {
      Vec3& p = scene_.force_effects.springs[i].position_m;
      p = (XM * p.homogeneous()).head<3>();
    }
    for (std::size_t i = first_constant; i < scene_.force_effects.constants.size(); ++i) {
      Vec3& f = scene_.force_effects.constants[i].force_n;
      const Vec3 d = XM.topLeftCorner<3, 3>() * f;
      if (d.norm() > 0.0) f = d.normalized() * f.norm();
    }
  }

  // ---- shapes
  void shape(pugi::xml_node original, pugi::xml_node n, const Mat4& X) {
    X3dShape s;
    s.def = n.attribute("DEF").as_string();
    s.line = line_of(original);
    s.deformable = std::string_view(n.name()) == "DeformableShape";
    for (pugi::xml_node c_orig : n.children()) {
      if (c_orig.type() != pugi::node_element) continue;
      const pugi::xml_node c = resolve(c_orig);
      const std::string_view t = c.name();
      const std::string_view field = c_orig.attribute("containerField").as_string();
      if (t == "Appearance") {
        appearance(c, s);
      } else if (is_geometry(t) && field == "hapticGeometry") {
        s.haptic_geometry_type = t;
        bool solid = true;
        s.haptic_mesh_W = geometry(c, solid, s);
        transform_mesh(s.haptic_mesh_W, X);
      } else if (is_geometry(t)) {
        s.geometry_type = t;
        s.mesh_W = geometry(c, s.solid, s);
        transform_mesh(s.mesh_W, X);
      } else if (s.deformable && (field == "deformer" || ends_with(t, "Deformer"))) {
        s.deformer_type = t;
      } else {
        unsupported(c_orig);
      }
    }
    s.layer = layer_;
    scene_.shapes.push_back(std::move(s));
  }

  void appearance(pugi::xml_node n, X3dShape& s) {
    for (pugi::xml_node c_orig : n.children()) {
      if (c_orig.type() != pugi::node_element) continue;
      const pugi::xml_node c = resolve(c_orig);
      const std::string_view t = c.name();
      if (t == "Material") {
        s.diffuse_color = vec3(c, "diffuseColor", s.diffuse_color);
        s.transparency = std::clamp(c.attribute("transparency").as_double(0.0), 0.0, 1.0);
        s.has_material = true;
      } else if (t == "SmoothSurface" || t == "FrictionalSurface" || t == "MagneticSurface" ||
                 t == "OpenHapticsSurface" || t == "DepthMapSurface" || t == "HapticTexturesSurface") {
        s.touchable = true;
        s.surface_type = t;
        s.surface = surface(c);
      } else {
        unsupported(c_orig);
      }
    }
  }

  haptics::SurfaceMaterial surface(pugi::xml_node n) {
    const std::string_view t = n.name();
    haptics::SurfaceMaterial m;
    const bool magnetic = t == "MagneticSurface" || t == "OpenHapticsSurface";
    m.kind = t == "SmoothSurface" ? SurfaceKind::kSmooth : magnetic ? SurfaceKind::kMagnetic : SurfaceKind::kFrictional;
    m.stiffness = number(n, "stiffness", 0.5);
    m.damping_n_s_per_m = number(n, "damping", 0.0);
    m.use_relative_values = boolean(n, "useRelativeValues", true);
    if (m.kind == SurfaceKind::kSmooth) {
      m.static_friction = 0.0;  // HAPI::FrictionSurface(k, d, 0, 0)
      m.dynamic_friction = 0.0;
    } else {
      m.static_friction = number(n, "staticFriction", 0.1);
      m.dynamic_friction = number(n, "dynamicFriction", 0.4);
    }
    if (magnetic) m.snap_distance_m = number(n, "snapDistance", 0.01);
    for (pugi::xml_node c : n.children())  // texture maps and the like
      if (c.type() == pugi::node_element) unsupported(c);
    return m;
  }

  // Geometry in its local frame; also reads `solid` and the geometry's own option nodes.
  mesh::TriMesh geometry(pugi::xml_node n, bool& solid, X3dShape& s) {
    const std::string_view t = n.name();
    solid = boolean(n, "solid", true);
    mesh::TriMesh m;
    pugi::xml_node coord;
    for (pugi::xml_node c_orig : n.children()) {
      if (c_orig.type() != pugi::node_element) continue;
      const pugi::xml_node c = resolve(c_orig);
      const std::string_view ct = c.name();
      if (ct == "Coordinate") coord = c;
      else if (ct == "HapticsOptions") { if (!s.haptics_options) s.haptics_options = haptics_options(c); }
      else if (ct == "GeometryBoundTreeOptions") { if (!s.bound_tree_options) s.bound_tree_options = bound_tree_options(c); }
      else unsupported(c_orig);
    }
    if (t == "Sphere") {
      m = make_sphere(number(n, "radius", 1.0));
    } else if (t == "Box") {
      m = make_box(vec3(n, "size", Vec3::Constant(2.0)));
    } else if (t == "Cylinder") {
      const double r = number(n, "radius", 1.0);
      m = make_round(r, r, number(n, "height", 2.0), boolean(n, "side", true), boolean(n, "bottom", true), boolean(n, "top", true));
    } else if (t == "Cone") {
      m = make_round(number(n, "bottomRadius", 1.0), 0.0, number(n, "height", 2.0), boolean(n, "side", true),
                     boolean(n, "bottom", true), false);
    } else if (t == "Rectangle2D") {
      const auto sz = numbers(n, "size", 2, {2.0, 2.0});
      const double x = 0.5 * sz[0], y = 0.5 * sz[1];
      m.vertices = {Vec3(-x, -y, 0), Vec3(x, -y, 0), Vec3(x, y, 0), Vec3(-x, y, 0)};
      m.triangles = {{0, 1, 2}, {0, 2, 3}};
    } else {
      indexed_set(n, coord, m);
    }
    return m;
  }

  void indexed_set(pugi::xml_node n, pugi::xml_node coord, mesh::TriMesh& m) {
    const bool triangle_set = std::string_view(n.name()) == "IndexedTriangleSet";
    if (coord) {
      const auto p = numbers(coord, "point");
      if (p.size() % 3 != 0)
        fail(ErrorCode::kParse, line_of(coord), fmt::format("<Coordinate> field point: {} numbers, not a multiple of 3", p.size()));
      for (std::size_t i = 0; i + 2 < p.size(); i += 3) m.vertices.emplace_back(p[i], p[i + 1], p[i + 2]);
    }
    const auto index = integers(n, triangle_set ? "index" : "coordIndex");
    const auto check = [&](std::int64_t i) {
      if (i < 0 || i >= static_cast<std::int64_t>(m.vertices.size()))
        fail(ErrorCode::kInvalidMesh, line_of(n),
             fmt::format("<{}>: index {} out of range (the Coordinate has {} points)", n.name(), i, m.vertices.size()));
      return static_cast<mesh::NodeIndex>(i);
    };
    if (triangle_set) {
      if (index.size() % 3 != 0)
        scene_.warnings.push_back(fmt::format("{}:{}: IndexedTriangleSet: {} indices, the last {} ignored", file_.string(),
                                              line_of(n), index.size(), index.size() % 3));
      for (std::size_t i = 0; i + 2 < index.size(); i += 3)
        m.triangles.push_back({check(index[i]), check(index[i + 1]), check(index[i + 2])});
    } else {
      // Polygons separated by −1 (the last one may omit it), fan-triangulated.
      std::vector<mesh::NodeIndex> polygon;
      const auto flush = [&] {
        for (std::size_t k = 1; k + 1 < polygon.size(); ++k) m.triangles.push_back({polygon[0], polygon[k], polygon[k + 1]});
        polygon.clear();
      };
      for (std::int64_t i : index) {
        if (i == -1) flush();
        else polygon.push_back(check(i));
      }
      flush();
    }
    if (!boolean(n, "ccw", true))
      for (auto& t : m.triangles) std::swap(t[1], t[2]);
  }

  // ---- options
  X3dHapticsOptions haptics_options(pugi::xml_node n) const {
    X3dHapticsOptions o;
    o.touchable_face = choice<X3dTouchableFace>(n, "touchableFace",
                                                {{"AS_GRAPHICS", X3dTouchableFace::kAsGraphics},
                                                 {"FRONT", X3dTouchableFace::kFront},
                                                 {"BACK", X3dTouchableFace::kBack},
                                                 {"FRONT_AND_BACK", X3dTouchableFace::kFrontAndBack}},
                                                o.touchable_face);
    o.max_distance_m = number(n, "maxDistance", o.max_distance_m);
    o.look_ahead_factor = number(n, "lookAheadFactor", o.look_ahead_factor);
    o.use_bound_tree = boolean(n, "useBoundTree", o.use_bound_tree);
    o.interpolate_force_effects = boolean(n, "interpolateForceEffects", o.interpolate_force_effects);
    o.dynamic_mode = choice<X3dDynamicMode>(n, "dynamicMode",
                                            {{"TRANSFORM_CHANGED", X3dDynamicMode::kTransformChanged},
                                             {"ALWAYS", X3dDynamicMode::kAlways},
                                             {"NEVER", X3dDynamicMode::kNever}},
                                            o.dynamic_mode);
    return o;
  }

  X3dBoundTreeOptions bound_tree_options(pugi::xml_node n) const {
    X3dBoundTreeOptions o;
    o.bound_type = choice<X3dBoundType>(
        n, "boundType", {{"AABB", X3dBoundType::kAabb}, {"OBB", X3dBoundType::kObb}, {"SPHERE", X3dBoundType::kSphere}},
        o.bound_type);
    const auto leaf = integers(n, "maxTrianglesInLeaf");
    if (!leaf.empty()) o.max_triangles_in_leaf = static_cast<std::int32_t>(leaf[0]);
    return o;
  }

  void global_settings(pugi::xml_node n) {
    if (!scene_.global_settings) scene_.global_settings.emplace();
    X3dGlobalSettings& g = *scene_.global_settings;
    for (pugi::xml_node c_orig : n.children()) {
      if (c_orig.type() != pugi::node_element) continue;
      const pugi::xml_node c = resolve(c_orig);
      const std::string_view t = c.name();
      if (t == "HapticsOptions") {
        if (!g.haptics) g.haptics = haptics_options(c);
      } else if (t == "GeometryBoundTreeOptions") {
        if (!g.bound_tree) g.bound_tree = bound_tree_options(c);
      } else if (t == "DebugOptions") {
        if (g.debug) continue;
        X3dDebugOptions d;
        d.draw_bound = boolean(c, "drawBound", false);
        const auto depth = integers(c, "drawBoundTree");
        if (!depth.empty()) d.draw_bound_tree = static_cast<std::int32_t>(depth[0]);
        d.draw_haptic_triangles = boolean(c, "drawHapticTriangles", false);
        d.print_shader_warnings = boolean(c, "printShaderWarnings", false);
        g.debug = d;
      } else {
        unsupported(c_orig);
      }
    }
  }

  // ---- devices
  void device_info(pugi::xml_node n) {
    for (pugi::xml_node c_orig : n.children()) {
      if (c_orig.type() != pugi::node_element) continue;
      const pugi::xml_node c = resolve(c_orig);
      if (!ends_with(c.name(), "Device")) {
        unsupported(c_orig);
        continue;
      }
      X3dDevice d;
      d.type = c.name();
      d.def = c.attribute("DEF").as_string();
      d.device_name = string(c, "deviceName", "");
      const auto pc = numbers(c, "positionCalibration", 16, {d.position_calibration.begin(), d.position_calibration.end()});
      std::copy(pc.begin(), pc.end(), d.position_calibration.begin());
      const auto oc = numbers(c, "orientationCalibration", 4, {1, 0, 0, 0});
      std::copy(oc.begin(), oc.end(), d.orientation_calibration.begin());
      d.force_limit_n = number(c, "forceLimit", -1.0);
      for (pugi::xml_node r_orig : c.children()) {
        if (r_orig.type() != pugi::node_element) continue;
        const pugi::xml_node r = resolve(r_orig);
        const std::string_view rt = r.name();
        const std::string_view field = r_orig.attribute("containerField").as_string();
        if (field == "stylus") continue;  // the drawn stylus: graphics only
        if (!ends_with(rt, "Renderer")) {
          unsupported(r_orig);
          continue;
        }
        if (d.renderer) continue;
        X3dRenderer renderer;
        renderer.type = rt;
        if (rt == "GodObjectRenderer") renderer.kind = haptics::RendererKind::kGodObject;
        if (rt == "RuspiniRenderer") {
          renderer.kind = haptics::RendererKind::kRuspini;
          renderer.proxy_radius_m = number(r, "proxyRadius", 0.0025);
        }
        d.renderer = renderer;
      }
      scene_.devices.push_back(std::move(d));
    }
  }

  fs::path file_;
  std::string text_;
  std::vector<std::ptrdiff_t> line_starts_;
  std::map<std::string, std::vector<pugi::xml_node>, std::less<>> defs_;
  static constexpr std::int64_t kMaxVisitedNodes = 200000;
  std::int64_t visited_{0};
  X3dScene scene_;
  int layer_{0};  // haptic layer of the shapes being visited
};

}  // namespace

Expected<X3dScene> read_x3d_scene(const std::filesystem::path& path) {
  std::ifstream in(path, std::ios::binary);
  if (!in) return make_error(ErrorCode::kIo, "cannot open X3D file", path.string());
  std::ostringstream buffer;
  buffer << in.rdbuf();
  try {
    X3dReader reader(path, buffer.str());
    return reader.run();
  } catch (const ParseFailure& f) {
    return std::unexpected(f.error);
  }
}

}  // namespace hof::scene
