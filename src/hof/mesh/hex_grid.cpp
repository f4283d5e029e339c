#include "hof/mesh/hex_grid.h"

#include <fmt/format.h>

#include <algorithm>
#include <cmath>
#include <limits>

namespace hof::mesh {

namespace {

// A grid larger than this is a unit mistake (millimetres read as metres), not a model.
constexpr std::int64_t kMaxGridNodes = 16'000'000;

// Faces of a positively oriented Hex, wound so their normals point outward: −z, +z, −y, +y,
// −x, +x.
constexpr std::array<std::array<int, 4>, 6> kHexFaces = {
    {{0, 3, 2, 1}, {4, 5, 6, 7}, {0, 1, 5, 4}, {3, 7, 6, 2}, {0, 4, 7, 3}, {1, 2, 6, 5}}};

// Coordinate of grid plane i on axis a; the last plane sits exactly at max so that callers
// can select the far faces with ==.
double grid_coordinate(const Vec3& min, const Vec3& max, const std::array<int, 3>& n, int axis, int i) {
  if (i == n[axis] - 1) return max[axis];
  return min[axis] + (max[axis] - min[axis]) * static_cast<double>(i) / static_cast<double>(n[axis] - 1);
}

Expected<void> check_grid(const char* who, const std::array<int, 3>& n, const Vec3& min, const Vec3& max) {
  if (n[0] < 2 || n[1] < 2 || n[2] < 2) {
    return make_error(
        ErrorCode::kInvalidArgument,
        fmt::format("{}: n = ({}, {}, {}): every axis needs at least 2 nodes (one cell)", who, n[0], n[1], n[2]));
  }
  const std::int64_t nodes = std::int64_t{n[0]} * n[1] * n[2];
  if (nodes > kMaxGridNodes) {
    return make_error(ErrorCode::kInvalidArgument, fmt::format("{}: n = ({}, {}, {}) makes {} nodes, more than {}", who,
                                                               n[0], n[1], n[2], nodes, kMaxGridNodes));
  }
  if (!min.allFinite() || !max.allFinite()) {
    return make_error(ErrorCode::kInvalidArgument, fmt::format("{}: the box corners are not finite", who));
  }
  for (int a = 0; a < 3; ++a) {
    if (!(min[a] < max[a])) {
      return make_error(ErrorCode::kInvalidArgument,
                        fmt::format("{}: min ({} {} {}) must be below max ({} {} {}) on every axis (axis {} is not)",
                                    who, min.x(), min.y(), min.z(), max.x(), max.y(), max.z(), "xyz"[a]));
    }
  }
  return {};
}

// The eight nodes of cell (i, j, k) in Hex order, as full-grid node indices.
Hex cell_hex(const std::array<int, 3>& n, int i, int j, int k) {
  auto at = [&](int di, int dj, int dk) {
    return static_cast<NodeIndex>((i + di) + n[0] * ((j + dj) + n[1] * (k + dk)));
  };
  return {at(0, 0, 0), at(1, 0, 0), at(1, 1, 0), at(0, 1, 0), at(0, 0, 1), at(1, 0, 1), at(1, 1, 1), at(0, 1, 1)};
}

// Separating-axis test of a triangle against an axis-aligned box (Akenine-Möller, "Fast 3D
// triangle-box overlap testing", JGT 6(1), 2001): the nine edge × box-axis directions, the
// three box normals and the triangle normal. Touching counts as overlapping.
bool triangle_box_overlap(const Vec3& centre, const Vec3& half, const Vec3& a, const Vec3& b, const Vec3& c) {
  const Vec3 v0 = a - centre, v1 = b - centre, v2 = c - centre;
  const std::array<Vec3, 3> edges = {v1 - v0, v2 - v1, v0 - v2};
  for (const Vec3& e : edges) {
    for (int k = 0; k < 3; ++k) {
      const Vec3 axis = Vec3::Unit(k).cross(e);
      const double p0 = axis.dot(v0), p1 = axis.dot(v1), p2 = axis.dot(v2);
      const double r = half.dot(axis.cwiseAbs());
      if (std::min({p0, p1, p2}) > r || std::max({p0, p1, p2}) < -r) return false;
    }
  }
  for (int k = 0; k < 3; ++k) {
    if (std::min({v0[k], v1[k], v2[k]}) > half[k] || std::max({v0[k], v1[k], v2[k]}) < -half[k]) return false;
  }
  const Vec3 normal = edges[0].cross(edges[1]);
  return std::abs(normal.dot(v0)) <= half.dot(normal.cwiseAbs());
}

// Where a vertical ray at (px, py) crosses triangle (a, b, c) of `v`, if it does. Points on
// an edge or vertex are owned by exactly one of the triangles that share it, by the
// rasteriser's top-left rule, and each edge function is evaluated from its lower-indexed end
// so that the two triangles of an edge compute exactly opposite values: the count of
// crossings along a ray is then exact even where the ray passes through edges and vertices
// (as it does for axis-aligned test shapes).
std::optional<double> vertical_crossing(const std::vector<Vec3>& v, Tri t, double px, double py) {
  auto cross2 = [](const Vec3& p, const Vec3& q, double x, double y) {
    return (q.x() - p.x()) * (y - p.y()) - (q.y() - p.y()) * (x - p.x());
  };
  const double area2 = cross2(v[t[0]], v[t[1]], v[t[2]].x(), v[t[2]].y());
  if (area2 == 0.0) return std::nullopt;  // vertical: the ray runs along it, its neighbours count
  if (area2 < 0.0) std::swap(t[1], t[2]);
  std::array<double, 3> w{};
  for (int e = 0; e < 3; ++e) {
    const NodeIndex from = t[(e + 1) % 3], to = t[(e + 2) % 3];  // edge opposite corner e
    const bool forward = from < to;
    const Vec3& p = v[forward ? from : to];
    const Vec3& q = v[forward ? to : from];
    const double value = forward ? cross2(p, q, px, py) : -cross2(p, q, px, py);
    if (value < 0.0) return std::nullopt;
    if (value == 0.0) {
      const double dx = v[to].x() - v[from].x(), dy = v[to].y() - v[from].y();
      const bool top_left = dy < 0.0 || (dy == 0.0 && dx < 0.0);
      if (!top_left) return std::nullopt;
    }
    w[e] = value;
  }
  const double sum = w[0] + w[1] + w[2];
  if (!(sum > 0.0)) return std::nullopt;
  return (w[0] * v[t[0]].z() + w[1] * v[t[1]].z() + w[2] * v[t[2]].z()) / sum;
}

}  // namespace

std::array<double, 8> hex_shape_functions(const Vec3& xi) {
  std::array<double, 8> out{};
  for (int c = 0; c < 8; ++c) {
    const auto& s = kHexCornerSigns[c];
    out[c] = 0.125 * (1.0 + s[0] * xi.x()) * (1.0 + s[1] * xi.y()) * (1.0 + s[2] * xi.z());
  }
  return out;
}

Eigen::Matrix<double, 3, 8> hex_shape_derivatives(const Vec3& xi) {
  Eigen::Matrix<double, 3, 8> d;
  for (int c = 0; c < 8; ++c) {
    const auto& s = kHexCornerSigns[c];
    const double fx = 1.0 + s[0] * xi.x(), fy = 1.0 + s[1] * xi.y(), fz = 1.0 + s[2] * xi.z();
    d(0, c) = 0.125 * s[0] * fy * fz;
    d(1, c) = 0.125 * s[1] * fx * fz;
    d(2, c) = 0.125 * s[2] * fx * fy;
  }
  return d;
}

double hex_volume(const std::vector<Vec3>& nodes, const Hex& hex) {
  const double g = 1.0 / std::sqrt(3.0);
  double volume = 0.0;
  for (const auto& s : kHexCornerSigns) {
    const Eigen::Matrix<double, 3, 8> d = hex_shape_derivatives(Vec3(s[0] * g, s[1] * g, s[2] * g));
    Mat3 jacobian = Mat3::Zero();
    for (int c = 0; c < 8; ++c) jacobian += nodes[hex[c]] * d.col(c).transpose();
    volume += jacobian.determinant();  // Gauss weight 1
  }
  return volume;
}

Expected<HexGrid> regular_grid(std::array<int, 3> n, const Vec3& min, const Vec3& max) {
  if (auto ok = check_grid("regular grid", n, min, max); !ok) return std::unexpected(ok.error());
  HexGrid grid;
  grid.min = min;
  grid.max = max;
  grid.n = n;
  grid.nodes.reserve(static_cast<std::size_t>(n[0]) * n[1] * n[2]);
  for (int k = 0; k < n[2]; ++k) {
    for (int j = 0; j < n[1]; ++j) {
      for (int i = 0; i < n[0]; ++i) {
        grid.nodes.emplace_back(grid_coordinate(min, max, n, 0, i), grid_coordinate(min, max, n, 1, j),
                                grid_coordinate(min, max, n, 2, k));
      }
    }
  }
  for (int k = 0; k + 1 < n[2]; ++k) {
    for (int j = 0; j + 1 < n[1]; ++j) {
      for (int i = 0; i + 1 < n[0]; ++i) {
        grid.hexes.push_back(cell_hex(n, i, j, k));
        grid.hex_cells.push_back(i + (n[0] - 1) * (j + (n[1] - 1) * k));
        grid.hex_on_surface.push_back(0);
      }
    }
  }
  return grid;
}

Expected<HexGrid> sparse_grid(const TriMesh& surface, std::array<int, 3> n,
                              const std::optional<std::pair<Vec3, Vec3>>& box) {
  const char* who = "sparse grid";
  if (surface.vertices.empty() || surface.triangles.empty()) {
    return make_error(ErrorCode::kInvalidMesh, fmt::format("{}: the surface is empty (no triangles)", who));
  }
  for (std::size_t t = 0; t < surface.triangles.size(); ++t) {
    for (NodeIndex i : surface.triangles[t]) {
      if (i < 0 || static_cast<std::size_t>(i) >= surface.vertices.size()) {
        return make_error(ErrorCode::kInvalidMesh,
                          fmt::format("{}: triangle {} uses vertex {} of {}", who, t, i, surface.vertices.size()));
      }
    }
  }
  Vec3 lo = Vec3::Constant(std::numeric_limits<double>::infinity());
  Vec3 hi = -lo;
  for (const Vec3& p : surface.vertices) {
    if (!p.allFinite())
      return make_error(ErrorCode::kInvalidMesh, fmt::format("{}: a surface vertex is not finite", who));
    lo = lo.cwiseMin(p);
    hi = hi.cwiseMax(p);
  }
  if (box) {
    lo = box->first;
    hi = box->second;
  } else {
    // SOFA's SparseGridTopology::buildFromTriangleMesh enlarges the box by 1% per side, so that
    // the surface does not lie on the outer cell faces.
    const Vec3 margin = (hi - lo) / 100.0;
    lo -= margin;
    hi += margin;
  }
  if (auto ok = check_grid(who, n, lo, hi); !ok) return std::unexpected(ok.error());

  const std::array<int, 3> cells = {n[0] - 1, n[1] - 1, n[2] - 1};
  const Vec3 h((hi.x() - lo.x()) / cells[0], (hi.y() - lo.y()) / cells[1], (hi.z() - lo.z()) / cells[2]);
  const auto cell_index = [&](int i, int j, int k) {
    return static_cast<std::size_t>(i) +
           static_cast<std::size_t>(cells[0]) * (j + static_cast<std::size_t>(cells[1]) * k);
  };
  // Per cell: 0 empty, kSurfaceCell (the surface passes through it) or kInsideCell.
  constexpr std::uint8_t kSurfaceCell = 1, kInsideCell = 2;
  std::vector<std::uint8_t> keep(static_cast<std::size_t>(cells[0]) * cells[1] * cells[2], 0);
  const auto clamp_cell = [&](double value, int axis) {
    return std::clamp(static_cast<int>(std::floor((value - lo[axis]) / h[axis])), 0, cells[axis] - 1);
  };

  // Cells the surface passes through. The box is shrunk by a hair so that a triangle lying in
  // a cell face (an axis-aligned surface on a grid plane) does not claim the cell outside it.
  const Vec3 half = 0.5 * h * (1.0 - 1e-9);
  for (const Tri& t : surface.triangles) {
    const Vec3& a = surface.vertices[t[0]];
    const Vec3& b = surface.vertices[t[1]];
    const Vec3& c = surface.vertices[t[2]];
    const Vec3 tmin = a.cwiseMin(b).cwiseMin(c), tmax = a.cwiseMax(b).cwiseMax(c);
    if ((tmax.array() < lo.array()).any() || (tmin.array() > hi.array()).any()) continue;
    const int i0 = clamp_cell(tmin.x(), 0), i1 = clamp_cell(tmax.x(), 0);
    const int j0 = clamp_cell(tmin.y(), 1), j1 = clamp_cell(tmax.y(), 1);
    const int k0 = clamp_cell(tmin.z(), 2), k1 = clamp_cell(tmax.z(), 2);
    for (int k = k0; k <= k1; ++k) {
      for (int j = j0; j <= j1; ++j) {
        for (int i = i0; i <= i1; ++i) {
          const Vec3 centre = lo + Vec3((i + 0.5) * h.x(), (j + 0.5) * h.y(), (k + 0.5) * h.z());
          if (triangle_box_overlap(centre, half, a, b, c)) keep[cell_index(i, j, k)] = kSurfaceCell;
        }
      }
    }
  }

  // Cells whose centre is inside: a vertical ray through each column of cell centres; a centre
  // is inside when the surface crosses the ray above it an odd number of times (an odd total
  // means the surface is not closed). The crossings of each column are found from the
  // triangles whose projection covers it.
  std::vector<std::vector<double>> crossings(static_cast<std::size_t>(cells[0]) * cells[1]);
  const auto column_range = [&](double from, double to, int axis) {
    // Columns whose centre coordinate lies in [from, to].
    const int first = std::max(0, static_cast<int>(std::ceil((from - lo[axis]) / h[axis] - 0.5)));
    const int last = std::min(cells[axis] - 1, static_cast<int>(std::floor((to - lo[axis]) / h[axis] - 0.5)));
    return std::pair<int, int>(first, last);
  };
  for (const Tri& t : surface.triangles) {
    const Vec3& a = surface.vertices[t[0]];
    const Vec3& b = surface.vertices[t[1]];
    const Vec3& c = surface.vertices[t[2]];
    const auto [i0, i1] = column_range(std::min({a.x(), b.x(), c.x()}), std::max({a.x(), b.x(), c.x()}), 0);
    const auto [j0, j1] = column_range(std::min({a.y(), b.y(), c.y()}), std::max({a.y(), b.y(), c.y()}), 1);
    for (int j = j0; j <= j1; ++j) {
      for (int i = i0; i <= i1; ++i) {
        const double px = lo.x() + (i + 0.5) * h.x(), py = lo.y() + (j + 0.5) * h.y();
        if (const auto z = vertical_crossing(surface.vertices, t, px, py)) {
          crossings[static_cast<std::size_t>(i) + static_cast<std::size_t>(cells[0]) * j].push_back(*z);
        }
      }
    }
  }
  std::vector<std::uint8_t> centre_inside(keep.size(), 0);
  for (int j = 0; j < cells[1]; ++j) {
    for (int i = 0; i < cells[0]; ++i) {
      std::vector<double>& zs = crossings[static_cast<std::size_t>(i) + static_cast<std::size_t>(cells[0]) * j];
      if (zs.size() % 2 != 0) {
        return make_error(ErrorCode::kInvalidMesh,
                          fmt::format("{}: the surface is not closed: a vertical ray at x = {:.6g}, y = {:.6g} m "
                                      "crosses it {} times (an odd number)",
                                      who, lo.x() + (i + 0.5) * h.x(), lo.y() + (j + 0.5) * h.y(), zs.size()));
      }
      std::sort(zs.begin(), zs.end());
      for (int k = 0; k < cells[2]; ++k) {
        const double z = lo.z() + (k + 0.5) * h.z();
        const auto above = zs.end() - std::upper_bound(zs.begin(), zs.end(), z);
        if (above % 2 == 1) centre_inside[cell_index(i, j, k)] = 1;
      }
    }
  }

  // SOFA's rule (SparseGridTopology::voxelizeTriangleMesh): every cell starts inside; a flood
  // fill from each cell of the grid's outer layer through face neighbours that the surface
  // does not cross (SparseGridTopology::propagateFrom) marks the cells outside. What it cannot
  // reach stays inside — also a pocket of outside space that crossed cells wall in (a cavity,
  // or a concave fold a coarse grid does not resolve), which the centre test drops. The two
  // agree on every other cell, except where the surface lies in grid planes: HoF then counts
  // no cell as crossed (above), the fill leaks through, and the centre test keeps the cells
  // inside. A cell is kept when either says inside.
  std::vector<std::uint8_t> reached(keep.size(), 0);
  std::vector<std::array<int, 3>> stack;
  const auto visit = [&](int i, int j, int k) {
    const std::size_t at = cell_index(i, j, k);
    if (reached[at] != 0 || keep[at] == kSurfaceCell) return;
    reached[at] = 1;
    stack.push_back({i, j, k});
  };
  for (int k = 0; k < cells[2]; ++k) {
    for (int j = 0; j < cells[1]; ++j) {
      for (int i = 0; i < cells[0]; ++i) {
        if (i == 0 || j == 0 || k == 0 || i == cells[0] - 1 || j == cells[1] - 1 || k == cells[2] - 1) visit(i, j, k);
      }
    }
  }
  while (!stack.empty()) {
    const auto [i, j, k] = stack.back();
    stack.pop_back();
    if (i > 0) visit(i - 1, j, k);
    if (i + 1 < cells[0]) visit(i + 1, j, k);
    if (j > 0) visit(i, j - 1, k);
    if (j + 1 < cells[1]) visit(i, j + 1, k);
    if (k > 0) visit(i, j, k - 1);
    if (k + 1 < cells[2]) visit(i, j, k + 1);
  }
  for (std::size_t at = 0; at < keep.size(); ++at) {
    if (keep[at] == 0 && (centre_inside[at] != 0 || reached[at] == 0)) keep[at] = kInsideCell;
  }

  HexGrid grid;
  grid.min = lo;
  grid.max = hi;
  grid.n = n;
  // SOFA's order (SparseGridTopology::buildFromRegularGridTypes): the cells the surface
  // crosses, then the inside ones, each in cell order; nodes sorted by x, then y, then z (its
  // map keyed by position). Node and element indices in a SOFA scene then mean the same here.
  std::vector<NodeIndex> renumber(static_cast<std::size_t>(n[0]) * n[1] * n[2], -1);
  for (const std::uint8_t kind : {kSurfaceCell, kInsideCell}) {
    for (int k = 0; k < cells[2]; ++k) {
      for (int j = 0; j < cells[1]; ++j) {
        for (int i = 0; i < cells[0]; ++i) {
          if (keep[cell_index(i, j, k)] != kind) continue;
          grid.hexes.push_back(cell_hex(n, i, j, k));
          grid.hex_cells.push_back(static_cast<std::int32_t>(cell_index(i, j, k)));
          grid.hex_on_surface.push_back(kind == kSurfaceCell ? 1 : 0);
          for (NodeIndex g : grid.hexes.back()) renumber[static_cast<std::size_t>(g)] = 0;
        }
      }
    }
  }
  if (grid.hexes.empty()) {
    return make_error(ErrorCode::kInvalidArgument,
                      fmt::format("{}: the grid has no cell inside the surface (n = ({}, {}, {}), box ({:.6g} {:.6g} "
                                  "{:.6g}) to ({:.6g} {:.6g} {:.6g}) m)",
                                  who, n[0], n[1], n[2], lo.x(), lo.y(), lo.z(), hi.x(), hi.y(), hi.z()));
  }
  for (int i = 0; i < n[0]; ++i) {
    for (int j = 0; j < n[1]; ++j) {
      for (int k = 0; k < n[2]; ++k) {
        NodeIndex& slot = renumber[static_cast<std::size_t>(i) +
                                   static_cast<std::size_t>(n[0]) * (j + static_cast<std::size_t>(n[1]) * k)];
        if (slot < 0) continue;
        slot = static_cast<NodeIndex>(grid.nodes.size());
        grid.nodes.emplace_back(grid_coordinate(lo, hi, n, 0, i), grid_coordinate(lo, hi, n, 1, j),
                                grid_coordinate(lo, hi, n, 2, k));
      }
    }
  }
  for (Hex& hex : grid.hexes) {
    for (NodeIndex& g : hex) g = renumber[static_cast<std::size_t>(g)];
  }
  return grid;
}

BoundarySurface hex_boundary(const std::vector<Vec3>& nodes, const std::vector<Hex>& hexes) {
  // Sort all 6H faces by their sorted node quadruple; a face seen once is on the boundary
  // (sorting rather than hashing keeps the result independent of platforms).
  struct FaceRecord {
    std::array<NodeIndex, 4> key;
    std::int32_t hex;
    std::int8_t local_face;
  };
  std::vector<FaceRecord> faces;
  faces.reserve(hexes.size() * 6);
  for (std::size_t h = 0; h < hexes.size(); ++h) {
    for (std::int8_t f = 0; f < 6; ++f) {
      std::array<NodeIndex, 4> key{};
      for (int c = 0; c < 4; ++c) key[c] = hexes[h][kHexFaces[f][c]];
      std::sort(key.begin(), key.end());
      faces.push_back({key, static_cast<std::int32_t>(h), f});
    }
  }
  std::sort(faces.begin(), faces.end(), [](const FaceRecord& a, const FaceRecord& b) {
    return a.key != b.key ? a.key < b.key : (a.hex != b.hex ? a.hex < b.hex : a.local_face < b.local_face);
  });
  BoundarySurface out;
  std::vector<std::pair<std::int32_t, std::int8_t>> boundary;  // (hex, local face)
  for (std::size_t i = 0; i < faces.size();) {
    std::size_t j = i + 1;
    while (j < faces.size() && faces[j].key == faces[i].key) ++j;
    if (j - i == 1) boundary.emplace_back(faces[i].hex, faces[i].local_face);
    if (j - i > 2) ++out.non_manifold_faces;
    i = j;
  }
  std::sort(boundary.begin(), boundary.end());

  out.volume_to_surface.assign(nodes.size(), -1);
  out.volume_triangles.reserve(2 * boundary.size());
  out.triangle_tet.reserve(2 * boundary.size());
  for (const auto& [h, f] : boundary) {
    const Hex& hex = hexes[static_cast<std::size_t>(h)];
    const auto& q = kHexFaces[f];
    // An inverted hexahedron's faces are flipped so that they still face out of it.
    const bool inverted = hex_volume(nodes, hex) < 0.0;
    for (const Tri& local : {Tri{q[0], q[1], q[2]}, Tri{q[0], q[2], q[3]}}) {
      Tri tri = {hex[local[0]], hex[local[1]], hex[local[2]]};
      if (inverted) std::swap(tri[1], tri[2]);
      out.volume_triangles.push_back(tri);
      out.triangle_tet.push_back(h);
      for (NodeIndex n : tri) out.volume_to_surface[n] = 0;  // mark; numbered below
    }
  }
  number_boundary_vertices(nodes, out);
  return out;
}

}  // namespace hof::mesh
