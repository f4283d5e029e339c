// .hof projects written: to_xml (what `hof gui` saves, what a project round-trips through) and
// write_project (atomically, never a half-written file). Read by project.cpp.

#include <fmt/format.h>

#include <string>
#include <string_view>

#include "hof/core/file_write.h"
#include "hof/scene/detail/project_fields.h"
#include "hof/scene/project.h"

namespace hof::scene {

namespace {

using detail::number_text;
using detail::write_fields;
using detail::xml_escape;

std::string vec(const Vec3& v) { return number_text(v.x()) + " " + number_text(v.y()) + " " + number_text(v.z()); }

std::string surface_xml(const haptics::SurfaceMaterial& s, std::string_view indent) {
  return fmt::format("{}<surface {}/>\n", indent, write_fields(detail::surface_fields(), s));
}

std::string tissue_xml(const procedures::TissueNeedleParameters& t, const std::string& body) {
  const std::string named = body.empty() ? std::string() : fmt::format(" body=\"{}\"", xml_escape(body));
  return fmt::format("      <tissue{} {}/>\n", named, write_fields(detail::tissue_fields(), t));
}

std::string needle_xml(const procedures::NeedleConfig& n) {
  std::string out = fmt::format("    <needle {}>\n", write_fields(detail::needle_fields(), n));
  out += tissue_xml(n.tissue, "");
  for (const auto& [body, tissue] : n.bodies) out += tissue_xml(tissue, body);
  return out + "    </needle>\n";
}

}  // namespace

std::string to_xml(const HofProject& p) {
  std::string out;
  out += "<?xml version=\"1.0\" encoding=\"UTF-8\"?>\n";
  out += fmt::format("<hof version=\"1\" name=\"{}\">\n", xml_escape(p.name));
  // Parameters set on the scene's bodies (the command seam's changes), after the scene.
  std::string sets;
  for (const ParameterChange& c : p.parameters) {
    sets += fmt::format("    <set body=\"{}\" component=\"{}\" parameter=\"{}\" value=\"{}\"/>\n", xml_escape(c.body),
                        xml_escape(c.component), xml_escape(c.parameter), number_text(c.value));
  }
  for (const MaterialRegion& region : p.regions) {
    const std::string force_field =
        region.force_field.empty() ? std::string() : fmt::format(" forceField=\"{}\"", xml_escape(region.force_field));
    std::string shape;
    switch (region.shape) {
      case MaterialRegion::Shape::kSphere:
        shape =
            fmt::format("shape=\"sphere\" center=\"{}\" radius=\"{}\"", vec(region.center), number_text(region.radius));
        break;
      case MaterialRegion::Shape::kBox:
        shape = fmt::format("shape=\"box\" min=\"{}\" max=\"{}\"", vec(region.box_min), vec(region.box_max));
        break;
      case MaterialRegion::Shape::kGroup:
        shape = fmt::format("shape=\"group\" physicalGroup=\"{}\"", region.physical_group);
        break;
    }
    std::string material;
    if (region.young_modulus_pa) material += fmt::format(" youngModulus=\"{}\"", number_text(*region.young_modulus_pa));
    if (region.poisson_ratio) material += fmt::format(" poissonRatio=\"{}\"", number_text(*region.poisson_ratio));
    if (region.mass_density_kg_per_m3)
      material += fmt::format(" massDensity=\"{}\"", number_text(*region.mass_density_kg_per_m3));
    sets += fmt::format("    <region name=\"{}\" body=\"{}\"{} {}{}/>\n", xml_escape(region.name),
                        xml_escape(region.body), force_field, shape, material);
  }
  const std::string unit = p.scene_unit.empty() ? std::string() : fmt::format(" unit=\"{}\"", xml_escape(p.scene_unit));
  if (!p.mechanics_inline.empty()) {
    out += fmt::format("  <mechanics{}>\n", unit) + p.mechanics_inline + sets + "  </mechanics>\n";
  } else if (sets.empty()) {
    out += fmt::format("  <mechanics scene=\"{}\"{}/>\n", xml_escape(p.mechanics_scene.generic_string()), unit);
  } else {
    out += fmt::format("  <mechanics scene=\"{}\"{}>\n", xml_escape(p.mechanics_scene.generic_string()), unit) + sets +
           "  </mechanics>\n";
  }
  if (!p.bodies.empty() || !p.obstacles.empty()) {
    out += "  <bodies>\n";
    for (const BodySetup& b : p.bodies) {
      std::string model = b.model.empty() ? std::string() : fmt::format(" model=\"{}\"", xml_escape(b.model));
      if (b.grid[0] > 0) model += fmt::format(" grid=\"{} {} {}\"", b.grid[0], b.grid[1], b.grid[2]);
      if (b.contact) model += fmt::format(" contact=\"{}\"", *b.contact ? "true" : "false");
      if (b.surface) {
        out += fmt::format("    <body name=\"{}\"{}>\n", xml_escape(b.name), model) +
               surface_xml(*b.surface, "      ") + "    </body>\n";
      } else {
        out += fmt::format("    <body name=\"{}\"{}/>\n", xml_escape(b.name), model);
      }
    }
    for (const ObstacleSetup& o : p.obstacles) {
      const std::string open =
          fmt::format("    <obstacle name=\"{}\" mesh=\"{}\" translation=\"{}\"{}", xml_escape(o.name),
                      xml_escape(o.mesh.generic_string()), vec(o.translation),
                      o.contact ? fmt::format(" contact=\"{}\"", *o.contact ? "true" : "false") : std::string());
      out += o.surface ? open + ">\n" + surface_xml(*o.surface, "      ") + "    </obstacle>\n" : open + "/>\n";
    }
    out += "  </bodies>\n";
  }
  if (p.contact) {
    const std::string attributes = write_fields(detail::contact_fields(), p.contact->settings);
    if (p.contact->disabled_pairs.empty()) {
      out += fmt::format("  <contact {}/>\n", attributes);
    } else {
      out += fmt::format("  <contact {}>\n", attributes);
      for (const auto& [a, b] : p.contact->disabled_pairs)
        out += fmt::format("    <pair a=\"{}\" b=\"{}\" enabled=\"false\"/>\n", xml_escape(a), xml_escape(b));
      out += "  </contact>\n";
    }
  }
  out += fmt::format("  <haptics {}>\n", write_fields(detail::haptics_fields(), p));
  out += fmt::format("    <calibration {}/>\n", write_fields(detail::calibration_fields(), p));
  out += surface_xml(p.surface, "    ");
  out += fmt::format("    <safety {}/>\n", write_fields(detail::safety_fields(), p.safety));
  out += fmt::format("    <options {}/>\n", write_fields(detail::options_fields(), p));
  out += fmt::format("    <stylus {}/>\n", write_fields(detail::stylus_fields(), p));
  if (p.needle) out += needle_xml(*p.needle);
  if (p.tool) out += fmt::format("    <tool {}/>\n", write_fields(detail::tool_fields(), *p.tool));
  for (const HandSetup& hand : p.hands) {
    out += fmt::format("    <tool {}{}/>\n", write_fields(detail::tool_fields(), hand.tool),
                       hand.max_force_n > 0.0 ? fmt::format(" maxForce=\"{}\"", hand.max_force_n) : std::string());
  }
  if (p.effects.springs.empty() && p.effects.viscosities.empty() && p.effects.constants.empty()) {
    out += "    <effects/>\n";
  } else {
    out += "    <effects>\n";
    for (const auto& e : p.effects.springs)
      out += fmt::format("      <SpringEffect {}/>\n", write_fields(detail::spring_effect_fields(), e));
    for (const auto& e : p.effects.viscosities) {
      out += fmt::format("      <ViscosityEffect {}/>\n", write_fields(detail::viscosity_effect_fields(), e));
    }
    for (const auto& e : p.effects.constants)
      out += fmt::format("      <ForceField {}/>\n", write_fields(detail::force_field_fields(), e));
    out += "    </effects>\n";
  }
  out += "  </haptics>\n";
  out += fmt::format("  <graphics {}>\n", write_fields(detail::graphics_fields(), p.graphics));
  out += fmt::format("    <material {}/>\n", write_fields(detail::material_fields(), p.graphics));
  out += fmt::format("    <light {}/>\n", write_fields(detail::light_fields(), p.graphics));
  out += "  </graphics>\n";
  out += "</hof>\n";
  return out;
}

Expected<void> write_project(const HofProject& project, const std::filesystem::path& path) {
  // Temporary file, flushed, then renamed: a full disk, a crash or a folder removed mid-save
  // leaves the previous project whole, never half a file.
  return write_file_atomically(path, to_xml(project));
}

}  // namespace hof::scene
