// Mesh pipeline benchmarks on the `fine` standard liver (~40,000 tetrahedra):
// reading each file format, boundary extraction, edges and the quality report.
// Run: build/release/bin/hof_bench_mesh

#include <benchmark/benchmark.h>

#include <cstdio>
#include <cstdlib>
#include <filesystem>

#include "hof/mesh/boundary.h"
#include "hof/mesh/liver_generator.h"
#include "hof/mesh/mesh_io.h"
#include "hof/mesh/mesh_report.h"

namespace {

using namespace hof::mesh;

// The fine liver and its files, made once for all benchmarks.
struct FineLiver {
  Mesh mesh;
  std::filesystem::path dir;

  FineLiver() {
    auto m = generate_liver(LiverResolution::kFine);
    if (!m) {
      std::fprintf(stderr, "%s\n", m.error().to_string().c_str());
      std::exit(1);
    }
    mesh = std::move(*m);
    dir = std::filesystem::temp_directory_path() / "hof_bench_mesh";
    std::filesystem::create_directories(dir);
    bool ok = write_mesh(mesh, dir / "fine-v4.msh", MshVersion::k4_1).has_value() &&
              write_mesh(mesh, dir / "fine-v2.msh", MshVersion::k2_2).has_value() &&
              write_mesh(mesh, dir / "fine.vtu").has_value();
    const BoundarySurface b = extract_boundary(mesh.nodes, mesh.tets);
    Mesh surface;
    surface.nodes = b.surface.vertices;
    surface.triangles = b.surface.triangles;
    ok = ok && write_mesh(surface, dir / "fine.obj").has_value();
    if (!ok) {
      std::fprintf(stderr, "could not write the benchmark files in %s\n", dir.c_str());
      std::exit(1);
    }
  }
};

const FineLiver& fine() {
  static const FineLiver liver;
  return liver;
}

void read_file(benchmark::State& state, const char* name) {
  const auto path = fine().dir / name;
  std::size_t tets = 0;
  for (auto _ : state) {
    auto r = read_mesh(path);
    if (!r)
      state.SkipWithError(r.error().to_string().c_str());
    else
      tets = r->mesh.tets.size();
    benchmark::DoNotOptimize(tets);
  }
  state.counters["tets"] = static_cast<double>(tets);
  state.counters["bytes"] = static_cast<double>(std::filesystem::file_size(path));
}

void BM_ReadMshV41_Fine(benchmark::State& s) { read_file(s, "fine-v4.msh"); }
void BM_ReadMshV22_Fine(benchmark::State& s) { read_file(s, "fine-v2.msh"); }
void BM_ReadVtu_Fine(benchmark::State& s) { read_file(s, "fine.vtu"); }
void BM_ReadObjSurface_Fine(benchmark::State& s) { read_file(s, "fine.obj"); }

void BM_ExtractBoundary_Fine(benchmark::State& state) {
  const Mesh& m = fine().mesh;
  for (auto _ : state) {
    BoundarySurface b = extract_boundary(m.nodes, m.tets);
    benchmark::DoNotOptimize(b.surface.triangles.data());
  }
  state.counters["tets"] = static_cast<double>(m.tets.size());
  state.SetItemsProcessed(state.iterations() * static_cast<std::int64_t>(m.tets.size()));
}

void BM_TetEdges_Fine(benchmark::State& state) {
  const Mesh& m = fine().mesh;
  for (auto _ : state) {
    auto edges = tet_edges(m.tets);
    benchmark::DoNotOptimize(edges.data());
  }
}

void BM_MeshReport_Fine(benchmark::State& state) {
  const Mesh& m = fine().mesh;
  for (auto _ : state) {
    MeshReport r = make_mesh_report(m);
    benchmark::DoNotOptimize(r.volume_m3);
  }
}

BENCHMARK(BM_ReadMshV41_Fine)->Unit(benchmark::kMillisecond);
BENCHMARK(BM_ReadMshV22_Fine)->Unit(benchmark::kMillisecond);
BENCHMARK(BM_ReadVtu_Fine)->Unit(benchmark::kMillisecond);
BENCHMARK(BM_ReadObjSurface_Fine)->Unit(benchmark::kMillisecond);
BENCHMARK(BM_ExtractBoundary_Fine)->Unit(benchmark::kMillisecond);
BENCHMARK(BM_TetEdges_Fine)->Unit(benchmark::kMillisecond);
BENCHMARK(BM_MeshReport_Fine)->Unit(benchmark::kMillisecond);

}  // namespace

BENCHMARK_MAIN();
