// Tests of the UDP bridge device (hof/haptics/device_backends/udp_device.h): the byte layout
// of docs/device-protocol.md, and real exchanges with a peer socket on 127.0.0.1 (ephemeral
// ports). Every wait is a bounded loop with a generous deadline: nothing asserts on timing,
// so the tests pass on a loaded machine and never hang.

#include <arpa/inet.h>
#include <netinet/in.h>
#include <poll.h>
#include <sys/socket.h>
#include <sys/stat.h>
#include <unistd.h>

#include <fmt/format.h>
#include <gtest/gtest.h>

#include <array>
#include <atomic>
#include <chrono>
#include <cmath>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <functional>
#include <limits>
#include <optional>
#include <thread>
#include <vector>

#include "hof/haptics/device.h"
#include "hof/haptics/device_backends/udp_device.h"

namespace hof::haptics {
namespace {

using Clock = std::chrono::steady_clock;
constexpr auto kDeadline = std::chrono::seconds(5);

/// Polls `done` every millisecond until it holds or the deadline passes.
bool eventually(const std::function<bool()>& done, std::chrono::milliseconds every = std::chrono::milliseconds(1)) {
  const auto end = Clock::now() + kDeadline;
  while (Clock::now() < end) {
    if (done()) return true;
    std::this_thread::sleep_for(every);
  }
  return done();
}

/// The device side of the protocol: a UDP socket on 127.0.0.1 (or another loopback address).
class Peer {
 public:
  explicit Peer(const char* address = "127.0.0.1") {
    fd_ = ::socket(AF_INET, SOCK_DGRAM | SOCK_CLOEXEC, 0);
    sockaddr_in a{};
    a.sin_family = AF_INET;
    ::inet_pton(AF_INET, address, &a.sin_addr);
    ok_ = fd_ >= 0 && ::bind(fd_, reinterpret_cast<const sockaddr*>(&a), sizeof(a)) == 0;
  }
  ~Peer() {
    if (fd_ >= 0) ::close(fd_);
  }
  Peer(const Peer&) = delete;
  Peer& operator=(const Peer&) = delete;

  [[nodiscard]] bool ok() const { return ok_; }

  void send_raw(std::uint16_t port, const std::uint8_t* data, std::size_t size) const {
    sockaddr_in to{};
    to.sin_family = AF_INET;
    to.sin_port = htons(port);
    to.sin_addr.s_addr = htonl(INADDR_LOOPBACK);
    ::sendto(fd_, data, size, 0, reinterpret_cast<const sockaddr*>(&to), sizeof(to));
  }
  template <class Packet>
  void send(std::uint16_t port, const Packet& packet) const {
    std::array<std::uint8_t, udp::kMaxPacketSize> bytes{};
    const std::size_t size = udp::encode(packet, bytes);
    send_raw(port, bytes.data(), size);
  }

  /// Sends `packet` sealed with `key` for `session` (the authenticated protocol, version 2).
  template <class Packet>
  void send_sealed(std::uint16_t port, const Packet& packet, std::uint64_t session, const udp::Key& key) const {
    std::array<std::uint8_t, udp::kMaxPacketSize> bytes{};
    const std::size_t size = udp::seal(bytes, udp::encode(packet, bytes), session, key);
    send_raw(port, bytes.data(), size);
  }

  /// The next datagram within `wait_ms`, raw.
  std::optional<std::vector<std::uint8_t>> receive_raw(int wait_ms = 5) const {
    pollfd p{fd_, POLLIN, 0};
    if (::poll(&p, 1, wait_ms) <= 0) return std::nullopt;
    std::array<std::uint8_t, 256> bytes{};
    const ssize_t n = ::recv(fd_, bytes.data(), bytes.size(), MSG_DONTWAIT);
    if (n <= 0) return std::nullopt;
    return std::vector<std::uint8_t>(bytes.begin(), bytes.begin() + n);
  }

  /// The next force packet within `wait_ms`, if any.
  std::optional<udp::ForcePacket> receive_force(int wait_ms = 5) const {
    pollfd p{fd_, POLLIN, 0};
    if (::poll(&p, 1, wait_ms) <= 0) return std::nullopt;
    std::array<std::uint8_t, 256> bytes{};
    const ssize_t n = ::recv(fd_, bytes.data(), bytes.size(), MSG_DONTWAIT);
    udp::ForcePacket f;
    if (n <= 0 || !udp::decode(std::span<const std::uint8_t>(bytes.data(), static_cast<std::size_t>(n)), f)) {
      return std::nullopt;
    }
    return f;
  }

 private:
  int fd_{-1};
  bool ok_{false};
};

udp::StatePacket state(std::uint32_t sequence, double x = 0.01) {
  udp::StatePacket s;
  s.sequence = sequence;
  s.device_time_s = 0.001 * sequence;
  s.position_m = Vec3(x, 0.02, -0.03);
  s.orientation = Eigen::Quaterniond(Eigen::AngleAxisd(0.3, Vec3::UnitY()));
  s.has_velocity = true;
  s.velocity_m_per_s = Vec3(0.1, 0.0, -0.2);
  s.buttons = 1;
  return s;
}

std::unique_ptr<UdpDevice> open_udp(double timeout_s = 0.1, const std::string& host = "127.0.0.1") {
  UdpDeviceConfig config;
  config.host = host;
  config.port = 0;
  config.timeout_s = timeout_s;
  auto d = UdpDevice::open(config);
  EXPECT_TRUE(d) << d.error().to_string();
  return d ? std::move(*d) : nullptr;
}

/// Sends states (increasing sequence from `first`) until read() reports one, or the deadline.
bool stream_until_valid(UdpDevice& device, const Peer& peer, std::uint32_t first, DeviceReading& out) {
  std::uint32_t seq = first;
  return eventually([&] {
    peer.send(device.local_port(), state(seq++));
    out = device.read(0.0);
    return out.valid;
  });
}

// ---------------------------------------------------------------------------------------
// Byte layout

TEST(UdpProtocol, StateLayoutIsLittleEndianAndRoundTrips) {
  std::array<std::uint8_t, udp::kMaxPacketSize> bytes{};
  udp::StatePacket s = state(0x01020304U);
  ASSERT_EQ(udp::encode(s, bytes), udp::kStateWithVelocitySize);
  EXPECT_EQ(std::memcmp(bytes.data(), "HOFS", 4), 0);
  EXPECT_EQ(bytes[4], 1);  // version 1, little-endian u16
  EXPECT_EQ(bytes[5], 0);
  EXPECT_EQ(bytes[6], udp::kStateHasVelocity);
  EXPECT_EQ(bytes[8], 0x04);  // sequence, little-endian
  EXPECT_EQ(bytes[11], 0x01);
  EXPECT_EQ(bytes[12], 1);  // buttons
  double x = 0.0;
  std::uint64_t raw = 0;
  for (int i = 0; i < 8; ++i) raw |= static_cast<std::uint64_t>(bytes[24 + i]) << (8 * i);
  std::memcpy(&x, &raw, 8);
  EXPECT_EQ(x, 0.01);  // position x at offset 24

  udp::StatePacket back;
  ASSERT_TRUE(udp::decode(std::span<const std::uint8_t>(bytes.data(), udp::kStateWithVelocitySize), back));
  EXPECT_EQ(back.sequence, s.sequence);
  EXPECT_EQ(back.position_m, s.position_m);
  EXPECT_EQ(back.velocity_m_per_s, s.velocity_m_per_s);
  EXPECT_NEAR(back.orientation.angularDistance(s.orientation), 0.0, 1e-12);

  s.has_velocity = false;
  ASSERT_EQ(udp::encode(s, bytes), udp::kStateSize);
  ASSERT_TRUE(udp::decode(std::span<const std::uint8_t>(bytes.data(), udp::kStateSize), back));
  EXPECT_FALSE(back.has_velocity);
  // One byte more or less, another version, or a NaN: malformed.
  EXPECT_FALSE(udp::decode(std::span<const std::uint8_t>(bytes.data(), udp::kStateSize + 1), back));
  EXPECT_FALSE(udp::decode(std::span<const std::uint8_t>(bytes.data(), udp::kStateSize - 1), back));
  bytes[4] = 2;
  EXPECT_FALSE(udp::decode(std::span<const std::uint8_t>(bytes.data(), udp::kStateSize), back));
  s.position_m.y() = std::numeric_limits<double>::quiet_NaN();
  udp::encode(s, bytes);
  EXPECT_FALSE(udp::decode(std::span<const std::uint8_t>(bytes.data(), udp::kStateSize), back));
}

TEST(UdpProtocol, HelloAndForceRoundTrip) {
  std::array<std::uint8_t, udp::kMaxPacketSize> bytes{};
  udp::HelloPacket h;
  h.max_force_n = 3.3;
  h.max_stiffness_n_per_m = 700;
  h.workspace_radius_m = 0.1;
  std::memcpy(h.model.data(), "omni", 4);
  ASSERT_EQ(udp::encode(h, bytes), udp::kHelloSize);
  EXPECT_EQ(std::memcmp(bytes.data(), "HOFH", 4), 0);
  udp::HelloPacket hb;
  ASSERT_TRUE(udp::decode(std::span<const std::uint8_t>(bytes.data(), udp::kHelloSize), hb));
  const DeviceSpec spec = udp::apply_hello(DeviceSpec{}, hb);
  EXPECT_EQ(spec.model, "omni");
  EXPECT_EQ(spec.max_force_n, 3.3);
  EXPECT_EQ(spec.max_stiffness_n_per_m, 700.0);
  EXPECT_EQ(spec.max_damping_n_s_per_m, DeviceSpec{}.max_damping_n_s_per_m);  // not stated: kept

  udp::ForcePacket f;
  f.echo_sequence = 7;
  f.sequence = 9;
  f.force_n = Vec3(1, -2, 3);
  f.torque_n_m = Vec3(0.1, 0, 0);
  f.closing = true;
  ASSERT_EQ(udp::encode(f, bytes), udp::kForceSize);
  EXPECT_EQ(std::memcmp(bytes.data(), "HOFF", 4), 0);
  EXPECT_EQ(bytes[8], 7);
  EXPECT_EQ(bytes[12], 9);
  udp::ForcePacket fb;
  ASSERT_TRUE(udp::decode(std::span<const std::uint8_t>(bytes.data(), udp::kForceSize), fb));
  EXPECT_EQ(fb.force_n, f.force_n);
  EXPECT_EQ(fb.torque_n_m, f.torque_n_m);
  EXPECT_TRUE(fb.closing);
  EXPECT_EQ(udp::packet_type(std::span<const std::uint8_t>(bytes.data(), 4)), udp::PacketType::kForce);
}

TEST(UdpProtocol, SequenceComparisonWrapsAround) {
  EXPECT_TRUE(udp::newer(1, 0));
  EXPECT_FALSE(udp::newer(0, 1));
  EXPECT_FALSE(udp::newer(5, 5));
  EXPECT_TRUE(udp::newer(2, 0xFFFFFFFEU));
  EXPECT_FALSE(udp::newer(0xFFFFFFFEU, 2));
}

// ---------------------------------------------------------------------------------------
// Exchanges over loopback

TEST(UdpDevice, StatesFromThePeerReachRead) {
  auto device = open_udp();
  ASSERT_TRUE(device);
  Peer peer;
  ASSERT_TRUE(peer.ok());
  EXPECT_FALSE(device->read(0.0).valid);  // nothing yet
  DeviceReading r;
  ASSERT_TRUE(stream_until_valid(*device, peer, 1, r));
  EXPECT_EQ(r.position_m, Vec3(0.01, 0.02, -0.03));
  EXPECT_EQ(r.velocity_m_per_s, Vec3(0.1, 0.0, -0.2));
  EXPECT_NEAR(r.orientation.angularDistance(state(1).orientation), 0.0, 1e-12);
  EXPECT_EQ(r.buttons, 1U);
  EXPECT_GT(r.time_s, 0.0);
  EXPECT_EQ(device->health(), DeviceHealth::kOk);
  EXPECT_GE(device->stats().states, 1U);
}

TEST(UdpDevice, VelocityIsEstimatedWhenThePeerSendsNone) {
  auto device = open_udp(1.0);
  ASSERT_TRUE(device);
  Peer peer;
  std::uint32_t seq = 1;
  // Positions x = 0.1 m/s · t: every estimate after the first sample is 0.1 m/s.
  ASSERT_TRUE(eventually([&] {
    udp::StatePacket s = state(seq, 0.1 * 0.001 * seq);
    s.has_velocity = false;
    peer.send(device->local_port(), s);
    ++seq;
    const DeviceReading r = device->read(0.0);
    return r.valid && std::abs(r.velocity_m_per_s.x() - 0.1) < 1e-9;
  }));
}

TEST(UdpDevice, WrittenForceReachesThePeer) {
  auto device = open_udp();
  ASSERT_TRUE(device);
  Peer peer;
  const Vec3 force(0.5, -1.25, 2.0);
  const Vec3 torque(0.0, 0.01, 0.0);
  device->write_force(force, torque);
  std::uint32_t seq = 100;
  std::optional<udp::ForcePacket> got;
  ASSERT_TRUE(eventually([&] {
    peer.send(device->local_port(), state(seq++));
    while (auto f = peer.receive_force(1)) got = f;
    return got && got->force_n == force;
  }));
  EXPECT_EQ(got->torque_n_m, torque);
  EXPECT_GE(got->echo_sequence, 100U);
  EXPECT_LT(got->echo_sequence, seq);
  EXPECT_FALSE(got->closing);

  // A non-finite force never leaves HoF.
  device->write_force(Vec3(std::nan(""), 0, 0), Vec3::Zero());
  got.reset();
  ASSERT_TRUE(eventually([&] {
    peer.send(device->local_port(), state(seq++));
    while (auto f = peer.receive_force(1)) got = f;
    return got && got->force_n == Vec3::Zero();
  }));
}

TEST(UdpDevice, SilenceTimesOutAndTheNextStateRecovers) {
  auto device = open_udp(0.05);
  ASSERT_TRUE(device);
  Peer peer;
  DeviceReading r;
  ASSERT_TRUE(stream_until_valid(*device, peer, 500, r));
  ASSERT_TRUE(eventually([&] { return device->health() == DeviceHealth::kTimedOut; }));
  EXPECT_FALSE(device->read(0.0).valid);
  // A restarted bridge begins again at sequence 0: after a timeout it is accepted.
  ASSERT_TRUE(stream_until_valid(*device, peer, 0, r));
  EXPECT_EQ(device->health(), DeviceHealth::kOk);
}

TEST(UdpDevice, GarbageDatagramsAreCountedAndIgnored) {
  auto device = open_udp(1.0);
  ASSERT_TRUE(device);
  Peer peer;
  DeviceReading r;
  ASSERT_TRUE(stream_until_valid(*device, peer, 1, r));
  const std::uint64_t before = device->stats().malformed;

  std::array<std::uint8_t, udp::kMaxPacketSize> bytes{};
  const std::size_t size = udp::encode(state(1000, 0.05), bytes);
  std::array<std::uint8_t, udp::kMaxPacketSize> bad = bytes;
  const std::uint8_t junk[] = {0xde, 0xad, 0xbe, 0xef, 0x00, 0x01};
  peer.send_raw(device->local_port(), junk, sizeof(junk));      // foreign magic
  peer.send_raw(device->local_port(), bytes.data(), size - 8);  // truncated state
  bad[4] = 9;
  peer.send_raw(device->local_port(), bad.data(), size);  // unknown version
  bad = bytes;
  bad[6] = 0x80;
  peer.send_raw(device->local_port(), bad.data(), size);  // unknown flag
  bad = bytes;
  for (int i = 24; i < 32; ++i) bad[i] = 0xff;  // x = NaN
  peer.send_raw(device->local_port(), bad.data(), size);
  peer.send(device->local_port(), udp::ForcePacket{});  // HoF never takes forces
  std::array<std::uint8_t, 4000> big{};
  std::memcpy(big.data(), "HOFS", 4);
  peer.send_raw(device->local_port(), big.data(), big.size());  // oversized
  ASSERT_TRUE(eventually([&] { return device->stats().malformed >= before + 7; }));
  // None of them moved the stylus; the next good state does.
  EXPECT_EQ(device->read(0.0).position_m.x(), 0.01);
  EXPECT_EQ(device->health(), DeviceHealth::kOk);
  ASSERT_TRUE(eventually([&] {
    peer.send(device->local_port(), state(2000, 0.04));
    return device->read(0.0).position_m.x() == 0.04;
  }));
}

TEST(UdpDevice, OldAndOutOfOrderStatesAreDropped) {
  auto device = open_udp(1.0);
  ASSERT_TRUE(device);
  Peer peer;
  ASSERT_TRUE(eventually([&] {
    peer.send(device->local_port(), state(50, 0.05));
    return device->read(0.0).valid;
  }));
  const std::uint64_t stale_before = device->stats().stale;
  peer.send(device->local_port(), state(49, 0.02));  // older
  peer.send(device->local_port(), state(50, 0.03));  // repeated
  ASSERT_TRUE(eventually([&] { return device->stats().stale >= stale_before + 2; }));
  EXPECT_EQ(device->read(0.0).position_m.x(), 0.05);
}

TEST(UdpDevice, OnlyTheConfiguredHostIsHeard) {
  auto device = open_udp(1.0, "127.0.0.1");
  ASSERT_TRUE(device);
  Peer stranger("127.0.0.2");
  if (!stranger.ok()) GTEST_SKIP() << "cannot bind 127.0.0.2 here";
  ASSERT_TRUE(eventually([&] {
    stranger.send(device->local_port(), state(1));
    return device->stats().foreign > 0;
  }));
  EXPECT_FALSE(device->read(0.0).valid);
}

TEST(UdpDevice, ASecondSenderCannotTakeTheSessionOver) {
  // Two senders on this machine: the first to send a state has the device; the second (another
  // port) is refused and counted, its positions never read, no force ever sent to it.
  UdpDeviceConfig config;  // no host: a local bridge, loopback only
  config.timeout_s = 0.05;
  auto opened = UdpDevice::open(config);
  ASSERT_TRUE(opened) << opened.error().to_string();
  UdpDevice& device = **opened;
  Peer owner, intruder;
  DeviceReading r;
  ASSERT_TRUE(stream_until_valid(device, owner, 1, r));
  device.write_force(Vec3(0.5, 0.0, 0.0), Vec3::Zero());
  udp::StatePacket hijack = state(1000000);
  hijack.position_m = Vec3(9.0, 9.0, 9.0);
  ASSERT_TRUE(eventually([&] {
    intruder.send(device.local_port(), hijack);
    intruder.send(device.local_port(), udp::HelloPacket{});
    return device.stats().other_sender >= 4;
  }));
  EXPECT_NE(device.read(0.0).position_m, hijack.position_m);
  EXPECT_FALSE(intruder.receive_force(20)) << "a force went to the second sender";
  // ... also after the owner falls silent (timed out): the session stays the owner's.
  ASSERT_TRUE(eventually([&] { return device.health() == DeviceHealth::kTimedOut; }));
  for (int i = 0; i < 5; ++i) intruder.send(device.local_port(), state(static_cast<std::uint32_t>(i)));
  EXPECT_FALSE(intruder.receive_force(20));
  EXPECT_EQ(device.health(), DeviceHealth::kTimedOut);
  // The owner comes back (same port, sequence restarted) and has it again.
  ASSERT_TRUE(stream_until_valid(device, owner, 0, r));
  EXPECT_EQ(device.health(), DeviceHealth::kOk);
}

TEST(UdpDevice, ALocalBridgeListensOnLoopbackOnly) {
  UdpDeviceConfig config;
  auto opened = UdpDevice::open(config);
  ASSERT_TRUE(opened) << opened.error().to_string();
  // A datagram to the port on another local address (not loopback's 127.0.0.1) finds nobody.
  Peer stranger("127.0.0.2");
  if (!stranger.ok()) GTEST_SKIP() << "cannot bind 127.0.0.2 here";
  const int fd = ::socket(AF_INET, SOCK_DGRAM | SOCK_CLOEXEC, 0);
  ASSERT_GE(fd, 0);
  sockaddr_in local{};
  local.sin_family = AF_INET;
  local.sin_port = htons((*opened)->local_port());
  ::inet_pton(AF_INET, "127.0.0.2", &local.sin_addr);  // the port on 127.0.0.2: not bound there
  std::array<std::uint8_t, udp::kMaxPacketSize> bytes{};
  const std::size_t size = udp::encode(state(1), bytes);
  for (int i = 0; i < 5; ++i)
    ::sendto(fd, bytes.data(), size, 0, reinterpret_cast<const sockaddr*>(&local), sizeof(local));
  ::close(fd);
  std::this_thread::sleep_for(std::chrono::milliseconds(30));
  EXPECT_EQ((*opened)->stats().datagrams, 0u);
}

TEST(UdpDevice, HelloSetsTheSpecWhenOpenWaitsForIt) {
  // Find a free port, then let a peer thread greet it while open() waits.
  std::uint16_t port = 0;
  {
    auto probe = open_udp();
    ASSERT_TRUE(probe);
    port = probe->local_port();
  }
  Peer peer;
  std::atomic<bool> stop{false};
  std::thread greeter([&] {
    udp::HelloPacket h;
    h.max_force_n = 3.3;
    h.max_stiffness_n_per_m = 400.0;
    std::memcpy(h.model.data(), "touch", 5);
    while (!stop.load()) {
      peer.send(port, h);
      std::this_thread::sleep_for(std::chrono::milliseconds(2));
    }
  });
  UdpDeviceConfig greeted;
  greeted.host = "127.0.0.1";
  greeted.port = port;
  greeted.hello_wait_s = 5.0;
  auto device = UdpDevice::open(greeted);
  stop = true;
  greeter.join();
  ASSERT_TRUE(device) << device.error().to_string();
  EXPECT_EQ((*device)->spec().model, "touch");
  EXPECT_EQ((*device)->spec().max_force_n, 3.3);
  EXPECT_EQ((*device)->spec().max_stiffness_n_per_m, 400.0);
  EXPECT_TRUE(dynamic_cast<UdpDevice&>(**device).last_hello().has_value());
}

TEST(UdpDevice, CloseReturnsPromptlyAndSendsAFinalZeroForce) {
  auto device = open_udp(1.0);
  ASSERT_TRUE(device);
  Peer peer;
  DeviceReading r;
  device->write_force(Vec3(1, 0, 0), Vec3::Zero());
  ASSERT_TRUE(stream_until_valid(*device, peer, 1, r));
  const auto start = Clock::now();
  device->close();
  device->close();  // idempotent
  EXPECT_LT(Clock::now() - start, kDeadline);
  std::optional<udp::ForcePacket> last;
  ASSERT_TRUE(eventually([&] {
    while (auto f = peer.receive_force(1)) last = f;
    return last && last->closing;
  }));
  EXPECT_EQ(last->force_n, Vec3::Zero());

  // A port already taken cannot be opened twice.
  auto holder = open_udp();
  ASSERT_TRUE(holder);
  UdpDeviceConfig same_port;
  same_port.port = holder->local_port();
  auto second = UdpDevice::open(same_port);
  ASSERT_FALSE(second);
  EXPECT_NE(second.error().message.find("cannot bind the UDP port"), std::string::npos) << second.error().message;
}

// ---------------------------------------------------------------------------------------
// The authenticated protocol (version 2): a shared key, a session per hello, HMAC-SHA256

udp::Key test_key(std::uint8_t seed) {
  udp::Key key{};
  for (std::size_t i = 0; i < key.size(); ++i) key[i] = static_cast<std::uint8_t>(seed + 7 * i);
  return key;
}

/// What a sealed datagram holds once its tag checks out with `key`.
struct Unsealed {
  std::vector<std::uint8_t> body;
  std::uint64_t session{0};
};
std::optional<Unsealed> unseal(const std::vector<std::uint8_t>& bytes, const udp::Key& key) {
  Unsealed u;
  u.body.resize(udp::kMaxPacketSize);
  const std::size_t size = udp::unseal(bytes, key, u.session, u.body);
  if (size == 0) return std::nullopt;
  u.body.resize(size);
  return u;
}

TEST(UdpProtocol, ASealedPacketRoundTripsAndAnyChangedByteIsRefused) {
  const udp::Key key = test_key(1);
  std::array<std::uint8_t, udp::kMaxPacketSize> bytes{};
  const std::size_t plain = udp::encode(state(42), bytes);
  const std::size_t size = udp::seal(bytes, plain, 0x1122334455667788ULL, key);
  ASSERT_EQ(size, udp::kStateWithVelocitySize + udp::kAuthTrailerSize);
  EXPECT_EQ(bytes[4], 2);  // version 2 on the wire
  const std::vector<std::uint8_t> sealed(bytes.begin(), bytes.begin() + static_cast<std::ptrdiff_t>(size));
  auto opened = unseal(sealed, key);
  ASSERT_TRUE(opened);
  EXPECT_EQ(opened->session, 0x1122334455667788ULL);
  udp::StatePacket back;
  ASSERT_TRUE(udp::decode(opened->body, back));
  EXPECT_EQ(back.sequence, 42u);
  // Every single changed byte (body, session or tag), a wrong key, a cut or a version-1
  // packet: refused.
  for (std::size_t i = 0; i < sealed.size(); ++i) {
    std::vector<std::uint8_t> forged = sealed;
    forged[i] ^= 0x01;
    EXPECT_FALSE(unseal(forged, key)) << "byte " << i;
  }
  EXPECT_FALSE(unseal(sealed, test_key(2)));
  EXPECT_FALSE(unseal(std::vector<std::uint8_t>(sealed.begin(), sealed.end() - 1), key));
  EXPECT_FALSE(
      unseal(std::vector<std::uint8_t>(bytes.begin(), bytes.begin() + static_cast<std::ptrdiff_t>(plain)), key));
}

/// Opens a keyed device on loopback, greets it from `peer` and returns the session of the
/// challenge it answers with (0 if none came).
std::uint64_t handshake(UdpDevice& device, const Peer& peer, const udp::Key& key, std::uint32_t hello_sequence) {
  std::uint64_t session = 0;
  eventually([&] {
    udp::HelloPacket h;
    h.sequence = hello_sequence;
    peer.send_sealed(device.local_port(), h, 0, key);
    while (auto raw = peer.receive_raw(5)) {
      auto u = unseal(*raw, key);
      udp::ChallengePacket c;
      if (u && udp::decode(u->body, c) && c.echo_sequence == hello_sequence) session = u->session;
    }
    return session != 0;
  });
  return session;
}

std::unique_ptr<UdpDevice> open_keyed(const udp::Key& key, double timeout_s = 1.0) {
  UdpDeviceConfig config;
  config.timeout_s = timeout_s;
  config.key = key;
  auto d = UdpDevice::open(config);
  EXPECT_TRUE(d) << d.error().to_string();
  return d ? std::move(*d) : nullptr;
}

TEST(UdpDevice, WithAKeyOnlyAuthenticatedStatesOfTheSessionDriveTheDevice) {
  const udp::Key key = test_key(3);
  auto device = open_keyed(key);
  ASSERT_TRUE(device);
  device->write_force(Vec3(0.25, 0.0, 0.0), Vec3::Zero());
  Peer bridge, forger;
  // Plain (version 1) states and states sealed with another key are refused and never answered.
  ASSERT_TRUE(eventually([&] {
    forger.send(device->local_port(), state(1));
    forger.send_sealed(device->local_port(), state(2), 0, test_key(9));
    return device->stats().unauthenticated >= 4;
  }));
  EXPECT_FALSE(device->read(0.0).valid);
  EXPECT_FALSE(forger.receive_raw(20)) << "HoF answered an unauthenticated sender";

  // The bridge: hello → challenge (a session) → sealed states of that session are read, and the
  // force comes back sealed for that session.
  const std::uint64_t session = handshake(*device, bridge, key, 7);
  ASSERT_NE(session, 0u);
  std::optional<udp::ForcePacket> force;
  std::uint32_t seq = 1;
  ASSERT_TRUE(eventually([&] {
    bridge.send_sealed(device->local_port(), state(seq++, 0.02), session, key);
    while (auto raw = bridge.receive_raw(2)) {
      auto u = unseal(*raw, key);
      udp::ForcePacket f;
      if (u && u->session == session && udp::decode(u->body, f)) force = f;
    }
    return force.has_value() && device->read(0.0).valid;
  }));
  EXPECT_DOUBLE_EQ(device->read(0.0).position_m.x(), 0.02);
  EXPECT_EQ(force->force_n, Vec3(0.25, 0.0, 0.0));
  // A state sealed for no session (0) or a made-up one is refused as a replay.
  const auto replayed_before = device->stats().replayed;
  bridge.send_sealed(device->local_port(), state(seq + 100, 5.0), session + 1, key);
  ASSERT_TRUE(eventually([&] { return device->stats().replayed > replayed_before; }));
  EXPECT_NE(device->read(0.0).position_m.x(), 5.0);
}

TEST(UdpDevice, AReplayedStateIsRefusedInItsSessionAndAfter) {
  const udp::Key key = test_key(4);
  auto device = open_keyed(key, 0.05);
  ASSERT_TRUE(device);
  Peer bridge;
  const std::uint64_t first = handshake(*device, bridge, key, 1);
  ASSERT_NE(first, 0u);
  std::uint32_t seq = 10;
  ASSERT_TRUE(eventually([&] {
    bridge.send_sealed(device->local_port(), state(seq++, 0.01), first, key);
    return device->read(0.0).valid;
  }));
  // A recorded state (an older sequence of this session) sent again: stale, not read.
  udp::StatePacket recorded = state(5, 0.07);
  const auto stale_before = device->stats().stale;
  bridge.send_sealed(device->local_port(), recorded, first, key);
  ASSERT_TRUE(eventually([&] { return device->stats().stale > stale_before; }));
  EXPECT_NE(device->read(0.0).position_m.x(), 0.07);
  // After a timeout the sequence check does not relax (with a key a restarted bridge asks for a
  // new session instead).
  ASSERT_TRUE(eventually([&] { return device->health() == DeviceHealth::kTimedOut; }));
  bridge.send_sealed(device->local_port(), recorded, first, key);
  ASSERT_TRUE(eventually([&] { return device->stats().stale > stale_before + 1; }));
  EXPECT_EQ(device->health(), DeviceHealth::kTimedOut);
  // A new hello starts a new session: everything sealed for the old one is a replay.
  const std::uint64_t second = handshake(*device, bridge, key, 2);
  ASSERT_NE(second, 0u);
  EXPECT_NE(second, first);
  const auto replayed_before = device->stats().replayed;
  bridge.send_sealed(device->local_port(), state(seq + 1000, 0.07), first, key);
  ASSERT_TRUE(eventually([&] { return device->stats().replayed > replayed_before; }));
  EXPECT_NE(device->read(0.0).position_m.x(), 0.07);
  // ... while the new session starts again from any sequence.
  std::uint32_t fresh = 0;
  ASSERT_TRUE(eventually([&] {
    bridge.send_sealed(device->local_port(), state(fresh++, 0.03), second, key);
    return device->read(0.0).valid;
  }));
  EXPECT_DOUBLE_EQ(device->read(0.0).position_m.x(), 0.03);
}

TEST(UdpDevice, ABridgeOnAnotherMachineNeedsAKey) {
  UdpDeviceConfig config;
  config.host = "192.0.2.10";  // TEST-NET-1 (RFC 5737): never a real host
  auto refused = UdpDevice::open(config);
  ASSERT_FALSE(refused);
  EXPECT_NE(refused.error().message.find("key=FILE"), std::string::npos) << refused.error().message;
  config.key = test_key(5);
  auto opened = UdpDevice::open(config);
  ASSERT_TRUE(opened) << opened.error().to_string();
}

TEST(UdpKeyFile, KeygenWritesAPrivateKeyThatReadsBackAndBadFilesAreNamed) {
  const auto dir = std::filesystem::temp_directory_path() / fmt::format("hof-key-{}", ::getpid());
  std::filesystem::create_directories(dir);
  const std::string path = (dir / "bridge.key").string();
  std::filesystem::remove(path);
  ASSERT_TRUE(udp::write_new_key_file(path));
  struct stat info {};
  ASSERT_EQ(::stat(path.c_str(), &info), 0);
  EXPECT_EQ(info.st_mode & 0777U, 0600U);
  auto key = udp::read_key_file(path);
  ASSERT_TRUE(key) << key.error().to_string();
  EXPECT_NE(*key, udp::Key{});
  EXPECT_FALSE(udp::write_new_key_file(path)) << "an existing key was overwritten";
  EXPECT_EQ(*udp::read_key_file(path), *key);
  UdpDeviceConfig keyed;
  keyed.host = "127.0.0.1";
  keyed.key = *key;
  auto device = UdpDevice::open(keyed);
  EXPECT_TRUE(device) << device.error().to_string();

  const auto write = [&](const std::string& name, const std::string& text, unsigned mode) {
    const std::string p = (dir / name).string();
    std::ofstream(p) << text;
    std::filesystem::permissions(p, static_cast<std::filesystem::perms>(mode));
    return p;
  };
  const std::string hex64(64, 'a');
  const auto readable = udp::read_key_file(write("shared.key", hex64, 0644));
  ASSERT_FALSE(readable);
  EXPECT_NE(readable.error().message.find("chmod 600"), std::string::npos) << readable.error().message;
  EXPECT_NE(readable.error().to_string().find("shared.key"), std::string::npos);
  EXPECT_FALSE(udp::read_key_file(write("short.key", std::string(62, 'a'), 0600)));
  EXPECT_FALSE(udp::read_key_file(write("nothex.key", std::string(63, 'a') + "g", 0600)));
  EXPECT_TRUE(udp::read_key_file(write("spaced.key", hex64.substr(0, 32) + "\n" + hex64.substr(32) + "\n", 0600)));
  EXPECT_FALSE(udp::read_key_file(dir.string()));  // a directory
  EXPECT_FALSE(udp::read_key_file((dir / "missing.key").string()));
  std::filesystem::remove_all(dir);
}

}  // namespace
}  // namespace hof::haptics
