// The builder's X3D part: an H3D scene's shapes as rigid or deformable bodies, its force
// effects, device settings and viewpoint; a scene with nothing to touch opens, naming why.

#include <algorithm>

#include <fmt/format.h>
#include <fmt/ranges.h>

#include "hof/scene/detail/world_parts.h"
#include "hof/scene/x3d_scene.h"

namespace hof::scene::detail {

namespace {

// What the shapes came to, for the reason a world has nothing to touch.
struct ShapeCounts {
  bool any_deformable{false};
  std::size_t seen_only{0};                  // shapes without a haptic surface
  std::size_t switched_off{0};               // shapes with one, under a ToggleGroup hapticsOn false
  std::vector<std::string> empty_touchable;  // shapes with a surface and no triangles
};

// A DeformableShape: the thesis' surface model — springs on the triangle edges, uniform
// mass, the open border held (or, for a closed surface, its lowest tenth along y, X3D's
// up) — driven by the mechanics instead of H3D's CoordinateDeformer.
mechanics::ModelConfig deformable_shape_config(const std::string& name, const mesh::TriMesh& geometry,
                                               const X3dDeformableDefaults& d) {
  mechanics::ModelConfig c;
  c.name = name;
  c.positions = geometry.vertices;
  c.triangles = geometry.triangles;
  c.mass.kind = mechanics::MassKind::kUniform;
  c.mass.total_mass_kg = d.total_mass_kg;
  c.gravity_m_per_s2 = Vec3::Zero();
  mechanics::ForceFieldConfig springs;
  springs.name = "springs";
  std::vector<std::int32_t> held = border_nodes(c.triangles);
  springs.mesh_springs = mechanics::MeshSpringConfig{d.spring_stiffness_n_per_m, d.spring_damping_n_s_per_m,
                                                     held.empty() ? 1.0 : d.open_sheet_rest_length_scale};
  c.force_fields.push_back(springs);
  if (held.empty()) {
    double lo = c.positions.front().y(), hi = lo;
    for (const Vec3& p : c.positions) {
      lo = std::min(lo, p.y());
      hi = std::max(hi, p.y());
    }
    for (std::size_t i = 0; i < c.positions.size(); ++i) {
      if (c.positions[i].y() <= lo + 0.1 * (hi - lo)) held.push_back(static_cast<std::int32_t>(i));
    }
  }
  c.fixed.push_back(mechanics::FixedConstraintConfig{"border", held, std::nullopt, false, {true, true, true}});
  c.ode.rayleigh_mass = c.ode.rayleigh_stiffness = d.rayleigh;
  c.linear.iterations = 25;
  c.dt_s = d.dt_s;
  return c;
}

// The shapes: rigid bodies, deformable ones, and the shapes only seen.
Expected<ShapeCounts> add_shapes(World& w, const X3dScene& x3d, const X3dDeformableDefaults& d) {
  ShapeCounts out;
  for (const X3dShape& shape : x3d.shapes) {
    // A rigid shape is felt through its hapticGeometry when it has one (as H3D renders it); a
    // deformable one is simulated on its geometry (the mesh that deforms).
    const mesh::TriMesh& geometry =
        shape.deformable || shape.haptic_mesh_W.triangles.empty() ? shape.mesh_W : shape.haptic_mesh_W;
    if (geometry.triangles.empty()) {
      if (shape.touchable) {
        out.empty_touchable.push_back(fmt::format(
            "{} (line {}, {})", shape.def.empty() ? "Shape" : shape.def, shape.line,
            shape.geometry_type.empty() ? "no geometry HoF draws" : shape.geometry_type + " without triangles"));
      }
      continue;
    }
    if (shape.haptics_switched_off)
      ++out.switched_off;
    else if (!shape.touchable)
      ++out.seen_only;
    const std::string name = unique_name(
        w.bodies, !shape.def.empty()
                      ? shape.def
                      : fmt::format("{}@{}", shape.geometry_type.empty() ? "Shape" : shape.geometry_type, shape.line));
    const Appearance appearance{shape.diffuse_color, shape.transparency};
    if (!shape.touchable) {
      w.visuals.push_back(VisualShape{name, shape.mesh_W, appearance});  // seen, not felt
      continue;
    }
    if (shape.has_material) w.appearances[name] = appearance;
    if (!shape.solid) w.project.touchable_face = collision::TouchableFace::kFrontAndBack;  // X3D solid='false'
    if (!shape.deformable) {
      // A plain Shape: rigid and fixed, as H3D renders it.
      coupling::SessionBody body;
      body.name = name;
      body.surface = geometry;
      body.material = shape.surface;
      body.layer = shape.layer;
      w.bodies.push_back(std::move(body));
      continue;
    }
    // A DeformableShape, simulated.
    out.any_deformable = true;
    auto body = make_deformable(deformable_shape_config(name, geometry, d), std::nullopt, false);
    if (!body) return std::unexpected(body.error());
    body->material = shape.surface;
    body->layer = shape.layer;
    w.bodies.push_back(std::move(*body));
  }
  return out;
}

// The device, renderer, effects and viewpoint of the scene, and what it skipped.
void take_settings(World& w, const X3dScene& x3d, const std::filesystem::path& file) {
  if (!x3d.devices.empty()) {
    const X3dDevice& device = x3d.devices.front();
    w.project.position_calibration = device.position_calibration;
    if (device.renderer && device.renderer->kind) {
      w.project.renderer = *device.renderer->kind;
      w.project.proxy_radius_m = device.renderer->proxy_radius_m;
    }
  }
  w.project.effects = x3d.force_effects;
  if (!x3d.viewpoints.empty()) w.project.graphics.viewpoint_m = x3d.viewpoints.front().position;
  w.skipped = x3d.unsupported;
  w.warnings = x3d.warnings;
  if (x3d.root_element != "X3D" && x3d.root_element != "Scene") {
    w.warnings.insert(w.warnings.begin(),
                      fmt::format("{}:{}: the root element is <{}>, not <X3D>: read as a scene, as H3DViewer does",
                                  file.string(), x3d.root_line, x3d.root_element));
  }
}

// Why a world of no body and no effect has nothing to touch, naming the real cause (shapes
// only seen, a surface on no triangles, haptic nodes not modelled), in one sentence.
std::string nothing_to_touch(const X3dScene& x3d, const ShapeCounts& counts) {
  std::vector<std::string> causes;
  if (counts.seen_only > 0) {
    causes.push_back(fmt::format("{} shape{} only seen (no haptic surface in {} Appearance)", counts.seen_only,
                                 counts.seen_only == 1 ? " is" : "s are", counts.seen_only == 1 ? "its" : "their"));
  }
  if (counts.switched_off > 0) {
    causes.push_back(fmt::format("{} shape{} under a ToggleGroup with hapticsOn false", counts.switched_off,
                                 counts.switched_off == 1 ? " is" : "s are"));
  }
  if (x3d.effects_switched_off > 0) {
    causes.push_back(fmt::format("{} force effect{} under a ToggleGroup with hapticsOn false", x3d.effects_switched_off,
                                 x3d.effects_switched_off == 1 ? " is" : "s are"));
  }
  if (!counts.empty_touchable.empty())
    causes.push_back(fmt::format("a haptic surface on no triangles: {}", fmt::join(counts.empty_touchable, ", ")));
  // Not modelled, and haptic (an Appearance's surface, an effect, a deformer): the likely reason.
  if (!x3d.unsupported_haptic.empty()) {
    causes.push_back(fmt::format("haptic nodes HoF does not model: {}", fmt::join(x3d.unsupported_haptic, ", ")));
  }
  if (x3d.shapes.empty()) causes.push_back("no Shape");
  if (causes.empty()) {
    // Shapes whose geometry HoF does not model (Text, NurbsPatchSurface, ...): those geometries.
    causes.push_back(x3d.unsupported_geometry.empty()
                         ? std::string("no shape has a geometry HoF models")
                         : fmt::format("no shape has a geometry HoF models (not modelled: {})",
                                       fmt::join(x3d.unsupported_geometry, ", ")));
  }
  return fmt::format("nothing to touch: {}{}", fmt::join(causes, "; "),
                     x3d.effects_switched_off > 0 ? "" : ", and no force effect");
}

}  // namespace

Expected<void> add_x3d(World& w, const std::filesystem::path& file) {
  auto x3d = read_x3d_scene(file);
  if (!x3d) return std::unexpected(x3d.error());
  // Open what H3DViewer opens: a file whose root is an X3D node HoF reads — a scene fragment
  // (<Group>, <Transform>), a settings file (<DeviceInfo>, a stylus) — is read as a scene (a
  // settings file then has nothing to touch, and says so). A root that is no X3D node HoF
  // knows (<svg>, <html>) is not an X3D file.
  if (!x3d->root_known) {
    return make_error(ErrorCode::kParse,
                      fmt::format("not an X3D scene: its root element <{}> is not an X3D node (a scene starts with "
                                  "<X3D> or <Scene>)",
                                  x3d->root_element),
                      file.string(), x3d->root_line);
  }
  const X3dDeformableDefaults d;
  auto counts = add_shapes(w, *x3d, d);
  if (!counts) return std::unexpected(counts.error());
  if (counts->any_deformable) {
    w.defaults.push_back(
        fmt::format("DeformableShape springs/stiffness = {} N/m, springs/damping = {} N s/m, "
                    "springs/restLengthScale = {} for an open sheet (a drum skin, border held; a closed "
                    "surface: 1, lowest tenth held), mass = {} kg, rayleigh = {}, dt = {} s, no gravity "
                    "(X3D gives no mechanics)",
                    d.spring_stiffness_n_per_m, d.spring_damping_n_s_per_m, d.open_sheet_rest_length_scale,
                    d.total_mass_kg, d.rayleigh, d.dt_s));
  }
  take_settings(w, *x3d, file);
  if (w.bodies.empty() && x3d->force_effects.empty()) {
    // Open what H3DViewer opens: a scene with nothing to touch is still shown, saying why.
    w.nothing_to_touch = nothing_to_touch(*x3d, *counts);
    w.warnings.push_back(fmt::format("{}: {} (shown, not felt)", file.string(), w.nothing_to_touch));
  }
  return {};
}

}  // namespace hof::scene::detail
