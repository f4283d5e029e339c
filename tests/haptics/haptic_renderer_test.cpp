// Haptic rendering against analytic expectations: flat-face force law, force shading across an
// edge, friction cone, and the proxy never inside a closed surface (static and moving).

#include "hof/haptics/haptic_renderer.h"

#include <gtest/gtest.h>

#include <cmath>
#include <numbers>
#include <random>

#include "haptics_test_support.h"
#include "hof/mesh/boundary.h"
#include "hof/mesh/liver_generator.h"

namespace hof::haptics {
namespace {

using testing::box_surface;
using testing::floor_snapshot;
using testing::sphere_surface;
using testing::winding_number;

constexpr double kDeviceStiffness = 1000.0;  // N/m, the device's max stiffness

SurfaceMaterial smooth(double relative_stiffness = 1.0) {
  SurfaceMaterial m;
  m.kind = SurfaceKind::kSmooth;
  m.stiffness = relative_stiffness;
  return m;
}

RendererConfig config(RendererKind kind) {
  RendererConfig c;
  c.kind = kind;
  return c;
}

class ProxyRendererTest : public ::testing::TestWithParam<RendererKind> {};

TEST_P(ProxyRendererTest, FlatFaceForceIsNormalAndStiffnessTimesPenetration) {
  // Top face of a box at z = 0; the device presses straight down at (0.01, 0.02).
  const SurfaceSnapshot s = make_snapshot(box_surface(Vec3(-0.1, -0.1, -0.05), Vec3(0.1, 0.1, 0.0)));
  RendererConfig no_shading = config(GetParam());
  no_shading.force_shading = false;  // a box's corner normals would tilt the shaded force on its faces
  HapticRenderer r(no_shading, smooth(0.8), kDeviceStiffness);
  const double radius = GetParam() == RendererKind::kRuspini ? r.config().proxy_radius_m : 0.0;
  r.reset(Vec3(0.01, 0.02, 0.05));
  for (double depth : {0.001, 0.004, 0.01}) {
    // Approach from above in a few ticks, then hold.
    for (double z : {0.02, 0.005, -depth}) r.update(Vec3(0.01, 0.02, z), Vec3::Zero(), s, false, 1e-3);
    const ContactState& c = r.update(Vec3(0.01, 0.02, -depth), Vec3::Zero(), s, false, 1e-3);
    ASSERT_TRUE(c.in_contact);
    const double expected = 0.8 * kDeviceStiffness * (depth + radius);  // sphere penetration for Ruspini
    EXPECT_NEAR(c.force.z(), expected, 0.01 * expected) << "depth " << depth;
    EXPECT_NEAR(c.force.head<2>().norm(), 0.0, 1e-9 * expected);
    EXPECT_NEAR(c.proxy.z(), radius, 1e-5);
  }
}

TEST_P(ProxyRendererTest, NoForceOutside) {
  const SurfaceSnapshot s = make_snapshot(box_surface(Vec3(-0.1, -0.1, -0.05), Vec3(0.1, 0.1, 0.0)));
  HapticRenderer r(config(GetParam()), smooth(), kDeviceStiffness);
  r.reset(Vec3(0, 0, 0.05));
  const ContactState& c = r.update(Vec3(0.0, 0.0, 0.02), Vec3::Zero(), s, false, 1e-3);
  EXPECT_FALSE(c.in_contact);
  EXPECT_EQ(c.force, Vec3::Zero());
  EXPECT_EQ(c.proxy, Vec3(0.0, 0.0, 0.02));
}

INSTANTIATE_TEST_SUITE_P(Proxies, ProxyRendererTest,
                         ::testing::Values(RendererKind::kGodObject, RendererKind::kRuspini));

// Largest change of force direction between consecutive ticks while the device slides at a
// constant depth under a faceted sphere, across several edges.
double largest_direction_jump(bool shading) {
  const SurfaceSnapshot s = make_snapshot(sphere_surface(Vec3::Zero(), 0.05, 12, 24));
  RendererConfig c = config(RendererKind::kRuspini);
  c.force_shading = shading;
  c.proxy_radius_m = 0.001;
  HapticRenderer r(c, smooth(), kDeviceStiffness);
  r.reset(Vec3(0.0, 0.0, 0.1));
  double worst = 0.0;
  Vec3 previous = Vec3::Zero();
  for (int i = 0; i <= 600; ++i) {
    // A meridian arc 4 mm inside the sphere, from the pole sideways.
    const double angle = 0.2 + 0.6 * i / 600.0;
    const Vec3 device = 0.046 * Vec3(std::sin(angle) * std::cos(0.1), std::sin(angle) * std::sin(0.1), std::cos(angle));
    const ContactState& contact = r.update(device, Vec3::Zero(), s, false, 1e-3);
    if (!contact.in_contact) continue;
    const Vec3 direction = contact.force.normalized();
    if (previous != Vec3::Zero()) worst = std::max(worst, std::acos(std::clamp(direction.dot(previous), -1.0, 1.0)));
    previous = direction;
  }
  return worst * 180.0 / std::numbers::pi;
}

TEST(ForceShading, MakesTheForceDirectionContinuousAcrossEdges) {
  const double flat = largest_direction_jump(false);
  const double shaded = largest_direction_jump(true);
  // 12 rings: neighbouring faces meet at 15°; a path crossing an edge jumps by about that.
  EXPECT_GT(flat, 8.0);
  EXPECT_LT(shaded, 1.0);
}

TEST(Friction, HoldsInsideTheStaticConeAndSlidesOutside) {
  const SurfaceSnapshot s = make_snapshot(box_surface(Vec3(-0.2, -0.2, -0.05), Vec3(0.2, 0.2, 0.0)));
  SurfaceMaterial m;
  m.kind = SurfaceKind::kFrictional;
  m.stiffness = 1.0;
  m.static_friction = 0.5;
  m.dynamic_friction = 0.3;
  for (const double ratio : {0.3, 0.8}) {  // tangential over normal force: below / above μs
    HapticRenderer r(config(RendererKind::kGodObject), m, kDeviceStiffness);
    r.reset(Vec3(0, 0, 0.01));
    const double depth = 0.004;
    r.update(Vec3(0, 0, 0.001), Vec3::Zero(), s, false, 1e-3);
    r.update(Vec3(0, 0, -depth), Vec3::Zero(), s, false, 1e-3);
    const Vec3 pressed = r.update(Vec3(0, 0, -depth), Vec3::Zero(), s, false, 1e-3).proxy;
    // Displace the device sideways so that k·δ = ratio · k·depth, hold for 50 ticks.
    const Vec3 device(ratio * depth, 0, -depth);
    Vec3 proxy = pressed;
    for (int i = 0; i < 50; ++i) proxy = r.update(device, Vec3::Zero(), s, false, 1e-3).proxy;
    if (ratio < m.static_friction) {
      EXPECT_NEAR((proxy - pressed).norm(), 0.0, 1e-9) << "static friction must hold";
      EXPECT_NEAR(r.contact().force.x(), -ratio * depth * kDeviceStiffness, 1e-6);
    } else {
      EXPECT_GT(proxy.x() - pressed.x(), 0.5 * ratio * depth) << "must slide toward the device";
    }
  }
}

// ---- fall-through ---------------------------------------------------------------------------

struct FallThroughCount {
  int inside{0};
  int ticks{0};
};

// Random trajectories around a closed surface: slow wandering, and jumps that cross the whole
// object in one tick. Counts ticks whose proxy ends inside (winding number > ½, or for
// Ruspini a sphere centre closer than its radius to being inside).
FallThroughCount random_trajectories(RendererKind kind, const mesh::TriMesh& surface, int trajectories) {
  const SurfaceSnapshot s = make_snapshot(surface);
  Vec3 lo = surface.vertices.front(), hi = lo;
  for (const Vec3& p : surface.vertices) {
    lo = lo.cwiseMin(p);
    hi = hi.cwiseMax(p);
  }
  const Vec3 center = 0.5 * (lo + hi), half = 0.5 * (hi - lo);
  std::mt19937 random(1234);
  std::uniform_real_distribution<double> unit(-1.0, 1.0);
  FallThroughCount count;
  HapticRenderer r(config(kind), smooth(), kDeviceStiffness);
  for (int k = 0; k < trajectories; ++k) {
    // Start well outside, on a random side.
    Vec3 start(unit(random), unit(random), unit(random));
    start = center + 1.6 * half.cwiseProduct(start.normalized());
    r.reset(start);
    Vec3 device = start;
    for (int tick = 0; tick < 6; ++tick) {
      const bool jump = (tick % 3) == 2;
      const Vec3 step(unit(random), unit(random), unit(random));
      // Jumps aim through the object (to the far side); other ticks press inward by up to 30%.
      device = jump ? Vec3(center - 1.3 * (device - center) + 0.3 * half.cwiseProduct(step))
                    : Vec3(device + 0.5 * (center - device) * std::abs(step.x()) + 0.1 * half.cwiseProduct(step));
      const ContactState& c = r.update(device, Vec3::Zero(), s, false, 1e-3);
      ++count.ticks;
      if (winding_number(s.vertices, s.triangles, c.proxy) > 0.5) ++count.inside;
    }
  }
  return count;
}

TEST(FallThrough, ProxiesNeverEndInsideAClosedLiverOverTenThousandTrajectories) {
  const mesh::Mesh liver = *mesh::generate_liver(mesh::LiverResolution::kSimple);
  const mesh::BoundarySurface b = mesh::extract_boundary(liver.nodes, liver.tets);
  for (RendererKind kind : {RendererKind::kGodObject, RendererKind::kRuspini}) {
    const FallThroughCount count = random_trajectories(kind, b.surface, 10000);
    EXPECT_EQ(count.inside, 0) << "renderer " << static_cast<int>(kind) << " over " << count.ticks << " ticks";
  }
}

TEST(FallThrough, PenaltyFallsThroughAThinPlateWhereProxiesDoNot) {
  // A 4 mm plate; the device comes down through it 3 mm per tick.
  const SurfaceSnapshot s = make_snapshot(box_surface(Vec3(-0.1, -0.1, -0.004), Vec3(0.1, 0.1, 0.0)));
  for (RendererKind kind : {RendererKind::kPenalty, RendererKind::kGodObject, RendererKind::kRuspini}) {
    HapticRenderer r(config(kind), smooth(), kDeviceStiffness);
    r.reset(Vec3(0, 0, 0.01));
    Vec3 last_force = Vec3::Zero();
    for (double z = 0.01; z > -0.02; z -= 0.003)
      last_force = r.update(Vec3(0, 0, z), Vec3::Zero(), s, false, 1e-3).force;
    const double proxy_z = r.contact().proxy.z();
    if (kind == RendererKind::kPenalty) {
      // Once past the middle, the nearest face is the bottom one: pushed out below.
      EXPECT_LE(last_force.z(), 0.0);
      EXPECT_LT(proxy_z, -0.003);
    } else {
      EXPECT_GE(proxy_z, 0.0) << "proxy must stay on top";
      EXPECT_GT(last_force.z(), 0.0) << "and push the device back up";
    }
  }
}

// The window's snapshot is copied from the haptic loop's rather than computed again: the copy
// must be what update_snapshot gives for the same positions (normals, and a tree that finds
// the same hits), and a snapshot left at rest must not be.
TEST(SnapshotCopy, ACopiedSnapshotIsTheUpdatedOne) {
  const mesh::TriMesh rest = sphere_surface(Vec3::Zero(), 0.05, 12, 24);
  SurfaceSnapshot haptic = make_snapshot(rest);
  SurfaceSnapshot computed = make_snapshot(rest);
  SurfaceSnapshot copied = make_snapshot(rest);
  std::vector<Vec3> moved(rest.vertices.size()), velocities(rest.vertices.size());
  for (std::size_t i = 0; i < moved.size(); ++i) {
    const Vec3& p = rest.vertices[i];
    moved[i] = Vec3(1.5 * p.x(), p.y(), 0.6 * p.z()) + Vec3(0.01, 0.0, 0.0);  // squashed and moved
    velocities[i] = Vec3(0.0, 0.0, p.z());
  }
  update_snapshot(haptic, moved, velocities, 0.25);
  update_snapshot(computed, moved, velocities, 0.25);
  copy_snapshot_geometry(copied, haptic);
  EXPECT_EQ(copied.vertices, computed.vertices);
  EXPECT_EQ(copied.velocities, computed.velocities);
  EXPECT_EQ(copied.vertex_normals, computed.vertex_normals);
  EXPECT_EQ(copied.time_s, 0.25);
  int hits = 0;
  for (int k = 0; k < 64; ++k) {
    const double a = 0.1 * k;
    const Vec3 from(0.2 * std::cos(a), 0.2 * std::sin(a), 0.03 * std::sin(3 * a));
    // From outside to the moved sphere's centre: every segment hits it.
    const collision::SweepHit c = copied.tree.first_hit_segment(copied.view(), from, Vec3(0.01, 0, 0));
    const collision::SweepHit e = computed.tree.first_hit_segment(computed.view(), from, Vec3(0.01, 0, 0));
    ASSERT_EQ(c.triangle, e.triangle) << k;
    hits += c.triangle >= 0;
    EXPECT_NEAR((c.point - e.point).norm(), 0.0, 1e-12) << k;
  }
  EXPECT_EQ(hits, 64);
  const SurfaceSnapshot at_rest = make_snapshot(rest);
  EXPECT_NE(at_rest.vertex_normals, copied.vertex_normals);
}

TEST(MovingSurface, PulsingSphereNeverSwallowsTheProxy) {
  const mesh::TriMesh rest = sphere_surface(Vec3::Zero(), 1.0, 16, 32);  // unit sphere, scaled below
  SurfaceSnapshot s = make_snapshot(rest);
  std::vector<Vec3> moved(rest.vertices.size());
  for (RendererKind kind : {RendererKind::kGodObject, RendererKind::kRuspini}) {
    HapticRenderer r(config(kind), smooth(), kDeviceStiffness);
    r.reset(Vec3(0.0, 0.0, 0.08));
    int inside = 0;
    std::mt19937 random(7);
    std::uniform_real_distribution<double> jitter(-0.002, 0.002);
    for (int tick = 0; tick < 4000; ++tick) {
      const double t = tick * 1e-3;
      // Radius 5 cm ± 2 cm at 3 Hz: the surface sweeps up to 0.4 mm per tick into the proxy.
      const double radius = 0.05 + 0.02 * std::sin(2 * std::numbers::pi * 3.0 * t);
      for (std::size_t i = 0; i < moved.size(); ++i) moved[i] = radius * rest.vertices[i];
      update_snapshot(s, moved, {}, t);
      // The device rests on the sphere's top, pressing 5 mm in, and wanders.
      const Vec3 device(jitter(random), jitter(random), radius - 0.005);
      const ContactState& c = r.update(device, Vec3::Zero(), s, true, 1e-3);
      if (winding_number(s.vertices, s.triangles, c.proxy) > 0.5) ++inside;
    }
    EXPECT_EQ(inside, 0) << "renderer " << static_cast<int>(kind);
  }
}

TEST(MovingSurface, WavingSheetKeepsTheProxyOnTop) {
  // A 0.2 m sheet, z = A sin(k x − ω t), faces up; the device presses 3 mm under it.
  const int n = 40;
  mesh::TriMesh sheet;
  for (int j = 0; j <= n; ++j) {
    for (int i = 0; i <= n; ++i) sheet.vertices.emplace_back(-0.1 + 0.2 * i / n, -0.1 + 0.2 * j / n, 0.0);
  }
  for (int j = 0; j < n; ++j) {
    for (int i = 0; i < n; ++i) {
      const int a = j * (n + 1) + i;
      sheet.triangles.push_back({a, a + 1, a + n + 2});
      sheet.triangles.push_back({a, a + n + 2, a + n + 1});
    }
  }
  SurfaceSnapshot s = make_snapshot(sheet);
  auto height = [](double x, double t) { return 0.01 * std::sin(40.0 * x - 2 * std::numbers::pi * 2.0 * t); };
  std::vector<Vec3> moved(sheet.vertices.size());
  for (RendererKind kind : {RendererKind::kGodObject, RendererKind::kRuspini}) {
    HapticRenderer r(config(kind), smooth(), kDeviceStiffness);
    r.reset(Vec3(0, 0, 0.03));
    const double radius = kind == RendererKind::kRuspini ? r.config().proxy_radius_m : 0.0;
    int below = 0;
    for (int tick = 0; tick < 3000; ++tick) {
      const double t = tick * 1e-3;
      for (std::size_t i = 0; i < moved.size(); ++i) {
        moved[i] = Vec3(sheet.vertices[i].x(), sheet.vertices[i].y(), height(sheet.vertices[i].x(), t));
      }
      update_snapshot(s, moved, {}, t);
      const double x = 0.05 * std::sin(2 * std::numbers::pi * 0.5 * t);  // slides back and forth
      const ContactState& c = r.update(Vec3(x, 0.01, height(x, t) - 0.003), Vec3::Zero(), s, true, 1e-3);
      // Exact sheet height under the proxy (piecewise linear between grid columns).
      const double cell = 0.2 / n;
      const double u = (c.proxy.x() + 0.1) / cell;
      const int column = std::clamp(static_cast<int>(std::floor(u)), 0, n - 1);
      const double w = u - column;
      const double x0 = -0.1 + column * cell;
      const double surface_z = (1 - w) * height(x0, t) + w * height(x0 + cell, t);
      if (c.proxy.z() < surface_z + radius - 1e-7) ++below;
    }
    EXPECT_EQ(below, 0) << "renderer " << static_cast<int>(kind);
  }
}

TEST(MagneticSurface, HoldsTheProxyWithinTheSnapDistance) {
  const SurfaceSnapshot s = floor_snapshot();
  SurfaceMaterial m;
  m.kind = SurfaceKind::kMagnetic;
  m.stiffness = 1.0;
  m.static_friction = m.dynamic_friction = 0.0;
  m.snap_distance_m = 0.005;
  RendererConfig c;
  c.kind = RendererKind::kGodObject;
  HapticRenderer r(c, m, 1000.0);
  r.reset(Vec3(0, 0, 0.01));
  r.update(Vec3(0, 0, -0.002), Vec3::Zero(), s, false, 1e-3);
  ASSERT_TRUE(r.update(Vec3(0, 0, -0.002), Vec3::Zero(), s, false, 1e-3).in_contact);
  // Lifted 3 mm off the surface: still held, pulled back down.
  const ContactState& held = r.update(Vec3(0, 0, 0.003), Vec3::Zero(), s, false, 1e-3);
  EXPECT_TRUE(held.in_contact);
  EXPECT_NEAR(held.force.z(), -1000.0 * 0.003, 0.01);
  // Beyond the snap distance: released.
  EXPECT_FALSE(r.update(Vec3(0, 0, 0.008), Vec3::Zero(), s, false, 1e-3).in_contact);
}

TEST(ZeroForceSurface, TracksTheSurfaceWithoutForce) {
  const SurfaceSnapshot s = floor_snapshot();
  SurfaceMaterial m;
  m.kind = SurfaceKind::kZeroForce;
  RendererConfig c;
  c.kind = RendererKind::kGodObject;
  HapticRenderer r(c, m, 1000.0);
  r.reset(Vec3(0, 0, 0.01));
  r.update(Vec3(0, 0, -0.004), Vec3::Zero(), s, false, 1e-3);
  const ContactState& contact = r.update(Vec3(0, 0, -0.004), Vec3::Zero(), s, false, 1e-3);
  EXPECT_TRUE(contact.in_contact);
  EXPECT_EQ(contact.force, Vec3::Zero());
  EXPECT_NEAR(contact.penetration_m, 0.004, 1e-5);  // the needle's depth
  EXPECT_NEAR(contact.proxy.z(), 0.0, 1e-5);
}

}  // namespace
}  // namespace hof::haptics
