// A setting named as the project file names it, parsed once into a typed edit (project_edit.h):
// the element path walked over the project's own structure, the attribute read and checked by
// the table the file's reader uses (detail/project_fields.h).

#include "hof/scene/project_edit.h"

#include <fmt/format.h>

#include <algorithm>
#include <charconv>
#include <cstdint>
#include <utility>
#include <vector>

#include "hof/scene/detail/project_fields.h"

namespace hof::scene {

namespace {

using detail::Fields;

// The elements a setting can be in, as the file has them.
enum class Element : std::uint8_t {
  kRoot,
  kHaptics,
  kCalibration,
  kSurface,
  kSafety,
  kOptions,
  kStylus,
  kNeedle,
  kTissue,
  kEffects,
  kSpringEffect,
  kViscosityEffect,
  kForceField,
  kGraphics,
  kMaterial,
  kLight,
};

struct Child {
  std::string_view name;
  Element element;
  std::size_t count;  // how many the project has (the written file's)
};

// The children of `e` in `p`, in the order the writer writes them.
std::vector<Child> children(Element e, const HofProject& p) {
  switch (e) {
    case Element::kRoot:
      return {{"haptics", Element::kHaptics, 1}, {"graphics", Element::kGraphics, 1}};
    case Element::kHaptics: {
      std::vector<Child> c{{"calibration", Element::kCalibration, 1},
                           {"surface", Element::kSurface, 1},
                           {"safety", Element::kSafety, 1},
                           {"options", Element::kOptions, 1},
                           {"stylus", Element::kStylus, 1}};
      if (p.needle) c.push_back({"needle", Element::kNeedle, 1});
      c.push_back({"effects", Element::kEffects, 1});
      return c;
    }
    case Element::kNeedle:
      return {{"tissue", Element::kTissue, p.needle ? 1 + p.needle->bodies.size() : 0}};
    case Element::kEffects: {
      std::vector<Child> c;
      if (!p.effects.springs.empty()) c.push_back({"SpringEffect", Element::kSpringEffect, p.effects.springs.size()});
      if (!p.effects.viscosities.empty())
        c.push_back({"ViscosityEffect", Element::kViscosityEffect, p.effects.viscosities.size()});
      if (!p.effects.constants.empty()) c.push_back({"ForceField", Element::kForceField, p.effects.constants.size()});
      return c;
    }
    case Element::kGraphics:
      return {{"material", Element::kMaterial, 1}, {"light", Element::kLight, 1}};
    default:
      return {};
  }
}

Error invalid(std::string message) { return Error{ErrorCode::kInvalidArgument, std::move(message), {}, 0, -1}; }

// A new value of `T` with `attribute` read from `text` by `fields` (the reader's check), else
// the error.
struct Setting {
  const HofProject& project;
  const std::filesystem::path& path;
  std::string name;      // element@attribute, as errors name it
  std::string walked;    // hof/haptics/…, as errors name the element
  std::string_view tag;  // the element's name, as the reader's messages give it
  std::string_view attribute;
  std::string_view value;

  Error refused(std::string message) const {
    return Error{ErrorCode::kParse, fmt::format("'{}' = '{}': {}", name, value, message), path.string(), 0, -1};
  }
  Error unknown_attribute(std::string known) const {
    return invalid(fmt::format("'{}': <{}> has no attribute '{}' (it has: {})", name, walked, attribute,
                               known.empty() ? "none" : known));
  }
  template <class T>
  Expected<T> read(const Fields<T>& fields, T into, std::string known_before = {}) const {
    for (const auto& f : fields) {
      if (f.name != attribute) continue;
      if (auto problem = f.read(into, tag, value)) return std::unexpected(refused(std::move(*problem)));
      return into;
    }
    for (const auto& f : fields) known_before += fmt::format("{}{}", known_before.empty() ? "" : ", ", f.name);
    return std::unexpected(unknown_attribute(std::move(known_before)));
  }
};

Expected<ProjectEdit> haptics_edit(const Setting& s) {
  auto next = s.read(detail::haptics_fields(), s.project);
  if (!next) return std::unexpected(next.error());
  if (auto problem = detail::check_haptic_rate(*next)) return std::unexpected(s.refused(std::move(*problem)));
  if (s.attribute == "device") return project_edit::Device{next->device};
  if (s.attribute == "hapticRate") return project_edit::HapticRate{next->haptic_rate_hz};
  if (s.attribute == "coupling") return project_edit::Coupling{next->coupling};
  return project_edit::Rendering{next->renderer, next->proxy_radius_m, next->force_shading, next->touchable_face};
}

Expected<ProjectEdit> needle_edit(const Setting& s, Element e, std::size_t index) {
  procedures::NeedleConfig n = *s.project.needle;
  if (e == Element::kNeedle) {
    auto read = s.read(detail::needle_fields(), n);
    if (!read) return std::unexpected(read.error());
    n = std::move(*read);
  } else if (index == 0) {
    // The set for every body (written first, without body="").
    auto read = s.read(detail::tissue_fields(), n.tissue);
    if (!read) return std::unexpected(read.error());
    if (auto problem = detail::check_tissue(*read, "")) return std::unexpected(s.refused(std::move(*problem)));
    n.tissue = std::move(*read);
  } else {
    auto& [body, tissue] = n.bodies[index - 1];
    if (s.attribute == "body") {
      if (s.value.empty()) {
        return std::unexpected(
            s.refused("<tissue body=\"\">: name the body, or leave body out for every deformable body"));
      }
      body = std::string(s.value);
    } else {
      auto read = s.read(detail::tissue_fields(), tissue, "body");
      if (!read) return std::unexpected(read.error());
      tissue = std::move(*read);
    }
    if (auto problem = detail::check_tissue(tissue, body)) return std::unexpected(s.refused(std::move(*problem)));
  }
  if (auto problem = detail::check_needle(n)) return std::unexpected(s.refused(std::move(*problem)));
  return project_edit::Needle{std::move(n)};
}

Expected<ProjectEdit> effects_edit(const Setting& s, Element e, std::size_t index) {
  haptics::ForceEffects effects = s.project.effects;
  const auto replace = [&](const auto& fields, auto& list) -> Expected<void> {
    auto read = s.read(fields, list[index]);
    if (!read) return std::unexpected(read.error());
    list[index] = std::move(*read);
    return {};
  };
  Expected<void> ok;
  if (e == Element::kSpringEffect)
    ok = replace(detail::spring_effect_fields(), effects.springs);
  else if (e == Element::kViscosityEffect)
    ok = replace(detail::viscosity_effect_fields(), effects.viscosities);
  else if (e == Element::kForceField)
    ok = replace(detail::force_field_fields(), effects.constants);
  else
    return std::unexpected(s.unknown_attribute(""));  // <effects> itself has none
  if (!ok) return std::unexpected(ok.error());
  return project_edit::Effects{std::move(effects)};
}

// The edit of `attribute` in element `e` (the `index`-th of its kind, from 0).
Expected<ProjectEdit> edit_of(const Setting& s, Element e, std::size_t index) {
  const HofProject& p = s.project;
  switch (e) {
    case Element::kRoot:
      return std::unexpected(s.unknown_attribute(""));
    case Element::kHaptics:
      return haptics_edit(s);
    case Element::kCalibration: {
      auto next = s.read(detail::calibration_fields(), p);
      if (!next) return std::unexpected(next.error());
      return project_edit::Calibration{next->position_calibration};
    }
    case Element::kSurface: {
      auto next = s.read(detail::surface_fields(), p.surface);
      if (!next) return std::unexpected(next.error());
      if (auto problem = detail::check_surface(*next)) return std::unexpected(s.refused(std::move(*problem)));
      return project_edit::Surface{*next};
    }
    case Element::kSafety: {
      auto next = s.read(detail::safety_fields(), p.safety);
      if (!next) return std::unexpected(next.error());
      if (s.attribute == "maxForce") return project_edit::ForceLimit{next->max_force_n};
      return project_edit::Safety{*next};
    }
    case Element::kOptions: {
      auto next = s.read(detail::options_fields(), p);
      if (!next) return std::unexpected(next.error());
      return project_edit::BoundTree{next->use_bound_tree, next->max_triangles_in_leaf};
    }
    case Element::kStylus: {
      auto next = s.read(detail::stylus_fields(), p);
      if (!next) return std::unexpected(next.error());
      return project_edit::Stylus{next->stylus_radius_m, next->stylus_length_m};
    }
    case Element::kNeedle:
    case Element::kTissue:
      return needle_edit(s, e, index);
    case Element::kEffects:
    case Element::kSpringEffect:
    case Element::kViscosityEffect:
    case Element::kForceField:
      return effects_edit(s, e, index);
    case Element::kGraphics:
    case Element::kMaterial:
    case Element::kLight: {
      const Fields<GraphicsSetup>& fields = e == Element::kGraphics   ? detail::graphics_fields()
                                            : e == Element::kMaterial ? detail::material_fields()
                                                                      : detail::light_fields();
      auto next = s.read(fields, p.graphics);
      if (!next) return std::unexpected(next.error());
      return project_edit::Graphics{*next};
    }
  }
  return std::unexpected(s.unknown_attribute(""));
}

}  // namespace

Expected<ProjectEdit> parse_project_edit(const HofProject& project, const std::filesystem::path& path,
                                         std::string_view element, std::string_view attribute, std::string_view value) {
  Setting s{project, path, fmt::format("{}@{}", element, attribute), "hof", "hof", attribute, value};
  Element at = Element::kRoot;
  std::size_t index = 0;
  std::size_t start = 0;
  while (!element.empty() && start <= element.size()) {
    const std::size_t slash = element.find('/', start);
    std::string_view part =
        element.substr(start, slash == std::string_view::npos ? std::string_view::npos : slash - start);
    // NAME[n]: the n-th such element (from 1, as XPath), e.g. haptics/effects/SpringEffect[2].
    int n = 1;
    if (const std::size_t open = part.find('['); open != std::string_view::npos && part.ends_with(']')) {
      const std::string_view number = part.substr(open + 1, part.size() - open - 2);
      const auto parsed = std::from_chars(number.data(), number.data() + number.size(), n);
      if (parsed.ec != std::errc() || parsed.ptr != number.data() + number.size() || n < 1) {
        return std::unexpected(invalid(fmt::format("'{}': '{}' is not NAME[n] with n >= 1", s.name, part)));
      }
      part = part.substr(0, open);
    }
    const std::vector<Child> kids = children(at, project);
    const auto child =
        std::find_if(kids.begin(), kids.end(), [&](const Child& c) { return c.name == part && c.count > 0; });
    if (child == kids.end()) {
      std::string known;
      for (const Child& c : kids) {
        if (c.count > 0) known += fmt::format("{}{}", known.empty() ? "" : ", ", c.name);
      }
      if (at == Element::kRoot && (part == "mechanics" || part == "bodies")) {
        return std::unexpected(
            invalid(fmt::format("'{}': <{}> is not set by name here (the settings set so are in: {}; a body's "
                                "parameters are mechanics/BODY/COMPONENT@PARAMETER)",
                                s.name, part, known)));
      }
      return std::unexpected(invalid(fmt::format("'{}': no element <{}> in <{}> (it has: {})", s.name, part, s.walked,
                                                 known.empty() ? "none" : known)));
    }
    if (static_cast<std::size_t>(n) > child->count) {
      return std::unexpected(
          invalid(fmt::format("'{}': <{}> has {} <{}>, not {}", s.name, s.walked, child->count, part, n)));
    }
    at = child->element;
    index = static_cast<std::size_t>(n - 1);
    s.walked += fmt::format("/{}{}", part, n > 1 ? fmt::format("[{}]", n) : std::string());
    s.tag = child->name;
    if (slash == std::string_view::npos) break;
    start = slash + 1;
  }
  return edit_of(s, at, index);
}

namespace {

// The first of `fields`' checks that `value` fails (a field without a check has none).
template <class T>
std::optional<std::string> check_each(const Fields<T>& fields, std::string_view element, const T& value) {
  for (const detail::Field<T>& f : fields) {
    if (!f.check) continue;
    if (auto problem = f.check(value, element)) return problem;
  }
  return std::nullopt;
}

// The problem of the element(s) `edit` changes in `next` (the project with the edit made).
std::optional<std::string> problem_of(const HofProject& next, const ProjectEdit& edit) {
  struct Check {
    const HofProject& p;
    std::optional<std::string> operator()(const project_edit::Device& e) const {
      if (e.spec.empty()) return std::string("haptics@device: name a device (auto, mouse, dhd, udp:PORT, ...)");
      return std::nullopt;
    }
    std::optional<std::string> operator()(const project_edit::HapticRate&) const {
      if (auto problem = check_each(detail::haptics_fields(), "haptics", p)) return problem;
      return detail::check_haptic_rate(p);
    }
    std::optional<std::string> operator()(const project_edit::Rendering&) const {
      return check_each(detail::haptics_fields(), "haptics", p);
    }
    std::optional<std::string> operator()(const project_edit::Coupling&) const {
      return check_each(detail::haptics_fields(), "haptics", p);
    }
    std::optional<std::string> operator()(const project_edit::Calibration&) const {
      return check_each(detail::calibration_fields(), "calibration", p);
    }
    std::optional<std::string> operator()(const project_edit::Surface&) const {
      if (auto problem = check_each(detail::surface_fields(), "surface", p.surface)) return problem;
      return detail::check_surface(p.surface);
    }
    std::optional<std::string> operator()(const project_edit::ForceLimit&) const {
      return check_each(detail::safety_fields(), "safety", p.safety);
    }
    std::optional<std::string> operator()(const project_edit::Safety&) const {
      return check_each(detail::safety_fields(), "safety", p.safety);
    }
    std::optional<std::string> operator()(const project_edit::BoundTree&) const {
      return check_each(detail::options_fields(), "options", p);
    }
    std::optional<std::string> operator()(const project_edit::Stylus&) const {
      return check_each(detail::stylus_fields(), "stylus", p);
    }
    std::optional<std::string> operator()(const project_edit::Needle& e) const {
      const procedures::NeedleConfig& n = e.needle;
      if (auto problem = check_each(detail::needle_fields(), "needle", n)) return problem;
      if (auto problem = check_each(detail::tissue_fields(), "tissue", n.tissue)) return problem;
      if (auto problem = detail::check_tissue(n.tissue, "")) return problem;
      for (const auto& [body, tissue] : n.bodies) {
        if (body.empty())
          return std::string("<tissue body=\"\">: name the body, or leave body out for every deformable body");
        if (auto problem = check_each(detail::tissue_fields(), "tissue", tissue)) return problem;
        if (auto problem = detail::check_tissue(tissue, body)) return problem;
      }
      return detail::check_needle(n);
    }
    std::optional<std::string> operator()(const project_edit::Effects& e) const {
      for (const auto& spring : e.effects.springs) {
        if (auto problem = check_each(detail::spring_effect_fields(), "SpringEffect", spring)) return problem;
      }
      for (const auto& viscosity : e.effects.viscosities) {
        if (auto problem = check_each(detail::viscosity_effect_fields(), "ViscosityEffect", viscosity)) return problem;
      }
      for (const auto& constant : e.effects.constants) {
        if (auto problem = check_each(detail::force_field_fields(), "ForceField", constant)) return problem;
      }
      return std::nullopt;
    }
    std::optional<std::string> operator()(const project_edit::Graphics& e) const {
      if (auto ok = check_graphics(e.graphics); !ok) return ok.error().message;
      return std::nullopt;
    }
    std::optional<std::string> operator()(const project_edit::Tool& e) const {
      if (!e.tool) return std::nullopt;  // the point/sphere proxy
      if (auto problem = check_each(detail::tool_fields(), "tool", *e.tool)) return problem;
      return detail::check_tool(*e.tool);
    }
  };
  return std::visit(Check{next}, edit);
}

}  // namespace

Expected<void> check_edit(const HofProject& project, const ProjectEdit& edit) {
  HofProject next = project;
  apply_edit(next, edit);
  if (auto problem = problem_of(next, edit)) return make_error(ErrorCode::kInvalidArgument, std::move(*problem));
  return {};
}

void apply_edit(HofProject& p, const ProjectEdit& edit) {
  struct Apply {
    HofProject& p;
    void operator()(const project_edit::Device& e) const { p.device = e.spec; }
    void operator()(const project_edit::HapticRate& e) const { p.haptic_rate_hz = e.hz; }
    void operator()(const project_edit::Rendering& e) const {
      p.renderer = e.renderer;
      p.proxy_radius_m = e.proxy_radius_m;
      p.force_shading = e.force_shading;
      p.touchable_face = e.touchable_face;
    }
    void operator()(const project_edit::Coupling& e) const { p.coupling = e.coupling; }
    void operator()(const project_edit::Calibration& e) const { p.position_calibration = e.position; }
    void operator()(const project_edit::Surface& e) const { p.surface = e.surface; }
    void operator()(const project_edit::ForceLimit& e) const { p.safety.max_force_n = e.max_force_n; }
    void operator()(const project_edit::Safety& e) const { p.safety = e.safety; }
    void operator()(const project_edit::BoundTree& e) const {
      p.use_bound_tree = e.use_bound_tree;
      p.max_triangles_in_leaf = e.max_triangles_in_leaf;
    }
    void operator()(const project_edit::Stylus& e) const {
      p.stylus_radius_m = e.radius_m;
      p.stylus_length_m = e.length_m;
    }
    void operator()(const project_edit::Needle& e) const { p.needle = e.needle; }
    void operator()(const project_edit::Effects& e) const { p.effects = e.effects; }
    void operator()(const project_edit::Graphics& e) const { p.graphics = e.graphics; }
    void operator()(const project_edit::Tool& e) const {
      p.tool = e.tool;
      if (e.tool) p.needle.reset();  // one tool on the stylus (scene::mount_tool)
    }
  };
  std::visit(Apply{p}, edit);
}

Expected<void> set_project_attribute(HofProject& project, const std::filesystem::path& path, std::string_view element,
                                     std::string_view attribute, std::string_view value) {
  auto edit = parse_project_edit(project, path, element, attribute, value);
  if (!edit) return std::unexpected(edit.error());
  apply_edit(project, *edit);
  return {};
}

}  // namespace hof::scene
