// Contact between bodies in a world: the project's <contact> element over the contact settings
// of the scene (a SOFA collision pipeline), and the bodies' own choices.

#include <fmt/format.h>
#include <fmt/ranges.h>

#include <algorithm>

#include "hof/scene/detail/world_parts.h"

namespace hof::scene::detail {

namespace {

Expected<std::int32_t> body_index(const World& w, const std::string& name, std::string_view what, std::int64_t line) {
  for (std::size_t i = 0; i < w.bodies.size(); ++i)
    if (w.bodies[i].name == name) return static_cast<std::int32_t>(i);
  std::vector<std::string> names;
  for (const coupling::SessionBody& b : w.bodies) names.push_back(b.name);
  return make_error(ErrorCode::kInvalidArgument,
                    fmt::format("{}: no body '{}' in the world (bodies: {})", what, name, fmt::join(names, ", ")),
                    w.file.string(), line);
}

// The body's whole surface as its collision models: triangles, edges and nodes.
void collide_whole_surface(coupling::SessionBody& b) {
  b.collision.enabled = true;
  b.collision.triangles = b.collision.lines = b.collision.points = true;
  b.collision.moving = b.collision.simulated = b.deformable();
}

// Whether the body collides through models of its own (its scene's).
bool has_models(const coupling::SessionBody& b) {
  const coupling::BodyCollision& c = b.collision;
  return c.enabled && (c.triangles || c.lines || c.points || !c.sphere_centers.empty());
}

}  // namespace

Expected<void> apply_contact(World& w) {
  coupling::ContactSettings& settings = w.config.contacts;
  if (w.project.contact) {
    settings = w.project.contact->settings;
    settings.disabled_pairs.clear();
    // Every body with a surface collides; a SOFA body keeps the collision models its scene gives.
    for (coupling::SessionBody& b : w.bodies) {
      if (!has_models(b) && !b.surface.triangles.empty()) collide_whole_surface(b);
    }
  } else if (settings.enabled) {
    // The scene's contact (a SOFA collision pipeline): the project's obstacles are supports
    // the bodies rest on.
    for (const ObstacleSetup& o : w.project.obstacles) {
      for (coupling::SessionBody& b : w.bodies)
        if (b.name == o.name && !b.deformable()) collide_whole_surface(b);
    }
  }
  // The bodies' own choices, last.
  struct Choice {
    std::string_view tag;
    std::string name;
    bool collides;
    std::int64_t line;
  };
  std::vector<Choice> choices;
  for (const BodySetup& setup : w.project.bodies)
    if (setup.contact) choices.push_back({"body", setup.name, *setup.contact, setup.line});
  for (const ObstacleSetup& o : w.project.obstacles)
    if (o.contact) choices.push_back({"obstacle", o.name, *o.contact, o.line});
  for (const auto& [tag, name, collides, line] : choices) {
    auto index = body_index(w, name, fmt::format("<{} name=\"{}\" contact=\"{}\">", tag, name, collides), line);
    if (!index) return std::unexpected(index.error());
    coupling::SessionBody& b = w.bodies[static_cast<std::size_t>(*index)];
    if (!collides) {
      b.collision.enabled = false;
    } else if (!has_models(b)) {
      if (b.surface.triangles.empty()) {
        return make_error(ErrorCode::kInvalidArgument,
                          fmt::format("<{} name=\"{}\" contact=\"true\">: a collision model on a body with no "
                                      "surface (it has no triangles)",
                                      tag, name),
                          w.file.string(), line);
      }
      collide_whole_surface(b);
    }
  }
  if (w.project.contact) {
    for (const auto& [a, b] : w.project.contact->disabled_pairs) {
      const std::string what = fmt::format("<contact><pair a=\"{}\" b=\"{}\">", a, b);
      const std::int64_t line = w.project.contact->line;
      auto i = body_index(w, a, what, line);
      if (!i) return std::unexpected(i.error());
      auto j = body_index(w, b, what, line);
      if (!j) return std::unexpected(j.error());
      if (*i == *j) {
        return make_error(ErrorCode::kInvalidArgument,
                          fmt::format("{}: a pair needs two different bodies (selfCollision switches a body's "
                                      "contact with itself)",
                                      what),
                          w.file.string(), line);
      }
      const std::pair<std::int32_t, std::int32_t> pair{std::min(*i, *j), std::max(*i, *j)};
      if (std::ranges::find(settings.disabled_pairs, pair) == settings.disabled_pairs.end())
        settings.disabled_pairs.push_back(pair);
    }
    std::ranges::sort(settings.disabled_pairs);
  }
  return {};
}

}  // namespace hof::scene::detail
