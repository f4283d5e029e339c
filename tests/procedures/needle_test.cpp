// The needle tool driven tick by tick (as the haptic loop drives it, without the loop): the
// paths a hand takes that a scripted poke does not — back into the same hole, still with a
// noisy velocity, sideways out of the path, a change of parameters mid-insertion — and the
// tissue coupling's bookkeeping.

#include <gtest/gtest.h>

#include <array>
#include <cmath>

#include "hof/mesh/liver_generator.h"
#include "hof/procedures/needle.h"

#include "support/allocation_counter.h"
#include "support/box_surface.h"

namespace hof::procedures {
namespace {

// A block whose top face is z = 0 (body 0), and the contact a proxy reports on it: in contact
// while the stylus is at or below the top (or within `reach` above it).
struct Bench {
  haptics::SurfaceSnapshot surface;
  std::shared_ptr<NeedleTool> tool;
  haptics::ToolState state;
  Vec3 force{Vec3::Zero()};
  Vec3 surface_force{Vec3::Zero()};
  double time_s{0.0};
  Vec3 position{0.0, 0.0, 0.01};
  bool contact_override{false};  // keep the proxy in contact (a surface dragged out with the needle)

  explicit Bench(const NeedleConfig& config) {
    // The top face z = hi is triangles 2 and 3.
    surface = haptics::make_snapshot(hof::testing::box_surface(Vec3(-0.05, -0.05, -0.1), Vec3(0.05, 0.05, 0.0)));
    auto made = NeedleTool::make(config, {"block"}, {true});
    EXPECT_TRUE(made) << made.error().to_string();
    tool = *made;
  }

  // One tick with the stylus at `to`, moving at `velocity`.
  void tick(const Vec3& to, const Vec3& velocity) {
    position = to;
    time_s += 1e-3;
    std::array<haptics::ContactState, 1> contacts{};
    if (position.z() <= 0.0 || contact_override) {
      contacts[0].in_contact = true;
      contacts[0].triangle = 2;
      contacts[0].point = Vec3(position.x(), position.y(), 0.0);
      contacts[0].normal = Vec3(0, 0, 1);
      contacts[0].force = Vec3(0, 0, 5.0);  // what a stiff surface would push back with
    }
    const std::array<const haptics::SurfaceSnapshot*, 1> surfaces{&surface};
    std::array<Vec3, 1> layer_forces{contacts[0].force};
    haptics::ToolTickInput in;
    in.time_s = time_s;
    in.dt_s = 1e-3;
    in.position = position;
    in.velocity = velocity;
    in.contacts = contacts;
    in.surfaces = surfaces;
    in.max_stiffness_n_per_m = 3000.0;
    force = tool->tick(in, layer_forces, state);
    surface_force = layer_forces[0];
  }
  // Moves along −z (inward) at `speed` (m/s, negative: outward) to depth `depth` (m).
  void move_to_depth(double depth, double speed, const Vec3& lateral = Vec3::Zero()) {
    const double z_goal = -depth;
    const double step = std::abs(speed) * 1e-3;
    const double direction = z_goal < position.z() ? -1.0 : 1.0;
    while ((z_goal - position.z()) * direction > 1e-12) {
      const double z = direction < 0 ? std::max(z_goal, position.z() - step) : std::min(z_goal, position.z() + step);
      tick(Vec3(lateral.x(), lateral.y(), z), Vec3(0, 0, direction * std::abs(speed)));
    }
  }
  void hold(double seconds, double noise = 0.0) {
    for (int k = 0; k < static_cast<int>(seconds * 1e3); ++k) tick(position, Vec3(0, 0, k % 2 ? noise : -noise));
  }
  [[nodiscard]] NeedlePhase phase() const { return static_cast<NeedlePhase>(state.phase); }
};

TEST(NeedleTool, PushedBackIntoItsHoleTheNeedleMeetsFrictionOnlyNotANewCapsule) {
  NeedleConfig config;
  config.tissue.model = NeedleForceModel::kSimoneOkamura;
  Bench b(config);
  b.move_to_depth(0.03, 0.01);  // in, through the capsule (20 mm)
  ASSERT_TRUE(b.state.broken);
  // Out to just above the entry: the surface was dragged out with the needle, the proxy still
  // touches it.
  b.contact_override = true;
  b.move_to_depth(-0.0001, 0.01);
  EXPECT_EQ(b.phase(), NeedlePhase::kOut);
  EXPECT_EQ(b.surface_force, Vec3::Zero()) << "the dragged-out surface must not spring the hand back";
  // Back in through the same hole: no capsule, no cutting — friction on the inserted length.
  b.move_to_depth(0.015, 0.01);
  EXPECT_EQ(b.phase(), NeedlePhase::kPunctured);
  EXPECT_TRUE(b.state.broken);
  const double d = b.state.depth_m, v = b.state.axial_velocity_m_per_s;
  EXPECT_NEAR(d, 0.015, 1e-9);
  EXPECT_NEAR(b.state.axial_force_n, d * (0.121 + 3200.0 * v), 1e-9);
  // Beyond the old depth, new tissue is cut: the post-puncture model again (friction + cutting 0).
  b.move_to_depth(0.035, 0.01);
  EXPECT_NEAR(b.state.axial_force_n, b.state.depth_m * (0.121 + 3200.0 * b.state.axial_velocity_m_per_s), 1e-9);
  // Out, and off the surface: the hole is forgotten; the next contact is a new insertion.
  b.move_to_depth(-0.0001, 0.01);
  b.contact_override = false;
  b.move_to_depth(-0.005, 0.01);
  b.move_to_depth(0.005, 0.01);
  EXPECT_EQ(b.phase(), NeedlePhase::kPrePuncture);
  EXPECT_FALSE(b.state.broken);
}

TEST(NeedleTool, AStillNeedleWithANoisyVelocityStaysInRelaxation) {
  Bench b(NeedleConfig{});
  b.move_to_depth(0.03, 0.01);
  b.hold(0.2);  // relaxation begins
  ASSERT_EQ(b.phase(), NeedlePhase::kRelaxation);
  const double start = b.state.axial_force_n;
  // A real device's velocity estimate: ±1.5 mm/s from tick to tick (above the 1 mm/s band).
  double previous = start;
  for (int k = 0; k < 3000; ++k) {
    b.tick(b.position, Vec3(0, 0, k % 2 ? 0.0015 : -0.0015));
    ASSERT_EQ(b.phase(), NeedlePhase::kRelaxation) << "tick " << k;
    ASSERT_LE(std::abs(b.state.axial_force_n), std::abs(previous) + 1e-15);
    previous = b.state.axial_force_n;
  }
  EXPECT_LT(std::abs(previous), 0.3 * std::abs(start));  // τ = 2 s, 3 s: e^{-1.5} ≈ 0.22
}

TEST(NeedleTool, TornSidewaysOutOfItsPathTheNeedleIsWithdrawn) {
  Bench b(NeedleConfig{});
  b.move_to_depth(0.03, 0.01);
  ASSERT_EQ(b.phase(), NeedlePhase::kPunctured);
  // 5 mm sideways: held by the lateral spring (500 N/m), pulled back toward the path.
  b.tick(Vec3(0.005, 0.0, -0.03), Vec3::Zero());
  EXPECT_NEAR(b.force.x(), -500.0 * 0.005, 1e-6);
  EXPECT_NE(b.phase(), NeedlePhase::kOut);
  // 25 mm sideways (beyond pathTolerance, 20 mm): torn out.
  b.tick(Vec3(0.025, 0.0, -0.03), Vec3::Zero());
  EXPECT_EQ(b.phase(), NeedlePhase::kOut);
  EXPECT_EQ(b.force, Vec3::Zero());
}

TEST(NeedleTool, BeforePunctureTheDimpleSlidesWithTheTip) {
  Bench b(NeedleConfig{});
  b.move_to_depth(0.005, 0.01);
  ASSERT_EQ(b.phase(), NeedlePhase::kPrePuncture);
  // Sliding 30 mm across the intact capsule: no lateral force, the same depth and force.
  const double f = b.state.axial_force_n;
  for (int k = 1; k <= 300; ++k) b.tick(Vec3(1e-4 * k, 0.0, -0.005), Vec3(0.1, 0.0, 0.0));
  EXPECT_EQ(b.phase(), NeedlePhase::kPrePuncture);
  EXPECT_NEAR(b.force.x(), 0.0, 1e-12);
  EXPECT_NEAR(b.state.axial_force_n, f, 1e-12);
  EXPECT_NEAR(b.state.entry.x(), 0.03, 1e-12);
}

TEST(NeedleTool, NewParametersReachTheNextTickAndTheNeedleKeepsItsPhase) {
  Bench b(NeedleConfig{});
  b.move_to_depth(0.03, 0.01);
  ASSERT_EQ(b.phase(), NeedlePhase::kPunctured);
  NeedleConfig changed;
  changed.tissue.fung_post.f0_n = -2.0;
  ASSERT_TRUE(b.tool->configure(changed));
  b.tick(Vec3(0, 0, -0.0301), Vec3(0, 0, -0.01));
  EXPECT_EQ(b.phase(), NeedlePhase::kPunctured);
  EXPECT_NEAR(b.state.axial_force_n, fung_force(changed.tissue.fung_post, b.state.depth_m, changed.tissue.fung_form),
              1e-12);
  // A bad value is refused and changes nothing.
  changed.tissue.capsule_m = -1.0;
  EXPECT_FALSE(b.tool->configure(changed));
  EXPECT_EQ(b.tool->config().tissue.capsule_m, 0.02);
  // A restart (a device switch, a new calibration) forgets the insertion.
  b.tool->restart();
  b.tick(Vec3(0, 0, 0.01), Vec3::Zero());
  EXPECT_EQ(b.phase(), NeedlePhase::kFree);
}

TEST(NeedleTool, SceneLengthsInMillimetresAreConverted) {
  // The same insertion in a scene drawn in mm: depth, capsule and force as in metres.
  auto tool = *NeedleTool::make(NeedleConfig{}, {"block"}, {true}, 1e-3);
  Bench b(NeedleConfig{});
  b.tool = tool;
  b.position = Vec3(0, 0, 10.0);
  for (int k = 0; k <= 2500; ++k) b.tick(Vec3(0, 0, -0.01 * k), Vec3(0, 0, -10.0));  // 10 mm/s, to 25 mm
  EXPECT_NEAR(b.state.depth_m, 0.025, 1e-9);
  EXPECT_TRUE(b.state.broken);  // the 20 mm capsule, in mm
  const TissueNeedleParameters defaults;
  EXPECT_NEAR(b.state.axial_force_n, fung_force(defaults.fung_post, 0.025, defaults.fung_form), 1e-9);
  EXPECT_NEAR(tool->spread_radius(0), 10.0, 1e-12);  // 0.01 m in mm
}

TEST(NeedleTool, TheTickDoesNotAllocate) {
  HOF_SKIP_UNLESS_COUNTING_ALLOCATIONS();
  Bench b(NeedleConfig{});
  b.tick(Vec3(0, 0, 0.001), Vec3(0, 0, -0.01));
  const long before = hof::testing::thread_allocation_count();
  b.move_to_depth(0.03, 0.01);
  b.hold(1.0, 0.002);
  b.move_to_depth(-0.001, 0.01);
  EXPECT_EQ(hof::testing::thread_allocation_count(), before);
}

TEST(NeedleTissueCoupling, TheReactionIsSpreadOverManyNodesAndSumsToItExactly) {
  const mesh::Mesh liver = *mesh::generate_liver(mesh::LiverResolution::kMedium);
  mechanics::ModelConfig c;
  c.positions = liver.nodes;
  c.tets = liver.tets;
  const mechanics::MechanicalModel model = *mechanics::build_model(c);
  const mechanics::MechanicalState s = mechanics::make_state(model);
  for (const double radius : {0.01, 1e-5}) {  // a reach with many nodes, and one with none (the 4 nearest)
    NeedleConfig config;
    config.tissue.spread_radius_m = radius;
    auto tool = *NeedleTool::make(config, {"liver"}, {true});
    NeedleTissueCoupling coupling(tool);
    for (const NeedlePhase phase : {NeedlePhase::kPrePuncture, NeedlePhase::kPunctured, NeedlePhase::kExtraction}) {
      haptics::ToolState needle;
      needle.active = needle.touched = true;
      needle.broken = phase != NeedlePhase::kPrePuncture;
      needle.phase = static_cast<std::uint8_t>(phase);
      needle.body = 0;
      needle.entry = Vec3(0.03, 0.0, 0.05);
      needle.axis = Vec3(0, 0, -1);
      needle.depth_m = 0.04;
      needle.force = Vec3(0.3, -0.2, phase == NeedlePhase::kExtraction ? -0.7 : 1.9);  // on the hand
      std::vector<double> forces(3 * model.node_count(), 0.0);
      coupling.add_tissue_forces(needle, model, s, forces);
      Vec3 total = Vec3::Zero();
      int loaded = 0;
      for (std::size_t n = 0; n < model.node_count(); ++n) {
        const Vec3 f(forces[3 * n], forces[3 * n + 1], forces[3 * n + 2]);
        total += f;
        loaded += f.norm() > 0.0 ? 1 : 0;
      }
      EXPECT_NEAR((total + needle.force).norm(), 0.0, 1e-12) << "radius " << radius << ", " << phase_name(phase);
      EXPECT_GE(loaded, 4) << "radius " << radius << ", " << phase_name(phase);
      if (radius > 1e-3 && phase != NeedlePhase::kPrePuncture) {
        EXPECT_GE(loaded, 8);  // along the 40 mm path (the liver's inside is meshed coarser than its surface)
      }
    }
  }
}

}  // namespace
}  // namespace hof::procedures
