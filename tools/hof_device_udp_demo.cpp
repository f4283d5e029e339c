// hof-device-udp-demo: a stand-in for a vendor-SDK bridge. It plays the device side of the
// UDP protocol of docs/device-protocol.md: sends a hello, then the state of a simulated
// stylus at --rate Hz to HoF's port, and prints the forces HoF sends back. The stylus is any
// simulated HoF device spec: a scripted motion ("circle,repeat", the default) or a compliant
// virtual hand ("virtual-hand:poke"), which also feels the forces received (closed loop).
//
//   hof-device-udp-demo --port 5000 --motion "poke,depth=0.01" --seconds 20
//
// Exit status: 0 after --seconds (or at the end of a finite motion, or on Ctrl-C), 1 on a
// setup error.

#include <arpa/inet.h>
#include <netdb.h>
#include <netinet/in.h>
#include <sys/socket.h>
#include <unistd.h>

#include <fmt/format.h>
#include <CLI/CLI.hpp>

#include <array>
#include <chrono>
#include <csignal>
#include <cstring>
#include <optional>
#include <string>
#include <thread>

#include "hof/haptics/device.h"
#include "hof/haptics/device_backends/udp_device.h"
#include "hof/scene/device_config.h"

namespace {

using Clock = std::chrono::steady_clock;
namespace udp = hof::haptics::udp;

volatile std::sig_atomic_t g_interrupted = 0;
extern "C" void on_interrupt(int) { g_interrupted = 1; }

struct Options {
  std::uint16_t port{5000};
  std::string host{"127.0.0.1"};
  std::uint16_t local_port{0};
  double seconds{10.0};
  std::string motion{"circle,repeat"};
  double rate_hz{1000.0};
  double print_hz{10.0};
  bool no_velocity{false};
  std::string key_file;  ///< set: the authenticated protocol (version 2)
};

/// A UDP socket bound to `local_port`, with the resolved address of HoF.
struct Link {
  int fd{-1};
  sockaddr_in hof{};
  ~Link() {
    if (fd >= 0) ::close(fd);
  }
};

std::optional<std::string> open_link(const Options& o, Link& link) {
  addrinfo hints{};
  hints.ai_family = AF_INET;
  hints.ai_socktype = SOCK_DGRAM;
  addrinfo* found = nullptr;
  if (const int rc = ::getaddrinfo(o.host.c_str(), nullptr, &hints, &found); rc != 0 || found == nullptr) {
    return fmt::format("cannot resolve host '{}': {}", o.host, ::gai_strerror(rc));
  }
  link.hof = *reinterpret_cast<const sockaddr_in*>(found->ai_addr);
  link.hof.sin_port = htons(o.port);
  ::freeaddrinfo(found);

  link.fd = ::socket(AF_INET, SOCK_DGRAM | SOCK_CLOEXEC, 0);
  if (link.fd < 0) return fmt::format("cannot create a socket: {}", std::strerror(errno));
  sockaddr_in local{};
  local.sin_family = AF_INET;
  local.sin_addr.s_addr = htonl(INADDR_ANY);
  local.sin_port = htons(o.local_port);
  if (::bind(link.fd, reinterpret_cast<const sockaddr*>(&local), sizeof(local)) != 0) {
    return fmt::format("cannot bind local port {}: {}", o.local_port, std::strerror(errno));
  }
  return std::nullopt;
}

/// With a key: the key and the session HoF issued in its latest challenge (0: none yet).
struct Auth {
  std::optional<udp::Key> key;
  std::uint64_t session{0};
};

template <class Packet>
void send(const Link& link, const Auth& auth, const Packet& packet) {
  std::array<std::uint8_t, udp::kMaxPacketSize> bytes{};
  std::size_t size = udp::encode(packet, bytes);
  if (auth.key) size = udp::seal(bytes, size, auth.session, *auth.key);
  ::sendto(link.fd, bytes.data(), size, MSG_DONTWAIT, reinterpret_cast<const sockaddr*>(&link.hof), sizeof(link.hof));
}

udp::HelloPacket hello_for(const hof::haptics::DeviceSpec& spec) {
  udp::HelloPacket h;
  h.max_force_n = spec.max_force_n;
  h.max_stiffness_n_per_m = spec.max_stiffness_n_per_m;
  h.max_damping_n_s_per_m = spec.max_damping_n_s_per_m;
  h.workspace_radius_m = spec.workspace_radius_m;
  h.nominal_rate_hz = spec.nominal_rate_hz;
  std::strncpy(h.model.data(), spec.model.c_str(), h.model.size() - 1);
  return h;
}

int run(const Options& o) {
  // The simulated stylus: "scripted:" is implied unless the motion names a backend.
  const std::string spec = o.motion.find(':') == std::string::npos ? "scripted:" + o.motion : o.motion;
  auto device = hof::scene::open_device(spec);
  if (!device) {
    fmt::print(stderr, "hof-device-udp-demo: {}\n", device.error().to_string());
    return 1;
  }
  Link link;
  if (auto error = open_link(o, link)) {
    fmt::print(stderr, "hof-device-udp-demo: {}\n", *error);
    return 1;
  }
  Auth auth;
  if (!o.key_file.empty()) {
    auto key = udp::read_key_file(o.key_file);
    if (!key) {
      fmt::print(stderr, "hof-device-udp-demo: {}\n", key.error().to_string());
      return 1;
    }
    auth.key = *key;
  }
  fmt::print("sending '{}' to {}:{} at {} Hz for {} s{}\n", spec, o.host, o.port, o.rate_hz, o.seconds,
             auth.key ? " (authenticated, protocol version 2)" : "");

  const auto period = std::chrono::duration_cast<Clock::duration>(std::chrono::duration<double>(1.0 / o.rate_hz));
  const auto print_every = std::chrono::duration<double>(1.0 / o.print_hz);
  const udp::HelloPacket hello = hello_for((*device)->spec());
  const auto start = Clock::now();
  auto next_tick = start;
  auto next_hello = start;
  auto next_print = start;
  std::uint32_t sequence = 0;
  std::uint64_t forces = 0;
  std::optional<udp::ForcePacket> last_force;
  Clock::time_point last_force_at = start;
  bool hof_closed = false;

  while (g_interrupted == 0) {
    const auto now = Clock::now();
    const double t = std::chrono::duration<double>(now - start).count();
    if (t > o.seconds) break;
    if (now >= next_hello) {  // HoF may start after us: greet it every second
      // With a key a hello asks for a new session: only when there is none, or HoF went quiet
      // (it may have restarted and forgotten ours).
      if (!auth.key || auth.session == 0 || now - last_force_at > std::chrono::seconds(1)) send(link, auth, hello);
      next_hello += std::chrono::seconds(1);
    }

    // Take every force that arrived; the last one is what the stylus feels now.
    std::array<std::uint8_t, 256> bytes{};
    ssize_t n = 0;
    while ((n = ::recv(link.fd, bytes.data(), bytes.size(), MSG_DONTWAIT)) > 0) {
      std::span<const std::uint8_t> packet(bytes.data(), static_cast<std::size_t>(n));
      std::array<std::uint8_t, udp::kMaxPacketSize> body{};
      if (auth.key) {  // only what HoF sealed with our key, in our session
        std::uint64_t session = 0;
        const std::size_t size = udp::unseal(packet, *auth.key, session, body);
        if (size == 0) continue;
        packet = std::span<const std::uint8_t>(body.data(), size);
        if (udp::ChallengePacket c; udp::decode(packet, c)) {
          auth.session = session;
          continue;
        }
        if (session != auth.session) continue;
      }
      udp::ForcePacket f;
      if (!udp::decode(packet, f)) continue;
      ++forces;
      last_force = f;
      last_force_at = Clock::now();
      hof_closed = hof_closed || f.closing;
    }
    if (last_force) (*device)->write_force(last_force->force_n, last_force->torque_n_m);

    const hof::haptics::DeviceReading r = (*device)->read(t);
    if (!r.valid) {
      fmt::print("the motion has ended\n");
      break;
    }
    udp::StatePacket s;
    s.sequence = ++sequence;
    s.device_time_s = t;
    s.position_m = r.position_m;
    s.orientation = r.orientation;
    s.has_velocity = !o.no_velocity;
    s.velocity_m_per_s = r.velocity_m_per_s;
    s.buttons = r.buttons;
    if (!auth.key || auth.session != 0) send(link, auth, s);  // authenticated: only once HoF answered

    if (now >= next_print) {
      const hof::Vec3 f = last_force ? last_force->force_n : hof::Vec3::Zero();
      fmt::print("t={:7.3f} s  p=({:+.4f}, {:+.4f}, {:+.4f}) m  F=({:+.3f}, {:+.3f}, {:+.3f}) N  lag={} packets{}\n", t,
                 r.position_m.x(), r.position_m.y(), r.position_m.z(), f.x(), f.y(), f.z(),
                 last_force ? static_cast<std::int64_t>(sequence) - last_force->echo_sequence : -1,
                 hof_closed ? "  (HoF closed)" : "");
      next_print += std::chrono::duration_cast<Clock::duration>(print_every);
    }

    // Fixed-rate pacing; after a long stall, start again from now instead of bursting.
    next_tick += period;
    if (Clock::now() - next_tick > std::chrono::milliseconds(100)) next_tick = Clock::now();
    std::this_thread::sleep_until(next_tick);
  }
  fmt::print("sent {} states, received {} forces{}\n", sequence, forces, forces == 0 ? " (is HoF listening?)" : "");
  return 0;
}

}  // namespace

int main(int argc, char** argv) {
  CLI::App app{"Speak HoF's UDP device protocol: send a simulated stylus, print the forces received"};
  Options o;
  app.add_option("--port", o.port, "HoF's UDP port")->capture_default_str();
  app.add_option("--host", o.host, "HoF's host (IPv4 name or address)")->capture_default_str();
  app.add_option("--local-port", o.local_port, "Port to send from (0: any)")->capture_default_str();
  app.add_option("--seconds", o.seconds, "How long to run")->check(CLI::PositiveNumber)->capture_default_str();
  app.add_option("--motion", o.motion,
                 "Scripted motion (e.g. 'poke,depth=0.01', 'press-and-slide', 'circle,radius=0.03,repeat') "
                 "or a full simulated spec ('virtual-hand:poke')")
      ->capture_default_str();
  app.add_option("--rate", o.rate_hz, "States per second")->check(CLI::Range(1.0, 20000.0))->capture_default_str();
  app.add_option("--print-rate", o.print_hz, "Lines printed per second")
      ->check(CLI::Range(0.1, 1000.0))
      ->capture_default_str();
  app.add_flag("--no-velocity", o.no_velocity, "Leave velocity out of the states (HoF then differentiates)");
  app.add_option(
         "--key", o.key_file,
         "Shared key file (hof device keygen): speak the authenticated protocol, as HoF's udp:HOST:PORT,key=FILE")
      ->check(CLI::ExistingFile);
  CLI11_PARSE(app, argc, argv);
  std::signal(SIGINT, on_interrupt);
  std::signal(SIGTERM, on_interrupt);
  return run(o);
}
