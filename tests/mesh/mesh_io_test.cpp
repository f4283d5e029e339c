// The format dispatch and the checks before writing (src/hof/mesh/mesh_io.cpp): extensions, missing
// files, refused writes, deterministic writers, and every prefix and many corruptions of valid files of
// each format ending in a value or an Error.

#include <gtest/gtest.h>

#include <random>
#include <string>
#include <vector>

#include "hof/mesh/mesh_io.h"
#include "mesh_io_test_support.h"

namespace hof::mesh {
namespace {

using namespace io_test;

TEST(MeshIoAnchors, LiverObjAndMshShareTheirNodes) {
  // The SOFA liver surface and volume use the same node list, so they combine into one
  // Mesh whose triangles and tets index the same nodes.
  const auto volume = read_mesh(kLiverMsh);
  const auto surface = read_mesh(kLiverObj);
  ASSERT_TRUE(volume && surface);
  EXPECT_TRUE(same_bits(volume->mesh.nodes, surface->mesh.nodes));
}

TEST_F(MeshIoTest, WritersAreDeterministic) {
  const Mesh m = sample_mesh();
  for (const char* name : {"d.msh", "d.obj", "d.off", "d.vtu"}) {
    ASSERT_TRUE(write_mesh(m, file(std::string("1") + name)));
    ASSERT_TRUE(write_mesh(m, file(std::string("2") + name)));
    EXPECT_EQ(slurp(file(std::string("1") + name)), slurp(file(std::string("2") + name))) << name;
  }
}

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

}  // namespace
}  // namespace hof::mesh
