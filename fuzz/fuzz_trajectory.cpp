// libFuzzer target: replay trajectories (hof::haptics::load_replay, the `replay:FILE.csv`
// device), then the device played at a few times (interpolation over whatever times and
// positions were accepted).
#include <cmath>
#include <cstddef>
#include <cstdint>
#include <cstdlib>

#include "fuzz_common.h"
#include "hof/haptics/device_backends/replay_device.h"

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  const auto path = hof::fuzz::write_input(data, size, "trajectory.csv");
  auto samples = hof::haptics::load_replay(path);
  if (!samples) {
    hof::fuzz::check_error(samples.error(), path);
    return 0;
  }
  for (const bool loop : {false, true}) {
    hof::haptics::ReplayDevice device(*samples, loop);
    const double first = samples->front().t_s, last = samples->back().t_s;
    for (const double t : {first - 1.0, first, 0.5 * (first + last), last, last + 1.0, 3.0 * last + 7.0}) {
      const hof::haptics::DeviceReading r = device.read(t);
      // What the loader accepted plays back as finite numbers.
      if (r.valid && !r.position_m.allFinite()) std::abort();
    }
  }
  return 0;
}
