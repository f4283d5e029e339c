#pragma once
// An axis-aligned box as a closed triangle surface, normals outward: the rigid block the
// coupling and needle tests press on.

#include "hof/mesh/mesh.h"

namespace hof::testing {

inline mesh::TriMesh box_surface(const Vec3& lo, const Vec3& hi) {
  mesh::TriMesh m;
  for (int i = 0; i < 8; ++i)
    m.vertices.emplace_back(i & 1 ? hi.x() : lo.x(), i & 2 ? hi.y() : lo.y(), i & 4 ? hi.z() : lo.z());
  const auto quad = [&](int a, int b, int c, int d) {
    m.triangles.push_back({a, b, c});
    m.triangles.push_back({a, c, d});
  };
  quad(0, 2, 3, 1);  // z = lo
  quad(4, 5, 7, 6);  // z = hi
  quad(0, 1, 5, 4);  // y = lo
  quad(2, 6, 7, 3);  // y = hi
  quad(0, 4, 6, 2);  // x = lo
  quad(1, 3, 7, 5);  // x = hi
  return m;
}

}  // namespace hof::testing
