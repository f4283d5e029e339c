#pragma once
/// @file
/// The UDP bridge device (spec `udp:[HOST:]PORT[,timeout=S][,hello_wait=S]`): a program
/// around any vendor SDK sends the device state as datagrams and receives the force to
/// render. The byte layout is in docs/device-protocol.md; the encode/decode helpers here
/// implement it (little-endian, fixed sizes) and are public so bridges and tests written in
/// C++ can reuse them.
///
/// Threads: UdpDevice owns one receiver thread that poll()s the socket and a self-pipe,
/// validates datagrams, publishes accepted states through a SeqLock and answers every
/// accepted state with the latest force (also through a SeqLock). read() and write_force()
/// only touch those SeqLocks and atomics: no allocation, lock, system call or blocking.

#include <array>
#include <atomic>
#include <cstddef>
#include <cstdint>
#include <cstring>
#include <memory>
#include <optional>
#include <span>
#include <string>
#include <type_traits>

#include "hof/haptics/device.h"
#include "hof/haptics/device_backends/udp_auth.h"

namespace hof::haptics {

// ---------------------------------------------------------------------------------------
// SeqLock: one writer publishes a small trivially copyable value, readers take consistent
// copies without locking (sequence lock; the payload is stored in atomic words so concurrent
// access is well defined; on x86 every access below compiles to a plain move).

template <class T>
requires std::is_trivially_copyable_v<T>
class SeqLock {
 public:
  /// Publishes `value`. Single writer only. Wait-free.
  void store(const T& value) noexcept {
    std::array<std::uint64_t, kWords> raw{};
    std::memcpy(raw.data(), &value, sizeof(T));
    // The odd count is visible before any word changes (release on the words keeps the
    // count store ahead of them); the even count publishes them.
    const std::uint32_t s = seq_.load(std::memory_order_relaxed);
    seq_.store(s + 1, std::memory_order_relaxed);
    for (std::size_t i = 0; i < kWords; ++i) words_[i].store(raw[i], std::memory_order_release);
    seq_.store(s + 2, std::memory_order_release);
  }
  /// Copies the latest value into `out`; retries at most `attempts` times while a store is
  /// in progress and returns false (out unchanged) if it never saw a consistent value.
  bool try_load(T& out, int attempts = 64) const noexcept {
    for (int a = 0; a < attempts; ++a) {
      const std::uint32_t s1 = seq_.load(std::memory_order_acquire);
      if (s1 & 1U) continue;
      // Acquire on the words keeps the second count load after them (Boehm, "Can seqlocks
      // get along with programming language memory models?", MSPC 2012).
      std::array<std::uint64_t, kWords> raw{};
      for (std::size_t i = 0; i < kWords; ++i) raw[i] = words_[i].load(std::memory_order_acquire);
      if (seq_.load(std::memory_order_relaxed) == s1) {
        std::memcpy(static_cast<void*>(&out), raw.data(), sizeof(T));
        return true;
      }
    }
    return false;
  }
  /// Number of completed stores.
  [[nodiscard]] std::uint32_t version() const noexcept { return seq_.load(std::memory_order_acquire) / 2; }

 private:
  static constexpr std::size_t kWords = (sizeof(T) + 7) / 8;
  std::atomic<std::uint32_t> seq_{0};
  std::array<std::atomic<std::uint64_t>, kWords> words_{};
};

// ---------------------------------------------------------------------------------------
// Wire protocol (docs/device-protocol.md)

namespace udp {

inline constexpr std::uint16_t kVersion = 1;
inline constexpr std::size_t kStateSize = 80;               ///< 'HOFS' without velocity
inline constexpr std::size_t kStateWithVelocitySize = 104;  ///< 'HOFS' with velocity
inline constexpr std::size_t kHelloSize = 88;               ///< 'HOFH'
inline constexpr std::size_t kForceSize = 64;               ///< 'HOFF'
inline constexpr std::size_t kChallengeSize = 16;           ///< 'HOFC' (version 2 only)
/// The largest datagram of either version (a sealed state with velocity).
inline constexpr std::size_t kMaxPacketSize = kStateWithVelocitySize + kAuthTrailerSize;
inline constexpr std::size_t kModelNameSize = 32;

inline constexpr std::uint16_t kStateHasVelocity = 1U << 0;  ///< state flag: velocity follows
inline constexpr std::uint16_t kForceFinal = 1U << 0;        ///< force flag: HoF is closing

/// Device → HoF, one per servo tick ('HOFS').
struct StatePacket {
  std::uint32_t sequence{0};      ///< increments by one per packet (wraps at 2³²)
  double device_time_s{0.0};      ///< the device's own clock
  Vec3 position_m{Vec3::Zero()};  ///< device frame (x right, y up, z toward the user)
  Eigen::Quaterniond orientation{Eigen::Quaterniond::Identity()};
  bool has_velocity{false};
  Vec3 velocity_m_per_s{Vec3::Zero()};
  std::uint32_t buttons{0};  ///< bit 0 = main button
};

/// Device → HoF, at start and from time to time ('HOFH'): what the device can do.
/// A value ≤ 0 means "not stated" (HoF keeps its own).
struct HelloPacket {
  std::uint32_t sequence{0};
  double max_force_n{0.0};
  double max_stiffness_n_per_m{0.0};
  double max_damping_n_s_per_m{0.0};
  double workspace_radius_m{0.0};
  double nominal_rate_hz{0.0};
  std::array<char, kModelNameSize> model{};  ///< UTF-8, NUL-padded
};

/// HoF → device, in answer to each accepted state ('HOFF').
struct ForcePacket {
  std::uint32_t echo_sequence{0};  ///< sequence of the latest state HoF accepted
  std::uint32_t sequence{0};       ///< HoF's own counter
  Vec3 force_n{Vec3::Zero()};      ///< device frame, already safety-clamped
  Vec3 torque_n_m{Vec3::Zero()};
  bool closing{false};  ///< HoF is closing: render zero and stop waiting
};

/// HoF → bridge, version 2 only ('HOFC'): the answer to an authenticated hello. Its sealed
/// trailer carries the new session nonce, which every later state must carry.
struct ChallengePacket {
  std::uint32_t echo_sequence{0};  ///< sequence of the hello it answers
};

/// The packet kinds, told apart by their magic.
enum class PacketType : std::uint8_t { kState, kHello, kForce, kChallenge, kUnknown };

/// Which packet `bytes` claims to be (by its magic); kUnknown when too short or foreign.
[[nodiscard]] PacketType packet_type(std::span<const std::uint8_t> bytes);

/// Encoders write the packet into `out` and return its size (0 if `out` is too small).
std::size_t encode(const StatePacket& packet, std::span<std::uint8_t> out);
std::size_t encode(const HelloPacket& packet, std::span<std::uint8_t> out);
std::size_t encode(const ForcePacket& packet, std::span<std::uint8_t> out);
std::size_t encode(const ChallengePacket& packet, std::span<std::uint8_t> out);

/// Decoders check magic, version, exact size, flags and that every number is finite (and the
/// quaternion non-zero: it is normalised). They return false for a malformed packet.
[[nodiscard]] bool decode(std::span<const std::uint8_t> bytes, StatePacket& out);
[[nodiscard]] bool decode(std::span<const std::uint8_t> bytes, HelloPacket& out);
[[nodiscard]] bool decode(std::span<const std::uint8_t> bytes, ForcePacket& out);
[[nodiscard]] bool decode(std::span<const std::uint8_t> bytes, ChallengePacket& out);

/// True when sequence `a` is newer than `b` in wrap-around (serial number) arithmetic.
[[nodiscard]] constexpr bool newer(std::uint32_t a, std::uint32_t b) { return static_cast<std::int32_t>(a - b) > 0; }

/// The spec `base` with the stated fields of `hello` applied.
[[nodiscard]] DeviceSpec apply_hello(const DeviceSpec& base, const HelloPacket& hello);

}  // namespace udp

// ---------------------------------------------------------------------------------------
// The device

/// Where UdpDevice listens and how it judges freshness (from the spec `udp:...`).
struct UdpDeviceConfig {
  /// Empty: the bridge runs on this machine — HoF listens on the loopback address only, so no
  /// other host can reach the port. Else the bridge's IPv4 host: HoF listens on every
  /// interface and takes datagrams from that host only.
  std::string host;
  std::uint16_t port{0};     ///< UDP port HoF listens on; 0 picks a free one (local_port())
  double timeout_s{0.1};     ///< no accepted state for this long (counted from open()) →
                             ///< kTimedOut, readings invalid; the next state recovers
  double hello_wait_s{0.0};  ///< open() waits up to this long for a hello to set spec()
  DeviceSpec spec{};         ///< spec until (and unless) a hello arrives within hello_wait_s
  /// Set: the authenticated protocol (version 2) — only sealed datagrams with a valid tag are
  /// read, forces go out sealed. Required when `host` is not a loopback address.
  std::optional<udp::Key> key;
};

/// Counters kept by the receiver thread (relaxed, for diagnostics).
struct UdpDeviceStats {
  std::uint64_t datagrams{0};  ///< everything received
  std::uint64_t states{0};     ///< states accepted
  std::uint64_t hellos{0};
  std::uint64_t stale{0};      ///< states dropped: sequence not newer than the last accepted
  std::uint64_t malformed{0};  ///< bad magic, version, size, flags or numbers
  std::uint64_t foreign{0};    ///< from a host other than the configured one
  /// From a second sender once the first has the session (another address or port): refused,
  /// never takes over — no one else drives the device or receives its forces.
  std::uint64_t other_sender{0};
  std::uint64_t unauthenticated{0};  ///< with a key: no valid tag (forged, corrupted, or version 1)
  std::uint64_t replayed{0};         ///< with a key: a state of another (older) session
  std::uint64_t forces_sent{0};
  std::uint64_t send_errors{0};
};

/// The HoF end of the bridge: the device state comes from datagrams, the force goes back
/// in answer to each state. health(): kOk while states arrive, kTimedOut after timeout_s
/// of silence, kFailed if the socket fails.
class UdpDevice final : public Device {
 public:
  /// Binds the port, resolves the host and starts the receiver thread. Errors (kIo or
  /// kInvalidArgument): socket/bind failure (port in use), unknown host, bad timeout, a
  /// remote (non-loopback) host without a key.
  [[nodiscard]] static Expected<std::unique_ptr<UdpDevice>> open(const UdpDeviceConfig& config);
  ~UdpDevice() override;

  [[nodiscard]] const DeviceSpec& spec() const override { return spec_; }
  [[nodiscard]] std::string_view backend() const override { return "udp"; }
  /// The latest accepted state (time_s is the device's clock). valid only while health() is
  /// kOk and a state has arrived. Without velocity in the packets, velocity is the backward
  /// difference of the last two positions over their device times.
  DeviceReading read(double time_s) override;
  /// Stores the force sent in answer to the next state (non-finite → zero).
  void write_force(const Vec3& force_n, const Vec3& torque_n_m) override;
  [[nodiscard]] DeviceHealth health() const override;
  /// Stops and joins the receiver (woken through a self-pipe), then sends a final zero
  /// force to the last peer. Idempotent.
  void close() override;

  /// The port actually bound (useful with port 0).
  [[nodiscard]] std::uint16_t local_port() const;
  [[nodiscard]] UdpDeviceStats stats() const;
  /// The latest hello received, if any (may arrive after open; spec() is fixed at open).
  [[nodiscard]] std::optional<udp::HelloPacket> last_hello() const;

 private:
  struct Impl;
  explicit UdpDevice(std::unique_ptr<Impl> impl, const DeviceSpec& spec);
  std::unique_ptr<Impl> impl_;
  DeviceSpec spec_;
};

}  // namespace hof::haptics
