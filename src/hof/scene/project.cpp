#include "hof/scene/project.h"
#include "hof/scene/detail/project_names.h"
#include "hof/mesh/xml_depth.h"

#include "hof/core/file_write.h"

#include "hof/core/text.h"

#include "hof/scene/sofa_scene_edit.h"
#include "hof/scene/x3d_scene.h"

#include <fmt/format.h>

#include <charconv>
#include <fstream>
#include <pugixml.hpp>
#include <sstream>

namespace hof::scene {

namespace detail {

const char* renderer_name(haptics::RendererKind k) {
  switch (k) {
    case haptics::RendererKind::kPenalty: return "PenaltyRenderer";
    case haptics::RendererKind::kGodObject: return "GodObjectRenderer";
    case haptics::RendererKind::kRuspini: return "RuspiniRenderer";
  }
  return "RuspiniRenderer";
}

}  // namespace detail

using detail::renderer_name;

namespace {

// Line of a byte offset in the file text (for error messages).
std::int64_t line_of(const std::string& text, std::ptrdiff_t offset) {
  std::int64_t line = 1;
  for (std::ptrdiff_t i = 0; i < offset && i < static_cast<std::ptrdiff_t>(text.size()); ++i) line += text[static_cast<std::size_t>(i)] == '\n';
  return line;
}

struct ProjectReader {
  const std::string& text;
  std::string file;
  std::optional<Error> error;

  Error at(const pugi::xml_node& node, std::string message) const {
    return Error{ErrorCode::kParse, std::move(message), file, line_of(text, node.offset_debug()), -1};
  }
  bool fail(const pugi::xml_node& node, std::string message) {
    if (!error) error = at(node, std::move(message));
    return false;
  }
  double get(const pugi::xml_node& node, const char* name, double fallback) {
    const pugi::xml_attribute a = node.attribute(name);
    if (!a) return fallback;
    double v = 0.0;
    const std::string s = a.value();
    const auto r = std::from_chars(s.data(), s.data() + s.size(), v);
    if (r.ec != std::errc() || r.ptr != s.data() + s.size() || !std::isfinite(v)) {
      fail(node, fmt::format("<{}> {}=\"{}\" is not a number", node.name(), name, s));
      return fallback;
    }
    return v;
  }
  /// A whole number in [lo, hi] (checked before any conversion to int: casting an
  /// out-of-range double is undefined behaviour).
  int get_count(const pugi::xml_node& node, const char* name, int fallback, int lo, int hi) {
    const double v = get(node, name, fallback);
    if (!(v >= lo && v <= hi && v == std::floor(v))) {
      fail(node, fmt::format("<{}> {}=\"{}\" must be a whole number from {} to {}", node.name(), name,
                             node.attribute(name).value(), lo, hi));
      return fallback;
    }
    return static_cast<int>(v);
  }
  bool get_bool(const pugi::xml_node& node, const char* name, bool fallback) {
    const pugi::xml_attribute a = node.attribute(name);
    if (!a) return fallback;
    const std::string s = a.value();
    if (s == "true" || s == "1") return true;
    if (s == "false" || s == "0") return false;
    fail(node, fmt::format("<{}> {}=\"{}\" must be true or false", node.name(), name, s));
    return fallback;
  }
  Vec3 get_vec(const pugi::xml_node& node, const char* name, const Vec3& fallback) {
    const pugi::xml_attribute a = node.attribute(name);
    if (!a) return fallback;
    std::istringstream in(a.value());
    Vec3 v;
    if (!(in >> v.x() >> v.y() >> v.z()) || !v.allFinite()) {
      fail(node, fmt::format("<{}> {}=\"{}\" must be three numbers", node.name(), name, a.value()));
      return fallback;
    }
    return v;
  }
};

haptics::SurfaceMaterial read_surface(ProjectReader& r, const pugi::xml_node& s) {
  haptics::SurfaceMaterial m;
  const std::string type = s.attribute("type").as_string("SmoothSurface");
  if (type == "SmoothSurface") m.kind = haptics::SurfaceKind::kSmooth;
  else if (type == "FrictionalSurface") m.kind = haptics::SurfaceKind::kFrictional;
  else if (type == "MagneticSurface") m.kind = haptics::SurfaceKind::kMagnetic;
  else if (type == "ZeroForceSurface") m.kind = haptics::SurfaceKind::kZeroForce;
  else r.fail(s, fmt::format("unknown surface type \"{}\"", type));
  m.stiffness = r.get(s, "stiffness", m.stiffness);
  m.damping_n_s_per_m = r.get(s, "damping", m.damping_n_s_per_m);
  m.use_relative_values = r.get_bool(s, "useRelativeValues", m.use_relative_values);
  m.static_friction = r.get(s, "staticFriction", m.static_friction);
  m.dynamic_friction = r.get(s, "dynamicFriction", m.dynamic_friction);
  m.snap_distance_m = r.get(s, "snapDistance", m.snap_distance_m);
  if (auto valid = haptics::validate(m); !valid) r.fail(s, valid.error().message);
  return m;
}

}  // namespace


namespace {





// N numbers of an attribute (e.g. fungPre="a b d0 F0"), else an error naming it.
template <std::size_t N>
bool read_numbers(ProjectReader& r, const pugi::xml_node& node, const char* name, std::array<double, N>& out, const char* meaning) {
  const pugi::xml_attribute a = node.attribute(name);
  if (!a) return false;
  std::istringstream in(a.value());
  std::array<double, N> v{};
  for (double& x : v) {
    if (!(in >> x) || !std::isfinite(x)) {
      r.fail(node, fmt::format("<{}> {}=\"{}\" must be {} numbers ({})", node.name(), name, a.value(), N, meaning));
      return false;
    }
  }
  std::string rest;
  if (in >> rest) {
    r.fail(node, fmt::format("<{}> {}=\"{}\" must be {} numbers ({})", node.name(), name, a.value(), N, meaning));
    return false;
  }
  out = v;
  return true;
}

procedures::TissueNeedleParameters read_tissue(ProjectReader& r, const pugi::xml_node& node, procedures::TissueNeedleParameters t) {
  t.pierceable = r.get_bool(node, "pierceable", t.pierceable);
  const std::string model = node.attribute("model").as_string(std::string(procedures::model_name(t.model)).c_str());
  if (model == "fung") t.model = procedures::NeedleForceModel::kFung;
  else if (model == "simone-okamura") t.model = procedures::NeedleForceModel::kSimoneOkamura;
  else r.fail(node, fmt::format("<tissue> model=\"{}\": expected fung or simone-okamura", model));
  const std::string form = node.attribute("fungForm").as_string(std::string(procedures::form_name(t.fung_form)).c_str());
  if (form == "integrated") t.fung_form = procedures::FungForm::kIntegrated;
  else if (form == "printed") t.fung_form = procedures::FungForm::kPrinted;
  else r.fail(node, fmt::format("<tissue> fungForm=\"{}\": expected integrated ((F0 + b) e^(a (d - d0)) - b) or printed (... + b)", form));
  t.capsule_m = r.get(node, "capsule", t.capsule_m);
  t.puncture_force_n = r.get(node, "punctureForce", t.puncture_force_n);
  t.relaxation_time_s = r.get(node, "relaxationTime", t.relaxation_time_s);
  if (std::array<double, 4> v{}; read_numbers(r, node, "fungPre", v, "a 1/m, b N, d0 m, F0 N")) t.fung_pre = {v[0], v[1], v[2], v[3]};
  if (std::array<double, 4> v{}; read_numbers(r, node, "fungPost", v, "a 1/m, b N, d0 m, F0 N")) t.fung_post = {v[0], v[1], v[2], v[3]};
  if (std::array<double, 3> v{}; read_numbers(r, node, "stiffness", v, "a0 N, a1 N/m, a2 N/m2")) t.stiffness = {v[0], v[1], v[2]};
  t.cutting_force_n = r.get(node, "cuttingForce", t.cutting_force_n);
  if (std::array<double, 4> v{}; read_numbers(r, node, "friction", v, "Cp N/m, Cn N/m, bp N s/m2, bn N s/m2")) {
    t.friction.static_positive_n_per_m = v[0];
    t.friction.static_negative_n_per_m = v[1];
    t.friction.damping_positive_n_s_per_m2 = v[2];
    t.friction.damping_negative_n_s_per_m2 = v[3];
  }
  t.friction.velocity_band_m_per_s = r.get(node, "frictionVelocityBand", t.friction.velocity_band_m_per_s);
  t.lateral_stiffness_n_per_m = r.get(node, "lateralStiffness", t.lateral_stiffness_n_per_m);
  t.lateral_damping_n_s_per_m = r.get(node, "lateralDamping", t.lateral_damping_n_s_per_m);
  t.spread_radius_m = r.get(node, "spreadRadius", t.spread_radius_m);
  t.path_tolerance_m = r.get(node, "pathTolerance", t.path_tolerance_m);
  const std::string body = node.attribute("body").as_string("");
  if (auto ok = procedures::validate(t, body.empty() ? std::string("<tissue>") : fmt::format("<tissue body=\"{}\">", body)); !ok) {
    r.fail(node, ok.error().message);
  }
  return t;
}

procedures::NeedleConfig read_needle(ProjectReader& r, const pugi::xml_node& node) {
  procedures::NeedleConfig n;
  const std::string axis = node.attribute("axis").as_string("motion");
  if (axis == "motion") n.axis = procedures::NeedleAxis::kMotion;
  else if (axis == "normal") n.axis = procedures::NeedleAxis::kNormal;
  else if (axis == "stylus") n.axis = procedures::NeedleAxis::kStylus;
  else r.fail(node, fmt::format("<needle> axis=\"{}\": expected motion, normal or stylus", axis));
  n.velocity_filter_s = r.get(node, "velocityFilter", n.velocity_filter_s);
  if (!(n.velocity_filter_s >= 0.0 && n.velocity_filter_s <= 1.0)) {
    r.fail(node, fmt::format("<needle> velocityFilter must be in [0, 1] s, got {}", n.velocity_filter_s));
  }
  procedures::NeedleGeometry& g = n.geometry;
  g.length_m = r.get(node, "length", g.length_m);
  g.shaft_diameter_m = r.get(node, "shaftDiameter", g.shaft_diameter_m);
  g.tip_diameter_m = r.get(node, "tipDiameter", g.tip_diameter_m);
  g.tip_length_m = r.get(node, "tipLength", g.tip_length_m);
  g.syringe_diameter_m = r.get(node, "syringeDiameter", g.syringe_diameter_m);
  g.syringe_length_m = r.get(node, "syringeLength", g.syringe_length_m);
  // The common set first (the one without a body), so that a body's set starts from it.
  for (const pugi::xml_node t : node.children("tissue")) {
    if (!t.attribute("body")) n.tissue = read_tissue(r, t, n.tissue);
  }
  for (const pugi::xml_node t : node.children()) {
    if (t.type() != pugi::node_element) continue;
    if (std::string(t.name()) != "tissue") {
      r.fail(t, fmt::format("unknown element <{}> in <needle> (tissue)", t.name()));
      continue;
    }
    if (!t.attribute("body")) continue;
    const std::string body = t.attribute("body").as_string("");
    if (body.empty()) {
      r.fail(t, "<tissue body=\"\">: name the body, or leave body out for every deformable body");
      continue;
    }
    n.bodies.emplace_back(body, read_tissue(r, t, n.tissue));
  }
  if (auto ok = procedures::validate(n); !ok) r.fail(node, ok.error().message);
  return n;
}

}  // namespace

Expected<void> check_graphics(const GraphicsSetup& g) {
  const auto fail = [](std::string message) -> Expected<void> { return make_error(ErrorCode::kInvalidArgument, std::move(message)); };
  if (g.render_mode != "shaded" && g.render_mode != "wireframe" && g.render_mode != "shaded+wireframe" && g.render_mode != "points") {
    return fail(fmt::format("unknown renderMode \"{}\" (shaded, wireframe, shaded+wireframe, points)", g.render_mode));
  }
  if (g.color_by != "material" && g.color_by != "displacement" && g.color_by != "strain" && g.color_by != "stress") {
    return fail(fmt::format("unknown colorBy \"{}\" (material, displacement, strain, stress)", g.color_by));
  }
  if (!g.viewpoint_m.allFinite() || !g.look_at_m.allFinite()) return fail("<graphics> viewpoint and lookAt must be three numbers");
  const auto unit_colour = [](const Vec3& c) { return c.allFinite() && (c.array() >= 0.0).all() && (c.array() <= 1.0).all(); };
  if (!unit_colour(g.diffuse_color)) return fail("<material> diffuseColor must be three numbers in [0, 1]");
  if (!unit_colour(g.specular_color)) return fail("<material> specularColor must be three numbers in [0, 1]");
  const std::pair<const char*, double> units[] = {{"<material> shininess", g.shininess},
                                                   {"<material> transparency", g.transparency},
                                                   {"<light> headlightIntensity", g.headlight_intensity},
                                                   {"<light> intensity", g.light_intensity},
                                                   {"<light> ambientIntensity", g.ambient_intensity}};
  for (const auto& [name, v] : units) {
    if (!(v >= 0.0 && v <= 1.0)) return fail(fmt::format("{} must be in [0, 1], got {}", name, v));
  }
  if (!g.light_direction.allFinite() || !(g.light_direction.norm() > 0.0)) return fail("<light> direction must not be zero");
  return {};
}


Expected<HofProject> read_project(const std::filesystem::path& path) {
  std::ifstream in(path, std::ios::binary);
  if (!in) return make_error(ErrorCode::kIo, "cannot open the project file", path.string());
  std::stringstream buffer;
  buffer << in.rdbuf();
  return parse_project(buffer.str(), path);
}

Expected<void> set_project_attribute(HofProject& project, const std::filesystem::path& path, std::string_view element,
                                     std::string_view attribute, std::string_view value) {
  // Through the canonical text and the reader: the names are the file's own, and a value is
  // checked exactly as when a file is read.
  const std::string name = fmt::format("{}@{}", element, attribute);
  pugi::xml_document doc;
  const std::string text = to_xml(project);
  if (!doc.load_buffer(text.data(), text.size())) return make_error(ErrorCode::kParse, "the project does not serialise", path.string());
  pugi::xml_node node = doc.child("hof");
  std::string walked = "hof";
  std::size_t start = 0;
  while (!element.empty() && start <= element.size()) {
    const std::size_t slash = element.find('/', start);
    std::string part(element.substr(start, slash == std::string_view::npos ? std::string_view::npos : slash - start));
    // NAME[n]: the n-th such element (from 1, as XPath), e.g. haptics/effects/SpringEffect[2].
    int index = 1;
    if (const std::size_t open = part.find('['); open != std::string::npos && part.ends_with(']')) {
      const std::string number = part.substr(open + 1, part.size() - open - 2);
      const auto parsed = std::from_chars(number.data(), number.data() + number.size(), index);
      if (parsed.ec != std::errc() || parsed.ptr != number.data() + number.size() || index < 1) {
        return make_error(ErrorCode::kInvalidArgument, fmt::format("'{}': '{}' is not NAME[n] with n >= 1", name, part));
      }
      part.resize(open);
    }
    pugi::xml_node child = node.child(part.c_str());
    for (int k = 1; child && k < index; ++k) child = child.next_sibling(part.c_str());
    if (!child && index > 1 && node.child(part.c_str())) {
      int count = 0;
      for (pugi::xml_node c = node.child(part.c_str()); c; c = c.next_sibling(part.c_str())) ++count;
      return make_error(ErrorCode::kInvalidArgument, fmt::format("'{}': <{}> has {} <{}>, not {}", name, walked, count, part, index));
    }
    if (!child) {
      std::string known;
      for (const pugi::xml_node c : node.children()) {
        if (c.type() != pugi::node_element) continue;
        if (known.find(std::string(c.name()) + ",") == std::string::npos) known += std::string(c.name()) + ", ";
      }
      if (known.size() >= 2) known.resize(known.size() - 2);
      return make_error(ErrorCode::kInvalidArgument,
                        fmt::format("'{}': no element <{}> in <{}> (it has: {})", name, part, walked, known.empty() ? "none" : known));
    }
    node = child;
    walked += "/" + part + (index > 1 ? fmt::format("[{}]", index) : std::string());
    if (slash == std::string_view::npos) break;
    start = slash + 1;
  }
  pugi::xml_attribute a = node.attribute(std::string(attribute).c_str());
  if (!a) {
    std::string known;
    for (const pugi::xml_attribute k : node.attributes()) known += std::string(known.empty() ? "" : ", ") + k.name();
    return make_error(ErrorCode::kInvalidArgument,
                      fmt::format("'{}': <{}> has no attribute '{}' (it has: {})", name, walked, attribute, known.empty() ? "none" : known));
  }
  a.set_value(std::string(value).c_str());
  std::ostringstream out;
  doc.save(out, "  ");
  auto changed = parse_project(out.str(), path);
  if (!changed) {
    Error e = changed.error();
    e.message = fmt::format("'{}' = '{}': {}", name, value, e.message);
    e.line = 0;
    return std::unexpected(e);
  }
  project = std::move(*changed);
  return {};
}

namespace {

// <region>: a part of a body with its own material (sphere, box or a Gmsh physical group).
MaterialRegion read_region(ProjectReader& r, const pugi::xml_node& node) {
  MaterialRegion region;
  region.name = node.attribute("name").as_string("region");
  region.body = node.attribute("body").as_string("");
  region.force_field = node.attribute("forceField").as_string("");
  if (region.body.empty()) r.fail(node, "<region> needs body=\"NAME\" (the body whose elements it holds)");
  const std::string shape = node.attribute("shape").as_string("sphere");
  if (shape == "sphere") {
    region.shape = MaterialRegion::Shape::kSphere;
    region.center = r.get_vec(node, "center", Vec3::Zero());
    region.radius = r.get(node, "radius", 0.0);
    if (!(region.radius > 0.0)) r.fail(node, "<region shape=\"sphere\"> needs radius > 0");
  } else if (shape == "box") {
    region.shape = MaterialRegion::Shape::kBox;
    region.box_min = r.get_vec(node, "min", Vec3::Zero());
    region.box_max = r.get_vec(node, "max", Vec3::Zero());
    if (!(region.box_max.array() > region.box_min.array()).all()) r.fail(node, "<region shape=\"box\"> needs min < max on every axis");
  } else if (shape == "group") {
    region.shape = MaterialRegion::Shape::kGroup;
    if (!node.attribute("physicalGroup")) r.fail(node, "<region shape=\"group\"> needs physicalGroup=\"TAG\" (a Gmsh physical tag)");
    const double tag = r.get(node, "physicalGroup", 0.0);
    if (!(std::abs(tag) < 2e9) || tag != std::floor(tag)) r.fail(node, "<region physicalGroup> must be a whole number (a Gmsh physical tag)");
    else region.physical_group = static_cast<std::int32_t>(tag);
  } else {
    r.fail(node, fmt::format("<region> shape=\"{}\": expected sphere, box or group", shape));
  }
  if (node.attribute("youngModulus")) {
    region.young_modulus_pa = r.get(node, "youngModulus", 0.0);
    if (!(*region.young_modulus_pa > 0.0)) r.fail(node, "<region> youngModulus must be > 0 (Pa)");
  }
  if (node.attribute("poissonRatio")) {
    region.poisson_ratio = r.get(node, "poissonRatio", 0.0);
    if (!(*region.poisson_ratio > -1.0 && *region.poisson_ratio < 0.5)) r.fail(node, "<region> poissonRatio must be in (-1, 0.5)");
  }
  if (node.attribute("massDensity")) {
    region.mass_density_kg_per_m3 = r.get(node, "massDensity", 0.0);
    if (!(*region.mass_density_kg_per_m3 > 0.0)) r.fail(node, "<region> massDensity must be > 0 (kg/m^3)");
  }
  if (!region.young_modulus_pa && !region.poisson_ratio && !region.mass_density_kg_per_m3) {
    r.fail(node, "<region> needs youngModulus, poissonRatio or massDensity");
  }
  return region;
}

// <bodies>: the bodies' options (<body>) and fixed obstacles (<obstacle>).
void read_bodies(ProjectReader& r, const pugi::xml_node& bodies, HofProject& p) {
  for (const pugi::xml_node b : bodies.children()) {
    if (b.type() != pugi::node_element) continue;
    const std::string tag = b.name();
    const std::string name = b.attribute("name").as_string("");
    if (name.empty()) {
      r.fail(b, fmt::format("<{}> needs a name", tag));
      continue;
    }
    std::optional<haptics::SurfaceMaterial> surface;
    if (const pugi::xml_node s = b.child("surface")) surface = read_surface(r, s);
    if (tag == "body") {
      const std::string model = b.attribute("model").as_string("");
      if (!model.empty() && model != "springs" && model != "membrane" && model != "hexahedra") {
        r.fail(b, fmt::format("<body model=\"{}\">: expected springs, membrane (surface bodies) or hexahedra (volume bodies)", model));
      }
      std::array<int, 3> grid{0, 0, 0};
      if (b.attribute("grid")) {
        const Vec3 n = r.get_vec(b, "grid", Vec3::Zero());
        if (model != "hexahedra") r.fail(b, "<body grid=...> goes with model=\"hexahedra\"");
        if (!(n.array() >= 2.0).all() || !(n.array() <= 512.0).all() || !(n.array() == n.array().floor()).all()) {
          r.fail(b, "<body grid=\"nx ny nz\">: whole numbers of nodes per axis, 2 to 512");
        } else {  // converted only once in range
          for (int a = 0; a < 3; ++a) grid[static_cast<std::size_t>(a)] = static_cast<int>(n[a]);
        }
      }
      p.bodies.push_back(BodySetup{name, surface, model, grid});
    } else if (tag == "obstacle") {
      ObstacleSetup o;
      o.name = name;
      o.mesh = b.attribute("mesh").as_string("");
      if (o.mesh.empty()) r.fail(b, "<obstacle> needs mesh=\"FILE\" (OBJ, STL, OFF or a tetrahedral mesh)");
      o.translation = r.get_vec(b, "translation", Vec3::Zero());
      o.surface = surface;
      p.obstacles.push_back(std::move(o));
    } else {
      r.fail(b, fmt::format("unknown element <{}> in <bodies> (body, obstacle)", tag));
    }
  }
}

// <haptics>: the device, rate, renderer, contact coupling, calibration, surface, options,
// stylus, needle, force effects and safety.
void read_haptics(ProjectReader& r, const pugi::xml_node& h, HofProject& p) {
  p.device = h.attribute("device").as_string(p.device.c_str());
  p.haptic_rate_hz = r.get(h, "hapticRate", p.haptic_rate_hz);
  const std::string renderer = h.attribute("renderer").as_string(renderer_name(p.renderer));
  if (renderer == "RuspiniRenderer") p.renderer = haptics::RendererKind::kRuspini;
  else if (renderer == "GodObjectRenderer") p.renderer = haptics::RendererKind::kGodObject;
  else if (renderer == "PenaltyRenderer") p.renderer = haptics::RendererKind::kPenalty;
  else r.fail(h, fmt::format("unknown renderer \"{}\" (RuspiniRenderer, GodObjectRenderer, PenaltyRenderer)", renderer));
  p.proxy_radius_m = r.get(h, "proxyRadius", p.proxy_radius_m);
  p.force_shading = r.get_bool(h, "forceShading", p.force_shading);
  const std::string face = h.attribute("touchableFace").as_string("FRONT");
  if (face == "FRONT") p.touchable_face = collision::TouchableFace::kFront;
  else if (face == "BACK") p.touchable_face = collision::TouchableFace::kBack;
  else if (face == "FRONT_AND_BACK") p.touchable_face = collision::TouchableFace::kFrontAndBack;
  else r.fail(h, fmt::format("unknown touchableFace \"{}\" (FRONT, BACK, FRONT_AND_BACK)", face));
  const std::string coupling = h.attribute("coupling").as_string("barycentric");
  if (coupling == "barycentric") p.coupling = coupling::ContactCoupling::kBarycentric;
  else if (coupling == "closest-vertex") p.coupling = coupling::ContactCoupling::kClosestVertex;
  else if (coupling == "compliance") p.coupling = coupling::ContactCoupling::kCompliance;
  else if (coupling == "fem-reaction") p.coupling = coupling::ContactCoupling::kFemReaction;
  else r.fail(h, fmt::format("unknown coupling \"{}\" (barycentric, closest-vertex, compliance, fem-reaction)", coupling));
  if (const pugi::xml_node c = h.child("calibration")) {
    if (const pugi::xml_attribute a = c.attribute("positionCalibration")) {
      std::istringstream values(a.value());
      for (double& v : p.position_calibration) {
        if (!(values >> v)) {
          r.fail(c, "positionCalibration must be 16 numbers (a row-major 4x4 matrix)");
          break;
        }
      }
    }
  }
  if (const pugi::xml_node s = h.child("surface")) p.surface = read_surface(r, s);
  if (const pugi::xml_node o = h.child("options")) {
    p.use_bound_tree = r.get_bool(o, "useBoundTree", p.use_bound_tree);
    p.max_triangles_in_leaf = r.get_count(o, "maxTrianglesInLeaf", p.max_triangles_in_leaf, 1, 1000000);
  }
  if (const pugi::xml_node st = h.child("stylus")) {
    p.stylus_radius_m = r.get(st, "radius", p.stylus_radius_m);
    p.stylus_length_m = r.get(st, "length", p.stylus_length_m);
  }
  if (const pugi::xml_node n = h.child("needle")) p.needle = read_needle(r, n);
  for (const pugi::xml_node e : h.child("effects").children()) {
    const std::string type = e.name();
    if (type == "SpringEffect") {
      haptics::SpringEffect spring;
      spring.position_m = r.get_vec(e, "position", spring.position_m);
      spring.spring_constant_n_per_m = r.get(e, "springConstant", spring.spring_constant_n_per_m);
      spring.start_distance_m = r.get(e, "startDistance", spring.start_distance_m);
      spring.escape_distance_m = r.get(e, "escapeDistance", spring.escape_distance_m);
      spring.damping_n_s_per_m = r.get(e, "damping", spring.damping_n_s_per_m);
      p.effects.springs.push_back(spring);
    } else if (type == "ViscosityEffect") {
      haptics::ViscosityEffect viscosity;
      viscosity.viscosity_pa_s = r.get(e, "viscosity", viscosity.viscosity_pa_s);
      viscosity.radius_m = r.get(e, "radius", viscosity.radius_m);
      viscosity.damping_factor = r.get(e, "dampingFactor", viscosity.damping_factor);
      viscosity.enabled = r.get_bool(e, "enabled", viscosity.enabled);
      p.effects.viscosities.push_back(viscosity);
    } else if (type == "ForceField") {
      p.effects.constants.push_back(haptics::ConstantForceEffect{r.get_vec(e, "force", Vec3::Zero())});
    } else if (e.type() == pugi::node_element) {
      r.fail(e, fmt::format("unknown force effect <{}> (SpringEffect, ViscosityEffect, ForceField)", type));
    }
  }
  if (const pugi::xml_node s = h.child("safety")) {
    p.safety.fade_in_s = r.get(s, "fadeIn", p.safety.fade_in_s);
    p.safety.fade_out_s = r.get(s, "fadeOut", p.safety.fade_out_s);
    p.safety.max_snapshot_age_s = r.get(s, "maxSnapshotAge", p.safety.max_snapshot_age_s);
    p.safety.max_consecutive_overruns = r.get_count(s, "maxConsecutiveOverruns", p.safety.max_consecutive_overruns, 1, 1000000);
    p.safety.max_force_n = r.get(s, "maxForce", p.safety.max_force_n);
    if (!(p.safety.max_force_n >= 0.0)) r.fail(s, fmt::format("<safety> maxForce must be >= 0 N (0: the device's own limit), got {}", p.safety.max_force_n));
  }
}

// The thesis' appendix project: <h3d><haptics><device filename="DeviceX.x3d"/>…
// <graphics><viewpoint filename="…x3d"/>. The device file gives the calibration and the
// renderer; the viewpoint file the camera. (Stylus and geometry files: the stylus is drawn
// by HoF, the touchable surface comes from the simulated body.)
Expected<void> read_h3d_files(const pugi::xml_node& h3d, const std::filesystem::path& path, HofProject& p) {
  if (!h3d) return {};
  const std::filesystem::path folder = path.parent_path();
  if (const char* device = h3d.child("haptics").child("device").attribute("filename").as_string(nullptr)) {
    auto x3d = read_x3d_scene(folder / device);
    if (!x3d) return std::unexpected(x3d.error());
    if (!x3d->devices.empty()) {
      const X3dDevice& d = x3d->devices.front();
      p.position_calibration = d.position_calibration;
      if (d.renderer && d.renderer->kind) {
        p.renderer = *d.renderer->kind;
        p.proxy_radius_m = d.renderer->proxy_radius_m;
      }
    }
  }
  if (const char* viewpoint = h3d.child("graphics").child("viewpoint").attribute("filename").as_string(nullptr)) {
    auto x3d = read_x3d_scene(folder / viewpoint);
    if (!x3d) return std::unexpected(x3d.error());
    if (!x3d->viewpoints.empty()) p.graphics.viewpoint_m = x3d->viewpoints.front().position;
  }
  return {};
}

// <graphics>: the camera, render mode, colours, material and light.
void read_graphics(ProjectReader& r, const pugi::xml_node& g, HofProject& p) {
  // A value in [0, 1] (colours' parts, intensities, shininess), else an error naming it.
  const auto unit_interval = [&](const pugi::xml_node& node, const char* name, double fallback) {
    const double v = r.get(node, name, fallback);
    if (!(v >= 0.0 && v <= 1.0)) {
      r.fail(node, fmt::format("<{}> {} must be in [0, 1], got {}", node.name(), name, v));
      return fallback;
    }
    return v;
  };
  p.graphics.viewpoint_m = r.get_vec(g, "viewpoint", p.graphics.viewpoint_m);
  p.graphics.look_at_m = r.get_vec(g, "lookAt", p.graphics.look_at_m);
  p.graphics.render_mode = g.attribute("renderMode").as_string(p.graphics.render_mode.c_str());
  if (p.graphics.render_mode != "shaded" && p.graphics.render_mode != "wireframe" &&
      p.graphics.render_mode != "shaded+wireframe" && p.graphics.render_mode != "points") {
    r.fail(g, fmt::format("unknown renderMode \"{}\" (shaded, wireframe, shaded+wireframe, points)", p.graphics.render_mode));
  }
  p.graphics.color_by = g.attribute("colorBy").as_string(p.graphics.color_by.c_str());
  if (p.graphics.color_by != "material" && p.graphics.color_by != "displacement" && p.graphics.color_by != "strain" &&
      p.graphics.color_by != "stress") {
    r.fail(g, fmt::format("unknown colorBy \"{}\" (material, displacement, strain, stress)", p.graphics.color_by));
  }
  if (const pugi::xml_node m = g.child("material")) {
    const auto unit_colour = [&](const char* name, const Vec3& fallback) {
      const Vec3 c = r.get_vec(m, name, fallback);
      if (!((c.array() >= 0.0).all() && (c.array() <= 1.0).all())) {
        r.fail(m, fmt::format("<material> {} must be three numbers in [0, 1]", name));
        return fallback;
      }
      return c;
    };
    const auto unit_number = [&](const char* name, double fallback) { return unit_interval(m, name, fallback); };
    p.graphics.diffuse_color = unit_colour("diffuseColor", p.graphics.diffuse_color);
    p.graphics.specular_color = unit_colour("specularColor", p.graphics.specular_color);
    p.graphics.shininess = unit_number("shininess", p.graphics.shininess);
    p.graphics.transparency = unit_number("transparency", p.graphics.transparency);
  }
  if (const pugi::xml_node l = g.child("light")) {
    const auto unit_number = [&](const char* name, double fallback) { return unit_interval(l, name, fallback); };
    p.graphics.headlight = r.get_bool(l, "headlight", p.graphics.headlight);
    p.graphics.headlight_intensity = unit_number("headlightIntensity", p.graphics.headlight_intensity);
    p.graphics.light_direction = r.get_vec(l, "direction", p.graphics.light_direction);
    if (!(p.graphics.light_direction.norm() > 0.0)) r.fail(l, "<light> direction must not be zero");
    p.graphics.light_intensity = unit_number("intensity", p.graphics.light_intensity);
    p.graphics.ambient_intensity = unit_number("ambientIntensity", p.graphics.ambient_intensity);
  }
}

}  // namespace

Expected<HofProject> parse_project(const std::string& text, const std::filesystem::path& path) {
  pugi::xml_document doc;
  const pugi::xml_parse_result parsed = doc.load_buffer(text.data(), text.size());
  if (!parsed) {
    return std::unexpected(Error{ErrorCode::kParse, fmt::format("malformed XML: {}", parsed.description()), path.string(),
                                 line_of(text, parsed.offset), -1});
  }
  if (const pugi::xml_node deep = mesh::first_too_deep_element(doc)) {
    return std::unexpected(Error{ErrorCode::kParse,
                                 fmt::format("<{}> is nested deeper than {} levels", deep.name(), mesh::kMaxXmlDepth),
                                 path.string(), line_of(text, deep.offset_debug()), -1});
  }
  ProjectReader r{text, path.string(), std::nullopt};
  const pugi::xml_node root = doc.child("hof");
  if (!root) return make_error(ErrorCode::kParse, "not a HoF project: the root element must be <hof>", path.string(), 1);
  HofProject p;
  p.name = root.attribute("name").as_string("untitled");
  const pugi::xml_node mechanics = root.child("mechanics");
  // The scene inline as a SOFA node tree (ours: <mechanics><Node>; the thesis' appendix:
  // <sofa><sg><Node>), or in a separate file.
  pugi::xml_node inline_scene = mechanics.child("Node");
  if (!inline_scene) inline_scene = root.child("sofa").child("sg").child("Node");
  if (inline_scene) {
    std::ostringstream xml;
    inline_scene.print(xml, "  ", pugi::format_indent, pugi::encoding_utf8, 2);
    p.mechanics_inline = xml.str();
  } else if (mechanics && mechanics.attribute("scene")) {
    p.mechanics_scene = mechanics.attribute("scene").value();
  } else {
    return std::unexpected(r.at(mechanics ? mechanics : root,
                                "the project needs <mechanics scene=\"FILE.scn\"/> or a scene inline in <mechanics>"));
  }
  p.scene_unit = mechanics.attribute("unit").as_string("");
  for (const pugi::xml_node set : mechanics.children("set")) {
    coupling::ParameterChange c;
    c.body = set.attribute("body").as_string("");
    c.component = set.attribute("component").as_string("");
    c.parameter = set.attribute("parameter").as_string("");
    c.value = r.get(set, "value", 0.0);
    if (c.body.empty() || c.parameter.empty() || !set.attribute("value")) {
      return std::unexpected(r.at(set, "<set> needs body, parameter and value (and component, unless the parameter is the model's own)"));
    }
    p.parameters.push_back(std::move(c));
  }
  for (const pugi::xml_node node : mechanics.children("region")) p.regions.push_back(read_region(r, node));
  read_bodies(r, root.child("bodies"), p);
  if (const pugi::xml_node h = root.child("haptics")) read_haptics(r, h, p);
  if (auto ok = read_h3d_files(root.child("h3d"), path, p); !ok) return std::unexpected(ok.error());
  if (const pugi::xml_node g = root.child("graphics")) read_graphics(r, g, p);
  if (r.error) return std::unexpected(*r.error);
  if (!(p.haptic_rate_hz >= 100.0 && p.haptic_rate_hz <= 20000.0)) {
    return std::unexpected(r.at(root.child("haptics"), fmt::format("hapticRate must be in [100, 20000] Hz, got {}", p.haptic_rate_hz)));
  }
  return p;
}


std::filesystem::path scene_file(const HofProject& project, const std::filesystem::path& project_file) {
  return project.mechanics_inline.empty() ? project_file.parent_path() / project.mechanics_scene : project_file;
}

HofProject moved_project(const HofProject& project, const std::filesystem::path& from, const std::filesystem::path& to) {
  HofProject out = project;
  std::error_code ec;
  const std::filesystem::path folder = std::filesystem::absolute(to, ec).parent_path();
  if (out.mechanics_inline.empty() && !out.mechanics_scene.empty()) {
    const std::filesystem::path scene = std::filesystem::absolute(scene_file(project, from), ec);
    out.mechanics_scene = std::filesystem::relative(scene, folder, ec);
    if (ec || out.mechanics_scene.empty()) out.mechanics_scene = scene;
  } else if (!out.mechanics_inline.empty()) {
    out.mechanics_inline = reanchor_scene_files(out.mechanics_inline, std::filesystem::absolute(from, ec).parent_path(), folder);
  }
  return out;
}

coupling::SessionConfig session_config(const HofProject& p) {
  coupling::SessionConfig c;
  c.coupling = p.coupling;
  c.haptics.rate_hz = p.haptic_rate_hz;
  c.haptics.renderer.kind = p.renderer;
  c.haptics.renderer.proxy_radius_m = p.proxy_radius_m;
  c.haptics.renderer.force_shading = p.force_shading;
  c.haptics.renderer.touchable_face = p.touchable_face;
  c.haptics.material = p.surface;
  c.haptics.safety = p.safety;
  c.effects = p.effects;
  c.tree.use_bound_tree = p.use_bound_tree;
  c.tree.max_triangles_in_leaf = p.max_triangles_in_leaf;
  for (int r = 0; r < 4; ++r) {
    for (int k = 0; k < 4; ++k) c.haptics.calibration.position(r, k) = p.position_calibration[static_cast<std::size_t>(4 * r + k)];
  }
  return c;
}

}  // namespace hof::scene
