// The command seam: commands keep their order, a wrong one is a clear error that changes
// nothing, a full queue is an error rather than a wait, and commands submitted from other
// threads (the window and a script runner at once) are applied by the simulation between two
// steps. Written to run under ThreadSanitizer.

#include "hof/coupling/command_seam.h"

#include <gtest/gtest.h>

#include <algorithm>
#include <atomic>
#include <chrono>
#include <string>
#include <thread>
#include <vector>

#include "hof/coupling/session.h"
#include "hof/haptics/device_backends/scripted_device.h"

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

}  // namespace
}  // namespace hof::coupling
