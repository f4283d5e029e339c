// Two hands at once (issue 37): two scripted devices, each with its own shaped tool, haptic
// loop and force limit, on one liver — in virtual time (lock-step, deterministic).

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <memory>
#include <vector>

#include "hof/coupling/session.h"
#include "hof/haptics/device_backends/scripted_device.h"
#include "hof/mesh/boundary.h"
#include "hof/mesh/liver_generator.h"
#include "hof/procedures/shaped_tool.h"

#include "coupling/resting_liver.h"

namespace hof::coupling {
namespace {

// The simple liver (co-rotational FEM, E = 5.4 kPa), resting on its base.
struct Liver {
  mesh::Mesh mesh;
  mesh::BoundarySurface boundary;
  mechanics::ModelConfig config;
};

Liver make_liver() {
  mesh::Mesh m = *mesh::generate_liver(mesh::LiverResolution::kSimple);
  mesh::BoundarySurface b = mesh::extract_boundary(m.nodes, m.tets);
  mechanics::ModelConfig c = testing::resting_liver_config(m);
  c.ode.rayleigh_mass = c.ode.rayleigh_stiffness = 0.1;
  c.dt_s = 0.01;
  return Liver{std::move(m), std::move(b), std::move(c)};
}

// The highest surface point of the liver near (x, y).
double top_at(const Liver& liver, double x, double y) {
  double top = -1.0;
  for (const Vec3& v : liver.boundary.surface.vertices) {
    if (std::abs(v.x() - x) < 0.01 && std::abs(v.y() - y) < 0.01) top = std::max(top, v.z());
  }
  return top;
}

SessionBody liver_body(const Liver& liver) {
  auto model = mechanics::build_model(liver.config);
  EXPECT_TRUE(model) << model.error().to_string();
  auto mapping =
      SurfaceMapping::by_index(liver.mesh.nodes, liver.boundary.surface.vertices, liver.boundary.surface_to_volume);
  EXPECT_TRUE(mapping);
  SessionBody body;
  body.name = "liver";
  body.model.emplace(std::move(*model));
  body.surface = liver.boundary.surface;
  body.mapping = std::move(*mapping);
  body.config = liver.config;
  return body;
}

std::vector<SessionBody> liver_bodies(const Liver& liver) {
  std::vector<SessionBody> bodies;
  bodies.push_back(liver_body(liver));
  return bodies;
}

// A shaped tool and its tissue coupling on the liver.
struct MadeTool {
  std::shared_ptr<procedures::ShapedTool> tool;
  std::shared_ptr<procedures::ShapedTissueCoupling> coupling;
};
MadeTool make_tool(const Liver& liver, procedures::ToolShape shape, double radius, double length) {
  procedures::ShapedToolConfig c;
  c.shape = shape;
  c.radius_m = radius;
  c.length_m = length;
  auto tool = procedures::ShapedTool::make(c);
  EXPECT_TRUE(tool) << tool.error().to_string();
  auto mapping =
      SurfaceMapping::by_index(liver.mesh.nodes, liver.boundary.surface.vertices, liver.boundary.surface_to_volume);
  std::vector<procedures::ToolBodySurface> bodies{procedures::ToolBodySurface{
      liver.boundary.surface.triangles, liver.boundary.surface.vertices.size(), std::move(*mapping)}};
  return MadeTool{*tool, std::make_shared<procedures::ShapedTissueCoupling>(*tool, std::move(bodies))};
}

// A poke along −z onto the liver's top at (x, y), `depth` past it; or, with `free_space`, a
// poke that moves away above everything.
std::unique_ptr<haptics::ScriptedDevice> poke(const Liver& liver, double x, double y, double radius, double depth,
                                              bool free_space = false) {
  const double top = top_at(liver, x, y);
  EXPECT_GT(top, 0.0) << "no liver top at " << x << ", " << y;
  const Vec3 start = free_space ? Vec3(x, y, 0.3) : Vec3(x, y, top + radius + 0.01);
  const Vec3 direction = free_space ? Vec3(0, 0, 1) : Vec3(0, 0, -1);
  const haptics::MotionConfig motion = haptics::MotionConfig::poke(start, direction, 0.01, depth, 0.02, 0.5);
  auto scripted = haptics::ScriptedMotion::make(motion);
  EXPECT_TRUE(scripted) << scripted.error().to_string();
  return std::make_unique<haptics::ScriptedDevice>(*scripted);
}

constexpr double kRadius = 0.005;
constexpr double kLimitA_n = 3.0;  // the first hand's force limit
constexpr double kLimitB_n = 0.3;  // the second's: lower, so that its own limit is seen to hold

struct TwoHandRun {
  SessionReport report;
  double max_force_a{0.0}, max_force_b{0.0};  // as the devices received them (checked every 10 ms)
  int pressed_a{0}, pressed_b{0};             // checks with a force on the device
  std::vector<Vec3> final_positions;          // the liver's nodes at the end
};

// Hand A (a sphere) at x = −0.03 and hand B (a capsule) at x = +0.03, each pressing or in free
// space; `b_present` false: one hand only (A).
TwoHandRun run_hands(bool a_presses, bool b_presses, bool b_present = true) {
  const Liver liver = make_liver();
  const MadeTool a = make_tool(liver, procedures::ToolShape::kSphere, kRadius, 0.0);
  const MadeTool b = make_tool(liver, procedures::ToolShape::kCapsule, kRadius, 0.03);
  SessionConfig config;
  config.haptics.realtime_priority = false;
  config.haptics.safety.fade_in_s = 0.0;
  config.haptics.safety.max_force_n = kLimitA_n;
  config.tool = a.tool;
  config.tool_coupling = a.coupling;
  auto device_a = poke(liver, -0.03, 0.0, kRadius, 0.012, !a_presses);
  haptics::ScriptedDevice* seen_a = device_a.get();
  std::vector<std::unique_ptr<haptics::Device>> more;
  haptics::ScriptedDevice* seen_b = nullptr;
  if (b_present) {
    HandConfig hand;
    hand.device = "scripted (B)";
    hand.haptics = config.haptics;
    hand.haptics.safety.max_force_n = kLimitB_n;
    hand.tool = b.tool;
    hand.tool_coupling = b.coupling;
    config.more_hands.push_back(hand);
    auto device_b = poke(liver, 0.03, 0.0, kRadius, 0.012, !b_presses);
    seen_b = device_b.get();
    more.push_back(std::move(device_b));
  }
  auto session = Session::make(liver_bodies(liver), std::move(device_a), std::move(more), config);
  EXPECT_TRUE(session) << session.error().to_string();
  TwoHandRun run;
  if (!session) return run;
  EXPECT_EQ((*session)->hand_count(), b_present ? 2u : 1u);
  for (int k = 0; k < 200; ++k) {
    const SessionReport part = (*session)->run_virtual(0.01, {});
    run.report.max_force_n = std::max(run.report.max_force_n, part.max_force_n);
    EXPECT_FALSE(part.diverged) << part.divergence;
    if (run.report.hands.empty()) {
      run.report.hands = part.hands;
    } else {
      for (std::size_t h = 0; h < part.hands.size(); ++h) {
        run.report.hands[h].max_force_n = std::max(run.report.hands[h].max_force_n, part.hands[h].max_force_n);
        run.report.hands[h].contact_time_s += part.hands[h].contact_time_s;
        run.report.hands[h].haptic_ticks += part.hands[h].haptic_ticks;
        run.report.hands[h].clamped_contact_ticks += part.hands[h].clamped_contact_ticks;
      }
    }
    const double fa = seen_a->last_force().norm();
    run.max_force_a = std::max(run.max_force_a, fa);
    run.pressed_a += fa > 0.0 ? 1 : 0;
    if (seen_b) {
      const double fb = seen_b->last_force().norm();
      run.max_force_b = std::max(run.max_force_b, fb);
      run.pressed_b += fb > 0.0 ? 1 : 0;
    }
  }
  const mechanics::MechanicalState& state = (*session)->state();
  for (std::size_t n = 0; n < liver.mesh.nodes.size(); ++n)
    run.final_positions.push_back(state.position(static_cast<std::int32_t>(n)));
  return run;
}

// The largest displacement of the liver's nodes within 1.5 cm (in x and y) of (x, y).
double moved_near(const TwoHandRun& run, double x, double y) {
  const Liver liver = make_liver();
  double largest = 0.0;
  for (std::size_t n = 0; n < liver.mesh.nodes.size(); ++n) {
    const Vec3& p = liver.mesh.nodes[n];
    if (std::abs(p.x() - x) > 0.015 || std::abs(p.y() - y) > 0.015) continue;
    largest = std::max(largest, (run.final_positions[n] - p).norm());
  }
  return largest;
}

// A SOFA two-device scene gave both devices the first one's feedback: here each device gets its
// own tool's force only — the one in free space none at all — under its own limit.
TEST(SessionHands, EachDeviceReceivesTheForceOfItsOwnToolOnly) {
  const TwoHandRun run = run_hands(true, false);
  ASSERT_EQ(run.report.hands.size(), 2u);
  EXPECT_GT(run.pressed_a, 20);
  EXPECT_GT(run.max_force_a, 0.05);
  EXPECT_LE(run.max_force_a, kLimitA_n + 1e-9);
  EXPECT_EQ(run.pressed_b, 0);
  EXPECT_EQ(run.max_force_b, 0.0);
  EXPECT_EQ(run.report.hands[1].max_force_n, 0.0);
  EXPECT_EQ(run.report.hands[1].contact_time_s, 0.0);
  EXPECT_GT(run.report.hands[0].contact_time_s, 0.2);
  EXPECT_EQ(run.report.hands[0].max_force_n, run.report.max_force_n);  // the report's figures are the first hand's
  EXPECT_EQ(run.report.hands[0].haptic_ticks, run.report.hands[1].haptic_ticks);  // lock-step
  EXPECT_DOUBLE_EQ(run.report.hands[0].max_force_limit_n, kLimitA_n);
  EXPECT_DOUBLE_EQ(run.report.hands[1].max_force_limit_n, kLimitB_n);

  // The other way round: the second presses, the first is in free space.
  const TwoHandRun swapped = run_hands(false, true);
  EXPECT_EQ(swapped.pressed_a, 0);
  EXPECT_EQ(swapped.max_force_a, 0.0);
  EXPECT_EQ(swapped.report.max_force_n, 0.0);
  EXPECT_GT(swapped.pressed_b, 20);
  EXPECT_GT(swapped.max_force_b, 0.05);
  EXPECT_LE(swapped.max_force_b, kLimitB_n + 1e-9);
  EXPECT_LE(swapped.report.hands[1].max_force_n, kLimitB_n + 1e-9);
}

// Both press the same liver: each feels its own reaction (as when it presses alone, under its
// own limit), and the liver takes both presses.
TEST(SessionHands, TwoHandsPressingOneBodyEachFeelTheirOwnReactionAndTheBodyTakesBoth) {
  const TwoHandRun both = run_hands(true, true);
  const TwoHandRun only_a = run_hands(true, false);
  const TwoHandRun only_b = run_hands(false, true);
  ASSERT_EQ(both.report.hands.size(), 2u);
  EXPECT_LE(both.max_force_a, kLimitA_n + 1e-9);
  EXPECT_LE(both.report.hands[0].max_force_n, kLimitA_n + 1e-9);
  EXPECT_LE(both.report.hands[1].max_force_n, kLimitB_n + 1e-9);
  EXPECT_GT(both.report.hands[0].max_force_n, 2.0 * kLimitB_n);  // the first is not held to the second's limit
  EXPECT_EQ(both.report.hands[0].clamped_contact_ticks, 0);
  EXPECT_GT(both.report.hands[1].clamped_contact_ticks, 100);  // the second pressed into its own limit
  // Each hand's force as when it presses alone (the other press is 6 cm away).
  EXPECT_NEAR(both.report.hands[0].max_force_n, only_a.report.hands[0].max_force_n,
              0.2 * only_a.report.hands[0].max_force_n);
  EXPECT_NEAR(both.report.hands[1].max_force_n, only_b.report.hands[1].max_force_n,
              0.2 * only_b.report.hands[1].max_force_n);
  // The liver took both presses: near each, it moved as that hand alone moved it, and more than
  // the other hand alone did.
  const double both_at_a = moved_near(both, -0.03, 0.0), both_at_b = moved_near(both, 0.03, 0.0);
  EXPECT_GT(both_at_a, 1e-3);
  EXPECT_GT(both_at_b, 1e-3);
  EXPECT_GT(both_at_a, 2.0 * moved_near(only_b, -0.03, 0.0));
  EXPECT_GT(both_at_b, 2.0 * moved_near(only_a, 0.03, 0.0));
}

// One device: one hand, whose figures are the report's.
TEST(SessionHands, OneDeviceIsOneHandWithTheReportsFigures) {
  const TwoHandRun run = run_hands(true, false, false);
  ASSERT_EQ(run.report.hands.size(), 1u);
  EXPECT_EQ(run.report.hands[0].max_force_n, run.report.max_force_n);
  EXPECT_GT(run.report.hands[0].max_force_n, 0.05);
}

// Bad input: a device count that does not match the hands, one tool on two hands, another rate.
TEST(SessionHands, AHandWithoutItsDeviceOrWithAnotherHandsToolIsRefused) {
  const Liver liver = make_liver();
  const MadeTool a = make_tool(liver, procedures::ToolShape::kSphere, kRadius, 0.0);
  SessionConfig config;
  config.haptics.realtime_priority = false;
  config.tool = a.tool;
  config.tool_coupling = a.coupling;
  HandConfig hand;
  hand.device = "scripted:poke";
  hand.haptics = config.haptics;
  config.more_hands.push_back(hand);
  auto none = Session::make(liver_bodies(liver), poke(liver, 0, 0, kRadius, 0.01), {}, config);
  ASSERT_FALSE(none);
  EXPECT_NE(none.error().message.find("1 more hand(s) configured but 0 device(s)"), std::string::npos)
      << none.error().message;

  config.more_hands[0].tool = a.tool;  // the first hand's tool
  std::vector<std::unique_ptr<haptics::Device>> more;
  more.push_back(poke(liver, 0, 0, kRadius, 0.01));
  auto shared = Session::make(liver_bodies(liver), poke(liver, 0, 0, kRadius, 0.01), std::move(more), config);
  ASSERT_FALSE(shared);
  EXPECT_NE(shared.error().message.find("carries the first hand's tool"), std::string::npos) << shared.error().message;

  config.more_hands[0].tool.reset();
  config.more_hands[0].haptics.rate_hz = 500.0;
  more.clear();
  more.push_back(poke(liver, 0, 0, kRadius, 0.01));
  auto rate = Session::make(liver_bodies(liver), poke(liver, 0, 0, kRadius, 0.01), std::move(more), config);
  ASSERT_FALSE(rate);
  EXPECT_NE(rate.error().message.find("haptic rate 500 Hz"), std::string::npos) << rate.error().message;
}

}  // namespace
}  // namespace hof::coupling
