// The X3D reader's haptic nodes (H3D API): an Appearance's surface and what HoF renders for
// each kind, the force effects beyond springs, viscosity and constant forces, the geometry's
// haptic and bound-tree options, GlobalSettings and DeviceInfo. Field meanings and defaults
// follow ../shared/reference/h3d-nodes.md, cited per node.

#include <algorithm>
#include <memory>

#include <fmt/format.h>

#include "hof/scene/detail/x3d_reader.h"

namespace hof::scene::detail {

using haptics::SurfaceKind;

bool X3dReader::is_surface(std::string_view t) {
  return t == "SmoothSurface" || t == "FrictionalSurface" || t == "MagneticSurface" || t == "OpenHapticsSurface" ||
         t == "DepthMapSurface" || t == "HapticTexturesSurface";
}

void X3dReader::appearance(pugi::xml_node n, X3dShape& s) {
  for (pugi::xml_node c_orig : n.children()) {
    if (!is_child(c_orig)) continue;
    const pugi::xml_node c = source_.resolve(c_orig);
    const std::string_view t = c.name();
    if (t == "Material" || t == "TwoSidedMaterial") {
      s.diffuse_color = source_.vec3(c, "diffuseColor", s.diffuse_color);
      s.transparency = std::clamp(c.attribute("transparency").as_double(0.0), 0.0, 1.0);
      s.has_material = true;
    } else if (is_surface(t)) {
      s.touchable = true;
      s.surface_type = t;
      s.surface = surface(c);
    } else if (t == "MultiDeviceSurface") {
      // One surface per device index, the last repeating (h3d-nodes.md): HoF drives one
      // device, index 0, which feels the first.
      pugi::xml_node first;
      for (pugi::xml_node m : c.children()) {
        if (!is_child(m)) continue;
        const pugi::xml_node r = source_.resolve(m);
        if (!first && is_surface(r.name()))
          first = r;
        else
          unsupported(m);
      }
      if (first) {
        s.touchable = true;
        s.surface_type = first.name();
        s.surface = surface(first);
      }
    } else {
      const std::string_view field = c_orig.attribute("containerField").as_string();
      const bool haptic = field == "surface" || t.ends_with("Surface");
      unsupported(c_orig, {}, haptic ? Slot::kHaptic : Slot::kOther);
    }
  }
}

haptics::SurfaceMaterial X3dReader::surface(pugi::xml_node n) {
  const std::string_view t = n.name();
  haptics::SurfaceMaterial m;
  // OpenHapticsSurface is magnetic only when its `magnetic` field says so (default false).
  const bool magnetic = t == "MagneticSurface" || (t == "OpenHapticsSurface" && source_.boolean(n, "magnetic", false));
  m.kind = t == "SmoothSurface" ? SurfaceKind::kSmooth : magnetic ? SurfaceKind::kMagnetic : SurfaceKind::kFrictional;
  m.stiffness = source_.number(n, "stiffness", 0.5);
  m.damping_n_s_per_m = source_.number(n, "damping", 0.0);
  m.use_relative_values = source_.boolean(n, "useRelativeValues", true);
  if (m.kind == SurfaceKind::kSmooth) {
    m.static_friction = 0.0;  // HAPI::FrictionSurface(k, d, 0, 0)
    m.dynamic_friction = 0.0;
  } else {
    m.static_friction = source_.number(n, "staticFriction", 0.1);
    m.dynamic_friction = source_.number(n, "dynamicFriction", 0.4);
  }
  if (magnetic) m.snap_distance_m = source_.number(n, "snapDistance", 0.01);
  // What HoF renders in place of H3D's surfaces it does not have, said once per type.
  if (t == "OpenHapticsSurface" || t == "DepthMapSurface" || t == "HapticTexturesSurface") {
    const std::string_view as = t == "OpenHapticsSurface"
                                    ? "HoF's frictional (or, with magnetic true, magnetic) surface "
                                      "with its stiffness, damping and friction (HLAPI's own "
                                      "rendering is not modelled)"
                                : t == "DepthMapSurface" ? "a frictional surface: its depth map is not modelled"
                                                         : "a frictional surface: its texture maps are not modelled";
    if (approximated_.insert(std::string(t)).second) source_.warn(n, fmt::format("{}: rendered as {}", t, as));
  }
  for (pugi::xml_node c : n.children())  // texture maps and the like
    if (is_child(c)) unsupported(c);
  return m;
}

void X3dReader::magnetic_geometry_effect(pugi::xml_node n, const Mat4& X) {
  haptics::MagneticGeometryEffect e;
  e.enabled = source_.boolean(n, "enabled", true);
  e.start_distance_m = source_.number(n, "startDistance", 0.01);
  e.escape_distance_m = source_.number(n, "escapeDistance", 0.01);
  e.spring_constant_n_per_m = source_.number(n, "springConstant", 100.0);
  X3dShape scratch;
  auto surface = std::make_shared<mesh::TriMesh>();
  for (pugi::xml_node c_orig : n.children()) {
    if (!is_child(c_orig)) continue;
    const pugi::xml_node c = source_.resolve(c_orig);
    if (!is_geometry(c.name())) {
      unsupported(c_orig);
      continue;
    }
    bool solid = true;
    *surface = geometry(c, solid, scratch);
    transform_mesh(*surface, X);
    break;  // an SFNode: the first geometry
  }
  if (surface->triangles.empty()) {
    source_.warn(n, "MagneticGeometryEffect without a geometry (or with an empty one): no force");
    return;
  }
  e.surface = std::move(surface);
  scene_.force_effects.magnets.push_back(std::move(e));
}

void X3dReader::function_effect(pugi::xml_node n) {
  const bool of_time = std::string_view(n.name()) == "TimeFunctionEffect";
  std::array<std::optional<haptics::FunctionExpression>, 3> f;
  const std::array<std::string_view, 3> fields{"xFunction", "yFunction", "zFunction"};
  for (pugi::xml_node c_orig : n.children()) {
    if (!is_child(c_orig)) continue;
    const pugi::xml_node c = source_.resolve(c_orig);
    const std::string_view field = c_orig.attribute("containerField").as_string();
    const auto slot = std::ranges::find(fields, field);
    if (std::string_view(c.name()) != "GeneralFunction" || slot == fields.end()) {
      unsupported(c_orig);
      continue;
    }
    std::vector<std::string> params;
    for (std::string_view p : x3d_tokens(c.attribute("params").as_string())) params.emplace_back(p);
    const std::size_t wanted = of_time ? 1 : 3;
    if (params.size() != wanted) {
      // H3D ignores the effect then (it prints a warning): so does HoF.
      source_.warn(c, fmt::format("{}: GeneralFunction params '{}' must name {} variable(s): the effect is ignored",
                                  n.name(), c.attribute("params").as_string(), wanted));
      return;
    }
    auto expression = haptics::FunctionExpression::make(c.attribute("function").as_string(), params);
    if (!expression)
      source_.fail(c, ErrorCode::kParse, fmt::format("<GeneralFunction> function: {}", expression.error().message));
    f[static_cast<std::size_t>(slot - fields.begin())] = *expression;
  }
  if (!f[0] || !f[1] || !f[2]) {
    source_.warn(
        n,
        fmt::format("{}: xFunction, yFunction and zFunction are all needed (H3D ignores the effect otherwise): ignored",
                    n.name()));
    return;
  }
  if (of_time)
    scene_.force_effects.time_functions.push_back({*f[0], *f[1], *f[2]});
  else
    scene_.force_effects.position_functions.push_back({*f[0], *f[1], *f[2]});
}

void X3dReader::rotational_spring_effect(pugi::xml_node n) { unsupported(n, "(a torque: HoF renders forces only)"); }

X3dHapticsOptions X3dReader::haptics_options(pugi::xml_node n) const {
  X3dHapticsOptions o;
  o.touchable_face = source_.choice<X3dTouchableFace>(n, "touchableFace",
                                                      {{"AS_GRAPHICS", X3dTouchableFace::kAsGraphics},
                                                       {"FRONT", X3dTouchableFace::kFront},
                                                       {"BACK", X3dTouchableFace::kBack},
                                                       {"FRONT_AND_BACK", X3dTouchableFace::kFrontAndBack}},
                                                      o.touchable_face);
  o.max_distance_m = source_.number(n, "maxDistance", o.max_distance_m);
  o.look_ahead_factor = source_.number(n, "lookAheadFactor", o.look_ahead_factor);
  o.use_bound_tree = source_.boolean(n, "useBoundTree", o.use_bound_tree);
  o.interpolate_force_effects = source_.boolean(n, "interpolateForceEffects", o.interpolate_force_effects);
  o.dynamic_mode = source_.choice<X3dDynamicMode>(n, "dynamicMode",
                                                  {{"TRANSFORM_CHANGED", X3dDynamicMode::kTransformChanged},
                                                   {"ALWAYS", X3dDynamicMode::kAlways},
                                                   {"NEVER", X3dDynamicMode::kNever}},
                                                  o.dynamic_mode);
  return o;
}

X3dBoundTreeOptions X3dReader::bound_tree_options(pugi::xml_node n) const {
  X3dBoundTreeOptions o;
  o.bound_type = source_.choice<X3dBoundType>(
      n, "boundType", {{"AABB", X3dBoundType::kAabb}, {"OBB", X3dBoundType::kObb}, {"SPHERE", X3dBoundType::kSphere}},
      o.bound_type);
  const auto leaf = source_.integers(n, "maxTrianglesInLeaf");
  if (!leaf.empty()) o.max_triangles_in_leaf = static_cast<std::int32_t>(leaf[0]);
  return o;
}

void X3dReader::global_settings(pugi::xml_node n) {
  if (!scene_.global_settings) scene_.global_settings.emplace();
  X3dGlobalSettings& g = *scene_.global_settings;
  for (pugi::xml_node c_orig : n.children()) {
    if (c_orig.type() != pugi::node_element) continue;
    const pugi::xml_node c = source_.resolve(c_orig);
    const std::string_view t = c.name();
    if (t == "HapticsOptions") {
      if (!g.haptics) g.haptics = haptics_options(c);
    } else if (t == "GeometryBoundTreeOptions") {
      if (!g.bound_tree) g.bound_tree = bound_tree_options(c);
    } else if (t == "DebugOptions") {
      if (g.debug) continue;
      X3dDebugOptions d;
      d.draw_bound = source_.boolean(c, "drawBound", false);
      const auto depth = source_.integers(c, "drawBoundTree");
      if (!depth.empty()) d.draw_bound_tree = static_cast<std::int32_t>(depth[0]);
      d.draw_haptic_triangles = source_.boolean(c, "drawHapticTriangles", false);
      d.print_shader_warnings = source_.boolean(c, "printShaderWarnings", false);
      g.debug = d;
    } else {
      unsupported(c_orig);
    }
  }
}

void X3dReader::device_info(pugi::xml_node n) {
  for (pugi::xml_node c_orig : n.children()) {
    if (c_orig.type() != pugi::node_element) continue;
    const pugi::xml_node c = source_.resolve(c_orig);
    if (!ends_with(c.name(), "Device")) {
      unsupported(c_orig);
      continue;
    }
    X3dDevice d;
    d.type = c.name();
    d.def = c.attribute("DEF").as_string();
    d.device_name = source_.string(c, "deviceName", "");
    const auto pc =
        source_.numbers(c, "positionCalibration", 16, {d.position_calibration.begin(), d.position_calibration.end()});
    std::copy(pc.begin(), pc.end(), d.position_calibration.begin());
    const auto oc = source_.numbers(c, "orientationCalibration", 4, {1, 0, 0, 0});
    std::copy(oc.begin(), oc.end(), d.orientation_calibration.begin());
    d.force_limit_n = source_.number(c, "forceLimit", -1.0);
    for (pugi::xml_node r_orig : c.children()) {
      if (r_orig.type() != pugi::node_element) continue;
      const pugi::xml_node r = source_.resolve(r_orig);
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
        renderer.proxy_radius_m = source_.number(r, "proxyRadius", 0.0025);
      }
      d.renderer = renderer;
    }
    scene_.devices.push_back(std::move(d));
  }
}

}  // namespace hof::scene::detail
