// Needle insertion through the haptic loop's tool seam and the session's per-step hook, in
// virtual time: the force follows the model exactly, phase by phase; the tissue deforms around
// the path and is dragged on extraction; the device never gets more than its limit.

#include <gtest/gtest.h>

#include <cmath>
#include <set>

#include "hof/coupling/session.h"
#include "hof/haptics/device_backends/scripted_device.h"
#include "hof/mesh/boundary.h"
#include "hof/mesh/liver_generator.h"
#include "hof/procedures/needle.h"

#include "coupling/resting_liver.h"
#include "support/box_surface.h"

namespace hof::procedures {
namespace {

using coupling::Session;
using coupling::SessionBody;
using coupling::SessionConfig;

mesh::TriMesh box(const Vec3& lo, const Vec3& hi) { return hof::testing::box_surface(lo, hi); }

// Insert–hold–extract along −z: from `start`, `approach` to the surface, `depth` further at
// `speed`, hold, withdraw to the start at the same speed.
std::unique_ptr<haptics::ScriptedDevice> insertion(const Vec3& start, double approach, double depth, double speed,
                                                   double hold, const haptics::DeviceSpec& spec = {}) {
  const haptics::MotionConfig motion = haptics::MotionConfig::poke(start, Vec3(0, 0, -1), approach, depth, speed, hold);
  auto scripted = haptics::ScriptedMotion::make(motion);
  EXPECT_TRUE(scripted) << scripted.error().to_string();
  return std::make_unique<haptics::ScriptedDevice>(*scripted, spec);
}

SessionConfig needle_config(const NeedleConfig& needle, const std::vector<SessionBody>& bodies) {
  std::vector<std::string> names;
  std::vector<bool> deformable;
  for (const SessionBody& b : bodies) {
    names.push_back(b.name);
    deformable.push_back(b.deformable());
  }
  auto tool = NeedleTool::make(needle, names, deformable);
  EXPECT_TRUE(tool) << tool.error().to_string();
  SessionConfig config;
  config.haptics.realtime_priority = false;
  config.haptics.safety.fade_in_s = 0.0;
  config.tool = *tool;
  config.tool_coupling = std::make_shared<NeedleTissueCoupling>(*tool);
  return config;
}

// The tissue's parameters, written out here (not read from the library) for the checks.
constexpr double kPreA = 121.0, kPreB = -0.098, kPreD0 = 0.01145, kPreF0 = 0.2;
constexpr double kPostA = -31.0, kPostB = 1.7, kPostD0 = 0.01961, kPostF0 = -3.39;
double fung(double a, double b, double d0, double f0, double d) { return (f0 + b) * std::exp(a * (d - d0)) - b; }

struct BoxRun {
  std::vector<haptics::HapticSample> samples;
  coupling::SessionReport report;
};

// A rigid 10 cm box (top at z = 0) pierced along −z: the tissue does not move, so depth and
// force are exact functions of the script.
BoxRun pierce_box(NeedleConfig needle, haptics::RendererKind renderer, double speed = 0.01,
                  const haptics::DeviceSpec& spec = {}) {
  std::vector<SessionBody> bodies(1);
  bodies[0].name = "block";
  bodies[0].surface = box(Vec3(-0.05, -0.05, -0.1), Vec3(0.05, 0.05, 0.0));
  needle.bodies.emplace_back("block", needle.tissue);  // a rigid body is pierced only when named
  SessionConfig config = needle_config(needle, bodies);
  config.haptics.renderer.kind = renderer;
  auto session =
      Session::make(std::move(bodies), insertion(Vec3(0.003, 0.002, 0.01), 0.01, 0.04, speed, 1.0, spec), config);
  EXPECT_TRUE(session) << session.error().to_string();
  BoxRun run;
  const double seconds = (0.01 + 0.04 + 0.05) / speed + 1.0 + 0.5;
  run.report = (*session)->run_virtual(seconds, [&](const haptics::HapticSample& s) { run.samples.push_back(s); });
  return run;
}

TEST(NeedleInsertion, TheForceFollowsFungExactlyPhaseByPhase) {
  NeedleConfig needle;                              // the literature's defaults: Fung, capsule 20 mm, relaxation 2 s
  needle.tissue.fung_form = FungForm::kIntegrated;  // the form fung() writes out
  const BoxRun run = pierce_box(needle, haptics::RendererKind::kRuspini);
  std::set<NeedlePhase> seen;
  std::vector<NeedlePhase> order;
  double previous_axial = 0.0, relax_start = -1.0, relax_force = 0.0;
  NeedlePhase previous = NeedlePhase::kFree;
  int checked = 0;
  for (const haptics::HapticSample& s : run.samples) {
    ASSERT_TRUE(s.tool.active);
    if (!s.valid) continue;  // the script has ended
    const auto phase = static_cast<NeedlePhase>(s.tool.phase);
    if (order.empty() || order.back() != phase) order.push_back(phase);
    seen.insert(phase);
    const double d = s.tool.depth_m;
    const double v = s.tool.axial_velocity_m_per_s;  // the tool's (filtered) estimate, inward
    double expected = 0.0;
    switch (phase) {
      case NeedlePhase::kPrePuncture:
        expected = fung(kPreA, kPreB, kPreD0, kPreF0, d);
        break;
      case NeedlePhase::kPunctured:
        expected = fung(kPostA, kPostB, kPostD0, kPostF0, d);
        break;
      case NeedlePhase::kRelaxation:
        if (previous != NeedlePhase::kRelaxation) {
          relax_start = s.time_s;
          relax_force = previous_axial;
        }
        expected = relax_force * std::exp(-(s.time_s - relax_start) / 2.0);
        break;
      case NeedlePhase::kExtraction:  // Karnopp, its branches written out
        expected = v >= 0.001    ? d * (0.121 + 3200.0 * v)
                   : v <= -0.001 ? d * (-0.117 + -1600.0 * std::abs(v))
                                 : std::clamp(previous_axial, -0.117 * d, 0.121 * d);
        break;
      default:
        expected = 0.0;
        break;
    }
    if (s.time_s > 1.5 && s.time_s < 4.9) {
      // Away from the script's corners the velocity estimate is the script's (inserting at 10 mm/s).
      EXPECT_NEAR(v, 0.01, 1e-9) << "t = " << s.time_s;
    }
    EXPECT_NEAR(s.tool.axial_force_n, expected, 1e-9) << "phase " << phase_name(phase) << " at t = " << s.time_s;
    if (phase != NeedlePhase::kFree && phase != NeedlePhase::kOut && d > 0.0) {
      // The depth is the script's: the box top is z = 0, the axis −z.
      EXPECT_NEAR(d, -s.device.z(), 1e-9);
      // The hand feels −f along the axis, nothing sideways (the script moves on the axis).
      EXPECT_NEAR((s.requested_force - Vec3(0, 0, expected)).norm(), 0.0, 1e-9) << "t = " << s.time_s;
      ++checked;
    }
    previous_axial = s.tool.axial_force_n;
    previous = phase;
  }
  EXPECT_GT(checked, 5000);
  // Every phase, in the order of an insert–hold–extract.
  const std::vector<NeedlePhase> expected_order{
      NeedlePhase::kFree,       NeedlePhase::kTouching,   NeedlePhase::kPrePuncture, NeedlePhase::kPunctured,
      NeedlePhase::kRelaxation, NeedlePhase::kExtraction, NeedlePhase::kOut};
  EXPECT_EQ(order, expected_order);
}

TEST(NeedleInsertion, PunctureSwitchesModelRelaxationDecaysExtractionPullsTheOtherWay) {
  NeedleConfig integrated;  // Maurin's θ in the integrated form (an option): it pulls in after the puncture
  integrated.tissue.fung_form = FungForm::kIntegrated;
  const BoxRun run = pierce_box(integrated, haptics::RendererKind::kGodObject);
  double last_pre = 0.0, first_post = 0.0, puncture_depth = -1.0;
  std::vector<double> relaxation, extraction;
  NeedlePhase previous = NeedlePhase::kFree;
  for (const haptics::HapticSample& s : run.samples) {
    const auto phase = static_cast<NeedlePhase>(s.tool.phase);
    if (phase == NeedlePhase::kPrePuncture) last_pre = s.tool.axial_force_n;
    if (phase == NeedlePhase::kPunctured && previous == NeedlePhase::kPrePuncture) {
      first_post = s.tool.axial_force_n;
      puncture_depth = s.tool.depth_m;
    }
    if (phase == NeedlePhase::kRelaxation) relaxation.push_back(s.tool.axial_force_n);
    if (phase == NeedlePhase::kExtraction) extraction.push_back(s.tool.axial_force_n);
    previous = phase;
  }
  // The capsule breaks at its depth (20 mm, within one tick's travel), and the force drops.
  EXPECT_NEAR(puncture_depth, 0.02, 0.01 * 1e-3 + 1e-12);
  EXPECT_GT(last_pre, 0.3);
  EXPECT_LT(first_post, -3.0);
  // Relaxation: the magnitude decays, monotonically.
  ASSERT_GT(relaxation.size(), 100u);
  for (std::size_t i = 1; i < relaxation.size(); ++i) EXPECT_LE(std::abs(relaxation[i]), std::abs(relaxation[i - 1]));
  EXPECT_LT(std::abs(relaxation.back()), 0.7 * std::abs(relaxation.front()));
  // Extraction: friction that holds the needle back (f < 0 while the hand pulls out), and that
  // shrinks with the inserted length — not the insertion curve run backwards.
  ASSERT_GT(extraction.size(), 100u);
  for (double f : extraction) EXPECT_LE(f, 0.0);
  EXPECT_LT(std::abs(extraction.back()), std::abs(extraction.front()));
  EXPECT_GT(std::abs(extraction.front() - fung(kPostA, kPostB, kPostD0, kPostF0, 0.04)), 1.0);
}

// What the hand must feel with the default needle (Maurin et al. 2004, in vivo): the force
// rises while the capsule holds, drops by at least 30% when it breaks, resists insertion after
// it, and holds the needle back by friction while it is withdrawn.
TEST(NeedleInsertion, TheDefaultNeedleRisesDropsAtPunctureResistsAfterAndDragsOnExtraction) {
  const BoxRun run = pierce_box(NeedleConfig{}, haptics::RendererKind::kRuspini);
  std::vector<double> pre, post, extraction, extraction_depth;
  double sent_post_min = 1e9;
  NeedlePhase previous = NeedlePhase::kFree;
  double last_pre = 0.0, first_post = 0.0;
  for (const haptics::HapticSample& s : run.samples) {
    if (!s.valid) continue;
    const auto phase = static_cast<NeedlePhase>(s.tool.phase);
    const double f = s.tool.axial_force_n;
    if (phase == NeedlePhase::kPrePuncture) {
      pre.push_back(f);
      last_pre = f;
    }
    if (phase == NeedlePhase::kPunctured) {
      if (previous == NeedlePhase::kPrePuncture) first_post = f;
      post.push_back(f);
      // What the hand feels along the axis (the force sent, -f along -z here): pushed back out.
      sent_post_min = std::min(sent_post_min, s.force.z());
    }
    if (phase == NeedlePhase::kExtraction) {
      extraction.push_back(f);
      extraction_depth.push_back(s.tool.depth_m);
    }
    previous = phase;
  }
  ASSERT_GT(pre.size(), 100u);
  ASSERT_GT(post.size(), 100u);
  ASSERT_GT(extraction.size(), 100u);
  // Rise: monotone while the capsule holds, and to more than it began with.
  for (std::size_t i = 1; i < pre.size(); ++i) EXPECT_GE(pre[i], pre[i - 1] - 1e-12) << "pre-puncture sample " << i;
  EXPECT_GT(last_pre, pre.front() + 0.05);
  // Drop at the puncture: at least 30%.
  EXPECT_LT(first_post, 0.7 * last_pre);
  // After it the tissue resists insertion (never draws the needle in), and the hand feels it.
  for (double f : post) EXPECT_GT(f, 0.0);
  EXPECT_GT(post.back(), first_post);
  EXPECT_GT(sent_post_min, -1e-9);
  // Extraction: friction holding the needle back, shrinking with the inserted length.
  for (double f : extraction) EXPECT_LE(f, 0.0);
  EXPECT_LT(std::abs(extraction.back()), std::abs(extraction.front()));
  EXPECT_LT(extraction_depth.back(), extraction_depth.front());
}

TEST(NeedleInsertion, SimoneOkamuraPunctureThresholdAndKarnoppFriction) {
  NeedleConfig needle;
  needle.tissue.model = NeedleForceModel::kSimoneOkamura;
  needle.tissue.capsule_m = 0.05;        // deeper than the insertion: the force breaks it
  needle.tissue.puncture_force_n = 0.5;  // a0 + a1 d + a2 d² reaches 0.5 N at 14.3 mm
  const BoxRun run = pierce_box(needle, haptics::RendererKind::kGodObject);
  double puncture_depth = -1.0;
  NeedlePhase previous = NeedlePhase::kFree;
  int punctured = 0;
  for (const haptics::HapticSample& s : run.samples) {
    const auto phase = static_cast<NeedlePhase>(s.tool.phase);
    const double d = s.tool.depth_m, v = s.tool.axial_velocity_m_per_s;
    if (phase == NeedlePhase::kPrePuncture) {
      EXPECT_NEAR(s.tool.axial_force_n, 2.0 * d + 2300.0 * d * d, 1e-9);
    }
    if (phase == NeedlePhase::kPunctured) {
      if (previous == NeedlePhase::kPrePuncture) puncture_depth = d;
      // Stiffness gone; friction on the inserted length at the insertion speed (10 mm/s).
      EXPECT_NEAR(s.tool.axial_force_n, d * (0.121 + 3200.0 * v), 1e-9);
      ++punctured;
    }
    previous = phase;
  }
  const double threshold_depth = (-2.0 + std::sqrt(4.0 + 4 * 2300.0 * 0.5)) / (2 * 2300.0);
  EXPECT_NEAR(puncture_depth, threshold_depth, 1e-5 + 1e-12);
  EXPECT_GT(punctured, 1000);
}

// Presses a rigid block 5 mm deep with the needle; returns the largest push back (N) and
// whether the needle ever left `free`.
std::pair<double, bool> press_block(const NeedleConfig& needle) {
  std::vector<SessionBody> bodies(1);
  bodies[0].name = "block";
  bodies[0].surface = box(Vec3(-0.05, -0.05, -0.1), Vec3(0.05, 0.05, 0.0));
  SessionConfig config = needle_config(needle, bodies);
  auto session = Session::make(std::move(bodies), insertion(Vec3(0, 0, 0.01), 0.01, 0.005, 0.01, 0.2), config);
  EXPECT_TRUE(session);
  double pushed = 0.0;
  bool entered = false;
  (*session)->run_virtual(1.5, [&](const haptics::HapticSample& s) {
    entered = entered || static_cast<NeedlePhase>(s.tool.phase) != NeedlePhase::kFree;
    pushed = std::max(pushed, s.force.z());
  });
  return {pushed, entered};
}

TEST(NeedleInsertion, ARigidBodyIsAWallUnlessNamedAndANamedBodyCanBeMadeAWall) {
  // A rigid body not named in the needle's sets: a wall (its surface pushes back).
  const auto [unnamed_push, unnamed_entered] = press_block(NeedleConfig{});
  EXPECT_FALSE(unnamed_entered);
  EXPECT_GT(unnamed_push, 1.0);
  // Named with pierceable="true": entered (no surface force; 5 mm in, the capsule pushes).
  NeedleConfig named;
  named.bodies.emplace_back("block", named.tissue);
  const auto [named_push, named_entered] = press_block(named);
  EXPECT_TRUE(named_entered);
  EXPECT_LT(named_push, 0.2);
  // Named with pierceable="false": a wall again.
  named.bodies[0].second.pierceable = false;
  const auto [wall_push, wall_entered] = press_block(named);
  EXPECT_FALSE(wall_entered);
  EXPECT_GT(wall_push, 1.0);
}

TEST(NeedleInsertion, TheAxisFollowsTheMotionOrTheNormalAndTheLateralSpringHoldsThePath) {
  // An oblique insertion (17° from the normal) into the block.
  const auto run_oblique = [](NeedleAxis axis) {
    std::vector<SessionBody> bodies(1);
    bodies[0].name = "block";
    bodies[0].surface = box(Vec3(-0.05, -0.05, -0.1), Vec3(0.05, 0.05, 0.0));
    NeedleConfig needle;
    needle.axis = axis;
    needle.bodies.emplace_back("block", needle.tissue);
    SessionConfig config = needle_config(needle, bodies);
    // A point proxy on the flat face: the entry is where the path crosses it, the normal the
    // face's own (no shading from the box's edges).
    config.haptics.renderer.kind = haptics::RendererKind::kGodObject;
    const Vec3 direction(0.3, 0.0, -1.0);
    const haptics::MotionConfig motion = haptics::MotionConfig::poke(
        Vec3(-0.006, 0.0, 0.02), direction, 0.02 * direction.norm() /* to z = 0 */, 0.03, 0.01, 0.2);
    auto session = Session::make(
        std::move(bodies), std::make_unique<haptics::ScriptedDevice>(*haptics::ScriptedMotion::make(motion)), config);
    EXPECT_TRUE(session);
    haptics::HapticSample deepest;
    (*session)->run_virtual(5.6, [&](const haptics::HapticSample& s) {
      if (s.valid && s.tool.depth_m > deepest.tool.depth_m) deepest = s;
    });
    return deepest;
  };
  const Vec3 direction = Vec3(0.3, 0.0, -1.0).normalized();
  const haptics::HapticSample motion = run_oblique(NeedleAxis::kMotion);
  EXPECT_NEAR((motion.tool.axis - direction).norm(), 0.0, 1e-9);
  EXPECT_NEAR(motion.tool.depth_m, 0.03, 1e-5);
  // Along its own axis: no lateral force.
  EXPECT_NEAR((motion.requested_force + motion.tool.axial_force_n * motion.tool.axis).norm(), 0.0, 1e-9);
  const haptics::HapticSample normal = run_oblique(NeedleAxis::kNormal);
  EXPECT_NEAR((normal.tool.axis - Vec3(0, 0, -1)).norm(), 0.0, 1e-9);
  // Off its axis (the hand moved obliquely): the lateral spring pulls the tip back toward the
  // vertical path, 500 N/m times the offset.
  const Vec3 offset = (normal.device - normal.tool.entry) - normal.tool.depth_m * normal.tool.axis;
  const Vec3 lateral = normal.requested_force + normal.tool.axial_force_n * normal.tool.axis;
  EXPECT_GT(offset.norm(), 0.001);
  EXPECT_NEAR(lateral.dot(offset.normalized()), -500.0 * offset.norm(), 0.05 * 500.0 * offset.norm());
}

// The simple liver (co-rotational FEM, 5.4 kPa) pierced from above.
struct LiverRun {
  std::vector<haptics::HapticSample> samples;
  std::vector<Eigen::VectorXd> states;  // node positions at each step
  std::vector<double> state_times;
  mesh::Mesh liver;
};

LiverRun pierce_liver(NeedleForceModel model, FungForm form = FungForm::kIntegrated) {
  LiverRun run;
  run.liver = *mesh::generate_liver(mesh::LiverResolution::kSimple);
  const mesh::BoundarySurface b = mesh::extract_boundary(run.liver.nodes, run.liver.tets);
  mechanics::ModelConfig c = coupling::testing::resting_liver_config(run.liver);
  c.ode.rayleigh_mass = c.ode.rayleigh_stiffness = 0.1;
  c.dt_s = 0.01;
  auto built = mechanics::build_model(c);
  EXPECT_TRUE(built) << built.error().to_string();
  auto mapping = coupling::SurfaceMapping::by_index(run.liver.nodes, b.surface.vertices, b.surface_to_volume);
  EXPECT_TRUE(mapping);
  std::vector<SessionBody> bodies;
  bodies.push_back(SessionBody{"liver", std::move(*built), b.surface, std::move(*mapping), {}, {}});
  NeedleConfig needle;
  needle.tissue.model = model;
  needle.tissue.fung_form = form;
  SessionConfig config = needle_config(needle, bodies);
  // Over the right lobe's top (z ≈ 0.05), 30 mm in at 10 mm/s, hold 1 s, out.
  auto session = Session::make(std::move(bodies), insertion(Vec3(0.03, 0.0, 0.06), 0.01, 0.03, 0.01, 1.0), config);
  EXPECT_TRUE(session) << session.error().to_string();
  for (int step = 0; step < 800; ++step) {
    (*session)->run_virtual(0.01, [&](const haptics::HapticSample& s) { run.samples.push_back(s); });
    run.states.push_back((*session)->state().x);
    run.state_times.push_back(0.01 * (step + 1));
  }
  return run;
}

class LiverPierced : public ::testing::TestWithParam<std::pair<NeedleForceModel, FungForm>> {};

TEST_P(LiverPierced, DeformsAroundThePathAndIsDraggedOnExtraction) {
  const LiverRun run = pierce_liver(GetParam().first, GetParam().second);
  const Eigen::VectorXd& rest = run.states.front();
  // When each phase held, by time.
  double end_of_insertion = -1.0, start_of_extraction = -1.0, mid_extraction = -1.0;
  Vec3 entry = Vec3::Zero(), axis = Vec3::Zero();
  for (std::size_t i = 1; i < run.samples.size(); ++i) {
    const auto phase = static_cast<NeedlePhase>(run.samples[i].tool.phase);
    const auto before = static_cast<NeedlePhase>(run.samples[i - 1].tool.phase);
    if (before == NeedlePhase::kPunctured && phase == NeedlePhase::kRelaxation) {
      end_of_insertion = run.samples[i].time_s;
      entry = run.samples[i].tool.entry;
      axis = run.samples[i].tool.axis;
    }
    if (before == NeedlePhase::kRelaxation && phase == NeedlePhase::kExtraction)
      start_of_extraction = run.samples[i].time_s;
    if (phase == NeedlePhase::kExtraction && run.samples[i].tool.depth_m > 0.012 &&
        run.samples[i].tool.depth_m < 0.015) {
      mid_extraction = run.samples[i].time_s;
    }
  }
  ASSERT_GT(end_of_insertion, 0.0);
  ASSERT_GT(start_of_extraction, end_of_insertion);
  ASSERT_GT(mid_extraction, start_of_extraction);
  const auto state_at = [&](double t) -> const Eigen::VectorXd& {
    std::size_t k = 0;
    while (k + 1 < run.state_times.size() && run.state_times[k] < t) ++k;
    return run.states[k];
  };
  // At the end of the insertion: displaced, over many nodes (not one vertex).
  const Eigen::VectorXd& inserted = state_at(end_of_insertion);
  double largest = 0.0;
  std::vector<double> moved;
  for (Eigen::Index n = 0; n < rest.size() / 3; ++n) {
    moved.push_back((inserted.segment<3>(3 * n) - rest.segment<3>(3 * n)).norm());
    largest = std::max(largest, moved.back());
  }
  EXPECT_GT(largest, 1e-4);
  int spread = 0;
  for (double m : moved) spread += m > 0.5 * largest ? 1 : 0;
  EXPECT_GE(spread, 4) << "largest " << largest;
  // Extraction drags the tissue near the path outward (against the axis) from where it was
  // when the withdrawal began.
  const Eigen::VectorXd& held = state_at(start_of_extraction);
  const Eigen::VectorXd& dragged = state_at(mid_extraction);
  double outward = 0.0;
  int near_path = 0;
  for (Eigen::Index n = 0; n < rest.size() / 3; ++n) {
    const Vec3 x = held.segment<3>(3 * n);
    const double along = (x - entry).dot(axis);
    if (along < -0.005 || along > 0.03 || ((x - entry) - along * axis).norm() > 0.02)
      continue;  // the simple liver's nodes are ~15 mm apart
    outward += -(dragged.segment<3>(3 * n) - x).dot(axis);
    ++near_path;
  }
  ASSERT_GT(near_path, 0) << "entry " << entry.transpose() << " axis " << axis.transpose();
  EXPECT_GT(outward / near_path, 1e-5);
}

// Simone-Okamura, and Fung in the printed form (positive after puncture, so the tissue is
// pushed in while inserting and dragged out on extraction). In the integrated form the
// post-puncture force already pulls the tissue out while inserting (see docs/needle.md).
INSTANTIATE_TEST_SUITE_P(Needle, LiverPierced,
                         ::testing::Values(std::pair{NeedleForceModel::kSimoneOkamura, FungForm::kIntegrated},
                                           std::pair{NeedleForceModel::kFung, FungForm::kPrinted}));

TEST(NeedleInsertion, TheDeviceNeverGetsMoreThanItsLimitWhateverTheParameters) {
  haptics::DeviceSpec spec;
  spec.max_force_n = 3.3;  // a Touch
  spec.max_stiffness_n_per_m = 400.0;
  std::vector<NeedleConfig> sweep;
  for (double scale : {1e-6, 1.0, 1e3, 1e9, 1e300}) {
    NeedleConfig n;
    n.tissue.fung_pre = {121.0 * scale, -0.098 * scale, 0.0, 0.2 * scale};
    n.tissue.fung_post = {31.0 * scale, 1.7 * scale, 0.0, 3.39 * scale};
    n.tissue.friction.damping_negative_n_s_per_m2 = -1600.0 * scale;
    n.tissue.lateral_stiffness_n_per_m = 500.0 * scale;
    n.tissue.lateral_damping_n_s_per_m = scale;
    n.tissue.capsule_m = 0.001 * scale < 1e3 ? 0.001 : 1e3;
    sweep.push_back(n);
    n.tissue.model = NeedleForceModel::kSimoneOkamura;
    n.tissue.stiffness = {scale, -scale, scale};
    n.tissue.cutting_force_n = -scale;
    sweep.push_back(n);
  }
  for (const NeedleConfig& n : sweep) {
    for (double speed : {0.01, 0.5}) {
      const BoxRun run = pierce_box(n, haptics::RendererKind::kRuspini, speed, spec);
      for (const haptics::HapticSample& s : run.samples) {
        ASSERT_TRUE(s.force.allFinite());
        // Finite before the safety filter too: the tool itself never makes a NaN.
        ASSERT_TRUE(s.requested_force.allFinite()) << "t = " << s.time_s;
        ASSERT_TRUE(std::isfinite(s.tool.axial_force_n));
        ASSERT_LE(s.force.norm(), spec.max_force_n) << "t = " << s.time_s;
      }
    }
  }
}

}  // namespace
}  // namespace hof::procedures

namespace hof::procedures {
namespace {

// Two bodies side by side: a liver that is not touched, and a 4 cm block of FEM tissue (with a
// set of its own) that the needle enters. The block is a tetrahedral cube made here.
mechanics::ModelConfig block_config(const Vec3& origin, double size, int cells) {
  mechanics::ModelConfig c;
  c.name = "block";
  const double h = size / cells;
  const auto node = [&](int i, int j, int k) {
    return static_cast<std::int32_t>((k * (cells + 1) + j) * (cells + 1) + i);
  };
  for (int k = 0; k <= cells; ++k) {
    for (int j = 0; j <= cells; ++j) {
      for (int i = 0; i <= cells; ++i) c.positions.push_back(origin + Vec3(i * h, j * h, k * h));
    }
  }
  for (int k = 0; k < cells; ++k) {
    for (int j = 0; j < cells; ++j) {
      for (int i = 0; i < cells; ++i) {
        // Six tetrahedra per cube around its main diagonal (positively oriented).
        const std::array<std::int32_t, 8> v{
            node(i, j, k),     node(i + 1, j, k),     node(i + 1, j + 1, k),     node(i, j + 1, k),
            node(i, j, k + 1), node(i + 1, j, k + 1), node(i + 1, j + 1, k + 1), node(i, j + 1, k + 1)};
        const int tets[6][4] = {{0, 1, 2, 6}, {0, 2, 3, 6}, {0, 3, 7, 6}, {0, 7, 4, 6}, {0, 4, 5, 6}, {0, 5, 1, 6}};
        for (const auto& t : tets) {
          mesh::Tet tet{v[t[0]], v[t[1]], v[t[2]], v[t[3]]};
          const Vec3 a = c.positions[tet[0]], b = c.positions[tet[1]], cc = c.positions[tet[2]],
                     d = c.positions[tet[3]];
          if ((b - a).dot((cc - a).cross(d - a)) < 0.0) std::swap(tet[2], tet[3]);
          c.tets.push_back(tet);
        }
      }
    }
  }
  c.mass.mass_density_kg_per_m3 = 1000.0;
  c.gravity_m_per_s2 = Vec3::Zero();
  mechanics::ForceFieldConfig fem;
  fem.name = "FEM";
  fem.tetrahedron_fem = mechanics::TetrahedronFemConfig{15000.0, 0.45, mechanics::FemMethod::kLarge, {}, {}};
  c.force_fields.push_back(fem);
  mechanics::FixedConstraintConfig base;
  base.box = std::make_pair(origin - Vec3::Constant(1e-6), origin + Vec3(size, size, 1e-6));
  c.fixed.push_back(base);
  c.ode.rayleigh_mass = c.ode.rayleigh_stiffness = 0.1;
  c.dt_s = 0.01;
  return c;
}

SessionBody deformable_body(const std::string& name, mechanics::ModelConfig c) {
  c.name = name;
  mesh::Mesh m;
  m.nodes = c.positions;
  m.tets = c.tets;
  const mesh::BoundarySurface b = mesh::extract_boundary(m.nodes, m.tets);
  auto built = mechanics::build_model(c);
  EXPECT_TRUE(built) << built.error().to_string();
  auto mapping = coupling::SurfaceMapping::by_index(m.nodes, b.surface.vertices, b.surface_to_volume);
  EXPECT_TRUE(mapping);
  return SessionBody{name, std::move(*built), b.surface, std::move(*mapping), {}, c};
}

TEST(NeedleInsertion, EntersTheBodyItTouchesInAWorldOfSeveralWithThatBodysOwnParameters) {
  const mesh::Mesh liver = *mesh::generate_liver(mesh::LiverResolution::kSimple);
  std::vector<SessionBody> bodies;
  bodies.push_back(deformable_body("liver", coupling::testing::resting_liver_config(liver)));
  bodies.push_back(deformable_body("block", block_config(Vec3(0.2, -0.02, 0.0), 0.04, 6)));
  NeedleConfig needle;  // every deformable body: capsule 20 mm; the block: 8 mm, Simone-Okamura
  TissueNeedleParameters block = needle.tissue;
  block.capsule_m = 0.008;
  block.model = NeedleForceModel::kSimoneOkamura;
  needle.bodies.emplace_back("block", block);
  SessionConfig config = needle_config(needle, bodies);
  // Down into the block's top (z = 0.04) at its middle: 20 mm in, hold, out.
  auto session = Session::make(std::move(bodies), insertion(Vec3(0.221, 0.001, 0.05), 0.01, 0.02, 0.01, 0.5), config);
  ASSERT_TRUE(session) << session.error().to_string();
  double puncture_depth = -1.0;
  std::set<std::int32_t> pierced;
  NeedlePhase previous = NeedlePhase::kFree;
  const coupling::SessionReport report = (*session)->run_virtual(6.0, [&](const haptics::HapticSample& s) {
    const auto phase = static_cast<NeedlePhase>(s.tool.phase);
    if (s.tool.body >= 0) pierced.insert(s.tool.body);
    if (phase == NeedlePhase::kPunctured && previous == NeedlePhase::kPrePuncture) puncture_depth = s.tool.depth_m;
    if (phase == NeedlePhase::kPrePuncture) {
      EXPECT_NEAR(s.tool.axial_force_n, 2.0 * s.tool.depth_m + 2300.0 * s.tool.depth_m * s.tool.depth_m, 1e-9);
    }
    previous = phase;
  });
  EXPECT_EQ(pierced, std::set<std::int32_t>{1});
  EXPECT_NEAR(puncture_depth, 0.008, 1e-5 + 1e-12);  // the block's capsule, not the common one
  ASSERT_EQ(report.bodies.size(), 2u);
  EXPECT_LT(report.bodies[0].max_displacement_m, 1e-9);  // the liver is not touched (round-off only)
  EXPECT_GT(report.bodies[1].max_displacement_m, 1e-4);
  EXPECT_GT(report.bodies[1].contact_time_s, 1.0);
}

TEST(NeedleInsertion, RealTimeSessionRunsAndStopsCleanlyWithTheNeedle) {
  // Real time on two threads: whatever the machine's load, no force above the limit, no NaN,
  // telemetry in tick order, and a clean stop.
  const mesh::Mesh liver = *mesh::generate_liver(mesh::LiverResolution::kSimple);
  std::vector<SessionBody> bodies;
  bodies.push_back(deformable_body("liver", coupling::testing::resting_liver_config(liver)));
  SessionConfig config = needle_config(NeedleConfig{}, bodies);
  haptics::DeviceSpec spec;
  spec.max_force_n = 3.3;
  auto session =
      Session::make(std::move(bodies), insertion(Vec3(0.03, 0.0, 0.06), 0.01, 0.03, 0.05, 0.1, spec), config);
  ASSERT_TRUE(session) << session.error().to_string();
  std::uint64_t last_tick = 0;
  bool ordered = true, any = false;
  const coupling::SessionReport report = (*session)->run_realtime(1.0, [&](const haptics::HapticSample& s) {
    ordered = ordered && (!any || s.tick > last_tick);
    last_tick = s.tick;
    any = true;
    EXPECT_TRUE(s.force.allFinite());
    EXPECT_LE(s.force.norm(), spec.max_force_n);
  });
  EXPECT_TRUE(any);
  EXPECT_TRUE(ordered);
  EXPECT_FALSE(report.diverged) << report.divergence;
  EXPECT_FALSE((*session)->realtime_running());
}

}  // namespace
}  // namespace hof::procedures
