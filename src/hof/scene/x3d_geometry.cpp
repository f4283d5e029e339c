// Triangle meshes of the X3D geometry nodes (ISO/IEC 19775-1). Each builder works in the
// node's local frame; the reader transforms the result into the world frame.

#include "hof/scene/detail/x3d_geometry.h"

#include <algorithm>
#include <cmath>
#include <numbers>
#include <utility>

namespace hof::scene::detail {
namespace {

constexpr int kSphereStacks = 16;
constexpr int kSphereSlices = 32;  // multiple of 4: the tessellation reaches ±r on x and z

void add_quad(mesh::TriMesh& m, mesh::NodeIndex a, mesh::NodeIndex b, mesh::NodeIndex c, mesh::NodeIndex d) {
  m.triangles.push_back({a, b, c});
  m.triangles.push_back({a, c, d});
}

mesh::NodeIndex index(std::size_t i) { return static_cast<mesh::NodeIndex>(i); }

}  // namespace

void orient_outward(mesh::TriMesh& m) {
  for (auto& t : m.triangles) {
    const Vec3& a = m.vertices[static_cast<std::size_t>(t[0])];
    const Vec3& b = m.vertices[static_cast<std::size_t>(t[1])];
    const Vec3& c = m.vertices[static_cast<std::size_t>(t[2])];
    if ((b - a).cross(c - a).dot(a + b + c) < 0.0) std::swap(t[1], t[2]);
  }
}

mesh::TriMesh make_sphere(double r) {
  mesh::TriMesh m;
  m.vertices.emplace_back(0.0, r, 0.0);
  for (int i = 1; i < kSphereStacks; ++i) {
    const double phi = std::numbers::pi * i / kSphereStacks;
    for (int j = 0; j < kSphereSlices; ++j) {
      const double theta = 2.0 * std::numbers::pi * j / kSphereSlices;
      m.vertices.emplace_back(r * std::sin(phi) * std::sin(theta), r * std::cos(phi),
                              r * std::sin(phi) * std::cos(theta));
    }
  }
  m.vertices.emplace_back(0.0, -r, 0.0);
  const auto ring = [](int i, int j) {
    return static_cast<mesh::NodeIndex>(1 + (i - 1) * kSphereSlices + j % kSphereSlices);
  };
  const auto south = index(m.vertices.size() - 1);
  for (int j = 0; j < kSphereSlices; ++j) {
    m.triangles.push_back({0, ring(1, j), ring(1, j + 1)});
    for (int i = 1; i + 1 < kSphereStacks; ++i)
      add_quad(m, ring(i, j), ring(i + 1, j), ring(i + 1, j + 1), ring(i, j + 1));
    m.triangles.push_back({south, ring(kSphereStacks - 1, j + 1), ring(kSphereStacks - 1, j)});
  }
  orient_outward(m);
  return m;
}

mesh::TriMesh make_box(const Vec3& size) {
  mesh::TriMesh m;
  const Vec3 h = 0.5 * size;
  for (int i = 0; i < 8; ++i)
    m.vertices.emplace_back((i & 1) ? h.x() : -h.x(), (i & 2) ? h.y() : -h.y(), (i & 4) ? h.z() : -h.z());
  add_quad(m, 0, 2, 3, 1);  // z−
  add_quad(m, 4, 5, 7, 6);  // z+
  add_quad(m, 0, 1, 5, 4);  // y−
  add_quad(m, 2, 6, 7, 3);  // y+
  add_quad(m, 0, 4, 6, 2);  // x−
  add_quad(m, 1, 3, 7, 5);  // x+
  orient_outward(m);
  return m;
}

mesh::TriMesh make_round(double bottom_radius, double top_radius, double height, bool side, bool bottom, bool top) {
  mesh::TriMesh m;
  constexpr int n = kRoundSlices;  // a constant: the lambdas below need not capture it
  for (int j = 0; j < n; ++j) {
    const double t = 2.0 * std::numbers::pi * j / n;
    m.vertices.emplace_back(bottom_radius * std::sin(t), -0.5 * height, bottom_radius * std::cos(t));
  }
  const bool cone = top_radius <= 0.0;
  if (cone) {
    m.vertices.emplace_back(0.0, 0.5 * height, 0.0);
  } else {
    for (int j = 0; j < n; ++j) {
      const double t = 2.0 * std::numbers::pi * j / n;
      m.vertices.emplace_back(top_radius * std::sin(t), 0.5 * height, top_radius * std::cos(t));
    }
  }
  const auto b = [](int j) { return static_cast<mesh::NodeIndex>(j % n); };
  const auto tp = [cone](int j) { return static_cast<mesh::NodeIndex>(cone ? n : n + j % n); };
  for (int j = 0; j < n && side; ++j) {
    if (cone)
      m.triangles.push_back({b(j), b(j + 1), tp(j)});
    else
      add_quad(m, b(j), b(j + 1), tp(j + 1), tp(j));
  }
  if (bottom) {
    const auto c = index(m.vertices.size());
    m.vertices.emplace_back(0.0, -0.5 * height, 0.0);
    for (int j = 0; j < n; ++j) m.triangles.push_back({c, b(j + 1), b(j)});
  }
  if (top && !cone) {
    const auto c = index(m.vertices.size());
    m.vertices.emplace_back(0.0, 0.5 * height, 0.0);
    for (int j = 0; j < n; ++j) m.triangles.push_back({c, tp(j), tp(j + 1)});
  }
  orient_outward(m);
  return m;
}

mesh::TriMesh make_rectangle(double size_x, double size_y) {
  mesh::TriMesh m;
  const double x = 0.5 * size_x, y = 0.5 * size_y;
  m.vertices = {Vec3(-x, -y, 0), Vec3(x, -y, 0), Vec3(x, y, 0), Vec3(-x, y, 0)};
  m.triangles = {{0, 1, 2}, {0, 2, 3}};
  return m;
}

mesh::TriMesh make_disk(double inner_radius, double outer_radius) {
  mesh::TriMesh m;
  if (!(outer_radius > inner_radius) || outer_radius <= 0.0) return m;
  constexpr int n = kRoundSlices;
  // Angle increasing from +x toward +y: counter-clockwise seen from +z, the front side.
  for (int j = 0; j < n; ++j) {
    const double t = 2.0 * std::numbers::pi * j / n;
    m.vertices.emplace_back(outer_radius * std::cos(t), outer_radius * std::sin(t), 0.0);
  }
  const auto outer = [](int j) { return static_cast<mesh::NodeIndex>(j % n); };
  if (inner_radius <= 0.0) {
    m.vertices.emplace_back(0.0, 0.0, 0.0);
    for (int j = 0; j < n; ++j) m.triangles.push_back({n, outer(j), outer(j + 1)});
    return m;
  }
  for (int j = 0; j < n; ++j) {
    const double t = 2.0 * std::numbers::pi * j / n;
    m.vertices.emplace_back(inner_radius * std::cos(t), inner_radius * std::sin(t), 0.0);
  }
  const auto inner = [](int j) { return static_cast<mesh::NodeIndex>(n + j % n); };
  for (int j = 0; j < n; ++j) add_quad(m, inner(j), outer(j), outer(j + 1), inner(j + 1));
  return m;
}

mesh::TriMesh make_elevation_grid(std::int64_t x_dimension, std::int64_t z_dimension, double x_spacing,
                                  double z_spacing, std::span<const double> height) {
  mesh::TriMesh m;
  if (x_dimension < 2 || z_dimension < 2) return m;  // no quad: nothing to draw (the spec's "empty")
  for (std::int64_t j = 0; j < z_dimension; ++j) {
    for (std::int64_t i = 0; i < x_dimension; ++i) {
      m.vertices.emplace_back(x_spacing * static_cast<double>(i), height[static_cast<std::size_t>(i + j * x_dimension)],
                              z_spacing * static_cast<double>(j));
    }
  }
  const auto v = [x_dimension](std::int64_t i, std::int64_t j) {
    return static_cast<mesh::NodeIndex>(i + j * x_dimension);
  };
  // (i, j) → (i, j+1) → (i+1, j+1) → (i+1, j) turns counter-clockwise seen from +y: the spec's
  // default (ccw TRUE) gives the grid normals with a positive y component.
  for (std::int64_t j = 0; j + 1 < z_dimension; ++j) {
    for (std::int64_t i = 0; i + 1 < x_dimension; ++i) add_quad(m, v(i, j), v(i, j + 1), v(i + 1, j + 1), v(i + 1, j));
  }
  return m;
}

mesh::TriMesh make_extrusion(std::span<const Vec2> cross_section, std::span<const Vec3> spine,
                             std::span<const Vec2> scale, std::span<const Vec4> orientation, bool begin_cap,
                             bool end_cap) {
  mesh::TriMesh m;
  const std::size_t ns = spine.size();
  const std::size_t nc = cross_section.size();
  constexpr double kTiny = 1e-12;
  const bool spine_closed = (spine.front() - spine.back()).norm() < kTiny;
  const bool section_closed = (cross_section.front() - cross_section.back()).norm() < kTiny;

  // The SCP of each spine point (19775-1, Extrusion): Y along the spine (central differences,
  // one-sided at open ends, wrapped at a closed spine's ends), Z normal to the spine's bend
  // (taken from the neighbour where the spine is straight, flipped to keep its sense), X = Y × Z.
  std::vector<Vec3> ys(ns), zs(ns);
  for (std::size_t i = 0; i < ns; ++i) {
    Vec3 y;
    if (i == 0 || i + 1 == ns) {
      y = spine_closed ? Vec3(spine[1] - spine[ns - 2])
                       : (i == 0 ? Vec3(spine[1] - spine[0]) : Vec3(spine[ns - 1] - spine[ns - 2]));
    } else {
      y = spine[i + 1] - spine[i - 1];
    }
    ys[i] = y;
    Vec3 z = Vec3::Zero();
    if (i > 0 && i + 1 < ns)
      z = (spine[i + 1] - spine[i]).cross(spine[i - 1] - spine[i]);
    else if (spine_closed)
      z = (spine[1] - spine[0]).cross(spine[ns - 2] - spine[0]);
    zs[i] = z;
  }
  // A zero Y (coincident points) takes its neighbour's; a spine with no length at all keeps +y.
  for (std::size_t i = 1; i < ns; ++i)
    if (ys[i].norm() < kTiny) ys[i] = ys[i - 1];
  for (std::size_t i = ns - 1; i-- > 0;)
    if (ys[i].norm() < kTiny) ys[i] = ys[i + 1];
  for (Vec3& y : ys) y = y.norm() < kTiny ? Vec3::UnitY() : Vec3(y.normalized());
  // Open ends take the Z of their neighbour; collinear points the previous Z.
  if (!spine_closed && ns > 2) {
    zs[0] = zs[1];
    zs[ns - 1] = zs[ns - 2];
  }
  const bool any_z = std::ranges::any_of(zs, [](const Vec3& z) { return z.norm() >= kTiny; });
  if (!any_z) {
    // Entirely collinear spine: the rotation taking +y to the spine direction takes +z to Z.
    const Eigen::Quaterniond q = Eigen::Quaterniond::FromTwoVectors(Vec3::UnitY(), ys[0]);
    for (Vec3& z : zs) z = q * Vec3::UnitZ();
  } else {
    std::size_t first = 0;
    while (zs[first].norm() < kTiny) ++first;
    for (std::size_t i = 0; i < first; ++i) zs[i] = zs[first];
    for (std::size_t i = first + 1; i < ns; ++i)
      if (zs[i].norm() < kTiny) zs[i] = zs[i - 1];
    for (Vec3& z : zs) z.normalize();
    for (std::size_t i = 1; i < ns; ++i)
      if (zs[i].dot(zs[i - 1]) < 0.0) zs[i] = -zs[i];
  }

  for (std::size_t i = 0; i < ns; ++i) {
    const Vec3 y = ys[i];
    // Z made orthogonal to Y (they are by construction for a planar bend; not after the
    // neighbour fallbacks above), then X completes the right-handed frame.
    Vec3 z = zs[i] - zs[i].dot(y) * y;
    z = z.norm() < kTiny ? Vec3(Eigen::Quaterniond::FromTwoVectors(Vec3::UnitY(), y) * Vec3::UnitZ())
                         : Vec3(z.normalized());
    const Vec3 x = y.cross(z);
    Eigen::Matrix3d scp;
    scp << x, y, z;
    const Vec2 s = scale[std::min(i, scale.size() - 1)];
    const Vec4 r = orientation[std::min(i, orientation.size() - 1)];
    const Vec3 axis(r[0], r[1], r[2]);
    const Eigen::Matrix3d R = axis.norm() > kTiny ? Eigen::AngleAxisd(r[3], axis.normalized()).toRotationMatrix()
                                                  : Eigen::Matrix3d::Identity();
    // Scaled, then rotated by orientation, then placed in the SCP.
    for (const Vec2& c : cross_section)
      m.vertices.push_back(spine[i] + scp * (R * Vec3(s.x() * c.x(), 0.0, s.y() * c.y())));
  }
  const auto v = [nc](std::size_t i, std::size_t k) { return static_cast<mesh::NodeIndex>(i * nc + k); };
  // Sides: the quad (i, k) (i, k+1) (i+1, k+1) (i+1, k) faces outward for the default data (a
  // clockwise-from-above square section swept up +y), the orientation ccw TRUE means.
  for (std::size_t i = 0; i + 1 < ns; ++i) {
    for (std::size_t k = 0; k + 1 < nc; ++k) add_quad(m, v(i, k), v(i, k + 1), v(i + 1, k + 1), v(i + 1, k));
  }
  // Caps, fan-triangulated (the spec's convex TRUE default): the begin cap faces back along the
  // spine, the end cap forward. A closed spine has no ends to cap.
  const std::size_t cap_points = section_closed ? nc - 1 : nc;
  if (!spine_closed && cap_points >= 3) {
    for (std::size_t k = 1; k + 1 < cap_points; ++k) {
      if (begin_cap) m.triangles.push_back({v(0, 0), v(0, k + 1), v(0, k)});
      if (end_cap) m.triangles.push_back({v(ns - 1, 0), v(ns - 1, k), v(ns - 1, k + 1)});
    }
  }
  return m;
}

std::size_t append_grouped(std::vector<mesh::Tri>& out, VertexGrouping grouping,
                           std::span<const std::vector<mesh::NodeIndex>> runs) {
  std::size_t left_out = 0;
  for (const std::vector<mesh::NodeIndex>& run : runs) {
    const std::size_t n = run.size();
    switch (grouping) {
      case VertexGrouping::kTriangles:
        for (std::size_t i = 0; i + 2 < n; i += 3) out.push_back({run[i], run[i + 1], run[i + 2]});
        left_out += n % 3;
        break;
      case VertexGrouping::kQuads:
        for (std::size_t i = 0; i + 3 < n; i += 4) {
          out.push_back({run[i], run[i + 1], run[i + 2]});
          out.push_back({run[i], run[i + 2], run[i + 3]});
        }
        left_out += n % 4;
        break;
      case VertexGrouping::kFans:
      case VertexGrouping::kPolygons:
        for (std::size_t k = 1; k + 1 < n; ++k) out.push_back({run[0], run[k], run[k + 1]});
        if (n < 3) left_out += n;
        break;
      case VertexGrouping::kStrips:
        // Triangle k is (k, k+1, k+2); every other one is reversed so that all keep the
        // strip's winding (19775-1, TriangleStripSet).
        for (std::size_t k = 0; k + 2 < n; ++k) {
          if (k % 2 == 0)
            out.push_back({run[k], run[k + 1], run[k + 2]});
          else
            out.push_back({run[k + 1], run[k], run[k + 2]});
        }
        if (n < 3) left_out += n;
        break;
    }
  }
  return left_out;
}

}  // namespace hof::scene::detail
