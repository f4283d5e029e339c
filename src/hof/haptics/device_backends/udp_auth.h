#pragma once
/// @file
/// Authentication of the UDP device protocol, version 2 (docs/device-protocol.md): a bridge
/// on another machine shares a 256-bit key with HoF; every datagram carries the session
/// nonce HoF issued and an HMAC-SHA256 tag over its bytes (RFC 2104 / FIPS 198-1, computed
/// by libsodium), so no host without the key can drive the device or read its forces, and a
/// recorded datagram replayed later is refused (old session, or sequence not newer).

#include <array>
#include <cstddef>
#include <cstdint>
#include <span>
#include <string>

#include "hof/core/error.h"

namespace hof::haptics::udp {

inline constexpr std::uint16_t kAuthVersion = 2;
inline constexpr std::size_t kKeySize = 32;     ///< HMAC-SHA256 key, bytes
inline constexpr std::size_t kSessionSize = 8;  ///< session nonce, bytes (u64 little-endian)
inline constexpr std::size_t kTagSize = 32;     ///< HMAC-SHA256 tag, bytes
inline constexpr std::size_t kAuthTrailerSize = kSessionSize + kTagSize;

/// The shared secret of HoF and one remote bridge.
using Key = std::array<std::uint8_t, kKeySize>;

/// Reads a key file: 64 hexadecimal digits (whitespace and a trailing newline allowed), as
/// `hof device keygen` writes it. Refuses a file that other users may read (like ssh), a
/// key of the wrong length, and non-hex characters, naming the file.
[[nodiscard]] Expected<Key> read_key_file(const std::string& path);

/// Writes a new random key to `path` with mode 0600; refuses to overwrite an existing file.
[[nodiscard]] Expected<void> write_new_key_file(const std::string& path);

/// A random session nonce (never 0: 0 means "no session").
[[nodiscard]] std::uint64_t random_session();

/// Seals the version-1 packet in `buffer[0, size)` in place: its version field becomes 2 and
/// the session nonce and the HMAC tag (over every byte before the tag) are appended. Returns
/// the sealed size, or 0 if `buffer` is too small or `size` is shorter than a header.
std::size_t seal(std::span<std::uint8_t> buffer, std::size_t size, std::uint64_t session, const Key& key);

/// Checks a sealed packet: size, version 2 and the tag (in constant time). On success it
/// copies the packet body into `body` with its version field set back to 1 (so the version-1
/// decoders read it), stores the session nonce and returns the body size; else returns 0.
std::size_t unseal(std::span<const std::uint8_t> bytes, const Key& key, std::uint64_t& session,
                   std::span<std::uint8_t> body);

}  // namespace hof::haptics::udp
