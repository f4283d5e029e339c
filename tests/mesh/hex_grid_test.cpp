// Hexahedral grids: SOFA's RegularGridTopology numbering, SparseGridTopology voxelisation of a
// closed surface, the boundary of a set of hexahedra, trilinear shape functions.

#include "hof/mesh/hex_grid.h"

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <limits>
#include <numeric>

#include "hof/mesh/liver_generator.h"
#include "hof/mesh/mesh_io.h"
#include "hof/mesh/surface_check.h"

namespace hof::mesh {
namespace {

TEST(RegularGrid, NumbersNodesAndCornersAsSofa) {
  auto grid = regular_grid({4, 3, 2}, Vec3(0, 0, 0), Vec3(0.3, 0.2, 0.1));
  ASSERT_TRUE(grid) << grid.error().to_string();
  ASSERT_EQ(grid->nodes.size(), 24u);
  ASSERT_EQ(grid->hexes.size(), 6u);  // (4−1)(3−1)(2−1)
  // Node (i, j, k) at i + n0 (j + n1 k); the far planes exactly at max.
  EXPECT_TRUE(grid->nodes[1 + 4 * (2 + 3 * 1)].isApprox(Vec3(0.1, 0.2, 0.1), 1e-15));
  EXPECT_EQ(grid->nodes.back(), Vec3(0.3, 0.2, 0.1));
  // Cell (1, 1, 0): corners in SOFA's order.
  const Hex expected = {5, 6, 10, 9, 17, 18, 22, 21};
  EXPECT_EQ(grid->hexes[4], expected);
  EXPECT_EQ(grid->hex_cells[4], 4);
  double volume = 0.0;
  for (const Hex& h : grid->hexes) {
    EXPECT_GT(hex_volume(grid->nodes, h), 0.0);
    volume += hex_volume(grid->nodes, h);
  }
  EXPECT_NEAR(volume, 0.3 * 0.2 * 0.1, 1e-15);
  EXPECT_TRUE(grid->cell_size().isApprox(Vec3(0.1, 0.1, 0.1)));
}

TEST(RegularGrid, RefusesFewerThanTwoNodesOrAnEmptyBox) {
  auto flat = regular_grid({1, 3, 3}, Vec3(0, 0, 0), Vec3(1, 1, 1));
  ASSERT_FALSE(flat);
  EXPECT_NE(flat.error().message.find("n = (1, 3, 3)"), std::string::npos) << flat.error().message;
  auto empty = regular_grid({3, 3, 3}, Vec3(0, 0, 0), Vec3(1, 0, 1));
  ASSERT_FALSE(empty);
  EXPECT_NE(empty.error().message.find("axis y"), std::string::npos) << empty.error().message;
}

TEST(HexShape, FunctionsAreAPartitionOfUnityAndReproduceCoordinates) {
  const Vec3 xi(0.3, -0.7, 1.4);  // outside too: the same polynomials extrapolate
  const auto n = hex_shape_functions(xi);
  EXPECT_NEAR(std::accumulate(n.begin(), n.end(), 0.0), 1.0, 1e-15);
  Vec3 reproduced = Vec3::Zero();
  Eigen::Matrix<double, 3, 8> d = hex_shape_derivatives(xi);
  Mat3 jacobian = Mat3::Zero();
  for (int c = 0; c < 8; ++c) {
    const Vec3 corner(kHexCornerSigns[c][0], kHexCornerSigns[c][1], kHexCornerSigns[c][2]);
    reproduced += n[c] * corner;
    jacobian += corner * d.col(c).transpose();
  }
  EXPECT_TRUE(reproduced.isApprox(xi, 1e-15));
  EXPECT_TRUE(jacobian.isApprox(Mat3::Identity(), 1e-15));
}

TEST(HexVolume, IsExactForATwistedHexahedron) {
  // An affine image of the unit cube has volume |det A|; twisting the top face (a non-planar
  // side) changes it by an amount the 2×2×2 rule still integrates exactly: compare with a
  // fine midpoint sum of det J.
  std::vector<Vec3> nodes;
  Mat3 a;
  a << 1.0, 0.2, 0.1, -0.1, 0.9, 0.3, 0.05, 0.1, 1.2;
  for (const auto& s : kHexCornerSigns) nodes.push_back(a * Vec3((s[0] + 1) / 2.0, (s[1] + 1) / 2.0, (s[2] + 1) / 2.0));
  const Hex hex = {0, 1, 2, 3, 4, 5, 6, 7};
  EXPECT_NEAR(hex_volume(nodes, hex), a.determinant(), 1e-14);
  nodes[6] += Vec3(0.2, -0.1, 0.15);
  nodes[4] += Vec3(-0.05, 0.1, 0.0);
  double sum = 0.0;
  const int steps = 40;
  for (int i = 0; i < steps; ++i) {
    for (int j = 0; j < steps; ++j) {
      for (int k = 0; k < steps; ++k) {
        const Vec3 xi = Vec3(i + 0.5, j + 0.5, k + 0.5) * (2.0 / steps) - Vec3::Ones();
        const Eigen::Matrix<double, 3, 8> d = hex_shape_derivatives(xi);
        Mat3 jacobian = Mat3::Zero();
        for (int c = 0; c < 8; ++c) jacobian += nodes[static_cast<std::size_t>(c)] * d.col(c).transpose();
        sum += jacobian.determinant() * std::pow(2.0 / steps, 3);
      }
    }
  }
  EXPECT_NEAR(hex_volume(nodes, hex), sum, 1e-5 * sum);
}

TEST(HexBoundary, OfABoxIsClosedOutwardWithTwoTrianglesPerFace) {
  auto grid = regular_grid({4, 3, 3}, Vec3(-0.1, 0, 0), Vec3(0.2, 0.1, 0.05));
  ASSERT_TRUE(grid);
  const BoundarySurface b = hex_boundary(grid->nodes, grid->hexes);
  // Faces: 2(3·2 + 3·2 + 2·2) = 32 quads.
  EXPECT_EQ(b.surface.triangles.size(), 64u);
  EXPECT_EQ(b.surface.vertices.size(), grid->nodes.size() - 2);  // all but the two interior nodes
  const SurfaceCheck check = check_surface(b.surface);
  EXPECT_TRUE(check.closed_outward());
  EXPECT_NEAR(check.signed_volume_m3, 0.3 * 0.1 * 0.05, 1e-15);
  for (std::size_t t = 0; t < b.volume_triangles.size(); ++t) {
    for (int c = 0; c < 3; ++c) {
      EXPECT_EQ(b.surface_to_volume[static_cast<std::size_t>(b.surface.triangles[t][c])], b.volume_triangles[t][c]);
    }
  }
}

// The surface of the cube [0, 1]³ as two triangles per face of a 3×3 grid of squares, their
// diagonals on the rays through the cell centres of the grid below: the crossing rule must
// count each ray once where it passes through a shared edge.
TriMesh unit_cube_surface() {
  auto grid = regular_grid({4, 4, 4}, Vec3(0, 0, 0), Vec3(1, 1, 1));
  return hex_boundary(grid->nodes, grid->hexes).surface;
}

TEST(SparseGrid, KeepsExactlyTheCellsOfAnAlignedCube) {
  // Cells of 1/3 in the box [−1, 2]³: the cube is the middle 3×3×3 block; its faces lie on
  // grid planes and must not claim the cells outside them.
  auto grid =
      sparse_grid(unit_cube_surface(), {10, 10, 10}, std::pair<Vec3, Vec3>(Vec3::Constant(-1), Vec3::Constant(2)));
  ASSERT_TRUE(grid) << grid.error().to_string();
  EXPECT_EQ(grid->hexes.size(), 27u);
  EXPECT_EQ(grid->nodes.size(), 64u);
  for (const Vec3& p : grid->nodes)
    EXPECT_TRUE((p.array() > -1e-12).all() && (p.array() < 1 + 1e-12).all()) << p.transpose();
  // The same cube with SOFA's default box (1% larger): every cell is crossed or inside.
  auto fitted = sparse_grid(unit_cube_surface(), {5, 5, 5});
  ASSERT_TRUE(fitted);
  EXPECT_EQ(fitted->hexes.size(), 64u);
  EXPECT_NEAR(fitted->min.x(), -0.01, 1e-15);
  EXPECT_NEAR(fitted->max.z(), 1.01, 1e-15);
  // SOFA's order: the 56 cells of the outer shell (the surface crosses them) first, then the
  // 8 inside; nodes sorted by x, then y, then z.
  ASSERT_EQ(fitted->hex_on_surface.size(), 64u);
  EXPECT_EQ(std::count(fitted->hex_on_surface.begin(), fitted->hex_on_surface.begin() + 56, 1), 56);
  EXPECT_EQ(std::count(fitted->hex_on_surface.begin() + 56, fitted->hex_on_surface.end(), 0), 8);
  EXPECT_TRUE(std::is_sorted(fitted->nodes.begin(), fitted->nodes.end(), [](const Vec3& a, const Vec3& b) {
    return std::lexicographical_compare(a.data(), a.data() + 3, b.data(), b.data() + 3);
  }));
  for (const Hex& hex : fitted->hexes) EXPECT_GT(hex_volume(fitted->nodes, hex), 0.0);
}

// The six faces of the box [lo, hi], two triangles each, wound counter-clockwise seen from
// outside; `inward` reverses them (the wall of a cavity).
TriMesh box_surface(const Vec3& lo, const Vec3& hi, bool inward) {
  auto grid = regular_grid({2, 2, 2}, lo, hi);
  TriMesh box = hex_boundary(grid->nodes, grid->hexes).surface;
  if (inward) {
    for (Tri& t : box.triangles) std::swap(t[1], t[2]);
  }
  return box;
}

// SOFA keeps what a flood fill from the grid's outer layer through uncrossed cells cannot
// reach (SparseGridTopology::voxelizeTriangleMesh, propagateFrom): a cavity walled in by
// crossed cells is inside for it, though its centre is outside the solid. Unit cells in
// [0, 6]³; a hollow cube, outer faces at 0.5 and 5.5, cavity [1.5, 4.5]³: the surface crosses
// the 208 cells of the shell, and the 2×2×2 cells of the cavity are walled in.
TEST(SparseGrid, KeepsACavityWalledInByCrossedCellsAsSofa) {
  TriMesh hollow = box_surface(Vec3::Constant(0.5), Vec3::Constant(5.5), false);
  const TriMesh cavity = box_surface(Vec3::Constant(1.5), Vec3::Constant(4.5), true);
  const auto offset = static_cast<NodeIndex>(hollow.vertices.size());
  hollow.vertices.insert(hollow.vertices.end(), cavity.vertices.begin(), cavity.vertices.end());
  for (Tri t : cavity.triangles) hollow.triangles.push_back({t[0] + offset, t[1] + offset, t[2] + offset});
  auto grid = sparse_grid(hollow, {7, 7, 7}, std::pair<Vec3, Vec3>(Vec3::Zero(), Vec3::Constant(6)));
  ASSERT_TRUE(grid) << grid.error().to_string();
  ASSERT_EQ(grid->hexes.size(), 216u);
  EXPECT_EQ(grid->nodes.size(), 343u);  // the cavity's centre node too
  // The crossed cells first, then the eight of the cavity, inside and whole (fill 1).
  EXPECT_EQ(std::count(grid->hex_on_surface.begin(), grid->hex_on_surface.begin() + 208, 1), 208);
  EXPECT_EQ(std::count(grid->hex_on_surface.begin() + 208, grid->hex_on_surface.end(), 0), 8);
  for (std::size_t h = 208; h < 216; ++h) {
    const std::int32_t cell = grid->hex_cells[h];
    const int i = cell % 6, j = (cell / 6) % 6, k = cell / 36;
    EXPECT_TRUE(i >= 2 && i <= 3 && j >= 2 && j <= 3 && k >= 2 && k <= 3) << "cell " << cell;
  }
}

TEST(SparseGrid, CoversTheBundledLiverAndDropsEmptyCells) {
  auto read = read_mesh(HOF_SOURCE_DIR "/data/models/liver-medium.obj");
  ASSERT_TRUE(read) << read.error().to_string();
  const TriMesh surface{read->mesh.nodes, read->mesh.triangles};
  auto grid = sparse_grid(surface, {9, 9, 9});
  ASSERT_TRUE(grid) << grid.error().to_string();
  EXPECT_LT(grid->hexes.size(), 8u * 8u * 8u);  // empty corners of the box are dropped
  EXPECT_GT(grid->hexes.size(), 100u);
  // Every surface vertex lies in a kept cell.
  const Vec3 h = grid->cell_size();
  std::vector<bool> kept(8 * 8 * 8, false);
  for (std::int32_t cell : grid->hex_cells) kept[static_cast<std::size_t>(cell)] = true;
  for (const Vec3& p : surface.vertices) {
    const Vec3 c = ((p - grid->min).array() / h.array()).floor();
    EXPECT_TRUE(kept[static_cast<std::size_t>(c.x() + 8 * (c.y() + 8 * c.z()))]) << p.transpose();
  }
  // The kept cells enclose the liver: more volume than it, by less than one layer of cells.
  const double liver = check_surface(surface).signed_volume_m3;
  double cells = 0.0;
  for (const Hex& hex : grid->hexes) cells += hex_volume(grid->nodes, hex);
  EXPECT_GT(cells, liver);
  EXPECT_LT(cells, 2.5 * liver);
  // Its boundary encloses the same volume (divergence theorem) and has no open edge. Every
  // node is used.
  const BoundarySurface b = hex_boundary(grid->nodes, grid->hexes);
  const SurfaceCheck check = check_surface(b.surface);
  EXPECT_EQ(check.boundary_edges, 0);
  EXPECT_NEAR(check.signed_volume_m3, cells, 1e-12);
  std::vector<int> uses(grid->nodes.size(), 0);
  for (const Hex& hex : grid->hexes) {
    for (NodeIndex n : hex) ++uses[static_cast<std::size_t>(n)];
  }
  EXPECT_EQ(std::count(uses.begin(), uses.end(), 0), 0);
}

TEST(SparseGrid, AFinerGridHugsTheSurfaceCloser) {
  const TriMesh surface = make_liver_surface(8);
  const double liver = check_surface(surface).signed_volume_m3;
  double previous = std::numeric_limits<double>::infinity();
  for (int n : {6, 11, 21}) {
    auto grid = sparse_grid(surface, {n, n, n});
    ASSERT_TRUE(grid) << grid.error().to_string();
    double cells = 0.0;
    for (const Hex& hex : grid->hexes) cells += hex_volume(grid->nodes, hex);
    EXPECT_GT(cells, liver);
    EXPECT_LT(cells, previous);
    previous = cells;
  }
  EXPECT_LT(previous, 1.3 * liver);
}

TEST(SparseGrid, ErrorsAreClear) {
  auto empty = sparse_grid(TriMesh{}, {5, 5, 5});
  ASSERT_FALSE(empty);
  EXPECT_NE(empty.error().message.find("empty"), std::string::npos);

  // A box that misses the surface: no cell.
  auto none = sparse_grid(unit_cube_surface(), {4, 4, 4}, std::pair<Vec3, Vec3>(Vec3::Constant(5), Vec3::Constant(6)));
  ASSERT_FALSE(none);
  EXPECT_NE(none.error().message.find("the grid has no cell inside the surface"), std::string::npos)
      << none.error().message;

  // An open surface: the cube without one triangle of its top.
  TriMesh open = unit_cube_surface();
  for (std::size_t t = 0; t < open.triangles.size(); ++t) {
    const Tri& tri = open.triangles[t];
    if (open.vertices[tri[0]].z() == 1.0 && open.vertices[tri[1]].z() == 1.0 && open.vertices[tri[2]].z() == 1.0) {
      open.triangles.erase(open.triangles.begin() + static_cast<std::ptrdiff_t>(t));
      break;
    }
  }
  auto leaky = sparse_grid(open, {7, 7, 7});
  ASSERT_FALSE(leaky);
  EXPECT_NE(leaky.error().message.find("not closed"), std::string::npos) << leaky.error().message;

  auto coarse = sparse_grid(unit_cube_surface(), {1, 4, 4});
  ASSERT_FALSE(coarse);
  EXPECT_NE(coarse.error().message.find("at least 2"), std::string::npos);
}

}  // namespace
}  // namespace hof::mesh
