#pragma once
// What the mesh file tests share (tests/mesh/io_*_test.cpp, mesh_io_test.cpp): a scratch folder per test,
// byte helpers for hand-made binary files, a sample mesh with everything a writer can store, and
// an error matcher that checks the file name and line.

#include <gtest/gtest.h>
#include <unistd.h>

#include <array>
#include <bit>
#include <cstdint>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <random>
#include <sstream>
#include <string>
#include <string_view>
#include <vector>

#include "hof/mesh/mesh_io.h"

namespace hof::mesh::io_test {

namespace fs = std::filesystem;

// ---------------------------------------------------------------------------------------
// Helpers

inline std::string slurp(const fs::path& path) {
  std::ifstream in(path, std::ios::binary);
  std::ostringstream out;
  out << in.rdbuf();
  return out.str();
}

/// Bitwise comparison of node arrays: == would accept 0.0 vs -0.0.
inline bool same_bits(const std::vector<Vec3>& a, const std::vector<Vec3>& b) {
  if (a.size() != b.size()) return false;
  return a.empty() || std::memcmp(a.data(), b.data(), a.size() * sizeof(Vec3)) == 0;
}

/// Random bytes, the same on every run.
inline std::string garbage(std::size_t size, unsigned seed) {
  std::mt19937 rng(seed);
  std::string bytes(size, '\0');
  for (char& c : bytes) c = static_cast<char>(rng() & 0xff);
  return bytes;
}

/// Little-endian (or swapped) binary helpers for hand-made binary files.
struct Bytes {
  std::string data;
  bool swap{false};
  Bytes& text(std::string_view s) {
    data += s;
    return *this;
  }
  Bytes& i32(std::int32_t v) {
    auto u = static_cast<std::uint32_t>(v);
    if (swap) u = std::byteswap(u);
    data.append(reinterpret_cast<const char*>(&u), 4);
    return *this;
  }
  Bytes& u32(std::uint32_t u) {
    data.append(reinterpret_cast<const char*>(&u), 4);
    return *this;
  }
  Bytes& f64(double v) {
    auto u = std::bit_cast<std::uint64_t>(v);
    if (swap) u = std::byteswap(u);
    data.append(reinterpret_cast<const char*>(&u), 8);
    return *this;
  }
  Bytes& f32(float v) {
    data.append(reinterpret_cast<const char*>(&v), 4);
    return *this;
  }
};

inline const char* const kLiverMsh = HOF_ANCHORS_DIR "/sofa/mesh/liver.msh";
inline const char* const kLiverObj = HOF_ANCHORS_DIR "/sofa/mesh/liver.obj";
inline const char* const kLiverSmoothObj = HOF_ANCHORS_DIR "/sofa/mesh/liver-smooth.obj";

/// Each test gets its own folder under the system temp directory, removed afterwards.
class MeshIoTest : public ::testing::Test {
 protected:
  void SetUp() override {
    const auto* info = ::testing::UnitTest::GetInstance()->current_test_info();
    dir_ = fs::temp_directory_path() /
           ("hof_mesh_io_" + std::to_string(::getpid()) + "_" + info->test_suite_name() + "_" + info->name());
    fs::remove_all(dir_);
    fs::create_directories(dir_);
  }
  void TearDown() override {
    std::error_code ec;
    fs::remove_all(dir_, ec);
  }

  fs::path file(const std::string& name) const { return dir_ / name; }

  fs::path write(const std::string& name, std::string_view content) const {
    const fs::path path = dir_ / name;
    std::ofstream out(path, std::ios::binary);
    out.write(content.data(), static_cast<std::streamsize>(content.size()));
    return path;
  }

  /// Reads `content` stored as `name`; expects failure and returns the error.
  Error read_error(const std::string& name, std::string_view content) const {
    const auto result = read_mesh(write(name, content));
    EXPECT_FALSE(result.has_value()) << name << " was read without error";
    return result ? Error{} : result.error();
  }

  fs::path dir_;
};

/// Asserts the error's code and that its one-line text holds `file:line:` and `fragment`.
inline void expect_error_at(const Error& e, ErrorCode code, const std::string& file_name, std::int64_t line,
                            const std::string& fragment) {
  const std::string text = e.to_string();
  EXPECT_EQ(e.code, code) << text;
  EXPECT_NE(text.find(file_name + ":" + std::to_string(line) + ": "), std::string::npos) << text;
  EXPECT_NE(text.find(fragment), std::string::npos) << text;
}

/// A small mesh with everything a writer can store: two tets and three triangles sharing
/// nodes, regions, normals, coordinates that need all 17 digits, and a negative zero.
inline Mesh sample_mesh() {
  Mesh m;
  m.nodes = {Vec3(0.1, 0.2, 1.0 / 3.0), Vec3(1e-300, -0.0, 2.5), Vec3(1.0, 1e22, -7.125), Vec3(0.0, 0.0, 1.0),
             Vec3(-1.0 / 7.0, 3.0, 4.0)};
  m.tets = {{0, 1, 2, 3}, {1, 2, 3, 4}};
  m.tet_regions = {4, 9};
  m.triangles = {{0, 1, 2}, {1, 2, 4}, {0, 3, 4}};
  m.triangle_regions = {2, 2, 0};
  m.normals = {Vec3(0, 0, 1), Vec3(0, 1, 0), Vec3(1, 0, 0), Vec3(0.6, 0.8, 0), Vec3(0, -1, 0)};
  return m;
}

/// A Gmsh 2.2 binary file: 5 nodes (tags 1..5), a point, two tets in physical 9.
/// `node_count` is the count written in $Nodes, `last_tag` the last node of the second tet.
inline std::string binary_msh(bool swap, int node_count = 5, int last_tag = 5) {
  Bytes b;
  b.swap = swap;
  b.text("$MeshFormat\n2.2 1 8\n").i32(1).text("\n$EndMeshFormat\n$Nodes\n");
  b.text(std::to_string(node_count) + "\n");
  const double coords[5][3] = {{0.1, 0.2, 0.3}, {1.0 / 3.0, 0, 0}, {0, 1, 0}, {0, 0, 1}, {1, 1, 1}};
  for (int i = 0; i < 5; ++i) b.i32(i + 1).f64(coords[i][0]).f64(coords[i][1]).f64(coords[i][2]);
  b.text("\n$EndNodes\n$Elements\n3\n");
  b.i32(15).i32(1).i32(2).i32(1).i32(0).i32(0).i32(1);
  b.i32(4).i32(2).i32(2);
  b.i32(2).i32(9).i32(9).i32(1).i32(2).i32(3).i32(4);
  b.i32(3).i32(9).i32(9).i32(2).i32(3).i32(4).i32(last_tag);
  b.text("\n$EndElements\n");
  return b.data;
}

inline std::string binary_stl(const std::vector<std::array<float, 9>>& triangles,
                              std::string header = "solid binary file whose header starts like ASCII") {
  header.resize(80, ' ');
  Bytes b;
  b.text(header).u32(static_cast<std::uint32_t>(triangles.size()));
  for (const auto& t : triangles) {
    b.f32(0).f32(0).f32(1);
    for (const float v : t) b.f32(v);
    b.text(std::string(2, '\0'));
  }
  return b.data;
}

inline constexpr std::string_view kHeader22 = "$MeshFormat\n2.2 0 8\n$EndMeshFormat\n";

}  // namespace hof::mesh::io_test
