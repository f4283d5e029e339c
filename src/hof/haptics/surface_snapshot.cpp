#include "hof/haptics/surface_snapshot.h"

#include <algorithm>
#include <chrono>

namespace hof::haptics {

namespace {

void compute_vertex_normals(SurfaceSnapshot& s) {
  std::fill(s.vertex_normals.begin(), s.vertex_normals.end(), Vec3::Zero());
  for (const mesh::Tri& t : s.triangles) {
    // Area-weighted: the cross product's length is twice the area.
    const Vec3 n = (s.vertices[t[1]] - s.vertices[t[0]]).cross(s.vertices[t[2]] - s.vertices[t[0]]);
    for (mesh::NodeIndex v : t) s.vertex_normals[v] += n;
  }
  for (Vec3& n : s.vertex_normals) {
    const double length = n.norm();
    n = length > 0.0 ? Vec3(n / length) : Vec3::Zero();
  }
}

}  // namespace

Vec3 SurfaceSnapshot::face_normal(std::int32_t t) const {
  const mesh::Tri& tri = triangles[t];
  const Vec3 n = (vertices[tri[1]] - vertices[tri[0]]).cross(vertices[tri[2]] - vertices[tri[0]]);
  const double length = n.norm();
  return length > 0.0 ? Vec3(n / length) : Vec3::Zero();
}

Vec3 SurfaceSnapshot::shaded_normal(std::int32_t t, const Vec3& w) const {
  const mesh::Tri& tri = triangles[t];
  const Vec3 n = w[0] * vertex_normals[tri[0]] + w[1] * vertex_normals[tri[1]] + w[2] * vertex_normals[tri[2]];
  const double length = n.norm();
  return length > 0.0 ? Vec3(n / length) : face_normal(t);
}

SurfaceSnapshot make_snapshot(const mesh::TriMesh& surface, const collision::AabbTreeOptions& options) {
  SurfaceSnapshot s;
  s.vertices = surface.vertices;
  s.triangles = surface.triangles;
  s.velocities.assign(surface.vertices.size(), Vec3::Zero());
  s.vertex_normals.assign(surface.vertices.size(), Vec3::Zero());
  compute_vertex_normals(s);
  s.tree = collision::AabbTree::build(s.view(), options);
  s.parts.push_back(SurfacePart{0, static_cast<std::int32_t>(s.vertices.size()), 0,
                                static_cast<std::int32_t>(s.triangles.size()), false, false});
  return s;
}

SurfaceSnapshot make_snapshot(std::span<const mesh::TriMesh> surfaces, std::span<const bool> is_static,
                              std::span<const bool> closed, const collision::AabbTreeOptions& options) {
  SurfaceSnapshot s;
  bool all_static = !surfaces.empty();
  for (std::size_t i = 0; i < surfaces.size(); ++i) {
    const mesh::TriMesh& m = surfaces[i];
    SurfacePart part;
    part.first_vertex = static_cast<std::int32_t>(s.vertices.size());
    part.vertex_count = static_cast<std::int32_t>(m.vertices.size());
    part.first_triangle = static_cast<std::int32_t>(s.triangles.size());
    part.triangle_count = static_cast<std::int32_t>(m.triangles.size());
    part.is_static = i < is_static.size() && is_static[i];
    part.closed = i < closed.size() && closed[i];
    all_static = all_static && part.is_static;
    s.vertices.insert(s.vertices.end(), m.vertices.begin(), m.vertices.end());
    for (const mesh::Tri& t : m.triangles) {
      s.triangles.push_back({t[0] + part.first_vertex, t[1] + part.first_vertex, t[2] + part.first_vertex});
    }
    s.parts.push_back(part);
  }
  s.velocities.assign(s.vertices.size(), Vec3::Zero());
  s.vertex_normals.assign(s.vertices.size(), Vec3::Zero());
  compute_vertex_normals(s);
  s.tree = collision::AabbTree::build(s.view(), options);
  // Nothing simulated behind it (rigid shapes only, or no shape at all): never stale.
  s.is_static = all_static || surfaces.empty();
  return s;
}

void update_snapshot(SurfaceSnapshot& s, std::span<const Vec3> positions, std::span<const Vec3> velocities,
                     double time_s) {
  const auto start = std::chrono::steady_clock::now();
  std::copy(positions.begin(), positions.end(), s.vertices.begin());
  if (velocities.empty()) {
    std::fill(s.velocities.begin(), s.velocities.end(), Vec3::Zero());
  } else {
    std::copy(velocities.begin(), velocities.end(), s.velocities.begin());
  }
  compute_vertex_normals(s);
  if (s.tree.refit(s.view())) s.tree = collision::AabbTree::build(s.view(), s.tree.options());
  s.time_s = time_s;
  ++s.sequence;
  s.refit_s = std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
}

void copy_snapshot_geometry(SurfaceSnapshot& to, const SurfaceSnapshot& from) {
  to.vertices.assign(from.vertices.begin(), from.vertices.end());
  to.velocities.assign(from.velocities.begin(), from.velocities.end());
  to.vertex_normals.assign(from.vertex_normals.begin(), from.vertex_normals.end());
  to.tree = from.tree;
  to.time_s = from.time_s;
  to.refit_s = 0.0;  // nothing refitted here
  ++to.sequence;
}

}  // namespace hof::haptics
