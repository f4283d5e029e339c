// libFuzzer target: the UDP device's datagrams (hof::haptics::udp, docs/device-protocol.md):
// every packet kind decoded from any bytes; what a decoder accepts must be finite, and a
// hello applied to a spec must leave a usable spec.
#include <cmath>
#include <cstddef>
#include <cstdint>
#include <cstdlib>
#include <span>

#include "hof/haptics/device_backends/udp_device.h"

namespace udp = hof::haptics::udp;

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  const std::span<const std::uint8_t> bytes(data, size);
  (void)udp::packet_type(bytes);
  if (udp::StatePacket s; udp::decode(bytes, s)) {
    if (!std::isfinite(s.device_time_s) || !s.position_m.allFinite() || !s.velocity_m_per_s.allFinite() ||
        !s.orientation.coeffs().allFinite()) {
      std::abort();
    }
  }
  if (udp::HelloPacket h; udp::decode(bytes, h)) {
    const hof::haptics::DeviceSpec spec = udp::apply_hello(hof::haptics::DeviceSpec{}, h);
    if (!(spec.max_force_n > 0.0) || !std::isfinite(spec.max_force_n)) std::abort();
  }
  if (udp::ForcePacket f; udp::decode(bytes, f)) {
    if (!f.force_n.allFinite() || !f.torque_n_m.allFinite()) std::abort();
  }
  if (udp::ChallengePacket c; udp::decode(bytes, c)) (void)c.echo_sequence;
  return 0;
}
