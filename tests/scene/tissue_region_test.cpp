// Heterogeneous tissue: regions give elements their own modulus, Poisson ratio and density
// (by sphere, box or Gmsh physical group), and the bundled tumour example is found by
// palpation — a press above the tumour meets more force at the same indentation than presses
// away from it, and than the same press on the liver without its tumour.

#include <gtest/gtest.h>

#include <filesystem>
#include <fstream>

#include "hof/coupling/press_recorder.h"
#include "hof/coupling/session.h"
#include "hof/haptics/device.h"
#include "hof/mechanics/mechanical_model.h"
#include "hof/scene/device_config.h"
#include "hof/scene/project.h"
#include "hof/scene/world.h"

namespace hof::scene {
namespace {

namespace fs = std::filesystem;
const fs::path kExamples = fs::path(HOF_SOURCE_DIR) / "examples";

struct Palpation {
  std::vector<coupling::Press> presses;
  std::vector<double> force_at_4mm;  // per press, −1 when the press did not reach it
};

Palpation palpate(const HofProject& project) {
  auto world = build_world(project, kExamples / "liver-tumour-palpation.hof");
  EXPECT_TRUE(world) << world.error().to_string();
  if (!world) return {};
  auto device = scene::open_device(world->device);
  EXPECT_TRUE(device) << device.error().to_string();
  const double duration = (*device)->script_duration_s();
  coupling::SessionConfig config = world->config;
  config.haptics.realtime_priority = false;
  auto session = coupling::Session::make(std::move(world->bodies), std::move(*device), config);
  EXPECT_TRUE(session) << session.error().to_string();
  if (!session) return {};
  coupling::PressRecorder recorder(**session);
  (*session)->run_virtual(duration, [&](const haptics::HapticSample& s) { recorder.add(s); });
  Palpation out;
  out.presses = recorder.presses();
  for (const coupling::Press& p : out.presses) {
    // Mean of the loading force over 3.5–5 mm: the bins around 4 mm.
    double sum = 0.0;
    int n = 0;
    for (double d : {0.00375, 0.00425, 0.00475}) {
      const double f = recorder.force_at(p, d);
      if (f >= 0.0) {
        sum += f;
        ++n;
      }
    }
    out.force_at_4mm.push_back(n ? sum / n : -1.0);
  }
  return out;
}

TEST(TumourPalpation, ThePressAboveTheTumourMeetsMoreForceAtTheSameIndentation) {
  auto project = read_project(kExamples / "liver-tumour-palpation.hof");
  ASSERT_TRUE(project) << project.error().to_string();
  ASSERT_EQ(project->regions.size(), 1u);
  const Vec3 tumour = project->regions[0].center;
  const Palpation with = palpate(*project);
  ASSERT_EQ(with.presses.size(), 5u) << "the sweep presses five times";
  // The press whose first contact is closest to above the tumour, and the two farthest.
  std::size_t above = 0;
  const auto lateral = [&](const coupling::Press& p) { return (p.first_contact - tumour).head<2>().norm(); };
  for (std::size_t k = 0; k < with.presses.size(); ++k) {
    if (lateral(with.presses[k]) < lateral(with.presses[above])) above = k;
  }
  EXPECT_EQ(above, 2u);
  ASSERT_GT(with.force_at_4mm[above], 0.0);
  for (std::size_t away : {std::size_t{0}, std::size_t{4}}) {
    EXPECT_GT(lateral(with.presses[away]), 0.025);
    ASSERT_GT(with.force_at_4mm[away], 0.0);
    EXPECT_GT(with.force_at_4mm[above], 1.5 * with.force_at_4mm[away]) << "press " << away + 1;
    EXPECT_GT(with.presses[above].stiffness, 1.3 * with.presses[away].stiffness) << "press " << away + 1;
  }
  // The same sweep without the tumour: the press above it is no stiffer than the others.
  HofProject healthy = *project;
  healthy.regions.clear();
  const Palpation without = palpate(healthy);
  ASSERT_EQ(without.presses.size(), 5u);
  ASSERT_GT(without.force_at_4mm[above], 0.0);
  EXPECT_GT(with.force_at_4mm[above], 1.4 * without.force_at_4mm[above]);
  EXPECT_LT(without.presses[above].stiffness, 1.3 * without.presses[0].stiffness);
}

TEST(TissueRegions, PoissonRatioAndDensityByRegionAndTheirErrors) {
  auto world = build_world(kExamples / "liver-palpation-medium-fem.hof");
  ASSERT_TRUE(world) << world.error().to_string();
  mechanics::ModelConfig config = *world->bodies[0].config;
  MaterialRegion lobe;
  lobe.name = "lobe";
  lobe.body = "Liver";
  lobe.shape = MaterialRegion::Shape::kBox;
  lobe.box_min = Vec3(-0.2, -0.2, -0.2);
  lobe.box_max = Vec3(0.0, 0.2, 0.2);
  lobe.poisson_ratio = 0.3;
  lobe.mass_density_kg_per_m3 = 2000.0;
  auto count = apply_material_region(config, lobe);
  ASSERT_TRUE(count) << count.error().to_string();
  EXPECT_GT(*count, 100u);
  EXPECT_LT(*count, config.tets.size());
  const auto& fem = *config.force_fields[0].tetrahedron_fem;
  EXPECT_TRUE(fem.element_young_modulus_pa.empty());  // not set by this region
  ASSERT_EQ(fem.element_poisson_ratio.size(), config.tets.size());
  ASSERT_EQ(config.mass.element_mass_density_kg_per_m3.size(), config.tets.size());
  const auto base = mechanics::build_model(*world->bodies[0].config);
  const auto model = mechanics::build_model(config);
  ASSERT_TRUE(model) << model.error().to_string();
  EXPECT_EQ(model->force_fields.size(), 2u);  // one per Poisson ratio
  // The heavier half: (2000 − 1060) kg/m³ more over its volume.
  EXPECT_GT(model->total_mass_kg(), 1.3 * base->total_mass_kg());

  MaterialRegion bad = lobe;
  bad.poisson_ratio = 0.5;
  EXPECT_FALSE(apply_material_region(config, bad));
  bad = lobe;
  bad.poisson_ratio.reset();
  bad.mass_density_kg_per_m3.reset();
  auto nothing = apply_material_region(config, bad);
  ASSERT_FALSE(nothing);
  EXPECT_NE(nothing.error().message.find("sets nothing"), std::string::npos);
  bad = lobe;
  bad.shape = MaterialRegion::Shape::kGroup;
  bad.physical_group = 7;
  config.element_regions.clear();
  auto no_groups = apply_material_region(config, bad);
  ASSERT_FALSE(no_groups);
  EXPECT_NE(no_groups.error().message.find("no physical groups"), std::string::npos) << no_groups.error().message;
}

TEST(TissueRegions, AGmshPhysicalGroupSelectsItsTetrahedra) {
  // Two tetrahedra sharing a face, physical groups 1 and 2.
  const fs::path dir = fs::temp_directory_path() / "hof_tissue_groups";
  fs::create_directories(dir);
  std::ofstream(dir / "two.msh")
      << "$MeshFormat\n2.2 0 8\n$EndMeshFormat\n$Nodes\n5\n1 0 0 0\n2 1 0 0\n3 0 1 0\n4 0 0 1\n5 0 0 -1\n"
         "$EndNodes\n$Elements\n2\n1 4 2 1 1 1 2 3 4\n2 4 2 2 2 1 3 2 5\n$EndElements\n";
  std::ofstream(dir / "two.scn")
      << "<Node name=\"root\" gravity=\"0 0 0\">\n  <Node name=\"Body\">\n    <EulerImplicitSolver/>\n"
         "    <CGLinearSolver/>\n    <MeshGmshLoader name=\"l\" filename=\"two.msh\"/>\n"
         "    <MechanicalObject src=\"@l\"/>\n    <DiagonalMass massDensity=\"1000\"/>\n"
         "    <TetrahedronFEMForceField name=\"FEM\" youngModulus=\"1000\"/>\n"
         "    <FixedProjectiveConstraint indices=\"0 1 2\"/>\n  </Node>\n</Node>\n";
  std::ofstream(dir / "two.hof")
      << "<hof version=\"1\" name=\"groups\">\n  <mechanics scene=\"two.scn\">\n"
         "    <region name=\"hard\" body=\"Body\" shape=\"group\" physicalGroup=\"2\" youngModulus=\"9000\"/>\n"
         "  </mechanics>\n</hof>\n";
  auto world = build_world(dir / "two.hof");
  ASSERT_TRUE(world) << world.error().to_string();
  const auto& config = *world->bodies[0].config;
  ASSERT_EQ(config.element_regions, (std::vector<std::int32_t>{1, 2}));
  EXPECT_EQ(config.force_fields[0].tetrahedron_fem->element_young_modulus_pa, (std::vector<double>{0.0, 9000.0}));
  // Round trip of the region through the project file.
  auto project = read_project(dir / "two.hof");
  ASSERT_TRUE(project);
  EXPECT_NE(to_xml(*project).find("shape=\"group\" physicalGroup=\"2\" youngModulus=\"9000\""), std::string::npos)
      << to_xml(*project);
  fs::remove_all(dir);
}

}  // namespace
}  // namespace hof::scene

namespace hof::scene {
namespace {

TEST(BodyModel, AnX3dDeformableShapeBecomesAMembrane) {
  const fs::path x3d = fs::path(HOF_ANCHORS_DIR) / "h3d/examples/All/DeformableShape.x3d";
  const fs::path dir = fs::temp_directory_path() / "hof_body_model";
  fs::create_directories(dir);
  // The X3D world names its deformable shape; find it first.
  auto plain = build_world(x3d);
  ASSERT_TRUE(plain) << plain.error().to_string();
  std::string name;
  for (const auto& b : plain->bodies) {
    if (b.config) name = b.name;
  }
  ASSERT_FALSE(name.empty());
  std::ofstream(dir / "drum.hof")
      << "<hof version=\"1\" name=\"drum\">\n  <mechanics scene=\"" << x3d.string()
      << "\"/>\n  <haptics device=\"scripted:poke,start=0;0;0.1,direction=0;0;-1,depth=0.01\"/>\n"
      << "  <bodies>\n    <body name=\"" << name << "\" model=\"membrane\"/>\n  </bodies>\n</hof>\n";
  auto world = build_world(dir / "drum.hof");
  ASSERT_TRUE(world) << world.error().to_string();
  const coupling::SessionBody* body = nullptr;
  for (const auto& b : world->bodies) {
    if (b.name == name) body = &b;
  }
  ASSERT_NE(body, nullptr);
  ASSERT_TRUE(body->config);
  ASSERT_EQ(body->config->force_fields.size(), 1u);
  ASSERT_TRUE(body->config->force_fields[0].triangle_fem);
  const auto& fem = *body->config->force_fields[0].triangle_fem;
  EXPECT_EQ(body->config->force_fields[0].name, "membrane");
  EXPECT_NEAR(fem.poisson_ratio, 1.0 / 3.0, 1e-12);
  EXPECT_GT(fem.young_modulus_pa, 0.0);
  EXPECT_EQ(body->model->force_fields[0]->type_name(), "TriangleFEMForceField");
  // The project's device stays the project's (the scene's DeviceInfo does not override it).
  EXPECT_NE(world->device.find("scripted:poke"), std::string::npos) << world->device;

  // A volume cannot take a surface model: the error names the body.
  std::ofstream(dir / "bad.hof")
      << "<hof version=\"1\" name=\"bad\">\n  <mechanics scene=\"" << (kExamples / "liver-medium-fem.scn").string()
      << "\"/>\n  <bodies>\n    <body name=\"Liver\" model=\"membrane\"/>\n  </bodies>\n</hof>\n";
  auto bad = build_world(dir / "bad.hof");
  ASSERT_FALSE(bad);
  EXPECT_NE(bad.error().message.find("<body name=\"Liver\" model=\"membrane\">"), std::string::npos)
      << bad.error().message;
  fs::remove_all(dir);
}

}  // namespace
}  // namespace hof::scene

namespace hof::scene {
namespace {

TEST(BodyModel, AVolumeBodyFilledWithHexahedraKeepsItsSurfaceMaterialAndSupports) {
  auto project = read_project(kExamples / "liver-palpation-medium-hex.hof");
  ASSERT_TRUE(project) << project.error().to_string();
  // With a tumour region too: regions apply to the hexahedra.
  MaterialRegion tumour;
  tumour.name = "tumour";
  tumour.body = "Liver";
  tumour.center = Vec3(0.03, 0.0, 0.036);
  tumour.radius = 0.015;
  tumour.young_modulus_pa = 54000.0;
  project->regions.push_back(tumour);
  auto world = build_world(*project, kExamples / "liver-palpation-medium-hex.hof");
  ASSERT_TRUE(world) << world.error().to_string();
  const coupling::SessionBody& body = world->bodies[0];
  const auto& config = *body.config;
  EXPECT_TRUE(config.tets.empty());
  EXPECT_EQ(config.hexahedra.size(), body.model->hexahedra.size());
  EXPECT_GT(config.hexahedra.size(), 100u);
  // The fine surface (the tetrahedral liver's boundary), mapped into the grid.
  EXPECT_EQ(body.surface.triangles.size(), 3380u);
  EXPECT_FALSE(body.mapping.is_identity());
  // The material: the scene's FEM (E 5.4 kPa, ν 0.45, large), the tumour's cells stiffer.
  ASSERT_TRUE(config.force_fields[0].hexahedron_fem);
  const auto& fem = *config.force_fields[0].hexahedron_fem;
  EXPECT_DOUBLE_EQ(fem.young_modulus_pa, 5400.0);
  EXPECT_DOUBLE_EQ(fem.poisson_ratio, 0.45);
  EXPECT_GT(std::count(fem.element_young_modulus_pa.begin(), fem.element_young_modulus_pa.end(), 54000.0), 0);
  // The base stays held: every held node of the grid lies near the liver's held base.
  EXPECT_GT(body.model->fixed_dofs.size(), 30u);
  double highest = -1.0;
  for (const std::int32_t dof : body.model->fixed_dofs)
    highest = std::max(highest, config.positions[static_cast<std::size_t>(dof / 3)].z());
  EXPECT_LT(highest, 0.0);  // the liver spans z −0.038 to 0.054; its base is held
  // About the same mass: the grid covers the liver within a cell, its surface cells half full.
  auto tet_world = build_world(kExamples / "liver-palpation-medium-fem.hof");
  ASSERT_TRUE(tet_world);
  EXPECT_NEAR(body.model->total_mass_kg(), tet_world->bodies[0].model->total_mass_kg(),
              0.25 * tet_world->bodies[0].model->total_mass_kg())
      << "half-full surface cells (fillWeighted)";
}

}  // namespace
}  // namespace hof::scene
