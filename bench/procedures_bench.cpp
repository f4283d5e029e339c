// The needle's cost: its haptic tick (inside the tissue, after the puncture: the Fung law, the
// lateral spring) and its per-step reaction spread along a 45 mm path in the medium liver; a
// shaped tool's tick (a capsule lying on a finely meshed floor, ~1,000 triangles within reach).
// Run: build/release/bin/hof_bench_procedures (--benchmark_repetitions=5 for the spread).

#include <benchmark/benchmark.h>

#include <array>

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

// A capsule (r 4 mm, shaft 40 mm) lying on the sheet, pressed 2 mm in and moving sideways
// 1 mm/tick (1 m/s): the tick gathers the triangles within its reach from the bound tree, moves
// the proxy, pushes it out along the shaft and sums the contacts. Arg: squares per side of a
// 20 cm sheet (88: ~1,000 triangles within reach).
void BM_ShapedToolTickCapsule(benchmark::State& state) {
  procedures::ShapedToolConfig config;
  config.shape = procedures::ToolShape::kCapsule;
  config.radius_m = 0.004;
  config.length_m = 0.04;
  config.orientation = {0.0, 1.0, 0.0, 1.5707963267948966};  // the shaft along +x
  auto tool = *procedures::ShapedTool::make(config);
  const haptics::SurfaceSnapshot surface = sheet_snapshot(0.1, static_cast<int>(state.range(0)));
  std::array<haptics::ContactState, 1> contacts{};
  std::array<const haptics::SurfaceSnapshot*, 1> surfaces{&surface};
  std::array<Vec3, 1> forces{};
  haptics::ToolTickInput in;
  in.contacts = contacts;
  in.surfaces = surfaces;
  in.velocity = Vec3(0, 1.0, 0);
  haptics::ToolState out;
  in.position = Vec3(-0.02, -0.01, 0.02);
  (void)tool->tick(in, forces, out);
  for (int k = 0; k < 100; ++k) {
    in.position.z() = 0.02 - 2.2e-4 * k;  // down to 2 mm into the sheet
    (void)tool->tick(in, forces, out);
  }
  double y = -0.01;
  for (auto _ : state) {
    y = y > 0.01 ? -0.01 : y + 0.001;
    in.position.y() = y;
    benchmark::DoNotOptimize(tool->tick(in, forces, out));
  }
  std::vector<std::int32_t> near(surface.triangles.size());
  // The reach the tick gathers: the shape's bounding sphere (about the shaft's middle), two
  // sub-moves and the motion.
  state.counters["triangles_in_reach"] =
      static_cast<double>(surface.tree.triangles_near(Vec3(0.0, y, 0.002), 0.024 + 0.004 + 0.0005, near));
  state.counters["contacts"] = out.contact_count;
  state.counters["force_n"] = out.force.norm();
}
BENCHMARK(BM_ShapedToolTickCapsule)->Arg(44)->Arg(88)->Arg(176)->ArgNames({"squares"})->Unit(benchmark::kMicrosecond);

}  // namespace

BENCHMARK_MAIN();
