// VTK .vtu reading and writing (src/hof/mesh/io_vtu.cpp): exact round trips and bad input.

#include <gtest/gtest.h>

#include <string>
#include <vector>

#include "hof/mesh/mesh_io.h"
#include "mesh_io_test_support.h"

namespace hof::mesh {
namespace {

using namespace io_test;

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
  expect_error_at(read_error("nan.vtu", replace("1 1e+22 -7.125", "1 nan -7.125")), ErrorCode::kInvalidMesh, "nan.vtu",
                  27, "not a finite number");
  expect_error_at(read_error("count.vtu", replace("NumberOfPoints=\"5\"", "NumberOfPoints=\"6\"")), ErrorCode::kParse,
                  "count.vtu", 24, "DataArray 'Points' holds 15 values, expected 18");
  expect_error_at(read_error("xml.vtu", replace("</Points>", "</Pointz>")), ErrorCode::kParse, "xml.vtu", 31,
                  "not valid XML");
}

}  // namespace
}  // namespace hof::mesh
