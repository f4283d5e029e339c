// The haptic-rate coupling (issue 17): the simulation steps once per haptic tick and the force
// felt at every tick is the FEM's own reaction of the step before it: the tissue's elastic
// force summed over the contact's neighbourhood, computed here independently from the body's
// state by a model of our own. A press into the liver, in virtual time.

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

// The haptic-rate settings: dt = the haptic period, few warm-started two-level CG iterations,
// matrix reused.
mechanics::ModelConfig haptic_rate_config(const mesh::Mesh& liver) {
  mechanics::ModelConfig c = testing::resting_liver_config(liver);
  c.ode.rayleigh_mass = 0.1;
  c.ode.rayleigh_stiffness = 0.1;
  c.dt_s = 1e-3;
  mechanics::use_haptic_rate_solver(c.linear, c.ode, c.positions.size());
  return c;
}

struct Press {
  std::unique_ptr<Session> session;
  mesh::BoundarySurface boundary;
  Vec3 top;
};

Press make_press(const mesh::Mesh& liver, ContactCoupling coupling, double dt_s = 1e-3, double depth_m = 0.005) {
  Press p;
  p.boundary = mesh::extract_boundary(liver.nodes, liver.tets);
  std::int32_t best = -1;
  for (std::size_t s = 0; s < p.boundary.surface.vertices.size(); ++s) {
    const Vec3& v = p.boundary.surface.vertices[s];
    if ((v.head<2>() - Eigen::Vector2d(0.03, 0.0)).norm() < 0.015 && (best < 0 || v.z() > p.top.z())) {
      best = static_cast<std::int32_t>(s);
      p.top = v;
    }
  }
  EXPECT_GE(best, 0);
  mechanics::ModelConfig config = haptic_rate_config(liver);
  config.dt_s = dt_s;
  auto model = mechanics::build_model(config);
  EXPECT_TRUE(model) << model.error().to_string();
  auto mapping = SurfaceMapping::by_index(liver.nodes, p.boundary.surface.vertices, p.boundary.surface_to_volume);
  EXPECT_TRUE(mapping);
  const haptics::MotionConfig motion =
      haptics::MotionConfig::poke(p.top + Vec3(0, 0, 0.003), Vec3(0, 0, -1), 0.003, depth_m, 0.02, 0.6);
  auto scripted = haptics::ScriptedMotion::make(motion);
  EXPECT_TRUE(scripted);
  haptics::DeviceSpec spec;
  spec.max_force_n = 50.0;
  spec.max_stiffness_n_per_m = 2000.0;
  SessionConfig session_config;
  session_config.coupling = coupling;
  session_config.haptics.rate_hz = 1000.0;
  session_config.haptics.renderer.kind = haptics::RendererKind::kGodObject;
  session_config.haptics.material.stiffness = 1.0;
  session_config.haptics.safety.fade_in_s = 0.0;
  session_config.haptics.realtime_priority = false;
  auto session = Session::make(SessionBody{"liver", std::move(*model), p.boundary.surface, std::move(*mapping), {}, {}},
                               std::make_unique<haptics::ScriptedDevice>(*scripted, spec), session_config);
  if (session)
    p.session = std::move(*session);
  else
    ADD_FAILURE() << session.error().to_string();
  return p;
}

TEST(FemReactionCoupling, TheForceFeltAtEveryTickIsTheFemReactionOfTheStepBefore) {
  const mesh::Mesh liver = *mesh::generate_liver(mesh::LiverResolution::kSimple);
  Press press = make_press(liver, ContactCoupling::kFemReaction);
  ASSERT_TRUE(press.session);
  Session& session = *press.session;
  // Our own copy of the mechanics, to recompute the reaction from the body's state alone.
  auto reference = mechanics::build_model(haptic_rate_config(liver));
  ASSERT_TRUE(reference);
  mechanics::MechanicalState scratch = mechanics::make_state(*reference);

  struct Seen {
    haptics::HapticSample sample;
    Vec3 reaction_before{Vec3::Zero()};  // the FEM reaction at the previous tick's contact
    bool previous_contact{false};
  };
  std::vector<Seen> seen;
  haptics::HapticSample previous;
  bool have_previous = false;
  const SessionReport report = session.run_virtual(1.0, [&](const haptics::HapticSample& s) {
    Seen e{s, Vec3::Zero(), have_previous && previous.contact};
    if (e.previous_contact) {
      // The body's state now is the one after the last step: its reaction at the contact that
      // step was loaded at (the previous tick's).
      // The patch the coupling sums over: the surface within 1 cm of the contact point (or two
      // of the contact triangle's longest edges), held nodes left out.
      const mesh::Tri& tri = press.boundary.surface.triangles[static_cast<std::size_t>(previous.triangle)];
      const Eigen::VectorXd& x = session.state(0).x;
      auto at = [&](std::int32_t surface_vertex) {
        return Vec3(x.segment<3>(
            3 * static_cast<Eigen::Index>(press.boundary.surface_to_volume[static_cast<std::size_t>(surface_vertex)])));
      };
      const Vec3 point = previous.barycentric[0] * at(tri[0]) + previous.barycentric[1] * at(tri[1]) +
                         previous.barycentric[2] * at(tri[2]);
      double longest = 0.0;
      for (int k = 0; k < 3; ++k) longest = std::max(longest, (at(tri[k]) - at(tri[(k + 1) % 3])).norm());
      const double radius = std::max(0.01, 2.0 * longest);
      std::vector<std::int32_t> nodes;
      for (std::size_t v = 0; v < press.boundary.surface.vertices.size(); ++v) {
        const std::int32_t node = press.boundary.surface_to_volume[v];
        if ((at(static_cast<std::int32_t>(v)) - point).norm() <= radius &&
            !reference->fixed_dof_mask[3 * static_cast<std::size_t>(node)]) {
          nodes.push_back(node);
        }
      }
      for (int k = 0; k < 3; ++k) nodes.push_back(press.boundary.surface_to_volume[static_cast<std::size_t>(tri[k])]);
      const std::vector<double> weights(nodes.size(), 1.0);
      scratch.x = session.state(0).x;
      scratch.v = session.state(0).v;
      e.reaction_before = mechanics::point_elastic_force(*reference, scratch, nodes, weights);
    }
    seen.push_back(e);
    previous = s;
    have_previous = true;
  });
  ASSERT_FALSE(report.diverged) << report.divergence;
  EXPECT_EQ(report.fall_through_events, 0);
  // One simulation step per haptic tick.
  EXPECT_EQ(report.simulation_steps, report.haptic_ticks);

  int compared = 0, differs_from_spring = 0;
  double largest = 0.0;
  for (const Seen& e : seen) {
    if (!e.sample.contact || !e.previous_contact) continue;
    const Vec3 expected = e.reaction_before.dot(e.sample.contact_normal) > 0.0 ? e.reaction_before : Vec3::Zero();
    const Vec3 felt = e.sample.requested_force;
    EXPECT_LT((felt - expected).norm(), 1e-9 + 1e-9 * expected.norm())
        << fmt::format("tick {}: felt ({:.6f} {:.6f} {:.6f}) N, FEM reaction ({:.6f} {:.6f} {:.6f}) N", e.sample.tick,
                       felt.x(), felt.y(), felt.z(), expected.x(), expected.y(), expected.z());
    // The renderer's spring (stiffness × penetration) would be another force: the mode is on.
    const double spring = 1.0 * 2000.0 * e.sample.penetration_m;
    if (std::abs(felt.norm() - spring) > 0.05 * spring) ++differs_from_spring;
    largest = std::max(largest, felt.norm());
    ++compared;
  }
  const Seen& last = seen[seen.size() - 2];  // the end of the hold (the press lasts 1 s)
  std::printf(
      "%d contact ticks compared; largest felt %.4f N; at the end of the hold: felt %.4f N, renderer spring %.4f N\n",
      compared, largest, last.sample.requested_force.norm(), 2000.0 * last.sample.penetration_m);
  EXPECT_GT(compared, 500);
  // While the tissue moves, its reaction is not the spring's force (inertia, damping: the
  // mode is on)...
  EXPECT_GT(differs_from_spring, 100);
  // ... and once it has settled under the held tool, the two balance (Newton's third law).
  ASSERT_TRUE(last.sample.contact);
  EXPECT_NEAR(last.sample.requested_force.norm(), 2000.0 * last.sample.penetration_m,
              0.02 * last.sample.requested_force.norm());
  // A 5 mm press into a 5.4 kPa liver pushes back with a force a hand feels.
  EXPECT_GT(largest, 0.05);
  EXPECT_LT(largest, 50.0);
}

TEST(FemReactionCoupling, NeedsOneSimulationStepPerHapticTick) {
  const mesh::Mesh liver = *mesh::generate_liver(mesh::LiverResolution::kSimple);
  const mesh::BoundarySurface b = mesh::extract_boundary(liver.nodes, liver.tets);
  mechanics::ModelConfig config = haptic_rate_config(liver);
  config.dt_s = 0.01;
  auto model = mechanics::build_model(config);
  ASSERT_TRUE(model);
  auto mapping = SurfaceMapping::by_index(liver.nodes, b.surface.vertices, b.surface_to_volume);
  ASSERT_TRUE(mapping);
  haptics::MotionConfig motion;
  auto scripted = haptics::ScriptedMotion::make(motion);
  ASSERT_TRUE(scripted);
  SessionConfig session_config;
  session_config.coupling = ContactCoupling::kFemReaction;
  auto session =
      Session::make(SessionBody{"liver", std::move(*model), b.surface, std::move(*mapping), {}, {}},
                    std::make_unique<haptics::ScriptedDevice>(*scripted, haptics::DeviceSpec{}), session_config);
  ASSERT_FALSE(session);
  EXPECT_NE(session.error().message.find("dt 0.01 s, the haptic period is 0.001 s"), std::string::npos)
      << session.error().message;

  // And a running session refuses a dt that breaks it.
  Press press = make_press(liver, ContactCoupling::kFemReaction);
  ASSERT_TRUE(press.session);
  auto refused = press.session->submit(
      command::SetParameter{BodyId{0}, {{mechanics::ComponentKind::kModel, 0}, mechanics::ParameterId::kDt}, 0.005});
  ASSERT_FALSE(refused);
  EXPECT_NE(refused.error().message.find("fem-reaction"), std::string::npos) << refused.error().message;
}

// The god-object (a point proxy) in the dent it presses, 12 mm deep into the soft liver. The
// dent's walls move between ticks; a proxy that slid along one wall ended up a fraction of a
// millimetre behind the next, the sweep toward the device never crossed that front face, and
// the proxy fell through to the device. It must stay on the surface while the hand is held in.
TEST(GodObjectInADent, StaysInContactAndNeverFallsThroughWhilePressedDeep) {
  const mesh::Mesh liver = *mesh::generate_liver(mesh::LiverResolution::kMedium);
  for (const ContactCoupling coupling : {ContactCoupling::kBarycentric, ContactCoupling::kFemReaction}) {
    Press p = make_press(liver, coupling, 1e-3, 0.010);
    ASSERT_TRUE(p.session);
    bool touched = false;
    int lost = 0;
    double deepest = 0.0;
    const SessionReport report = p.session->run_virtual(1.4, [&](const haptics::HapticSample& s) {
      const double depth = p.top.z() - s.device.z();
      if (s.contact) touched = true;
      // From 1 mm in to the end of the hold (the press takes 0.75 s, the hold 0.6 s).
      if (touched && depth > 0.001 && s.time_s < 1.35) {
        deepest = std::max(deepest, depth);
        if (!s.contact) ++lost;
      }
    });
    ASSERT_FALSE(report.diverged) << report.divergence;
    EXPECT_GT(deepest, 0.0099);
    EXPECT_EQ(lost, 0) << "ticks out of contact while pressed in";
    EXPECT_EQ(report.fall_through_events, 0);
  }
}

}  // namespace
}  // namespace hof::coupling
