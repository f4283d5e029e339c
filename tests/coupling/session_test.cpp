// The haptic session end to end in virtual time: a scripted poke into the simple liver.

#include "hof/coupling/session.h"

#include <gtest/gtest.h>

#include "hof/haptics/device_backends/scripted_device.h"
#include "hof/mechanics/step.h"
#include "hof/mesh/boundary.h"
#include "hof/mesh/liver_generator.h"

#include "coupling/resting_liver.h"

namespace hof::coupling {
namespace {

struct PokeRun {
  SessionReport report;
  std::vector<Vec3> forces;
  std::vector<Vec3> proxies;
};

PokeRun poke(ContactCoupling coupling, haptics::RendererKind renderer, double seconds = 1.5) {
  const mesh::Mesh liver = *mesh::generate_liver(mesh::LiverResolution::kSimple);
  const mesh::BoundarySurface b = mesh::extract_boundary(liver.nodes, liver.tets);
  mechanics::ModelConfig c = testing::resting_liver_config(liver);  // resting on its lowest centimetre
  c.ode.rayleigh_mass = c.ode.rayleigh_stiffness = 0.1;
  c.dt_s = 0.01;
  auto model = mechanics::build_model(c);
  EXPECT_TRUE(model) << model.error().to_string();
  auto mapping = SurfaceMapping::by_index(liver.nodes, b.surface.vertices, b.surface_to_volume);
  EXPECT_TRUE(mapping);
  SessionBody body{"liver", std::move(*model), b.surface, std::move(*mapping), {}, {}};

  // straight down onto the right lobe's top, 1.5 cm deep
  const haptics::MotionConfig motion =
      haptics::MotionConfig::poke(Vec3(0.03, 0.0, 0.09), Vec3(0, 0, -1), 0.04, 0.015, 0.05, 0.2);
  auto scripted = haptics::ScriptedMotion::make(motion);
  EXPECT_TRUE(scripted);
  haptics::DeviceSpec spec;
  spec.max_stiffness_n_per_m = 500.0;
  auto device = std::make_unique<haptics::ScriptedDevice>(*scripted, spec);

  SessionConfig config;
  config.coupling = coupling;
  config.haptics.renderer.kind = renderer;
  config.haptics.material.stiffness = 1.0;
  config.haptics.realtime_priority = false;
  auto session = Session::make(std::move(body), std::move(device), config);
  EXPECT_TRUE(session) << session.error().to_string();
  PokeRun run;
  run.report = (*session)->run_virtual(seconds, [&](const haptics::HapticSample& s) {
    run.forces.push_back(s.force);
    run.proxies.push_back(s.proxy);
  });
  return run;
}

TEST(Session, PokingTheLiverDeformsItWithoutFallThrough) {
  for (ContactCoupling coupling : {ContactCoupling::kClosestVertex, ContactCoupling::kBarycentric}) {
    const PokeRun run = poke(coupling, haptics::RendererKind::kRuspini);
    EXPECT_FALSE(run.report.diverged) << run.report.divergence;
    EXPECT_EQ(run.report.haptic_ticks, 1500);
    EXPECT_EQ(run.report.simulation_steps, 150);
    EXPECT_GT(run.report.contact_time_s, 0.1);
    EXPECT_GT(run.report.max_force_n, 0.5);
    EXPECT_GT(run.report.max_displacement_m, 0.002);  // the tissue gave way under the probe
    EXPECT_EQ(run.report.fall_through_events, 0);
  }
}

TEST(Session, DeterministicRunsAreIdentical) {
  const PokeRun a = poke(ContactCoupling::kBarycentric, haptics::RendererKind::kGodObject, 0.8);
  const PokeRun b = poke(ContactCoupling::kBarycentric, haptics::RendererKind::kGodObject, 0.8);
  EXPECT_EQ(a.forces, b.forces);
  EXPECT_EQ(a.proxies, b.proxies);
}

TEST(SurfaceMapping, ByIndexRefusesASurfaceThatDoesNotShareTheNodes) {
  const std::vector<Vec3> nodes = {Vec3(0, 0, 0), Vec3(1, 0, 0)};
  const std::vector<Vec3> surface = {Vec3(0, 0, 0), Vec3(1, 0.1, 0)};
  const std::vector<mesh::NodeIndex> map = {0, 1};
  auto m = SurfaceMapping::by_index(nodes, surface, map);
  ASSERT_FALSE(m);
  EXPECT_NE(m.error().message.find("surface vertex 1"), std::string::npos);
}

TEST(SurfaceMapping, BarycentricReproducesPointsInsideAndMovesWithTheVolume) {
  const std::vector<Vec3> nodes = {Vec3(0, 0, 0), Vec3(1, 0, 0), Vec3(0, 1, 0), Vec3(0, 0, 1)};
  const std::vector<mesh::Tet> tets = {{0, 1, 2, 3}};
  const std::vector<Vec3> surface = {Vec3(0.2, 0.3, 0.1), Vec3(0.0, 0.0, 0.5)};
  auto m = SurfaceMapping::barycentric(nodes, tets, surface);
  ASSERT_TRUE(m);
  std::vector<double> x = {0, 0, 0, 1, 0, 0, 0, 1, 0, 0, 0, 1};
  std::vector<Vec3> out(2);
  m->apply(x, out);
  EXPECT_LT((out[0] - surface[0]).norm(), 1e-12);
  for (std::size_t i = 0; i < x.size(); i += 3) x[i] += 0.5;  // translate the volume
  m->apply(x, out);
  EXPECT_LT((out[1] - (surface[1] + Vec3(0.5, 0, 0))).norm(), 1e-12);
  // A force on a surface point is spread by the same weights (sums to the force).
  std::vector<double> f(12, 0.0);
  m->add_vertex_force(0, Vec3(0, 0, 1), f);
  EXPECT_NEAR(f[2] + f[5] + f[8] + f[11], 1.0, 1e-12);
}

}  // namespace
}  // namespace hof::coupling
