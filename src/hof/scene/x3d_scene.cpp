// X3D (H3D API) reader. One pass over the scene graph in document order, carrying the
// accumulated local-to-world matrix. The files and what their nodes stand for (USE → the node
// DEF'd before it, ProtoInstance → a copy of its PROTO's body with the fields substituted,
// Inline → the file it names; each file and PROTO body with DEF names of its own) are
// detail/x3d_source's; the meshes of the geometry nodes detail/x3d_geometry's; the haptic
// nodes (surfaces, effects, options, settings, devices) x3d_haptic_nodes.cpp's.
// Failures inside the walk are raised as a private exception and returned as hof::Error at
// the single entry point, so nothing escapes this file.

#include "hof/scene/x3d_scene.h"
#include "hof/scene/detail/x3d_geometry.h"
#include "hof/scene/detail/x3d_reader.h"
#include "hof/scene/detail/x3d_source.h"

#include <fmt/format.h>
#include <pugixml.hpp>

#include <algorithm>
#include <array>
#include <cmath>
#include <fstream>
#include <map>
#include <memory>
#include <numbers>
#include <optional>
#include <set>
#include <sstream>
#include <string_view>
#include <utility>

namespace hof::scene {
namespace detail {

namespace fs = std::filesystem;

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

void transform_mesh(mesh::TriMesh& m, const Mat4& X) {
  for (auto& v : m.vertices) v = (X * v.homogeneous()).head<3>();
  if (X.topLeftCorner<3, 3>().determinant() < 0.0)
    for (auto& t : m.triangles) std::swap(t[1], t[2]);
}

X3dScene X3dReader::run(std::string text) {
  const std::string_view head = std::string_view(text).substr(0, 64);
  if (head.starts_with("#X3D") || head.starts_with("#VRML")) {
    source_.fail_at(scene_.file, 1, ErrorCode::kUnsupported,
                    "the X3D classic VRML encoding (#X3D / #VRML) is not read: only X3D's XML encoding (<X3D>...)");
  }
  X3dDocument& doc = source_.parse(scene_.file, std::move(text), nullptr, 0);
  const pugi::xml_node root = doc.xml.document_element();
  if (!root) source_.fail_at(scene_.file, 1, ErrorCode::kParse, "no root element");
  scene_.root_element = root.name();
  scene_.root_line = source_.line_of(root);
  root_ = root;
  inline_stack_.push_back(source_.weakly_canonical(scene_.file));
  visit(root, Mat4::Identity());
  if (!scene_.unsupported.empty()) {
    std::string list;
    for (std::size_t i = 0; i < scene_.unsupported.size() && i < 8; ++i)
      list += (i ? ", " : "") + scene_.unsupported[i];
    if (scene_.unsupported.size() > 8) list += ", ...";
    scene_.warnings.push_back(
        fmt::format("{}: {} node(s) not modelled, ignored: {}", scene_.file.string(), scene_.unsupported.size(), list));
  }
  return std::move(scene_);
}

void X3dReader::unsupported(pugi::xml_node original, std::string_view extra, Slot slot) {
  if (original == root_) scene_.root_known = false;
  const pugi::xml_node n = source_.resolve_use(original);
  std::string def = n.attribute("DEF").as_string();
  std::string entry = def.empty() ? std::string(n.name()) : fmt::format("{} '{}'", n.name(), def);
  if (std::string_view(n.name()) == "ProtoInstance") entry += fmt::format(" '{}'", n.attribute("name").as_string());
  if (!extra.empty()) entry += fmt::format(" {}", extra);
  const fs::path& file = source_.doc_of(original).file;
  entry = file == scene_.file
              ? fmt::format("{} (line {})", entry, source_.line_of(original))
              : fmt::format("{} ({} line {})", entry, file.filename().string(), source_.line_of(original));
  const std::string_view type = n.name();
  if (slot == Slot::kOther && (type.ends_with("Effect") || type.ends_with("Deformer"))) slot = Slot::kHaptic;
  if (slot == Slot::kGeometry) scene_.unsupported_geometry.push_back(entry);
  if (slot == Slot::kHaptic) scene_.unsupported_haptic.push_back(entry);
  scene_.unsupported.push_back(std::move(entry));
}

bool X3dReader::is_group(std::string_view t) {
  return t == "X3D" || t == "Scene" || t == "Group" || t == "StaticGroup" || t == "HapticLayeredGroup" ||
         t == "Collision" || t == "Billboard" || t == "Anchor";
}

bool X3dReader::is_geometry(std::string_view t) {
  return t == "Sphere" || t == "Box" || t == "Cylinder" || t == "Cone" || t == "IndexedTriangleSet" ||
         t == "IndexedFaceSet" || t == "Rectangle2D" || t == "Disk2D" || t == "ElevationGrid" || t == "Extrusion" ||
         t == "TriangleSet" || t == "TriangleFanSet" || t == "TriangleStripSet" || t == "IndexedTriangleFanSet" ||
         t == "IndexedTriangleStripSet" || t == "QuadSet" || t == "IndexedQuadSet" || t == "GeometryGroup";
}

bool X3dReader::is_child(pugi::xml_node c) {
  if (c.type() != pugi::node_element) return false;
  const std::string_view t = c.name();
  const std::string_view field = c.attribute("containerField").as_string();
  return t != "IS" && !t.starts_with("Metadata") && field != "metadata" && field != "proxy";
}

void X3dReader::visit_children(pugi::xml_node n, const Mat4& X) {
  for (pugi::xml_node c : n.children())
    if (is_child(c)) visit(c, X);
}

pugi::xml_node X3dReader::nth_child(pugi::xml_node n, std::int64_t i) {
  for (pugi::xml_node c : n.children()) {
    if (!is_child(c)) continue;
    if (i-- == 0) return c;
  }
  return {};
}

void X3dReader::visit(pugi::xml_node original, const Mat4& X) {
  // USE copies subtrees: a chain of nodes each USE'd twice by the next doubles the tree at
  // every link (2^40 nodes from 40 lines). Bounded, so such a file is refused, not a hang.
  if (++visited_ > kMaxVisitedNodes) {
    source_.fail(original, ErrorCode::kParse,
                 fmt::format("the scene expands to more than {} nodes through USE", kMaxVisitedNodes));
  }
  const std::string_view tag = original.name();
  if (tag == "head" || tag == "meta" || tag == "component" || tag == "unit" || tag == "ProtoDeclare" ||
      tag == "ExternProtoDeclare") {
    return;  // PROTO declarations: read where they are instantiated
  }
  const pugi::xml_node n = source_.resolve(original);
  const std::string_view t = n.name();
  if (t == "HapticLayeredGroup") {
    // H3D: each child is a haptic layer, rendered with its own proxy (forces summed).
    const int outer = layer_;
    int index = 0;
    for (pugi::xml_node c : n.children()) {
      if (!is_child(c)) continue;
      layer_ = index++;
      visit(c, X);
    }
    layer_ = outer;
  } else if (is_group(t)) {
    visit_children(n, X);
  } else if (t == "ToggleGroup") {
    // H3D ToggleGroup: graphicsOn / hapticsOn switch its children's drawing and feel.
    // Haptics off: its shapes are seen only, its force effects not rendered; graphics off
    // as well: nothing of it is shown either.
    const bool haptics_on = source_.boolean(n, "hapticsOn", true);
    const bool graphics_on = source_.boolean(n, "graphicsOn", true);
    if (!haptics_on && !graphics_on) return;
    if (!haptics_on) {
      ++haptics_off_;
      visit_children(n, X);
      --haptics_off_;
    } else {
      visit_children(n, X);
    }
  } else if (t == "DynamicTransform") {
    // H3D DynamicTransform: a rigid body moved by its own dynamics (mass, momentum, force).
    // HoF places its children where it starts — `position`, `orientation` — and says once
    // that it does not move them.
    const Vec3 p = source_.vec3(n, "position", Vec3::Zero());
    const Mat4 R = axis_angle(source_.numbers(n, "orientation", 4, {0, 0, 1, 0}));
    if (!dynamic_transform_noted_) {
      source_.warn(n,
                   "DynamicTransform: its children are placed where it starts (position, orientation); its motion "
                   "(mass, momentum, force, torque) is not simulated");
      dynamic_transform_noted_ = true;
    }
    visit_children(n, X * translation(p) * R);
  } else if (t == "Switch") {
    // 19775-1, Switch: only the child whichChoice names is traversed; −1 (the default) or an
    // index past the children: none.
    if (const pugi::xml_node c = nth_child(n, source_.integer(n, "whichChoice", -1));
        c && source_.integer(n, "whichChoice", -1) >= 0)
      visit(c, X);
  } else if (t == "LOD") {
    // 19775-1, LOD: level 0, the most detailed, is shown nearest the viewer; HoF has no
    // viewer distance, and takes that one.
    if (const pugi::xml_node c = nth_child(n, 0)) visit(c, X);
  } else if (t == "Inline") {
    inline_file(n, X);
  } else if (t == "Transform") {
    visit_children(n, X * transform_matrix(n));
  } else if (t == "MatrixTransform") {
    const auto m = source_.numbers(n, "matrix", 16, {1, 0, 0, 0, 0, 1, 0, 0, 0, 0, 1, 0, 0, 0, 0, 1});
    visit_children(n, X * Eigen::Map<const Eigen::Matrix<double, 4, 4, Eigen::RowMajor>>(m.data()));
  } else if (t == "FitToBoxTransform") {
    fit_to_box(n, X);
  } else if (t == "Shape" || t == "DeformableShape") {
    shape(original, n, X);
  } else if (t == "DeviceInfo") {
    device_info(n);
  } else if (t == "GlobalSettings") {
    global_settings(n);
  } else if (haptics_off_ > 0 && (t.ends_with("Effect") || t == "ForceField")) {
    source_.warn(n, fmt::format("{}: under a ToggleGroup with hapticsOn false, not rendered", t));
    ++scene_.effects_switched_off;
  } else if (t == "SpringEffect") {
    haptics::SpringEffect s;
    s.position_m = (X * source_.vec3(n, "position", Vec3::Zero()).homogeneous()).head<3>();
    s.spring_constant_n_per_m = source_.number(n, "springConstant", 100.0);
    s.start_distance_m = source_.number(n, "startDistance", 0.01);
    s.escape_distance_m = source_.number(n, "escapeDistance", 0.01);
    s.damping_n_s_per_m = source_.number(n, "damping", 0.0);
    scene_.force_effects.springs.push_back(s);
  } else if (t == "ViscosityEffect") {
    haptics::ViscosityEffect v;
    v.viscosity_pa_s = source_.number(n, "viscosity", 0.01);
    v.radius_m = source_.number(n, "radius", 0.0025);
    v.damping_factor = source_.number(n, "dampingFactor", 0.5);
    v.enabled = source_.boolean(n, "enabled", true);
    scene_.force_effects.viscosities.push_back(v);
  } else if (t == "ForceField") {
    // The force keeps its magnitude and turns with the enclosing transforms.
    const Vec3 f = source_.vec3(n, "force", Vec3::Zero());
    const Vec3 d = X.topLeftCorner<3, 3>() * f;
    scene_.force_effects.constants.push_back({d.norm() > 0.0 ? Vec3(d.normalized() * f.norm()) : Vec3::Zero()});
  } else if (t == "MagneticGeometryEffect") {
    magnetic_geometry_effect(n, X);
  } else if (t == "PositionFunctionEffect" || t == "TimeFunctionEffect") {
    function_effect(n);
  } else if (t == "RotationalSpringEffect") {
    rotational_spring_effect(n);
  } else if (t == "Viewpoint") {
    X3dViewpoint v;
    v.position = source_.vec3(n, "position", v.position);
    const auto o = source_.numbers(n, "orientation", 4, {0, 0, 1, 0});
    std::copy(o.begin(), o.end(), v.orientation.begin());
    v.field_of_view_rad = source_.number(n, "fieldOfView", v.field_of_view_rad);
    scene_.viewpoints.push_back(v);
  } else {
    unsupported(original);
  }
}

void X3dReader::inline_file(pugi::xml_node n, const Mat4& X) {
  if (!source_.boolean(n, "load", true)) return;
  const std::vector<std::string> urls = x3d_mf_string(n.attribute("url").as_string());
  const fs::path folder = source_.doc_of(n).file.parent_path();
  for (const std::string& url : urls) {
    if (x3d_is_remote(url)) continue;
    const fs::path path = folder / url.substr(0, url.find('#'));
    if (!fs::is_regular_file(path)) continue;
    if (is_classic_vrml(path)) {
      // H3DViewer reads the classic encoding too; HoF reads X3D's XML only: the Inline is
      // not shown, the scene still opens.
      source_.warn(n, fmt::format("Inline url '{}': the classic VRML encoding (.wrl, #VRML / #X3D) is not read: "
                                  "not shown",
                                  url));
      return;
    }
    const fs::path key = source_.weakly_canonical(path);
    if (std::ranges::find(inline_stack_, key) != inline_stack_.end()) {
      std::string chain;
      for (const fs::path& p : inline_stack_) chain += p.filename().string() + " → ";
      source_.fail(
          n, ErrorCode::kParse,
          fmt::format("Inline url '{}' includes a file that includes it: {}{}", url, chain, path.filename().string()));
    }
    if (static_cast<int>(inline_stack_.size()) > kMaxInlineDepth)
      source_.fail(n, ErrorCode::kParse,
                   fmt::format("Inline url '{}': Inlines nest deeper than {}", url, kMaxInlineDepth));
    const X3dDocument& d = source_.load(n, path);
    if (!d.xml.document_element()) return;
    inline_stack_.push_back(key);
    visit(d.xml.document_element(), X);
    inline_stack_.pop_back();
    return;
  }
  source_.warn(n, urls.empty() ? std::string("Inline without a url")
                               : fmt::format("Inline: none of its urls is a file beside the scene ({}): not shown",
                                             n.attribute("url").as_string()));
}

bool X3dReader::is_classic_vrml(const fs::path& path) {
  const std::string ext = path.extension().string();
  if (ext == ".wrl" || ext == ".wrz" || ext == ".x3dv" || ext == ".x3dvz") return true;
  std::ifstream in(path, std::ios::binary);
  char head[5] = {};
  in.read(head, 5);
  const std::string_view h(head, static_cast<std::size_t>(in.gcount()));
  return h.starts_with("#VRML") || h.starts_with("#X3D");
}

Mat4 X3dReader::transform_matrix(pugi::xml_node n) const {
  const Vec3 t = source_.vec3(n, "translation", Vec3::Zero());
  const Vec3 c = source_.vec3(n, "center", Vec3::Zero());
  const Vec3 s = source_.vec3(n, "scale", Vec3::Ones());
  const Mat4 R = axis_angle(source_.numbers(n, "rotation", 4, {0, 0, 1, 0}));
  const Mat4 SR = axis_angle(source_.numbers(n, "scaleOrientation", 4, {0, 0, 1, 0}));
  Mat4 S = Mat4::Identity();
  S.diagonal().head<3>() = s;
  return translation(t) * translation(c) * R * SR * S * SR.transpose() * translation(-c);
}

void X3dReader::fit_to_box(pugi::xml_node n, const Mat4& X) {
  const Vec3 box_size = source_.vec3(n, "boxSize", Vec3::Constant(0.1));
  const Vec3 box_center = source_.vec3(n, "boxCenter", Vec3::Zero());
  const bool uniform = source_.boolean(n, "uniformScalingOnly", false);
  const bool active = source_.boolean(n, "active", true);
  const std::size_t first_shape = scene_.shapes.size();
  const std::size_t first_spring = scene_.force_effects.springs.size();
  const std::size_t first_constant = scene_.force_effects.constants.size();
  const std::size_t first_magnet = scene_.force_effects.magnets.size();
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
  for (std::size_t i = first_magnet; i < scene_.force_effects.magnets.size(); ++i) {
    auto moved = std::make_shared<mesh::TriMesh>(*scene_.force_effects.magnets[i].surface);
    transform_mesh(*moved, XM);
    scene_.force_effects.magnets[i].surface = std::move(moved);
  }
  for (std::size_t i = first_constant; i < scene_.force_effects.constants.size(); ++i) {
    Vec3& f = scene_.force_effects.constants[i].force_n;
    const Vec3 d = XM.topLeftCorner<3, 3>() * f;
    if (d.norm() > 0.0) f = d.normalized() * f.norm();
  }
}

void X3dReader::shape(pugi::xml_node original, pugi::xml_node n, const Mat4& X) {
  X3dShape s;
  s.def = n.attribute("DEF").as_string();
  s.line = source_.line_of(original);
  s.deformable = std::string_view(n.name()) == "DeformableShape";
  for (pugi::xml_node c_orig : n.children()) {
    if (!is_child(c_orig)) continue;
    const pugi::xml_node c = source_.resolve(c_orig);
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
      // A Shape's children are its appearance and its geometry (a node's default
      // containerField): what is not an Appearance sits in the geometry slot.
      const bool in_geometry_slot = field.empty() || field == "geometry" || field == "hapticGeometry";
      unsupported(c_orig, {}, in_geometry_slot ? Slot::kGeometry : Slot::kOther);
    }
  }
  if (s.deformable && s.mesh_W.triangles.empty() && !s.haptic_mesh_W.triangles.empty()) {
    // A DeformableShape with only a hapticGeometry: that geometry is what is felt (H3D
    // renders it), so it is the one simulated.
    s.geometry_type = s.haptic_geometry_type;
    s.mesh_W = std::move(s.haptic_mesh_W);
    s.haptic_mesh_W = {};
  }
  if (s.touchable && haptics_off_ > 0) {
    source_.warn(original, "Shape under a ToggleGroup with hapticsOn false: seen, not felt");
    s.touchable = false;
    s.haptics_switched_off = true;
  }
  warn_if_zero_size(original, s);
  s.layer = layer_;
  scene_.shapes.push_back(std::move(s));
}

void X3dReader::warn_if_zero_size(pugi::xml_node original, const X3dShape& s) {
  const mesh::TriMesh& m = !s.haptic_mesh_W.triangles.empty() ? s.haptic_mesh_W : s.mesh_W;
  if (m.triangles.empty()) return;
  Eigen::AlignedBox3d bound;
  for (const Vec3& v : m.vertices) bound.extend(v);
  const Vec3 size = bound.sizes();
  int flat = 0;
  for (int k = 0; k < 3; ++k) flat += size[k] <= 1e-12 ? 1 : 0;
  if (flat >= 2) {
    source_.warn(original,
                 fmt::format("{} has zero size ({} x {} x {} m): nothing to see or touch",
                             s.geometry_type.empty() ? "Shape" : s.geometry_type, size.x(), size.y(), size.z()));
  }
}

mesh::TriMesh X3dReader::geometry(pugi::xml_node n, bool& solid, X3dShape& s) {
  const std::string_view t = n.name();
  // 19775-1: the Geometry2D nodes are two-sided by default (solid FALSE), the others solid.
  solid = source_.boolean(n, "solid", !(t == "Rectangle2D" || t == "Disk2D"));
  mesh::TriMesh m;
  pugi::xml_node coord;
  std::vector<pugi::xml_node> members;  // a GeometryGroup's geometries
  for (pugi::xml_node c_orig : n.children()) {
    if (!is_child(c_orig)) continue;
    const pugi::xml_node c = source_.resolve(c_orig);
    const std::string_view ct = c.name();
    if (ct == "Coordinate" || ct == "CoordinateDouble")
      coord = c;
    else if (ct == "HapticsOptions") {
      if (!s.haptics_options) s.haptics_options = haptics_options(c);
    } else if (ct == "GeometryBoundTreeOptions") {
      if (!s.bound_tree_options) s.bound_tree_options = bound_tree_options(c);
    } else if (t == "GeometryGroup" && is_geometry(ct))
      members.push_back(c);
    else
      unsupported(c_orig);
  }
  if (t == "Sphere") {
    m = detail::make_sphere(source_.number(n, "radius", 1.0));
  } else if (t == "Box") {
    m = detail::make_box(source_.vec3(n, "size", Vec3::Constant(2.0)));
  } else if (t == "Cylinder") {
    const double r = source_.number(n, "radius", 1.0);
    m = detail::make_round(r, r, source_.number(n, "height", 2.0), source_.boolean(n, "side", true),
                           source_.boolean(n, "bottom", true), source_.boolean(n, "top", true));
  } else if (t == "Cone") {
    m = detail::make_round(source_.number(n, "bottomRadius", 1.0), 0.0, source_.number(n, "height", 2.0),
                           source_.boolean(n, "side", true), source_.boolean(n, "bottom", true), false);
  } else if (t == "Rectangle2D") {
    const auto sz = source_.numbers(n, "size", 2, {2.0, 2.0});
    m = detail::make_rectangle(sz[0], sz[1]);
  } else if (t == "Disk2D") {
    m = detail::make_disk(source_.number(n, "innerRadius", 0.0), source_.number(n, "outerRadius", 1.0));
  } else if (t == "ElevationGrid") {
    m = elevation_grid(n);
  } else if (t == "Extrusion") {
    m = extrusion(n);
  } else if (t == "GeometryGroup") {
    // H3D GeometryGroup: several geometries drawn and felt as one; two-sided if any member is.
    for (pugi::xml_node g : members) {
      bool member_solid = true;
      mesh::TriMesh part = geometry(g, member_solid, s);
      solid = solid && member_solid;
      const auto offset = static_cast<mesh::NodeIndex>(m.vertices.size());
      m.vertices.insert(m.vertices.end(), part.vertices.begin(), part.vertices.end());
      for (mesh::Tri tri : part.triangles) m.triangles.push_back({tri[0] + offset, tri[1] + offset, tri[2] + offset});
    }
  } else {
    composed_set(n, coord, m);
  }
  return m;
}

mesh::TriMesh X3dReader::elevation_grid(pugi::xml_node n) {
  const std::int64_t nx = source_.integer(n, "xDimension", 0);
  const std::int64_t nz = source_.integer(n, "zDimension", 0);
  const auto height = source_.numbers(n, "height");
  if (nx < 0 || nz < 0 || nx > 100000 || nz > 100000)
    source_.fail(n, ErrorCode::kParse,
                 fmt::format("<ElevationGrid>: xDimension {} and zDimension {} must be in [0, 100000]", nx, nz));
  if (static_cast<std::int64_t>(height.size()) < nx * nz)
    source_.fail(n, ErrorCode::kInvalidMesh,
                 fmt::format("<ElevationGrid>: {} heights for a {} × {} grid", height.size(), nx, nz));
  mesh::TriMesh m = detail::make_elevation_grid(nx, nz, source_.number(n, "xSpacing", 1.0),
                                                source_.number(n, "zSpacing", 1.0), height);
  if (!source_.boolean(n, "ccw", true)) flip(m);
  return m;
}

mesh::TriMesh X3dReader::extrusion(pugi::xml_node n) {
  const auto cs = source_.tuples(n, "crossSection", 2, {1, 1, 1, -1, -1, -1, -1, 1, 1, 1});
  const auto sp = source_.tuples(n, "spine", 3, {0, 0, 0, 0, 1, 0});
  const auto sc = source_.tuples(n, "scale", 2, {1, 1});
  const auto orient = source_.tuples(n, "orientation", 4, {0, 0, 1, 0});
  std::vector<detail::Vec2> cross_section, scale;
  std::vector<Vec3> spine;
  std::vector<detail::Vec4> orientation;
  for (std::size_t i = 0; i + 1 < cs.size(); i += 2) cross_section.emplace_back(cs[i], cs[i + 1]);
  for (std::size_t i = 0; i + 2 < sp.size(); i += 3) spine.emplace_back(sp[i], sp[i + 1], sp[i + 2]);
  for (std::size_t i = 0; i + 1 < sc.size(); i += 2) scale.emplace_back(sc[i], sc[i + 1]);
  for (std::size_t i = 0; i + 3 < orient.size(); i += 4)
    orientation.emplace_back(orient[i], orient[i + 1], orient[i + 2], orient[i + 3]);
  if (scale.empty()) scale.emplace_back(1.0, 1.0);
  if (orientation.empty()) orientation.emplace_back(0.0, 0.0, 1.0, 0.0);
  if (cross_section.size() < 2 || spine.size() < 2) {
    source_.warn(n, fmt::format("Extrusion: {} cross-section and {} spine points: no surface", cross_section.size(),
                                spine.size()));
    return {};
  }
  mesh::TriMesh m = detail::make_extrusion(cross_section, spine, scale, orientation,
                                           source_.boolean(n, "beginCap", true), source_.boolean(n, "endCap", true));
  if (!source_.boolean(n, "ccw", true)) flip(m);
  return m;
}

void X3dReader::flip(mesh::TriMesh& m) {
  for (auto& t : m.triangles) std::swap(t[1], t[2]);
}

std::vector<Vec3> X3dReader::points(pugi::xml_node coord) {
  std::vector<Vec3> out;
  const auto p = source_.numbers(coord, "point");
  if (p.size() % 3 != 0)
    source_.fail(coord, ErrorCode::kParse,
                 fmt::format("<{}> field point: {} numbers, not a multiple of 3", coord.name(), p.size()));
  for (std::size_t i = 0; i + 2 < p.size(); i += 3) out.emplace_back(p[i], p[i + 1], p[i + 2]);
  const std::string_view def = coord.attribute("DEF").as_string();
  if (!out.empty() || def.empty()) return out;
  const X3dDocument& d = source_.doc_of(coord);
  for (const pugi::xml_node route : d.routes) {
    const std::string_view to_field = route.attribute("toField").as_string();
    if (def != route.attribute("toNode").as_string() || (to_field != "point" && to_field != "set_point")) continue;
    const std::string_view from = route.attribute("fromNode").as_string();
    pugi::xml_node source;
    if (const auto it = d.defs.find(from); it != d.defs.end()) {
      for (pugi::xml_node candidate : it->second)
        if (std::string_view(candidate.name()) == "CoordinateInterpolator") source = candidate;
      if (!source && !it->second.empty()) source = it->second.back();
    }
    if (source && std::string_view(source.name()) == "CoordinateInterpolator") {
      const auto keys = source_.numbers(source, "key");
      const auto values = source_.tuples(source, "keyValue", 3, {});
      const std::size_t per_key = keys.empty() ? 0 : values.size() / 3 / keys.size();
      for (std::size_t i = 0; i < per_key; ++i) out.emplace_back(values[3 * i], values[3 * i + 1], values[3 * i + 2]);
      source_.warn(
          coord, fmt::format("Coordinate '{}' has no points: a ROUTE (line {}) animates it from CoordinateInterpolator "
                             "'{}' (line {}); drawn still, at its first key (HoF does not animate)",
                             def, source_.line_of(route), from, source_.line_of(source)));
    } else {
      source_.warn(coord,
                   fmt::format("Coordinate '{}' has no points: they come through a ROUTE (line {}) from {} '{}', which "
                               "HoF does not run; the shape has no surface",
                               def, source_.line_of(route), source ? source.name() : "an unknown node", from));
    }
    return out;
  }
  return out;
}

void X3dReader::composed_set(pugi::xml_node n, pugi::xml_node coord, mesh::TriMesh& m) {
  using detail::VertexGrouping;
  const std::string_view t = n.name();
  if (coord) m.vertices = points(coord);
  const bool indexed = t.starts_with("Indexed");
  const VertexGrouping grouping = t.ends_with("TriangleSet")      ? VertexGrouping::kTriangles
                                  : t.ends_with("QuadSet")        ? VertexGrouping::kQuads
                                  : t.ends_with("TriangleFanSet") ? VertexGrouping::kFans
                                  : t.ends_with("StripSet")       ? VertexGrouping::kStrips
                                                                  : VertexGrouping::kPolygons;
  const bool separated = grouping != VertexGrouping::kTriangles && grouping != VertexGrouping::kQuads;
  std::vector<std::vector<mesh::NodeIndex>> runs(1);
  const std::int64_t count = static_cast<std::int64_t>(m.vertices.size());
  if (indexed) {
    // Fans, strips and faces end at −1 (the last one may omit it); triangles and quads run on.
    for (std::int64_t i : source_.integers(n, t == "IndexedFaceSet" ? "coordIndex" : "index")) {
      if (i == -1 && separated) {
        runs.emplace_back();
        continue;
      }
      if (i < 0 || i >= count)
        source_.fail(n, ErrorCode::kInvalidMesh,
                     fmt::format("<{}>: index {} out of range (the Coordinate has {} points)", t, i, count));
      runs.back().push_back(static_cast<mesh::NodeIndex>(i));
    }
  } else if (separated) {
    // fanCount / stripCount: how many of the points, in order, each fan or strip takes.
    const char* field = grouping == VertexGrouping::kFans ? "fanCount" : "stripCount";
    std::int64_t next = 0;
    runs.clear();
    for (std::int64_t c : source_.integers(n, field)) {
      if (c < 0 || next + c > count) {
        source_.warn(n, fmt::format("{}: {} {} past the {} points: the rest ignored", t, field, c, count));
        break;
      }
      runs.emplace_back();
      for (std::int64_t k = 0; k < c; ++k) runs.back().push_back(static_cast<mesh::NodeIndex>(next++));
    }
  } else {
    for (std::int64_t i = 0; i < count; ++i) runs.back().push_back(static_cast<mesh::NodeIndex>(i));
  }
  const std::size_t left_out = detail::append_grouped(m.triangles, grouping, runs);
  if (left_out > 0) {
    source_.warn(
        n, fmt::format("{}: {} {} left over (not a whole {}): ignored", t, left_out, indexed ? "indices" : "points",
                       grouping == VertexGrouping::kQuads       ? "quad"
                       : grouping == VertexGrouping::kTriangles ? "triangle"
                                                                : "triangle (fewer than 3)"));
  }
  if (!source_.boolean(n, "ccw", true)) flip(m);
}

}  // namespace detail

Expected<X3dScene> read_x3d_scene(const std::filesystem::path& path) {
  std::ifstream in(path, std::ios::binary);
  if (!in) return make_error(ErrorCode::kIo, "cannot open X3D file", path.string());
  std::ostringstream buffer;
  buffer << in.rdbuf();
  try {
    detail::X3dReader reader(path);
    return reader.run(buffer.str());
  } catch (const detail::X3dParseFailure& f) {
    return std::unexpected(f.error);
  }
}

}  // namespace hof::scene
