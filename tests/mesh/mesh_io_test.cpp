// Tests of hof/mesh/mesh_io.h: real third-party files read in place, exact round trips
// through every writable format, small inline files for each reader feature, and one test
// per kind of bad input, matching the message, file name and line.

#include "hof/mesh/mesh_io.h"

#include <gtest/gtest.h>
#include <unistd.h>

#include <bit>
#include <chrono>
#include <cstdint>
#include <cstring>
#include <fstream>
#include <random>
#include <sstream>
#include <string>
#include <vector>

namespace hof::mesh {
namespace {

namespace fs = std::filesystem;

// ---------------------------------------------------------------------------------------
// Helpers

std::string slurp(const fs::path& path) {
  std::ifstream in(path, std::ios::binary);
  std::ostringstream out;
  out << in.rdbuf();
  return out.str();
}

/// Bitwise comparison of node arrays: == would accept 0.0 vs -0.0.
bool same_bits(const std::vector<Vec3>& a, const std::vector<Vec3>& b) {
  if (a.size() != b.size()) return false;
  return a.empty() || std::memcmp(a.data(), b.data(), a.size() * sizeof(Vec3)) == 0;
}

/// Random bytes, the same on every run.
std::string garbage(std::size_t size, unsigned seed) {
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

const char* const kLiverMsh = HOF_ANCHORS_DIR "/sofa/mesh/liver.msh";
const char* const kLiverObj = HOF_ANCHORS_DIR "/sofa/mesh/liver.obj";
const char* const kLiverSmoothObj = HOF_ANCHORS_DIR "/sofa/mesh/liver-smooth.obj";

/// Each test gets its own folder under the system temp directory, removed afterwards.
class MeshIoTest : public ::testing::Test {
 protected:
  void SetUp() override {
    const auto* info = ::testing::UnitTest::GetInstance()->current_test_info();
    dir_ = fs::temp_directory_path() /
           ("hof_mesh_io_" + std::to_string(::getpid()) + "_" + info->test_suite_name() + "_" +
            info->name());
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
void expect_error_at(const Error& e, ErrorCode code, const std::string& file_name,
                     std::int64_t line, const std::string& fragment) {
  const std::string text = e.to_string();
  EXPECT_EQ(e.code, code) << text;
  EXPECT_NE(text.find(file_name + ":" + std::to_string(line) + ": "), std::string::npos) << text;
  EXPECT_NE(text.find(fragment), std::string::npos) << text;
}

/// A small mesh with everything a writer can store: two tets and three triangles sharing
/// nodes, regions, normals, coordinates that need all 17 digits, and a negative zero.
Mesh sample_mesh() {
  Mesh m;
  m.nodes = {Vec3(0.1, 0.2, 1.0 / 3.0), Vec3(1e-300, -0.0, 2.5), Vec3(1.0, 1e22, -7.125),
             Vec3(0.0, 0.0, 1.0),       Vec3(-1.0 / 7.0, 3.0, 4.0)};
  m.tets = {{0, 1, 2, 3}, {1, 2, 3, 4}};
  m.tet_regions = {4, 9};
  m.triangles = {{0, 1, 2}, {1, 2, 4}, {0, 3, 4}};
  m.triangle_regions = {2, 2, 0};
  m.normals = {Vec3(0, 0, 1), Vec3(0, 1, 0), Vec3(1, 0, 0), Vec3(0.6, 0.8, 0), Vec3(0, -1, 0)};
  return m;
}

// ---------------------------------------------------------------------------------------
// Third-party files, read in place

TEST(MeshIoAnchors, LiverMshIsGmshV1With181NodesAnd596Tets) {
  const auto r = read_mesh(kLiverMsh);
  ASSERT_TRUE(r) << r.error().to_string();
  EXPECT_EQ(r->report.format, "gmsh-1");
  EXPECT_EQ(r->mesh.nodes.size(), 181u);
  EXPECT_EQ(r->mesh.tets.size(), 596u);
  EXPECT_TRUE(r->mesh.triangles.empty());
  EXPECT_EQ(r->mesh.tet_regions, std::vector<std::int32_t>(596, 1));
  EXPECT_EQ(r->mesh.nodes.front(), Vec3(-0.979259, 2.23512, 2.61245));
  // "1 4 1 1 4 128 141 138 142": tags are 1-based, indices 0-based.
  EXPECT_EQ(r->mesh.tets.front(), (Tet{127, 140, 137, 141}));
  EXPECT_EQ(r->mesh.tets.back(), (Tet{145, 21, 7, 5}));
  EXPECT_TRUE(r->report.warnings.empty());
}

TEST(MeshIoAnchors, LiverObjHas181VerticesAnd274Triangles) {
  const auto r = read_mesh(kLiverObj);  // CRLF line ends
  ASSERT_TRUE(r) << r.error().to_string();
  EXPECT_EQ(r->report.format, "obj");
  EXPECT_EQ(r->mesh.nodes.size(), 181u);
  EXPECT_EQ(r->mesh.triangles.size(), 274u);
  EXPECT_TRUE(r->mesh.normals.empty());
  EXPECT_EQ(r->mesh.triangles.front(), (Tri{0, 1, 2}));
}

TEST(MeshIoAnchors, LiverSmoothObjHasPerVertexNormals) {
  const auto r = read_mesh(kLiverSmoothObj);
  ASSERT_TRUE(r) << r.error().to_string();
  EXPECT_EQ(r->mesh.nodes.size(), 2194u);
  EXPECT_EQ(r->mesh.triangles.size(), 4384u);
  ASSERT_EQ(r->mesh.normals.size(), 2194u);
  // "f 1//1 2194//2 1375//3": vertex 1 first gets vn 1.
  EXPECT_EQ(r->mesh.triangles.front(), (Tri{0, 2193, 1374}));
  EXPECT_EQ(r->mesh.normals[0], Vec3(0.324945, -0.640133, 0.696161));
  EXPECT_EQ(r->mesh.normals[2193], Vec3(0.352111, -0.885083, -0.304377));
  EXPECT_TRUE(r->report.warnings.empty());
}

TEST(MeshIoAnchors, LiverObjAndMshShareTheirNodes) {
  // The SOFA liver surface and volume use the same node list, so they combine into one
  // Mesh whose triangles and tets index the same nodes.
  const auto volume = read_mesh(kLiverMsh);
  const auto surface = read_mesh(kLiverObj);
  ASSERT_TRUE(volume && surface);
  EXPECT_TRUE(same_bits(volume->mesh.nodes, surface->mesh.nodes));
}

// ---------------------------------------------------------------------------------------
// Round trips

TEST_F(MeshIoTest, LiverRoundTripsExactlyThroughGmsh22And41) {
  const auto original = read_mesh(kLiverMsh);
  ASSERT_TRUE(original);
  const Mesh& m0 = original->mesh;

  ASSERT_TRUE(write_msh(m0, file("a.msh"), MshVersion::k2_2));
  const auto a = read_mesh(file("a.msh"));
  ASSERT_TRUE(a) << a.error().to_string();
  EXPECT_EQ(a->report.format, "gmsh-2.2-ascii");

  ASSERT_TRUE(write_msh(a->mesh, file("b.msh"), MshVersion::k4_1));
  const auto b = read_mesh(file("b.msh"));
  ASSERT_TRUE(b) << b.error().to_string();
  EXPECT_EQ(b->report.format, "gmsh-4.1-ascii");

  ASSERT_TRUE(write_msh(b->mesh, file("c.msh"), MshVersion::k2_2));
  const auto c = read_mesh(file("c.msh"));
  ASSERT_TRUE(c) << c.error().to_string();

  for (const auto* r : {&*a, &*b, &*c}) {
    EXPECT_TRUE(same_bits(r->mesh.nodes, m0.nodes));
    EXPECT_EQ(r->mesh.tets, m0.tets);
    EXPECT_EQ(r->mesh.tet_regions, m0.tet_regions);
    EXPECT_EQ(r->mesh, m0);
  }
  // Same mesh, same bytes.
  EXPECT_EQ(slurp(file("a.msh")), slurp(file("c.msh")));
}

TEST_F(MeshIoTest, SampleMeshRoundTripsThroughGmshBothVersions) {
  Mesh m = sample_mesh();
  m.normals.clear();  // Gmsh stores no normals
  for (const auto version : {MshVersion::k2_2, MshVersion::k4_1}) {
    ASSERT_TRUE(write_msh(m, file("s.msh"), version));
    const auto r = read_mesh(file("s.msh"));
    ASSERT_TRUE(r) << r.error().to_string();
    EXPECT_TRUE(same_bits(r->mesh.nodes, m.nodes));
    EXPECT_EQ(r->mesh, m);
  }
}

TEST_F(MeshIoTest, Gmsh41KeepsElementOrderWhenRegionsInterleave) {
  Mesh m = sample_mesh();
  m.normals.clear();
  m.tets = {{0, 1, 2, 3}, {1, 2, 3, 4}, {0, 1, 3, 4}, {0, 2, 3, 4}};
  m.tet_regions = {1, 2, 1, 2};
  ASSERT_TRUE(write_msh(m, file("i.msh"), MshVersion::k4_1));
  const auto r = read_mesh(file("i.msh"));
  ASSERT_TRUE(r) << r.error().to_string();
  EXPECT_EQ(r->mesh.tets, m.tets);
  EXPECT_EQ(r->mesh.tet_regions, m.tet_regions);
}

TEST_F(MeshIoTest, MeshWithoutRegionsRoundTripsWithoutRegions) {
  Mesh m = sample_mesh();
  m.normals.clear();
  m.tet_regions.clear();
  m.triangle_regions.clear();
  for (const auto version : {MshVersion::k2_2, MshVersion::k4_1}) {
    ASSERT_TRUE(write_msh(m, file("n.msh"), version));
    const auto r = read_mesh(file("n.msh"));
    ASSERT_TRUE(r) << r.error().to_string();
    EXPECT_EQ(r->mesh, m);
  }
  ASSERT_TRUE(write_vtu(m, file("n.vtu")));
  const auto v = read_mesh(file("n.vtu"));
  ASSERT_TRUE(v) << v.error().to_string();
  EXPECT_EQ(v->mesh, m);
}

TEST_F(MeshIoTest, LiverRoundTripsExactlyThroughVtu) {
  const auto original = read_mesh(kLiverMsh);
  ASSERT_TRUE(original);
  ASSERT_TRUE(write_mesh(original->mesh, file("liver.vtu")));
  const auto back = read_mesh(file("liver.vtu"));
  ASSERT_TRUE(back) << back.error().to_string();
  EXPECT_EQ(back->report.format, "vtu");
  EXPECT_TRUE(same_bits(back->mesh.nodes, original->mesh.nodes));
  EXPECT_EQ(back->mesh, original->mesh);
}

TEST_F(MeshIoTest, VtuKeepsTetsTrianglesRegionsAndNormals) {
  const Mesh m = sample_mesh();
  ASSERT_TRUE(write_vtu(m, file("s.vtu")));
  const auto r = read_mesh(file("s.vtu"));
  ASSERT_TRUE(r) << r.error().to_string();
  EXPECT_TRUE(same_bits(r->mesh.nodes, m.nodes));
  EXPECT_EQ(r->mesh, m);
  const std::string text = slurp(file("s.vtu"));
  EXPECT_NE(text.find("type=\"Float64\" Name=\"Points\""), std::string::npos);
  EXPECT_NE(text.find("type=\"Int32\" Name=\"region\""), std::string::npos);
}

TEST_F(MeshIoTest, ObjRoundTripKeepsTrianglesAndNormals) {
  Mesh m = sample_mesh();
  m.tets.clear();
  m.tet_regions.clear();
  m.triangle_regions.clear();  // OBJ stores no regions
  ASSERT_TRUE(write_obj(m, file("s.obj")));
  const auto r = read_mesh(file("s.obj"));
  ASSERT_TRUE(r) << r.error().to_string();
  EXPECT_TRUE(same_bits(r->mesh.nodes, m.nodes));
  EXPECT_EQ(r->mesh, m);

  m.normals.clear();
  ASSERT_TRUE(write_obj(m, file("plain.obj")));
  const auto plain = read_mesh(file("plain.obj"));
  ASSERT_TRUE(plain);
  EXPECT_EQ(plain->mesh, m);
}

TEST_F(MeshIoTest, LiverSmoothObjRoundTripsExactly) {
  const auto original = read_mesh(kLiverSmoothObj);
  ASSERT_TRUE(original);
  ASSERT_TRUE(write_mesh(original->mesh, file("smooth.obj")));
  const auto back = read_mesh(file("smooth.obj"));
  ASSERT_TRUE(back) << back.error().to_string();
  EXPECT_EQ(back->mesh, original->mesh);
}

TEST_F(MeshIoTest, OffRoundTripKeepsTriangles) {
  Mesh m = sample_mesh();
  m.tets.clear();
  m.tet_regions.clear();
  m.triangle_regions.clear();
  m.normals.clear();
  ASSERT_TRUE(write_off(m, file("s.off")));
  const auto r = read_mesh(file("s.off"));
  ASSERT_TRUE(r) << r.error().to_string();
  EXPECT_EQ(r->report.format, "off");
  EXPECT_TRUE(same_bits(r->mesh.nodes, m.nodes));
  EXPECT_EQ(r->mesh, m);
}

TEST_F(MeshIoTest, WritersAreDeterministic) {
  const Mesh m = sample_mesh();
  for (const char* name : {"d.msh", "d.obj", "d.off", "d.vtu"}) {
    ASSERT_TRUE(write_mesh(m, file(std::string("1") + name)));
    ASSERT_TRUE(write_mesh(m, file(std::string("2") + name)));
    EXPECT_EQ(slurp(file(std::string("1") + name)), slurp(file(std::string("2") + name))) << name;
  }
}

// ---------------------------------------------------------------------------------------
// Gmsh reader features, small inline files

TEST_F(MeshIoTest, GmshV2MixedElementsAreCountedAndMapped) {
  const auto path = write("mixed.msh",
                          "$MeshFormat\n2.2 0 8\n$EndMeshFormat\n"
                          "$PhysicalNames\n2\n2 7 \"skin\"\n3 9 \"liver\"\n$EndPhysicalNames\n"
                          "$Nodes\n6\n"
                          "10 0 0 0\n20 1 0 0\n30 0 1 0\n40 0 0 1\n50 1 1 0\n60 1 1 1\n"
                          "$EndNodes\n"
                          "$Elements\n8\n"
                          "1 15 2 0 1 10\n"              // point
                          "2 1 2 0 1 10 20\n"            // line
                          "3 8 2 0 1 10 20 30\n"         // 3-node line
                          "4 2 2 7 2 10 20 30\n"         // triangle, physical 7
                          "5 2 2 7 2 20 50 30\n"         // triangle
                          "6 4 2 9 3 10 20 30 40\n"      // tet, physical 9
                          "7 3 2 0 4 10 20 50 30\n"      // quad (line 26)
                          "8 4 3 9 3 5 20 50 30 60\n"    // tet with 3 tags
                          "$EndElements\n"
                          "$NodeData\n1\n\"x\"\n$EndNodeData\n");
  const auto r = read_mesh(path);
  ASSERT_TRUE(r) << r.error().to_string();
  EXPECT_EQ(r->report.format, "gmsh-2.2-ascii");
  ASSERT_EQ(r->mesh.nodes.size(), 6u);
  EXPECT_EQ(r->mesh.nodes[4], Vec3(1, 1, 0));
  EXPECT_EQ(r->mesh.triangles, (std::vector<Tri>{{0, 1, 2}, {1, 4, 2}}));
  EXPECT_EQ(r->mesh.triangle_regions, (std::vector<std::int32_t>{7, 7}));
  EXPECT_EQ(r->mesh.tets, (std::vector<Tet>{{0, 1, 2, 3}, {1, 4, 2, 5}}));
  EXPECT_EQ(r->mesh.tet_regions, (std::vector<std::int32_t>{9, 9}));
  EXPECT_EQ(r->report.ignored_points, 1);
  EXPECT_EQ(r->report.ignored_lines, 2);
  EXPECT_EQ(r->report.ignored_other, 1);
  ASSERT_EQ(r->report.warnings.size(), 1u);
  EXPECT_NE(r->report.warnings[0].find("mixed.msh:26: ignored 1 element(s) of Gmsh type 3"),
            std::string::npos)
      << r->report.warnings[0];
}

TEST_F(MeshIoTest, GmshV41SmallFileWithEntitiesAndParametricNodes) {
  const auto path = write("small41.msh",
                          "$MeshFormat\n4.1 0 8\n$EndMeshFormat\n"
                          "$Entities\n1 0 1 1\n"
                          "1 0 0 0 0\n"
                          "5 0 0 0 1 1 0 1 7 0\n"
                          "3 0 0 0 1 1 1 1 9 0\n"
                          "$EndEntities\n"
                          "$Nodes\n2 5 1 5\n"
                          "0 1 0 1\n1\n0 0 0\n"
                          "2 5 1 4\n2\n3\n4\n5\n"
                          "1 0 0 0.5 0.5\n0 1 0 0.1 0.2\n0 0 1 0.3 0.3\n1 1 1 0.2 0.2\n"
                          "$EndNodes\n"
                          "$Elements\n3 4 1 4\n"
                          "0 1 15 1\n1 1\n"
                          "2 5 2 1\n2 1 2 3\n"
                          "3 3 4 2\n3 1 2 3 4\n4 2 3 4 5\n"
                          "$EndElements\n");
  const auto r = read_mesh(path);
  ASSERT_TRUE(r) << r.error().to_string();
  EXPECT_EQ(r->report.format, "gmsh-4.1-ascii");
  ASSERT_EQ(r->mesh.nodes.size(), 5u);
  EXPECT_EQ(r->mesh.nodes[1], Vec3(1, 0, 0));
  EXPECT_EQ(r->mesh.nodes[4], Vec3(1, 1, 1));
  EXPECT_EQ(r->mesh.triangles, (std::vector<Tri>{{0, 1, 2}}));
  EXPECT_EQ(r->mesh.triangle_regions, (std::vector<std::int32_t>{5}));
  EXPECT_EQ(r->mesh.tets, (std::vector<Tet>{{0, 1, 2, 3}, {1, 2, 3, 4}}));
  EXPECT_EQ(r->mesh.tet_regions, (std::vector<std::int32_t>{3, 3}));
  EXPECT_EQ(r->report.ignored_points, 1);
}

/// A Gmsh 2.2 binary file: 5 nodes (tags 1..5), a point, two tets in physical 9.
/// `node_count` is the count written in $Nodes, `last_tag` the last node of the second tet.
std::string binary_msh(bool swap, int node_count = 5, int last_tag = 5) {
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

TEST_F(MeshIoTest, GmshV2BinarySmallFileBothByteOrders) {
  for (const bool swap : {false, true}) {
    const auto r = read_mesh(write("bin.msh", binary_msh(swap)));
    ASSERT_TRUE(r) << r.error().to_string();
    EXPECT_EQ(r->report.format, "gmsh-2.2-binary");
    ASSERT_EQ(r->mesh.nodes.size(), 5u);
    EXPECT_EQ(r->mesh.nodes[0], Vec3(0.1, 0.2, 0.3));
    EXPECT_EQ(r->mesh.nodes[1], Vec3(1.0 / 3.0, 0, 0));
    EXPECT_EQ(r->mesh.tets, (std::vector<Tet>{{0, 1, 2, 3}, {1, 2, 3, 4}}));
    EXPECT_EQ(r->mesh.tet_regions, (std::vector<std::int32_t>{9, 9}));
    EXPECT_EQ(r->report.ignored_points, 1);
  }
}

TEST_F(MeshIoTest, GmshBinaryTruncatedReportsByteOffset) {
  const std::string full = binary_msh(false);
  const Error e = read_error("cut.msh", full.substr(0, 120));
  EXPECT_EQ(e.code, ErrorCode::kParse);
  EXPECT_GE(e.byte_offset, 0);
  EXPECT_NE(e.to_string().find("cut.msh: byte "), std::string::npos) << e.to_string();
}

TEST_F(MeshIoTest, GmshBinaryWrongNodeCountReportsByteOffset) {
  // The count says 4 nodes, so the fifth node's bytes stand where $EndNodes should be.
  const Error e = read_error("count.msh", binary_msh(false, 4));
  EXPECT_EQ(e.code, ErrorCode::kParse);
  EXPECT_NE(e.to_string().find("count.msh: byte 161: expected $EndNodes"), std::string::npos)
      << e.to_string();
}

TEST_F(MeshIoTest, GmshBinaryMissingNodeReportsByteOffset) {
  const Error e = read_error("missing.msh", binary_msh(false, 5, 99));
  EXPECT_EQ(e.code, ErrorCode::kInvalidMesh);
  // Header to the node data 49 bytes, nodes 5 x 28, "\n$EndNodes\n$Elements\n3\n" 23, the
  // point block 28, the tet block header 12 and the first tet 28: the second tet is at 280.
  EXPECT_NE(e.to_string().find("missing.msh: byte 280: element refers to node tag 99"),
            std::string::npos)
      << e.to_string();
}

TEST_F(MeshIoTest, ProgressIsReportedFromZeroToOne) {
  std::vector<double> fractions;
  const auto r = read_msh(kLiverMsh, [&](std::string_view task, double f) {
    EXPECT_NE(task.find("liver.msh"), std::string_view::npos);
    fractions.push_back(f);
  });
  ASSERT_TRUE(r);
  ASSERT_GE(fractions.size(), 2u);
  EXPECT_EQ(fractions.front(), 0.0);
  EXPECT_EQ(fractions.back(), 1.0);
}

// ---------------------------------------------------------------------------------------
// OBJ, OFF, STL reader features

TEST_F(MeshIoTest, ObjAllIndexFormsQuadAndNegativeIndices) {
  const auto path = write("forms.obj",
                          "# all face forms\n"
                          "mtllib forms.mtl\n"
                          "o thing\n"
                          "v 0 0 0\n"
                          "v 1 0 0\n"
                          "v 1 1 0\n"
                          "v 0 1 0\n"
                          "v 0 0 1 1.0\n"  // optional w
                          "vt 0 0\nvt 1 0\nvt 1 1\n"
                          "vn 0 0 1\nvn 0 0 -1\n"
                          "g group\nusemtl red\ns off\n"
                          "f 1 2 3\n"
                          "f 1/1 2/2 3/3\n"
                          "f 1//1 3//1 4//1\n"
                          "f 1/1/2 2/2/2 5/3/2   # comment after a face\n"
                          "f -5 -4 -3 -2\n"  // quad, relative indices
                          "l 1 2\n"
                          "p 1\n"
                          "f -1/-1/-1 -2/-2/-1 -3/-3/-2\n"
                          "f 1 2 \\\n 4\n");  // continued line
  const auto r = read_mesh(path);
  ASSERT_TRUE(r) << r.error().to_string();
  EXPECT_EQ(r->mesh.nodes.size(), 5u);
  EXPECT_EQ(r->mesh.triangles, (std::vector<Tri>{{0, 1, 2},
                                                 {0, 1, 2},
                                                 {0, 2, 3},
                                                 {0, 1, 4},
                                                 {0, 1, 2},
                                                 {0, 2, 3},
                                                 {4, 3, 2},
                                                 {0, 1, 3}}));
  // The first normal a face gives a vertex wins.
  ASSERT_EQ(r->mesh.normals.size(), 5u);
  EXPECT_EQ(r->mesh.normals[0], Vec3(0, 0, 1));
  EXPECT_EQ(r->mesh.normals[1], Vec3(0, 0, -1));
  EXPECT_EQ(r->mesh.normals[2], Vec3(0, 0, 1));
  EXPECT_EQ(r->mesh.normals[3], Vec3(0, 0, 1));
  EXPECT_EQ(r->mesh.normals[4], Vec3(0, 0, -1));
  EXPECT_EQ(r->report.ignored_lines, 1);
  EXPECT_EQ(r->report.ignored_points, 1);
  EXPECT_TRUE(r->report.warnings.empty());
}

TEST_F(MeshIoTest, ObjVerticesWithoutNormalGetZeroAndAWarning) {
  const auto r = read_mesh(write("partial.obj", "v 0 0 0\nv 1 0 0\nv 0 1 0\nv 0 0 1\n"
                                                "vn 0 0 1\nf 1//1 2//1 3//1\n"));
  ASSERT_TRUE(r) << r.error().to_string();
  ASSERT_EQ(r->mesh.normals.size(), 4u);
  EXPECT_EQ(r->mesh.normals[3], Vec3::Zero());
  ASSERT_EQ(r->report.warnings.size(), 1u);
  EXPECT_NE(r->report.warnings[0].find("1 vertices have no normal"), std::string::npos);
}

TEST_F(MeshIoTest, OffWithCommentsColoursAndAQuad) {
  const auto r = read_mesh(write("quad.off",
                                 "COFF # coloured\n"
                                 "# counts follow\n"
                                 "4 1 0\n"
                                 "0 0 0 255 0 0 255\n"
                                 "1 0 0 255 0 0 255\n"
                                 "1 1 0 255 0 0 255\n"
                                 "0 1 0 255 0 0 255\n"
                                 "4 0 1 2 3 0.5 0.5 0.5\n"));
  ASSERT_TRUE(r) << r.error().to_string();
  EXPECT_EQ(r->mesh.nodes.size(), 4u);
  EXPECT_EQ(r->mesh.triangles, (std::vector<Tri>{{0, 1, 2}, {0, 2, 3}}));
}

TEST_F(MeshIoTest, StlAsciiWeldsByExactPositionInOrderOfAppearance) {
  const auto r = read_mesh(write("two.stl",
                                 "solid two\n"
                                 "  facet normal 0 0 1\n    outer loop\n"
                                 "      vertex 0 0 0\n      vertex 1 0 0\n      vertex 1 1 0\n"
                                 "    endloop\n  endfacet\n"
                                 "  facet normal nan nan nan\n    outer loop\n"
                                 "      vertex -0 0 0\n      vertex 1 1 0\n      vertex 0 1 0\n"
                                 "    endloop\n  endfacet\n"
                                 "endsolid two\n"));
  ASSERT_TRUE(r) << r.error().to_string();
  EXPECT_EQ(r->report.format, "stl-ascii");
  EXPECT_EQ(r->mesh.nodes, (std::vector<Vec3>{Vec3(0, 0, 0), Vec3(1, 0, 0), Vec3(1, 1, 0), Vec3(0, 1, 0)}));
  EXPECT_EQ(r->mesh.triangles, (std::vector<Tri>{{0, 1, 2}, {0, 2, 3}}));
}

std::string binary_stl(const std::vector<std::array<float, 9>>& triangles,
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

TEST_F(MeshIoTest, StlBinaryIsDetectedBySizeEvenWhenHeaderSaysSolid) {
  const auto r = read_mesh(write("bin.stl", binary_stl({{0, 0, 0, 1, 0, 0, 1, 1, 0},
                                                       {0, 0, 0, 1, 1, 0, 0, 1, 0.1f}})));
  ASSERT_TRUE(r) << r.error().to_string();
  EXPECT_EQ(r->report.format, "stl-binary");
  ASSERT_EQ(r->mesh.nodes.size(), 4u);
  EXPECT_EQ(r->mesh.nodes[3], Vec3(0, 1, static_cast<double>(0.1f)));
  EXPECT_EQ(r->mesh.triangles, (std::vector<Tri>{{0, 1, 2}, {0, 2, 3}}));
}

// ---------------------------------------------------------------------------------------
// Dispatch and writer errors

TEST_F(MeshIoTest, ExtensionIsCaseInsensitive) {
  ASSERT_TRUE(write_mesh(sample_mesh(), file("UPPER.MSH")));
  EXPECT_TRUE(slurp(file("UPPER.MSH")).starts_with("$MeshFormat\n4.1 0 8\n"));
  const auto r = read_mesh(file("UPPER.MSH"));
  ASSERT_TRUE(r) << r.error().to_string();
  EXPECT_EQ(r->mesh.tets.size(), 2u);
}

TEST_F(MeshIoTest, AMissingFileWithoutAnExtensionIsSaidToBeMissing) {
  const auto r = read_mesh(file("no-such-folder/Shader"));
  ASSERT_FALSE(r);
  EXPECT_EQ(r.error().message, "no such file");
}

TEST_F(MeshIoTest, UnknownExtensionIsAClearError) {
  const auto r = read_mesh(write("mesh.xyz", "1 2 3\n"));
  ASSERT_FALSE(r);
  EXPECT_EQ(r.error().code, ErrorCode::kUnsupported);
  EXPECT_NE(r.error().to_string().find("unknown mesh file extension '.xyz'"), std::string::npos);
  const auto w = write_mesh(sample_mesh(), file("mesh.stl"));
  ASSERT_FALSE(w);
  EXPECT_EQ(w.error().code, ErrorCode::kUnsupported);
}

TEST_F(MeshIoTest, MissingFileIsAnIoError) {
  for (const char* name : {"none.msh", "none.obj", "none.stl", "none.off", "none.vtu"}) {
    const auto r = read_mesh(file(name));
    ASSERT_FALSE(r);
    EXPECT_EQ(r.error().code, ErrorCode::kIo) << name;
    EXPECT_NE(r.error().to_string().find(name), std::string::npos);
  }
  fs::create_directory(file("dir.msh"));
  const auto d = read_mesh(file("dir.msh"));
  ASSERT_FALSE(d);
  EXPECT_EQ(d.error().code, ErrorCode::kIo);
  EXPECT_NE(d.error().message.find("directory"), std::string::npos);
  const auto dev = read_msh("/dev/zero");  // endless: must be refused, not read
  ASSERT_FALSE(dev);
  EXPECT_EQ(dev.error().code, ErrorCode::kIo);
}

TEST_F(MeshIoTest, WritingTetsOnlyToObjOrOffIsRefused) {
  const auto liver = read_mesh(kLiverMsh);
  ASSERT_TRUE(liver);
  for (const char* name : {"t.obj", "t.off"}) {
    const auto w = write_mesh(liver->mesh, file(name));
    ASSERT_FALSE(w);
    EXPECT_EQ(w.error().code, ErrorCode::kInvalidArgument);
    EXPECT_NE(w.error().message.find("extract the boundary"), std::string::npos);
  }
}

TEST_F(MeshIoTest, WritingAnInconsistentMeshIsRefused) {
  Mesh m = sample_mesh();
  m.tets[1][2] = 5;  // only 5 nodes
  const auto w = write_mesh(m, file("bad.msh"));
  ASSERT_FALSE(w);
  EXPECT_EQ(w.error().code, ErrorCode::kInvalidArgument);
  EXPECT_FALSE(fs::exists(file("bad.msh")));
  const auto io = write_mesh(sample_mesh(), file("no/such/dir/x.msh"));
  ASSERT_FALSE(io);
  EXPECT_EQ(io.error().code, ErrorCode::kIo);
}

// ---------------------------------------------------------------------------------------
// Bad Gmsh input: one test per defect, message with file and line

constexpr std::string_view kHeader22 = "$MeshFormat\n2.2 0 8\n$EndMeshFormat\n";

TEST_F(MeshIoTest, GmshTruncatedFile) {
  // Cut inside the last node.
  const Error e = read_error("trunc.msh", std::string(kHeader22) +
                                              "$Nodes\n3\n1 0.5 0.5 0.5\n2 1.5 0.5 0.5\n3 0.5 1.5");
  expect_error_at(e, ErrorCode::kParse, "trunc.msh", 8, "unexpected end of file: expected z coordinate");
  EXPECT_NE(e.message.find("node 3 of 3"), std::string::npos) << e.message;
  // Cut so early that the count cannot fit: caught at the count, before any reserve.
  const Error c = read_error("short.msh", std::string(kHeader22) + "$Nodes\n4\n1 0 0 0\n2 1 0 0\n3 0 1");
  expect_error_at(c, ErrorCode::kParse, "short.msh", 5, "the file is truncated or the count is wrong");
}

TEST_F(MeshIoTest, GmshSectionNotClosed) {
  const Error e = read_error("open.msh", std::string(kHeader22) + "$Nodes\n1\n1 0 0 0\n");
  expect_error_at(e, ErrorCode::kParse, "open.msh", 6, "not closed by $EndNodes");
}

TEST_F(MeshIoTest, GmshNodeCountLargerThanNodes) {
  const Error e = read_error("count.msh", std::string(kHeader22) +
                                              "$Nodes\n3\n1 0 0 0\n2 1 0 0\n$EndNodes\n");
  expect_error_at(e, ErrorCode::kParse, "count.msh", 8, "count is wrong");
}

TEST_F(MeshIoTest, GmshNodeCountSmallerThanNodes) {
  const Error e = read_error("count.msh", std::string(kHeader22) +
                                              "$Nodes\n1\n1 0 0 0\n2 1 0 0\n$EndNodes\n");
  expect_error_at(e, ErrorCode::kParse, "count.msh", 7, "expected $EndNodes");
}

TEST_F(MeshIoTest, GmshV41BlockCountsDisagreeWithHeader) {
  const Error e = read_error("v41.msh",
                             "$MeshFormat\n4.1 0 8\n$EndMeshFormat\n"
                             "$Nodes\n1 2 1 2\n0 1 0 3\n1\n2\n3\n0 0 0\n1 0 0\n0 1 0\n$EndNodes\n");
  expect_error_at(e, ErrorCode::kParse, "v41.msh", 6, "count is wrong");
}

TEST_F(MeshIoTest, GmshElementReferencesMissingNode) {
  const Error e = read_error("index.msh", std::string(kHeader22) +
                                              "$Nodes\n4\n1 0 0 0\n2 1 0 0\n3 0 1 0\n4 0 0 1\n"
                                              "$EndNodes\n$Elements\n2\n"
                                              "1 4 2 1 1 1 2 3 4\n"
                                              "2 4 2 1 1 1 2 3 99\n$EndElements\n");
  expect_error_at(e, ErrorCode::kInvalidMesh, "index.msh", 14, "node tag 99");
}

TEST_F(MeshIoTest, GmshNanCoordinate) {
  const Error e = read_error("nan.msh", std::string(kHeader22) + "$Nodes\n2\n1 0 0 0\n2 0 nan 0\n$EndNodes\n");
  expect_error_at(e, ErrorCode::kInvalidMesh, "nan.msh", 7, "not a finite number");
}

TEST_F(MeshIoTest, GmshInfiniteCoordinateFromOverflow) {
  const Error e = read_error("inf.msh", std::string(kHeader22) + "$Nodes\n1\n1 0 0 1e400\n$EndNodes\n");
  expect_error_at(e, ErrorCode::kInvalidMesh, "inf.msh", 6, "not a finite number");
}

TEST_F(MeshIoTest, GmshNonNumericToken) {
  const Error e = read_error("word.msh", std::string(kHeader22) + "$Nodes\n1\n1 0 zero 0\n$EndNodes\n");
  expect_error_at(e, ErrorCode::kParse, "word.msh", 6, "found 'zero'");
}

TEST_F(MeshIoTest, GmshUnknownElementType) {
  const Error e = read_error("type.msh", std::string(kHeader22) +
                                             "$Nodes\n1\n1 0 0 0\n$EndNodes\n"
                                             "$Elements\n1\n1 999 2 0 0 1\n$EndElements\n");
  expect_error_at(e, ErrorCode::kParse, "type.msh", 10, "unknown Gmsh element type 999");
}

TEST_F(MeshIoTest, GmshV1ElementNodeCountMismatch) {
  const Error e = read_error("v1.msh", "$NOD\n1\n1 0 0 0\n$ENDNOD\n$ELM\n1\n1 4 1 1 3 1 1 1\n$ENDELM\n");
  expect_error_at(e, ErrorCode::kParse, "v1.msh", 7, "has 4 nodes, the line says 3");
}

TEST_F(MeshIoTest, GmshDuplicateNodeTag) {
  const Error e = read_error("dup.msh", std::string(kHeader22) + "$Nodes\n2\n7 0 0 0\n7 1 0 0\n$EndNodes\n");
  expect_error_at(e, ErrorCode::kInvalidMesh, "dup.msh", 8, "node tag 7 appears more than once");
}

TEST_F(MeshIoTest, GmshAbsurdCountFailsWithoutAllocating) {
  const Error e = read_error("huge.msh", std::string(kHeader22) + "$Nodes\n999999999999999\n1 0 0 0\n$EndNodes\n");
  expect_error_at(e, ErrorCode::kParse, "huge.msh", 5, "node count 999999999999999 is impossible");
  const Error b = read_error("huge4.msh", "$MeshFormat\n4.1 0 8\n$EndMeshFormat\n"
                                          "$Nodes\n1 2000000000 1 2000000000\n$EndNodes\n");
  expect_error_at(b, ErrorCode::kParse, "huge4.msh", 5, "impossible");
}

TEST_F(MeshIoTest, GmshUnsupportedVersion) {
  const Error e = read_error("v3.msh", "$MeshFormat\n3.0 0 8\n$EndMeshFormat\n");
  expect_error_at(e, ErrorCode::kUnsupported, "v3.msh", 2, "version 3.0 is not supported");
}

TEST_F(MeshIoTest, GmshEmptyFile) {
  expect_error_at(read_error("empty.msh", ""), ErrorCode::kParse, "empty.msh", 1, "file is empty");
  expect_error_at(read_error("blank.msh", " \n\n"), ErrorCode::kParse, "blank.msh", 1, "file is empty");
}

TEST_F(MeshIoTest, GmshBinaryGarbage) {
  for (unsigned seed = 1; seed <= 20; ++seed) {
    const Error e = read_error("garbage.msh", garbage(4096, seed));
    EXPECT_EQ(e.code, ErrorCode::kParse) << e.to_string();
    EXPECT_GE(e.line, 1);
    EXPECT_LE(e.line, 40) << e.to_string();  // the first token, whatever line it is on
    EXPECT_NE(e.message.find("not a Gmsh mesh file"), std::string::npos) << e.to_string();
  }
}

TEST_F(MeshIoTest, GmshNoNodeSection) {
  const Error e = read_error("nonodes.msh", std::string(kHeader22));
  EXPECT_EQ(e.code, ErrorCode::kInvalidMesh);
  EXPECT_NE(e.to_string().find("nonodes.msh:3: no $Nodes section"), std::string::npos) << e.to_string();
}

// ---------------------------------------------------------------------------------------
// Bad OBJ / OFF / STL / VTU input

TEST_F(MeshIoTest, ObjBadInput) {
  expect_error_at(read_error("empty.obj", ""), ErrorCode::kParse, "empty.obj", 1, "file is empty");
  expect_error_at(read_error("range.obj", "v 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 4\n"),
                  ErrorCode::kInvalidMesh, "range.obj", 4, "vertex index 4 is out of range");
  expect_error_at(read_error("neg.obj", "v 0 0 0\nv 1 0 0\nv 0 1 0\nf -1 -2 -4\n"),
                  ErrorCode::kInvalidMesh, "neg.obj", 4, "vertex index -4 is out of range");
  expect_error_at(read_error("zero.obj", "v 0 0 0\nv 1 0 0\nv 0 1 0\nf 0 1 2\n"),
                  ErrorCode::kInvalidMesh, "zero.obj", 4, "index 0");
  expect_error_at(read_error("normal.obj", "v 0 0 0\nv 1 0 0\nv 0 1 0\nvn 0 0 1\nf 1//1 2//2 3//1\n"),
                  ErrorCode::kInvalidMesh, "normal.obj", 5, "normal index 2 is out of range");
  expect_error_at(read_error("nan.obj", "v 0 0 0\nv 1 NaN 0\n"), ErrorCode::kInvalidMesh,
                  "nan.obj", 2, "not a finite number");
  expect_error_at(read_error("word.obj", "v 0 0 0\nv 1 x 0\n"), ErrorCode::kParse, "word.obj", 2,
                  "'x' is not a number");
  expect_error_at(read_error("short.obj", "v 0 0\n"), ErrorCode::kParse, "short.obj", 1,
                  "needs 3 values, found 2");
  expect_error_at(read_error("face.obj", "v 0 0 0\nv 1 0 0\nf 1 2\n"), ErrorCode::kInvalidMesh,
                  "face.obj", 3, "face with 2 vertices");
  expect_error_at(read_error("form.obj", "v 0 0 0\nv 1 0 0\nv 0 1 0\nf 1/ 2 3\n"), ErrorCode::kParse,
                  "form.obj", 4, "bad face vertex '1/'");
  expect_error_at(read_error("novert.obj", "# nothing\ng x\n"), ErrorCode::kInvalidMesh,
                  "novert.obj", 2, "no vertices");
  expect_error_at(read_error("unknown.obj", "v 0 0 0\nbogus 1 2\n"), ErrorCode::kParse,
                  "unknown.obj", 2, "unknown OBJ statement 'bogus'");
}

TEST_F(MeshIoTest, ObjBinaryGarbage) {
  for (unsigned seed = 1; seed <= 20; ++seed) {
    const Error e = read_error("garbage.obj", garbage(4096, seed));
    EXPECT_TRUE(e.code == ErrorCode::kParse || e.code == ErrorCode::kInvalidMesh) << e.to_string();
    EXPECT_GE(e.line, 1);
    EXPECT_LE(e.line, 40) << e.to_string();
  }
}

TEST_F(MeshIoTest, OffBadInput) {
  expect_error_at(read_error("empty.off", ""), ErrorCode::kParse, "empty.off", 1, "file is empty");
  expect_error_at(read_error("header.off", "PLY\n3 1 0\n"), ErrorCode::kParse, "header.off", 1,
                  "not an OFF file");
  // One vertex short: the face line is taken as vertex 4, then the face is missing.
  expect_error_at(read_error("few.off", "OFF\n4 1 0\n0.25 0.25 0.25\n1.25 0.25 0.25\n0.25 1.25 0.25\n3 0 1 2\n"),
                  ErrorCode::kParse, "few.off", 6, "face 1 of 1");
  expect_error_at(read_error("short.off", "OFF\n4 1 0\n0 0 0\n1 0 0\n0 1 0\n3 0 1 2\n"),
                  ErrorCode::kParse, "short.off", 2, "face count 1 is impossible");
  expect_error_at(read_error("more.off", "OFF\n3 1 0\n0 0 0\n1 0 0\n0 1 0\n3 0 1 2\n3 0 1 2\n"),
                  ErrorCode::kParse, "more.off", 7, "face count is wrong");
  expect_error_at(read_error("range.off", "OFF\n3 1 0\n0 0 0\n1 0 0\n0 1 0\n3 0 1 3\n"),
                  ErrorCode::kInvalidMesh, "range.off", 6, "vertex index 3 is out of range");
  expect_error_at(read_error("nan.off", "OFF\n3 1 0\n0 0 0\n1 0 inf\n0 1 0\n3 0 1 2\n"),
                  ErrorCode::kInvalidMesh, "nan.off", 4, "not a finite number");
  expect_error_at(read_error("huge.off", "OFF\n99999999999 1 0\n0 0 0\n"), ErrorCode::kParse,
                  "huge.off", 2, "vertex count 99999999999 is impossible");
  for (unsigned seed = 1; seed <= 20; ++seed) {
    const Error e = read_error("garbage.off", garbage(4096, seed));
    EXPECT_EQ(e.code, ErrorCode::kParse) << e.to_string();
    EXPECT_LE(e.line, 40) << e.to_string();
  }
}

TEST_F(MeshIoTest, StlBadInput) {
  expect_error_at(read_error("empty.stl", ""), ErrorCode::kParse, "empty.stl", 1, "file is empty");
  expect_error_at(read_error("open.stl", "solid x\nfacet normal 0 0 1\nouter loop\nvertex 0 0 0\n"),
                  ErrorCode::kParse, "open.stl", 4, "unexpected end of file");
  expect_error_at(read_error("word.stl", "solid x\nfacet normal 0 0 1\nouter loop\nvertex 0 a 0\n"),
                  ErrorCode::kParse, "word.stl", 4, "found 'a'");
  expect_error_at(read_error("four.stl", "solid x\nfacet normal 0 0 1\nouter loop\n"
                                         "vertex 0 0 0\nvertex 1 0 0\nvertex 0 1 0\nvertex 1 1 0\n"
                                         "endloop\nendfacet\nendsolid x\n"),
                  ErrorCode::kParse, "four.stl", 7, "expected 'endloop'");
  const Error nan = read_error("nan.stl", binary_stl({{0, 0, 0, 1, 0, std::nanf(""), 1, 1, 0}}));
  EXPECT_EQ(nan.code, ErrorCode::kInvalidMesh);
  EXPECT_NE(nan.to_string().find("nan.stl: byte 108: "), std::string::npos) << nan.to_string();
  for (unsigned seed = 1; seed <= 20; ++seed) {
    const Error e = read_error("garbage.stl", garbage(4096, seed));
    EXPECT_EQ(e.code, ErrorCode::kParse) << e.to_string();
    EXPECT_NE(e.to_string().find("garbage.stl: byte 80: not an STL file"), std::string::npos)
        << e.to_string();
  }
  // A binary file one byte short of what its count says.
  std::string cut = binary_stl({{0, 0, 0, 1, 0, 0, 1, 1, 0}, {0, 0, 0, 1, 1, 0, 0, 1, 0}}, "binary");
  cut.pop_back();
  const Error c = read_error("cut.stl", cut);
  EXPECT_NE(c.to_string().find("does not match a binary STL of 2 triangles"), std::string::npos)
      << c.to_string();
}

TEST_F(MeshIoTest, VtuBadInput) {
  expect_error_at(read_error("empty.vtu", ""), ErrorCode::kParse, "empty.vtu", 1, "file is empty");
  for (unsigned seed = 1; seed <= 20; ++seed) {
    const Error e = read_error("garbage.vtu", garbage(4096, seed));
    EXPECT_EQ(e.code, ErrorCode::kParse) << e.to_string();
    EXPECT_GE(e.line, 1);
    EXPECT_LE(e.line, 40) << e.to_string();
  }
  ASSERT_TRUE(write_vtu(sample_mesh(), file("good.vtu")));
  const std::string good = slurp(file("good.vtu"));
  const auto replace = [&](const std::string& from, const std::string& to) {
    std::string text = good;
    const std::size_t at = text.find(from);
    EXPECT_NE(at, std::string::npos) << from;
    return text.replace(at, from.size(), to);
  };
  // Line numbers below follow the writer's layout (normals on lines 6-10, ...).
  expect_error_at(read_error("range.vtu", replace("          0 1 2 3\n", "          0 1 2 7\n")),
                  ErrorCode::kInvalidMesh, "range.vtu", 34, "refers to point 7");
  expect_error_at(read_error("nan.vtu", replace("1 1e+22 -7.125", "1 nan -7.125")),
                  ErrorCode::kInvalidMesh, "nan.vtu", 27, "not a finite number");
  expect_error_at(read_error("count.vtu", replace("NumberOfPoints=\"5\"", "NumberOfPoints=\"6\"")),
                  ErrorCode::kParse, "count.vtu", 24, "DataArray 'Points' holds 15 values, expected 18");
  expect_error_at(read_error("xml.vtu", replace("</Points>", "</Pointz>")), ErrorCode::kParse,
                  "xml.vtu", 31, "not valid XML");
}

// ---------------------------------------------------------------------------------------
// Robustness: every prefix and many corruptions of valid files end in a value or an Error

TEST_F(MeshIoTest, TruncatedAndCorruptedFilesNeverCrash) {
  const Mesh m = sample_mesh();
  Mesh surface = m;
  surface.tets.clear();
  surface.tet_regions.clear();
  surface.triangle_regions.clear();
  ASSERT_TRUE(write_msh(m, file("v22.msh"), MshVersion::k2_2));
  ASSERT_TRUE(write_msh(m, file("v41.msh"), MshVersion::k4_1));
  ASSERT_TRUE(write_mesh(surface, file("s.obj")));
  ASSERT_TRUE(write_mesh(surface, file("s.off")));
  ASSERT_TRUE(write_mesh(m, file("s.vtu")));
  write("bin.msh", binary_msh(false));
  write("bin.stl", binary_stl({{0, 0, 0, 1, 0, 0, 1, 1, 0}, {0, 0, 0, 1, 1, 0, 0, 1, 0}}));
  std::mt19937 rng(7);
  for (const char* name : {"v22.msh", "v41.msh", "s.obj", "s.off", "s.vtu", "bin.msh", "bin.stl"}) {
    const std::string original = slurp(file(name));
    const std::string ext = fs::path(name).extension().string();
    int failures = 0;
    for (std::size_t n = 0; n < original.size(); n += 3) {
      if (!read_mesh(write("cut" + ext, original.substr(0, n)))) ++failures;
    }
    EXPECT_GT(failures, 0) << name;
    for (int i = 0; i < 300; ++i) {
      std::string corrupt = original;
      for (int k = 0; k < 3; ++k) {
        corrupt[rng() % corrupt.size()] = static_cast<char>(rng() & 0xff);
      }
      const auto r = read_mesh(write("bad" + ext, corrupt));
      if (!r) {
        EXPECT_FALSE(r.error().message.empty());
      }
    }
  }
}

TEST_F(MeshIoTest, LargeGmshFileReadsQuickly) {
  // A 19^3 grid of cubes, 6 tets each: 41154 tets. The timing is reported, not gated.
  constexpr int kN = 19;
  Mesh m;
  const auto id = [](int i, int j, int k) { return static_cast<NodeIndex>((k * (kN + 1) + j) * (kN + 1) + i); };
  for (int k = 0; k <= kN; ++k)
    for (int j = 0; j <= kN; ++j)
      for (int i = 0; i <= kN; ++i) m.nodes.emplace_back(0.01 * i, 0.01 * j + 1e-9 * i, 0.01 * k / 3.0);
  for (int k = 0; k < kN; ++k)
    for (int j = 0; j < kN; ++j)
      for (int i = 0; i < kN; ++i) {
        const NodeIndex c[8] = {id(i, j, k),         id(i + 1, j, k),         id(i + 1, j + 1, k),
                                id(i, j + 1, k),     id(i, j, k + 1),         id(i + 1, j, k + 1),
                                id(i + 1, j + 1, k + 1), id(i, j + 1, k + 1)};
        const int tets[6][4] = {{0, 1, 2, 6}, {0, 2, 3, 6}, {0, 3, 7, 6},
                                {0, 7, 4, 6}, {0, 4, 5, 6}, {0, 5, 1, 6}};
        for (const auto& t : tets) m.tets.push_back({c[t[0]], c[t[1]], c[t[2]], c[t[3]]});
      }
  m.tet_regions.assign(m.tets.size(), 3);
  ASSERT_TRUE(write_msh(m, file("big.msh"), MshVersion::k4_1));
  const auto start = std::chrono::steady_clock::now();
  const auto r = read_mesh(file("big.msh"));
  const double seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
  ASSERT_TRUE(r) << r.error().to_string();
  EXPECT_EQ(r->mesh, m);
  RecordProperty("read_seconds_41k_tets", std::to_string(seconds));
  std::printf("read %zu tets in %.3f s\n", r->mesh.tets.size(), seconds);
}

}  // namespace
}  // namespace hof::mesh
