// .hof projects written: to_xml (what `hof gui` saves, what a project round-trips through) and
// write_project (atomically, never a half-written file). Read by project.cpp.

#include <fmt/format.h>

#include <charconv>
#include <initializer_list>
#include <string>
#include <string_view>

#include "hof/core/file_write.h"
#include "hof/core/text.h"
#include "hof/scene/detail/project_names.h"
#include "hof/scene/project.h"

namespace hof::scene {

namespace {

using detail::renderer_name;

std::string number(double v) {
  char buffer[64];
  const auto result = std::to_chars(buffer, buffer + sizeof buffer, v);
  return std::string(buffer, result.ptr);
}

std::string vec(const Vec3& v) { return number(v.x()) + " " + number(v.y()) + " " + number(v.z()); }

const char* face_name(collision::TouchableFace f) {
  switch (f) {
    case collision::TouchableFace::kFront: return "FRONT";
    case collision::TouchableFace::kBack: return "BACK";
    case collision::TouchableFace::kFrontAndBack: return "FRONT_AND_BACK";
  }
  return "FRONT";
}

const char* coupling_name(coupling::ContactCoupling c) {
  switch (c) {
    case coupling::ContactCoupling::kClosestVertex: return "closest-vertex";
    case coupling::ContactCoupling::kBarycentric: return "barycentric";
    case coupling::ContactCoupling::kCompliance: return "compliance";
    case coupling::ContactCoupling::kFemReaction: return "fem-reaction";
  }
  return "barycentric";
}

const char* surface_name(haptics::SurfaceKind k) {
  switch (k) {
    case haptics::SurfaceKind::kSmooth: return "SmoothSurface";
    case haptics::SurfaceKind::kFrictional: return "FrictionalSurface";
    case haptics::SurfaceKind::kMagnetic: return "MagneticSurface";
    case haptics::SurfaceKind::kZeroForce: return "ZeroForceSurface";
  }
  return "SmoothSurface";
}

// Text for an XML attribute value: markup characters escaped; bytes that are not UTF-8 (a
// Latin-1 name, say) written as U+FFFD so the file stays well-formed.
std::string xml_escape(std::string_view text) {
  std::string out;
  for (const char c : valid_utf8(text)) {
    switch (c) {
      case '&': out += "&amp;"; break;
      case '<': out += "&lt;"; break;
      case '>': out += "&gt;"; break;
      case '"': out += "&quot;"; break;
      default: out += c;
    }
  }
  return out;
}


std::string surface_xml(const haptics::SurfaceMaterial& s, std::string_view indent) {
  return fmt::format(
      "{}<surface type=\"{}\" stiffness=\"{}\" damping=\"{}\" useRelativeValues=\"{}\" staticFriction=\"{}\" "
      "dynamicFriction=\"{}\" snapDistance=\"{}\"/>\n",
      indent, surface_name(s.kind), number(s.stiffness), number(s.damping_n_s_per_m), s.use_relative_values ? "true" : "false",
      number(s.static_friction), number(s.dynamic_friction), number(s.snap_distance_m));
}

std::string numbers(std::initializer_list<double> values) {
  std::string out;
  for (double v : values) out += (out.empty() ? "" : " ") + number(v);
  return out;
}

std::string tissue_xml(const procedures::TissueNeedleParameters& t, const std::string& body) {
  const std::string named = body.empty() ? std::string() : fmt::format(" body=\"{}\"", xml_escape(body));
  return fmt::format(
      "      <tissue{} pierceable=\"{}\" model=\"{}\" capsule=\"{}\" punctureForce=\"{}\" relaxationTime=\"{}\" "
      "fungForm=\"{}\" fungPre=\"{}\" fungPost=\"{}\" stiffness=\"{}\" cuttingForce=\"{}\" friction=\"{}\" frictionVelocityBand=\"{}\" "
      "lateralStiffness=\"{}\" lateralDamping=\"{}\" spreadRadius=\"{}\" pathTolerance=\"{}\"/>\n",
      named, t.pierceable ? "true" : "false", procedures::model_name(t.model), number(t.capsule_m), number(t.puncture_force_n),
      number(t.relaxation_time_s), procedures::form_name(t.fung_form), numbers({t.fung_pre.a_per_m, t.fung_pre.b_n, t.fung_pre.d0_m, t.fung_pre.f0_n}),
      numbers({t.fung_post.a_per_m, t.fung_post.b_n, t.fung_post.d0_m, t.fung_post.f0_n}),
      numbers({t.stiffness.a0_n, t.stiffness.a1_n_per_m, t.stiffness.a2_n_per_m2}), number(t.cutting_force_n),
      numbers({t.friction.static_positive_n_per_m, t.friction.static_negative_n_per_m, t.friction.damping_positive_n_s_per_m2,
               t.friction.damping_negative_n_s_per_m2}),
      number(t.friction.velocity_band_m_per_s), number(t.lateral_stiffness_n_per_m), number(t.lateral_damping_n_s_per_m),
      number(t.spread_radius_m), number(t.path_tolerance_m));
}

std::string needle_xml(const procedures::NeedleConfig& n) {
  const procedures::NeedleGeometry& g = n.geometry;
  std::string out = fmt::format(
      "    <needle axis=\"{}\" velocityFilter=\"{}\" length=\"{}\" shaftDiameter=\"{}\" tipDiameter=\"{}\" tipLength=\"{}\" "
      "syringeDiameter=\"{}\" syringeLength=\"{}\">\n",
      procedures::axis_name(n.axis), number(n.velocity_filter_s), number(g.length_m), number(g.shaft_diameter_m), number(g.tip_diameter_m),
      number(g.tip_length_m), number(g.syringe_diameter_m), number(g.syringe_length_m));
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
  for (const coupling::ParameterChange& c : p.parameters) {
    sets += fmt::format("    <set body=\"{}\" component=\"{}\" parameter=\"{}\" value=\"{}\"/>\n", xml_escape(c.body),
                        xml_escape(c.component), xml_escape(c.parameter), number(c.value));
  }
  for (const MaterialRegion& region : p.regions) {
    const std::string force_field =
        region.force_field.empty() ? std::string() : fmt::format(" forceField=\"{}\"", xml_escape(region.force_field));
    std::string shape;
    switch (region.shape) {
      case MaterialRegion::Shape::kSphere:
        shape = fmt::format("shape=\"sphere\" center=\"{}\" radius=\"{}\"", vec(region.center), number(region.radius));
        break;
      case MaterialRegion::Shape::kBox:
        shape = fmt::format("shape=\"box\" min=\"{}\" max=\"{}\"", vec(region.box_min), vec(region.box_max));
        break;
      case MaterialRegion::Shape::kGroup: shape = fmt::format("shape=\"group\" physicalGroup=\"{}\"", region.physical_group); break;
    }
    std::string material;
    if (region.young_modulus_pa) material += fmt::format(" youngModulus=\"{}\"", number(*region.young_modulus_pa));
    if (region.poisson_ratio) material += fmt::format(" poissonRatio=\"{}\"", number(*region.poisson_ratio));
    if (region.mass_density_kg_per_m3) material += fmt::format(" massDensity=\"{}\"", number(*region.mass_density_kg_per_m3));
    sets += fmt::format("    <region name=\"{}\" body=\"{}\"{} {}{}/>\n", xml_escape(region.name), xml_escape(region.body),
                        force_field, shape, material);
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
      if (b.surface) {
        out += fmt::format("    <body name=\"{}\"{}>\n", xml_escape(b.name), model) + surface_xml(*b.surface, "      ") + "    </body>\n";
      } else {
        out += fmt::format("    <body name=\"{}\"{}/>\n", xml_escape(b.name), model);
      }
    }
    for (const ObstacleSetup& o : p.obstacles) {
      const std::string open = fmt::format("    <obstacle name=\"{}\" mesh=\"{}\" translation=\"{}\"", xml_escape(o.name),
                                           xml_escape(o.mesh.generic_string()), vec(o.translation));
      out += o.surface ? open + ">\n" + surface_xml(*o.surface, "      ") + "    </obstacle>\n" : open + "/>\n";
    }
    out += "  </bodies>\n";
  }
  out += fmt::format(
      "  <haptics device=\"{}\" hapticRate=\"{}\" renderer=\"{}\" proxyRadius=\"{}\" forceShading=\"{}\" "
      "touchableFace=\"{}\" coupling=\"{}\">\n",
      xml_escape(p.device), number(p.haptic_rate_hz), renderer_name(p.renderer), number(p.proxy_radius_m), p.force_shading ? "true" : "false",
      face_name(p.touchable_face), coupling_name(p.coupling));
  std::string calibration;
  for (std::size_t i = 0; i < 16; ++i) calibration += (i ? " " : "") + number(p.position_calibration[i]);
  out += fmt::format("    <calibration positionCalibration=\"{}\"/>\n", calibration);
  out += surface_xml(p.surface, "    ");
  out += fmt::format("    <safety fadeIn=\"{}\" fadeOut=\"{}\" maxSnapshotAge=\"{}\" maxConsecutiveOverruns=\"{}\" maxForce=\"{}\"/>\n",
                     number(p.safety.fade_in_s), number(p.safety.fade_out_s), number(p.safety.max_snapshot_age_s),
                     p.safety.max_consecutive_overruns, number(p.safety.max_force_n));
  out += fmt::format("    <options useBoundTree=\"{}\" maxTrianglesInLeaf=\"{}\"/>\n", p.use_bound_tree ? "true" : "false",
                     p.max_triangles_in_leaf);
  out += fmt::format("    <stylus radius=\"{}\" length=\"{}\"/>\n", number(p.stylus_radius_m), number(p.stylus_length_m));
  if (p.needle) out += needle_xml(*p.needle);
  if (p.effects.springs.empty() && p.effects.viscosities.empty() && p.effects.constants.empty()) {
    out += "    <effects/>\n";
  } else {
    out += "    <effects>\n";
    for (const auto& e : p.effects.springs) {
      out += fmt::format(
          "      <SpringEffect position=\"{}\" springConstant=\"{}\" startDistance=\"{}\" escapeDistance=\"{}\" damping=\"{}\"/>\n",
          vec(e.position_m), number(e.spring_constant_n_per_m), number(e.start_distance_m), number(e.escape_distance_m),
          number(e.damping_n_s_per_m));
    }
    for (const auto& e : p.effects.viscosities) {
      out += fmt::format("      <ViscosityEffect viscosity=\"{}\" radius=\"{}\" dampingFactor=\"{}\" enabled=\"{}\"/>\n",
                         number(e.viscosity_pa_s), number(e.radius_m), number(e.damping_factor), e.enabled ? "true" : "false");
    }
    for (const auto& e : p.effects.constants) out += fmt::format("      <ForceField force=\"{}\"/>\n", vec(e.force_n));
    out += "    </effects>\n";
  }
  out += "  </haptics>\n";
  out += fmt::format("  <graphics viewpoint=\"{}\" lookAt=\"{}\" renderMode=\"{}\" colorBy=\"{}\">\n", vec(p.graphics.viewpoint_m),
                     vec(p.graphics.look_at_m), p.graphics.render_mode, p.graphics.color_by);
  out += fmt::format("    <material diffuseColor=\"{}\" specularColor=\"{}\" shininess=\"{}\" transparency=\"{}\"/>\n",
                     vec(p.graphics.diffuse_color), vec(p.graphics.specular_color), number(p.graphics.shininess),
                     number(p.graphics.transparency));
  out += fmt::format("    <light headlight=\"{}\" headlightIntensity=\"{}\" direction=\"{}\" intensity=\"{}\" ambientIntensity=\"{}\"/>\n",
                     p.graphics.headlight ? "true" : "false", number(p.graphics.headlight_intensity), vec(p.graphics.light_direction),
                     number(p.graphics.light_intensity), number(p.graphics.ambient_intensity));
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
