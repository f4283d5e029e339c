// Contact between bodies, the penalty response (coupling/detail/body_contact_pass.h), through
// whole sessions in virtual time: a soft block dropped on a rigid floor comes to rest within the
// contact distance and stops moving, and does not tunnel through it at 5 m/s with dt 10 ms;
// stiff contact at dt 20 ms stays finite; two blocks pressed together feel equal and opposite
// forces and the far one moves; contact switched off (or with no collision models, or with the
// bodies apart) changes nothing, bit for bit; bad settings are clear errors.

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <limits>

#include "hof/coupling/detail/body_contact_pass.h"
#include "hof/coupling/detail/world_step.h"
#include "hof/coupling/session.h"
#include "hof/haptics/device_backends/scripted_device.h"
#include "hof/mechanics/step.h"
#include "hof/mesh/boundary.h"

#include "mechanics/test_meshes.h"
#include "support/allocation_counter.h"

namespace hof::coupling {
namespace {

// A device that stays 1 m away from everything: only the bodies touch each other.
std::unique_ptr<haptics::Device> idle_device() {
  auto scripted =
      haptics::ScriptedMotion::make(haptics::MotionConfig::poke(Vec3(0, 1, 0), Vec3(0, 1, 0), 0.01, 0.001, 0.01, 0.0));
  EXPECT_TRUE(scripted) << scripted.error().to_string();
  return std::make_unique<haptics::ScriptedDevice>(*scripted);
}

SessionConfig contact_config(double stiffness_n_per_m) {
  SessionConfig config;
  config.haptics.realtime_priority = false;
  config.contacts.enabled = true;
  config.contacts.contact_distance_m = 1e-3;
  config.contacts.alarm_distance_m = 3e-3;
  config.contacts.stiffness_n_per_m = stiffness_n_per_m;
  return config;
}

struct BlockOptions {
  Vec3 corner{Vec3::Zero()};  // its lowest corner, m
  double size_m{0.04};
  int cells{3};
  double youngs_pa{5000.0};
  Vec3 gravity{0.0, -9.81, 0.0};
  double dt_s{0.01};
  double rayleigh_stiffness{0.0};
};

// A soft cube of linear (co-rotational) tetrahedral FEM, its boundary as the collision surface.
SessionBody soft_block(const std::string& name, const BlockOptions& o) {
  auto box = mechanics::testing::box_mesh(o.cells, o.cells, o.cells, Vec3::Constant(o.size_m));
  for (Vec3& p : box.nodes) p += o.corner;
  const mesh::BoundarySurface boundary = mesh::extract_boundary(box.nodes, box.tets);
  mechanics::ModelConfig c;
  c.name = name;
  c.positions = box.nodes;
  c.tets = box.tets;
  c.mass.kind = mechanics::MassKind::kDiagonal;
  c.mass.mass_density_kg_per_m3 = 1000.0;
  c.gravity_m_per_s2 = o.gravity;
  mechanics::ForceFieldConfig fem;
  fem.name = "FEM";
  fem.tetrahedron_fem = mechanics::TetrahedronFemConfig{o.youngs_pa, 0.3, mechanics::FemMethod::kLarge, {}, {}};
  c.force_fields.push_back(fem);
  c.ode.kind = mechanics::OdeSolverKind::kEulerImplicit;
  c.ode.rayleigh_stiffness = o.rayleigh_stiffness;
  c.linear.kind = mechanics::LinearSolverKind::kSparseLdlt;
  c.dt_s = o.dt_s;
  c.threads = 1;
  auto model = mechanics::build_model(c);
  EXPECT_TRUE(model) << model.error().to_string();
  auto mapping = SurfaceMapping::by_index(box.nodes, boundary.surface.vertices, boundary.surface_to_volume);
  EXPECT_TRUE(mapping) << mapping.error().to_string();
  SessionBody body;
  body.name = name;
  body.model.emplace(std::move(*model));
  body.surface = boundary.surface;
  body.mapping = std::move(*mapping);
  body.config = c;
  body.collision.enabled = true;
  return body;
}

// A rigid floor at y = 0: two triangles 2 m across, their front (+y) up.
SessionBody floor_body() {
  SessionBody floor;
  floor.name = "floor";
  floor.surface.vertices = {Vec3(-1, 0, -1), Vec3(-1, 0, 1), Vec3(1, 0, 1), Vec3(1, 0, -1)};
  floor.surface.triangles = {{0, 1, 2}, {0, 2, 3}};
  floor.collision.enabled = true;
  return floor;
}

double lowest_y(const Session& session, std::size_t body) {
  const mechanics::MechanicalState& state = session.state(body);
  double lowest = std::numeric_limits<double>::infinity();
  for (Eigen::Index i = 1; i < state.x.size(); i += 3) lowest = std::min(lowest, state.x[i]);
  return lowest;
}

double highest_y(const Session& session, std::size_t body) {
  const mechanics::MechanicalState& state = session.state(body);
  double highest = -std::numeric_limits<double>::infinity();
  for (Eigen::Index i = 1; i < state.x.size(); i += 3) highest = std::max(highest, state.x[i]);
  return highest;
}

struct DropRun {
  std::vector<double> kinetic;  // per 10 ms of virtual time
  std::vector<double> lowest, highest;
  SessionReport report;
  double final_lowest{0.0};
};

DropRun drop_on_floor(const BlockOptions& block, double stiffness, double seconds, bool contact = true) {
  std::vector<SessionBody> bodies;
  bodies.push_back(soft_block("block", block));
  bodies.push_back(floor_body());
  SessionConfig config = contact_config(stiffness);
  config.contacts.enabled = contact;
  auto session = Session::make(std::move(bodies), idle_device(), config);
  EXPECT_TRUE(session) << session.error().to_string();
  DropRun run;
  for (double t = 0.0; t < seconds - 1e-9; t += 0.01) {
    run.report = (*session)->run_virtual(0.01, {});
    if (run.report.diverged) break;
    run.kinetic.push_back(mechanics::kinetic_energy((*session)->model(), (*session)->state(0)));
    run.lowest.push_back(lowest_y(**session, 0));
    run.highest.push_back(highest_y(**session, 0));
  }
  run.final_lowest = lowest_y(**session, 0);
  return run;
}

TEST(BodyContactPass, SoftBlockComesToRestOnARigidFloorWithinTheContactDistance) {
  BlockOptions block;
  block.corner = Vec3(-0.02, 0.01, -0.02);  // 1 cm above the floor
  block.rayleigh_stiffness = 0.01;
  const DropRun run = drop_on_floor(block, 1000.0, 3.0);
  ASSERT_FALSE(run.report.diverged) << run.report.divergence;
  const double contact_distance = 1e-3;
  // At rest: no deeper than the contact distance into the floor, and resting on it (within the
  // contact distance of it, not bouncing above).
  EXPECT_GE(run.final_lowest, -contact_distance);
  EXPECT_LE(run.final_lowest, contact_distance);
  // The kinetic energy decays after the impact: the last half second's largest is a small
  // fraction of the largest after the first contact.
  const auto impact = static_cast<std::size_t>(
      std::find_if(run.lowest.begin(), run.lowest.end(), [&](double y) { return y < contact_distance; }) -
      run.lowest.begin());
  ASSERT_LT(impact, run.lowest.size()) << "the block never reached the floor";
  const double after_impact =
      *std::max_element(run.kinetic.begin() + static_cast<std::ptrdiff_t>(impact), run.kinetic.end());
  const double last = *std::max_element(run.kinetic.end() - 50, run.kinetic.end());
  EXPECT_LT(last, 1e-3 * after_impact) << "after impact " << after_impact << " J, last 0.5 s " << last << " J";
  // Every contact pushes the block up, and at rest its total is its weight.
  const double weight = 1000.0 * std::pow(block.size_m, 3) * 9.81;  // ρ V g
  ASSERT_EQ(run.report.bodies.size(), 2u);
  EXPECT_GT(run.report.bodies[0].body_contacts, 0);
  EXPECT_NEAR(run.report.bodies[0].body_contact_force_n.y(), weight, 0.02 * weight);
  EXPECT_NEAR(run.report.bodies[1].body_contact_force_n.y(), -weight, 0.02 * weight);
  EXPECT_FALSE(run.report.friction_solved_as_penalty);
}

TEST(BodyContactPass, SphereModelsFollowTheVolumeAndCarryTheBlock) {
  // SOFA's SphereCollisionModel on a deformable body: four spheres near the block's bottom
  // corners, its surface taking no part; the block comes to rest on them.
  BlockOptions block;
  block.corner = Vec3(-0.02, 0.005, -0.02);
  block.rayleigh_stiffness = 0.01;
  SessionBody body = soft_block("block", block);
  body.collision.triangles = body.collision.lines = body.collision.points = false;
  const double radius = 0.004;
  for (double x : {-0.01, 0.01}) {
    for (double z : {-0.01, 0.01}) {
      body.collision.sphere_centers.emplace_back(x, block.corner.y() + radius + 1e-3, z);
      body.collision.sphere_radii.push_back(radius);
    }
  }
  const std::vector<Vec3> centres = body.collision.sphere_centers;
  std::vector<SessionBody> bodies;
  bodies.push_back(std::move(body));
  bodies.push_back(floor_body());
  auto session = Session::make(std::move(bodies), idle_device(), contact_config(1000.0));
  ASSERT_TRUE(session) << session.error().to_string();
  const SessionReport report = (*session)->run_virtual(3.0, {});
  ASSERT_FALSE(report.diverged) << report.divergence;
  // Where the spheres are now: their centres through the volume, as the pass maps them.
  const mechanics::MechanicalModel& model = (*session)->model();
  auto mapping = SurfaceMapping::barycentric(model.rest_positions, model.tets, centres);
  ASSERT_TRUE(mapping);
  std::vector<Vec3> now(centres.size());
  const Eigen::VectorXd& x = (*session)->state(0).x;
  mapping->apply({x.data(), static_cast<std::size_t>(x.size())}, now);
  const double contact_distance = 1e-3;
  for (const Vec3& c : now) {
    EXPECT_GE(c.y() - radius, -contact_distance);
    EXPECT_LE(c.y() - radius, contact_distance);
  }
  // Only the spheres touch (the soft block's corners sag past them to the floor's plane, and
  // its surface takes no part).
  EXPECT_EQ(report.bodies[0].body_contacts, 4);
  const double weight = 1000.0 * std::pow(block.size_m, 3) * 9.81;
  EXPECT_NEAR(report.bodies[0].body_contact_force_n.y(), weight, 0.02 * weight);
}

TEST(BodyContactPass, APassInContactAllocatesNothingOnceTheContactsHaveBeenSeen) {
  HOF_SKIP_UNLESS_COUNTING_ALLOCATIONS();
  // The world's own step (contacts, the pass, the body's step) on a block resting on the
  // floor; the surface follows the nodes as the snapshot publisher makes it.
  BlockOptions block;
  block.corner = Vec3(-0.02, 0.0005, -0.02);
  std::vector<SessionBody> bodies;
  bodies.push_back(soft_block("block", block));
  bodies.push_back(floor_body());
  detail::World world;
  detail::init_world(world, std::move(bodies), idle_device(), contact_config(1000.0));
  SessionReport report;
  const auto step = [&] {
    ASSERT_TRUE(detail::advance_bodies(world, report));
    detail::BodyRuntime& r = world.bodies[0];
    r.body.mapping.apply({r.state.x.data(), static_cast<std::size_t>(r.state.x.size())}, r.surface_positions);
  };
  for (int k = 0; k < 50; ++k) step();
  ASSERT_GT(report.body_contacts, 0);
  const long before = hof::testing::thread_allocation_count();
  for (int k = 0; k < 50; ++k) step();
  EXPECT_EQ(hof::testing::thread_allocation_count() - before, 0);
  EXPECT_GT(report.body_contacts, 0);
}

TEST(BodyContactPass, BlockAtFiveMetresPerSecondDoesNotTunnelThroughTheFloorAtTenMillisecondSteps) {
  BlockOptions block;
  // Gravity that brings it to 5 m/s over its 5 cm drop (v² = 2 g h): 5 cm per step at impact,
  // more than the block's own 4 cm height.
  block.gravity = Vec3(0.0, -250.0, 0.0);
  block.corner = Vec3(-0.02, 0.05, -0.02);
  block.youngs_pa = 50000.0;
  const DropRun run = drop_on_floor(block, 20000.0, 0.5);
  ASSERT_FALSE(run.report.diverged) << run.report.divergence;
  double fastest = 0.0;
  const double mass = 1000.0 * std::pow(block.size_m, 3);
  for (double e : run.kinetic) fastest = std::max(fastest, std::sqrt(2.0 * e / mass));
  EXPECT_GT(fastest, 4.5) << "it must hit at about 5 m/s";
  // A penalty spring acts from the step after the crossing, so the first contact step finds
  // the block up to one step's travel deep; it must never be wholly through, and it must end
  // on top.
  for (double y : run.highest) EXPECT_GT(y, 0.0) << "the block went through the floor";
  EXPECT_GT(run.final_lowest, -1e-3);
  EXPECT_LT(run.final_lowest, 0.02);
  // Without contact it does fall through (the test would see it).
  EXPECT_LT(drop_on_floor(block, 20000.0, 0.5, false).final_lowest, -0.1);
}

TEST(BodyContactPass, StiffContactAtTwentyMillisecondStepsStaysFiniteAndBounded) {
  BlockOptions block;
  block.corner = Vec3(-0.02, 0.005, -0.02);
  block.dt_s = 0.02;
  const DropRun run = drop_on_floor(block, 1e6, 2.0);  // ω h ≈ 2000 per contact node: explicit would need dt < 10 µs
  ASSERT_FALSE(run.report.diverged) << run.report.divergence;
  // Bounded: never deeper than one step's travel at impact (about 6 mm), never thrown up
  // higher than it started, and never more kinetic energy than the fall gave it.
  const double mass = 1000.0 * std::pow(block.size_m, 3);
  const double fall_energy = mass * 9.81 * (block.corner.y() + 0.01);
  for (std::size_t k = 0; k < run.lowest.size(); ++k) {
    ASSERT_TRUE(std::isfinite(run.lowest[k]) && std::isfinite(run.kinetic[k]));
    EXPECT_GT(run.lowest[k], -0.01);
    EXPECT_LT(run.lowest[k], block.corner.y() + 1e-3);
    EXPECT_LT(run.kinetic[k], fall_energy);
  }
  EXPECT_GT(run.final_lowest, -1e-3);
}

TEST(BodyContactPass, TwoBlocksPressedTogetherFeelEqualAndOppositeForcesAndTheFarOneMoves) {
  BlockOptions pushed;
  pushed.corner = Vec3(-0.04, 0.0, 0.0);
  pushed.gravity = Vec3(2.0, 0.0, 0.0);  // toward the other block
  BlockOptions far = pushed;
  far.corner = Vec3(0.0005, 0.0, 0.0);  // 0.5 mm away: within the contact distance
  far.gravity = Vec3::Zero();
  far.youngs_pa = 20000.0;
  std::vector<SessionBody> bodies;
  bodies.push_back(soft_block("pushed", pushed));
  bodies.push_back(soft_block("far", far));
  auto session = Session::make(std::move(bodies), idle_device(), contact_config(500.0));
  ASSERT_TRUE(session) << session.error().to_string();
  SessionReport report;
  for (int k = 0; k < 30; ++k) {
    report = (*session)->run_virtual(0.01, {});
    ASSERT_FALSE(report.diverged) << report.divergence;
    const Vec3 a = report.bodies[0].body_contact_force_n, b = report.bodies[1].body_contact_force_n;
    if (report.bodies[0].body_contacts == 0) continue;
    EXPECT_GT(a.norm(), 0.0);
    EXPECT_LE((a + b).norm(), 1e-9 * a.norm()) << "step " << k;
    EXPECT_LT(a.x(), 0.0) << "the far block pushes the pushed one back";
    // The forces that reached each body's nodes add up to the same totals.
    const Eigen::VectorXd& fa = (*session)->state(0).external_force;
    const Eigen::VectorXd& fb = (*session)->state(1).external_force;
    Vec3 node_a = Vec3::Zero(), node_b = Vec3::Zero();
    for (Eigen::Index i = 0; i < fa.size(); i += 3) node_a += fa.segment<3>(i);
    for (Eigen::Index i = 0; i < fb.size(); i += 3) node_b += fb.segment<3>(i);
    EXPECT_LE((node_a - a).norm(), 1e-9 * a.norm());
    EXPECT_LE((node_a + node_b).norm(), 1e-9 * a.norm());
  }
  EXPECT_GT(report.max_body_contacts, 0);
  // The far block, free and not pulled by anything else, was pushed along +x.
  const mechanics::MechanicalState& state = (*session)->state(1);
  double mean_x = 0.0;
  for (Eigen::Index i = 0; i < state.x.size(); i += 3) mean_x += state.x[i];
  mean_x /= static_cast<double>(state.x.size() / 3);
  EXPECT_GT(mean_x, 0.0005 + 0.02 + 1e-4) << "the far body did not move";
}

// The block's positions after `seconds` of falling with contact configured as `config` says.
Eigen::VectorXd fall(SessionConfig config, bool collision_models, double height) {
  BlockOptions block;
  block.corner = Vec3(-0.02, height, -0.02);
  std::vector<SessionBody> bodies;
  bodies.push_back(soft_block("block", block));
  bodies.push_back(floor_body());
  for (SessionBody& b : bodies) b.collision.enabled = collision_models;
  auto session = Session::make(std::move(bodies), idle_device(), config);
  EXPECT_TRUE(session) << session.error().to_string();
  (*session)->run_virtual(0.2, {});
  return (*session)->state(0).x;
}

TEST(BodyContactPass, ContactOffOrWithoutContactsChangesNothingBitForBit) {
  SessionConfig off;
  off.haptics.realtime_priority = false;
  const Eigen::VectorXd reference = fall(off, true, 0.5);
  EXPECT_EQ(fall(contact_config(1000.0), false, 0.5), reference) << "no collision models";
  EXPECT_EQ(fall(contact_config(1000.0), true, 0.5), reference) << "collision models far apart";
  // And the floor does stop it when it is near and contact is on.
  EXPECT_NE(fall(contact_config(1000.0), true, 0.002), fall(off, true, 0.002));
}

TEST(BodyContactPass, DisabledPairsPassThroughEachOther) {
  SessionConfig config = contact_config(1000.0);
  config.contacts.disabled_pairs.emplace_back(0, 1);
  SessionConfig off;
  off.haptics.realtime_priority = false;
  EXPECT_EQ(fall(config, true, 0.002), fall(off, true, 0.002));
}

TEST(BodyContactPass, FrictionConstraintsAreSolvedAsPenaltyAndSaidSo) {
  SessionConfig config = contact_config(1000.0);
  config.contacts.response = ContactResponse::kFrictionConstraint;
  config.contacts.friction = 0.3;
  std::vector<SessionBody> bodies;
  BlockOptions block;
  block.corner = Vec3(-0.02, 0.0005, -0.02);
  bodies.push_back(soft_block("block", block));
  bodies.push_back(floor_body());
  auto session = Session::make(std::move(bodies), idle_device(), config);
  ASSERT_TRUE(session);
  const SessionReport report = (*session)->run_virtual(0.1, {});
  EXPECT_TRUE(report.friction_solved_as_penalty);
  EXPECT_GT(report.body_contacts, 0);
}

TEST(BodyContactPass, PairStiffnessFollowsTheBodiesOwnWhenTheyGiveIt) {
  ContactSettings settings;
  settings.stiffness_n_per_m = 100.0;
  BodyCollision a, b;
  EXPECT_DOUBLE_EQ(detail::pair_contact_stiffness(settings, a, b), 100.0);
  a.stiffness_n_per_m = 400.0;
  EXPECT_DOUBLE_EQ(detail::pair_contact_stiffness(settings, a, b), 400.0);
  EXPECT_DOUBLE_EQ(detail::pair_contact_stiffness(settings, b, a), 400.0);
  b.stiffness_n_per_m = 900.0;
  EXPECT_DOUBLE_EQ(detail::pair_contact_stiffness(settings, a, b), 600.0);
}

TEST(BodyContactPass, BadSettingsAreClearErrors) {
  const auto make = [](SessionConfig config, std::vector<SessionBody> bodies) {
    return Session::make(std::move(bodies), idle_device(), config);
  };
  const auto error_of = [&](SessionConfig config, std::vector<SessionBody> bodies) {
    auto s = make(std::move(config), std::move(bodies));
    return s ? std::string() : s.error().message;
  };
  const auto two = [] {
    std::vector<SessionBody> bodies;
    bodies.push_back(floor_body());
    bodies.push_back(floor_body());
    bodies[1].name = "ceiling";
    return bodies;
  };
  SessionConfig config = contact_config(1000.0);
  config.contacts.contact_distance_m = -1e-3;
  EXPECT_NE(error_of(config, two()).find("contact distance"), std::string::npos);
  config = contact_config(-5.0);
  EXPECT_NE(error_of(config, two()).find("stiffness"), std::string::npos);
  config = contact_config(1000.0);
  config.contacts.alarm_distance_m = 1e-4;
  EXPECT_NE(error_of(config, two()).find("alarm distance"), std::string::npos);
  std::vector<SessionBody> with_bad_body = two();
  with_bad_body[1].collision.stiffness_n_per_m = -1.0;
  EXPECT_NE(error_of(contact_config(1000.0), std::move(with_bad_body)).find("ceiling"), std::string::npos);
  std::vector<SessionBody> empty = two();
  empty[1].surface.triangles.clear();
  EXPECT_NE(error_of(contact_config(1000.0), std::move(empty)).find("no surface"), std::string::npos);
  config = contact_config(1000.0);
  config.contacts.disabled_pairs.emplace_back(0, 5);
  EXPECT_NE(error_of(config, two()).find("disabled pair"), std::string::npos);
}

}  // namespace
}  // namespace hof::coupling
