// Structural scene edits (the window's scene tree) and material regions: an edited scene
// reads back as the models the edit asked for, files stay found when a scene moves into a
// project elsewhere, and regions give their tetrahedra their own modulus through a round trip.

#include "hof/scene/sofa_scene_edit.h"

#include <fmt/format.h>
#include <gtest/gtest.h>

#include <algorithm>
#include <filesystem>
#include <fstream>

#include "hof/scene/project.h"
#include "hof/scene/sofa_scene.h"
#include "hof/scene/world.h"

namespace hof::scene {
namespace {

namespace fs = std::filesystem;

const fs::path kExamples = fs::path(HOF_SOURCE_DIR) / "examples";
const fs::path kTutorial = fs::path(HOF_ANCHORS_DIR) / "sofa" / "TutorialForceFieldLiverFEM.scn";

fs::path temp_folder(const std::string& name) {
  const fs::path dir = fs::temp_directory_path() / "hof_scene_edit_test" / name;
  fs::remove_all(dir);
  fs::create_directories(dir);
  return dir;
}

mechanics::ModelConfig only_model(const std::string& text, const fs::path& where) {
  auto scene = read_sofa_scene_text(text, where);
  EXPECT_TRUE(scene) << (scene ? "" : scene.error().to_string());
  if (!scene || scene->models.size() != 1) return {};
  return scene->models[0].config;
}

TEST(SceneEdit, AnInlinedSceneFindsItsMeshFromAnotherFolder) {
  const fs::path folder = temp_folder("inline");
  auto text = inline_scene(kTutorial, folder);
  ASSERT_TRUE(text) << text.error().to_string();
  // The loader's file now names the anchor's mesh from the new folder.
  EXPECT_EQ(text->find("filename=\"mesh/liver.msh\""), std::string::npos);
  EXPECT_EQ(text->find("<?xml"), std::string::npos);
  const mechanics::ModelConfig c = only_model(*text, folder / "project.hof");
  EXPECT_EQ(c.positions.size(), 181u);
  // Re-anchoring back to the anchor's folder gives names that resolve there again.
  const std::string back = reanchor_scene_files(*text, folder, kTutorial.parent_path());
  EXPECT_EQ(only_model(back, kTutorial).positions.size(), 181u);
}

TEST(SceneEdit, ReplacingTheForceFieldAndTheSolverReadsBackAsAskedAndKeepsTheRest) {
  const fs::path folder = temp_folder("replace");
  auto text = inline_scene(kTutorial, folder);
  ASSERT_TRUE(text);
  const fs::path where = folder / "project.hof";
  const mechanics::ModelConfig before = only_model(*text, where);

  // Neo-Hookean with the same small-strain E and ν: SOFA's ParameterSet is (μ, k).
  const double young = 50.0, poisson = 0.45;
  const double mu = young / (2.0 * (1.0 + poisson)), bulk = young / (3.0 * (1.0 - 2.0 * poisson));
  auto neo = edit_scene(*text, {SceneEdit::Action::kReplace,
                                "LiverFEM",
                                "FEM",
                                "TetrahedronHyperelasticityFEMForceField",
                                {{"materialName", "NeoHookean"}, {"ParameterSet", fmt::format("{} {}", mu, bulk)}}});
  ASSERT_TRUE(neo) << neo.error().to_string();
  auto solver = edit_scene(
      *neo, {SceneEdit::Action::kReplace, "LiverFEM", "cg_odesolver", "EulerExplicitSolver", {{"symplectic", "1"}}});
  ASSERT_TRUE(solver) << solver.error().to_string();
  const mechanics::ModelConfig after = only_model(*solver, where);
  ASSERT_EQ(after.force_fields.size(), 1u);
  ASSERT_TRUE(after.force_fields[0].neo_hookean.has_value());
  EXPECT_EQ(after.force_fields[0].name, "FEM");
  EXPECT_NEAR(after.force_fields[0].neo_hookean->young_modulus_pa, young, 1e-9 * young);
  EXPECT_NEAR(after.force_fields[0].neo_hookean->poisson_ratio, poisson, 1e-12);
  EXPECT_EQ(after.ode.kind, mechanics::OdeSolverKind::kEulerExplicit);
  EXPECT_EQ(after.ode.name, "cg_odesolver");
  // Everything else is as it was.
  EXPECT_EQ(after.positions.size(), before.positions.size());
  EXPECT_EQ(after.fixed.size(), before.fixed.size());
  EXPECT_EQ(after.mass.total_mass_kg, before.mass.total_mass_kg);
  EXPECT_EQ(after.dt_s, before.dt_s);
}

TEST(SceneEdit, AddAndRemoveComponentsAndNameWhatIsMissing) {
  const fs::path folder = temp_folder("add");
  auto text = inline_scene(kTutorial, folder);
  ASSERT_TRUE(text);
  const fs::path where = folder / "project.hof";
  auto removed = edit_scene(*text, {SceneEdit::Action::kRemove, "LiverFEM", "FixedProjectiveConstraint", "", {}});
  ASSERT_TRUE(removed) << removed.error().to_string();
  auto added = edit_scene(
      *removed,
      {SceneEdit::Action::kAdd, "LiverFEM", "push", "ConstantForceField", {{"indices", "5"}, {"forces", "0 0.1 0"}}});
  ASSERT_TRUE(added) << added.error().to_string();
  const mechanics::ModelConfig c = only_model(*added, where);
  EXPECT_TRUE(c.fixed.empty());
  ASSERT_EQ(c.force_fields.size(), 2u);
  EXPECT_EQ(c.force_fields[1].name, "push");
  ASSERT_TRUE(c.force_fields[1].constant_force.has_value());
  EXPECT_EQ(c.force_fields[1].constant_force->indices, std::vector<std::int32_t>{5});

  auto missing = edit_scene(*text, {SceneEdit::Action::kRemove, "LiverFEM", "FEM2", "", {}});
  ASSERT_FALSE(missing);
  EXPECT_NE(missing.error().message.find("no component 'FEM2'"), std::string::npos) << missing.error().message;
  EXPECT_NE(missing.error().message.find("FEM"), std::string::npos);
  auto no_node = edit_scene(*text, {SceneEdit::Action::kRemove, "Kidney", "FEM", "", {}});
  ASSERT_FALSE(no_node);
  EXPECT_NE(no_node.error().message.find("no node 'Kidney'"), std::string::npos);
  auto twice = edit_scene(*text, {SceneEdit::Action::kAdd, "LiverFEM", "FEM", "TetrahedronFEMForceField", {}});
  EXPECT_FALSE(twice);
}

TEST(SceneEdit, A2008SceneIsEditedInItsOwnSyntax) {
  const fs::path scene = fs::path(HOF_ANCHORS_DIR) / "sofa" / "history" / "2008-07-30_14f43fd649" / "liver.scn";
  if (!fs::exists(scene)) GTEST_SKIP() << "no 2008 liver anchor";
  const fs::path folder = temp_folder("legacy");
  auto text = inline_scene(scene, folder);
  ASSERT_TRUE(text) << text.error().to_string();
  const mechanics::ModelConfig before = only_model(*text, folder / "p.hof");
  ASSERT_FALSE(before.force_fields.empty());
  const std::string name = before.force_fields[0].name;
  auto edited = edit_scene(*text, {SceneEdit::Action::kReplace,
                                   before.name,
                                   name,
                                   "TetrahedronFEMForceField",
                                   {{"youngModulus", "800"}, {"poissonRatio", "0.3"}, {"method", "polar"}}});
  ASSERT_TRUE(edited) << edited.error().to_string();
  EXPECT_NE(edited->find("<Object type=\"TetrahedronFEMForceField\""), std::string::npos);
  const mechanics::ModelConfig after = only_model(*edited, folder / "p.hof");
  ASSERT_TRUE(after.force_fields[0].tetrahedron_fem.has_value());
  EXPECT_EQ(after.force_fields[0].tetrahedron_fem->young_modulus_pa, 800.0);
  EXPECT_EQ(after.force_fields[0].tetrahedron_fem->method, mechanics::FemMethod::kPolar);
}

TEST(SceneEdit, APerElementYoungModulusIsReadAsRegionsAndAWrongLengthIsRefused) {
  const fs::path folder = temp_folder("vector");
  auto text = inline_scene(kTutorial, folder);
  ASSERT_TRUE(text);
  const mechanics::ModelConfig c = only_model(*text, folder / "p.hof");
  std::string values;
  for (std::size_t t = 0; t < c.tets.size(); ++t) values += t == 7 ? "400 " : "50 ";
  auto listed = edit_scene(*text, {SceneEdit::Action::kReplace,
                                   "LiverFEM",
                                   "FEM",
                                   "TetrahedronFEMForceField",
                                   {{"youngModulus", values}, {"poissonRatio", "0.45"}}});
  ASSERT_TRUE(listed);
  const mechanics::ModelConfig regions = only_model(*listed, folder / "p.hof");
  const auto& fem = *regions.force_fields[0].tetrahedron_fem;
  EXPECT_EQ(fem.young_modulus_pa, 50.0);
  ASSERT_EQ(fem.element_young_modulus_pa.size(), c.tets.size());
  EXPECT_EQ(fem.element_young_modulus_pa[7], 400.0);
  EXPECT_EQ(fem.element_young_modulus_pa[8], 0.0);

  auto short_list = edit_scene(
      *text,
      {SceneEdit::Action::kReplace, "LiverFEM", "FEM", "TetrahedronFEMForceField", {{"youngModulus", "50 60 70"}}});
  ASSERT_TRUE(short_list);
  auto refused = read_sofa_scene_text(*short_list, folder / "p.hof");
  ASSERT_FALSE(refused);
  EXPECT_NE(refused.error().message.find("one per tetrahedron"), std::string::npos) << refused.error().message;
}

TEST(MaterialRegion, ASphereStiffensTheTetrahedraInsideAndRoundTripsThroughTheProject) {
  auto project = read_project(kExamples / "liver-palpation-medium-fem.hof");
  ASSERT_TRUE(project) << project.error().to_string();
  MaterialRegion tumour;
  tumour.name = "tumour";
  tumour.body = "Liver";
  tumour.center = Vec3(0.0, 0.0, 0.04);
  tumour.radius = 0.025;
  tumour.young_modulus_pa = 54000.0;
  project->regions.push_back(tumour);
  const fs::path file = kExamples / "liver-palpation-medium-fem.hof";
  auto world = build_world(*project, file);
  ASSERT_TRUE(world) << world.error().to_string();
  const auto& config = *world->bodies[0].config;
  const auto& fem = *config.force_fields[0].tetrahedron_fem;
  ASSERT_EQ(fem.element_young_modulus_pa.size(), config.tets.size());
  std::size_t inside = 0;
  for (std::size_t t = 0; t < config.tets.size(); ++t) {
    Vec3 centroid = Vec3::Zero();
    for (const std::int32_t n : config.tets[t]) centroid += config.positions[static_cast<std::size_t>(n)] / 4.0;
    const bool in = (centroid - tumour.center).norm() <= tumour.radius;
    EXPECT_EQ(fem.element_young_modulus_pa[t], in ? 54000.0 : 0.0) << "tetrahedron " << t;
    inside += in ? 1 : 0;
  }
  EXPECT_GT(inside, 10u);
  EXPECT_LT(inside, config.tets.size() / 2);

  const std::string xml = to_xml(*project);
  EXPECT_NE(xml.find("<region name=\"tumour\" body=\"Liver\" shape=\"sphere\" center=\"0 0 0.04\" radius=\"0.025\" "
                     "youngModulus=\"54000\"/>"),
            std::string::npos)
      << xml;
  auto again = parse_project(xml, file);
  ASSERT_TRUE(again) << again.error().to_string();
  EXPECT_EQ(to_xml(*again), xml);

  MaterialRegion wrong = tumour;
  wrong.force_field = "springs";
  project->regions = {wrong};
  auto refused = build_world(*project, file);
  ASSERT_FALSE(refused);
  EXPECT_NE(refused.error().message.find("<region name=\"tumour\""), std::string::npos) << refused.error().message;
  EXPECT_NE(refused.error().message.find("no FEM force field 'springs'"), std::string::npos) << refused.error().message;
}

}  // namespace
}  // namespace hof::scene
