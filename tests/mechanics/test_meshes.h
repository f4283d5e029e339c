#pragma once
// Structured meshes for analytic tests: tetrahedral boxes, and hexahedral grids (regular or with
// their interior distorted) with the hexahedral FEM configuration the mechanics and coupling
// tests share.

#include <gtest/gtest.h>

#include <array>
#include <random>
#include <vector>

#include "hof/mechanics/mechanical_model.h"
#include "hof/mesh/hex_grid.h"
#include "hof/mesh/mesh.h"
#include "hof/mesh/tet_geometry.h"

namespace hof::mechanics::testing {

struct BoxMesh {
  std::vector<Vec3> nodes;
  std::vector<mesh::Tet> tets;
  int nx, ny, nz;
  Vec3 size;
  [[nodiscard]] std::int32_t index(int i, int j, int k) const { return (k * (ny + 1) + j) * (nx + 1) + i; }
};

/// The box [0, size] split into nx·ny·nz cubes of 6 tetrahedra each (Kuhn/Freudenthal split
/// around each cube's main diagonal: conforming across cubes), positively oriented.
inline BoxMesh box_mesh(int nx, int ny, int nz, const Vec3& size) {
  BoxMesh m{{}, {}, nx, ny, nz, size};
  for (int k = 0; k <= nz; ++k) {
    for (int j = 0; j <= ny; ++j) {
      for (int i = 0; i <= nx; ++i) {
        // The far faces sit exactly at `size`, so tests can select them with ==.
        auto at = [](double length, int step, int steps) { return step == steps ? length : length * step / steps; };
        m.nodes.emplace_back(at(size.x(), i, nx), at(size.y(), j, ny), at(size.z(), k, nz));
      }
    }
  }
  // Corner c of a cube: bit 0 = +x, bit 1 = +y, bit 2 = +z. The six paths 0 → 7 along edges.
  const int paths[6][2] = {{1, 3}, {1, 5}, {2, 3}, {2, 6}, {4, 5}, {4, 6}};
  for (int k = 0; k < nz; ++k) {
    for (int j = 0; j < ny; ++j) {
      for (int i = 0; i < nx; ++i) {
        auto corner = [&](int c) { return m.index(i + (c & 1), j + ((c >> 1) & 1), k + ((c >> 2) & 1)); };
        for (const auto& p : paths) {
          mesh::Tet t = {corner(0), corner(p[0]), corner(p[1]), corner(7)};
          const auto c = mesh::tet_corners(m.nodes, t);
          if (mesh::tet_signed_volume(c[0], c[1], c[2], c[3]) < 0) std::swap(t[2], t[3]);
          m.tets.push_back(t);
        }
      }
    }
  }
  return m;
}

/// A regular grid of n[0]·n[1]·n[2] nodes over the box [0, size].
inline mesh::HexGrid box_grid(std::array<int, 3> n, const Vec3& size) {
  auto grid = mesh::regular_grid(n, Vec3::Zero(), size);
  EXPECT_TRUE(grid) << grid.error().to_string();
  return *grid;
}

// Moves the interior nodes of a grid by up to `fraction` of a cell, deterministically: the
// hexahedra become general (non-parallel faces, non-planar sides).
inline void distort_interior(mesh::HexGrid& grid, double fraction) {
  std::mt19937 random(7);
  std::uniform_real_distribution<double> uniform(-fraction, fraction);
  const Vec3 h = grid.cell_size();
  for (Vec3& p : grid.nodes) {
    const bool interior = ((p.array() > grid.min.array() + 1e-12) && (p.array() < grid.max.array() - 1e-12)).all();
    if (interior) p += Vec3(uniform(random) * h.x(), uniform(random) * h.y(), uniform(random) * h.z());
  }
}

inline ForceFieldConfig hex_field(FemMethod method, double young, double poisson) {
  ForceFieldConfig f;
  f.name = "FEM";
  f.hexahedron_fem = HexahedronFemConfig{};
  f.hexahedron_fem->young_modulus_pa = young;
  f.hexahedron_fem->poisson_ratio = poisson;
  f.hexahedron_fem->method = method;
  return f;
}

}  // namespace hof::mechanics::testing
