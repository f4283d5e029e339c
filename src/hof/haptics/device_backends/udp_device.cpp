#include "hof/haptics/device_backends/udp_device.h"

#include <arpa/inet.h>
#include <fcntl.h>
#include <netdb.h>
#include <netinet/in.h>
#include <poll.h>
#include <sys/socket.h>
#include <unistd.h>

#include <fmt/format.h>

#include <algorithm>
#include <bit>
#include <cerrno>
#include <chrono>
#include <cmath>
#include <cstring>
#include <thread>

namespace hof::haptics {

// ---------------------------------------------------------------------------------------
// Wire encoding: explicit little-endian byte order, whatever the host.

namespace udp {
namespace {

constexpr std::array<char, 4> kStateMagic{'H', 'O', 'F', 'S'};
constexpr std::array<char, 4> kHelloMagic{'H', 'O', 'F', 'H'};
constexpr std::array<char, 4> kForceMagic{'H', 'O', 'F', 'F'};
constexpr std::array<char, 4> kChallengeMagic{'H', 'O', 'F', 'C'};

class Writer {
 public:
  explicit Writer(std::uint8_t* p) : p_(p) {}
  void magic(const std::array<char, 4>& m) {
    for (const char c : m) *p_++ = static_cast<std::uint8_t>(c);
  }
  void u16(std::uint16_t v) { le(v, 2); }
  void u32(std::uint32_t v) { le(v, 4); }
  void f64(double v) { le(std::bit_cast<std::uint64_t>(v), 8); }
  void vec(const Vec3& v) {
    for (int i = 0; i < 3; ++i) f64(v[i]);
  }

 private:
  void le(std::uint64_t v, int bytes) {
    for (int i = 0; i < bytes; ++i) *p_++ = static_cast<std::uint8_t>(v >> (8 * i));
  }
  std::uint8_t* p_;
};

class Reader {
 public:
  explicit Reader(const std::uint8_t* p) : p_(p) {}
  bool magic(const std::array<char, 4>& m) {
    const bool same =
        std::equal(m.begin(), m.end(), p_, [](char c, std::uint8_t b) { return static_cast<std::uint8_t>(c) == b; });
    p_ += 4;
    return same;
  }
  std::uint16_t u16() { return static_cast<std::uint16_t>(le(2)); }
  std::uint32_t u32() { return static_cast<std::uint32_t>(le(4)); }
  double f64() { return std::bit_cast<double>(le(8)); }
  Vec3 vec() {
    Vec3 v;
    for (int i = 0; i < 3; ++i) v[i] = f64();
    return v;
  }

 private:
  std::uint64_t le(int bytes) {
    std::uint64_t v = 0;
    for (int i = 0; i < bytes; ++i) v |= static_cast<std::uint64_t>(*p_++) << (8 * i);
    return v;
  }
  const std::uint8_t* p_;
};

bool starts_with(std::span<const std::uint8_t> bytes, const std::array<char, 4>& magic) {
  return bytes.size() >= 4 && Reader(bytes.data()).magic(magic);
}

}  // namespace

PacketType packet_type(std::span<const std::uint8_t> bytes) {
  if (starts_with(bytes, kStateMagic)) return PacketType::kState;
  if (starts_with(bytes, kHelloMagic)) return PacketType::kHello;
  if (starts_with(bytes, kForceMagic)) return PacketType::kForce;
  if (starts_with(bytes, kChallengeMagic)) return PacketType::kChallenge;
  return PacketType::kUnknown;
}

std::size_t encode(const StatePacket& s, std::span<std::uint8_t> out) {
  const std::size_t size = s.has_velocity ? kStateWithVelocitySize : kStateSize;
  if (out.size() < size) return 0;
  Writer w(out.data());
  w.magic(kStateMagic);
  w.u16(kVersion);
  w.u16(s.has_velocity ? kStateHasVelocity : std::uint16_t{0});
  w.u32(s.sequence);
  w.u32(s.buttons);
  w.f64(s.device_time_s);
  w.vec(s.position_m);
  w.f64(s.orientation.w());
  w.vec(s.orientation.vec());
  if (s.has_velocity) w.vec(s.velocity_m_per_s);
  return size;
}

std::size_t encode(const HelloPacket& h, std::span<std::uint8_t> out) {
  if (out.size() < kHelloSize) return 0;
  Writer w(out.data());
  w.magic(kHelloMagic);
  w.u16(kVersion);
  w.u16(0);
  w.u32(h.sequence);
  w.u32(0);
  for (const double v :
       {h.max_force_n, h.max_stiffness_n_per_m, h.max_damping_n_s_per_m, h.workspace_radius_m, h.nominal_rate_hz}) {
    w.f64(v);
  }
  std::memcpy(out.data() + 56, h.model.data(), kModelNameSize);
  return kHelloSize;
}

std::size_t encode(const ForcePacket& f, std::span<std::uint8_t> out) {
  if (out.size() < kForceSize) return 0;
  Writer w(out.data());
  w.magic(kForceMagic);
  w.u16(kVersion);
  w.u16(f.closing ? kForceFinal : std::uint16_t{0});
  w.u32(f.echo_sequence);
  w.u32(f.sequence);
  w.vec(f.force_n);
  w.vec(f.torque_n_m);
  return kForceSize;
}

std::size_t encode(const ChallengePacket& c, std::span<std::uint8_t> out) {
  if (out.size() < kChallengeSize) return 0;
  Writer w(out.data());
  w.magic(kChallengeMagic);
  w.u16(kVersion);  // seal() makes it 2: a challenge only exists sealed
  w.u16(0);
  w.u32(c.echo_sequence);
  w.u32(0);
  return kChallengeSize;
}

bool decode(std::span<const std::uint8_t> bytes, ChallengePacket& out) {
  if (bytes.size() != kChallengeSize) return false;
  Reader r(bytes.data());
  if (!r.magic(kChallengeMagic) || r.u16() != kVersion || r.u16() != 0) return false;
  out.echo_sequence = r.u32();
  return r.u32() == 0;
}

bool decode(std::span<const std::uint8_t> bytes, StatePacket& out) {
  if (bytes.size() < 8) return false;
  Reader r(bytes.data());
  if (!r.magic(kStateMagic) || r.u16() != kVersion) return false;
  const std::uint16_t flags = r.u16();
  if ((flags & ~kStateHasVelocity) != 0) return false;
  const bool has_velocity = (flags & kStateHasVelocity) != 0;
  if (bytes.size() != (has_velocity ? kStateWithVelocitySize : kStateSize)) return false;
  StatePacket s;
  s.sequence = r.u32();
  s.buttons = r.u32();
  s.device_time_s = r.f64();
  s.position_m = r.vec();
  const double qw = r.f64();
  const Vec3 qv = r.vec();
  s.has_velocity = has_velocity;
  if (has_velocity) s.velocity_m_per_s = r.vec();
  const Eigen::Vector4d q(qw, qv.x(), qv.y(), qv.z());
  const double norm = q.norm();
  if (!std::isfinite(s.device_time_s) || !s.position_m.allFinite() || !s.velocity_m_per_s.allFinite() ||
      !std::isfinite(norm) || norm < 1e-9) {
    return false;
  }
  s.orientation = Eigen::Quaterniond(qw / norm, qv.x() / norm, qv.y() / norm, qv.z() / norm);
  out = s;
  return true;
}

bool decode(std::span<const std::uint8_t> bytes, HelloPacket& out) {
  if (bytes.size() != kHelloSize) return false;
  Reader r(bytes.data());
  if (!r.magic(kHelloMagic) || r.u16() != kVersion || r.u16() != 0) return false;
  HelloPacket h;
  h.sequence = r.u32();
  r.u32();  // reserved
  h.max_force_n = r.f64();
  h.max_stiffness_n_per_m = r.f64();
  h.max_damping_n_s_per_m = r.f64();
  h.workspace_radius_m = r.f64();
  h.nominal_rate_hz = r.f64();
  for (const double v :
       {h.max_force_n, h.max_stiffness_n_per_m, h.max_damping_n_s_per_m, h.workspace_radius_m, h.nominal_rate_hz}) {
    if (!std::isfinite(v)) return false;
  }
  std::memcpy(h.model.data(), bytes.data() + 56, kModelNameSize);
  h.model.back() = '\0';  // always terminated
  out = h;
  return true;
}

bool decode(std::span<const std::uint8_t> bytes, ForcePacket& out) {
  if (bytes.size() != kForceSize) return false;
  Reader r(bytes.data());
  if (!r.magic(kForceMagic) || r.u16() != kVersion) return false;
  const std::uint16_t flags = r.u16();
  if ((flags & ~kForceFinal) != 0) return false;
  ForcePacket f;
  f.closing = (flags & kForceFinal) != 0;
  f.echo_sequence = r.u32();
  f.sequence = r.u32();
  f.force_n = r.vec();
  f.torque_n_m = r.vec();
  if (!f.force_n.allFinite() || !f.torque_n_m.allFinite()) return false;
  out = f;
  return true;
}

DeviceSpec apply_hello(const DeviceSpec& base, const HelloPacket& hello) {
  DeviceSpec spec = base;
  if (hello.max_force_n > 0.0) spec.max_force_n = hello.max_force_n;
  if (hello.max_stiffness_n_per_m > 0.0) spec.max_stiffness_n_per_m = hello.max_stiffness_n_per_m;
  if (hello.max_damping_n_s_per_m > 0.0) spec.max_damping_n_s_per_m = hello.max_damping_n_s_per_m;
  if (hello.workspace_radius_m > 0.0) spec.workspace_radius_m = hello.workspace_radius_m;
  if (hello.nominal_rate_hz > 0.0) spec.nominal_rate_hz = hello.nominal_rate_hz;
  if (hello.model[0] != '\0') spec.model = std::string(hello.model.data());
  return spec;
}

}  // namespace udp

// ---------------------------------------------------------------------------------------
// Receiver side

namespace {

using Clock = std::chrono::steady_clock;

/// What crosses from the receiver thread to read(): plain numbers only.
struct StateSnapshot {
  double device_time_s{0.0};
  double p[3]{};
  double q[4]{1.0, 0.0, 0.0, 0.0};
  double v[3]{};
  std::uint32_t buttons{0};
  std::uint32_t sequence{0};
  std::uint64_t count{0};  ///< states accepted so far (0: none yet)
};

struct ForceSnapshot {
  double f[3]{};
  double t[3]{};
};

}  // namespace

struct UdpDevice::Impl {
  UdpDeviceConfig config;
  int sock{-1};
  int wake_read{-1};
  int wake_write{-1};
  std::uint16_t port{0};
  bool filter_host{false};
  in_addr host_addr{};
  std::thread thread;
  std::atomic<bool> stop{false};
  std::atomic<bool> closed{false};
  std::atomic<DeviceHealth> health{DeviceHealth::kOk};

  SeqLock<StateSnapshot> state;
  SeqLock<ForceSnapshot> force;
  SeqLock<udp::HelloPacket> hello;

  struct Counters {
    std::atomic<std::uint64_t> datagrams{0}, states{0}, hellos{0}, stale{0}, malformed{0}, foreign{0}, other_sender{0},
        unauthenticated{0}, replayed{0}, forces_sent{0}, send_errors{0};
  } counters;

  // Receiver thread only (and close() after the join).
  sockaddr_in peer{};
  bool has_peer{false};
  bool resync{true};  // accept the next state whatever its sequence
  std::uint32_t last_sequence{0};
  bool has_previous{false};
  double previous_time_s{0.0};
  Vec3 previous_position{Vec3::Zero()};
  std::uint64_t accepted{0};
  std::uint32_t force_sequence{0};
  Clock::time_point last_accept{};
  // With a key: the session nonce of the latest challenge (0: none issued yet). Only states
  // carrying it are read, so a datagram recorded in an earlier session cannot be replayed.
  std::uint64_t session{0};

  // Reader (haptic tick) only.
  StateSnapshot last_read{};

  ~Impl() {
    for (const int fd : {sock, wake_read, wake_write}) {
      if (fd >= 0) ::close(fd);
    }
  }

  static void bump(std::atomic<std::uint64_t>& c) { c.fetch_add(1, std::memory_order_relaxed); }

  void run();
  void handle(std::span<const std::uint8_t> bytes, const sockaddr_in& from, Clock::time_point now);
  void accept_state(const udp::StatePacket& s, const sockaddr_in& from, Clock::time_point now);
  void send_force(bool closing);
  void send_challenge(std::uint32_t hello_sequence, const sockaddr_in& to);
  /// Sends `buffer[0, size)` (sealed first when there is a key); false if it did not go out.
  bool send_datagram(std::span<std::uint8_t> buffer, std::size_t size, const sockaddr_in& to);
};

// The receiver loop: wait for the socket or the wake pipe, drain the socket, then check the
// timeout. The poll period is a quarter of the timeout (1–50 ms) so timeouts are detected
// promptly even when nothing arrives.
void UdpDevice::Impl::run() {
  const int poll_ms = std::clamp(static_cast<int>(config.timeout_s * 250.0), 1, 50);
  const auto timeout = std::chrono::duration<double>(config.timeout_s);
  std::array<std::uint8_t, 2048> buffer{};
  while (!stop.load(std::memory_order_acquire)) {
    std::array<pollfd, 2> fds{pollfd{sock, POLLIN, 0}, pollfd{wake_read, POLLIN, 0}};
    const int ready = ::poll(fds.data(), fds.size(), poll_ms);
    if (ready < 0 && errno != EINTR) {
      health.store(DeviceHealth::kFailed, std::memory_order_release);
      return;
    }
    if (fds[1].revents != 0) break;
    if (ready > 0 && fds[0].revents != 0) {
      for (int i = 0; i < 256; ++i) {  // bounded drain
        sockaddr_in from{};
        socklen_t from_size = sizeof(from);
        const ssize_t n = ::recvfrom(sock, buffer.data(), buffer.size(), MSG_DONTWAIT | MSG_TRUNC,
                                     reinterpret_cast<sockaddr*>(&from), &from_size);
        if (n < 0) {
          if (errno == EAGAIN || errno == EWOULDBLOCK || errno == EINTR || errno == ECONNREFUSED) break;
          health.store(DeviceHealth::kFailed, std::memory_order_release);
          return;
        }
        bump(counters.datagrams);
        if (static_cast<std::size_t>(n) > buffer.size()) {  // truncated: too big to be ours
          bump(counters.malformed);
          continue;
        }
        handle(std::span<const std::uint8_t>(buffer.data(), static_cast<std::size_t>(n)), from, Clock::now());
      }
    }
    if (Clock::now() - last_accept > timeout) {
      // A restarted peer may begin again at sequence 0. With a key it gets a new session
      // through a hello instead, so the sequence check never relaxes (replay protection).
      if (!config.key) resync = true;
      DeviceHealth expected = DeviceHealth::kOk;
      health.compare_exchange_strong(expected, DeviceHealth::kTimedOut, std::memory_order_acq_rel);
    }
  }
}

void UdpDevice::Impl::handle(std::span<const std::uint8_t> raw, const sockaddr_in& from, Clock::time_point now) {
  if (filter_host && from.sin_addr.s_addr != host_addr.s_addr) {
    bump(counters.foreign);
    return;
  }
  // With a key, only datagrams sealed with it are read (any version-1 datagram is refused).
  std::array<std::uint8_t, udp::kMaxPacketSize> body_buffer{};
  std::span<const std::uint8_t> bytes = raw;
  std::uint64_t packet_session = 0;
  if (config.key) {
    const std::size_t size = udp::unseal(raw, *config.key, packet_session, body_buffer);
    if (size == 0) {
      bump(counters.unauthenticated);
      return;
    }
    bytes = std::span<const std::uint8_t>(body_buffer.data(), size);
  }
  // The first sender of an accepted state has the session for as long as the device is open:
  // anyone else (another address, or another port on the same host) is refused and counted.
  // A restarted bridge keeps its source port to be taken back (docs/device-protocol.md).
  if (has_peer && (peer.sin_addr.s_addr != from.sin_addr.s_addr || peer.sin_port != from.sin_port)) {
    bump(counters.other_sender);
    return;
  }
  switch (udp::packet_type(bytes)) {
    case udp::PacketType::kState: {
      udp::StatePacket s;
      if (!udp::decode(bytes, s)) break;
      if (config.key && (session == 0 || packet_session != session)) {
        bump(counters.replayed);  // sealed by the key holder, but for another session
        return;
      }
      accept_state(s, from, now);
      return;
    }
    case udp::PacketType::kHello: {
      udp::HelloPacket h;
      if (!udp::decode(bytes, h)) break;
      hello.store(h);
      bump(counters.hellos);
      resync = true;
      if (config.key) {
        // A new session for every hello: the states of any earlier one (recorded and replayed
        // by a third party) no longer match. A replayed hello can only end the session, not
        // drive the device: the challenge is useless without the key.
        session = udp::random_session();
        send_challenge(h.sequence, from);
      }
      return;
    }
    case udp::PacketType::kForce:      // HoF never receives forces
    case udp::PacketType::kChallenge:  // nor challenges
    case udp::PacketType::kUnknown:
      break;
  }
  bump(counters.malformed);
}

void UdpDevice::Impl::accept_state(const udp::StatePacket& s, const sockaddr_in& from, Clock::time_point now) {
  // One peer (handle() refused any other): the first state starts its sequence.
  const bool same_peer = has_peer && peer.sin_addr.s_addr == from.sin_addr.s_addr && peer.sin_port == from.sin_port;
  if (!resync && same_peer && !udp::newer(s.sequence, last_sequence)) {
    bump(counters.stale);
    return;
  }
  if (!same_peer || resync) has_previous = false;
  resync = false;
  peer = from;
  has_peer = true;
  last_sequence = s.sequence;

  // Velocity: the device's own, or the backward difference over device time.
  Vec3 v = s.velocity_m_per_s;
  if (!s.has_velocity) {
    v.setZero();
    if (has_previous && s.device_time_s > previous_time_s) {
      v = (s.position_m - previous_position) / (s.device_time_s - previous_time_s);
    }
  }
  has_previous = true;
  previous_time_s = s.device_time_s;
  previous_position = s.position_m;

  StateSnapshot snap;
  snap.device_time_s = s.device_time_s;
  for (int i = 0; i < 3; ++i) {
    snap.p[i] = s.position_m[i];
    snap.v[i] = v[i];
  }
  snap.q[0] = s.orientation.w();
  snap.q[1] = s.orientation.x();
  snap.q[2] = s.orientation.y();
  snap.q[3] = s.orientation.z();
  snap.buttons = s.buttons;
  snap.sequence = s.sequence;
  snap.count = ++accepted;
  state.store(snap);
  last_accept = now;
  health.store(DeviceHealth::kOk, std::memory_order_release);
  bump(counters.states);
  send_force(false);
}

void UdpDevice::Impl::send_force(bool closing) {
  if (!has_peer) return;
  ForceSnapshot f{};
  if (!closing) force.try_load(f);  // if never consistent (cannot happen in practice): zero
  udp::ForcePacket packet;
  packet.echo_sequence = last_sequence;
  packet.sequence = ++force_sequence;
  packet.force_n = Vec3(f.f[0], f.f[1], f.f[2]);
  packet.torque_n_m = Vec3(f.t[0], f.t[1], f.t[2]);
  packet.closing = closing;
  std::array<std::uint8_t, udp::kMaxPacketSize> bytes{};
  bump(send_datagram(bytes, udp::encode(packet, bytes), peer) ? counters.forces_sent : counters.send_errors);
}

void UdpDevice::Impl::send_challenge(std::uint32_t hello_sequence, const sockaddr_in& to) {
  std::array<std::uint8_t, udp::kMaxPacketSize> bytes{};
  if (!send_datagram(bytes, udp::encode(udp::ChallengePacket{hello_sequence}, bytes), to)) bump(counters.send_errors);
}

bool UdpDevice::Impl::send_datagram(std::span<std::uint8_t> buffer, std::size_t size, const sockaddr_in& to) {
  if (config.key) size = udp::seal(buffer, size, session, *config.key);
  const ssize_t sent = ::sendto(sock, buffer.data(), size, MSG_DONTWAIT | MSG_NOSIGNAL,
                                reinterpret_cast<const sockaddr*>(&to), sizeof(to));
  return size > 0 && sent == static_cast<ssize_t>(size);
}

// ---------------------------------------------------------------------------------------
// UdpDevice

UdpDevice::UdpDevice(std::unique_ptr<Impl> impl, const DeviceSpec& spec) : impl_(std::move(impl)), spec_(spec) {}

UdpDevice::~UdpDevice() { close(); }

Expected<std::unique_ptr<UdpDevice>> UdpDevice::open(const UdpDeviceConfig& config) {
  const auto fail = [&](ErrorCode code, const std::string& what) {
    return make_error(code, fmt::format("udp: {} (port {})", what, config.port));
  };
  if (!std::isfinite(config.timeout_s) || config.timeout_s <= 0.0)
    return fail(ErrorCode::kInvalidArgument, fmt::format("timeout must be > 0 s (got {})", config.timeout_s));
  if (!std::isfinite(config.hello_wait_s) || config.hello_wait_s < 0.0)
    return fail(ErrorCode::kInvalidArgument, fmt::format("hello_wait must be >= 0 s (got {})", config.hello_wait_s));

  auto impl = std::make_unique<Impl>();
  impl->config = config;
  if (!config.host.empty()) {
    addrinfo hints{};
    hints.ai_family = AF_INET;
    hints.ai_socktype = SOCK_DGRAM;
    addrinfo* found = nullptr;
    const int rc = ::getaddrinfo(config.host.c_str(), nullptr, &hints, &found);
    if (rc != 0 || found == nullptr) {
      return fail(ErrorCode::kInvalidArgument,
                  fmt::format("cannot resolve host '{}': {}", config.host, ::gai_strerror(rc)));
    }
    impl->host_addr = reinterpret_cast<const sockaddr_in*>(found->ai_addr)->sin_addr;
    impl->filter_host = true;
    ::freeaddrinfo(found);
    // Plain datagrams from the network could be forged by anyone on it (a source address
    // proves nothing in UDP): a bridge on another machine must authenticate.
    const bool loopback = (ntohl(impl->host_addr.s_addr) >> 24) == 127;
    if (!loopback && !config.key) {
      return fail(ErrorCode::kInvalidArgument,
                  fmt::format("a bridge on another machine ('{}') needs a shared key: add key=FILE "
                              "(make one with `hof device keygen FILE`; docs/device-protocol.md)",
                              config.host));
    }
  }

  impl->sock = ::socket(AF_INET, SOCK_DGRAM | SOCK_CLOEXEC, 0);
  if (impl->sock < 0) return fail(ErrorCode::kIo, fmt::format("cannot create a socket: {}", std::strerror(errno)));
  sockaddr_in addr{};
  addr.sin_family = AF_INET;
  // A local bridge: the loopback interface only, unreachable from the network.
  const bool local_bridge = config.host.empty() || (ntohl(impl->host_addr.s_addr) >> 24) == 127;
  addr.sin_addr.s_addr = htonl(local_bridge ? INADDR_LOOPBACK : INADDR_ANY);
  addr.sin_port = htons(config.port);
  if (::bind(impl->sock, reinterpret_cast<const sockaddr*>(&addr), sizeof(addr)) != 0) {
    return fail(ErrorCode::kIo, fmt::format("cannot bind the UDP port: {}", std::strerror(errno)));
  }
  socklen_t size = sizeof(addr);
  if (::getsockname(impl->sock, reinterpret_cast<sockaddr*>(&addr), &size) != 0) {
    return fail(ErrorCode::kIo, fmt::format("getsockname failed: {}", std::strerror(errno)));
  }
  impl->port = ntohs(addr.sin_port);

  std::array<int, 2> pipe_fds{-1, -1};
  if (::pipe2(pipe_fds.data(), O_CLOEXEC | O_NONBLOCK) != 0) {
    return fail(ErrorCode::kIo, fmt::format("cannot create the wake pipe: {}", std::strerror(errno)));
  }
  impl->wake_read = pipe_fds[0];
  impl->wake_write = pipe_fds[1];
  impl->last_accept = Clock::now();
  Impl* raw = impl.get();
  impl->thread = std::thread([raw] { raw->run(); });

  // Optionally wait for the bridge to say what the device can do; spec() is fixed after.
  DeviceSpec spec = config.spec;
  const auto deadline = Clock::now() + std::chrono::duration<double>(config.hello_wait_s);
  while (raw->counters.hellos.load(std::memory_order_acquire) == 0 && Clock::now() < deadline) {
    std::this_thread::sleep_for(std::chrono::milliseconds(2));
  }
  udp::HelloPacket hello;
  if (raw->counters.hellos.load(std::memory_order_acquire) > 0 && raw->hello.try_load(hello, 1 << 20)) {
    spec = udp::apply_hello(spec, hello);
  }
  return std::unique_ptr<UdpDevice>(new UdpDevice(std::move(impl), spec));
}

DeviceReading UdpDevice::read(double /*time_s*/) {
  StateSnapshot s;
  if (impl_->state.try_load(s)) impl_->last_read = s;
  s = impl_->last_read;
  DeviceReading r;
  r.time_s = s.device_time_s;
  r.position_m = Vec3(s.p[0], s.p[1], s.p[2]);
  r.velocity_m_per_s = Vec3(s.v[0], s.v[1], s.v[2]);
  r.orientation = Eigen::Quaterniond(s.q[0], s.q[1], s.q[2], s.q[3]);
  r.buttons = s.buttons;
  r.valid = s.count > 0 && health() == DeviceHealth::kOk;
  return r;
}

void UdpDevice::write_force(const Vec3& force_n, const Vec3& torque_n_m) {
  ForceSnapshot f;
  if (force_n.allFinite() && torque_n_m.allFinite()) {
    for (int i = 0; i < 3; ++i) {
      f.f[i] = force_n[i];
      f.t[i] = torque_n_m[i];
    }
  }
  impl_->force.store(f);
}

DeviceHealth UdpDevice::health() const { return impl_->health.load(std::memory_order_acquire); }

void UdpDevice::close() {
  if (!impl_ || impl_->closed.exchange(true)) return;
  impl_->stop.store(true, std::memory_order_release);
  const std::uint8_t byte = 1;
  [[maybe_unused]] const ssize_t w = ::write(impl_->wake_write, &byte, 1);
  if (impl_->thread.joinable()) impl_->thread.join();
  impl_->send_force(true);  // the receiver is gone: its peer data is ours now
}

std::uint16_t UdpDevice::local_port() const { return impl_->port; }

UdpDeviceStats UdpDevice::stats() const {
  const auto& c = impl_->counters;
  const auto get = [](const std::atomic<std::uint64_t>& a) { return a.load(std::memory_order_relaxed); };
  UdpDeviceStats s;
  s.datagrams = get(c.datagrams);
  s.states = get(c.states);
  s.hellos = get(c.hellos);
  s.stale = get(c.stale);
  s.malformed = get(c.malformed);
  s.foreign = get(c.foreign);
  s.other_sender = get(c.other_sender);
  s.unauthenticated = get(c.unauthenticated);
  s.replayed = get(c.replayed);
  s.forces_sent = get(c.forces_sent);
  s.send_errors = get(c.send_errors);
  return s;
}

std::optional<udp::HelloPacket> UdpDevice::last_hello() const {
  udp::HelloPacket h;
  if (impl_->counters.hellos.load(std::memory_order_acquire) == 0 || !impl_->hello.try_load(h, 1 << 20)) {
    return std::nullopt;
  }
  return h;
}

}  // namespace hof::haptics
