// Fault injection in the coupled system (issue "Reliability and safety"): an exploding
// simulation, a simulation thread that stalls, a device that stops answering or sends garbage,
// a snapshot that never arrives, the window thread blocked. In each case the device never
// receives a force above its limit or a non-finite force, the force fades to zero within a
// bound computed from the safety configuration, the fault is reported, and the session
// recovers or stops cleanly.
//
// Virtual time (lock-step) wherever the fault can be expressed there: those tests are exact
// and count ticks. The real-time tests check only what holds under any load — no deadlock,
// no lost or torn snapshot, a clean stop — and wait on counts (ticks, steps, samples) with
// generous deadlines, never on durations.

#include <gtest/gtest.h>

#include <atomic>
#include <chrono>
#include <cmath>
#include <functional>
#include <limits>
#include <memory>
#include <thread>
#include <vector>

#include "hof/coupling/session.h"
#include "hof/mechanics/force_field.h"
#include "hof/mesh/boundary.h"
#include "hof/mesh/liver_generator.h"

#include "coupling/resting_liver.h"

namespace hof::coupling {
namespace {

using Clock = std::chrono::steady_clock;
using haptics::HapticSample;

constexpr double kTick = 1e-3;  // the default haptic rate, 1 kHz
// A real-time wait that has not seen its count by then has hung (a generous deadline, not a
// timing: a loaded 2-core machine reaches every count below in well under a second).
constexpr auto kDeadline = std::chrono::seconds(60);

// ---- The world: the simple liver (co-rotational FEM, resting on its base), pressed from above.

const mesh::Mesh& simple_liver() {
  static const mesh::Mesh liver = *mesh::generate_liver(mesh::LiverResolution::kSimple);
  return liver;
}

mechanics::ModelConfig stable_liver() {
  mechanics::ModelConfig c = testing::resting_liver_config(simple_liver());
  c.name = "Liver";
  c.ode.rayleigh_mass = c.ode.rayleigh_stiffness = 0.1;
  return c;
}

// Explicit Euler at dt = 10 ms on tissue a thousand times stiffer: the critical step is
// ~0.1 ms, so the first disturbance (the press) grows by orders of magnitude every step until
// a node passes the model's speed limit.
mechanics::ModelConfig exploding_liver() {
  mechanics::ModelConfig c = stable_liver();
  c.ode.kind = mechanics::OdeSolverKind::kEulerExplicit;
  c.force_fields[0].tetrahedron_fem->young_modulus_pa *= 1000.0;
  return c;
}

SessionBody liver_body(const mechanics::ModelConfig& c, std::unique_ptr<mechanics::ForceField> extra = nullptr) {
  const mesh::BoundarySurface b = mesh::extract_boundary(simple_liver().nodes, simple_liver().tets);
  auto model = mechanics::build_model(c);
  EXPECT_TRUE(model) << model.error().to_string();
  // A test-only field joins the built model before the session makes its state (the state
  // sizes one field state per field): it adds no force and no stiffness.
  if (extra) model->force_fields.push_back(std::move(extra));
  auto mapping = SurfaceMapping::by_index(simple_liver().nodes, b.surface.vertices, b.surface_to_volume);
  EXPECT_TRUE(mapping);
  return SessionBody{"Liver", std::move(*model), b.surface, std::move(*mapping), {}, c};
}

// Straight down onto the right lobe (as the other coupling tests): out of contact until
// ~0.8 s, 1 cm past the first touch at 1 s, then held.
Vec3 press(double t) { return Vec3(0.03, 0.0, 0.09 - 0.05 * std::clamp(t, 0.0, 1.0)); }

// ---- Devices.

enum class Fault : std::uint8_t {
  kNone,
  kSilent,  // no sample (valid = false), health kTimedOut
  kNanPosition,
  kInfPosition,
  kNanVelocity,
  kZeroQuaternion,  // no rotation at all: garbage
  kNanQuaternion,
  kScaledQuaternion,  // finite, |q| = 5: a rotation badly scaled, not garbage
  kJumpDown,          // 3 m straight through the body in one tick
  kJumpAside,         // 3 m to the side in one tick
};

/// A device following `path` in the device frame (identity calibration: the world) whose
/// reading is spoiled as `schedule` says; remembers every force it is sent.
class FaultyDevice final : public haptics::Device {
 public:
  using Path = std::function<Vec3(double)>;
  using Schedule = std::function<Fault(double)>;
  FaultyDevice(Path path, Schedule schedule) : path_(std::move(path)), schedule_(std::move(schedule)) {
    forces.reserve(1 << 16);
  }
  [[nodiscard]] const haptics::DeviceSpec& spec() const override { return spec_; }
  [[nodiscard]] std::string_view backend() const override { return "faulty"; }
  haptics::DeviceReading read(double time_s) override {
    const Fault fault = schedule_ ? schedule_(time_s) : Fault::kNone;
    health_.store(fault == Fault::kSilent ? haptics::DeviceHealth::kTimedOut : haptics::DeviceHealth::kOk);
    haptics::DeviceReading r;
    r.time_s = time_s;
    r.position_m = path_(time_s);
    r.velocity_m_per_s = (path_(time_s + 1e-4) - path_(time_s - 1e-4)) / 2e-4;
    r.valid = fault != Fault::kSilent;
    const double nan = std::numeric_limits<double>::quiet_NaN(), inf = std::numeric_limits<double>::infinity();
    switch (fault) {
      case Fault::kNanPosition:
        r.position_m.x() = nan;
        break;
      case Fault::kInfPosition:
        r.position_m.z() = -inf;
        break;
      case Fault::kNanVelocity:
        r.velocity_m_per_s.y() = nan;
        break;
      case Fault::kZeroQuaternion:
        r.orientation.coeffs().setZero();
        break;
      case Fault::kNanQuaternion:
        r.orientation.coeffs() << nan, 0.0, 0.0, 1.0;
        break;
      case Fault::kScaledQuaternion:
        r.orientation.coeffs() << 0.0, 0.0, 0.0, 5.0;
        break;
      case Fault::kJumpDown:
        r.position_m += Vec3(0.0, 0.0, -3.0);
        break;
      case Fault::kJumpAside:
        r.position_m += Vec3(3.0, 0.0, 0.0);
        break;
      default:
        break;
    }
    if (fault == Fault::kSilent) ++silent_reads;
    return r;
  }
  void write_force(const Vec3& force, const Vec3&) override {
    if (forces.size() < forces.capacity()) forces.push_back(force);
    last_force = force;
  }
  [[nodiscard]] haptics::DeviceHealth health() const override { return health_.load(); }

  std::vector<Vec3> forces;  // every force written (haptic thread; read it when the loop has stopped)
  Vec3 last_force{Vec3::Zero()};
  std::int64_t silent_reads{0};

 private:
  haptics::DeviceSpec spec_;  // the virtual model: 8 N, 2000 N/s
  Path path_;
  Schedule schedule_;
  std::atomic<haptics::DeviceHealth> health_{haptics::DeviceHealth::kOk};
};

// ---- A simulation that stalls: a field whose add_force blocks while asked to.

struct StallControl {
  std::atomic<bool> requested{false};  // the next force evaluation blocks until this is false
  std::atomic<bool> inside{false};     // a force evaluation is blocked now
  std::atomic<std::int64_t> stalls{0};
};

class StallField final : public mechanics::ForceField {
 public:
  explicit StallField(std::shared_ptr<StallControl> control) : control_(std::move(control)) { set_name("stall"); }
  [[nodiscard]] std::string_view type_name() const override { return "TestStallField"; }
  void collect_couplings(std::vector<std::pair<std::int32_t, std::int32_t>>&) const override {}
  void bind(const mechanics::BlockSparseMatrix&) override {}
  void add_force(const Eigen::VectorXd&, const Eigen::VectorXd&, mechanics::ForceFieldState&,
                 Eigen::VectorXd&) const override {
    if (!control_->requested.load()) return;
    // A solver that stopped making progress (a page fault storm, a lock elsewhere, a debugger):
    // the step does not return until the test lets it.
    control_->stalls.fetch_add(1);
    control_->inside.store(true);
    while (control_->requested.load()) std::this_thread::sleep_for(std::chrono::milliseconds(1));
    control_->inside.store(false);
  }
  void add_stiffness(const mechanics::ForceFieldState&, double, mechanics::BlockSparseMatrix&) const override {}
  [[nodiscard]] bool has_stiffness() const override { return false; }
  [[nodiscard]] double potential_energy(const Eigen::VectorXd&, const mechanics::ForceFieldState&) const override {
    return 0.0;
  }

 private:
  std::shared_ptr<StallControl> control_;
};

// ---- Bounds, from the safety configuration and the device's specification.

SessionConfig session_config() {
  SessionConfig config;
  config.haptics.realtime_priority = false;
  return config;  // the default safety: fade in 0.5 s, out 0.05 s, snapshots stale after 0.25 s
}

// Ticks the slew limit needs to take a force at the device's limit to zero.
std::int64_t slew_ticks(const haptics::DeviceSpec& spec) {
  return static_cast<std::int64_t>(std::ceil(spec.max_force_n / (spec.max_force_rate_n_per_s * kTick)));
}
// A fault the safety filter sees at once (no reading, garbage, a failed simulation): the gain
// falls to zero over fade_out_s, and the slew limit takes what is left to zero.
std::int64_t fade_out_ticks(const haptics::SafetyConfig& safety, const haptics::DeviceSpec& spec) {
  return static_cast<std::int64_t>(std::ceil(safety.fade_out_s / kTick)) + slew_ticks(spec) + 1;
}
// Geometry that stops arriving: stale once older than max_snapshot_age_s, then the fade.
std::int64_t stale_fade_ticks(const haptics::SafetyConfig& safety, const haptics::DeviceSpec& spec) {
  return static_cast<std::int64_t>(std::ceil(safety.max_snapshot_age_s / kTick)) + fade_out_ticks(safety, spec) + 1;
}

// Every force sent: finite and within the device's limit (the safety filter's promise).
void expect_every_force_safe(const std::vector<HapticSample>& samples, double limit) {
  for (const HapticSample& s : samples) {
    ASSERT_TRUE(s.force.allFinite()) << "tick " << s.tick;
    ASSERT_LE(s.force.norm(), limit) << "tick " << s.tick;
  }
}
enum class Slew : std::uint8_t { kChecked, kNotChecked };
// What the device itself received: finite, within the limit, and (in virtual time, where every
// tick is one period) never a step above the slew limit between two ticks: no spike. In real
// time a late tick may step further (the limit is a rate), and stopping sends zero at once.
void expect_device_forces_safe(const FaultyDevice& device, Slew slew) {
  const haptics::DeviceSpec& spec = device.spec();
  for (std::size_t i = 0; i < device.forces.size(); ++i) {
    ASSERT_TRUE(device.forces[i].allFinite()) << "write " << i;
    ASSERT_LE(device.forces[i].norm(), spec.max_force_n) << "write " << i;
    if (slew == Slew::kChecked && i > 0) {
      ASSERT_LE((device.forces[i] - device.forces[i - 1]).norm(), spec.max_force_rate_n_per_s * kTick + 1e-9)
          << "write " << i;
    }
  }
}

// ---- 1. An exploding simulation.

TEST(FaultInjection, AnExplodingSimulationIsReportedAndItsForceFadesOutThenANewModelRecovers) {
  // Pressed by a stable liver first; at 1.5 s (1 cm deep, ~1 N) its model is switched to one
  // that blows up under the press.
  auto device = std::make_unique<FaultyDevice>(press, nullptr);
  FaultyDevice& probe = *device;
  const SessionConfig config = session_config();
  auto made = Session::make(liver_body(stable_liver()), std::move(device), config);
  ASSERT_TRUE(made) << made.error().to_string();
  Session& session = **made;
  std::vector<HapticSample> samples;
  const auto keep = [&](const HapticSample& s) { samples.push_back(s); };
  const SessionReport pressed = session.run_virtual(1.5, keep);
  ASSERT_FALSE(pressed.diverged) << pressed.divergence;
  ASSERT_GT(samples.back().force.norm(), 0.3) << "the stylus must be pressing when the model explodes";

  ASSERT_TRUE(session.submit(command::SetModel{BodyId{0}, exploding_liver(), nullptr}));
  const std::size_t before = samples.size();
  const SessionReport exploded = session.run_virtual(2.0, keep);
  ASSERT_TRUE(exploded.diverged);
  EXPECT_NE(exploded.divergence.find("body 'Liver'"), std::string::npos) << exploded.divergence;
  EXPECT_NE(exploded.divergence.find("EulerExplicitSolver"), std::string::npos) << exploded.divergence;
  EXPECT_LT(exploded.haptic_ticks, 2000) << "a diverged run stops";
  // The run stops at the step that failed, after ticking on until the force was zero: the
  // ticks after the last good step are that fade, within its bound.
  const auto ticks_to_failure = static_cast<std::size_t>((exploded.simulation_steps + 1) * 10);
  const std::size_t after = samples.size() - before;
  ASSERT_GE(after, ticks_to_failure);
  const std::size_t fade = after - ticks_to_failure;
  EXPECT_GE(fade, 1u);
  EXPECT_LE(static_cast<std::int64_t>(fade), fade_out_ticks(config.haptics.safety, probe.spec()));
  EXPECT_GT(samples[before + ticks_to_failure - 1].force.norm(), 0.0)
      << "nothing to fade: the test would prove nothing";
  EXPECT_TRUE(samples.back().force.isZero(0.0));
  EXPECT_TRUE(probe.last_force.isZero(0.0)) << "the run left the device pushing";
  EXPECT_GT(exploded.safety.watchdog, 0u);
  expect_every_force_safe(samples, probe.spec().max_force_n);
  // The state kept is the last good one.
  EXPECT_TRUE(session.state().x.allFinite());

  // Stays stopped: another run fails at its first step, and still leaves the device at rest.
  const SessionReport again = session.run_virtual(0.5, keep);
  EXPECT_TRUE(again.diverged);
  EXPECT_TRUE(probe.last_force.isZero(0.0));

  // Recovery: a stable model again, from rest; the force comes back while the stylus presses.
  ASSERT_TRUE(session.submit(command::SetModel{BodyId{0}, stable_liver(), nullptr}));
  ASSERT_TRUE(session.submit(command::Reset{}));
  const std::size_t recovered_from = samples.size();
  const SessionReport recovered = session.run_virtual(1.5, keep);
  EXPECT_FALSE(recovered.diverged) << recovered.divergence;
  EXPECT_GT(samples.back().force.norm(), 0.3) << "the force did not come back";
  EXPECT_EQ(recovered.fall_through_events, 0);
  for (std::size_t i = recovered_from; i < samples.size(); ++i)
    ASSERT_LE(samples[i].force.norm(), probe.spec().max_force_n);
  expect_every_force_safe(samples, probe.spec().max_force_n);
  expect_device_forces_safe(probe, Slew::kChecked);
}

TEST(FaultInjection, AnExplodingSimulationInRealTimeEndsTheSimulationThreadAndTheForceFadesOut) {
  auto device = std::make_unique<FaultyDevice>(press, nullptr);
  FaultyDevice& probe = *device;
  const SessionConfig config = session_config();
  auto made = Session::make(liver_body(stable_liver()), std::move(device), config);
  ASSERT_TRUE(made) << made.error().to_string();
  Session& session = **made;
  std::vector<HapticSample> samples;
  const auto keep = [&](const HapticSample& s) { samples.push_back(s); };
  session.start_realtime();
  // Pressing (the force faded in), then the model that blows up under the press — switched in
  // while running (the exploding model alone would blow up from rounding before the stylus
  // arrives, and there would be no force to fade).
  const auto deadline = Clock::now() + kDeadline;
  const auto pushing_now = [&] {
    if (samples.size() < 50) return false;
    for (std::size_t i = samples.size() - 50; i < samples.size(); ++i) {
      if (samples[i].force.norm() <= 0.3) return false;
    }
    return true;
  };
  while (!pushing_now() && Clock::now() < deadline) {
    session.poll(keep);
    std::this_thread::sleep_for(std::chrono::milliseconds(5));
  }
  ASSERT_TRUE(pushing_now()) << "never pressed";
  ASSERT_TRUE(session.submit(command::SetModel{BodyId{0}, exploding_liver(), nullptr}));
  while (!session.simulation_ended() && Clock::now() < deadline) {
    session.poll(keep);
    std::this_thread::sleep_for(std::chrono::milliseconds(5));
  }
  ASSERT_TRUE(session.simulation_ended()) << "the simulation neither diverged nor ended";
  EXPECT_TRUE(session.realtime_running()) << "the haptic loop goes on until the supervisor stops";
  EXPECT_TRUE(session.haptic_loop().simulation_failed());
  // The haptic loop keeps running without the simulation and fades the force out: from the
  // moment the end was seen, at most the fade's ticks push (fewer under load: ticks are never
  // closer than a period on average, and the fade is counted in the loop's own time).
  session.poll(keep);
  const std::size_t seen_at = samples.size();
  while ((samples.size() < seen_at + 200 || !samples.back().force.isZero(0.0)) && Clock::now() < deadline) {
    session.poll(keep);
    std::this_thread::sleep_for(std::chrono::milliseconds(5));
  }
  ASSERT_TRUE(samples.back().force.isZero(0.0)) << "the force never faded out";
  std::int64_t pushing = 0;
  for (std::size_t i = seen_at; i < samples.size(); ++i) pushing += samples[i].force.isZero(0.0) ? 0 : 1;
  // (+10: a tick that follows a late one closely; the watchdog alone would push ~250 more.)
  EXPECT_LE(pushing, fade_out_ticks(config.haptics.safety, probe.spec()) + 10);
  for (std::size_t i = seen_at; i < samples.size(); ++i) {
    if (samples[i].force.isZero(0.0)) {
      for (std::size_t j = i; j < samples.size(); ++j)
        ASSERT_TRUE(samples[j].force.isZero(0.0)) << "came back at tick " << j;
      break;
    }
  }
  const SessionReport report = session.stop_realtime(keep);
  EXPECT_FALSE(session.realtime_running());
  EXPECT_TRUE(report.diverged);
  EXPECT_NE(report.divergence.find("body 'Liver'"), std::string::npos) << report.divergence;
  EXPECT_GT(report.safety.watchdog, 0u);
  EXPECT_TRUE(probe.last_force.isZero(0.0));
  EXPECT_EQ(samples.size(), static_cast<std::size_t>(session.haptic_loop().ticks())) << "a sample was lost";
  expect_every_force_safe(samples, probe.spec().max_force_n);
  expect_device_forces_safe(probe, Slew::kNotChecked);
}

// ---- 2. A simulation thread that stalls.

// Polls until `done` holds (deadline: a hang), giving every sample to `keep`.
template <class Done>
bool poll_until(Session& session, const std::function<void(const HapticSample&)>& keep, Done done) {
  const auto deadline = Clock::now() + kDeadline;
  while (!done()) {
    if (Clock::now() > deadline) return false;
    session.poll(keep);
    std::this_thread::sleep_for(std::chrono::milliseconds(2));
  }
  session.poll(keep);
  return true;
}

// The last `n` samples all satisfy `p`.
template <class P>
bool last_n(const std::vector<HapticSample>& samples, std::size_t n, P p) {
  if (samples.size() < n) return false;
  for (std::size_t i = samples.size() - n; i < samples.size(); ++i) {
    if (!p(samples[i])) return false;
  }
  return true;
}

TEST(FaultInjection, AStalledSimulationThreadFadesTheForceOutAndItComesBackWhenTheStallEnds) {
  auto stall = std::make_shared<StallControl>();
  auto device = std::make_unique<FaultyDevice>(press, nullptr);
  FaultyDevice& probe = *device;
  const SessionConfig config = session_config();
  auto made = Session::make(liver_body(stable_liver(), std::make_unique<StallField>(stall)), std::move(device), config);
  ASSERT_TRUE(made) << made.error().to_string();
  Session& session = **made;
  std::vector<HapticSample> samples;
  const std::function<void(const HapticSample&)> keep = [&](const HapticSample& s) { samples.push_back(s); };
  const auto pushing = [](const HapticSample& s) { return s.force.norm() > 0.3; };
  session.start_realtime();

  // Pressing, the force faded in.
  ASSERT_TRUE(poll_until(session, keep, [&] { return last_n(samples, 50, pushing); })) << "never pressed";
  // The stall: the next step blocks in its force evaluation.
  stall->requested.store(true);
  ASSERT_TRUE(poll_until(session, keep, [&] { return stall->inside.load(); })) << "the stall never began";
  const std::uint64_t steps_at_stall = session.steps_taken();
  // The ticks from the ones polled after the stall began on have the last snapshot published
  // (a tick polled just then may have started before that publish).
  const std::size_t seen = samples.size();
  ASSERT_TRUE(poll_until(session, keep, [&] { return samples.size() > seen + 5; }));
  const std::size_t stalled_from = seen;
  const std::uint64_t frozen = samples.back().snapshot_sequence;
  // The haptic loop runs on without the simulation, and its watchdog takes the force to zero.
  const auto zero = [](const HapticSample& s) { return s.force.isZero(0.0); };
  ASSERT_TRUE(poll_until(session, keep, [&] {
    return last_n(samples, 100, zero) && samples.size() > stalled_from + 100;
  })) << "the force never faded out during the stall";
  EXPECT_EQ(session.steps_taken(), steps_at_stall) << "the stall did not hold the simulation";
  EXPECT_TRUE(stall->inside.load());
  // Counted from the last snapshot that arrived: at most the watchdog's bound pushes (twice
  // over, for the step that was still running when the stall began).
  std::int64_t pushing_on_frozen = 0, on_frozen = 0;
  for (std::size_t i = stalled_from; i < samples.size(); ++i) {
    EXPECT_EQ(samples[i].snapshot_sequence, frozen) << "a snapshot arrived from a stalled simulation";
    ++on_frozen;
    pushing_on_frozen += zero(samples[i]) ? 0 : 1;
  }
  EXPECT_LE(pushing_on_frozen, 2 * stale_fade_ticks(config.haptics.safety, probe.spec()));
  EXPECT_GT(on_frozen, 100);

  // The stall ends: steps again, and the force fades back in.
  stall->requested.store(false);
  ASSERT_TRUE(poll_until(session, keep, [&] {
    return session.steps_taken() > steps_at_stall + 10 && last_n(samples, 50, pushing);
  })) << "the force did not come back after the stall";
  const SessionReport report = session.stop_realtime(keep);
  EXPECT_FALSE(session.realtime_running());
  EXPECT_FALSE(report.diverged) << report.divergence;
  EXPECT_GT(report.safety.watchdog, 0u);
  EXPECT_EQ(stall->stalls.load(), 1);
  EXPECT_TRUE(probe.last_force.isZero(0.0));
  EXPECT_EQ(samples.size(), static_cast<std::size_t>(session.haptic_loop().ticks())) << "a sample was lost";
  expect_every_force_safe(samples, probe.spec().max_force_n);
  expect_device_forces_safe(probe, Slew::kNotChecked);
}

// ---- 3. A device that stops answering, or sends garbage.

struct DeviceRun {
  std::vector<HapticSample> samples;
  SessionReport report;
  FaultyDevice* device{nullptr};
  std::unique_ptr<Session> session;
};

DeviceRun run_faulty_device(FaultyDevice::Schedule schedule, double seconds) {
  auto device = std::make_unique<FaultyDevice>(press, std::move(schedule));
  DeviceRun run;
  run.device = device.get();
  auto made = Session::make(liver_body(stable_liver()), std::move(device), session_config());
  EXPECT_TRUE(made) << made.error().to_string();
  run.session = std::move(*made);
  run.report = run.session->run_virtual(seconds, [&](const HapticSample& s) { run.samples.push_back(s); });
  return run;
}

TEST(FaultInjection, ADeviceThatStopsAnsweringGetsNoForceAndTheForceComesBackWhenItAnswersAgain) {
  // Silent (timed out) from 1.5 s to 2 s: ticks 1500 to 1999.
  const auto silent = [](double t) { return t >= 1.5 - 1e-9 && t < 2.0 - 1e-9 ? Fault::kSilent : Fault::kNone; };
  DeviceRun run = run_faulty_device(silent, 3.5);
  const std::vector<HapticSample>& s = run.samples;
  ASSERT_EQ(s.size(), 3500u);
  const haptics::SafetyConfig safety = session_config().haptics.safety;
  ASSERT_GT(s[1499].force.norm(), 0.3) << "the stylus must be pressing when the device goes silent";
  EXPECT_EQ(run.device->silent_reads, 500);
  for (std::size_t i = 1500; i < 2000; ++i) {
    EXPECT_FALSE(s[i].valid);
    // No reading: zero at once, as fast as the slew limit lets the force fall.
    if (static_cast<std::int64_t>(i) >= 1500 + slew_ticks(run.device->spec())) {
      ASSERT_TRUE(s[i].force.isZero(0.0)) << "tick " << i;
    }
  }
  EXPECT_EQ(run.report.safety.no_reading, 500u) << "each silent tick is counted";
  EXPECT_EQ(run.report.safety.non_finite, 0u);
  // Back: faded in again over fade_in_s, and pressing as before.
  EXPECT_TRUE(s[2000].valid);
  const std::size_t back = 2000 + static_cast<std::size_t>(std::ceil(safety.fade_in_s / kTick)) + 100;
  for (std::size_t i = back; i < s.size(); ++i) ASSERT_GT(s[i].force.norm(), 0.3) << "tick " << i;
  EXPECT_NEAR(s.back().force.norm(), s[1499].force.norm(), 0.3 * s[1499].force.norm());
  EXPECT_FALSE(run.report.diverged) << run.report.divergence;
  EXPECT_EQ(run.report.fall_through_events, 0);
  expect_every_force_safe(s, run.device->spec().max_force_n);
  expect_device_forces_safe(*run.device, Slew::kChecked);
}

TEST(FaultInjection, ADeviceSendingGarbageGetsZeroOrFiniteForcesAndNoSpike) {
  const auto garbage = [](double t) {
    const auto tick = static_cast<std::int64_t>(std::llround(t / kTick));
    if (tick >= 1500 && tick < 1510) return Fault::kNanPosition;
    if (tick >= 1600 && tick < 1610) return Fault::kInfPosition;
    if (tick >= 1700 && tick < 1705) return Fault::kNanVelocity;
    if (tick >= 1800 && tick < 1805) return Fault::kZeroQuaternion;
    if (tick >= 1850 && tick < 1855) return Fault::kNanQuaternion;
    if (tick >= 1900 && tick < 1950) return Fault::kScaledQuaternion;
    if (tick == 2500 || tick == 2600) return Fault::kJumpDown;
    if (tick == 2700 || tick == 2800) return Fault::kJumpAside;
    return Fault::kNone;
  };
  DeviceRun run = run_faulty_device(garbage, 3.5);
  const std::vector<HapticSample>& s = run.samples;
  ASSERT_EQ(s.size(), 3500u);
  const double limit = run.device->spec().max_force_n;
  expect_every_force_safe(s, limit);
  expect_device_forces_safe(*run.device, Slew::kChecked);
  // Every tick with a non-finite value, a zero quaternion or a jump is counted, and only those.
  EXPECT_EQ(run.report.safety.non_finite, 10u + 10u + 5u + 5u + 5u + 4u);
  EXPECT_EQ(run.report.safety.no_reading, 0u);
  for (std::size_t start : {1500u, 1600u, 1700u, 1800u, 1850u}) {
    ASSERT_GT(s[start - 1].force.norm(), 0.3) << "the stylus must be pressing when garbage arrives at tick " << start;
    EXPECT_FALSE(s[start].valid);
    const std::size_t zero_from = start + static_cast<std::size_t>(slew_ticks(run.device->spec()));
    EXPECT_TRUE(s[zero_from].force.isZero(0.0)) << "tick " << zero_from;
  }
  // A scaled quaternion is a rotation: the reading is used.
  for (std::size_t i = 1900; i < 1950; ++i) EXPECT_TRUE(s[i].valid) << "tick " << i;
  // A jump of metres in one tick (SafetyConfig::max_reading_jump_m) is garbage too: that tick
  // is not rendered, so the proxy does not teleport (dragged along the surfaces and back) and
  // the force only dips (the slew limit) instead of jumping toward the device's limit — a
  // spike would be a slew step (2 N) up; the tissue's own rebound after the dip is a few %.
  for (std::size_t jump : {2500u, 2600u, 2700u, 2800u}) {
    const HapticSample& before = s[jump - 1];
    ASSERT_GT(before.force.norm(), 0.3) << "tick " << jump;
    EXPECT_FALSE(s[jump].valid) << "tick " << jump;
    EXPECT_TRUE(s[jump + 1].valid) << "the stylus back where it was is a reading again, tick " << jump + 1;
    for (std::size_t i = jump; i <= jump + 20; ++i) {
      ASSERT_LT((s[i].proxy - before.proxy).norm(), 1e-3) << "the proxy moved with the jump, tick " << i;
      ASSERT_LE(s[i].force.norm(), before.force.norm() + 0.5) << "spike at tick " << i;
    }
    EXPECT_NEAR(s[jump + 20].force.norm(), before.force.norm(), 0.5) << "tick " << jump;
  }
  EXPECT_FALSE(run.report.diverged) << run.report.divergence;
  EXPECT_EQ(run.report.fall_through_events, 0);
  // The garbage never reached the tissue: it moved as a 1 cm press moves it.
  EXPECT_LT(run.report.max_displacement_m, 0.03);
  EXPECT_TRUE(run.session->state().x.allFinite());
}

// ---- 4. A snapshot that never arrives.

TEST(FaultInjection, AHapticLoopThatNeverGetsASnapshotSendsNoForceAndStartsWhenOneArrives) {
  // The loop alone, over a surface buffer nobody has published to yet, the stylus pressing
  // where the liver will be.
  const mesh::BoundarySurface b = mesh::extract_boundary(simple_liver().nodes, simple_liver().tets);
  const haptics::SurfaceSnapshot liver = haptics::make_snapshot(b.surface);
  TripleBuffer<haptics::SurfaceSnapshot> surfaces(liver);  // slots sized, nothing published
  FaultyDevice device(press, nullptr);
  haptics::HapticLoopConfig config = session_config().haptics;
  haptics::HapticLoop loop(device, surfaces, config);
  for (int i = 0; i < 1500; ++i) {
    loop.tick(i * kTick);
    ASSERT_TRUE(device.last_force.isZero(0.0)) << "tick " << i;
  }
  EXPECT_EQ(loop.safety_counters().watchdog, 1500u);
  ASSERT_TRUE(loop.samples().acquire());
  EXPECT_FALSE(loop.samples().read().contact) << "no surface yet: nothing to touch";
  // The first snapshot arrives (and keeps arriving): the proxy, left where the stylus started
  // (no surface to move against), meets the surface on its way to the stylus 1 cm inside, and
  // the force fades in.
  for (int i = 1500; i < 3000; ++i) {
    haptics::SurfaceSnapshot& slot = surfaces.write_slot();
    slot.time_s = i * kTick;
    surfaces.publish();
    loop.tick(i * kTick);
    ASSERT_TRUE(device.last_force.allFinite());
    ASSERT_LE(device.last_force.norm(), device.spec().max_force_n);
  }
  EXPECT_EQ(loop.safety_counters().watchdog, 1500u) << "fresh geometry is not stale";
  EXPECT_GT(device.last_force.norm(), 0.3) << "the force did not come once the geometry arrived";
  expect_device_forces_safe(device, Slew::kChecked);
}

TEST(FaultInjection, ASessionWhoseFirstStepNeverCompletesSendsNoForceAndStartsWhenItDoes) {
  auto stall = std::make_shared<StallControl>();
  stall->requested.store(true);  // the very first step blocks
  auto device = std::make_unique<FaultyDevice>(press, nullptr);
  FaultyDevice& probe = *device;
  const SessionConfig config = session_config();
  auto made = Session::make(liver_body(stable_liver(), std::make_unique<StallField>(stall)), std::move(device), config);
  ASSERT_TRUE(made) << made.error().to_string();
  Session& session = **made;
  std::vector<HapticSample> samples;
  const std::function<void(const HapticSample&)> keep = [&](const HapticSample& s) { samples.push_back(s); };
  session.start_realtime();
  // The stylus reaches the liver (at ~0.8 s of the loop's clock) and presses it, against the
  // rest shape published when the session was made — by then far older than the watchdog
  // allows: the renderer asks for a force, and none is sent.
  std::size_t counted = 0;
  std::int64_t asked = 0;
  ASSERT_TRUE(poll_until(session, keep, [&] {
    for (; counted < samples.size(); ++counted)
      asked += samples[counted].contact && samples[counted].requested_force.norm() > 0.3 ? 1 : 0;
    return asked >= 200;
  })) << "the stylus never pressed the liver";
  EXPECT_EQ(session.steps_taken(), 0u);
  EXPECT_TRUE(stall->inside.load());
  for (const HapticSample& s : samples)
    ASSERT_TRUE(s.force.isZero(0.0)) << "tick " << s.tick << " pushed on a never-stepped body";

  // The step completes: the simulation runs, and the force fades in.
  stall->requested.store(false);
  const auto pushing = [](const HapticSample& s) { return s.force.norm() > 0.3; };
  ASSERT_TRUE(poll_until(session, keep, [&] { return session.steps_taken() > 10 && last_n(samples, 50, pushing); }))
      << "the force did not come once the simulation stepped";
  const SessionReport report = session.stop_realtime(keep);
  EXPECT_FALSE(session.realtime_running());
  EXPECT_FALSE(report.diverged);
  EXPECT_GT(report.safety.watchdog, 200u);
  EXPECT_EQ(samples.size(), static_cast<std::size_t>(session.haptic_loop().ticks()));
  expect_every_force_safe(samples, probe.spec().max_force_n);
  expect_device_forces_safe(probe, Slew::kNotChecked);
}

// ---- 5. The window thread blocked.

// A surface snapshot as published whole: every vertex finite, the normals those of these
// positions (a slot half overwritten by the next step would not match its own normals).
::testing::AssertionResult whole(const haptics::SurfaceSnapshot& s, std::size_t vertex_count) {
  if (s.vertices.size() != vertex_count || s.vertex_normals.size() != vertex_count)
    return ::testing::AssertionFailure() << "sizes";
  std::vector<Vec3> normals(vertex_count, Vec3::Zero());
  for (const mesh::Tri& t : s.triangles) {
    const Vec3 n = (s.vertices[t[1]] - s.vertices[t[0]]).cross(s.vertices[t[2]] - s.vertices[t[0]]);
    for (int k = 0; k < 3; ++k) normals[t[k]] += n;
  }
  for (std::size_t i = 0; i < vertex_count; ++i) {
    if (!s.vertices[i].allFinite()) return ::testing::AssertionFailure() << "vertex " << i << " not finite";
    const Vec3 n = normals[i].normalized();
    if ((n - s.vertex_normals[i]).norm() > 1e-6)
      return ::testing::AssertionFailure() << "vertex " << i << ": normal of other positions";
  }
  return ::testing::AssertionSuccess();
}

TEST(FaultInjection, AWindowThatStopsReadingBlocksNeitherTheSimulationNorTheHapticLoopAndAReaderSeesNoTornSnapshot) {
  auto device = std::make_unique<FaultyDevice>(press, nullptr);
  auto made = Session::make(liver_body(stable_liver()), std::move(device), session_config());
  ASSERT_TRUE(made) << made.error().to_string();
  Session& session = **made;
  // The window asks for both, then blocks (never reads, never polls).
  TripleBuffer<haptics::SurfaceSnapshot>& surfaces = session.graphics_surfaces();
  TripleBuffer<std::vector<std::vector<double>>>& states = session.graphics_states();
  const std::size_t vertex_count = session.body().surface.vertices.size();
  const auto dofs = static_cast<std::size_t>(3 * session.model().node_count());
  session.start_realtime();
  const auto deadline = Clock::now() + kDeadline;
  while ((session.steps_taken() < 100 || session.haptic_loop().ticks() < 1000) && Clock::now() < deadline) {
    std::this_thread::sleep_for(std::chrono::milliseconds(10));
  }
  ASSERT_GE(session.steps_taken(), 100u) << "the simulation waited for a window that does not read";
  ASSERT_GE(session.haptic_loop().ticks(), 1000u) << "the haptic loop waited for a window that does not read";

  // The window unblocks and reads as fast as it can, on its own thread.
  std::atomic<bool> stop{false};
  std::atomic<std::int64_t> surfaces_read{0}, states_read{0}, torn{0};
  std::thread window([&] {
    double last_time = -1.0;
    std::uint64_t last_sequence = 0;
    while (!stop.load()) {
      if (surfaces.acquire()) {
        const haptics::SurfaceSnapshot& s = surfaces.read();
        if (!whole(s, vertex_count) || s.time_s < last_time || s.sequence <= last_sequence) torn.fetch_add(1);
        last_time = s.time_s;
        last_sequence = s.sequence;
        surfaces_read.fetch_add(1);
      }
      if (states.acquire()) {
        const auto& x = states.read();
        bool ok = x.size() == 1 && x[0].size() == dofs;
        for (std::size_t i = 0; ok && i < x[0].size(); ++i) ok = std::isfinite(x[0][i]);
        if (!ok) torn.fetch_add(1);
        states_read.fetch_add(1);
      }
    }
  });
  const std::uint64_t steps_before = session.steps_taken();
  while ((surfaces_read.load() < 100 || states_read.load() < 100 || session.steps_taken() < steps_before + 100) &&
         Clock::now() < deadline + kDeadline) {
    session.poll({});
    std::this_thread::sleep_for(std::chrono::milliseconds(10));
  }
  stop.store(true);
  window.join();
  const SessionReport report = session.stop_realtime();
  EXPECT_FALSE(session.realtime_running());
  EXPECT_GE(surfaces_read.load(), 100);
  EXPECT_GE(states_read.load(), 100);
  EXPECT_EQ(torn.load(), 0) << "a reader saw a snapshot that was not one step's";
  EXPECT_FALSE(report.diverged);
}

}  // namespace
}  // namespace hof::coupling
