// Compliance coupling: a slow press into the medium liver. The force felt at each
// indentation must match the static FEM reaction at that indentation, solved separately
// (the pressed node held at the device position, a static Newton solve with LDLT), within 10%
// along the press and in size.

#include <fmt/format.h>
#include <gtest/gtest.h>

#include "hof/coupling/session.h"
#include "hof/haptics/device_backends/scripted_device.h"
#include "hof/mechanics/step.h"
#include "hof/mesh/boundary.h"
#include "hof/mesh/liver_generator.h"

#include "coupling/resting_liver.h"

namespace hof::coupling {
namespace {

mechanics::ModelConfig liver_config(const mesh::Mesh& liver) {
  mechanics::ModelConfig c = testing::resting_liver_config(liver);
  c.ode.rayleigh_mass = 1.0;  // strongly damped: the press is quasi-static
  c.ode.rayleigh_stiffness = 0.1;
  c.linear.iterations = 100;
  c.dt_s = 0.02;
  return c;
}

// Internal elastic force at `node` when it is held at `position` and the rest of the liver
// is in static equilibrium: what the tissue pushes back on the probe with.
Vec3 static_reaction(const mesh::Mesh& liver, std::int32_t node, const Vec3& position) {
  mechanics::ModelConfig c = liver_config(liver);
  c.fixed.push_back(mechanics::FixedConstraintConfig{"probe", {node}, std::nullopt, false, {true, true, true}});
  c.ode.kind = mechanics::OdeSolverKind::kStatic;
  c.ode.newton_iterations = 30;
  c.ode.newton_residual_tolerance_n = 1e-9;
  c.linear.kind = mechanics::LinearSolverKind::kSparseLdlt;
  auto model = mechanics::build_model(c);
  EXPECT_TRUE(model);
  mechanics::MechanicalState state = mechanics::make_state(*model);
  state.x.segment<3>(3 * node) = position;
  EXPECT_TRUE(mechanics::step(*model, state));
  Eigen::VectorXd internal = Eigen::VectorXd::Zero(state.x.size());
  model->force_fields[0]->add_force(state.x, state.v, state.field_states[0], internal);
  return internal.segment<3>(3 * node);
}

TEST(ComplianceCoupling, FeltForceMatchesTheStaticFemReactionWithinTenPercent) {
  const mesh::Mesh liver = *mesh::generate_liver(mesh::LiverResolution::kMedium);
  const mesh::BoundarySurface b = mesh::extract_boundary(liver.nodes, liver.tets);
  // The highest surface node near (0.03, 0): the probe comes straight down onto it.
  std::int32_t node = -1;
  for (std::size_t s = 0; s < b.surface_to_volume.size(); ++s) {
    const Vec3& p = b.surface.vertices[s];
    if ((p.head<2>() - Eigen::Vector2d(0.03, 0.0)).norm() < 0.01 && (node < 0 || p.z() > liver.nodes[node].z())) {
      node = b.surface_to_volume[s];
    }
  }
  ASSERT_GE(node, 0);
  const Vec3 top = liver.nodes[node];

  auto model = mechanics::build_model(liver_config(liver));
  ASSERT_TRUE(model);
  auto mapping = SurfaceMapping::by_index(liver.nodes, b.surface.vertices, b.surface_to_volume);
  ASSERT_TRUE(mapping);
  // slow: 1 mm per 0.25 s
  const haptics::MotionConfig motion =
      haptics::MotionConfig::poke(top + Vec3(0, 0, 0.004), Vec3(0, 0, -1), 0.004, 0.004, 0.004, 0.5);
  auto scripted = haptics::ScriptedMotion::make(motion);
  ASSERT_TRUE(scripted);
  haptics::DeviceSpec spec;
  spec.max_force_n = 50.0;
  spec.max_stiffness_n_per_m = 2000.0;
  SessionConfig config;
  config.coupling = ContactCoupling::kCompliance;
  config.haptics.renderer.kind = haptics::RendererKind::kGodObject;
  config.haptics.material.stiffness = 1.0;
  config.haptics.safety.fade_in_s = 0.0;
  config.haptics.realtime_priority = false;
  auto session = Session::make(SessionBody{"liver", std::move(*model), b.surface, std::move(*mapping), {}, {}},
                               std::make_unique<haptics::ScriptedDevice>(*scripted, spec), config);
  ASSERT_TRUE(session) << session.error().to_string();
  std::vector<haptics::HapticSample> samples;
  const SessionReport report =
      (*session)->run_virtual(2.6, [&](const haptics::HapticSample& s) { samples.push_back(s); });
  ASSERT_FALSE(report.diverged) << report.divergence;
  EXPECT_EQ(report.fall_through_events, 0);

  int compared = 0;
  for (const double depth : {0.001, 0.002, 0.003, 0.004}) {
    // The sample whose device is closest to this depth below the rest surface, in contact.
    const haptics::HapticSample* best = nullptr;
    for (const auto& s : samples) {
      if (!s.contact || s.time_s < 0.5) continue;
      if (!best || std::abs(top.z() - s.device.z() - depth) < std::abs(top.z() - best->device.z() - depth)) best = &s;
    }
    ASSERT_NE(best, nullptr);
    const Vec3 expected = static_reaction(liver, node, best->device);
    const Vec3 felt = best->force;
    // Along the press, and in size, within 10%. Sideways the two differ by construction: the
    // reference holds the node in all three directions, while the frictionless proxy slides on
    // the tilting surface, so the sideways part depends on the mesh's local shape (between 4%
    // and 11% of the force on the medium livers that different compilers once generated); the
    // whole vector is held to 20%, which still catches a force pointing the wrong way.
    const std::string where =
        fmt::format("depth {}: felt ({:.4f} {:.4f} {:.4f}) N, static FEM ({:.4f} {:.4f} {:.4f}) N", depth, felt.x(),
                    felt.y(), felt.z(), expected.x(), expected.y(), expected.z());
    EXPECT_LT(std::abs(felt.z() - expected.z()), 0.10 * std::abs(expected.z())) << where;
    EXPECT_LT(std::abs(felt.norm() - expected.norm()), 0.10 * expected.norm()) << where;
    EXPECT_LT((felt - expected).norm(), 0.20 * expected.norm()) << where;
    ++compared;
  }
  EXPECT_EQ(compared, 4);
}

}  // namespace
}  // namespace hof::coupling
