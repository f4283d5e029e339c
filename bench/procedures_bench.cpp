// The needle's cost: its haptic tick (inside the tissue, after the puncture: the Fung law, the
// lateral spring) and its per-step reaction spread along a 45 mm path in the medium liver.
// Run: build/release/bin/hof_bench_procedures (--benchmark_repetitions=5 for the spread).

#include <benchmark/benchmark.h>

#include <array>

#include "hof/mechanics/mechanical_model.h"
#include "hof/mesh/boundary.h"
#include "hof/mesh/liver_generator.h"
#include "hof/procedures/needle.h"
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

}  // namespace

BENCHMARK_MAIN();
