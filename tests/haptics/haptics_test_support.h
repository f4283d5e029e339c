#pragma once
// Helpers for haptics tests: a programmable device that records what it is sent, closed test
// surfaces, and a point-in-closed-surface test by winding number.

#include <cmath>
#include <functional>
#include <numbers>
#include <vector>

#include "hof/haptics/device.h"
#include "hof/haptics/surface_snapshot.h"
#include "hof/mesh/mesh.h"

namespace hof::haptics::testing {

/// A device whose position is a function of time; remembers every force written.
class ProgrammedDevice final : public Device {
 public:
  using Path = std::function<Vec3(double)>;
  explicit ProgrammedDevice(Path path, DeviceSpec spec = {}) : path_(std::move(path)), spec_(std::move(spec)) {
    forces.reserve(1 << 20);
  }
  [[nodiscard]] const DeviceSpec& spec() const override { return spec_; }
  [[nodiscard]] std::string_view backend() const override { return "programmed"; }
  DeviceReading read(double time_s) override {
    DeviceReading r;
    r.time_s = time_s;
    r.position_m = path_(time_s);
    const double h = 1e-4;
    r.velocity_m_per_s = (path_(time_s + h) - path_(time_s - h)) / (2 * h);
    r.valid = valid;
    return r;
  }
  void write_force(const Vec3& force, const Vec3&) override {
    if (forces.size() < forces.capacity()) forces.push_back(force);
    last_force = force;
  }
  [[nodiscard]] DeviceHealth health() const override { return DeviceHealth::kOk; }

  std::vector<Vec3> forces;
  Vec3 last_force{Vec3::Zero()};
  bool valid{true};

 private:
  Path path_;
  DeviceSpec spec_;
};

/// Closed, outward box surface [lo, hi] split into 12 triangles.
inline mesh::TriMesh box_surface(const Vec3& lo, const Vec3& hi) {
  mesh::TriMesh m;
  for (int i = 0; i < 8; ++i)
    m.vertices.emplace_back(i & 1 ? hi.x() : lo.x(), i & 2 ? hi.y() : lo.y(), i & 4 ? hi.z() : lo.z());
  const int quads[6][4] = {{0, 2, 3, 1}, {4, 5, 7, 6}, {0, 1, 5, 4}, {2, 6, 7, 3}, {0, 4, 6, 2}, {1, 3, 7, 5}};
  for (const auto& q : quads) {
    m.triangles.push_back({q[0], q[1], q[2]});
    m.triangles.push_back({q[0], q[2], q[3]});
  }
  return m;
}

/// UV sphere of `radius` at `center`, outward (a faceted sphere: flat triangles).
inline mesh::TriMesh sphere_surface(const Vec3& center, double radius, int rings, int segments) {
  mesh::TriMesh m;
  m.vertices.push_back(center + Vec3(0, 0, radius));
  for (int r = 1; r < rings; ++r) {
    const double theta = std::numbers::pi * r / rings;
    for (int s = 0; s < segments; ++s) {
      const double phi = 2 * std::numbers::pi * s / segments;
      m.vertices.push_back(
          center + radius * Vec3(std::sin(theta) * std::cos(phi), std::sin(theta) * std::sin(phi), std::cos(theta)));
    }
  }
  m.vertices.push_back(center - Vec3(0, 0, radius));
  const int south = static_cast<int>(m.vertices.size()) - 1;
  auto ring = [&](int r, int s) { return 1 + (r - 1) * segments + (s % segments); };
  for (int s = 0; s < segments; ++s) m.triangles.push_back({0, ring(1, s), ring(1, s + 1)});
  for (int r = 1; r + 1 < rings; ++r) {
    for (int s = 0; s < segments; ++s) {
      m.triangles.push_back({ring(r, s), ring(r + 1, s), ring(r + 1, s + 1)});
      m.triangles.push_back({ring(r, s), ring(r + 1, s + 1), ring(r, s + 1)});
    }
  }
  for (int s = 0; s < segments; ++s) m.triangles.push_back({south, ring(rings - 1, s + 1), ring(rings - 1, s)});
  return m;
}

/// Generalised winding number of a closed outward surface at p (≈1 inside, ≈0 outside), by
/// the solid angles of its triangles (Van Oosterom & Strackee 1983).
inline double winding_number(const std::vector<Vec3>& vertices, const std::vector<mesh::Tri>& triangles,
                             const Vec3& p) {
  double total = 0.0;
  for (const mesh::Tri& t : triangles) {
    const Vec3 a = vertices[t[0]] - p, b = vertices[t[1]] - p, c = vertices[t[2]] - p;
    const double la = a.norm(), lb = b.norm(), lc = c.norm();
    const double numerator = a.dot(b.cross(c));
    const double denominator = la * lb * lc + a.dot(b) * lc + b.dot(c) * la + c.dot(a) * lb;
    total += 2.0 * std::atan2(numerator, denominator);
  }
  return total / (4.0 * std::numbers::pi);
}

/// A static floor: the top face (z = 0) of a 0.4 m × 0.4 m × 0.1 m box.
inline SurfaceSnapshot floor_snapshot() {
  SurfaceSnapshot s = make_snapshot(box_surface(Vec3(-0.2, -0.2, -0.1), Vec3(0.2, 0.2, 0.0)));
  s.is_static = true;
  return s;
}

}  // namespace hof::haptics::testing
