#include "hof/haptics/device_backends/udp_auth.h"

#include <fcntl.h>
#include <sodium.h>
#include <sys/stat.h>
#include <unistd.h>

#include <fmt/format.h>

#include <cerrno>
#include <cstring>
#include <fstream>
#include <sstream>

namespace hof::haptics::udp {
namespace {

constexpr std::size_t kHeaderSize = 8;  // magic, version, flags
static_assert(crypto_auth_hmacsha256_BYTES == kTagSize);
static_assert(crypto_auth_hmacsha256_KEYBYTES == kKeySize);

// sodium_init() is idempotent and thread-safe; it must run before randombytes and HMAC.
bool sodium_ready() {
  static const bool ready = sodium_init() >= 0;
  return ready;
}

std::uint16_t version_of(std::span<const std::uint8_t> bytes) {
  return static_cast<std::uint16_t>(bytes[4] | (bytes[5] << 8));
}

void set_version(std::span<std::uint8_t> bytes, std::uint16_t version) {
  bytes[4] = static_cast<std::uint8_t>(version & 0xFFU);
  bytes[5] = static_cast<std::uint8_t>(version >> 8);
}

}  // namespace

Expected<Key> read_key_file(const std::string& path) {
  struct stat info {};
  if (::stat(path.c_str(), &info) != 0) {
    return make_error(ErrorCode::kIo, fmt::format("cannot read the key: {}", std::strerror(errno)), path);
  }
  if (!S_ISREG(info.st_mode)) return make_error(ErrorCode::kIo, "the key is not a regular file", path);
  if ((info.st_mode & (S_IRWXG | S_IRWXO)) != 0) {
    return make_error(
        ErrorCode::kInvalidArgument,
        fmt::format("the key may be read by other users (mode {:o}); run: chmod 600 {}", info.st_mode & 0777U, path),
        path);
  }
  std::ifstream in(path);
  std::stringstream text;
  text << in.rdbuf();
  if (!in) return make_error(ErrorCode::kIo, "cannot read the key", path);
  std::string hex;
  for (const char c : text.str()) {
    if (c == ' ' || c == '\t' || c == '\n' || c == '\r') continue;
    hex.push_back(c);
  }
  if (hex.size() != 2 * kKeySize) {
    return make_error(ErrorCode::kParse,
                      fmt::format("a key is {} hexadecimal digits, this file holds {} characters (make one with "
                                  "`hof device keygen FILE`)",
                                  2 * kKeySize, hex.size()),
                      path, 1);
  }
  Key key{};
  std::size_t decoded = 0;
  if (sodium_hex2bin(key.data(), key.size(), hex.data(), hex.size(), nullptr, &decoded, nullptr) != 0 ||
      decoded != kKeySize) {
    return make_error(ErrorCode::kParse, "the key holds a character that is not a hexadecimal digit", path, 1);
  }
  return key;
}

Expected<void> write_new_key_file(const std::string& path) {
  if (!sodium_ready()) return make_error(ErrorCode::kIo, "libsodium could not start", path);
  // O_EXCL: never overwrite a key a bridge may already use; 0600 from the first byte.
  const int fd = ::open(path.c_str(), O_WRONLY | O_CREAT | O_EXCL | O_CLOEXEC, 0600);
  if (fd < 0) return make_error(ErrorCode::kIo, fmt::format("cannot create the key: {}", std::strerror(errno)), path);
  Key key{};
  randombytes_buf(key.data(), key.size());
  std::array<char, 2 * kKeySize + 1> hex{};
  sodium_bin2hex(hex.data(), hex.size(), key.data(), key.size());
  sodium_memzero(key.data(), key.size());
  std::string line(hex.data());
  line.push_back('\n');
  const ssize_t written = ::write(fd, line.data(), line.size());
  const bool synced = ::fsync(fd) == 0;
  ::close(fd);
  if (written != static_cast<ssize_t>(line.size()) || !synced) {
    ::unlink(path.c_str());
    return make_error(ErrorCode::kIo, "cannot write the key", path);
  }
  return {};
}

std::uint64_t random_session() {
  if (!sodium_ready()) return 1;  // cannot happen on Linux (getrandom); stays authenticated
  std::uint64_t session = 0;
  while (session == 0) randombytes_buf(&session, sizeof(session));
  return session;
}

std::size_t seal(std::span<std::uint8_t> buffer, std::size_t size, std::uint64_t session, const Key& key) {
  if (size < kHeaderSize || buffer.size() < size + kAuthTrailerSize || !sodium_ready()) return 0;
  set_version(buffer, kAuthVersion);
  for (std::size_t i = 0; i < kSessionSize; ++i) buffer[size + i] = static_cast<std::uint8_t>(session >> (8 * i));
  const std::size_t covered = size + kSessionSize;
  crypto_auth_hmacsha256(buffer.data() + covered, buffer.data(), covered, key.data());
  return covered + kTagSize;
}

std::size_t unseal(std::span<const std::uint8_t> bytes, const Key& key, std::uint64_t& session,
                   std::span<std::uint8_t> body) {
  if (bytes.size() < kHeaderSize + kAuthTrailerSize || version_of(bytes) != kAuthVersion || !sodium_ready()) return 0;
  const std::size_t covered = bytes.size() - kTagSize;
  const std::size_t body_size = covered - kSessionSize;
  if (body.size() < body_size) return 0;
  if (crypto_auth_hmacsha256_verify(bytes.data() + covered, bytes.data(), covered, key.data()) != 0) return 0;
  std::uint64_t s = 0;
  for (std::size_t i = 0; i < kSessionSize; ++i) s |= static_cast<std::uint64_t>(bytes[body_size + i]) << (8 * i);
  std::memcpy(body.data(), bytes.data(), body_size);
  set_version(body, 1);
  session = s;
  return body_size;
}

}  // namespace hof::haptics::udp
