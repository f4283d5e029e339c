// Haptic tick cost of each renderer against the standard livers' surfaces, and the cost of
// refitting a surface snapshot. Run: build/release/bin/hof_bench_haptics
// The device slides over the liver's top pressing 3 mm in (a contact every tick); tick
// times are recorded per tick so that p50/p99/max can be reported (goal: p99 < 50 µs on
// `fine`).

#include <benchmark/benchmark.h>

#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <map>
#include <numbers>

#include "hof/haptics/haptic_renderer.h"
#include "hof/haptics/surface_snapshot.h"
#include "hof/mesh/boundary.h"
#include "hof/mesh/liver_generator.h"

namespace {

using namespace hof;
using namespace hof::haptics;

const mesh::TriMesh& liver_surface(mesh::LiverResolution r) {
  static std::map<mesh::LiverResolution, mesh::TriMesh> cache;
  auto it = cache.find(r);
  if (it == cache.end()) {
    auto m = mesh::generate_liver(r);
    if (!m) {
      std::fprintf(stderr, "%s\n", m.error().to_string().c_str());
      std::exit(1);
    }
    it = cache.emplace(r, mesh::extract_boundary(m->nodes, m->tets).surface).first;
  }
  return it->second;
}

// Height of the liver's top surface under (x, y), by a downward segment query.
double top_height(const SurfaceSnapshot& s, double x, double y) {
  const collision::SweepHit hit = s.tree.first_hit_segment(s.view(), Vec3(x, y, 0.5), Vec3(x, y, -0.5));
  return hit.triangle >= 0 ? hit.point.z() : 0.0;
}

void BM_Tick(benchmark::State& state, mesh::LiverResolution r, RendererKind kind) {
  const SurfaceSnapshot s = make_snapshot(liver_surface(r));
  RendererConfig config;
  config.kind = kind;
  SurfaceMaterial material;
  material.stiffness = 1.0;
  HapticRenderer renderer(config, material, 1000.0);
  // A loop of device positions 3 mm under the top surface (precomputed: not timed).
  constexpr int kPath = 4000;
  std::vector<Vec3> path(kPath);
  for (int i = 0; i < kPath; ++i) {
    const double a = 2 * std::numbers::pi * i / kPath;
    const double x = 0.03 + 0.04 * std::cos(a), y = 0.03 * std::sin(a);
    path[static_cast<std::size_t>(i)] = Vec3(x, y, top_height(s, x, y) - 0.003);
  }
  renderer.reset(path[0] + Vec3(0, 0, 0.02));
  std::vector<double> times;
  times.reserve(1 << 20);
  std::size_t i = 0;
  std::size_t contacts = 0;
  for (auto _ : state) {
    const auto t0 = std::chrono::steady_clock::now();
    const ContactState& c = renderer.update(path[i % kPath], Vec3::Zero(), s, false, 1e-3);
    const auto t1 = std::chrono::steady_clock::now();
    contacts += c.in_contact ? 1 : 0;
    if (times.size() < times.capacity()) times.push_back(std::chrono::duration<double, std::micro>(t1 - t0).count());
    ++i;
  }
  std::sort(times.begin(), times.end());
  auto q = [&](double f) {
    return times.empty() ? 0.0 : times[static_cast<std::size_t>(f * static_cast<double>(times.size() - 1))];
  };
  state.counters["p50_us"] = q(0.5);
  state.counters["p99_us"] = q(0.99);
  state.counters["max_us"] = times.empty() ? 0.0 : times.back();
  state.counters["contact_fraction"] = static_cast<double>(contacts) / static_cast<double>(std::max<std::size_t>(i, 1));
  state.counters["triangles"] = static_cast<double>(s.triangles.size());
}

void BM_Refit(benchmark::State& state, mesh::LiverResolution r) {
  const mesh::TriMesh& surface = liver_surface(r);
  SurfaceSnapshot s = make_snapshot(surface);
  std::vector<Vec3> moved = surface.vertices;
  double phase = 0.0;
  for (auto _ : state) {
    phase += 0.01;
    for (std::size_t k = 0; k < moved.size(); ++k) {
      moved[k] = surface.vertices[k] + Vec3(0, 0, 0.002 * std::sin(30.0 * surface.vertices[k].x() + phase));
    }
    update_snapshot(s, moved, {}, phase);
    benchmark::DoNotOptimize(s.vertices.data());
  }
  state.counters["triangles"] = static_cast<double>(s.triangles.size());
}

void register_all() {
  using R = mesh::LiverResolution;
  for (R r : {R::kSimple, R::kCoarse, R::kMedium, R::kFine}) {
    const std::string res(mesh::to_string(r));
    for (const auto& [kind, name] :
         {std::pair{RendererKind::kPenalty, "Penalty"}, std::pair{RendererKind::kGodObject, "GodObject"},
          std::pair{RendererKind::kRuspini, "Ruspini"}}) {
      benchmark::RegisterBenchmark(("Tick/" + res + "/" + name).c_str(), BM_Tick, r, kind)
          ->Unit(benchmark::kMicrosecond);
    }
    benchmark::RegisterBenchmark(("SnapshotUpdate/" + res).c_str(), BM_Refit, r)->Unit(benchmark::kMicrosecond);
  }
}

}  // namespace

int main(int argc, char** argv) {
  register_all();
  benchmark::Initialize(&argc, argv);
  benchmark::RunSpecifiedBenchmarks();
  benchmark::Shutdown();
  return 0;
}
