// The UDP protocol's authentication (src/hof/haptics/device_backends/udp_auth.cpp): the HMAC
// tag is HMAC-SHA256 over the header (version 2), body and session (checked against a value
// computed apart, with Python's hmac module), every altered byte or wrong key is refused,
// unsealing gives back the version-1 body, and key files are refused unless private and
// exactly 64 hexadecimal digits.

#include "hof/haptics/device_backends/udp_auth.h"

#include <gtest/gtest.h>
#include <sys/stat.h>

#include <cstdint>
#include <filesystem>
#include <fstream>
#include <string>
#include <vector>

#include "support/temp_dir.h"

namespace hof::haptics::udp {
namespace {

Key counting_key() {
  Key key{};
  for (std::size_t i = 0; i < key.size(); ++i) key[i] = static_cast<std::uint8_t>(i);
  return key;
}

// A version-1 packet: magic "HOFD", version 1, flags 0, then 12 body bytes 100..111.
std::vector<std::uint8_t> packet() {
  std::vector<std::uint8_t> p{'H', 'O', 'F', 'D', 1, 0, 0, 0};
  for (std::uint8_t b = 100; b < 112; ++b) p.push_back(b);
  return p;
}

constexpr std::uint64_t kSession = 0x0102030405060708ULL;

TEST(UdpAuth, TheTagIsHmacSha256OverHeaderBodyAndSession) {
  std::vector<std::uint8_t> buffer = packet();
  const std::size_t size = buffer.size();
  buffer.resize(size + kAuthTrailerSize);
  ASSERT_EQ(seal(buffer, size, kSession, counting_key()), size + kAuthTrailerSize);
  EXPECT_EQ(buffer[4], 2);  // version 2
  EXPECT_EQ(buffer[5], 0);
  for (std::size_t i = 0; i < kSessionSize; ++i) EXPECT_EQ(buffer[size + i], 8 - i);  // little-endian
  // python3: hmac.new(bytes(range(32)), sealed[:-32], hashlib.sha256).hexdigest()
  const std::string expected = "b7c6831c4272ca952a74a677d6a3208c5cc7c57086e9877beef5c01b5d9f7c48";
  std::string tag;
  for (std::size_t i = size + kSessionSize; i < buffer.size(); ++i) {
    static constexpr char kHex[] = "0123456789abcdef";
    tag += kHex[buffer[i] >> 4];
    tag += kHex[buffer[i] & 15];
  }
  EXPECT_EQ(tag, expected);
}

TEST(UdpAuth, UnsealGivesBackTheVersionOneBodyAndTheSession) {
  std::vector<std::uint8_t> buffer = packet();
  const std::size_t size = buffer.size();
  buffer.resize(size + kAuthTrailerSize);
  const std::size_t sealed = seal(buffer, size, kSession, counting_key());
  std::vector<std::uint8_t> body(64, 0xEE);
  std::uint64_t session = 0;
  ASSERT_EQ(unseal(std::span(buffer.data(), sealed), counting_key(), session, body), size);
  EXPECT_EQ(session, kSession);
  body.resize(size);
  EXPECT_EQ(body, packet());
}

TEST(UdpAuth, AnyAlteredByteAWrongKeyOrAWrongSizeIsRefused) {
  std::vector<std::uint8_t> buffer = packet();
  const std::size_t size = buffer.size();
  buffer.resize(size + kAuthTrailerSize);
  const std::size_t sealed = seal(buffer, size, kSession, counting_key());
  std::vector<std::uint8_t> body(64);
  std::uint64_t session = 77;
  for (std::size_t i = 0; i < sealed; ++i) {
    std::vector<std::uint8_t> forged = buffer;
    forged[i] ^= 0x01;
    EXPECT_EQ(unseal(forged, counting_key(), session, body), 0u) << "byte " << i;
  }
  Key other = counting_key();
  other[31] ^= 0x80;
  EXPECT_EQ(unseal(buffer, other, session, body), 0u);
  EXPECT_EQ(unseal(std::span(buffer.data(), sealed - 1), counting_key(), session, body), 0u);  // truncated
  std::vector<std::uint8_t> small(size - 1);
  EXPECT_EQ(unseal(buffer, counting_key(), session, small), 0u);  // no room for the body
  EXPECT_EQ(session, 77u);                                        // untouched by every refusal
  // Sealing needs room for the trailer and at least a header.
  std::vector<std::uint8_t> tight = packet();
  EXPECT_EQ(seal(tight, tight.size(), kSession, counting_key()), 0u);
  EXPECT_EQ(seal(buffer, 7, kSession, counting_key()), 0u);
}

TEST(UdpAuth, SessionsAreRandomAndNeverZero) {
  const std::uint64_t a = random_session(), b = random_session();
  EXPECT_NE(a, 0u);
  EXPECT_NE(b, 0u);
  EXPECT_NE(a, b);  // 2^-64 to fail by chance
}

TEST(UdpAuth, ANewKeyFileIsPrivateReadableAndNeverOverwritten) {
  const hof::testing::TempDir dir;
  const std::string path = (dir.path() / "bridge.key").string();
  ASSERT_TRUE(write_new_key_file(path));
  struct stat info {};
  ASSERT_EQ(::stat(path.c_str(), &info), 0);
  EXPECT_EQ(info.st_mode & 0777U, 0600U);
  EXPECT_EQ(std::filesystem::file_size(path), 65u);  // 64 digits and a newline
  const auto key = read_key_file(path);
  ASSERT_TRUE(key) << key.error().to_string();
  const auto again = write_new_key_file(path);
  ASSERT_FALSE(again);
  EXPECT_EQ(again.error().code, ErrorCode::kIo);
  EXPECT_EQ(read_key_file(path).value(), *key);  // the first key is still there
}

TEST(UdpAuth, KeyFilesThatAreSharedShortOrNotHexAreRefusedNamingTheFile) {
  const hof::testing::TempDir dir;
  const auto write_key = [&](const std::string& name, const std::string& text, unsigned mode) {
    const std::string path = (dir.path() / name).string();
    std::ofstream(path) << text;
    ::chmod(path.c_str(), mode);
    return path;
  };
  const std::string digits = "000102030405060708090a0b0c0d0e0f101112131415161718191a1b1c1d1e1f";
  const auto good =
      read_key_file(write_key("good.key", "  " + digits.substr(0, 32) + "\n" + digits.substr(32) + "\n", 0600));
  ASSERT_TRUE(good) << good.error().to_string();
  EXPECT_EQ(*good, counting_key());
  const auto shared = read_key_file(write_key("shared.key", digits, 0640));
  ASSERT_FALSE(shared);
  EXPECT_EQ(shared.error().code, ErrorCode::kInvalidArgument);
  EXPECT_NE(shared.error().to_string().find("chmod 600"), std::string::npos);
  EXPECT_NE(shared.error().to_string().find("shared.key"), std::string::npos);
  const auto short_key = read_key_file(write_key("short.key", digits.substr(2), 0600));
  ASSERT_FALSE(short_key);
  EXPECT_EQ(short_key.error().code, ErrorCode::kParse);
  EXPECT_NE(short_key.error().to_string().find("this file holds 62 characters"), std::string::npos);
  const auto not_hex = read_key_file(write_key("nothex.key", "zz" + digits.substr(2), 0600));
  ASSERT_FALSE(not_hex);
  EXPECT_EQ(not_hex.error().code, ErrorCode::kParse);
  const auto missing = read_key_file((dir.path() / "none.key").string());
  ASSERT_FALSE(missing);
  EXPECT_EQ(missing.error().code, ErrorCode::kIo);
}

}  // namespace
}  // namespace hof::haptics::udp
