// Prototyping a procedure on HoF: a tool of one's own on the stylus, in a world HoF builds.
//
// The tool is a vibrating palpation probe (a vibrotactile cue: while it touches tissue it adds
// a small sinusoidal force along the surface normal, as an ultrasonic or vibration probe would
// make the hand feel). It plugs into the haptic loop's tool seam (hof/haptics/tool.h): called
// every tick on the haptic thread after the surfaces are rendered, it adds its force and says
// what it did. The world is any file `hof run` takes; the session runs in virtual time
// (deterministic), with the world's own device (a bare scene's default probe presses it).
//
// Usage: vibrating_probe [WORLD.hof|.scn|.x3d] [--seconds S]

#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <memory>
#include <numbers>
#include <string>

#include <hof/core/version.h>
#include <hof/coupling/session.h>
#include <hof/haptics/device.h>
#include <hof/haptics/tool.h>
#include <hof/scene/device_config.h>
#include <hof/scene/world.h>

namespace {

class VibratingProbe final : public hof::haptics::Tool {
 public:
  VibratingProbe(double amplitude_n, double frequency_hz) : amplitude_n_(amplitude_n), frequency_hz_(frequency_hz) {}

  hof::Vec3 tick(const hof::haptics::ToolTickInput& input, std::span<hof::Vec3> /*layer_forces*/,
                 hof::haptics::ToolState& state) override {
    state = {};
    state.active = true;
    for (const hof::haptics::ContactState& contact : input.contacts) {
      if (!contact.in_contact) continue;
      state.touched = true;
      // F = A sin(2π f t) n: felt on top of the surface's own force (the safety filter then
      // holds the sum within the device's limit).
      const double phase = 2.0 * std::numbers::pi * frequency_hz_ * input.time_s;
      state.force = amplitude_n_ * std::sin(phase) * contact.normal;
      return state.force;
    }
    return hof::Vec3::Zero();
  }
  void restart() override {}

 private:
  double amplitude_n_;
  double frequency_hz_;
};

}  // namespace

int main(int argc, char** argv) {
  std::string file = std::string(HOF_EXAMPLES_DIR) + "/liver-palpation-simple.hof";
  double seconds = 2.0;
  for (int i = 1; i < argc; ++i) {
    const std::string arg = argv[i];
    if (arg == "--seconds" && i + 1 < argc)
      seconds = std::atof(argv[++i]);
    else
      file = arg;
  }
  auto world = hof::scene::build_world(file);
  if (!world) {
    std::fprintf(stderr, "vibrating_probe: %s\n", world.error().to_string().c_str());
    return 1;
  }
  auto device = hof::scene::open_device(world->device);  // the spec parsed into a typed DeviceConfig, then opened
  if (!device) {
    std::fprintf(stderr, "vibrating_probe: %s\n", device.error().to_string().c_str());
    return 1;
  }
  hof::coupling::SessionConfig config = world->config;
  config.tool = std::make_shared<VibratingProbe>(0.2, 250.0);  // 0.2 N at 250 Hz (the skin's most sensitive band)
  const std::string name = world->name;
  auto session = hof::coupling::Session::make(std::move(world->bodies), std::move(*device), config);
  if (!session) {
    std::fprintf(stderr, "vibrating_probe: %s\n", session.error().to_string().c_str());
    return 1;
  }
  double vibration_peak = 0.0;
  long touching = 0;
  const hof::coupling::SessionReport report =
      (*session)->run_virtual(seconds, [&](const hof::haptics::HapticSample& s) {
        if (!s.tool.touched) return;
        ++touching;
        vibration_peak = std::max(vibration_peak, s.tool.force.norm());
      });
  std::printf("HoF %s: '%s', %.2f s in virtual time: %lld haptic ticks, %lld simulation steps\n", hof::kVersion,
              name.c_str(), report.simulated_s, static_cast<long long>(report.haptic_ticks),
              static_cast<long long>(report.simulation_steps));
  std::printf("contact %.3f s, max force %.3f N; the probe vibrated on %ld ticks, peak %.3f N\n", report.contact_time_s,
              report.max_force_n, touching, vibration_peak);
  return touching > 0 && vibration_peak > 0.1 ? 0 : 2;
}
