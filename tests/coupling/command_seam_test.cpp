// The command seam: commands keep their order, a wrong one is a clear error that changes
// nothing, a full queue is an error rather than a wait, and commands submitted from other
// threads (the window and a script runner at once) are applied by the simulation between two
// steps. Written to run under ThreadSanitizer.

#include "hof/coupling/command_seam.h"

#include <gtest/gtest.h>

#include <algorithm>
#include <atomic>
#include <chrono>
#include <limits>
#include <string>
#include <thread>
#include <vector>

#include "hof/coupling/session.h"
#include "hof/haptics/device_backends/scripted_device.h"
#include "hof/mesh/boundary.h"

#include "mechanics/test_meshes.h"
#include "support/box_surface.h"

namespace hof::coupling {
namespace {

// A rigid 4 cm box and a stylus resting above it: a world that steps at 100 Hz, cheaply.
std::unique_ptr<Session> box_session() {
  std::vector<SessionBody> bodies(1);
  bodies[0].name = "box";
  bodies[0].surface = hof::testing::box_surface(Vec3(-0.02, -0.04, -0.02), Vec3(0.02, 0.0, 0.02));
  auto scripted = haptics::ScriptedMotion::make(
      haptics::MotionConfig::poke(Vec3(0, 0.05, 0), Vec3(0, -1, 0), 0.01, 0.0, 0.05, 0.1));
  EXPECT_TRUE(scripted);
  SessionConfig config;
  config.haptics.realtime_priority = false;
  config.pin_threads = false;
  auto session = Session::make(std::move(bodies),
                               std::make_unique<haptics::ScriptedDevice>(*scripted, haptics::DeviceSpec{}), config);
  EXPECT_TRUE(session) << session.error().to_string();
  return std::move(*session);
}

TEST(CommandSeam, CommandsAreAppliedInTheOrderTheyWereSubmitted) {
  auto session = box_session();
  ASSERT_TRUE(session->submit(command::Pause{}));
  ASSERT_TRUE(session->submit(command::SingleStep{2}));
  ASSERT_TRUE(session->submit(command::SetForceLimit{3.0}));
  ASSERT_TRUE(session->submit(command::Resume{}));
  const SessionReport report = session->run_virtual(0.05, {});
  const std::vector<std::string> expected{"step 0: pause", "step 0: single step x2", "step 0: force limit 3 N",
                                          "step 0: resume"};
  EXPECT_EQ(report.applied_commands, expected);
}

TEST(CommandSeam, AWrongCommandIsAClearErrorAndChangesNothing) {
  auto session = box_session();
  auto steps = session->submit(command::SingleStep{0});
  ASSERT_FALSE(steps);
  EXPECT_NE(steps.error().message.find("steps must be in [1, 1000000]"), std::string::npos) << steps.error().message;
  auto nobody = session->submit(command::SetMaterial{BodyId{1}, {}});
  ASSERT_FALSE(nobody);
  EXPECT_NE(nobody.error().message.find("no body #1 (bodies: box)"), std::string::npos) << nobody.error().message;
  auto rigid = session->submit(
      command::SetParameter{BodyId{0}, {{mechanics::ComponentKind::kModel, 0}, mechanics::ParameterId::kDt}, 0.001});
  ASSERT_FALSE(rigid);
  EXPECT_NE(rigid.error().message.find("rigid"), std::string::npos) << rigid.error().message;
  EXPECT_FALSE(session->parameter(
      BodyId{0}, mechanics::ParameterRef{{mechanics::ComponentKind::kModel, 0}, mechanics::ParameterId::kDt}));
  const SessionReport report = session->run_virtual(0.05, {});
  EXPECT_TRUE(report.applied_commands.empty());
  EXPECT_TRUE(session->material_changes().empty());
}

TEST(CommandSeam, AFullQueueIsAClearErrorNotAWait) {
  auto session = box_session();
  for (std::size_t i = 0; i < kCommandQueueCapacity; ++i)
    ASSERT_TRUE(session->submit(command::SetForceLimit{1.0})) << i;
  auto full = session->submit(command::SetMaterial{BodyId{0}, {}});
  ASSERT_FALSE(full);
  EXPECT_NE(full.error().message.find("queue is full"), std::string::npos) << full.error().message;
  EXPECT_TRUE(session->material_changes().empty()) << "a command refused for want of room changes nothing";
  const SessionReport report = session->run_virtual(0.01, {});  // one step takes them all
  EXPECT_EQ(report.applied_commands.size(), kCommandQueueCapacity);
  EXPECT_TRUE(session->submit(command::SetMaterial{BodyId{0}, {}}));
  EXPECT_EQ(session->material_changes().size(), 1u);
}

TEST(CommandSeam, CommandsFromTwoOtherThreadsAreAppliedBetweenStepsEachInItsOrder) {
  auto session = box_session();
  session->start_realtime();
  // The window and a script runner: each submits its own force limits, in increasing order.
  constexpr int kEach = 50;
  std::atomic<int> refused{0};
  const auto submitter = [&](double first) {
    for (int i = 0; i < kEach; ++i) {
      if (!session->submit(command::SetForceLimit{first + i})) refused.fetch_add(1);
    }
  };
  std::thread window(submitter, 100.0);
  std::thread script(submitter, 200.0);
  window.join();
  script.join();
  ASSERT_TRUE(session->submit(command::SetCalibration{haptics::Calibration{}}));
  const auto deadline = std::chrono::steady_clock::now() + std::chrono::seconds(20);
  while (session->calibrations_applied() == 0 && std::chrono::steady_clock::now() < deadline) {
    std::this_thread::sleep_for(std::chrono::milliseconds(5));
  }
  const SessionReport report = session->stop_realtime();
  ASSERT_EQ(refused.load(), 0);
  ASSERT_EQ(session->calibrations_applied(), 1u) << "the simulation did not apply the command";
  // Every command applied once, each thread's in its order, the calibration (submitted last) last.
  std::vector<double> from_window, from_script;
  for (const std::string& line : report.applied_commands) {
    const auto at = line.find("force limit ");
    if (at == std::string::npos) continue;
    const double value = std::stod(line.substr(at + 12));
    (value < 200.0 ? from_window : from_script).push_back(value);
  }
  ASSERT_EQ(from_window.size(), static_cast<std::size_t>(kEach));
  ASSERT_EQ(from_script.size(), static_cast<std::size_t>(kEach));
  EXPECT_TRUE(std::is_sorted(from_window.begin(), from_window.end()));
  EXPECT_TRUE(std::is_sorted(from_script.begin(), from_script.end()));
  ASSERT_FALSE(report.applied_commands.empty());
  EXPECT_NE(report.applied_commands.back().find("calibration"), std::string::npos) << report.applied_commands.back();
}

// A soft 4 cm block 0.5 mm above a rigid floor (y = 0), falling on it under gravity, with
// contact between bodies on (or off); the stylus stays 1 m away.
std::unique_ptr<Session> block_on_floor_session(bool contact, bool floor_collides = true) {
  auto box = mechanics::testing::box_mesh(3, 3, 3, Vec3::Constant(0.04));
  for (Vec3& p : box.nodes) p += Vec3(-0.02, 0.0005, -0.02);
  const mesh::BoundarySurface boundary = mesh::extract_boundary(box.nodes, box.tets);
  mechanics::ModelConfig c;
  c.name = "block";
  c.positions = box.nodes;
  c.tets = box.tets;
  c.mass.kind = mechanics::MassKind::kDiagonal;
  c.mass.mass_density_kg_per_m3 = 1000.0;
  c.gravity_m_per_s2 = Vec3(0.0, -9.81, 0.0);
  mechanics::ForceFieldConfig fem;
  fem.name = "FEM";
  fem.tetrahedron_fem = mechanics::TetrahedronFemConfig{5000.0, 0.3, mechanics::FemMethod::kLarge, {}, {}};
  c.force_fields.push_back(fem);
  c.ode.kind = mechanics::OdeSolverKind::kEulerImplicit;
  c.linear.kind = mechanics::LinearSolverKind::kSparseLdlt;
  c.dt_s = 0.01;
  c.threads = 1;
  auto model = mechanics::build_model(c);
  EXPECT_TRUE(model) << model.error().to_string();
  auto mapping = SurfaceMapping::by_index(box.nodes, boundary.surface.vertices, boundary.surface_to_volume);
  EXPECT_TRUE(mapping) << mapping.error().to_string();
  std::vector<SessionBody> bodies(2);
  bodies[0].name = "block";
  bodies[0].model.emplace(std::move(*model));
  bodies[0].surface = boundary.surface;
  bodies[0].mapping = std::move(*mapping);
  bodies[0].config = c;
  bodies[0].collision.enabled = true;
  bodies[1].name = "floor";
  bodies[1].surface.vertices = {Vec3(-1, 0, -1), Vec3(-1, 0, 1), Vec3(1, 0, 1), Vec3(1, 0, -1)};
  bodies[1].surface.triangles = {{0, 1, 2}, {0, 2, 3}};
  bodies[1].collision.enabled = floor_collides;
  auto scripted =
      haptics::ScriptedMotion::make(haptics::MotionConfig::poke(Vec3(0, 1, 0), Vec3(0, 1, 0), 0.01, 0.001, 0.01, 0.0));
  EXPECT_TRUE(scripted);
  SessionConfig config;
  config.haptics.realtime_priority = false;
  config.pin_threads = false;
  config.contacts.enabled = contact;
  config.contacts.contact_distance_m = 1e-3;
  config.contacts.alarm_distance_m = 3e-3;
  config.contacts.stiffness_n_per_m = 1000.0;
  auto session = Session::make(std::move(bodies), std::make_unique<haptics::ScriptedDevice>(*scripted), config);
  EXPECT_TRUE(session) << session.error().to_string();
  return std::move(*session);
}

double lowest_y(const Session& session) {
  const Eigen::VectorXd& x = session.state(0).x;
  double lowest = std::numeric_limits<double>::infinity();
  for (Eigen::Index i = 1; i < x.size(); i += 3) lowest = std::min(lowest, x[i]);
  return lowest;
}

TEST(CommandSeam, AContactPairSwitchedOffPassesThroughAndOnAgainRests) {
  // Switched off: the block falls through the floor as if contact were off.
  auto off = block_on_floor_session(true);
  auto& contacts = off->graphics_contacts();  // published from now on
  ASSERT_TRUE(off->submit(command::SetContactPair{BodyId{1}, BodyId{0}, false}));
  SessionReport report = off->run_virtual(0.2, {});
  EXPECT_EQ(report.applied_commands.front(), "step 0: contact block - floor off");
  EXPECT_LT(lowest_y(*off), -0.01) << "the block rests on a floor switched off";
  EXPECT_EQ(report.body_contacts, 0);
  ASSERT_TRUE(contacts.acquire());
  EXPECT_TRUE(contacts.read().enabled);
  EXPECT_TRUE(contacts.read().contacts.empty());
  // Off, then on again before a step: the same run as never switched, bit for bit.
  auto reference = block_on_floor_session(true);
  auto& seen = reference->graphics_contacts();
  auto switched = block_on_floor_session(true);
  ASSERT_TRUE(switched->submit(command::SetContactPair{BodyId{0}, BodyId{1}, false}));
  ASSERT_TRUE(switched->submit(command::SetContactPair{BodyId{0}, BodyId{1}, true}));
  const SessionReport resting = reference->run_virtual(0.2, {});
  report = switched->run_virtual(0.2, {});
  EXPECT_EQ(report.applied_commands.back(), "step 0: contact block - floor on");
  EXPECT_EQ(switched->state(0).x, reference->state(0).x);
  EXPECT_GT(lowest_y(*reference), -1e-3) << "the floor holds the block within the contact distance";
  // The contacts a reader sees are the pass's, with the response's forces: on the block,
  // pushing it up, summing to the force the report gives the block.
  ASSERT_TRUE(seen.acquire());
  const BodyContactsView& view = seen.read();
  ASSERT_FALSE(view.contacts.empty());
  EXPECT_EQ(static_cast<std::int64_t>(view.contacts.size()), resting.body_contacts);
  Vec3 on_block = Vec3::Zero();
  for (const BodyContactView& c : view.contacts) {
    ASSERT_TRUE((c.body_a == 0 && c.body_b == 1) || (c.body_a == 1 && c.body_b == 0));
    const Vec3 force = c.body_a == 0 ? c.force_on_a_n : Vec3(-c.force_on_a_n);
    EXPECT_NEAR(c.force_on_a_n.normalized().dot(c.normal), 1.0, 1e-9);  // along the normal, pushing a off b
    on_block += force;
  }
  EXPECT_GT(on_block.y(), 0.0) << "the floor pushes the block up";
  EXPECT_LT((on_block - resting.bodies[0].body_contact_force_n).norm(),
            1e-9 * std::max(1.0, resting.bodies[0].body_contact_force_n.norm()));
}

TEST(CommandSeam, AContactPairIsRefusedWhenContactIsOffOrABodyTakesNoPart) {
  auto no_contact = block_on_floor_session(false);
  auto off = no_contact->submit(command::SetContactPair{BodyId{0}, BodyId{1}, false});
  ASSERT_FALSE(off);
  EXPECT_NE(off.error().message.find("contact between bodies is off"), std::string::npos) << off.error().message;
  auto session = block_on_floor_session(true, false);
  auto nobody = session->submit(command::SetContactPair{BodyId{0}, BodyId{5}, false});
  ASSERT_FALSE(nobody);
  EXPECT_NE(nobody.error().message.find("no body #5 (bodies: block, floor)"), std::string::npos)
      << nobody.error().message;
  auto no_part = session->submit(command::SetContactPair{BodyId{0}, BodyId{1}, false});
  ASSERT_FALSE(no_part);
  EXPECT_NE(no_part.error().message.find("body 'floor' takes no part"), std::string::npos) << no_part.error().message;
  auto itself = session->submit(command::SetContactPair{BodyId{0}, BodyId{0}, false});
  ASSERT_FALSE(itself);
  EXPECT_NE(itself.error().message.find("two different bodies"), std::string::npos) << itself.error().message;
  EXPECT_TRUE(session->run_virtual(0.02, {}).applied_commands.empty());
}

}  // namespace
}  // namespace hof::coupling
