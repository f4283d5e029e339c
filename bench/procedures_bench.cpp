// The needle's cost: its haptic tick (inside the tissue, after the puncture: the Fung law, the
// lateral spring) and its per-step reaction spread along a 45 mm path in the medium liver; a
// shaped tool's tick (a capsule lying on a finely meshed floor, ~1,000 triangles within reach).
// Run: build/release/bin/hof_bench_procedures (--benchmark_repetitions=5 for the spread).

#include <benchmark/benchmark.h>

#include <algorithm>
#include <array>
#include <chrono>
#include <ctime>
#include <vector>

#include "hof/mechanics/mechanical_model.h"
#include "hof/mesh/boundary.h"
#include "hof/mesh/liver_generator.h"
#include "hof/procedures/needle.h"
#include "hof/procedures/shaped_tool.h"
#include "support/box_surface.h"

namespace {

using namespace hof;

// One closed box surface as the snapshot the tick reads (its part is body 0).
haptics::SurfaceSnapshot box_snapshot() {
  return haptics::make_snapshot(hof::testing::box_surface(Vec3(-0.05, -0.05, -0.1), Vec3(0.05, 0.05, 0.0)));
}

void BM_NeedleTickInside(benchmark::State& state) {
  procedures::NeedleConfig config;
  config.tissue.model = static_cast<procedures::NeedleForceModel>(state.range(0));
  auto tool = *procedures::NeedleTool::make(config, {"block"}, {true});
  const haptics::SurfaceSnapshot surface = box_snapshot();
  std::array<haptics::ContactState, 1> contacts{};
  contacts[0].in_contact = true;
  contacts[0].triangle = 2;
  contacts[0].point = Vec3(0.0, 0.0, 0.0);
  contacts[0].normal = Vec3(0, 0, 1);
  std::array<const haptics::SurfaceSnapshot*, 1> surfaces{&surface};
  std::array<Vec3, 1> forces{};
  haptics::ToolTickInput in;
  in.contacts = contacts;
  in.surfaces = surfaces;
  in.velocity = Vec3(0, 0, -0.01);
  haptics::ToolState out;
  double t = 0.0;
  // Into the tissue, past the capsule (30 mm), then measured there.
  for (int k = 0; k <= 3000; ++k, t += 1e-3) {
    in.time_s = t;
    in.position = Vec3(0.0001, 0.0, -1e-5 * k);
    (void)tool->tick(in, forces, out);
  }
  for (auto _ : state) {
    in.time_s = (t += 1e-3);
    forces[0] = Vec3(0, 0, 1);
    benchmark::DoNotOptimize(tool->tick(in, forces, out));
  }
  state.SetLabel(std::string(procedures::phase_name(static_cast<procedures::NeedlePhase>(out.phase))));
}
BENCHMARK(BM_NeedleTickInside)->Arg(0)->Arg(1)->ArgNames({"model"});

void BM_NeedleReactionSpread(benchmark::State& state) {
  const mesh::Mesh liver = *mesh::generate_liver(static_cast<mesh::LiverResolution>(state.range(0)));
  mechanics::ModelConfig c;
  c.positions = liver.nodes;
  c.tets = liver.tets;
  const mechanics::MechanicalModel model = *mechanics::build_model(c);
  const mechanics::MechanicalState s = mechanics::make_state(model);
  auto tool = *procedures::NeedleTool::make(procedures::NeedleConfig{}, {"liver"}, {true});
  procedures::NeedleTissueCoupling coupling(tool);
  haptics::ToolState needle;
  needle.active = needle.touched = needle.broken = true;
  needle.phase = static_cast<std::uint8_t>(procedures::NeedlePhase::kPunctured);
  needle.body = 0;
  needle.entry = Vec3(0.03, 0.0, 0.053);
  needle.axis = Vec3(0, 0, -1);
  needle.depth_m = 0.045;
  needle.force = Vec3(0, 0, -2.5);
  std::vector<double> forces(3 * model.node_count(), 0.0);
  for (auto _ : state) {
    coupling.add_tissue_forces(needle, model, s, forces);
    benchmark::DoNotOptimize(forces.data());
  }
  state.counters["nodes"] = static_cast<double>(model.node_count());
}
BENCHMARK(BM_NeedleReactionSpread)->Arg(2)->Arg(3)->ArgNames({"resolution"})->Unit(benchmark::kMicrosecond);

// A flat sheet at z = 0 over [-h, h]², `n` × `n` squares of two triangles.
haptics::SurfaceSnapshot sheet_snapshot(double h, int n) {
  mesh::TriMesh m;
  for (int j = 0; j <= n; ++j) {
    for (int i = 0; i <= n; ++i) m.vertices.emplace_back(-h + 2 * h * i / n, -h + 2 * h * j / n, 0.0);
  }
  for (int j = 0; j < n; ++j) {
    for (int i = 0; i < n; ++i) {
      const int a = j * (n + 1) + i;
      m.triangles.push_back({a, a + 1, a + n + 2});
      m.triangles.push_back({a, a + n + 2, a + n + 1});
    }
  }
  return haptics::make_snapshot(m);
}

// Per-tick times, for the percentiles the haptic loop's budget is about (a mean hides the slow
// ticks). The thread's CPU time per tick as well as the wall time: on the shared build machine
// the wall time includes the other processes' slices.
struct TickTimes {
  std::vector<double> wall_us, cpu_us;
  static double cpu_now_us() {
    timespec t{};
    clock_gettime(CLOCK_THREAD_CPUTIME_ID, &t);
    return 1e6 * static_cast<double>(t.tv_sec) + 1e-3 * static_cast<double>(t.tv_nsec);
  }
  static double percentile(std::vector<double> v, double q) {
    if (v.empty()) return 0.0;
    const auto k = static_cast<std::size_t>(q * static_cast<double>(v.size() - 1));
    std::nth_element(v.begin(), v.begin() + static_cast<std::ptrdiff_t>(k), v.end());
    return v[k];
  }
  void report(benchmark::State& state) const {
    state.counters["p50_cpu_us"] = percentile(cpu_us, 0.50);
    state.counters["p99_cpu_us"] = percentile(cpu_us, 0.99);
    state.counters["p99_wall_us"] = percentile(wall_us, 0.99);
    state.counters["ticks"] = static_cast<double>(cpu_us.size());
  }
};

// A capsule (r 4 mm, shaft 40 mm) lying on the sheet, pressed 2 mm in and moving sideways
// 1 mm/tick (1 m/s): the tick gathers the triangles within its reach from the bound tree, moves
// the proxy, pushes it out along the shaft and sums the contacts. Args: squares per side of a
// 20 cm sheet (88: ~1,000 triangles within reach), and the shaft's heading in the sheet's
// plane in degrees from +x (45: along a diagonal of the bound tree's boxes, its worst case).
void BM_ShapedToolTickCapsule(benchmark::State& state) {
  procedures::ShapedToolConfig config;
  config.shape = procedures::ToolShape::kCapsule;
  config.radius_m = 0.004;
  config.length_m = 0.04;
  // The shaft along +x (+z turned about y), then turned by the heading about z.
  const double heading = static_cast<double>(state.range(1)) * 3.14159265358979323846 / 180.0;
  const Eigen::Quaterniond q = Eigen::Quaterniond(Eigen::AngleAxisd(heading, Vec3::UnitZ())) *
                               Eigen::Quaterniond(Eigen::AngleAxisd(1.5707963267948966, Vec3::UnitY()));
  const Eigen::AngleAxisd aa(q);
  config.orientation = {aa.axis().x(), aa.axis().y(), aa.axis().z(), aa.angle()};
  auto tool = *procedures::ShapedTool::make(config);
  const haptics::SurfaceSnapshot surface = sheet_snapshot(0.1, static_cast<int>(state.range(0)));
  std::array<haptics::ContactState, 1> contacts{};
  std::array<const haptics::SurfaceSnapshot*, 1> surfaces{&surface};
  std::array<Vec3, 1> forces{};
  haptics::ToolTickInput in;
  in.contacts = contacts;
  in.surfaces = surfaces;
  // Sideways: across the shaft, in the sheet's plane.
  const Vec3 across = q * Vec3(0.0, 1.0, 0.0);
  const Vec3 along = q * Vec3(0.0, 0.0, 1.0);
  in.velocity = across;
  haptics::ToolState out;
  const Vec3 centre = -0.5 * 0.04 * along;  // the shaft's middle over the sheet's centre
  in.position = centre - 0.01 * across + Vec3(0, 0, 0.02);
  (void)tool->tick(in, forces, out);
  for (int k = 0; k < 100; ++k) {
    in.position.z() = 0.02 - 2.2e-4 * k;  // down to 2 mm into the sheet
    (void)tool->tick(in, forces, out);
  }
  double y = -0.01;
  TickTimes times;
  times.wall_us.reserve(1 << 22);
  times.cpu_us.reserve(1 << 22);
  for (auto _ : state) {
    y = y > 0.01 ? -0.01 : y + 0.001;
    in.position = centre + y * across + Vec3(0, 0, in.position.z());
    const auto wall = std::chrono::steady_clock::now();
    const double cpu = TickTimes::cpu_now_us();
    benchmark::DoNotOptimize(tool->tick(in, forces, out));
    if (times.cpu_us.size() < times.cpu_us.capacity()) {
      times.cpu_us.push_back(TickTimes::cpu_now_us() - cpu);
      times.wall_us.push_back(
          std::chrono::duration<double, std::micro>(std::chrono::steady_clock::now() - wall).count());
    }
  }
  times.report(state);
  std::vector<std::int32_t> near(surface.triangles.size());
  // The reach: the shape's bounding sphere (about the shaft's middle), two sub-moves and the
  // motion — the definition of "triangles within reach" the figure is about.
  state.counters["triangles_in_reach"] = static_cast<double>(
      surface.tree.triangles_near(centre + y * across + Vec3(0, 0, 0.002), 0.024 + 0.004 + 0.0005, near));
  state.counters["contacts"] = out.contact_count;
  state.counters["force_n"] = out.force.norm();
}
BENCHMARK(BM_ShapedToolTickCapsule)
    ->Args({44, 0})
    ->Args({88, 0})
    ->Args({88, 45})
    ->Args({176, 0})
    ->ArgNames({"squares", "heading"})
    ->Unit(benchmark::kMicrosecond);

}  // namespace

BENCHMARK_MAIN();
