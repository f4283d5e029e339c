#include "hof/scene/project.h"
#include "hof/mesh/xml_depth.h"
#include "hof/scene/detail/project_fields.h"
#include "hof/scene/device_config.h"

#include "hof/core/file_write.h"

#include "hof/core/text.h"

#include "hof/scene/sofa_scene_edit.h"
#include "hof/scene/x3d_scene.h"

#include <fmt/format.h>

#include <algorithm>
#include <charconv>
#include <fstream>
#include <pugixml.hpp>
#include <sstream>

namespace hof::scene {

namespace {

// Line of a byte offset in the file text (for error messages).
std::int64_t line_of(const std::string& text, std::ptrdiff_t offset) {
  std::int64_t line = 1;
  for (std::ptrdiff_t i = 0; i < offset && i < static_cast<std::ptrdiff_t>(text.size()); ++i)
    line += text[static_cast<std::size_t>(i)] == '\n';
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
  /// The attributes of `fields` that `node` has, read into `into` (detail/project_fields.h).
  template <class T>
  void read(const pugi::xml_node& node, const detail::Fields<T>& fields, T& into) {
    const auto attribute = [&](std::string_view name) -> std::optional<std::string_view> {
      const pugi::xml_attribute a = node.attribute(std::string(name).c_str());
      if (!a) return std::nullopt;
      return std::string_view(a.value());
    };
    if (auto problem = detail::read_fields(fields, node.name(), attribute, into)) fail(node, *problem);
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
  r.read(s, detail::surface_fields(), m);
  if (auto problem = detail::check_surface(m)) r.fail(s, *problem);
  return m;
}

}  // namespace

namespace {

// <tissue>: a body's set (body="NAME"), starting from the set for every body, or that set.
procedures::TissueNeedleParameters read_tissue(ProjectReader& r, const pugi::xml_node& node,
                                               procedures::TissueNeedleParameters t) {
  r.read(node, detail::tissue_fields(), t);
  if (auto problem = detail::check_tissue(t, node.attribute("body").as_string(""))) r.fail(node, *problem);
  return t;
}

procedures::NeedleConfig read_needle(ProjectReader& r, const pugi::xml_node& node) {
  procedures::NeedleConfig n;
  r.read(node, detail::needle_fields(), n);
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
  if (auto problem = detail::check_needle(n)) r.fail(node, *problem);
  return n;
}

}  // namespace

Expected<void> check_graphics(const GraphicsSetup& g) {
  // By the reader's own checks of <graphics>, <material> and <light> (detail/project_fields.h).
  for (const auto& [fields, element] :
       {std::pair{&detail::graphics_fields(), "graphics"}, std::pair{&detail::material_fields(), "material"},
        std::pair{&detail::light_fields(), "light"}}) {
    if (auto problem = detail::check_fields(*fields, element, g))
      return make_error(ErrorCode::kInvalidArgument, std::move(*problem));
  }
  return {};
}

Expected<HofProject> read_project(const std::filesystem::path& path) {
  std::ifstream in(path, std::ios::binary);
  if (!in) return make_error(ErrorCode::kIo, "cannot open the project file", path.string());
  std::stringstream buffer;
  buffer << in.rdbuf();
  return parse_project(buffer.str(), path);
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
    if (!(region.box_max.array() > region.box_min.array()).all())
      r.fail(node, "<region shape=\"box\"> needs min < max on every axis");
  } else if (shape == "group") {
    region.shape = MaterialRegion::Shape::kGroup;
    if (!node.attribute("physicalGroup"))
      r.fail(node, "<region shape=\"group\"> needs physicalGroup=\"TAG\" (a Gmsh physical tag)");
    const double tag = r.get(node, "physicalGroup", 0.0);
    if (!(std::abs(tag) < 2e9) || tag != std::floor(tag))
      r.fail(node, "<region physicalGroup> must be a whole number (a Gmsh physical tag)");
    else
      region.physical_group = static_cast<std::int32_t>(tag);
  } else {
    r.fail(node, fmt::format("<region> shape=\"{}\": expected sphere, box or group", shape));
  }
  if (node.attribute("youngModulus")) {
    region.young_modulus_pa = r.get(node, "youngModulus", 0.0);
    if (!(*region.young_modulus_pa > 0.0)) r.fail(node, "<region> youngModulus must be > 0 (Pa)");
  }
  if (node.attribute("poissonRatio")) {
    region.poisson_ratio = r.get(node, "poissonRatio", 0.0);
    if (!(*region.poisson_ratio > -1.0 && *region.poisson_ratio < 0.5))
      r.fail(node, "<region> poissonRatio must be in (-1, 0.5)");
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
    std::optional<bool> contact;
    if (const pugi::xml_attribute a = b.attribute("contact")) {
      const std::string_view v = a.value();
      if (v == "true" || v == "1")
        contact = true;
      else if (v == "false" || v == "0")
        contact = false;
      else
        r.fail(b, fmt::format("<{}> contact=\"{}\" must be true or false", tag, v));
    }
    if (tag == "body") {
      const std::string model = b.attribute("model").as_string("");
      if (!model.empty() && model != "springs" && model != "membrane" && model != "hexahedra") {
        r.fail(b, fmt::format(
                      "<body model=\"{}\">: expected springs, membrane (surface bodies) or hexahedra (volume bodies)",
                      model));
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
      p.bodies.push_back(BodySetup{name, surface, model, grid, contact, line_of(r.text, b.offset_debug())});
    } else if (tag == "obstacle") {
      ObstacleSetup o;
      o.name = name;
      o.mesh = b.attribute("mesh").as_string("");
      if (o.mesh.empty()) r.fail(b, "<obstacle> needs mesh=\"FILE\" (OBJ, STL, OFF or a tetrahedral mesh)");
      o.translation = r.get_vec(b, "translation", Vec3::Zero());
      o.surface = surface;
      o.contact = contact;
      o.line = line_of(r.text, b.offset_debug());
      p.obstacles.push_back(std::move(o));
    } else {
      r.fail(b, fmt::format("unknown element <{}> in <bodies> (body, obstacle)", tag));
    }
  }
}

// <contact>: contact between bodies, and the pairs switched off (<pair a b enabled="false">).
ContactSetup read_contact(ProjectReader& r, const pugi::xml_node& node) {
  ContactSetup c;
  c.line = line_of(r.text, node.offset_debug());
  r.read(node, detail::contact_fields(), c.settings);
  if (auto problem = detail::check_contact(c.settings)) r.fail(node, *problem);
  for (const pugi::xml_node pair : node.children()) {
    if (pair.type() != pugi::node_element) continue;
    if (std::string_view(pair.name()) != "pair") {
      r.fail(pair, fmt::format("unknown element <{}> in <contact> (pair)", pair.name()));
      continue;
    }
    const std::string a = pair.attribute("a").as_string("");
    const std::string b = pair.attribute("b").as_string("");
    if (a.empty() || b.empty()) {
      r.fail(pair, "<pair> needs a=\"BODY\" and b=\"BODY\"");
      continue;
    }
    const std::string_view enabled = pair.attribute("enabled").as_string("true");
    if (enabled == "false" || enabled == "0") {
      c.disabled_pairs.emplace_back(a, b);
    } else if (enabled != "true" && enabled != "1") {
      r.fail(pair, fmt::format("<pair> enabled=\"{}\" must be true or false", enabled));
    }
  }
  return c;
}

// Every <tool> of <haptics>: the first hand's (no device=, or the project's device) and one
// more hand for each other device (HofProject::hands).
void read_tools(ProjectReader& r, const pugi::xml_node& h, HofProject& p) {
  struct Written {
    procedures::ShapedToolConfig tool;
    double max_force_n{0.0};
    pugi::xml_node node;
  };
  std::vector<Written> tools;
  for (const pugi::xml_node t : h.children("tool")) {
    Written w{{}, 0.0, t};
    r.read(t, detail::tool_fields(), w.tool);
    w.max_force_n = r.get(t, "maxForce", 0.0);
    if (!(w.max_force_n >= 0.0))
      r.fail(t, fmt::format("<tool> maxForce must be >= 0 N (0: <safety> maxForce), got {}", w.max_force_n));
    if (auto problem = detail::check_tool(w.tool)) r.fail(t, *problem);
    if (w.tool.shape == procedures::ToolShape::kMesh && !w.tool.mesh.empty()) {
      const std::filesystem::path mesh = std::filesystem::path(r.file).parent_path() / w.tool.mesh;
      if (auto surface = procedures::read_tool_mesh(mesh); !surface) {
        r.fail(t, fmt::format("<tool> mesh=\"{}\": {}", w.tool.mesh, surface.error().to_string()));
      }
    }
    if (!w.tool.device.empty()) {
      // Checked as the CLI's --device is (a replay file beside the project, as the project's own).
      std::string spec = w.tool.device;
      if (const std::string_view replay = "replay:"; spec.starts_with(replay)) {
        const std::filesystem::path recording = spec.substr(replay.size());
        if (recording.is_relative())
          spec = std::string(replay) + (std::filesystem::path(r.file).parent_path() / recording).string();
      }
      if (spec != "auto") {
        if (auto parsed = parse_device_spec(spec); !parsed)
          r.fail(t, fmt::format("<tool> device=\"{}\": {}", w.tool.device, parsed.error().message));
      }
    }
    tools.push_back(std::move(w));
  }
  if (tools.empty()) return;
  const auto is_first_hands = [&](const Written& w) { return w.tool.device.empty() || w.tool.device == p.device; };
  // A project without a device of its own: its first tool's device is the first hand.
  if (p.device == "auto" && std::none_of(tools.begin(), tools.end(), is_first_hands))
    p.device = tools.front().tool.device;
  for (std::size_t i = 0; i < tools.size(); ++i) {
    const Written& w = tools[i];
    for (std::size_t k = 0; k < i; ++k) {
      const bool same = is_first_hands(w) ? is_first_hands(tools[k]) : tools[k].tool.device == w.tool.device;
      if (same) {
        r.fail(w.node, fmt::format("a second <tool> on the device \"{}\" (the first is at line {}): each device "
                                   "carries one tool",
                                   is_first_hands(w) ? p.device : w.tool.device,
                                   line_of(r.text, tools[k].node.offset_debug())));
        return;
      }
    }
    if (is_first_hands(w)) {
      if (p.needle) r.fail(w.node, "<tool> and <needle>: the stylus carries one of them");
      if (w.max_force_n > 0.0)
        r.fail(w.node,
               "<tool> maxForce: the first device's limit is <safety> maxForce (maxForce is for a tool on "
               "another device)");
      p.tool = w.tool;
    } else {
      p.hands.push_back(HandSetup{w.tool, w.max_force_n, line_of(r.text, w.node.offset_debug())});
    }
  }
}

// <haptics>: the device, rate, renderer, contact coupling, calibration, surface, options,
// stylus, needle, force effects and safety.
void read_haptics(ProjectReader& r, const pugi::xml_node& h, HofProject& p) {
  r.read(h, detail::haptics_fields(), p);
  if (const pugi::xml_node c = h.child("calibration")) r.read(c, detail::calibration_fields(), p);
  if (const pugi::xml_node s = h.child("surface")) p.surface = read_surface(r, s);
  if (const pugi::xml_node o = h.child("options")) r.read(o, detail::options_fields(), p);
  if (const pugi::xml_node st = h.child("stylus")) r.read(st, detail::stylus_fields(), p);
  if (const pugi::xml_node n = h.child("needle")) p.needle = read_needle(r, n);
  read_tools(r, h, p);
  for (const pugi::xml_node e : h.child("effects").children()) {
    const std::string type = e.name();
    if (type == "SpringEffect") {
      haptics::SpringEffect spring;
      r.read(e, detail::spring_effect_fields(), spring);
      p.effects.springs.push_back(spring);
    } else if (type == "ViscosityEffect") {
      haptics::ViscosityEffect viscosity;
      r.read(e, detail::viscosity_effect_fields(), viscosity);
      p.effects.viscosities.push_back(viscosity);
    } else if (type == "ForceField") {
      haptics::ConstantForceEffect force;
      r.read(e, detail::force_field_fields(), force);
      p.effects.constants.push_back(force);
    } else if (e.type() == pugi::node_element) {
      r.fail(e, fmt::format("unknown force effect <{}> (SpringEffect, ViscosityEffect, ForceField)", type));
    }
  }
  if (const pugi::xml_node s = h.child("safety")) r.read(s, detail::safety_fields(), p.safety);
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
  r.read(g, detail::graphics_fields(), p.graphics);
  if (const pugi::xml_node m = g.child("material")) r.read(m, detail::material_fields(), p.graphics);
  if (const pugi::xml_node l = g.child("light")) r.read(l, detail::light_fields(), p.graphics);
}

}  // namespace

Expected<HofProject> parse_project(const std::string& text, const std::filesystem::path& path) {
  pugi::xml_document doc;
  const pugi::xml_parse_result parsed = doc.load_buffer(text.data(), text.size());
  if (!parsed) {
    return std::unexpected(Error{ErrorCode::kParse, fmt::format("malformed XML: {}", parsed.description()),
                                 path.string(), line_of(text, parsed.offset), -1});
  }
  if (const pugi::xml_node deep = mesh::first_too_deep_element(doc)) {
    return std::unexpected(Error{ErrorCode::kParse,
                                 fmt::format("<{}> is nested deeper than {} levels", deep.name(), mesh::kMaxXmlDepth),
                                 path.string(), line_of(text, deep.offset_debug()), -1});
  }
  ProjectReader r{text, path.string(), std::nullopt};
  const pugi::xml_node root = doc.child("hof");
  if (!root)
    return make_error(ErrorCode::kParse, "not a HoF project: the root element must be <hof>", path.string(), 1);
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
    ParameterChange c;
    c.body = set.attribute("body").as_string("");
    c.component = set.attribute("component").as_string("");
    c.parameter = set.attribute("parameter").as_string("");
    c.value = r.get(set, "value", 0.0);
    if (c.body.empty() || c.parameter.empty() || !set.attribute("value")) {
      return std::unexpected(
          r.at(set, "<set> needs body, parameter and value (and component, unless the parameter is the model's own)"));
    }
    p.parameters.push_back(std::move(c));
  }
  for (const pugi::xml_node node : mechanics.children("region")) p.regions.push_back(read_region(r, node));
  read_bodies(r, root.child("bodies"), p);
  if (const pugi::xml_node c = root.child("contact")) p.contact = read_contact(r, c);
  if (const pugi::xml_node h = root.child("haptics")) read_haptics(r, h, p);
  if (auto ok = read_h3d_files(root.child("h3d"), path, p); !ok) return std::unexpected(ok.error());
  if (const pugi::xml_node g = root.child("graphics")) read_graphics(r, g, p);
  if (r.error) return std::unexpected(*r.error);
  if (auto problem = detail::check_haptic_rate(p)) return std::unexpected(r.at(root.child("haptics"), *problem));
  return p;
}

std::filesystem::path scene_file(const HofProject& project, const std::filesystem::path& project_file) {
  return project.mechanics_inline.empty() ? project_file.parent_path() / project.mechanics_scene : project_file;
}

HofProject moved_project(const HofProject& project, const std::filesystem::path& from,
                         const std::filesystem::path& to) {
  HofProject out = project;
  std::error_code ec;
  const std::filesystem::path folder = std::filesystem::absolute(to, ec).parent_path();
  if (out.mechanics_inline.empty() && !out.mechanics_scene.empty()) {
    const std::filesystem::path scene = std::filesystem::absolute(scene_file(project, from), ec);
    out.mechanics_scene = std::filesystem::relative(scene, folder, ec);
    if (ec || out.mechanics_scene.empty()) out.mechanics_scene = scene;
  } else if (!out.mechanics_inline.empty()) {
    out.mechanics_inline =
        reanchor_scene_files(out.mechanics_inline, std::filesystem::absolute(from, ec).parent_path(), folder);
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
    for (int k = 0; k < 4; ++k)
      c.haptics.calibration.position(r, k) = p.position_calibration[static_cast<std::size_t>(4 * r + k)];
  }
  return c;
}

}  // namespace hof::scene
