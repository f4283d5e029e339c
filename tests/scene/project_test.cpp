#include "hof/scene/project.h"
#include "hof/scene/project_edit.h"
#include "hof/scene/sofa_scene.h"

#include <gtest/gtest.h>

#include <cmath>
#include <filesystem>
#include <fstream>
#include <iterator>
#include <map>
#include <regex>
#include <sstream>

namespace hof::scene {
namespace {

std::string bytes(const std::filesystem::path& p) {
  std::ifstream in(p, std::ios::binary);
  return {std::istreambuf_iterator<char>(in), std::istreambuf_iterator<char>()};
}

TEST(Project, SaveLoadSaveIsByteIdentical) {
  const auto dir = std::filesystem::temp_directory_path() / "hof_project_test";
  std::filesystem::create_directories(dir);
  HofProject p;
  p.name = "round trip";
  p.mechanics_scene = "liver.scn";
  p.device = "scripted:circle,radius=0.02";
  p.renderer = haptics::RendererKind::kGodObject;
  p.proxy_radius_m = 0.003;
  p.surface.kind = haptics::SurfaceKind::kMagnetic;
  p.surface.stiffness = 0.1 + 0.2;  // not exactly representable: shortest round trip must hold
  p.position_calibration[0] = 3.0;
  p.graphics.viewpoint_m = Vec3(0.1, -0.4, 1.0 / 3.0);
  p.effects.springs.push_back(haptics::SpringEffect{Vec3(0.01, 0.02, 0.03), 150.0, 0.02, 0.03, 0.5, false});
  p.effects.viscosities.push_back(haptics::ViscosityEffect{});
  p.effects.constants.push_back(haptics::ConstantForceEffect{Vec3(0, 0, -0.5)});
  p.use_bound_tree = false;
  p.max_triangles_in_leaf = 4;
  ASSERT_TRUE(write_project(p, dir / "a.hof"));
  auto loaded = read_project(dir / "a.hof");
  ASSERT_TRUE(loaded) << loaded.error().to_string();
  ASSERT_TRUE(write_project(*loaded, dir / "b.hof"));
  EXPECT_EQ(bytes(dir / "a.hof"), bytes(dir / "b.hof"));
  EXPECT_EQ(loaded->surface.stiffness, 0.1 + 0.2);
  EXPECT_EQ(loaded->graphics.viewpoint_m, p.graphics.viewpoint_m);
  EXPECT_EQ(loaded->renderer, haptics::RendererKind::kGodObject);
  ASSERT_EQ(loaded->effects.springs.size(), 1u);
  EXPECT_EQ(loaded->effects.springs[0].spring_constant_n_per_m, 150.0);
  EXPECT_EQ(loaded->effects.constants[0].force_n, Vec3(0, 0, -0.5));
  EXPECT_FALSE(loaded->use_bound_tree);
  EXPECT_EQ(loaded->max_triangles_in_leaf, 4);
  std::filesystem::remove_all(dir);
}

TEST(Project, BundledExamplesRoundTrip) {
  for (const auto& entry : std::filesystem::directory_iterator(HOF_SOURCE_DIR "/examples")) {
    if (entry.path().extension() != ".hof") continue;
    auto p = read_project(entry.path());
    ASSERT_TRUE(p) << p.error().to_string();
    EXPECT_EQ(to_xml(*p), bytes(entry.path())) << entry.path() << " is not in canonical form";
  }
}

TEST(Project, NeedleRoundTripsWithEveryParameter) {
  const auto dir = std::filesystem::temp_directory_path() / "hof_project_needle";
  std::filesystem::create_directories(dir);
  HofProject p;
  p.mechanics_scene = "liver.scn";
  procedures::NeedleConfig needle;
  needle.axis = procedures::NeedleAxis::kStylus;
  needle.geometry.length_m = 0.12;
  needle.tissue.model = procedures::NeedleForceModel::kSimoneOkamura;
  needle.tissue.capsule_m = 0.1 / 3.0;
  needle.tissue.fung_post.f0_n = -2.5;
  needle.tissue.friction.damping_negative_n_s_per_m2 = -1234.5;
  procedures::TissueNeedleParameters tumour = needle.tissue;
  tumour.model = procedures::NeedleForceModel::kFung;
  tumour.puncture_force_n = 1.5;
  tumour.pierceable = false;
  needle.bodies.emplace_back("Tumour", tumour);
  p.needle = needle;
  ASSERT_TRUE(write_project(p, dir / "a.hof"));
  auto loaded = read_project(dir / "a.hof");
  ASSERT_TRUE(loaded) << loaded.error().to_string();
  ASSERT_TRUE(loaded->needle);
  EXPECT_EQ(*loaded->needle, needle);
  ASSERT_TRUE(write_project(*loaded, dir / "b.hof"));
  EXPECT_EQ(bytes(dir / "a.hof"), bytes(dir / "b.hof"));
  // A body's set starts from the common one: only what it names differs.
  std::ofstream(dir / "partial.hof")
      << "<hof>\n  <mechanics scene=\"x.scn\"/>\n  <haptics>\n    <needle>\n"
         "      <tissue capsule=\"0.03\"/>\n      <tissue body=\"B\" punctureForce=\"1\"/>\n"
         "    </needle>\n  </haptics>\n</hof>\n";
  loaded = read_project(dir / "partial.hof");
  ASSERT_TRUE(loaded) << loaded.error().to_string();
  ASSERT_EQ(loaded->needle->bodies.size(), 1u);
  EXPECT_EQ(loaded->needle->bodies[0].second.capsule_m, 0.03);
  EXPECT_EQ(loaded->needle->bodies[0].second.puncture_force_n, 1.0);
  std::filesystem::remove_all(dir);
}

TEST(Project, NeedleErrorsNameTheLineAndAttribute) {
  const auto dir = std::filesystem::temp_directory_path() / "hof_project_needle_errors";
  std::filesystem::create_directories(dir);
  const auto error_of = [&](const std::string& tissue) {
    std::ofstream(dir / "bad.hof") << "<hof>\n  <mechanics scene=\"x.scn\"/>\n  <haptics>\n    <needle>\n      "
                                   << tissue << "\n    </needle>\n  </haptics>\n</hof>\n";
    auto p = read_project(dir / "bad.hof");
    return p ? std::string("accepted") : p.error().to_string();
  };
  EXPECT_NE(error_of("<tissue model=\"magic\"/>").find("bad.hof:5"), std::string::npos);
  EXPECT_NE(error_of("<tissue model=\"magic\"/>").find("fung or simone-okamura"), std::string::npos);
  EXPECT_NE(error_of("<tissue fungPre=\"1 2 3\"/>").find("fungPre"), std::string::npos);
  EXPECT_NE(error_of("<tissue capsule=\"-1\"/>").find("capsule"), std::string::npos);
  EXPECT_NE(error_of("<tissue body=\"Liver\" spreadRadius=\"0\"/>").find("Liver"), std::string::npos);
  EXPECT_NE(error_of("<scalpel/>").find("unknown element <scalpel>"), std::string::npos);
  std::filesystem::remove_all(dir);
}

TEST(Project, ErrorsNameTheFileLineAndAttribute) {
  const auto dir = std::filesystem::temp_directory_path() / "hof_project_errors";
  std::filesystem::create_directories(dir);
  std::ofstream(dir / "bad.hof") << "<hof>\n  <mechanics scene=\"x.scn\"/>\n  <haptics hapticRate=\"fast\"/>\n</hof>\n";
  auto p = read_project(dir / "bad.hof");
  ASSERT_FALSE(p);
  EXPECT_NE(p.error().to_string().find("bad.hof:3"), std::string::npos) << p.error().to_string();
  EXPECT_NE(p.error().message.find("hapticRate"), std::string::npos);
  std::ofstream(dir / "broken.hof") << "<hof>\n  <mechanics scene=\"x.scn\">\n</hof>\n";
  p = read_project(dir / "broken.hof");
  ASSERT_FALSE(p);
  EXPECT_NE(p.error().message.find("malformed XML"), std::string::npos);
  std::filesystem::remove_all(dir);
}

TEST(Project, InlineSceneRoundTripsAndLoads) {
  const auto dir = std::filesystem::temp_directory_path() / "hof_project_inline";
  std::filesystem::create_directories(dir);
  const std::string mesh = HOF_SOURCE_DIR "/data/models/liver-simple.msh";
  std::ofstream(dir / "inline.hof")
      << "<hof name=\"inline\">\n  <mechanics>\n    <Node name=\"root\" dt=\"0.01\" gravity=\"0 0 0\">\n"
         "      <Node name=\"Liver\">\n        <EulerImplicitSolver/>\n        <CGLinearSolver/>\n"
         "        <MeshGmshLoader name=\"l\" filename=\""
      << mesh
      << "\"/>\n"
         "        <MechanicalObject src=\"@l\"/>\n        <UniformMass totalMass=\"1\"/>\n"
         "        <MeshSpringForceField stiffness=\"100\"/>\n        <FixedConstraint indices=\"0 1 2\"/>\n"
         "      </Node>\n    </Node>\n  </mechanics>\n</hof>\n";
  auto p = read_project(dir / "inline.hof");
  ASSERT_TRUE(p) << p.error().to_string();
  EXPECT_TRUE(p->mechanics_scene.empty());
  ASSERT_TRUE(write_project(*p, dir / "a.hof"));
  auto again = read_project(dir / "a.hof");
  ASSERT_TRUE(again);
  ASSERT_TRUE(write_project(*again, dir / "b.hof"));
  EXPECT_EQ(bytes(dir / "a.hof"), bytes(dir / "b.hof"));
  auto scene = read_sofa_scene(scene_file(*again, dir / "a.hof"));
  ASSERT_TRUE(scene) << scene.error().to_string();
  ASSERT_EQ(scene->models.size(), 1u);
  EXPECT_EQ(scene->models[0].config.positions.size(), 192u);
  std::filesystem::remove_all(dir);
}

TEST(Project, ThesisAppendixFormatIsRead) {
  // The thesis' appendix project (well-formed: its listing closes <hof> twice), 2008 syntax.
  const auto dir = std::filesystem::temp_directory_path() / "hof_project_thesis";
  std::filesystem::create_directories(dir);
  std::ofstream(dir / "thesis.hof")
      << "<?xml version=\"1.0\" encoding=\"UTF-8\"?>\n<hof>\n  <sofa>\n    <sg>\n"
         "      <Node name=\"root\" dt=\"0.02\" showBehaviorModels=\"0\" gravity=\"0 0 0\">\n"
         "        <Object type=\"CGImplicit\" iterations=\"5\"/>\n"
         "        <Object type=\"MeshTopology\" name=\"mesh\" filename=\"" HOF_SOURCE_DIR
         "/data/models/liver-coarse.msh\" />\n"
         "        <Object type=\"MechanicalObject\" name=\"mechanics\" template=\"Vec3d\" />\n"
         "        <Object type=\"FixedConstraint\" name=\"fixed\" indices=\"11 86 87 124 128\"/>\n"
         "        <Object type=\"ExternalForceField\" name=\"extforce\" force=\"0 0 0\" />\n"
         "        <Object type=\"MeshSpringForceField\" name=\"spring\" stiffness=\"1000\" damping=\"5\" />\n"
         "        <Object type=\"UniformMass\" name=\"mass\" totalMass=\"1000\"/>\n"
         "      </Node>\n    </sg>\n  </sofa>\n"
         "  <h3d>\n    <graphics fullscreen=\"no\" mirrored=\"no\" renderMode=\"MONO\"/>\n"
         "    <haptics showTime=\"no\"><device filename=\"" HOF_ANCHORS_DIR
         "/h3d/settings/common/device/FalconDevice\"/></haptics>\n  </h3d>\n</hof>\n";
  auto p = read_project(dir / "thesis.hof");
  ASSERT_TRUE(p) << p.error().to_string();
  auto scene = read_sofa_scene(scene_file(*p, dir / "thesis.hof"));
  ASSERT_TRUE(scene) << scene.error().to_string();
  ASSERT_EQ(scene->models.size(), 1u);
  const auto& c = scene->models[0].config;
  EXPECT_EQ(c.positions.size(), 677u);
  EXPECT_EQ(c.ode.kind, mechanics::OdeSolverKind::kEulerImplicit);
  EXPECT_EQ(c.linear.iterations, 5);
  ASSERT_EQ(c.force_fields.size(), 1u);
  EXPECT_EQ(c.force_fields[0].mesh_springs->stiffness_n_per_m, 1000.0);
  // The <h3d> device file (H3D's stock Falcon settings) gives the calibration diag(3, 3, 3, 1).
  EXPECT_EQ(p->position_calibration[0], 3.0);
  EXPECT_EQ(p->position_calibration[5], 3.0);
  EXPECT_EQ(p->position_calibration[15], 1.0);
  std::filesystem::remove_all(dir);
}

TEST(ProjectAttribute, SetsByTheFilesOwnNamesAndChecksAsTheReaderDoes) {
  HofProject p;
  p.mechanics_scene = "liver.scn";
  const std::filesystem::path file = "memory.hof";
  ASSERT_TRUE(set_project_attribute(p, file, "haptics/surface", "stiffness", "0.4"));
  EXPECT_DOUBLE_EQ(p.surface.stiffness, 0.4);
  ASSERT_TRUE(set_project_attribute(p, file, "haptics", "renderer", "GodObjectRenderer"));
  EXPECT_EQ(p.renderer, haptics::RendererKind::kGodObject);
  ASSERT_TRUE(set_project_attribute(p, file, "graphics", "viewpoint", "0 -0.4 0.2"));
  EXPECT_EQ(p.graphics.viewpoint_m, Vec3(0.0, -0.4, 0.2));
  ASSERT_TRUE(set_project_attribute(p, file, "graphics/material", "diffuseColor", "0.5 0.2 0.1"));
  EXPECT_EQ(p.graphics.diffuse_color, Vec3(0.5, 0.2, 0.1));
  ASSERT_TRUE(set_project_attribute(p, file, "graphics/light", "headlight", "false"));
  ASSERT_TRUE(set_project_attribute(p, file, "graphics/light", "direction", "0 0 -1"));
  EXPECT_FALSE(p.graphics.headlight);
  EXPECT_EQ(p.graphics.light_direction, Vec3(0.0, 0.0, -1.0));
  EXPECT_FALSE(set_project_attribute(p, file, "graphics/light", "intensity", "1.5"));
  EXPECT_FALSE(set_project_attribute(p, file, "graphics/light", "direction", "0 0 0"));
  EXPECT_EQ(p.graphics.light_intensity, 0.3);
  ASSERT_TRUE(set_project_attribute(p, file, "graphics", "colorBy", "stress"));

  // The n-th of several elements of a kind.
  p.effects.springs.resize(2);
  ASSERT_TRUE(set_project_attribute(p, file, "haptics/effects/SpringEffect[2]", "springConstant", "250"));
  EXPECT_DOUBLE_EQ(p.effects.springs[1].spring_constant_n_per_m, 250.0);
  EXPECT_DOUBLE_EQ(p.effects.springs[0].spring_constant_n_per_m, haptics::SpringEffect{}.spring_constant_n_per_m);
  ASSERT_TRUE(set_project_attribute(p, file, "haptics/effects/SpringEffect", "position", "0 0.1 0"));
  EXPECT_EQ(p.effects.springs[0].position_m, Vec3(0.0, 0.1, 0.0));
  auto third = set_project_attribute(p, file, "haptics/effects/SpringEffect[3]", "springConstant", "1");
  ASSERT_FALSE(third);
  EXPECT_NE(third.error().message.find("has 2 <SpringEffect>"), std::string::npos) << third.error().message;
  EXPECT_FALSE(set_project_attribute(p, file, "haptics/effects/SpringEffect[0]", "springConstant", "1"));
  EXPECT_FALSE(set_project_attribute(p, file, "haptics/effects/SpringEffect[x]", "springConstant", "1"));

  const std::string before = to_xml(p);
  // Wrong names list the right ones; wrong values say what is allowed; nothing changes.
  auto e = set_project_attribute(p, file, "haptics/surface", "stifness", "0.4");
  ASSERT_FALSE(e);
  EXPECT_NE(e.error().message.find("stiffness"), std::string::npos) << e.error().message;
  e = set_project_attribute(p, file, "haptics/surfac", "stiffness", "0.4");
  ASSERT_FALSE(e);
  EXPECT_NE(e.error().message.find("surface"), std::string::npos) << e.error().message;
  e = set_project_attribute(p, file, "haptics", "renderer", "FastRenderer");
  ASSERT_FALSE(e);
  EXPECT_NE(e.error().message.find("RuspiniRenderer"), std::string::npos) << e.error().message;
  e = set_project_attribute(p, file, "graphics/material", "shininess", "2");
  ASSERT_FALSE(e);
  e = set_project_attribute(p, file, "graphics", "renderMode", "cartoon");
  ASSERT_FALSE(e);
  e = set_project_attribute(p, file, "haptics/surface", "stiffness", "a lot");
  ASSERT_FALSE(e);
  EXPECT_EQ(to_xml(p), before);
}

// A project that writes every element of <haptics> and <graphics>: a needle with a body's own
// tissue set, force effects of each kind, settings away from the defaults.
HofProject rich_project() {
  HofProject p;
  p.name = "rich";
  p.mechanics_scene = "liver.scn";
  p.device = "mouse";
  p.haptic_rate_hz = 2000.0;
  p.renderer = haptics::RendererKind::kGodObject;
  p.touchable_face = collision::TouchableFace::kFrontAndBack;
  p.coupling = coupling::ContactCoupling::kCompliance;
  p.position_calibration[3] = 0.125;
  p.surface.kind = haptics::SurfaceKind::kFrictional;
  p.surface.stiffness = 0.7;
  p.safety.max_force_n = 2.5;
  p.use_bound_tree = false;
  p.max_triangles_in_leaf = 4;
  p.needle = procedures::NeedleConfig{};
  p.needle->axis = procedures::NeedleAxis::kNormal;
  p.needle->tissue.model = procedures::NeedleForceModel::kSimoneOkamura;
  p.needle->bodies.emplace_back("Liver", procedures::TissueNeedleParameters{});
  p.needle->bodies.back().second.capsule_m = 0.015;
  p.effects.springs.resize(2);
  p.effects.springs[1].position_m = Vec3(0.01, 0.02, 0.03);
  p.effects.viscosities.resize(1);
  p.effects.constants.push_back(haptics::ConstantForceEffect{Vec3(0.0, 0.0, -0.5)});
  p.graphics.render_mode = RenderMode::kShadedWireframe;
  p.graphics.color_by = ColorBy::kStrain;
  p.graphics.headlight = false;
  return p;
}

// The written file's elements under <haptics> and <graphics>, each as the edit path names it
// (haptics/effects/SpringEffect[2]) with its attributes: the writer writes one element a line.
std::vector<std::pair<std::string, std::vector<std::pair<std::string, std::string>>>> written_settings(
    const std::string& xml) {
  std::vector<std::pair<std::string, std::vector<std::pair<std::string, std::string>>>> out;
  std::vector<std::string> path;                       // the open elements' names, with [n]
  std::vector<std::map<std::string, int>> counts{{}};  // children seen per open element
  std::istringstream lines(xml);
  const std::regex open_tag(R"(^(\s*)<([A-Za-z]+)(.*?)(/?)>$)");
  const std::regex attribute(R"re(([A-Za-z]+)="([^"]*)")re");
  for (std::string line; std::getline(lines, line);) {
    std::smatch m;
    if (line.find("</") != std::string::npos || line.starts_with("<?")) {
      if (line.find("</") != std::string::npos && !path.empty()) {
        path.pop_back();
        counts.pop_back();
      }
      continue;
    }
    if (!std::regex_match(line, m, open_tag)) continue;  // an inline scene's text
    const std::string name = m[2];
    const int n = ++counts.back()[name];
    const std::string part = n > 1 ? name + "[" + std::to_string(n) + "]" : name;
    std::string element;
    for (std::size_t i = 1; i < path.size(); ++i) element += path[i] + "/";  // path[0]: hof
    element += part;
    const std::string attributes = m[3];
    std::vector<std::pair<std::string, std::string>> values;
    for (std::sregex_iterator a(attributes.begin(), attributes.end(), attribute), end; a != end; ++a)
      values.emplace_back((*a)[1], (*a)[2]);
    if (!path.empty() && (element.starts_with("haptics") || element.starts_with("graphics")))
      out.emplace_back(element, values);
    if (m[4] != "/") {
      path.push_back(part);
      counts.emplace_back();
    }
  }
  return out;
}

TEST(ProjectEdit, EveryWrittenAttributeSetToItsValueLeavesTheProjectUnchanged) {
  const HofProject p = rich_project();
  const std::string xml = to_xml(p);
  const auto settings = written_settings(xml);
  std::size_t checked = 0;
  for (const auto& [element, attributes] : settings) {
    for (const auto& [attribute, value] : attributes) {
      HofProject q = p;
      auto ok = set_project_attribute(q, "memory.hof", element, attribute, value);
      ASSERT_TRUE(ok) << element << "@" << attribute << ": " << ok.error().message;
      EXPECT_EQ(to_xml(q), xml) << element << "@" << attribute;
      ++checked;
    }
  }
  // <haptics> 7, calibration 1, surface 7, safety 5, options 2, stylus 2, needle 8, two tissue
  // sets 16 + 17 (body), 2 springs 10, viscosity 4, force 1, graphics 4, material 4, light 5.
  EXPECT_EQ(checked, 7u + 1 + 7 + 5 + 2 + 2 + 8 + 16 + 17 + 10 + 4 + 1 + 4 + 4 + 5);
  // Saved, read and saved again: the same bytes.
  auto read = parse_project(xml, "memory.hof");
  ASSERT_TRUE(read) << read.error().to_string();
  EXPECT_EQ(to_xml(*read), xml);
}

TEST(ProjectEdit, IsTypedByWhatTheSettingBelongsTo) {
  const HofProject p = rich_project();
  const auto edit = [&](std::string_view element, std::string_view attribute, std::string_view value) {
    auto e = parse_project_edit(p, "memory.hof", element, attribute, value);
    EXPECT_TRUE(e) << element << "@" << attribute;
    return e.value_or(ProjectEdit{});
  };
  EXPECT_TRUE(std::holds_alternative<project_edit::Rendering>(edit("haptics", "renderer", "PenaltyRenderer")));
  EXPECT_EQ(std::get<project_edit::Rendering>(edit("haptics", "renderer", "PenaltyRenderer")).renderer,
            haptics::RendererKind::kPenalty);
  EXPECT_TRUE(std::holds_alternative<project_edit::Device>(edit("haptics", "device", "falcon")));
  EXPECT_TRUE(std::holds_alternative<project_edit::ForceLimit>(edit("haptics/safety", "maxForce", "3")));
  EXPECT_EQ(std::get<project_edit::ForceLimit>(edit("haptics/safety", "maxForce", "3")).max_force_n, 3.0);
  EXPECT_TRUE(std::holds_alternative<project_edit::Safety>(edit("haptics/safety", "fadeIn", "1")));
  EXPECT_TRUE(std::holds_alternative<project_edit::Calibration>(
      edit("haptics/calibration", "positionCalibration", "2 0 0 0 0 2 0 0 0 0 2 0 0 0 0 1")));
  const auto effects = edit("haptics/effects/ForceField", "force", "1 2 3");
  ASSERT_TRUE(std::holds_alternative<project_edit::Effects>(effects));
  EXPECT_EQ(std::get<project_edit::Effects>(effects).effects.constants[0].force_n, Vec3(1.0, 2.0, 3.0));
  const auto tissue = edit("haptics/needle/tissue[2]", "capsule", "0.01");
  ASSERT_TRUE(std::holds_alternative<project_edit::Needle>(tissue));
  EXPECT_EQ(std::get<project_edit::Needle>(tissue).needle.bodies[0].second.capsule_m, 0.01);
  EXPECT_EQ(std::get<project_edit::Needle>(tissue).needle.tissue, p.needle->tissue);
  const auto graphics = edit("graphics", "renderMode", "points");
  ASSERT_TRUE(std::holds_alternative<project_edit::Graphics>(graphics));
  EXPECT_EQ(std::get<project_edit::Graphics>(graphics).graphics.render_mode, RenderMode::kPoints);
  EXPECT_EQ(render_mode_name(RenderMode::kShadedWireframe), "shaded+wireframe");
  EXPECT_EQ(color_by_name(ColorBy::kStress), "stress");
}

TEST(ProjectEdit, EachKindOfErrorNamesTheSettingAndWhatIsKnown) {
  HofProject p = rich_project();
  const std::string before = to_xml(p);
  const auto message = [&](std::string_view element, std::string_view attribute, std::string_view value) {
    auto e = set_project_attribute(p, "memory.hof", element, attribute, value);
    EXPECT_FALSE(e) << element << "@" << attribute;
    return e ? std::string() : e.error().message;
  };
  const auto has = [](const std::string& text, std::string_view part) { return text.find(part) != std::string::npos; };
  // A path: NAME[n] malformed; past the count; no such element (the known listed); a section
  // not set by name.
  EXPECT_TRUE(has(message("haptics/effects/SpringEffect[0]", "damping", "1"), "is not NAME[n] with n >= 1"));
  EXPECT_TRUE(has(message("haptics/needle/tissue[3]", "capsule", "1"), "<hof/haptics/needle> has 2 <tissue>, not 3"));
  EXPECT_TRUE(has(message("haptics/effects/SpringEffect[2]/x", "a", "1"),
                  "no element <x> in <hof/haptics/effects/SpringEffect[2]> (it has: none)"));
  EXPECT_TRUE(has(message("haptic", "renderer", "PenaltyRenderer"),
                  "no element <haptic> in <hof> (it has: haptics, graphics)"));
  EXPECT_TRUE(has(message("bodies", "name", "Liver"), "<bodies> is not set by name here"));
  HofProject no_needle = p;
  no_needle.needle.reset();
  auto e = set_project_attribute(no_needle, "memory.hof", "haptics/needle", "axis", "motion");
  ASSERT_FALSE(e);
  EXPECT_TRUE(
      has(e.error().message,
          "no element <needle> in <hof/haptics> (it has: calibration, surface, safety, options, stylus, effects)"))
      << e.error().message;
  // An attribute the element does not have (its attributes listed; a body's tissue set has body).
  EXPECT_TRUE(has(message("haptics/safety", "maxforce", "1"),
                  "<hof/haptics/safety> has no attribute 'maxforce' (it has: fadeIn, fadeOut, maxSnapshotAge, "
                  "maxConsecutiveOverruns, maxForce)"));
  EXPECT_TRUE(has(message("haptics/needle/tissue[2]", "bodyName", "x"), "(it has: body, pierceable, model,"));
  EXPECT_TRUE(has(message("haptics/effects", "springConstant", "1"),
                  "<hof/haptics/effects> has no attribute 'springConstant' (it has: none)"));
  // A value the reader refuses: not a number, not a choice, out of range, and the checks of the
  // whole element (the surface, a tissue set, the needle, the haptic rate) — each as the file's
  // reader says it, after the setting and its value.
  EXPECT_TRUE(has(message("haptics/stylus", "radius", "wide"),
                  "'haptics/stylus@radius' = 'wide': <stylus> radius=\"wide\" is not a number"));
  EXPECT_TRUE(
      has(message("haptics", "touchableFace", "SIDE"), "unknown touchableFace \"SIDE\" (FRONT, BACK, FRONT_AND_BACK)"));
  EXPECT_TRUE(
      has(message("graphics", "colorBy", "heat"), "unknown colorBy \"heat\" (material, displacement, strain, stress)"));
  EXPECT_TRUE(has(message("haptics/options", "maxTrianglesInLeaf", "0.5"), "must be a whole number from 1 to 1000000"));
  EXPECT_TRUE(has(message("haptics/light", "x", "1"), "no element <light> in <hof/haptics>"));
  EXPECT_TRUE(has(message("graphics/light", "useless", "1"), "has no attribute 'useless'"));
  EXPECT_TRUE(
      has(message("graphics/light", "headlight", "maybe"), "<light> headlight=\"maybe\" must be true or false"));
  EXPECT_TRUE(has(message("graphics/material", "diffuseColor", "1 2 3"),
                  "<material> diffuseColor must be three numbers in [0, 1]"));
  EXPECT_TRUE(has(message("haptics/effects/SpringEffect[2]", "position", "1 2"), "must be three numbers"));
  EXPECT_TRUE(has(message("haptics/needle/tissue", "fungPre", "1 2 3"), "must be 4 numbers (a 1/m, b N, d0 m, F0 N)"));
  EXPECT_TRUE(
      has(message("haptics/calibration", "positionCalibration", "1 0 0"), "positionCalibration must be 16 numbers"));
  EXPECT_TRUE(
      has(message("haptics/surface", "staticFriction", "2"), "surface: staticFriction must be in [0, 1], got 2"));
  EXPECT_TRUE(has(message("haptics/safety", "maxForce", "-1"), "<safety> maxForce must be >= 0 N"));
  EXPECT_TRUE(
      has(message("haptics/needle", "velocityFilter", "2"), "<needle> velocityFilter must be in [0, 1] s, got 2"));
  EXPECT_TRUE(has(message("haptics/needle", "tipLength", "1"), "needle"));
  EXPECT_TRUE(has(message("haptics/needle/tissue[2]", "body", ""), "<tissue body=\"\">: name the body"));
  EXPECT_TRUE(has(message("haptics", "hapticRate", "50"), "hapticRate must be in [100, 20000] Hz, got 50"));
  // A typed graphics edit is checked by the same rule, in the same words.
  GraphicsSetup g = p.graphics;
  g.transparency = 1.5;
  ASSERT_FALSE(check_graphics(g));
  EXPECT_EQ(check_graphics(g).error().message, "<material> transparency must be in [0, 1], got 1.5");
  EXPECT_TRUE(has(message("graphics/material", "transparency", "1.5"), check_graphics(g).error().message));
  g = p.graphics;
  g.viewpoint_m.x() = std::nan("");
  EXPECT_FALSE(check_graphics(g));
  auto refused = set_project_attribute(p, "memory.hof", "haptics/surface", "stiffness", "-1");
  ASSERT_FALSE(refused);
  EXPECT_EQ(refused.error().file, "memory.hof");  // a value refused names the project, as a file's error does
  EXPECT_EQ(to_xml(p), before);                   // nothing changed
}

}  // namespace
}  // namespace hof::scene

namespace hof::scene {
namespace {

// <contact>: every attribute and the pairs switched off read, written and read again equal; the
// bodies' contact="…" too.
TEST(ProjectContact, RoundTripsEverySettingAndPair) {
  const std::string text =
      "<hof version=\"1\" name=\"contact\">\n  <mechanics scene=\"organs.scn\"/>\n"
      "  <bodies>\n    <body name=\"Liver\" contact=\"true\"/>\n    <body name=\"Stomach\" contact=\"false\"/>\n"
      "    <obstacle name=\"Table\" mesh=\"table.obj\" translation=\"0 0 -0.1\" contact=\"false\"/>\n  </bodies>\n"
      "  <contact enabled=\"true\" response=\"friction\" stiffness=\"2500\" friction=\"0.4\" "
      "alarmDistance=\"0.004\" contactDistance=\"0.0015\" selfCollision=\"true\">\n"
      "    <pair a=\"Liver\" b=\"Table\" enabled=\"false\"/>\n    <pair a=\"Liver\" b=\"Stomach\"/>\n"
      "  </contact>\n</hof>\n";
  auto p = parse_project(text, "contact.hof");
  ASSERT_TRUE(p) << p.error().to_string();
  ASSERT_TRUE(p->contact);
  const coupling::ContactSettings& s = p->contact->settings;
  EXPECT_TRUE(s.enabled);
  EXPECT_EQ(s.response, coupling::ContactResponse::kFrictionConstraint);
  EXPECT_EQ(s.stiffness_n_per_m, 2500.0);
  EXPECT_EQ(s.friction, 0.4);
  EXPECT_EQ(s.alarm_distance_m, 0.004);
  EXPECT_EQ(s.contact_distance_m, 0.0015);
  EXPECT_TRUE(s.self_collision);
  // Only the pair switched off is kept (a pair left on is the default).
  ASSERT_EQ(p->contact->disabled_pairs.size(), 1u);
  EXPECT_EQ(p->contact->disabled_pairs[0], (std::pair<std::string, std::string>{"Liver", "Table"}));
  ASSERT_EQ(p->bodies.size(), 2u);
  EXPECT_EQ(p->bodies[0].contact, true);
  EXPECT_EQ(p->bodies[1].contact, false);
  EXPECT_EQ(p->obstacles[0].contact, false);
  // read → write → read: equal, and the text canonical from then on.
  const std::string written = to_xml(*p);
  auto again = parse_project(written, "contact.hof");
  ASSERT_TRUE(again) << again.error().to_string();
  ASSERT_TRUE(again->contact);
  EXPECT_EQ(again->contact->settings.response, s.response);
  EXPECT_EQ(again->contact->settings.stiffness_n_per_m, s.stiffness_n_per_m);
  EXPECT_EQ(again->contact->settings.friction, s.friction);
  EXPECT_EQ(again->contact->settings.alarm_distance_m, s.alarm_distance_m);
  EXPECT_EQ(again->contact->settings.contact_distance_m, s.contact_distance_m);
  EXPECT_EQ(again->contact->settings.self_collision, s.self_collision);
  EXPECT_EQ(again->contact->disabled_pairs, p->contact->disabled_pairs);
  EXPECT_EQ(again->bodies[1].contact, false);
  EXPECT_EQ(again->obstacles[0].contact, false);
  EXPECT_EQ(to_xml(*again), written);
  EXPECT_NE(written.find("<pair a=\"Liver\" b=\"Table\" enabled=\"false\"/>"), std::string::npos) << written;
  // A bare <contact/>: on, with the documented defaults, written in full.
  auto bare = parse_project("<hof>\n  <mechanics scene=\"x.scn\"/>\n  <contact/>\n</hof>\n", "bare.hof");
  ASSERT_TRUE(bare) << bare.error().to_string();
  ASSERT_TRUE(bare->contact);
  EXPECT_TRUE(bare->contact->settings.enabled);
  EXPECT_EQ(bare->contact->settings.response, coupling::ContactResponse::kPenalty);
  EXPECT_NE(to_xml(*bare).find("<contact enabled=\"true\" response=\"penalty\" stiffness=\"1000\" friction=\"0\" "
                               "alarmDistance=\"0.005\" contactDistance=\"0.001\" selfCollision=\"false\"/>"),
            std::string::npos)
      << to_xml(*bare);
  // No <contact>: none written (the bundled examples stay as they are).
  auto none = parse_project("<hof>\n  <mechanics scene=\"x.scn\"/>\n</hof>\n", "none.hof");
  ASSERT_TRUE(none);
  EXPECT_FALSE(none->contact);
  EXPECT_EQ(to_xml(*none).find("<contact"), std::string::npos);
}

TEST(ProjectContact, BadSettingsNameTheFileAndLine) {
  const auto error_of = [](const std::string& contact) {
    auto p = parse_project("<hof>\n  <mechanics scene=\"x.scn\"/>\n  " + contact + "\n</hof>\n", "bad.hof");
    return p ? std::string("accepted") : p.error().to_string();
  };
  struct Case {
    std::string contact;
    std::string says;
  };
  for (const Case& c : {Case{"<contact stiffness=\"-1\"/>", "<contact> stiffness must be ≥ 0 N/m, got -1"},
                        Case{"<contact alarmDistance=\"-0.01\"/>", "alarmDistance must be ≥ 0 m"},
                        Case{"<contact contactDistance=\"-0.01\"/>", "contactDistance must be ≥ 0 m"},
                        Case{"<contact friction=\"-0.2\"/>", "friction must be ≥ 0"},
                        Case{"<contact alarmDistance=\"0.001\" contactDistance=\"0.002\"/>",
                             "contactDistance 0.002 is larger than alarmDistance 0.001"},
                        Case{"<contact response=\"springs\"/>", "response=\"springs\": expected penalty"},
                        Case{"<contact enabled=\"maybe\"/>", "enabled=\"maybe\" must be true or false"},
                        Case{"<contact><pair a=\"Liver\"/></contact>", "<pair> needs a="},
                        Case{"<contact><group/></contact>", "unknown element <group> in <contact>"}}) {
    const std::string e = error_of(c.contact);
    EXPECT_NE(e.find("bad.hof:3"), std::string::npos) << e;
    EXPECT_NE(e.find(c.says), std::string::npos) << e;
  }
  auto p = parse_project(
      "<hof>\n  <mechanics scene=\"x.scn\"/>\n  <bodies>\n    <body name=\"L\" contact=\"yes\"/>\n"
      "  </bodies>\n</hof>\n",
      "bad.hof");
  ASSERT_FALSE(p);
  EXPECT_NE(p.error().to_string().find("bad.hof:4"), std::string::npos) << p.error().to_string();
  EXPECT_NE(p.error().message.find("<body> contact=\"yes\" must be true or false"), std::string::npos);
}

}  // namespace
}  // namespace hof::scene
