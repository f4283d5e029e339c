// Sessions on worlds of several bodies: rigid shapes, two livers, force effects only, and the
// command seam — in virtual time (lock-step, deterministic) and in real time (two threads).

#include <fmt/format.h>
#include <gtest/gtest.h>
#include <array>

#include <chrono>
#include <cmath>
#include <limits>
#include <numbers>
#include <thread>

#include "hof/core/cpu_affinity.h"
#include "hof/coupling/session.h"
#include "hof/haptics/device_backends/scripted_device.h"
#include "hof/mechanics/model_parameters.h"
#include "hof/mesh/boundary.h"
#include "hof/mesh/liver_generator.h"

#include "coupling/resting_liver.h"
#include "support/allocation_counter.h"
#include "support/box_surface.h"

namespace hof::coupling {
namespace {

mesh::TriMesh box(const Vec3& lo, const Vec3& hi) { return hof::testing::box_surface(lo, hi); }

std::unique_ptr<haptics::ScriptedDevice> poke_device(const Vec3& start, const Vec3& direction, double approach,
                                                     double depth, double speed, double hold,
                                                     const haptics::DeviceSpec& spec = {}) {
  const haptics::MotionConfig motion = haptics::MotionConfig::poke(start, direction, approach, depth, speed, hold);
  auto scripted = haptics::ScriptedMotion::make(motion);
  EXPECT_TRUE(scripted) << scripted.error().to_string();
  return std::make_unique<haptics::ScriptedDevice>(*scripted, spec);
}

SessionConfig god_object_config() {
  SessionConfig config;
  config.haptics.renderer.kind = haptics::RendererKind::kGodObject;
  config.haptics.realtime_priority = false;
  config.haptics.safety.fade_in_s = 0.0;
  return config;
}

struct RigidRun {
  std::vector<haptics::HapticSample> samples;
  SessionReport report;
};

// A 4 cm box (top at y = 0) pressed from above along −y by a poke of `depth` past its top.
RigidRun press_rigid_box(double depth, double speed) {
  std::vector<SessionBody> bodies(1);
  bodies[0].name = "box";
  bodies[0].surface = box(Vec3(-0.02, -0.04, -0.02), Vec3(0.02, 0.0, 0.02));
  const SessionConfig config = god_object_config();
  auto session =
      Session::make(std::move(bodies), poke_device(Vec3(0, 0.05, 0), Vec3(0, -1, 0), 0.05, depth, speed, 0.3), config);
  EXPECT_TRUE(session) << session.error().to_string();
  RigidRun run;
  run.report = (*session)->run_virtual(5.0, [&](const haptics::HapticSample& s) { run.samples.push_back(s); });
  return run;
}

TEST(WorldSession, RigidShapeHoldsThePressAtStiffnessTimesPenetration) {
  const RigidRun run = press_rigid_box(0.003, 0.02);  // 3 mm: 1500 N/m × 3 mm = 4.5 N, below the 8 N limit
  const double k = 0.5 * haptics::DeviceSpec{}.max_stiffness_n_per_m;
  int held = 0;
  for (const haptics::HapticSample& s : run.samples) {
    if (!s.valid || !s.contact) continue;
    EXPECT_NEAR(s.proxy.y(), 0.0, 1e-4) << "the proxy leaves the rigid surface at t = " << s.time_s;
    const double penetration = -s.device.y();
    if (penetration > 0.0029) {
      ++held;
      EXPECT_NEAR(s.force.norm(), std::min(k * penetration, 8.0), 0.05) << "t = " << s.time_s;
    }
  }
  EXPECT_GT(held, 200);
  EXPECT_EQ(run.report.fall_through_events, 0);
  ASSERT_EQ(run.report.bodies.size(), 1u);
  EXPECT_FALSE(run.report.bodies[0].deformable);
  EXPECT_GT(run.report.bodies[0].contact_time_s, 0.2);
}

// A penalty renderer pushes only within its reach (5 cm): a device driven deeper into a large
// body than that is no longer pushed back, its proxy is inside, and the run must say so.
TEST(WorldSession, AProxyDeepInsideABodyIsCountedAsFallingThroughAndAStartInsideIsNot) {
  const auto run = [](const Vec3& start, double depth) {
    std::vector<SessionBody> bodies(1);
    bodies[0].name = "block";
    bodies[0].surface = box(Vec3(-0.1, -0.2, -0.1), Vec3(0.1, 0.0, 0.1));
    SessionConfig config = god_object_config();
    config.haptics.renderer.kind = haptics::RendererKind::kPenalty;
    auto session = Session::make(std::move(bodies), poke_device(start, Vec3(0, -1, 0), 0.0, depth, 0.1, 0.3), config);
    EXPECT_TRUE(session) << session.error().to_string();
    return (*session)->run_virtual(2.0, {});
  };
  const SessionReport through = run(Vec3(0, 0.01, 0), 0.09);  // 8 cm deep: beyond the renderer's reach
  EXPECT_GT(through.fall_through_events, 0);
  EXPECT_EQ(through.bodies[0].fall_through_events, through.fall_through_events);
  EXPECT_FALSE(through.bodies[0].probe_started_inside);
  const SessionReport grazing = run(Vec3(0, 0.01, 0), 0.012);  // 2 mm deep: pushed back, not through
  EXPECT_EQ(grazing.fall_through_events, 0);
  EXPECT_GT(grazing.contact_time_s, 0.1);
  const SessionReport started = run(Vec3(0, -0.1, 0), 0.01);  // starts 10 cm inside and stays there
  EXPECT_TRUE(started.bodies[0].probe_started_inside);
  EXPECT_EQ(started.fall_through_events, 0);
}

TEST(WorldSession, RigidShapePushedAtTheDeviceLimitStaysPutAndTheForceIsClamped) {
  const RigidRun run = press_rigid_box(0.03, 0.02);  // 3 cm: 45 N requested
  int clamped = 0;
  for (const haptics::HapticSample& s : run.samples) {
    if (!s.valid || !s.contact) continue;
    EXPECT_NEAR(s.proxy.y(), 0.0, 1e-4);
    EXPECT_LE(s.force.norm(), 8.0 + 1e-9);
    if (s.requested_force.norm() > 8.0) {
      ++clamped;
      EXPECT_NEAR(s.force.norm(), 8.0, 1e-6);
    }
  }
  EXPECT_GT(clamped, 100);
  EXPECT_EQ(run.report.fall_through_events, 0);
  EXPECT_GT(run.report.clamped_contact_ticks, 100);
}

TEST(CommandSeam, ALowerForceLimitHoldsFromTheNextStepAndIsLiftedAgain) {
  // The box pressed 3 cm deep (45 N requested): 8 N (the device), then 2 N (the user's limit),
  // then 8 N again once the limit is lifted (0).
  std::vector<SessionBody> bodies(1);
  bodies[0].name = "box";
  bodies[0].surface = box(Vec3(-0.02, -0.04, -0.02), Vec3(0.02, 0.0, 0.02));
  auto session = Session::make(std::move(bodies), poke_device(Vec3(0, 0.05, 0), Vec3(0, -1, 0), 0.05, 0.03, 0.05, 10.0),
                               god_object_config());
  ASSERT_TRUE(session) << session.error().to_string();
  EXPECT_FALSE((*session)->submit(command::SetForceLimit{-1.0}));
  EXPECT_FALSE((*session)->submit(command::SetForceLimit{std::nan("")}));
  // Held 3 cm deep from 1.6 s on; the limit is set at 2.5 s and lifted at 4 s (from the
  // telemetry callback: any thread may submit).
  std::array<double, 3> top{};
  bool lowered = false, lifted = false;
  (*session)->run_virtual(6.0, [&](const haptics::HapticSample& s) {
    if (s.time_s >= 2.5 && !lowered) lowered = static_cast<bool>((*session)->submit(command::SetForceLimit{2.0}));
    if (s.time_s >= 4.0 && !lifted) lifted = static_cast<bool>((*session)->submit(command::SetForceLimit{0.0}));
    const int window = s.time_s > 1.9 && s.time_s < 2.5   ? 0
                       : s.time_s > 2.6 && s.time_s < 4.0 ? 1
                       : s.time_s > 4.6                   ? 2
                                                          : -1;
    if (window >= 0)
      top[static_cast<std::size_t>(window)] = std::max(top[static_cast<std::size_t>(window)], s.force.norm());
  });
  ASSERT_TRUE(lowered && lifted);
  EXPECT_NEAR(top[0], 8.0, 1e-6);
  EXPECT_LE(top[1], 2.0 + 1e-9);
  EXPECT_NEAR(top[1], 2.0, 1e-6);
  EXPECT_NEAR(top[2], 8.0, 1e-6);
}

TEST(WorldSession, RigidShapeCrossedInOneTickDoesNotLetTheProxyThrough) {
  // 200 m/s: 20 cm a tick — from 5 cm above the box to 11 cm below its top (through its
  // whole 4 cm height) in one tick.
  const RigidRun run = press_rigid_box(0.11, 200.0);
  bool crossed = false;
  for (const haptics::HapticSample& s : run.samples) {
    if (!s.valid) continue;
    if (s.device.y() < -0.05) {
      crossed = true;
      EXPECT_TRUE(s.contact);
      EXPECT_NEAR(s.proxy.y(), 0.0, 1e-4) << "t = " << s.time_s;
      EXPECT_LE(s.force.norm(), 8.0 + 1e-9);
    }
  }
  EXPECT_TRUE(crossed);
  EXPECT_EQ(run.report.fall_through_events, 0);
}

// Two simple livers 30 cm apart, each with its own solver; the probe presses the first.
struct TwoLivers {
  std::unique_ptr<Session> session;
  std::vector<Vec3> rest_b;
};

TwoLivers two_livers(mesh::LiverResolution resolution, const Vec3& probe_start) {
  const mesh::Mesh liver = *mesh::generate_liver(resolution);
  std::vector<SessionBody> bodies;
  for (int i = 0; i < 2; ++i) {
    mesh::Mesh placed = liver;
    for (Vec3& p : placed.nodes) p.x() += 0.3 * i;
    const mesh::BoundarySurface b = mesh::extract_boundary(placed.nodes, placed.tets);
    mechanics::ModelConfig c = testing::resting_liver_config(placed);
    c.name = i == 0 ? "A" : "B";
    c.ode.rayleigh_mass = c.ode.rayleigh_stiffness = 0.1;
    auto model = mechanics::build_model(c);
    EXPECT_TRUE(model) << model.error().to_string();
    auto mapping = SurfaceMapping::by_index(placed.nodes, b.surface.vertices, b.surface_to_volume);
    EXPECT_TRUE(mapping);
    SessionBody body;
    body.name = c.name;
    body.model.emplace(std::move(*model));
    body.surface = b.surface;
    body.mapping = std::move(*mapping);
    body.config = c;
    bodies.push_back(std::move(body));
  }
  SessionConfig config;
  config.haptics.realtime_priority = false;
  auto session =
      Session::make(std::move(bodies), poke_device(probe_start, Vec3(0, 0, -1), 0.04, 0.01, 0.05, 0.3), config);
  EXPECT_TRUE(session) << session.error().to_string();
  TwoLivers t;
  t.session = std::move(*session);
  return t;
}

TEST(WorldSession, TouchingOneLiverLeavesTheOtherAtRest) {
  TwoLivers t = two_livers(mesh::LiverResolution::kSimple, Vec3(0.03, 0.0, 0.09));
  std::int64_t contacts_on_a = 0, contacts_elsewhere = 0;
  const SessionReport report = t.session->run_virtual(1.5, [&](const haptics::HapticSample& s) {
    if (!s.contact) return;
    (t.session->body_of_triangle(s.triangle) == 0 ? contacts_on_a : contacts_elsewhere) += 1;
  });
  EXPECT_FALSE(report.diverged) << report.divergence;
  EXPECT_GT(contacts_on_a, 100);
  EXPECT_EQ(contacts_elsewhere, 0);
  ASSERT_EQ(report.bodies.size(), 2u);
  EXPECT_GT(report.bodies[0].max_displacement_m, 5e-4) << "the pressed liver did not move";
  EXPECT_GT(report.bodies[0].contact_time_s, 0.1);
  EXPECT_EQ(report.bodies[1].contact_time_s, 0.0);
  // Both were simulated (as many steps), and the untouched one stayed at rest.
  const mechanics::MechanicalState& b = t.session->state(1);
  const auto& model_b = *t.session->body(1).model;
  for (std::size_t i = 0; i < model_b.node_count(); ++i) {
    ASSERT_LE((b.position(static_cast<std::int32_t>(i)) - model_b.rest_positions[i]).norm(), 1e-12) << "node " << i;
  }
  EXPECT_EQ(report.fall_through_events, 0);
}

TEST(WorldSession, TheSameLiverPressedAloneOrBesideAnotherGivesTheSameForces) {
  TwoLivers t = two_livers(mesh::LiverResolution::kSimple, Vec3(0.03, 0.0, 0.09));
  std::vector<Vec3> pair_forces;
  t.session->run_virtual(1.0, [&](const haptics::HapticSample& s) { pair_forces.push_back(s.force); });

  const mesh::Mesh liver = *mesh::generate_liver(mesh::LiverResolution::kSimple);
  const mesh::BoundarySurface b = mesh::extract_boundary(liver.nodes, liver.tets);
  mechanics::ModelConfig c = testing::resting_liver_config(liver);
  c.ode.rayleigh_mass = c.ode.rayleigh_stiffness = 0.1;
  SessionBody body{"A",       *mechanics::build_model(c),
                   b.surface, *SurfaceMapping::by_index(liver.nodes, b.surface.vertices, b.surface_to_volume),
                   {},        c};
  SessionConfig config;
  config.haptics.realtime_priority = false;
  auto alone =
      Session::make(std::move(body), poke_device(Vec3(0.03, 0.0, 0.09), Vec3(0, 0, -1), 0.04, 0.01, 0.05, 0.3), config);
  ASSERT_TRUE(alone);
  std::vector<Vec3> alone_forces;
  (*alone)->run_virtual(1.0, [&](const haptics::HapticSample& s) { alone_forces.push_back(s.force); });
  ASSERT_EQ(pair_forces.size(), alone_forces.size());
  for (std::size_t i = 0; i < pair_forces.size(); ++i) ASSERT_EQ(pair_forces[i], alone_forces[i]) << "tick " << i;
}

// ---- Force effects only: no shape at all.

TEST(WorldSession, EffectOnlyWorldRendersEachEffectsOwnFormulaAtEveryTick) {
  SessionConfig config;
  config.haptics.realtime_priority = false;
  config.haptics.safety.fade_in_s = 0.0;
  const Vec3 anchor(0.01, 0.02, 0.0);
  haptics::SpringEffect spring;
  spring.position_m = anchor;
  spring.spring_constant_n_per_m = 100.0;
  spring.start_distance_m = 1.0;  // holds the device from the first tick
  spring.escape_distance_m = 1.0;
  haptics::ViscosityEffect viscosity;
  viscosity.viscosity_pa_s = 50.0;
  haptics::ConstantForceEffect constant;
  constant.force_n = Vec3(0.0, 0.3, 0.0);
  config.effects.springs.push_back(spring);
  config.effects.viscosities.push_back(viscosity);
  config.effects.constants.push_back(constant);
  haptics::MotionConfig circle;
  circle.kind = haptics::MotionKind::kCircle;
  circle.centre_m = Vec3(0.0, 0.0, 0.0);
  circle.normal = Vec3(0, 0, 1);
  circle.radius_m = 0.02;
  circle.period_s = 1.0;
  circle.repeat = 0;
  auto motion = haptics::ScriptedMotion::make(circle);
  ASSERT_TRUE(motion);
  haptics::DeviceSpec spec;
  spec.max_force_rate_n_per_s = 1e6;  // the first tick's step up is the effects', not a slew
  auto session =
      Session::make(std::vector<SessionBody>{}, std::make_unique<haptics::ScriptedDevice>(*motion, spec), config);
  ASSERT_TRUE(session) << session.error().to_string();
  int checked = 0;
  const SessionReport report = (*session)->run_virtual(2.0, [&](const haptics::HapticSample& s) {
    ASSERT_TRUE(s.valid);
    // H3D: spring k (p − x) − d v; Stokes drag −dampingFactor · 6π μ r · v; the constant.
    const Vec3 expected = 100.0 * (anchor - s.device) -
                          0.5 * 6.0 * std::numbers::pi * 50.0 * 0.0025 * s.device_velocity + Vec3(0.0, 0.3, 0.0);
    ASSERT_LT((s.force - expected).norm(), 1e-9) << "t = " << s.time_s;
    ++checked;
  });
  EXPECT_EQ(checked, 2000);
  EXPECT_GT(report.max_force_n, 1.0);
  EXPECT_EQ(report.contact_time_s, 0.0);
  EXPECT_GT(report.simulation_steps, 0);
}

// ---- The command seam.

// The liver's springs (its only force field), its linear solver and the model itself.
constexpr BodyId kLiver{0};
constexpr BodyId kNoBody{1};
constexpr mechanics::ComponentRef kSprings{mechanics::ComponentKind::kForceField, 0};
constexpr mechanics::ParameterRef kStiffness{kSprings, mechanics::ParameterId::kStiffness};

std::unique_ptr<Session> springs_liver_session(std::unique_ptr<haptics::Device> device, int simulation_threads = 0,
                                               bool pin_threads = true) {
  const mesh::Mesh liver = *mesh::generate_liver(mesh::LiverResolution::kSimple);
  const mesh::BoundarySurface b = mesh::extract_boundary(liver.nodes, liver.tets);
  mechanics::ModelConfig c = testing::resting_liver_config(liver);
  c.name = "Liver";
  c.force_fields.clear();
  mechanics::ForceFieldConfig springs;
  springs.name = "springs";
  springs.mesh_springs = mechanics::MeshSpringConfig{50.0, 0.5, 1.0};
  c.force_fields.push_back(springs);
  c.ode.rayleigh_mass = c.ode.rayleigh_stiffness = 0.1;
  SessionBody body{"Liver",   *mechanics::build_model(c),
                   b.surface, *SurfaceMapping::by_index(liver.nodes, b.surface.vertices, b.surface_to_volume),
                   {},        c};
  SessionConfig config;
  config.haptics.realtime_priority = false;
  config.simulation_threads = simulation_threads;
  config.pin_threads = pin_threads;
  auto session = Session::make(std::move(body), std::move(device), config);
  EXPECT_TRUE(session) << session.error().to_string();
  return std::move(*session);
}

TEST(CommandSeam, ABadValueIsRefusedWithAMessageAndChangesNothing) {
  auto session = springs_liver_session(poke_device(Vec3(0.03, 0, 0.09), Vec3(0, 0, -1), 0.04, 0.01, 0.05, 0.3));
  for (double bad : {-5.0, std::nan(""), std::numeric_limits<double>::infinity()}) {
    auto refused = session->submit(command::SetParameter{kLiver, kStiffness, bad});
    ASSERT_FALSE(refused);
    EXPECT_NE(refused.error().message.find("springs/stiffness"), std::string::npos) << refused.error().message;
  }
  EXPECT_FALSE(session->submit(command::SetParameter{kNoBody, kStiffness, 10.0}));
  using mechanics::ComponentKind, mechanics::ParameterId;
  EXPECT_FALSE(session->submit(
      command::SetParameter{kLiver, {{ComponentKind::kForceField, 1}, ParameterId::kYoungModulus}, 10.0}));
  EXPECT_FALSE(session->submit(command::SetParameter{kLiver, {kSprings, ParameterId::kYoungModulus}, 10.0}));
  EXPECT_FALSE(session->submit(
      command::SetParameter{kLiver, {{ComponentKind::kLinearSolver, 0}, ParameterId::kIterations}, 2.5}));
  EXPECT_FALSE(session->submit(command::SetParameter{kLiver, {{ComponentKind::kModel, 0}, ParameterId::kDt}, 0.0}));
  EXPECT_FALSE(session->submit(command::SingleStep{0}));
  haptics::SurfaceMaterial negative;
  negative.stiffness = -1.0;
  EXPECT_FALSE(session->submit(command::SetMaterial{kLiver, negative}));
  const SessionReport report = session->run_virtual(0.1, {});
  EXPECT_TRUE(report.applied_commands.empty());
  EXPECT_TRUE(session->parameter_changes().empty());
  EXPECT_EQ(session->body().config->force_fields[0].mesh_springs->stiffness_n_per_m, 50.0);
}

TEST(CommandSeam, AStiffnessChangedInVirtualTimeActsAtTheNextStep) {
  // Two identical sessions; one gets stiffer springs after 1 s, while the probe presses (from
  // 0.8 s): the runs agree to that step and differ from the next one on. (Before the contact the
  // springs are at rest length and exert nothing, whatever their stiffness: the runs would
  // differ only by rounding, which an -O1 build does not produce.)
  auto a = springs_liver_session(poke_device(Vec3(0.03, 0, 0.09), Vec3(0, 0, -1), 0.04, 0.01, 0.05, 0.3));
  auto b = springs_liver_session(poke_device(Vec3(0.03, 0, 0.09), Vec3(0, 0, -1), 0.04, 0.01, 0.05, 0.3));
  const SessionReport pressed = a->run_virtual(1.0, {});
  b->run_virtual(1.0, {});
  ASSERT_GT(pressed.bodies.at(0).max_displacement_m, 1e-4) << "the probe must deform the liver before the change";
  ASSERT_TRUE(a->state().x.isApprox(b->state().x, 0.0));
  ASSERT_TRUE(b->submit(command::SetParameter{kLiver, kStiffness, 500.0}));
  EXPECT_TRUE(b->parameter_changes().empty()) << "recorded once applied, not when submitted";
  const SessionReport rb = b->run_virtual(0.01, {});  // one step
  a->run_virtual(0.01, {});
  ASSERT_EQ(rb.applied_commands.size(), 1u);
  EXPECT_EQ(rb.applied_commands[0], "step 0: Liver/springs/stiffness = 500");
  EXPECT_FALSE(a->state().x.isApprox(b->state().x, 0.0)) << "the change did not act at the next step";
  EXPECT_EQ(b->body().config->force_fields[0].mesh_springs->stiffness_n_per_m, 500.0);
  ASSERT_EQ(b->parameter_changes().size(), 1u);
  EXPECT_EQ(b->parameter_changes()[0].value, 500.0);
}

TEST(CommandSeam, AModelSwitchedMidRunStartsFromTheCurrentShapeAndActsAtTheNextStep) {
  // Springs → co-rotational FEM at 1 s, while pressed (contact from 0.8 s): the switched run agrees with the
  // other to that step, continues from the same shape (no jump), and then follows the FEM.
  auto a = springs_liver_session(poke_device(Vec3(0.03, 0, 0.09), Vec3(0, 0, -1), 0.04, 0.01, 0.05, 0.3));
  auto b = springs_liver_session(poke_device(Vec3(0.03, 0, 0.09), Vec3(0, 0, -1), 0.04, 0.01, 0.05, 0.3));
  a->run_virtual(1.0, {});
  b->run_virtual(1.0, {});
  ASSERT_TRUE(b->submit(command::SetParameter{kLiver, kStiffness, 80.0}));
  b->run_virtual(0.01, {});
  ASSERT_EQ(b->parameter_changes().size(), 1u);
  const Eigen::VectorXd before = b->state().x;
  mechanics::ModelConfig fem = *b->body().config;
  fem.force_fields[0] = mechanics::ForceFieldConfig{};
  fem.force_fields[0].name = "FEM";
  fem.force_fields[0].tetrahedron_fem =
      mechanics::TetrahedronFemConfig{3000.0, 0.45, mechanics::FemMethod::kLarge, {}, {}};
  ASSERT_TRUE(b->submit(command::SetModel{kLiver, fem, nullptr}));
  const SessionReport rb = b->run_virtual(0.01, {});
  ASSERT_EQ(rb.applied_commands.size(), 1u);
  EXPECT_EQ(rb.applied_commands[0], "step 0: Liver has a new model");
  EXPECT_TRUE(b->body().config->force_fields[0].tetrahedron_fem.has_value());
  EXPECT_EQ(b->model().force_fields[0]->type_name(), "TetrahedronFEMForceField");
  EXPECT_TRUE(b->parameter_changes().empty()) << "the body's earlier changes are part of the new model";
  // One step from the same shape: no node moves more than a step's worth.
  EXPECT_LT((b->state().x - before).cwiseAbs().maxCoeff(), 2e-3);
  b->run_virtual(0.05, {});
  a->run_virtual(0.07, {});  // both at 1.07 s
  EXPECT_GT((a->state().x - b->state().x).cwiseAbs().maxCoeff(), 1e-5);
  EXPECT_TRUE(b->state().x.allFinite());

  // Another mesh, an unbuildable model, a rigid or unknown body: refused, nothing changes.
  mechanics::ModelConfig fewer = fem;
  fewer.positions.pop_back();
  auto other_mesh = b->submit(command::SetModel{kLiver, fewer, nullptr});
  ASSERT_FALSE(other_mesh);
  EXPECT_NE(other_mesh.error().message.find("another mesh"), std::string::npos) << other_mesh.error().message;
  mechanics::ModelConfig bad = fem;
  bad.force_fields[0].tetrahedron_fem->poisson_ratio = 0.7;
  auto unbuildable = b->submit(command::SetModel{kLiver, bad, nullptr});
  ASSERT_FALSE(unbuildable);
  EXPECT_NE(unbuildable.error().message.find("poissonRatio"), std::string::npos) << unbuildable.error().message;
  EXPECT_FALSE(b->submit(command::SetModel{kNoBody, fem, nullptr}));
  EXPECT_TRUE(b->run_virtual(0.02, {}).applied_commands.empty());
}

TEST(CommandSeam, ACalibrationChangedMidRunMovesTheStylusInTheWorldFromTheNextStep) {
  auto session = springs_liver_session(poke_device(Vec3(0.03, 0, 0.09), Vec3(0, 0, -1), 0.04, 0.01, 0.05, 0.3));
  std::vector<haptics::HapticSample> samples;
  const auto keep = [&](const haptics::HapticSample& s) { samples.push_back(s); };
  session->run_virtual(1.0, keep);  // pressing the liver from 0.8 s
  ASSERT_TRUE(samples.back().contact);
  const Vec3 before = samples.back().device;
  haptics::Calibration moved;
  moved.position.topRightCorner<3, 1>() = Vec3(0.5, 0.0, 0.0);  // half a metre away: nothing there
  ASSERT_TRUE(session->submit(command::SetCalibration{moved}));
  EXPECT_EQ(session->calibration().position, moved.position);
  EXPECT_EQ(session->calibrations_applied(), 0u) << "applied at the next step, not when submitted";
  samples.clear();
  const SessionReport report = session->run_virtual(0.05, keep);
  ASSERT_EQ(report.applied_commands.size(), 1u);
  EXPECT_EQ(report.applied_commands[0], "step 0: calibration");
  EXPECT_EQ(session->calibrations_applied(), 1u);
  ASSERT_FALSE(samples.empty());
  // From the first tick after the step: the device half a metre off, out of contact, no force.
  EXPECT_NEAR((samples.back().device - before).x(), 0.5, 0.01);
  EXPECT_FALSE(samples.back().contact);
  EXPECT_LT(samples.back().force.norm(), 1e-9);
  for (const haptics::HapticSample& s : samples) EXPECT_TRUE(s.force.allFinite());

  haptics::Calibration singular;
  singular.position.topLeftCorner<3, 3>().setZero();
  EXPECT_FALSE(session->submit(command::SetCalibration{singular}));
  haptics::Calibration projective;
  projective.position(3, 0) = 1.0;
  EXPECT_FALSE(session->submit(command::SetCalibration{projective}));
  EXPECT_EQ(session->calibration().position, moved.position);
}

TEST(CommandSeam, NodePositionsArePublishedForAReaderOnceAsked) {
  auto session = springs_liver_session(poke_device(Vec3(0.03, 0, 0.09), Vec3(0, 0, -1), 0.04, 0.01, 0.05, 0.3));
  TripleBuffer<std::vector<std::vector<double>>>& states = session->graphics_states();
  session->run_virtual(0.4, {});
  ASSERT_TRUE(states.acquire());
  ASSERT_EQ(states.read().size(), 1u);
  const Eigen::VectorXd& x = session->state().x;
  ASSERT_EQ(states.read()[0].size(), static_cast<std::size_t>(x.size()));
  for (Eigen::Index i = 0; i < x.size(); ++i) ASSERT_EQ(states.read()[0][static_cast<std::size_t>(i)], x[i]);
}

TEST(CommandSeam, CommandsDuringARealTimeRunAreAppliedBetweenSteps) {
  haptics::MotionConfig hold;
  hold.kind = haptics::MotionKind::kHold;
  hold.start_m = Vec3(0.03, 0.0, 0.09);
  hold.hold_s = std::numeric_limits<double>::infinity();
  auto session = springs_liver_session(std::make_unique<haptics::ScriptedDevice>(*haptics::ScriptedMotion::make(hold)));
  session->start_realtime();
  EXPECT_TRUE(session->realtime_running());
  ASSERT_TRUE(session->submit(command::SetParameter{kLiver, kStiffness, 80.0}));
  ASSERT_TRUE(session->submit(command::Pause{}));
  ASSERT_TRUE(session->submit(command::SingleStep{3}));
  ASSERT_TRUE(session->submit(command::Resume{}));
  ASSERT_TRUE(session->submit(command::SingleStep{2}));  // not paused any more: ignored
  haptics::SurfaceMaterial frictional;
  frictional.kind = haptics::SurfaceKind::kFrictional;
  ASSERT_TRUE(session->submit(command::SetMaterial{std::nullopt, frictional}));
  EXPECT_FALSE(session->submit(command::SetParameter{kLiver, kStiffness, -1.0}));
  // Wait for the simulation to take them (no timing asserted: however long it takes).
  std::int64_t samples = 0;
  while (session->haptic_loop().ticks() < 300) {
    session->poll([&](const haptics::HapticSample&) { ++samples; });
    std::this_thread::sleep_for(std::chrono::milliseconds(5));
  }
  const SessionReport report = session->stop_realtime([&](const haptics::HapticSample&) { ++samples; });
  EXPECT_FALSE(session->realtime_running());
  ASSERT_GE(report.applied_commands.size(), 6u);
  EXPECT_NE(report.applied_commands[0].find("Liver/springs/stiffness = 80"), std::string::npos);
  EXPECT_NE(report.applied_commands[1].find("pause"), std::string::npos);
  EXPECT_NE(report.applied_commands[2].find("single step x3"), std::string::npos);
  EXPECT_NE(report.applied_commands[4].find("single step ignored (not paused)"), std::string::npos);
  EXPECT_EQ(session->body().config->force_fields[0].mesh_springs->stiffness_n_per_m, 80.0);
  EXPECT_GT(report.simulation_steps, 0);
  // Every tick's sample reached the supervisor (none lost between the threads).
  EXPECT_EQ(samples, static_cast<std::int64_t>(session->haptic_loop().ticks()));
}

TEST(RealTimeSession, TheSimulationRunsOnTheThreadsAskedForAndEveryCoreButOneByDefault) {
  // Automatic: every core the process may use but one (the haptic loop's and the window's),
  // at least one.
  const int cores = static_cast<int>(allowed_cpus().size());
  for (int asked : {1, 2, 0}) {
    haptics::MotionConfig hold;
    hold.kind = haptics::MotionKind::kHold;
    hold.start_m = Vec3(0.03, 0.0, 0.09);
    hold.hold_s = std::numeric_limits<double>::infinity();
    auto session =
        springs_liver_session(std::make_unique<haptics::ScriptedDevice>(*haptics::ScriptedMotion::make(hold)), asked);
    session->start_realtime();
    while (session->haptic_loop().ticks() < 50) std::this_thread::sleep_for(std::chrono::milliseconds(2));
    const SessionReport report = session->stop_realtime({});
    EXPECT_GT(report.simulation_steps, 0);
    EXPECT_EQ(report.simulation_threads, asked > 0 ? asked : std::max(1, cores - 1)) << "asked " << asked;
  }
}

TEST(RealTimeSession, TheHapticLoopAndTheSnapshotsRunOnACpuOfTheirOwn) {
  const std::vector<int> cpus = allowed_cpus();
  for (const bool pin : {true, false}) {
    haptics::MotionConfig hold;
    hold.kind = haptics::MotionKind::kHold;
    hold.start_m = Vec3(0.03, 0.0, 0.09);
    hold.hold_s = std::numeric_limits<double>::infinity();
    auto session =
        springs_liver_session(std::make_unique<haptics::ScriptedDevice>(*haptics::ScriptedMotion::make(hold)), 0, pin);
    session->start_realtime();
    while (session->haptic_loop().ticks() < 50) std::this_thread::sleep_for(std::chrono::milliseconds(2));
    const SessionReport report = session->stop_realtime({});
    EXPECT_GT(report.simulation_steps, 0);
    if (!pin) {
      EXPECT_EQ(report.cpu_placement, "not pinned (asked)");
      EXPECT_FALSE(session->haptic_loop().pinned());
    } else if (cpus.size() >= 2) {
      // The last CPU the process may use carries the haptic loop; the simulation has the rest.
      EXPECT_NE(report.cpu_placement.find(fmt::format("haptics on CPU {}", cpus.back())), std::string::npos)
          << report.cpu_placement;
      EXPECT_EQ(report.cpu_placement.find(fmt::format("simulation on CPU {}", cpus.back())), std::string::npos);
      EXPECT_TRUE(session->haptic_loop().pinned());
    } else {
      EXPECT_EQ(report.cpu_placement, "not pinned");  // one CPU: the threads must share it
    }
  }
}

TEST(RealTimeSession, TheLastShapeOfARunIsPublishedAndEveryShapeInOrder) {
  // A press that moves the liver while the simulation stages its shapes for the publisher
  // thread: when the run stops, the shape a reader gets is the final state's, whatever the
  // timing; and the snapshots a reader saw came in increasing order.
  auto session = springs_liver_session(poke_device(Vec3(0.03, 0, 0.055), Vec3(0, 0, -1), 0.005, 0.01, 0.05, 5.0));
  TripleBuffer<haptics::SurfaceSnapshot>& shown = session->graphics_surfaces();
  session->start_realtime();
  std::uint64_t last_sequence = 0;
  double last_time = -1.0;
  bool first = true;
  while (session->haptic_loop().ticks() < 1000) {
    if (shown.acquire()) {
      if (!first) {
        EXPECT_GT(shown.read().sequence, last_sequence);
      }
      first = false;
      EXPECT_GE(shown.read().time_s, last_time);
      last_sequence = shown.read().sequence;
      last_time = shown.read().time_s;
    }
    std::this_thread::sleep_for(std::chrono::milliseconds(1));
  }
  const SessionReport report = session->stop_realtime({});
  ASSERT_GT(report.simulation_steps, 0);
  shown.acquire();  // (false when the reader above already had the last one)
  const Eigen::VectorXd& x = session->state().x;
  std::vector<Vec3> expected(session->body().surface.vertices.size());
  session->body().mapping.apply({x.data(), static_cast<std::size_t>(x.size())}, expected);
  const haptics::SurfaceSnapshot& last = shown.read();
  ASSERT_EQ(last.vertices.size(), expected.size());
  double moved = 0.0;
  for (std::size_t v = 0; v < expected.size(); ++v) {
    ASSERT_EQ(last.vertices[v], expected[v]) << "vertex " << v;
    moved = std::max(moved, (expected[v] - session->body().surface.vertices[v]).norm());
  }
  EXPECT_GT(moved, 1e-4) << "the press must have moved the surface";
  // Its bound tree was refitted to it: every triangle lies in the root box.
  const std::vector<std::pair<Vec3, Vec3>> root = last.tree.boxes(0);
  ASSERT_EQ(root.size(), 1u);
  for (const Vec3& p : last.vertices) {
    EXPECT_TRUE((p.array() >= root[0].first.array()).all() && (p.array() <= root[0].second.array()).all())
        << p.transpose();
  }
}

TEST(CommandSeam, AnotherDeviceIsSwitchedToWithItsOwnForceLimit) {
  // A box, touched first by nothing (a probe holding still far above), then by a device
  // with a 3.3 N limit pressing 3 cm in (10 N requested).
  std::vector<SessionBody> bodies(1);
  bodies[0].name = "box";
  bodies[0].surface = box(Vec3(-0.02, -0.04, -0.02), Vec3(0.02, 0.0, 0.02));
  haptics::MotionConfig hold;
  hold.kind = haptics::MotionKind::kHold;
  hold.start_m = Vec3(0.0, 0.5, 0.0);
  hold.hold_s = std::numeric_limits<double>::infinity();
  SessionConfig config = god_object_config();
  auto session = Session::make(std::move(bodies),
                               std::make_unique<haptics::ScriptedDevice>(*haptics::ScriptedMotion::make(hold)), config);
  ASSERT_TRUE(session);
  (*session)->run_virtual(0.1, {});
  // A device that is not there, and a motion that cannot be, are refused when submitted.
  auto absent = (*session)->submit(
      command::SetDevice{haptics::ReplayConfig{"/nonexistent/hof-replay.csv", false, {}}, "replay", nullptr});
  ASSERT_FALSE(absent);
  haptics::MotionConfig backwards;
  backwards.speed_m_per_s = -1.0;
  EXPECT_FALSE((*session)->submit(
      command::SetDevice{haptics::ScriptedConfig{backwards, {}}, "scripted:poke,speed=-1", nullptr}));
  haptics::MotionConfig
      poke;  // scripted:poke,start=0;0.05;0,direction=0;-1;0,approach=0.05,depth=0.03,speed=0.1,hold=1
  poke.start_m = Vec3(0.0, 0.05, 0.0);
  poke.direction = Vec3(0.0, -1.0, 0.0);
  poke.approach_m = 0.05;
  poke.depth_m = 0.03;
  poke.speed_m_per_s = 0.1;
  poke.hold_s = 1.0;
  const haptics::DeviceConfig omni =
      haptics::ScriptedConfig{poke, haptics::device_spec_for_model(haptics::DeviceModel::kOmni)};
  ASSERT_TRUE((*session)->submit(command::SetDevice{omni, "scripted:poke (omni)", nullptr}));
  double largest = 0.0;
  int clamped = 0;
  const SessionReport report = (*session)->run_virtual(2.0, [&](const haptics::HapticSample& s) {
    largest = std::max(largest, s.force.norm());
    if (s.requested_force.norm() > 3.3 && s.valid) ++clamped;
  });
  ASSERT_FALSE(report.applied_commands.empty());
  EXPECT_NE(report.applied_commands[0].find("device scripted:poke"), std::string::npos);
  EXPECT_LE(largest, 3.3 + 1e-9) << "the new device's limit must hold from its first tick";
  EXPECT_GT(clamped, 100);
  EXPECT_GT(report.contact_time_s, 0.5);
  EXPECT_EQ(report.fall_through_events, 0);
}

TEST(CommandSeam, TheHapticTickNeverAllocatesWhenSettingsChange) {
  HOF_SKIP_UNLESS_COUNTING_ALLOCATIONS();
  // A loop fed new settings (renderer, materials, effects) through its triple buffer, and
  // switched to another device.
  const mesh::TriMesh surface = box(Vec3(-0.02, -0.04, -0.02), Vec3(0.02, 0.0, 0.02));
  TripleBuffer<haptics::SurfaceSnapshot> surfaces(haptics::make_snapshot(surface));
  surfaces.publish();
  TripleBuffer<haptics::HapticSettings> settings;
  haptics::HapticLoopConfig config;
  config.realtime_priority = false;
  auto device = poke_device(Vec3(0, 0.05, 0), Vec3(0, -1, 0), 0.05, 0.005, 0.05, 1.0);
  auto other = poke_device(Vec3(0, 0.04, 0), Vec3(0, -1, 0), 0.04, 0.005, 0.05, 1.0);  // outlives the loop
  haptics::HapticLoop loop(*device, surfaces, config, &settings);
  double t = 0.0;
  for (int i = 0; i < 100; ++i, t += 0.001) loop.tick(t);
  for (int change = 0; change < 5; ++change) {
    haptics::HapticSettings& slot = settings.write_slot();
    slot.valid = true;
    slot.renderer.kind = change % 2 ? haptics::RendererKind::kGodObject : haptics::RendererKind::kRuspini;
    slot.materials.assign(1, haptics::SurfaceMaterial{});
    slot.materials[0].stiffness = 0.2 + 0.1 * change;
    slot.effects.springs.assign(static_cast<std::size_t>(change + 1), haptics::SpringEffect{});
    slot.effects.viscosities.assign(3, haptics::ViscosityEffect{});
    settings.publish();
    if (change == 2) {
      ASSERT_TRUE(loop.switch_device(*other));  // taken by the next tick
    }
    const auto before = hof::testing::thread_allocation_count();
    for (int i = 0; i < 200; ++i, t += 0.001) loop.tick(t);
    EXPECT_EQ(hof::testing::thread_allocation_count(), before) << "change " << change;
  }
}

}  // namespace
}  // namespace hof::coupling
