#include <algorithm>
#include <array>
#include <cmath>

#include <fmt/format.h>
#include <fmt/ranges.h>

#include "hof/mesh/sphere_file.h"
#include "hof/scene/sofa_components.h"
#include "hof/scene/sofa_scene_reader.h"

// Contact between bodies as a SOFA scene declares it: the collision pipeline (CollisionPipeline
// with a broad and a narrow phase), the intersection method (its alarm and contact distances),
// the response (CollisionResponse: penalty or friction constraints), and each body's collision
// models (Triangle/Line/Point/SphereCollisionModel and SOFA's older names for them). SOFA's
// names and defaults: its CollisionModel (contactStiffness 10, moving and simulated true,
// selfCollision false), BaseProximityIntersection (alarmDistance 1, contactDistance 0.5), and
// DiscreteIntersection (no distance: contact only where the shapes overlap).

namespace hof::scene::detail {

namespace {

// Collision models under today's names and the older ones SOFA still reads.
constexpr std::array kTriangleModels = {std::string_view("TriangleCollisionModel"),
                                        std::string_view("TriangleModel"),
                                        std::string_view("Triangle"),
                                        std::string_view("TTriangleModel"),
                                        std::string_view("TriangleMeshModel"),
                                        std::string_view("TriangleSetModel")};
constexpr std::array kLineModels = {std::string_view("LineCollisionModel"), std::string_view("LineModel"),
                                    std::string_view("Line"), std::string_view("LineMeshModel"),
                                    std::string_view("LineSetModel")};
constexpr std::array kPointModels = {std::string_view("PointCollisionModel"), std::string_view("PointModel"),
                                     std::string_view("Point"), std::string_view("PointMeshModel"),
                                     std::string_view("PointSetModel")};
constexpr std::array kSphereModels = {std::string_view("SphereCollisionModel"), std::string_view("SphereModel"),
                                      std::string_view("Sphere"), std::string_view("TSphereModel")};

template <std::size_t N>
bool among(const std::array<std::string_view, N>& names, std::string_view type) {
  return std::ranges::find(names, type) != names.end();
}

bool is_collision_model(std::string_view type) {
  return among(kTriangleModels, type) || among(kLineModels, type) || among(kPointModels, type) ||
         among(kSphereModels, type);
}

// The pipeline and its detection stages: HoF has its own (bound trees refitted each step, one
// broad phase over every body), which finds the same pairs.
constexpr std::array kPipelines = {std::string_view("CollisionPipeline"), std::string_view("DefaultPipeline")};
constexpr std::array kDetections = {
    std::string_view("BruteForceBroadPhase"),         std::string_view("BVHNarrowPhase"),
    std::string_view("BruteForceDetection"),          std::string_view("BruteForce"),
    std::string_view("ParallelBruteForceBroadPhase"), std::string_view("ParallelBVHNarrowPhase")};
// Intersection methods with an alarm and a contact distance (SOFA's BaseProximityIntersection).
constexpr std::array kProximityIntersections = {
    std::string_view("MinProximityIntersection"), std::string_view("LocalMinDistance"),
    std::string_view("NewProximityIntersection"), std::string_view("LMDNewProximityIntersection")};
constexpr double kSofaAlarmDistance = 1.0;      // BaseProximityIntersection's alarmDistance
constexpr double kSofaContactDistance = 0.5;    // BaseProximityIntersection's contactDistance
constexpr double kSofaContactStiffness = 10.0;  // CollisionModel's contactStiffness
constexpr std::array kResponseManagers = {
    std::string_view("CollisionResponse"), std::string_view("DefaultContactManager"),
    std::string_view("RuleBasedContactManager"), std::string_view("RuleBasedCollisionResponse")};

// CollisionResponse `response` names: what HoF solves for each.
constexpr std::array kPenaltyResponses = {std::string_view("PenalityContactForceField"), std::string_view("default"),
                                          std::string_view("BarycentricPenalityContact")};
constexpr std::array kFrictionResponses = {std::string_view("FrictionContactConstraint"),
                                           std::string_view("FrictionContact")};
// SOFA responses HoF does not have: solved as penalty contacts, and said so.
constexpr std::array kOtherResponses = {
    std::string_view("StickContactConstraint"),        std::string_view("stick"),
    std::string_view("BarycentricStickContact"),       std::string_view("AttachBodyConstraint"),
    std::string_view("RegistrationContactForceField"), std::string_view("registration"),
    std::string_view("distanceLMConstraint")};

}  // namespace

Expected<void> Reader::read_contacts(SceneNode& root) {
  coupling::ContactSettings& s = scene_.contacts;
  s.stiffness_n_per_m = kSofaContactStiffness;
  Component* pipeline = nullptr;
  Component* response = nullptr;
  Component* intersection = nullptr;
  std::vector<SceneNode*> pending{&root};
  while (!pending.empty()) {
    SceneNode* node = pending.back();
    pending.pop_back();
    for (auto& child : node->children) pending.push_back(child.get());
    for (auto& c : node->components) {
      const std::string& t = c->type;
      if (among(kPipelines, t)) {
        if (!pipeline) pipeline = c.get();
        c->used = true;
      } else if (among(kDetections, t)) {
        c->used = true;
      } else if (among(kProximityIntersections, t) || t == "DiscreteIntersection") {
        if (intersection) {
          warn(c->line, fmt::format("{}: a second intersection method; {} is used", c->label(), intersection->label()));
        } else {
          intersection = c.get();
        }
        c->used = true;
      } else if (among(kResponseManagers, t)) {
        if (!response) response = c.get();
        c->used = true;
      }
    }
  }
  // Distances: the proximity methods' (SOFA's defaults when absent), none for DiscreteIntersection.
  if (intersection && intersection->type != "DiscreteIntersection") {
    auto alarm = number(*intersection, "alarmDistance");
    if (!alarm) return std::unexpected(alarm.error());
    auto contact = number(*intersection, "contactDistance");
    if (!contact) return std::unexpected(contact.error());
    s.alarm_distance_m = alarm->value_or(kSofaAlarmDistance);
    s.contact_distance_m = contact->value_or(kSofaContactDistance);
    if (s.alarm_distance_m < 0.0)
      return fail(*intersection, fmt::format("alarmDistance {} is negative", s.alarm_distance_m),
                  ErrorCode::kInvalidArgument);
    if (s.contact_distance_m < 0.0)
      return fail(*intersection, fmt::format("contactDistance {} is negative", s.contact_distance_m),
                  ErrorCode::kInvalidArgument);
    if (s.contact_distance_m > s.alarm_distance_m) {
      return fail(*intersection,
                  fmt::format("contactDistance {} is larger than alarmDistance {} (pairs are detected within the "
                              "alarm distance, so the contact distance must not exceed it)",
                              s.contact_distance_m, s.alarm_distance_m),
                  ErrorCode::kInvalidArgument);
    }
  }
  if (response) {
    const std::string* name = response->attr("response");
    const std::string written = name ? std::string(trim(*name)) : std::string("default");
    if (among(kPenaltyResponses, written)) {
      s.response = coupling::ContactResponse::kPenalty;
    } else if (among(kFrictionResponses, written)) {
      s.response = coupling::ContactResponse::kFrictionConstraint;
      warn(response->line, fmt::format("{}: response {} is solved as penalty contacts (Coulomb friction from mu); "
                                       "constraint contacts are next",
                                       response->label(), written));
    } else if (among(kOtherResponses, written)) {
      s.response = coupling::ContactResponse::kPenalty;
      warn(response->line, fmt::format("{}: response {} is not simulated by HoF; the contacts are penalty contacts "
                                       "(PenalityContactForceField)",
                                       response->label(), written));
    } else {
      std::vector<std::string_view> known(kPenaltyResponses.begin(), kPenaltyResponses.end());
      known.insert(known.end(), kFrictionResponses.begin(), kFrictionResponses.end());
      known.insert(known.end(), kOtherResponses.begin(), kOtherResponses.end());
      std::ranges::sort(known);
      const std::vector<std::string> close = closest_names(written, known);
      return fail(*response, fmt::format("attribute response: unknown response '{}'{}", written,
                                         close.empty() ? fmt::format(" (known: {})", fmt::join(known, ", "))
                                                       : fmt::format("; did you mean {}?", fmt::join(close, ", "))));
    }
    // responseParams: "mu=0.8" (SOFA joins several with '&').
    if (const std::string* params = response->attr("responseParams")) {
      std::string_view rest = trim(*params);
      while (!rest.empty()) {
        const std::size_t amp = rest.find('&');
        const std::string_view item = trim(rest.substr(0, amp));
        rest = amp == std::string_view::npos ? std::string_view() : rest.substr(amp + 1);
        const std::size_t eq = item.find('=');
        if (item.empty() || eq == std::string_view::npos) continue;
        if (trim(item.substr(0, eq)) != "mu") continue;
        auto mu = numbers(*response, "responseParams", std::string(item.substr(eq + 1)));
        if (!mu) return std::unexpected(mu.error());
        if (mu->size() != 1 || mu->front() < 0.0) {
          return fail(*response,
                      fmt::format("attribute responseParams: mu '{}' is not a friction coefficient ≥ 0",
                                  std::string(item.substr(eq + 1))),
                      ErrorCode::kInvalidArgument);
        }
        s.friction = mu->front();
      }
    }
    if (response->type.starts_with("RuleBased") && response->attr("rules")) {
      warn(response->line, fmt::format("{}: its rules are not simulated by HoF; every pair of bodies gets response {}",
                                       response->label(), written));
    }
  }
  // SOFA detects nothing without a pipeline and responds to nothing without a response.
  s.enabled = pipeline && response;
  if (pipeline && !response) {
    warn(pipeline->line, fmt::format("{}: no CollisionResponse in the scene; as in SOFA, bodies do not respond to "
                                     "contact (they pass through each other)",
                                     pipeline->label()));
  } else if (response && !pipeline) {
    warn(response->line, fmt::format("{}: no CollisionPipeline in the scene; as in SOFA, no contact is detected "
                                     "(bodies pass through each other)",
                                     response->label()));
  }
  if (s.enabled && !intersection) {
    warn(pipeline->line, fmt::format("{}: no intersection method; HoF takes DiscreteIntersection's (contact only "
                                     "where the surfaces overlap: alarm and contact distances 0)",
                                     pipeline->label()));
  }
  return {};
}

Expected<coupling::BodyCollision> Reader::body_collision(SceneNode& node, bool has_surface, bool rigid) {
  coupling::BodyCollision out;
  out.triangles = out.lines = out.points = false;
  // The body's node, then (deformable bodies) the nodes mapped from it, however deep.
  std::vector<SceneNode*> nodes{&node};
  if (!rigid) {
    for (std::size_t i = 0; i < nodes.size(); ++i)
      for (auto& child : nodes[i]->children) {
        const bool mapped = std::ranges::any_of(child->components, [](const auto& c) { return is_mapping(c->type); });
        const bool own_solver =
            std::ranges::any_of(child->components, [](const auto& c) { return is_ode_solver(c->type); });
        if (mapped && !own_solver) nodes.push_back(child.get());
      }
  }
  std::optional<bool> moving, simulated, self_collision;
  std::optional<double> stiffness;
  std::optional<std::int32_t> group;
  for (SceneNode* n : nodes) {
    const bool mapped_node = n != &node;
    bool node_has_models = false;
    for (auto& owned : n->components) {
      Component& c = *owned;
      if (!is_collision_model(c.type)) continue;
      node_has_models = true;
      c.used = true;
      out.enabled = true;
      if (among(kSphereModels, c.type)) {
        if (auto r = read_spheres(*n, c, out); !r) return std::unexpected(r.error());
      } else {
        // A triangle, line or point model collides the body's surface: it needs one.
        bool node_surface = !mapped_node;
        for (const auto& o : n->components)
          node_surface = node_surface || is_topology(o->type) || o->type.ends_with("TopologyContainer") ||
                         is_loader(o->type) || o->type.ends_with("TopologicalMapping");
        if (!has_surface || !node_surface) {
          return fail(
              c,
              fmt::format("a collision model on a body with no surface: {} (give the node a triangle "
                          "topology, a Tetra2TriangleTopologicalMapping or a mesh loader)",
                          mapped_node ? fmt::format("node '{}' has no topology, loader or topological "
                                                    "mapping",
                                                    n->path)
                                      : fmt::format("body '{}' has no triangles, tetrahedra or hexahedra", node.path)),
              ErrorCode::kInvalidArgument);
        }
        out.triangles = out.triangles || among(kTriangleModels, c.type);
        out.lines = out.lines || among(kLineModels, c.type);
        out.points = out.points || among(kPointModels, c.type);
      }
      // The model's flags: the first model that states one gives the body's.
      const auto flag = [&](const char* key, std::optional<bool>& into) -> Expected<void> {
        auto v = boolean(c, key);
        if (!v) return std::unexpected(v.error());
        if (*v && !into) into = **v;
        return {};
      };
      if (auto r = flag("moving", moving); !r) return std::unexpected(r.error());
      if (auto r = flag("simulated", simulated); !r) return std::unexpected(r.error());
      if (auto r = flag("selfCollision", self_collision); !r) return std::unexpected(r.error());
      auto k = number(c, "contactStiffness");
      if (!k) return std::unexpected(k.error());
      if (*k) {
        if (**k < 0.0) return fail(c, fmt::format("contactStiffness {} is negative", **k), ErrorCode::kInvalidArgument);
        if (!stiffness) stiffness = **k;
      }
      if (const std::string* g = c.attr("group"); g && !group) {
        auto values = numbers(c, "group", *g);
        if (!values) return std::unexpected(values.error());
        if (!values->empty()) {
          const double v = values->front();
          if (v < 0.0 || v != std::floor(v) || v > 2147483647.0)
            return fail(c, fmt::format("attribute group: '{}' is not a whole number ≥ 0", *g));
          group = static_cast<std::int32_t>(v);
          if (values->size() > 1)
            warn(c.line, fmt::format("{}: HoF keeps one group per body; group {} is used", c.label(), *group));
        }
      }
    }
    if (!node_has_models || !mapped_node) continue;
    // The node carries the body's collision models: its state, topology and mapping are part
    // of them (the surface the body collides is its own touchable surface).
    bool own_mesh = false;
    for (auto& owned : n->components) {
      Component& c = *owned;
      if (c.type == "MechanicalObject" || is_mapping(c.type) || is_topology(c.type) ||
          c.type.ends_with("TopologyContainer") || c.type == "SphereLoader" || c.type.ends_with("GeometryAlgorithms") ||
          c.type.ends_with("TopologyModifier")) {
        c.used = true;
      } else if (is_loader(c.type) && c.type != "SphereLoader") {
        c.used = true;
        own_mesh = true;
      }
    }
    if (own_mesh && (out.triangles || out.lines || out.points)) {
      warn(n->line, fmt::format("node '{}': a collision mesh of its own; HoF collides the surface of body '{}' (its "
                                "touchable surface), which the mesh is mapped onto",
                                n->path, node.path));
    }
  }
  out.moving = moving.value_or(!rigid);
  out.simulated = simulated.value_or(!rigid);
  out.self_collision = self_collision;
  out.stiffness_n_per_m = stiffness;
  out.group = group.value_or(-1);
  return out;
}

Expected<void> Reader::read_spheres(SceneNode& node, Component& model, coupling::BodyCollision& out) {
  Component* loader = nullptr;
  Component* state = nullptr;
  for (auto& c : node.components) {
    if (c->type == "SphereLoader" && !loader) loader = c.get();
    if (c->type == "MechanicalObject" && !state) state = c.get();
  }
  // The .sph file: the node's SphereLoader's, or (2008's SphereModel) the model's own.
  if (!loader && model.attr("filename")) loader = &model;
  mesh::SphereSet file;
  if (loader) {
    const std::string* name = loader->attr("filename");
    if (!name) return fail(*loader, "attribute filename: missing (the .sph file of the spheres)");
    auto path = resolve_file(*loader, "filename", *name);
    if (!path) return std::unexpected(path.error());
    auto read = mesh::read_sph(*path);
    if (!read) {
      Error e = read.error();
      e.message = fmt::format("{} (scene {}): {}", loader->label(), path_.string(), e.message);
      return std::unexpected(std::move(e));
    }
    file = std::move(*read);
    loader->used = true;
  }
  // Centres: the state's positions as written, else (a link, or none) the loader's.
  std::vector<Vec3> centers;
  const std::string* position = state ? state->attr("position") : nullptr;
  if (position && !trim(*position).starts_with("@")) {
    auto values = numbers(*state, "position", *position);
    if (!values) return std::unexpected(values.error());
    if (values->size() % 3 != 0)
      return fail(*state, fmt::format("attribute position: {} numbers, not a whole number of points", values->size()));
    for (std::size_t i = 0; i + 2 < values->size(); i += 3)
      centers.emplace_back((*values)[i], (*values)[i + 1], (*values)[i + 2]);
  } else if (loader) {
    centers = file.centers;
  }
  if (centers.empty()) {
    return fail(model,
                fmt::format("a SphereCollisionModel with no spheres: node '{}' has no SphereLoader and no "
                            "MechanicalObject with positions",
                            node.path),
                ErrorCode::kInvalidArgument);
  }
  // Radii: listRadius as written, else (a link) the loader's, else `radius` for every sphere.
  std::vector<double> radii;
  const std::string* list = model.attr("listRadius");
  if (list && !trim(*list).starts_with("@")) {
    auto values = numbers(model, "listRadius", *list);
    if (!values) return std::unexpected(values.error());
    radii = *values;
  } else if (loader && (list || loader == &model)) {
    radii = file.radii;
  } else if (list) {
    return fail(model, fmt::format("attribute listRadius: the link '{}' finds no SphereLoader in node '{}'",
                                   std::string(trim(*list)), node.path));
  } else {
    auto r = number(model, "radius");
    if (!r) return std::unexpected(r.error());
    radii.assign(centers.size(), r->value_or(1.0));  // SphereCollisionModel's default radius: 1
  }
  if (radii.size() != centers.size()) {
    return fail(model,
                fmt::format("{} radii for {} spheres (listRadius must give one radius per sphere)", radii.size(),
                            centers.size()),
                ErrorCode::kInvalidArgument);
  }
  for (double r : radii)
    if (!(r > 0.0)) return fail(model, fmt::format("sphere radius {} is not positive", r), ErrorCode::kInvalidArgument);
  out.sphere_centers.insert(out.sphere_centers.end(), centers.begin(), centers.end());
  out.sphere_radii.insert(out.sphere_radii.end(), radii.begin(), radii.end());
  return {};
}

}  // namespace hof::scene::detail
