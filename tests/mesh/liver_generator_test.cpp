#include "hof/mesh/liver_generator.h"

#include <gtest/gtest.h>

#include <filesystem>
#include <fstream>
#include <iterator>
#include <map>

#include "hof/mesh/boundary.h"
#include "hof/mesh/mesh_io.h"
#include "hof/mesh/mesh_report.h"
#include "hof/mesh/surface_check.h"

namespace hof::mesh {
namespace {

class LiverResolutionTest : public ::testing::TestWithParam<LiverResolution> {
 protected:
  // Generating `fine` takes a moment: share each resolution's mesh between the tests.
  static const Mesh& liver(LiverResolution r) {
    static std::map<LiverResolution, Mesh> cache;
    auto it = cache.find(r);
    if (it == cache.end()) {
      auto m = generate_liver(r);
      EXPECT_TRUE(m.has_value()) << m.error().to_string();
      it = cache.emplace(r, m ? std::move(*m) : Mesh{}).first;
    }
    return it->second;
  }
};

TEST_P(LiverResolutionTest, TetCountWithinTwentyPercentOfTarget) {
  const Mesh& m = liver(GetParam());
  const auto target = static_cast<double>(target_tet_count(GetParam()));
  EXPECT_GE(static_cast<double>(m.tets.size()), 0.8 * target);
  EXPECT_LE(static_cast<double>(m.tets.size()), 1.2 * target);
}

TEST_P(LiverResolutionTest, NoInvertedElementsAndGoodAngles) {
  const MeshReport r = make_mesh_report(liver(GetParam()));
  EXPECT_EQ(r.quality.inverted, 0);
  EXPECT_EQ(r.quality.degenerate, 0);
  EXPECT_EQ(find_inverted_tets(liver(GetParam()).nodes, liver(GetParam()).tets).size(), 0u);
  EXPECT_GT(r.quality.min_dihedral_deg, 5.0);
  EXPECT_TRUE(r.problems.empty()) << r.problems.front();
}

TEST_P(LiverResolutionTest, SurfaceIsAClosedOutwardSingleSphere) {
  const Mesh& m = liver(GetParam());
  const BoundarySurface b = extract_boundary(m.nodes, m.tets);
  const SurfaceCheck c = check_surface(b.surface);
  EXPECT_TRUE(c.closed_outward());
  EXPECT_EQ(c.components, 1);
  EXPECT_EQ(c.euler_characteristic, 2);  // genus 0
  // The enclosed volume equals the sum of the tet volumes.
  EXPECT_NEAR(c.signed_volume_m3, make_mesh_report(m).volume_m3, 1e-12);
}

TEST_P(LiverResolutionTest, StoredTrianglesAreTheBoundaryAndMapIsConsistent) {
  const Mesh& m = liver(GetParam());
  const BoundarySurface b = extract_boundary(m.nodes, m.tets);
  EXPECT_EQ(m.triangles, b.volume_triangles);
  ASSERT_EQ(b.surface_to_volume.size(), b.surface.vertices.size());
  for (std::size_t s = 0; s < b.surface_to_volume.size(); ++s) {
    EXPECT_EQ(b.surface.vertices[s], m.nodes[b.surface_to_volume[s]]);
    EXPECT_EQ(b.volume_to_surface[b.surface_to_volume[s]], static_cast<std::int32_t>(s));
  }
}

TEST_P(LiverResolutionTest, PlausibleOrganSizeInMetres) {
  const MeshReport r = make_mesh_report(liver(GetParam()));
  const Vec3 size = r.bbox_max - r.bbox_min;
  EXPECT_GT(size.maxCoeff(), 0.17);  // about 0.2 m across
  EXPECT_LT(size.maxCoeff(), 0.25);
  EXPECT_GT(r.volume_m3, 0.8e-3);  // an adult liver holds about 1.5 L
  EXPECT_LT(r.volume_m3, 2.0e-3);
}

TEST_P(LiverResolutionTest, TwoLobesNotASphereOrABox) {
  const Mesh& m = liver(GetParam());
  const MeshReport r = make_mesh_report(m);
  // Thickness (z extent) of the left lobe (x < -0.06 m) vs the right lobe (x > 0.02 m).
  double left_lo = 1, left_hi = -1, right_lo = 1, right_hi = -1;
  for (const Vec3& p : m.nodes) {
    if (p.x() < -0.06) {
      left_lo = std::min(left_lo, p.z());
      left_hi = std::max(left_hi, p.z());
    } else if (p.x() > 0.02) {
      right_lo = std::min(right_lo, p.z());
      right_hi = std::max(right_hi, p.z());
    }
  }
  EXPECT_LT(left_hi - left_lo, 0.75 * (right_hi - right_lo));
  // Far from filling its bounding box (a box would fill it, an ellipsoid fills π/6 ≈ 0.52).
  const Vec3 size = r.bbox_max - r.bbox_min;
  EXPECT_LT(r.volume_m3 / size.prod(), 0.45);
}

INSTANTIATE_TEST_SUITE_P(Standard, LiverResolutionTest,
                         ::testing::Values(LiverResolution::kSimple, LiverResolution::kCoarse, LiverResolution::kMedium,
                                           LiverResolution::kFine),
                         [](const auto& param_info) { return std::string(to_string(param_info.param)); });

std::string file_bytes(const std::filesystem::path& p) {
  std::ifstream in(p, std::ios::binary);
  return {std::istreambuf_iterator<char>(in), std::istreambuf_iterator<char>()};
}

TEST(LiverGenerator, DeterministicToTheByte) {
  const auto dir = std::filesystem::temp_directory_path() / "hof_liver_determinism";
  std::filesystem::create_directories(dir);
  auto a = generate_liver(LiverResolution::kCoarse);
  auto b = generate_liver(LiverResolution::kCoarse);
  ASSERT_TRUE(a && b);
  EXPECT_EQ(*a, *b);
  ASSERT_TRUE(write_mesh(*a, dir / "a.msh").has_value());
  ASSERT_TRUE(write_mesh(*b, dir / "b.msh").has_value());
  const std::string bytes_a = file_bytes(dir / "a.msh");
  EXPECT_FALSE(bytes_a.empty());
  EXPECT_EQ(bytes_a, file_bytes(dir / "b.msh"));
  std::filesystem::remove_all(dir);
}

TEST(LiverGenerator, ResolutionNamesRoundTrip) {
  for (auto r :
       {LiverResolution::kSimple, LiverResolution::kCoarse, LiverResolution::kMedium, LiverResolution::kFine}) {
    EXPECT_EQ(parse_liver_resolution(to_string(r)), r);
  }
  EXPECT_FALSE(parse_liver_resolution("huge").has_value());
}

}  // namespace
}  // namespace hof::mesh
