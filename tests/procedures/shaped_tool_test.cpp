// A tool with a shape on the stylus (sphere, capsule), in virtual time: the proxy never sinks
// into a surface, the hand feels the coupling spring of the penetration, the tissue gets minus
// the felt force spread over the contacts along the shaft, and random motion against a rigid box
// never leaves the tool inside it nor sends the device more than its limit.

#include <gtest/gtest.h>

#include <cmath>
#include <cstdio>
#include <random>

#include "hof/coupling/session.h"
#include "hof/haptics/device_backends/scripted_device.h"
#include "hof/haptics/haptic_loop.h"
#include "hof/mesh/boundary.h"
#include "hof/mesh/liver_generator.h"
#include "hof/procedures/shaped_tool.h"

#include "coupling/resting_liver.h"
#include "support/allocation_counter.h"
#include "support/box_surface.h"
#include "support/temp_dir.h"

namespace hof::procedures {
namespace {

constexpr double kPi = 3.14159265358979323846;

// A rigid box (never stale for the loop's safety layer).
haptics::SurfaceSnapshot box_snapshot(const Vec3& lo, const Vec3& hi) {
  haptics::SurfaceSnapshot s = haptics::make_snapshot(hof::testing::box_surface(lo, hi));
  s.is_static = true;
  return s;
}

std::shared_ptr<ShapedTool> make_tool(ToolShape shape, double radius, double length,
                                      std::array<double, 4> orientation = {0, 0, 1, 0}) {
  ShapedToolConfig c;
  c.shape = shape;
  c.radius_m = radius;
  c.length_m = length;
  c.orientation = orientation;
  auto tool = ShapedTool::make(c);
  EXPECT_TRUE(tool) << tool.error().to_string();
  return *tool;
}

// The deepest overlap of the tool's shape (at the proxy, rotation r) with the triangles of `s`,
// and whether its first primitive's midpoint lies strictly inside the box [lo, hi].
double overlap(const ShapedTool& tool, const Mat3& r, const haptics::SurfaceSnapshot& s) {
  double worst = 0.0;
  for (const ToolPrimitive& p : tool.primitives()) {
    const Vec3 a = tool.proxy() + r * p.a;
    const Vec3 b = tool.proxy() + r * p.b;
    for (const mesh::Tri& t : s.triangles) {
      Vec3 on_segment, on_triangle, w;
      const double d = closest_segment_triangle(a, b, s.vertices[t[0]], s.vertices[t[1]], s.vertices[t[2]], on_segment,
                                                on_triangle, w);
      worst = std::max(worst, p.radius - d);
    }
  }
  return worst;
}

TEST(ClosestSegmentTriangle, MatchesTheCases) {
  const Vec3 p0(0, 0, 0), p1(1, 0, 0), p2(0, 1, 0);
  Vec3 s, t, w;
  // Above the face.
  EXPECT_NEAR(closest_segment_triangle(Vec3(0.2, 0.2, 0.5), Vec3(0.2, 0.2, 2), p0, p1, p2, s, t, w), 0.5, 1e-15);
  EXPECT_NEAR((t - Vec3(0.2, 0.2, 0)).norm(), 0.0, 1e-15);
  EXPECT_NEAR((w - Vec3(0.6, 0.2, 0.2)).norm(), 0.0, 1e-15);
  // Crossing it.
  EXPECT_EQ(closest_segment_triangle(Vec3(0.2, 0.2, -1), Vec3(0.2, 0.2, 1), p0, p1, p2, s, t, w), 0.0);
  // Parallel to the plane, across an edge: the edge's closest point.
  EXPECT_NEAR(closest_segment_triangle(Vec3(0.5, -1, 0.3), Vec3(0.5, 1, 0.3), p0, p1, p2, s, t, w), 0.3, 1e-15);
  // Skew to the edge p1–p2 outside the triangle.
  const double d = closest_segment_triangle(Vec3(1, 1, -1), Vec3(1, 1, 1), p0, p1, p2, s, t, w);
  EXPECT_NEAR(d, std::sqrt(0.5), 1e-15);
  EXPECT_NEAR((t - Vec3(0.5, 0.5, 0)).norm(), 0.0, 1e-15);
  // Degenerate: never a contact.
  EXPECT_TRUE(std::isinf(closest_segment_triangle(Vec3(0, 0, 1), Vec3(0, 0, 2), p0, p0, p1, s, t, w)));
}

TEST(ShapedToolConfig, BadNumbersAreRefusedByName) {
  ShapedToolConfig c;
  c.radius_m = -0.001;
  EXPECT_NE(validate(c).error().message.find("radius"), std::string::npos);
  c = {};
  c.shape = ToolShape::kCapsule;
  c.length_m = -0.01;
  EXPECT_NE(validate(c).error().message.find("length"), std::string::npos);
  c = {};
  c.shape = ToolShape::kMesh;
  EXPECT_NE(validate(c).error().message.find("mesh"), std::string::npos);
  c = {};
  c.orientation = {0, 0, 0, 1};
  EXPECT_FALSE(validate(c));
  EXPECT_TRUE(validate(ShapedToolConfig{}));
}

// A sphere pressed into a flat rigid floor (top z = 0) feels k times its penetration, straight
// up, and its proxy rests on the floor, never below.
TEST(ShapedTool, SpherePressedOnAFloorGivesTheSpringOfItsPenetrationAndNeverSinks) {
  const double r = 0.005;
  const auto tool = make_tool(ToolShape::kSphere, r, 0.0);
  const haptics::SurfaceSnapshot floor = box_snapshot(Vec3(-0.1, -0.1, -0.05), Vec3(0.1, 0.1, 0.0));
  std::array<const haptics::SurfaceSnapshot*, 1> surfaces{&floor};
  std::array<haptics::ContactState, 1> contacts{};
  std::array<Vec3, 1> layer_forces{};
  haptics::ToolTickInput in;
  in.surfaces = surfaces;
  in.contacts = contacts;
  in.max_stiffness_n_per_m = 1000.0;
  haptics::ToolState st;
  const double speed = 0.02;
  double z = 0.02;
  for (int k = 0; z > -0.004; ++k) {
    z = 0.02 - speed * 1e-3 * k;
    in.time_s = 1e-3 * k;
    in.position = Vec3(0.001, -0.002, z);
    in.velocity = Vec3(0, 0, -speed);
    layer_forces[0] = Vec3(0, 0, 5);
    (void)tool->tick(in, layer_forces, st);
    EXPECT_EQ(layer_forces[0], Vec3::Zero());  // the shape renders the floor, not the point
    ASSERT_GE(tool->proxy().z(), r - 1e-9) << "tick " << k;
    EXPECT_NEAR(tool->proxy().x(), 0.001, 1e-12);  // pressed straight down: no sliding
  }
  // Held still: the spring of the penetration r − z, up; one contact, the floor's body 0.
  in.velocity.setZero();
  Vec3 force;
  for (int k = 0; k < 3; ++k) force = tool->tick(in, layer_forces, st);
  const double penetration = r - z;
  EXPECT_NEAR((force - Vec3(0, 0, 1000.0 * penetration)).norm(), 0.0, 1e-9);
  EXPECT_NEAR(tool->proxy().z(), r, 1e-8);
  EXPECT_TRUE(st.touched);
  EXPECT_EQ(st.body, 0);
  EXPECT_GE(st.contact_count, 1);
  EXPECT_NEAR((st.normal - Vec3(0, 0, 1)).norm(), 0.0, 1e-12);
  // The torque about the device point: the contact is straight below it, the force straight up.
  EXPECT_NEAR(st.torque.norm(), 0.0, 1e-12);
  // Lifted clear: no force.
  in.position = Vec3(0.001, -0.002, 0.02);
  for (int k = 0; k < 10; ++k) force = tool->tick(in, layer_forces, st);
  EXPECT_EQ(force, Vec3::Zero());
  EXPECT_FALSE(st.touched);
}

// A capsule lying flat (shaft along +x) pressed on the floor: the contact runs along the shaft,
// and the torque of an off-centre load is the lever arm's.
TEST(ShapedTool, CapsuleLyingFlatTouchesAlongItsShaft) {
  const double r = 0.004, length = 0.04;
  const auto tool = make_tool(ToolShape::kCapsule, r, length, {0, 1, 0, kPi / 2});  // +z → +x
  const haptics::SurfaceSnapshot floor = box_snapshot(Vec3(-0.1, -0.1, -0.05), Vec3(0.1, 0.1, 0.0));
  std::array<const haptics::SurfaceSnapshot*, 1> surfaces{&floor};
  std::array<haptics::ContactState, 1> contacts{};
  std::array<Vec3, 1> layer_forces{};
  haptics::ToolTickInput in;
  in.surfaces = surfaces;
  in.contacts = contacts;
  in.max_stiffness_n_per_m = 800.0;
  haptics::ToolState st;
  for (int k = 0; k <= 100; ++k) {
    in.position = Vec3(0.0, 0.0, 0.01 - 1e-4 * k);  // down to 0
    (void)tool->tick(in, layer_forces, st);
  }
  // Held still for 0.5 s: the proxy's low-passed velocity (10 ms) has died out, so the force is
  // the coupling spring's alone.
  for (int k = 0; k < 500; ++k) (void)tool->tick(in, layer_forces, st);
  EXPECT_NEAR(st.length, length, 1e-15);
  EXPECT_NEAR((st.axis - Vec3(-1, 0, 0)).norm(), 0.0, 1e-12);
  const Vec3 force = tool->tick(in, layer_forces, st);
  EXPECT_NEAR((force - Vec3(0, 0, 800.0 * r)).norm(), 0.0, 1e-9);
  EXPECT_NEAR(tool->proxy().z(), r, 1e-8);
  // The floor is two triangles: both under the shaft's length.
  EXPECT_GE(st.contact_count, 2);
}

// 10,000 random trajectories of a sphere and a capsule against a rigid box through the haptic
// loop: at the end of every tick the tool is not inside the box, and the device's force is
// finite and within its limit.
class TableDevice final : public haptics::Device {
 public:
  explicit TableDevice(haptics::DeviceSpec spec) : spec_(std::move(spec)) {}
  [[nodiscard]] const haptics::DeviceSpec& spec() const override { return spec_; }
  [[nodiscard]] std::string_view backend() const override { return "table"; }
  haptics::DeviceReading read(double time_s) override {
    haptics::DeviceReading r;
    r.time_s = time_s;
    r.position_m = position;
    r.velocity_m_per_s = velocity;
    r.orientation = orientation;
    r.valid = true;
    return r;
  }
  void write_force(const Vec3& f, const Vec3&) override { force = f; }
  [[nodiscard]] haptics::DeviceHealth health() const override { return haptics::DeviceHealth::kOk; }
  Vec3 position{Vec3::Zero()};
  Vec3 velocity{Vec3::Zero()};
  Eigen::Quaterniond orientation{Eigen::Quaterniond::Identity()};
  Vec3 force{Vec3::Zero()};

 private:
  haptics::DeviceSpec spec_;
};

TEST(ShapedTool, RandomTrajectoriesNeverEndInsideARigidBoxNorExceedTheDeviceLimit) {
  const Vec3 lo(-0.02, -0.02, -0.02), hi(0.02, 0.02, 0.02);
  TripleBuffer<haptics::SurfaceSnapshot> surfaces(box_snapshot(lo, hi));
  surfaces.write_slot() = box_snapshot(lo, hi);
  surfaces.publish();
  const haptics::SurfaceSnapshot reference = box_snapshot(lo, hi);
  haptics::DeviceSpec spec;
  spec.max_force_n = 8.0;
  spec.max_stiffness_n_per_m = 2000.0;
  TableDevice device(spec);
  haptics::HapticLoopConfig config;
  config.realtime_priority = false;
  config.safety.fade_in_s = 0.0;
  haptics::HapticLoop loop(device, surfaces, config);
  const std::array<std::shared_ptr<ShapedTool>, 2> tools{make_tool(ToolShape::kSphere, 0.005, 0.0),
                                                         make_tool(ToolShape::kCapsule, 0.003, 0.03)};
  std::mt19937_64 rng(37);
  std::uniform_real_distribution<double> unit(-1.0, 1.0);
  constexpr int kTrajectories = 10000;
  constexpr int kTicks = 20;
  double time = 0.0;
  int touching = 0;
  for (int n = 0; n < kTrajectories; ++n) {
    ShapedTool& tool = *tools[static_cast<std::size_t>(n % 2)];
    loop.set_tool(&tool);
    tool.restart();
    // Start 6 cm from the centre (the capsule's length clears the box), aim through the box.
    Vec3 start;
    start.x() = unit(rng);
    start.y() = unit(rng);
    start.z() = unit(rng);
    if (start.norm() < 1e-3) start = Vec3(1, 0, 0);
    start = 0.08 * start.normalized();
    Vec3 aim;
    aim.x() = 0.02 * unit(rng);
    aim.y() = 0.02 * unit(rng);
    aim.z() = 0.02 * unit(rng);
    Vec3 axis;
    axis.x() = unit(rng);
    axis.y() = unit(rng);
    axis.z() = unit(rng);
    if (axis.norm() < 1e-3) axis = Vec3(0, 0, 1);
    const double angle = kPi * unit(rng);
    const double spin = 0.05 * unit(rng);  // rad per tick
    const Eigen::Quaterniond base(Eigen::AngleAxisd(angle, axis.normalized()));
    for (int k = 0; k < kTicks; ++k) {
      // Random steps of up to 8 mm, on the way to the aim and past it.
      Vec3 jitter;
      jitter.x() = 0.002 * unit(rng);
      jitter.y() = 0.002 * unit(rng);
      jitter.z() = 0.002 * unit(rng);
      const double s = static_cast<double>(k + 1) / kTicks;
      const Vec3 previous = device.position;
      device.position = start + 1.3 * s * (aim - start) + jitter;
      device.velocity = k == 0 ? Vec3::Zero() : Vec3((device.position - previous) / 1e-3);
      device.orientation = base * Eigen::Quaterniond(Eigen::AngleAxisd(spin * k, Vec3(0, 1, 0)));
      loop.tick(time);
      time += 1e-3;
      ASSERT_TRUE(device.force.allFinite()) << "trajectory " << n << " tick " << k;
      ASSERT_LE(device.force.norm(), spec.max_force_n + 1e-9) << "trajectory " << n << " tick " << k;
      const Mat3 r = (device.orientation * Eigen::Quaterniond::Identity()).normalized().toRotationMatrix();
      ASSERT_LE(overlap(tool, r, reference), 1e-6 * tool.primitives().front().radius + 1e-12)
          << "trajectory " << n << " tick " << k;
      // Not wholly inside either: the tip is outside the box.
      const Vec3 tip = tool.proxy();
      ASSERT_FALSE((tip.array() > lo.array()).all() && (tip.array() < hi.array()).all())
          << "trajectory " << n << " tick " << k;
      if (device.force.norm() > 0.1) ++touching;
    }
  }
  EXPECT_GT(touching, kTrajectories);  // they press the box, often
}

// 6-DOF: a capsule lying on a rigid floor, its tip held 2 mm into it, turned by the device so
// that its far end goes down into the floor (then back, then past a box's edge): at every tick
// the whole shaft is out of the floor (the proxy's pose gives way, it does not let the shaft
// sink), and the floor's reaction at the far end gives a torque about the device point that
// opposes the turn.
TEST(ShapedTool, TurningTheDeviceNeverSinksTheShaftIntoARigidShape) {
  const double r = 0.004, length = 0.04;
  const auto tool = make_tool(ToolShape::kCapsule, r, length, {0, 1, 0, kPi / 2});  // shaft along +x
  const haptics::SurfaceSnapshot floor = box_snapshot(Vec3(-0.1, -0.1, -0.05), Vec3(0.1, 0.1, 0.0));
  std::array<const haptics::SurfaceSnapshot*, 1> surfaces{&floor};
  std::array<haptics::ContactState, 1> contacts{};
  std::array<Vec3, 1> layer_forces{};
  haptics::ToolTickInput in;
  in.surfaces = surfaces;
  in.contacts = contacts;
  in.max_stiffness_n_per_m = 800.0;
  in.dt_s = 1e-3;
  haptics::ToolState st;
  const auto tick_at = [&](const Vec3& position, double angle, const Vec3& axis) {
    in.position = position;
    in.orientation = Eigen::Quaterniond(Eigen::AngleAxisd(angle, axis));
    (void)tool->tick(in, layer_forces, st);
    const Mat3 turned = (in.orientation * Eigen::Quaterniond(Eigen::AngleAxisd(kPi / 2, Vec3(0, 1, 0))))
                            .normalized()
                            .toRotationMatrix();
    EXPECT_NEAR((st.orientation.toRotationMatrix() - turned).norm(), 0.0, 1e-12);
    return overlap(*tool, st.orientation.toRotationMatrix(), floor);
  };
  for (int k = 0; k <= 60; ++k) {
    ASSERT_LE(tick_at(Vec3(0.0, 0.0, 0.01 - 1e-4 * k), 0.0, Vec3::UnitY()), 1e-6 * r + 1e-12) << "press " << k;
  }
  // The far end down: a turn about +y (+x toward −z), up to 30°, the device point held at z = 0.002.
  double max_torque = 0.0;
  for (int k = 0; k <= 300; ++k) {
    const double angle = (kPi / 6) * k / 300.0;
    ASSERT_LE(tick_at(Vec3(0.0, 0.0, 0.002), angle, Vec3::UnitY()), 1e-6 * r + 1e-12) << "turn " << k;
    // The shaft's far end is above the floor by at least its radius (less the tolerance).
    const Vec3 far = tool->proxy() + st.orientation.toRotationMatrix() * Vec3(0, 0, length);
    ASSERT_GE(far.z(), r * (1.0 - 1e-6) - 1e-12) << "turn " << k;
    if (k > 30) {
      ASSERT_TRUE(st.touched) << "turn " << k;
      EXPECT_LT(st.torque.y(), 0.0) << "turn " << k;  // against the turn about +y
      max_torque = std::max(max_torque, -st.torque.y());
    }
  }
  EXPECT_GT(max_torque, 0.01);  // N·m: the floor holds the far end up, 4 cm from the hand
  // Spun about the vertical while tilted, and rolled about the shaft: still out.
  for (int k = 0; k <= 200; ++k) {
    const Eigen::Quaterniond spin(Eigen::AngleAxisd(0.02 * k, Vec3::UnitZ()));
    in.orientation = spin * Eigen::Quaterniond(Eigen::AngleAxisd(kPi / 6, Vec3::UnitY()));
    in.position = Vec3(0.0, 0.0, 0.002);
    (void)tool->tick(in, layer_forces, st);
    ASSERT_LE(overlap(*tool, st.orientation.toRotationMatrix(), floor), 1e-6 * r + 1e-12) << "spin " << k;
  }
}

// A mesh tool that is not found, or not closed, is refused with the file's name and what is
// wrong; a closed one reads.
TEST(ReadToolMesh, AMissingOrOpenMeshIsAClearErrorNamingTheFile) {
  const hof::testing::TempDir dir;
  const std::string cube =
      "v 0 0 0\nv 1 0 0\nv 1 1 0\nv 0 1 0\nv 0 0 1\nv 1 0 1\nv 1 1 1\nv 0 1 1\n"
      "f 1 4 3\nf 1 3 2\nf 5 6 7\nf 5 7 8\nf 1 2 6\nf 1 6 5\nf 4 8 7\nf 4 7 3\nf 1 5 8\nf 1 8 4\n";
  const auto missing = read_tool_mesh(dir.path() / "nowhere.stl");
  ASSERT_FALSE(missing);
  EXPECT_NE(missing.error().to_string().find("nowhere.stl"), std::string::npos) << missing.error().to_string();
  EXPECT_NE(missing.error().message.find("not found"), std::string::npos) << missing.error().to_string();
  const auto open = read_tool_mesh(dir.write("open.obj", cube));
  ASSERT_FALSE(open);
  EXPECT_NE(open.error().to_string().find("open.obj"), std::string::npos) << open.error().to_string();
  EXPECT_NE(open.error().message.find("not closed"), std::string::npos) << open.error().to_string();
  EXPECT_NE(open.error().message.find("4 open edges"), std::string::npos) << open.error().to_string();
  const auto closed = read_tool_mesh(dir.write("closed.obj", cube + "f 2 3 7\nf 2 7 6\n"));
  ASSERT_TRUE(closed) << closed.error().to_string();
  EXPECT_EQ(closed->triangles.size(), 12u);
  // The read mesh makes a tool: its spheres cover the cube's corners.
  ShapedToolConfig c;
  c.shape = ToolShape::kMesh;
  c.mesh = "closed.obj";
  c.radius_m = 0.05;
  auto tool = ShapedTool::make(c, &*closed);
  ASSERT_TRUE(tool) << tool.error().to_string();
  EXPECT_EQ((*tool)->primitives().size(), 8u + 12u);
}

TEST(ShapedTool, TickAllocatesNothing) {
  HOF_SKIP_UNLESS_COUNTING_ALLOCATIONS();
  const auto tool = make_tool(ToolShape::kCapsule, 0.004, 0.04, {1, 0, 0, 0.3});
  const haptics::SurfaceSnapshot floor = box_snapshot(Vec3(-0.1, -0.1, -0.05), Vec3(0.1, 0.1, 0.0));
  std::array<const haptics::SurfaceSnapshot*, 1> surfaces{&floor};
  std::array<haptics::ContactState, 1> contacts{};
  std::array<Vec3, 1> layer_forces{};
  haptics::ToolTickInput in;
  in.surfaces = surfaces;
  in.contacts = contacts;
  haptics::ToolState st;
  in.position = Vec3(0, 0, 0.01);
  (void)tool->tick(in, layer_forces, st);
  const long before = hof::testing::allocation_count();
  for (int k = 0; k < 2000; ++k) {
    in.position = Vec3(0.02 * std::sin(0.01 * k), 0.0, 0.01 - 1e-5 * k);
    (void)tool->tick(in, layer_forces, st);
  }
  EXPECT_EQ(hof::testing::allocation_count() - before, 0);
  EXPECT_TRUE(st.touched);
}

// The simple liver (co-rotational FEM), resting on its base.
struct Liver {
  mesh::Mesh mesh;
  mesh::BoundarySurface boundary;
  mechanics::MechanicalModel model;
};

Liver make_liver() {
  mesh::Mesh m = *mesh::generate_liver(mesh::LiverResolution::kSimple);
  mesh::BoundarySurface b = mesh::extract_boundary(m.nodes, m.tets);
  mechanics::ModelConfig c = coupling::testing::resting_liver_config(m);
  c.ode.rayleigh_mass = c.ode.rayleigh_stiffness = 0.1;
  c.dt_s = 0.01;
  auto built = mechanics::build_model(c);
  EXPECT_TRUE(built) << built.error().to_string();
  return Liver{std::move(m), std::move(b), std::move(*built)};
}

ToolBodySurface body_surface(const Liver& liver) {
  auto mapping = coupling::SurfaceMapping::by_index(liver.mesh.nodes, liver.boundary.surface.vertices,
                                                    liver.boundary.surface_to_volume);
  EXPECT_TRUE(mapping);
  return ToolBodySurface{liver.boundary.surface.triangles, liver.boundary.surface.vertices.size(), std::move(*mapping)};
}

// The highest surface point of the liver near (x, y).
double top_at(const Liver& liver, double x, double y) {
  double top = -1.0;
  for (const Vec3& v : liver.boundary.surface.vertices) {
    if (std::abs(v.x() - x) < 0.01 && std::abs(v.y() - y) < 0.01) top = std::max(top, v.z());
  }
  return top;
}

// The tissue gets minus the felt force, exactly, spread over the contacts along the shaft.
TEST(ShapedTissueCoupling, TheTissueGetsMinusTheFeltForceAlongTheShaft) {
  const Liver liver = make_liver();
  const double r = 0.004, length = 0.04;
  const auto tool = make_tool(ToolShape::kCapsule, r, length, {0, 1, 0, kPi / 2});  // shaft along +x
  ShapedTissueCoupling coupling(tool, {body_surface(liver)});
  const mechanics::MechanicalState state = mechanics::make_state(liver.model);
  haptics::ToolState st;
  st.active = st.touched = true;
  st.body = 0;
  st.tip = Vec3(0.0, 0.0, top_at(liver, 0.02, 0.0) + r - 0.001);  // 1 mm into the top, tip at x = 0
  st.orientation = Eigen::Quaterniond(Eigen::AngleAxisd(kPi / 2, Vec3(0, 1, 0)));
  st.radius = r;
  st.length = length;
  st.depth_m = 0.002;
  st.force = Vec3(0.3, -0.2, 1.7);
  std::vector<double> forces(3 * liver.model.node_count(), 0.0);
  coupling.add_tissue_forces(st, liver.model, state, forces);
  Vec3 sum = Vec3::Zero();
  double near_middle = 0.0;
  for (std::size_t n = 0; n < liver.model.node_count(); ++n) {
    const Vec3 f(forces[3 * n], forces[3 * n + 1], forces[3 * n + 2]);
    sum += f;
    if (std::abs(liver.mesh.nodes[n].x() - 0.5 * length) < 0.01) near_middle += f.norm();
  }
  EXPECT_NEAR((sum + st.force).norm(), 0.0, 1e-9 * st.force.norm());
  EXPECT_GT(coupling.last_contacts().size(), 3u);
  EXPECT_GT(near_middle, 0.1 * st.force.norm());  // not only at the tip
}

// A capsule lying across the liver's top, pressed in and swept sideways (across its shaft)
// through the haptic loop and the session: the nodes near the middle of the shaft move, not only
// those near the tip; every felt force went to the tissue (the tool's state carries the liver).
TEST(ShapedTissueCoupling, ACapsuleSweptSidewaysDisplacesTheTissueAlongTheShaft) {
  Liver liver = make_liver();
  const double r = 0.004, length = 0.04;
  const double top = top_at(liver, 0.02, 0.0);
  const auto tool = make_tool(ToolShape::kCapsule, r, length, {0, 1, 0, kPi / 2});
  std::vector<coupling::SessionBody> bodies;
  auto mapping = coupling::SurfaceMapping::by_index(liver.mesh.nodes, liver.boundary.surface.vertices,
                                                    liver.boundary.surface_to_volume);
  ASSERT_TRUE(mapping);
  const std::size_t nodes = liver.model.node_count();
  std::vector<ToolBodySurface> surfaces{body_surface(liver)};
  bodies.push_back(
      coupling::SessionBody{"liver", std::move(liver.model), liver.boundary.surface, std::move(*mapping), {}, {}});
  coupling::SessionConfig config;
  config.haptics.realtime_priority = false;
  config.haptics.safety.fade_in_s = 0.0;
  config.tool = tool;
  config.tool_coupling = std::make_shared<ShapedTissueCoupling>(tool, std::move(surfaces));
  haptics::MotionConfig motion;
  motion.kind = haptics::MotionKind::kPressAndSlide;
  motion.start_m = Vec3(0.0, -0.01, top + r + 0.01);
  motion.direction = Vec3(0, 0, -1);
  motion.approach_m = 0.01;
  motion.depth_m = 0.004;
  motion.speed_m_per_s = 0.02;
  motion.slide_direction = Vec3(0, 1, 0);
  motion.slide_distance_m = 0.02;
  motion.hold_s = 0.2;
  auto scripted = haptics::ScriptedMotion::make(motion);
  ASSERT_TRUE(scripted) << scripted.error().to_string();
  auto session =
      coupling::Session::make(std::move(bodies), std::make_unique<haptics::ScriptedDevice>(*scripted), config);
  ASSERT_TRUE(session) << session.error().to_string();
  const Eigen::VectorXd rest = (*session)->state().x;
  double largest_middle = 0.0, largest_tip = 0.0, felt = 0.0;
  int touching = 0;
  for (int step = 0; step < 150; ++step) {
    (*session)->run_virtual(0.01, [&](const haptics::HapticSample& s) {
      if (s.tool.touched) {
        ++touching;
        EXPECT_EQ(s.tool.body, 0);
        felt = std::max(felt, s.force.norm());
      }
    });
    const Eigen::VectorXd& x = (*session)->state().x;
    for (std::size_t n = 0; n < nodes; ++n) {
      const Vec3& p = liver.mesh.nodes[n];
      if (std::abs(p.y()) > 0.02 || p.z() < top - 0.01) continue;
      const double moved =
          (x.segment<3>(3 * static_cast<Eigen::Index>(n)) - rest.segment<3>(3 * static_cast<Eigen::Index>(n))).norm();
      if (std::abs(p.x() - 0.5 * length) < 0.006) largest_middle = std::max(largest_middle, moved);
      if (std::abs(p.x()) < 0.006) largest_tip = std::max(largest_tip, moved);
    }
  }
  EXPECT_GT(touching, 100);
  EXPECT_GT(felt, 0.05);
  EXPECT_GT(largest_middle, 0.5e-3);
  EXPECT_GT(largest_middle, 0.3 * largest_tip);
}

// Chatter: a capsule lying across the liver's top, pressed 6 mm past the surface at the device's
// full stiffness (3 kN/m, several times the soft liver's own under the shaft) and held: the
// force the hand feels settles and stays steady. On this simple liver the press is steady; the
// default probe's press on the medium liver still swings at full force (docs/performance.md,
// "A tool with a shape"), which this test does not catch.
TEST(ShapedTissueCoupling, AFullForceSteadyPressOnTheLiverIsSmooth) {
  Liver liver = make_liver();
  const double r = 0.004, length = 0.04;
  const double top = top_at(liver, 0.02, 0.0);
  const auto tool = make_tool(ToolShape::kCapsule, r, length, {0, 1, 0, kPi / 2});
  auto mapping = coupling::SurfaceMapping::by_index(liver.mesh.nodes, liver.boundary.surface.vertices,
                                                    liver.boundary.surface_to_volume);
  ASSERT_TRUE(mapping);
  std::vector<ToolBodySurface> surfaces{body_surface(liver)};
  std::vector<coupling::SessionBody> bodies;
  bodies.push_back(
      coupling::SessionBody{"liver", std::move(liver.model), liver.boundary.surface, std::move(*mapping), {}, {}});
  coupling::SessionConfig config;
  config.haptics.realtime_priority = false;
  config.haptics.safety.fade_in_s = 0.0;
  config.tool = tool;
  config.tool_coupling = std::make_shared<ShapedTissueCoupling>(tool, std::move(surfaces));
  haptics::MotionConfig motion =
      haptics::MotionConfig::poke(Vec3(0.0, 0.0, top + r + 0.005), Vec3(0, 0, -1), 0.005, 0.006, 0.02, 10.0);
  auto scripted = haptics::ScriptedMotion::make(motion);
  ASSERT_TRUE(scripted) << scripted.error().to_string();
  auto session =
      coupling::Session::make(std::move(bodies), std::make_unique<haptics::ScriptedDevice>(*scripted), config);
  ASSERT_TRUE(session) << session.error().to_string();
  // Pressed in by 0.55 s; settled for 1.5 s; then 1 s of steady press, the felt force at each
  // simulation step (the mean over its ten ticks).
  std::vector<double> felt;
  double sum = 0.0;
  int ticks = 0;
  for (int step = 0; step < 300; ++step) {
    sum = 0.0;
    ticks = 0;
    (*session)->run_virtual(0.01, [&](const haptics::HapticSample& s) {
      sum += s.force.z();
      ++ticks;
      ASSERT_TRUE(s.force.allFinite());
    });
    if (step >= 200) felt.push_back(sum / std::max(1, ticks));
  }
  double lo = felt.front(), hi = felt.front(), mean = 0.0;
  int turns = 0;
  for (std::size_t i = 0; i < felt.size(); ++i) {
    lo = std::min(lo, felt[i]);
    hi = std::max(hi, felt[i]);
    mean += felt[i] / static_cast<double>(felt.size());
    if (i >= 2 && (felt[i] - felt[i - 1]) * (felt[i - 1] - felt[i - 2]) < 0.0) ++turns;
  }
  std::printf("steady press: mean %.4f N, range %.5f N, %d turns of dF in %zu steps\n", mean, hi - lo, turns,
              felt.size());
  EXPECT_GT(mean, 1.0);             // a real press: over 1 N up
  EXPECT_LT(hi - lo, 0.02 * mean);  // steady within 2%
  EXPECT_LT(turns, 10);             // not swinging step after step
}

}  // namespace
}  // namespace hof::procedures
