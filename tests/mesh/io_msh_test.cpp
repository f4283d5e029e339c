// Gmsh .msh reading (src/hof/mesh/io_msh.cpp): the SOFA liver read in place, small inline files for
// each reader feature (ASCII 1, 2.2 and 4.1, binary in both byte orders), and one test per kind of bad
// input, matching the message, file name and line.

#include <gtest/gtest.h>

#include <chrono>
#include <cstdio>
#include <string>
#include <vector>

#include "hof/mesh/mesh_io.h"
#include "mesh_io_test_support.h"

namespace hof::mesh {
namespace {

using namespace io_test;

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

TEST_F(MeshIoTest, GmshV2MixedElementsAreCountedAndMapped) {
  const auto path = write("mixed.msh",
                          "$MeshFormat\n2.2 0 8\n$EndMeshFormat\n"
                          "$PhysicalNames\n2\n2 7 \"skin\"\n3 9 \"liver\"\n$EndPhysicalNames\n"
                          "$Nodes\n6\n"
                          "10 0 0 0\n20 1 0 0\n30 0 1 0\n40 0 0 1\n50 1 1 0\n60 1 1 1\n"
                          "$EndNodes\n"
                          "$Elements\n8\n"
                          "1 15 2 0 1 10\n"            // point
                          "2 1 2 0 1 10 20\n"          // line
                          "3 8 2 0 1 10 20 30\n"       // 3-node line
                          "4 2 2 7 2 10 20 30\n"       // triangle, physical 7
                          "5 2 2 7 2 20 50 30\n"       // triangle
                          "6 4 2 9 3 10 20 30 40\n"    // tet, physical 9
                          "7 3 2 0 4 10 20 50 30\n"    // quad (line 26)
                          "8 4 3 9 3 5 20 50 30 60\n"  // tet with 3 tags
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
  EXPECT_NE(r->report.warnings[0].find("mixed.msh:26: ignored 1 element(s) of Gmsh type 3"), std::string::npos)
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
  EXPECT_NE(e.to_string().find("count.msh: byte 161: expected $EndNodes"), std::string::npos) << e.to_string();
}

TEST_F(MeshIoTest, GmshBinaryMissingNodeReportsByteOffset) {
  const Error e = read_error("missing.msh", binary_msh(false, 5, 99));
  EXPECT_EQ(e.code, ErrorCode::kInvalidMesh);
  // Header to the node data 49 bytes, nodes 5 x 28, "\n$EndNodes\n$Elements\n3\n" 23, the
  // point block 28, the tet block header 12 and the first tet 28: the second tet is at 280.
  EXPECT_NE(e.to_string().find("missing.msh: byte 280: element refers to node tag 99"), std::string::npos)
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

TEST_F(MeshIoTest, GmshTruncatedFile) {
  // Cut inside the last node.
  const Error e =
      read_error("trunc.msh", std::string(kHeader22) + "$Nodes\n3\n1 0.5 0.5 0.5\n2 1.5 0.5 0.5\n3 0.5 1.5");
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
  const Error e = read_error("count.msh", std::string(kHeader22) + "$Nodes\n3\n1 0 0 0\n2 1 0 0\n$EndNodes\n");
  expect_error_at(e, ErrorCode::kParse, "count.msh", 8, "count is wrong");
}

TEST_F(MeshIoTest, GmshNodeCountSmallerThanNodes) {
  const Error e = read_error("count.msh", std::string(kHeader22) + "$Nodes\n1\n1 0 0 0\n2 1 0 0\n$EndNodes\n");
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
  const Error b = read_error("huge4.msh",
                             "$MeshFormat\n4.1 0 8\n$EndMeshFormat\n"
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
        const NodeIndex c[8] = {id(i, j, k),     id(i + 1, j, k),     id(i + 1, j + 1, k),     id(i, j + 1, k),
                                id(i, j, k + 1), id(i + 1, j, k + 1), id(i + 1, j + 1, k + 1), id(i, j + 1, k + 1)};
        const int tets[6][4] = {{0, 1, 2, 6}, {0, 2, 3, 6}, {0, 3, 7, 6}, {0, 7, 4, 6}, {0, 4, 5, 6}, {0, 5, 1, 6}};
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
