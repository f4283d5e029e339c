#include "hof/mesh/liver_generator.h"

#include <fmt/format.h>
#include <algorithm>
#include <array>
#include <cmath>
#include <map>

#include "hof/mesh/boundary.h"
#include "hof/mesh/tet_geometry.h"
#include "hof/mesh/tetrahedralize.h"

namespace hof::mesh {

namespace {

struct Ellipsoid {
  Vec3 center;     // m
  Vec3 semi_axes;  // m
};

// The liver in an anatomical frame: x to the patient's left (the small left lobe is at
// negative x here, as seen from the front), y posterior, z cranial. Each lobe is an ellipsoid;
// every ellipsoid contains the origin, so their union is star-shaped about it and a radial
// projection of a sphere onto it is a closed surface that cannot intersect itself.
// Volumes: right lobe ≈ 1.2 L, left lobe ≈ 0.3 L, caudate ≈ 0.2 L — an adult liver is
// about 1.5 L and 0.15–0.2 m across (Gray's Anatomy, 41st ed.).
const std::array<Ellipsoid, 3> kLobes = {{
    {{0.030, 0.000, 0.000}, {0.075, 0.070, 0.055}},    // right lobe
    {{-0.050, 0.010, 0.008}, {0.065, 0.045, 0.026}},   // left lobe, thin and tapering
    {{0.010, -0.025, -0.015}, {0.040, 0.040, 0.035}},  // caudate/quadrate bulge
}};

// Blending width of the smooth union (dimensionless, in units of the ellipsoid "radius").
constexpr double kBlend = 0.12;

// Implicit function, negative inside: a smooth minimum (log-sum-exp) of the normalised
// ellipsoid radii minus one.
double liver_implicit(const Vec3& p) {
  double sum = 0.0;
  for (const Ellipsoid& e : kLobes) {
    const double g = (p - e.center).cwiseQuotient(e.semi_axes).norm() - 1.0;
    sum += std::exp(-g / kBlend);
  }
  return -kBlend * std::log(sum);
}

// Distance from the origin to the surface along unit direction `d`: march to the first sign
// change of the implicit function, then bisect.
double surface_radius(const Vec3& d) {
  constexpr double kStep = 0.002;
  constexpr double kMaxRadius = 0.5;
  double inside = 0.0;
  double outside = kStep;
  while (liver_implicit(outside * d) < 0.0 && outside < kMaxRadius) {
    inside = outside;
    outside += kStep;
  }
  for (int i = 0; i < 60; ++i) {
    const double mid = 0.5 * (inside + outside);
    (liver_implicit(mid * d) < 0.0 ? inside : outside) = mid;
  }
  return 0.5 * (inside + outside);
}

// Smooth, invertible shape maps applied after projection (each changes one coordinate by a
// monotone function or a shear, so the surface stays free of self-intersections):
// a flatter visceral (inferior) side, a domed diaphragmatic side, and a slant of the left lobe.
Vec3 shape_map(Vec3 p) {
  p.z() = p.z() * (0.8 + 0.2 * std::tanh(p.z() / 0.015));
  p.z() -= 0.02 * (p.x() / 0.1) * (p.x() / 0.1);
  p.y() += 0.15 * p.x();
  return p;
}

// Icosahedron with outward-wound faces.
void icosahedron(std::vector<Vec3>& v, std::vector<Tri>& f) {
  const double t = (1.0 + std::sqrt(5.0)) / 2.0;
  v = {{-1, t, 0},  {1, t, 0},  {-1, -t, 0}, {1, -t, 0}, {0, -1, t},  {0, 1, t},
       {0, -1, -t}, {0, 1, -t}, {t, 0, -1},  {t, 0, 1},  {-t, 0, -1}, {-t, 0, 1}};
  for (Vec3& p : v) p.normalize();
  f = {{0, 11, 5},  {0, 5, 1},  {0, 1, 7},  {0, 7, 10}, {0, 10, 11}, {1, 5, 9}, {5, 11, 4},
       {11, 10, 2}, {10, 7, 6}, {7, 1, 8},  {3, 9, 4},  {3, 4, 2},   {3, 2, 6}, {3, 6, 8},
       {3, 8, 9},   {4, 9, 5},  {2, 4, 11}, {6, 2, 10}, {8, 6, 7},   {9, 8, 1}};
  for (Tri& tri : f) {
    const Vec3 n = (v[tri[1]] - v[tri[0]]).cross(v[tri[2]] - v[tri[0]]);
    if (n.dot(v[tri[0]] + v[tri[1]] + v[tri[2]]) < 0.0) std::swap(tri[1], tri[2]);
  }
}

// Geodesic sphere: each icosahedron face split into frequency² triangles, points pushed to
// the unit sphere. Vertices on shared edges are merged through an exact key built from the
// integer barycentric coordinates, so the result does not depend on rounding.
TriMesh geodesic_sphere(int frequency) {
  std::vector<Vec3> ico;
  std::vector<Tri> faces;
  icosahedron(ico, faces);
  const int n = frequency;
  TriMesh out;
  // Key: the point as an integer combination of icosahedron vertices (weights sum to n).
  std::map<std::array<std::int64_t, 6>, NodeIndex> index_of;
  auto vertex = [&](const Tri& face, int i, int j) {
    const int k = n - i - j;
    std::array<std::pair<NodeIndex, int>, 3> w = {{{face[0], k}, {face[1], i}, {face[2], j}}};
    std::sort(w.begin(), w.end());
    std::array<std::int64_t, 6> key{};
    int m = 0;
    for (const auto& [id, weight] : w) {
      if (weight == 0) continue;
      key[2 * m] = id;
      key[2 * m + 1] = weight;
      ++m;
    }
    for (; m < 3; ++m) key[2 * m] = key[2 * m + 1] = -1;
    auto [it, inserted] = index_of.try_emplace(key, static_cast<NodeIndex>(out.vertices.size()));
    if (inserted) {
      const Vec3 p = (k * ico[face[0]] + i * ico[face[1]] + j * ico[face[2]]) / n;
      out.vertices.push_back(p.normalized());
    }
    return it->second;
  };
  for (const Tri& face : faces) {
    for (int i = 0; i < n; ++i) {
      for (int j = 0; j + i < n; ++j) {
        out.triangles.push_back({vertex(face, i, j), vertex(face, i + 1, j), vertex(face, i, j + 1)});
        if (i + j < n - 1) {
          out.triangles.push_back({vertex(face, i + 1, j), vertex(face, i + 1, j + 1), vertex(face, i, j + 1)});
        }
      }
    }
  }
  return out;
}

struct ResolutionPlan {
  std::int64_t target_tets;
  // Geodesic frequency of the surface. With the surface preserved, TetGen's quality
  // refinement yields a tet count that grows as about frequency^2.3; these were found by
  // meshing at each frequency and are checked against the target (±20%) by the tests.
  int surface_frequency;
};

ResolutionPlan plan(LiverResolution r) {
  switch (r) {
    case LiverResolution::kSimple:
      return {600, 4};
    case LiverResolution::kCoarse:
      return {2500, 7};
    case LiverResolution::kMedium:
      return {10000, 13};
    case LiverResolution::kFine:
      return {40000, 24};
  }
  return {600, 4};
}

// Spreads the low 10 bits of v so that two zero bits separate each (for 3-D Morton codes).
std::uint32_t spread_bits(std::uint32_t v) {
  v &= 0x3ffu;
  v = (v | (v << 16)) & 0x030000ffu;
  v = (v | (v << 8)) & 0x0300f00fu;
  v = (v | (v << 4)) & 0x030c30c3u;
  v = (v | (v << 2)) & 0x09249249u;
  return v;
}

}  // namespace

Mesh renumber_for_locality(const Mesh& in) {
  // Nodes along a Morton (Z-order) curve, tetrahedra by their smallest node: elements that
  // share nodes sit close in memory, which is what the solvers' gather loops and sparse
  // matrix products need from the cache.
  Vec3 lo = in.nodes.front(), hi = in.nodes.front();
  for (const Vec3& p : in.nodes) {
    lo = lo.cwiseMin(p);
    hi = hi.cwiseMax(p);
  }
  const Vec3 scale = 1023.0 * (hi - lo).cwiseMax(Vec3::Constant(1e-300)).cwiseInverse();
  std::vector<std::pair<std::uint32_t, NodeIndex>> keyed(in.nodes.size());
  for (std::size_t i = 0; i < in.nodes.size(); ++i) {
    const Vec3 q = (in.nodes[i] - lo).cwiseProduct(scale);
    const auto code = spread_bits(static_cast<std::uint32_t>(q.x())) |
                      (spread_bits(static_cast<std::uint32_t>(q.y())) << 1) |
                      (spread_bits(static_cast<std::uint32_t>(q.z())) << 2);
    keyed[i] = {code, static_cast<NodeIndex>(i)};
  }
  std::sort(keyed.begin(), keyed.end());
  std::vector<NodeIndex> new_index(in.nodes.size());
  Mesh out;
  out.nodes.resize(in.nodes.size());
  for (std::size_t k = 0; k < keyed.size(); ++k) {
    new_index[keyed[k].second] = static_cast<NodeIndex>(k);
    out.nodes[k] = in.nodes[keyed[k].second];
  }
  out.tets = in.tets;
  for (Tet& t : out.tets) {
    for (NodeIndex& n : t) n = new_index[n];
  }
  std::sort(out.tets.begin(), out.tets.end(), [](const Tet& a, const Tet& b) {
    return std::array<NodeIndex, 4>{*std::min_element(a.begin(), a.end()), a[0], a[1], a[2]} <
           std::array<NodeIndex, 4>{*std::min_element(b.begin(), b.end()), b[0], b[1], b[2]};
  });
  out.triangles = extract_boundary(out.nodes, out.tets).volume_triangles;
  return out;
}

std::int64_t target_tet_count(LiverResolution resolution) { return plan(resolution).target_tets; }

std::string_view to_string(LiverResolution resolution) {
  switch (resolution) {
    case LiverResolution::kSimple:
      return "simple";
    case LiverResolution::kCoarse:
      return "coarse";
    case LiverResolution::kMedium:
      return "medium";
    case LiverResolution::kFine:
      return "fine";
  }
  return "simple";
}

std::optional<LiverResolution> parse_liver_resolution(std::string_view name) {
  for (LiverResolution r :
       {LiverResolution::kSimple, LiverResolution::kCoarse, LiverResolution::kMedium, LiverResolution::kFine}) {
    if (name == to_string(r)) return r;
  }
  return std::nullopt;
}

TriMesh make_liver_surface(int frequency) {
  TriMesh surface = geodesic_sphere(std::max(frequency, 1));
  for (Vec3& p : surface.vertices) p = shape_map(surface_radius(p) * p);
  return surface;
}

Expected<Mesh> generate_liver(LiverResolution resolution, const ProgressSink& progress) {
  const ResolutionPlan p = plan(resolution);
  const std::string task = fmt::format("meshing liver ({})", to_string(resolution));
  if (progress) progress(task, 0.0);
  const TriMesh surface = make_liver_surface(p.surface_frequency);
  if (progress) progress(task, 0.2);

  // The surface is kept as sampled (-Y) and the interior filled by quality refinement alone:
  // the size of the tetrahedra then follows the surface triangles, which is what fixes the
  // count, and no volume bound forces small interior elements against large boundary ones
  // (that gradation is what produces slivers).
  TetrahedralizeOptions options;
  options.radius_edge_ratio = 1.5;
  options.min_dihedral_deg = 12.0;
  options.preserve_surface = true;
  auto mesh = tetrahedralize(surface, options, fmt::format("liver ({})", to_string(resolution)));
  if (!mesh) return std::unexpected(mesh.error());
  *mesh = renumber_for_locality(*mesh);
  if (progress) progress(task, 1.0);
  return mesh;
}

}  // namespace hof::mesh
