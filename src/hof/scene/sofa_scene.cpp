#include "hof/scene/sofa_scene.h"
#include "hof/mesh/xml_depth.h"

#include <fmt/ranges.h>

#include <algorithm>
#include <charconv>
#include <cmath>
#include <cstdlib>
#include <fstream>
#include <map>
#include <numbers>
#include <sstream>

#include "hof/mesh/mesh_io.h"
#include "hof/scene/sofa_components.h"
#include "hof/scene/sofa_scene_reader.h"

namespace hof::scene::detail {
namespace {

// 2008 aliases and today's renames (sofa-components.md). MeshLoader is decided by extension.
const std::map<std::string, std::string, std::less<>>& alias_table() {
  static const std::map<std::string, std::string, std::less<>> table{
      {"EulerImplicit", "EulerImplicitSolver"},
      {"ImplicitEulerSolver", "EulerImplicitSolver"},
      {"ImplicitEuler", "EulerImplicitSolver"},
      {"CGImplicit", "CGImplicitSolver"},
      {"Euler", "EulerExplicitSolver"},
      {"EulerSolver", "EulerExplicitSolver"},
      {"RungeKutta4", "RungeKutta4Solver"},
      {"CGSolver", "CGLinearSolver"},
      {"ConjugateGradient", "CGLinearSolver"},
      {"Mesh", "MeshTopology"},
      {"FixedConstraint", "FixedProjectiveConstraint"},
      {"PartialFixedConstraint", "PartialFixedProjectiveConstraint"},
      {"TetrahedralCorotationalFEMForceField", "TetrahedronFEMForceField"},
      {"MeshObjLoader", "MeshOBJLoader"},
      {"VisualModel", "OglModel"},
      {"VisualModelImpl", "OglModel"},
      {"StiffSpringForceField", "SpringForceField"},
  };
  return table;
}

std::vector<std::string_view> value_tokens(std::string_view s) {
  std::vector<std::string_view> out;
  std::size_t i = 0;
  while (i < s.size()) {
    while (i < s.size() && (std::isspace(static_cast<unsigned char>(s[i])) || s[i] == ',')) ++i;
    const std::size_t start = i;
    while (i < s.size() && !std::isspace(static_cast<unsigned char>(s[i])) && s[i] != ',') ++i;
    if (i > start) out.push_back(s.substr(start, i - start));
  }
  return out;
}

}  // namespace

bool is_ode_solver(std::string_view t) {
  return t == "EulerImplicitSolver" || t == "CGImplicitSolver" || t == "EulerExplicitSolver" ||
         t == "RungeKutta4Solver" || t == "StaticSolver";
}
bool is_linear_solver(std::string_view t) {
  return t == "CGLinearSolver" || t == "SparseLDLSolver" || t == "EigenSimplicialLDLT";
}
bool is_loader(std::string_view t) {
  return t == "MeshGmshLoader" || t == "MeshOBJLoader" || t == "MeshLoader" || t == "MeshSTLLoader" ||
         t == "MeshOffLoader";
}
bool is_topology(std::string_view t) {
  return t == "MeshTopology" || t == "TetrahedronSetTopologyContainer" || t == "TriangleSetTopologyContainer";
}
bool is_mapping(std::string_view t) { return t.ends_with("Mapping"); }

// A state of 3D points. SofaCUDA's templates (CudaVec3f, CudaVec3d and the padded CudaVec3f1)
// hold the same points on the GPU in single or double precision: HoF simulates them as the CPU
// scene does, in double precision, so a CUDA scene is the CPU scene here and nothing is lost.
bool is_vec3_template(std::string_view t) {
  return t == "Vec3" || t == "Vec3d" || t == "Vec3f" || t == "CudaVec3f" || t == "CudaVec3d" || t == "CudaVec3f1" ||
         t == "CudaVec3d1";
}

std::string_view trim(std::string_view s) {
  while (!s.empty() && std::isspace(static_cast<unsigned char>(s.front()))) s.remove_prefix(1);
  while (!s.empty() && std::isspace(static_cast<unsigned char>(s.back()))) s.remove_suffix(1);
  return s;
}

std::string lower(std::string s) {
  std::ranges::transform(s, s.begin(), [](unsigned char c) { return static_cast<char>(std::tolower(c)); });
  return s;
}

Expected<SofaScene> Reader::run() {
  scene_.file = path_;
  if (!have_text_) {
    std::ifstream in(path_, std::ios::binary);
    if (!in) return make_error(ErrorCode::kIo, fmt::format("cannot open scene '{}'", path_.string()), path_.string());
    std::ostringstream ss;
    ss << in.rdbuf();
    text_ = ss.str();
  }
  line_starts_.push_back(0);
  for (std::size_t i = 0; i < text_.size(); ++i)
    if (text_[i] == '\n') line_starts_.push_back(i + 1);

  pugi::xml_document doc;
  const pugi::xml_parse_result parsed =
      doc.load_buffer(text_.data(), text_.size(), pugi::parse_default, pugi::encoding_utf8);
  if (!parsed)
    return fail(ErrorCode::kParse, line_of(parsed.offset), fmt::format("malformed XML: {}", parsed.description()));
  if (const pugi::xml_node deep = mesh::first_too_deep_element(doc))
    return fail(ErrorCode::kParse, line_of(deep.offset_debug()),
                fmt::format("<{}> is nested deeper than {} levels", deep.name(), mesh::kMaxXmlDepth));
  pugi::xml_node xml_root = doc.document_element();
  // A HoF project carries its scene inline: <hof><mechanics><Node …>, or, in the thesis'
  // appendix format, <hof><sofa><sg><Node …>.
  if (std::string_view(xml_root.name()) == "hof") {
    pugi::xml_node inner = xml_root.child("mechanics").child("Node");
    if (!inner) {
      inner = xml_root.child("sofa").child("sg").child("Node");
      thesis_format_ = static_cast<bool>(inner);
    }
    if (!inner)
      return fail(ErrorCode::kParse, line_of(xml_root.offset_debug()),
                  "the project has no inline scene (<mechanics><Node> or <sofa><sg><Node>)");
    xml_root = inner;
  }
  if (std::string_view(xml_root.name()) != "Node")
    return fail(ErrorCode::kParse, line_of(xml_root.offset_debug()),
                fmt::format("the root element is <{}>, expected <Node>", xml_root.name()));

  root_ = std::make_unique<SceneNode>();
  if (auto r = build_node(xml_root, *root_); !r) return std::unexpected(r.error());
  if (auto r = check_types_and_attributes(); !r) return std::unexpected(r.error());
  if (auto r = collect_models(*root_); !r) return std::unexpected(r.error());
  if (auto r = read_contacts(*root_); !r) return std::unexpected(r.error());
  if (scene_.contacts.enabled && !models_without_surface_.empty()) {
    const Component& c = *models_without_surface_.front();
    return fail(c,
                "a collision model on a body with no surface: its node has no triangles (give it a triangle "
                "topology or a mesh loader), and the scene's collision pipeline asks for contact",
                ErrorCode::kInvalidArgument);
  }
  list_skipped(*root_);
  // Each component not simulated is named once: those that change SOFA's result have a warning
  // of their own (list_skipped); the others are listed here together.
  std::string others;
  std::size_t count = 0;
  for (const auto& s : scene_.skipped) {
    if (std::ranges::any_of(scene_.warnings, [&](const std::string& w) { return w.find(s) != std::string::npos; }))
      continue;
    others += (others.empty() ? "" : ", ") + s;
    ++count;
  }
  if (count) {
    scene_.warnings.push_back(
        fmt::format("{}: {} component(s) not simulated by HoF and skipped: {}", path_.string(), count, others));
  }
  if (scene_.models.empty()) warn(root_->line, "no simulated model (a Node with an ODE solver and a MechanicalObject)");
  return std::move(scene_);
}

// Builds the node tree: Node attributes inherit dt and gravity; `<Object type=X>` becomes X.
Expected<void> Reader::build_node(const pugi::xml_node& xml, SceneNode& node) {
  node.line = line_of(xml.offset_debug());
  node.name = xml.attribute("name") ? xml.attribute("name").value() : "Node";
  node.path = node.parent ? node.parent->path + "/" + node.name : node.name;
  if (node.parent) {
    node.dt_s = node.parent->dt_s;
    node.gravity = node.parent->gravity;
  }
  for (const char* old_flag : {"showBehaviorModels", "showCollisionModels", "showMappings", "showForceFields"})
    if (xml.attribute(old_flag)) legacy_ = true;
  // dt and gravity are parsed through a stand-in component so errors read the same.
  Component node_as_component;
  node_as_component.type = node_as_component.written = "Node";
  node_as_component.name = node.name;
  node_as_component.line = node.line;
  for (const pugi::xml_attribute& a : xml.attributes()) node_as_component.attrs.emplace_back(a.name(), a.value());
  if (auto dt = number(node_as_component, "dt"); !dt)
    return std::unexpected(dt.error());
  else if (*dt)
    node.dt_s = **dt;
  if (auto g = vec3(node_as_component, "gravity"); !g)
    return std::unexpected(g.error());
  else if (*g)
    node.gravity = **g;

  for (const pugi::xml_node& child : xml.children()) {
    if (child.type() != pugi::node_element) continue;
    const std::string_view tag = child.name();
    if (tag == "Node") {
      auto sub = std::make_unique<SceneNode>();
      sub->parent = &node;
      if (auto r = build_node(child, *sub); !r) return r;
      node.children.push_back(std::move(sub));
      continue;
    }
    auto c = std::make_unique<Component>();
    c->line = line_of(child.offset_debug());
    if (tag == "Object") {
      legacy_ = true;
      if (!child.attribute("type")) return fail(ErrorCode::kParse, c->line, "<Object> without a 'type' attribute");
      c->written = child.attribute("type").value();
    } else {
      c->written = std::string(tag);
    }
    for (const pugi::xml_attribute& a : child.attributes()) {
      if (tag == "Object" && std::string_view(a.name()) == "type") continue;
      c->attrs.emplace_back(a.name(), a.value());
    }
    if (c->written == "EulerImplicit" || c->written == "CGImplicit" || c->written == "CGImplicitSolver" ||
        c->written == "MeshLoader")
      legacy_ = true;
    const auto alias = alias_table().find(c->written);
    c->type = alias != alias_table().end() ? alias->second : c->written;
    if (const std::string* n = c->attr("name"))
      c->name = *n;
    else if (const std::string* p = c->attr("pluginName"))
      c->name = *p;
    else
      c->name = c->written;
    c->node = &node;
    c->index = node.components.size();
    node.components.push_back(std::move(c));
  }
  return {};
}

// ---- what SOFA would create -------------------------------------------------------------------

namespace {

// A plugin from outside SOFA's own repository: its component types are not in HoF's table.
// SOFA's modules are "Sofa.Component.X" (today) or "SofaBaseMechanics"-style (v20-v22); the
// few plugin packs whose names also begin with "Sofa" are listed.
bool is_external_plugin(std::string_view name) {
  static constexpr std::string_view kExternalSofaNamed[] = {"SofaPython",        "SofaPython3",  "SofaCUDA",
                                                            "SofaCarving",       "SofaSphFluid", "SofaDistanceGrid",
                                                            "SofaImplicitField", "SofaOpenCL",   "SofaAssimp"};
  if (std::ranges::find(kExternalSofaNamed, name) != std::end(kExternalSofaNamed)) return true;
  return !name.starts_with("Sofa");
}

// Attributes SOFA's parse() takes besides its data (older names it converts), and HoF's own
// additions to a component; never warned about.
bool is_accepted_extra_attribute(std::string_view type, std::string_view key) {
  // The factory's own (type, template), src="@loader", and SOFA's deprecated isCompliance.
  if (key == "name" || key == "template" || key == "type" || key == "src" || key == "isCompliance") return true;
  // Geometry HoF reads on any component that has it (compute_data): it is not ignored here.
  static constexpr std::string_view kGeometry[] = {"filename",   "fileMesh", "position",
                                                   "tetrahedra", "tetras",   "triangles"};
  if (std::ranges::find(kGeometry, key) != std::end(kGeometry)) return true;
  if (key == "coarseCorrection" || key == "coarseRefreshSteps")
    return type == "CGLinearSolver";                                           // HoF's CG preconditioner
  if (type.ends_with("Mapping")) return key == "object1" || key == "object2";  // input/output before v1.0
  if (type == "MechanicalObject" || type == "OglModel" || type == "VisualModel" || type == "VisualModelImpl") {
    static constexpr std::string_view kLegacyTransform[] = {"dx", "dy",    "dz", "rx", "ry",
                                                            "rz", "scale", "sx", "sy", "sz"};
    return std::ranges::find(kLegacyTransform, key) != std::end(kLegacyTransform);
  }
  if (is_loader(type)) return key == "scale";
  return false;
}

}  // namespace

// SOFA refuses a type its factory does not know ("Object type X was not created") and warns
// about data no component takes: so does HoF, with the closest names. A scene that requires a
// plugin from outside SOFA may name that plugin's components: those are named in a warning.
Expected<void> Reader::check_types_and_attributes() {
  std::vector<std::string> external_plugins;
  std::vector<const Component*> all;
  const auto collect = [&](const auto& self, const SceneNode& node) -> void {
    for (const auto& c : node.components) {
      all.push_back(c.get());
      if (c->type == "RequiredPlugin") {
        // pluginName lists the plugins (SOFA's vector data); without it the name is the plugin.
        std::vector<std::string> plugins;
        if (const std::string* list = c->attr("pluginName")) {
          for (std::string_view one : value_tokens(*list)) plugins.emplace_back(one);
        } else if (const std::string* name = c->attr("name")) {
          plugins.emplace_back(trim(*name));
        }
        for (const std::string& plugin : plugins)
          if (is_external_plugin(plugin) && std::ranges::find(external_plugins, plugin) == external_plugins.end())
            external_plugins.push_back(plugin);
      }
    }
    for (const auto& child : node.children) self(self, *child);
  };
  collect(collect, *root_);
  // The thesis' appendix format ran SOFA with the thesis' own components (ExternalForceField
  // carried the touch force from H3D; HoF's coupling does that job).
  if (thesis_format_) external_plugins.emplace_back("the thesis' SOFA-H3D glue");
  std::vector<std::string> unknown_from_plugins;
  for (const Component* c : all) {
    if (is_known_sofa_component(c->written) || is_known_sofa_component(c->type)) continue;
    if (!external_plugins.empty()) {
      unknown_from_plugins.push_back(c->label());
      continue;
    }
    const std::vector<std::string> near = closest_names(c->written, known_sofa_components());
    return fail(
        ErrorCode::kParse, c->line,
        fmt::format("unknown component type '{}': SOFA has no such component (\"Object type {} was not created\"){}",
                    c->written, c->written,
                    near.empty() ? std::string("; check its spelling")
                                 : fmt::format("; did you mean {}?", fmt::join(near, ", "))));
  }
  if (!unknown_from_plugins.empty()) {
    warn(root_->line,
         fmt::format("{} component(s) of a type HoF does not know, presumably from the plugin(s) the scene "
                     "requires ({}), are not simulated: {}",
                     unknown_from_plugins.size(), fmt::join(external_plugins, ", "),
                     fmt::join(unknown_from_plugins, ", ")));
  }
  // Attributes: checked where HoF has the component's data names (the components it reads),
  // in today's syntax (a 2008 scene's data had other names, which SOFA then took).
  if (legacy_) return {};
  for (const Component* c : all) {
    const std::span<const std::string_view> data = sofa_data_names(c->type);
    if (data.empty()) continue;
    for (const auto& [key, value] : c->attrs) {
      if (std::ranges::binary_search(data, std::string_view(key)) || is_accepted_extra_attribute(c->type, key))
        continue;
      const std::vector<std::string> near = closest_names(key, data, 1);
      warn(c->line,
           fmt::format("{}: attribute '{}' is not a data of {} and is ignored (SOFA ignores it too){}", c->label(), key,
                       c->type, near.empty() ? std::string() : fmt::format("; did you mean '{}'?", near.front())));
    }
  }
  return {};
}

// ---- attribute values -------------------------------------------------------------------------

Expected<std::vector<double>> Reader::numbers(const Component& c, std::string_view key, const std::string& text) const {
  std::vector<double> out;
  for (std::string_view tok : value_tokens(text)) {
    double v = 0.0;
    const auto [ptr, ec] = std::from_chars(tok.data(), tok.data() + tok.size(), v);
    if (ec != std::errc{} || ptr != tok.data() + tok.size() || !std::isfinite(v))
      return fail(c, fmt::format("attribute {}: '{}' is not a number", key, tok));
    out.push_back(v);
  }
  return out;
}

Expected<std::optional<double>> Reader::number(const Component& c, std::string_view key) const {
  const std::string* text = c.attr(key);
  if (!text) return std::optional<double>{};
  auto v = numbers(c, key, *text);
  if (!v) return std::unexpected(v.error());
  if (v->empty()) return fail(c, fmt::format("attribute {}: empty, expected a number", key));
  if (v->size() > 1 && std::ranges::any_of(*v, [&](double x) { return x != v->front(); }))
    return fail(c, fmt::format("attribute {}: {} different values; HoF takes one value per component", key, v->size()),
                ErrorCode::kUnsupported);
  return std::optional<double>{v->front()};
}

Expected<std::optional<Vec3>> Reader::vec3(const Component& c, std::string_view key) const {
  const std::string* text = c.attr(key);
  if (!text) return std::optional<Vec3>{};
  auto v = numbers(c, key, *text);
  if (!v) return std::unexpected(v.error());
  if (v->size() != 3) return fail(c, fmt::format("attribute {}: expected 3 numbers, got {}", key, v->size()));
  return std::optional<Vec3>{Vec3((*v)[0], (*v)[1], (*v)[2])};
}

Expected<std::optional<std::vector<std::int32_t>>> Reader::indices(const Component& c, std::string_view key) const {
  const std::string* text = c.attr(key);
  if (!text) return std::optional<std::vector<std::int32_t>>{};
  std::vector<std::int32_t> out;
  for (std::string_view tok : value_tokens(*text)) {
    std::int32_t v = 0;
    const auto [ptr, ec] = std::from_chars(tok.data(), tok.data() + tok.size(), v);
    if (ec != std::errc{} || ptr != tok.data() + tok.size() || v < 0)
      return fail(c, fmt::format("attribute {}: '{}' is not an index", key, tok));
    out.push_back(v);
  }
  return std::optional<std::vector<std::int32_t>>{std::move(out)};
}

Expected<std::optional<bool>> Reader::boolean(const Component& c, std::string_view key) const {
  const std::string* text = c.attr(key);
  if (!text) return std::optional<bool>{};
  const std::string v = lower(std::string(trim(*text)));
  if (v == "1" || v == "true") return std::optional<bool>{true};
  if (v == "0" || v == "false") return std::optional<bool>{false};
  return fail(c, fmt::format("attribute {}: '{}' is not a boolean (0/1/true/false)", key, *text));
}

// ---- models -----------------------------------------------------------------------------------

Expected<void> Reader::collect_models(SceneNode& node) {
  Component* state = nullptr;
  bool mapped = false;
  bool own_solver = false;
  bool geometry = false;
  for (auto& c : node.components) {
    if (c->type == "MechanicalObject" && !state) state = c.get();
    mapped = mapped || is_mapping(c->type);
    own_solver = own_solver || is_ode_solver(c->type);
    geometry = geometry || is_topology(c->type) || (is_loader(c->type) && c->type != "MeshOBJLoader");
  }
  if (state) {
    if (const std::string* tmpl = state->attr("template"); tmpl && !is_vec3_template(*tmpl)) {
      node.not_simulated_why = fmt::format("its MechanicalObject has template {}, which HoF does not simulate", *tmpl);
      warn(state->line, fmt::format("{}: template {} is not simulated (HoF simulates 3D points: Vec3d, Vec3f and "
                                    "SofaCUDA's CudaVec3f/CudaVec3d); node '{}' is not a body",
                                    state->label(), *tmpl, node.path));
      state = nullptr;
    }
  }
  bool solver_in_scope = own_solver;
  for (SceneNode* n = node.parent; n && !solver_in_scope; n = n->parent)
    solver_in_scope = std::ranges::any_of(n->components, [](const auto& c) { return is_ode_solver(c->type); });
  if (!mapped && ((state && solver_in_scope) || (!state && own_solver && geometry))) {
    auto model = make_model(node, state);
    if (!model) return std::unexpected(model.error());
    scene_.models.push_back(std::move(*model));
    simulated_nodes_.insert(&node);
  } else if (!mapped && !solver_in_scope) {
    // Nothing moves it: a triangle collision model here is a rigid obstacle.
    auto obstacle = make_obstacle(node, state);
    if (!obstacle) return std::unexpected(obstacle.error());
    if (*obstacle) scene_.obstacles.push_back(std::move(**obstacle));
  }
  for (auto& child : node.children)
    if (auto r = collect_models(*child); !r) return r;
  return {};
}

namespace {

// Components with no counterpart needed in HoF: they change nothing it simulates.
bool needs_no_counterpart(std::string_view type) {
  static constexpr std::string_view kTypes[] = {"RequiredPlugin",
                                                "DefaultAnimationLoop",
                                                "DefaultVisualManagerLoop",
                                                "VisualStyle",
                                                "InteractiveCamera",
                                                "Camera",
                                                "LightManager",
                                                "DirectionalLight",
                                                "PositionalLight",
                                                "SpotLight",
                                                "BackgroundSetting",
                                                "OglSceneFrame",
                                                "OglGrid",
                                                "OglLabel",
                                                "AttachBodyButtonSetting",
                                                "FixedPlaneConstraintSetting",
                                                "OglModel",
                                                "VisualModel",
                                                "OglShader",
                                                "MeshOBJLoader",
                                                "VisualGrid",
                                                "LineAxis"};
  return std::ranges::find(kTypes, type) != std::end(kTypes);
}

// Why a component HoF does not simulate changes SOFA's result ("" when it does not).
std::string_view what_changes(std::string_view type) {
  if (type.ends_with("CollisionModel") || type == "CubeModel" || type == "TriangleOctreeModel") {
    // HoF's own kinds left unused: their node is no body, obstacle or node mapped from a body.
    if (type.ends_with("CollisionModel") && (type.starts_with("Triangle") || type.starts_with("Line") ||
                                             type.starts_with("Point") || type.starts_with("Sphere"))) {
      return "its node is not a body, an obstacle with triangles, or a node mapped from a body (a mapping to "
             "the body's state); this model collides nothing";
    }
    return "HoF detects contact with triangle, line, point and sphere models only; this shape does not collide";
  }
  if (type.ends_with("Intersection"))
    return "HoF does not have this intersection method (it has SOFA's discrete and proximity ones)";
  if (type == "FreeMotionAnimationLoop" || type.ends_with("ConstraintSolver") ||
      type.ends_with("ConstraintCorrection")) {
    return "constraint-based contacts and constraints are not solved";
  }
  if (type.find("ForceField") != std::string_view::npos) return "its forces are missing from the body";
  if (type.find("Constraint") != std::string_view::npos) return "its constraint is missing";
  if (type.find("Mapping") != std::string_view::npos) return "what it maps does not follow the body";
  if (type.ends_with("Mass")) return "a second mass is not added";
  return {};
}

}  // namespace

// Why a node is not a body: its own state's reason, or (a node mapped from it, such as a rigid
// instrument's collision or visual model) an ancestor's; empty when neither says.
std::string_view Reader::not_simulated_why(const SceneNode& node) const {
  for (const SceneNode* n = &node; n; n = n->parent) {
    if (!n->not_simulated_why.empty()) return n->not_simulated_why;
    if (simulated_nodes_.contains(n)) return {};
  }
  return {};
}

void Reader::list_skipped(const SceneNode& node) {
  for (const auto& c : node.components) {
    if (c->used) continue;
    if (needs_no_counterpart(c->type)) {
      scene_.ignored.push_back(c->label());
      continue;
    }
    scene_.skipped.push_back(c->label());
    // The node is not a body (its state is rigid, 1D, ...): its components are skipped with it,
    // and the state's own warning says why once; "a second mass" or "missing forces" would not
    // be true of them.
    if (!not_simulated_why(node).empty()) continue;
    // A mass in a node that holds no body of HoF's is not a second mass of anything.
    if (c->type.ends_with("Mass") && !simulated_nodes_.contains(&node)) {
      warn(c->line, fmt::format("{} changes SOFA's result and is not simulated by HoF: node '{}' is not a simulated "
                                "body (no ODE solver above it, or its state is mapped)",
                                c->label(), node.path));
      continue;
    }
    // A mapping that carries a collision model (SOFA's collision spheres) is part of that model.
    // (Collision models under today's names and the older ones: SphereModel, Sphere, ...)
    static constexpr std::string_view kOlderCollisionModels[] = {
        "Sphere",    "SphereModel", "Triangle",   "TriangleModel", "TTriangleModel",    "Line",
        "LineModel", "Point",       "PointModel", "CubeModel",     "TriangleMeshModel", "TriangleSetModel"};
    const bool carries_collision =
        c->type.find("Mapping") != std::string::npos && std::ranges::any_of(node.components, [](const auto& o) {
          return o->type.ends_with("CollisionModel") ||
                 std::ranges::find(kOlderCollisionModels, o->type) != std::end(kOlderCollisionModels);
        });
    // With friction contacts, the constraint solver and its corrections are what SOFA solves the
    // contacts with; HoF solves them as penalty contacts, which those settings do not tune.
    const bool contact_constraints = scene_.contacts.enabled &&
                                     scene_.contacts.response == coupling::ContactResponse::kFrictionConstraint &&
                                     (c->type == "FreeMotionAnimationLoop" || c->type.ends_with("ConstraintSolver") ||
                                      c->type.ends_with("ConstraintCorrection"));
    if (contact_constraints) {
      warn(c->line, fmt::format("{} is not used by HoF: the contacts are solved as penalty contacts (constraint "
                                "contacts are next), which its settings do not tune",
                                c->label()));
      continue;
    }
    if (const std::string_view why = what_changes(c->type); !why.empty() && !carries_collision) {
      warn(c->line, fmt::format("{} changes SOFA's result and is not simulated by HoF: {}", c->label(), why));
    }
  }
  for (const auto& child : node.children) list_skipped(*child);
}

}  // namespace hof::scene::detail

namespace hof::scene {

Expected<SofaScene> read_sofa_scene(const std::filesystem::path& path) { return detail::Reader(path).run(); }

std::vector<std::filesystem::path> sofa_data_folders(const std::filesystem::path& scene_folder) {
  namespace fs = std::filesystem;
  std::vector<fs::path> out;
  std::error_code ec;
  const auto add = [&](const fs::path& dir) {
    if (dir.empty() || !fs::is_directory(dir, ec)) return;
    const fs::path normal = dir.lexically_normal();
    if (std::ranges::find(out, normal) == out.end()) out.push_back(normal);
  };
  for (fs::path dir = scene_folder;; dir = dir.parent_path()) {
    add(dir);
    if (dir == dir.parent_path() || dir.empty()) break;
  }
  if (const char* list = std::getenv("SOFA_DATA_PATH")) {
    std::string_view rest(list);
    while (!rest.empty()) {
      const std::size_t colon = rest.find(':');
      add(fs::path(std::string(rest.substr(0, colon))));
      if (colon == std::string_view::npos) break;
      rest.remove_prefix(colon + 1);
    }
  }
  if (const char* root = std::getenv("SOFA_ROOT"); root && *root) {
    add(fs::path(root) / "share");
    add(fs::path(root) / "examples");
  }
  return out;
}

Expected<SofaScene> read_sofa_scene_text(const std::string& text, const std::filesystem::path& path) {
  return detail::Reader(path, text).run();
}

}  // namespace hof::scene
