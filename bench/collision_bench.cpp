// Collision queries on the boundary surfaces of the four standard livers: tree build (leaf
// sizes 1 and 4), refit, and the three haptic queries with the tree and by brute force.
// Run: build/release/bin/hof_bench_collision (filter with --benchmark_filter=REGEX).
//
// Workload (the haptic use case): 1024 fixed motions per iteration, each starting within
// 5 mm of the surface (a random point of a random triangle, moved along its normal) and
// moving 1 cm in a random direction, so about half of them cross the surface.
// closest_point searches up to 1 cm (H3D HapticsOptions.maxDistance), the swept sphere has
// the RuspiniRenderer proxy radius 2.5 mm. `per_query` is the time of one query.

#include <benchmark/benchmark.h>

#include <cstdio>
#include <cstdlib>
#include <limits>
#include <map>
#include <random>
#include <string>
#include <vector>

#include "hof/collision/aabb_tree.h"
#include "hof/mesh/boundary.h"
#include "hof/mesh/liver_generator.h"

namespace {

using namespace hof;
using namespace hof::collision;
using mesh::LiverResolution;

constexpr int kQueries = 1024;
constexpr double kMaxDistance = 0.01;    // m
constexpr double kProxyRadius = 0.0025;  // m

const mesh::TriMesh& surface(LiverResolution r) {
  static std::map<LiverResolution, mesh::TriMesh> cache;
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

TriangleMeshView view(const mesh::TriMesh& m) { return {m.vertices, m.triangles}; }

struct Motions {
  std::vector<Vec3> a, b;
};

Motions make_motions(const mesh::TriMesh& m) {
  std::mt19937 gen(12345);
  std::uniform_real_distribution<double> unit(0.0, 1.0), signed_unit(-1.0, 1.0);
  std::uniform_int_distribution<std::size_t> pick(0, m.triangles.size() - 1);
  Motions q;
  for (int i = 0; i < kQueries; ++i) {
    const mesh::Tri& t = m.triangles[pick(gen)];
    double u = unit(gen), v = unit(gen);
    if (u + v > 1.0) u = 1.0 - u, v = 1.0 - v;
    const Vec3& p0 = m.vertices[t[0]];
    const Vec3 e1 = m.vertices[t[1]] - p0, e2 = m.vertices[t[2]] - p0;
    const Vec3 a = p0 + u * e1 + v * e2 + 0.005 * signed_unit(gen) * e1.cross(e2).normalized();
    const Vec3 d = Vec3(signed_unit(gen), signed_unit(gen), signed_unit(gen)).normalized();
    q.a.push_back(a);
    q.b.push_back(a + 0.01 * d);
  }
  return q;
}

void set_counters(benchmark::State& state, const mesh::TriMesh& m, std::int64_t per_iteration) {
  state.SetItemsProcessed(state.iterations() * per_iteration);
  state.counters["triangles"] = static_cast<double>(m.triangles.size());
  state.counters["per_query"] = benchmark::Counter(
      static_cast<double>(per_iteration), benchmark::Counter::kIsIterationInvariantRate | benchmark::Counter::kInvert);
}

void bm_build(benchmark::State& state, LiverResolution r, int leaf) {
  const mesh::TriMesh& m = surface(r);
  int depth = 0;
  for (auto _ : state) {
    const AabbTree tree = AabbTree::build(view(m), {.max_triangles_in_leaf = leaf});
    depth = tree.depth();
    benchmark::DoNotOptimize(depth);
  }
  state.counters["triangles"] = static_cast<double>(m.triangles.size());
  state.counters["depth"] = depth;
}

void bm_refit(benchmark::State& state, LiverResolution r) {
  const mesh::TriMesh& rest = surface(r);
  mesh::TriMesh moved = rest;
  for (Vec3& v : moved.vertices) v += 0.002 * Vec3(std::sin(30 * v.y()), std::cos(20 * v.z()), 0.0);
  AabbTree tree = AabbTree::build(view(rest));
  bool flip = false;
  for (auto _ : state) {
    flip = !flip;
    benchmark::DoNotOptimize(tree.refit(view(flip ? moved : rest)));
  }
  state.counters["triangles"] = static_cast<double>(rest.triangles.size());
}

enum class Query { kClosestPoint, kSegment, kSweptSphere };

void bm_query(benchmark::State& state, LiverResolution r, Query query, bool use_tree) {
  const mesh::TriMesh& m = surface(r);
  const Motions q = make_motions(m);
  const AabbTree tree = AabbTree::build(view(m), {.use_bound_tree = use_tree});
  std::int64_t hits = 0;
  for (auto _ : state) {
    hits = 0;
    for (int i = 0; i < kQueries; ++i) {
      std::int32_t triangle = -1;
      switch (query) {
        case Query::kClosestPoint:
          triangle = tree.closest_point(view(m), q.a[i], kMaxDistance).triangle;
          break;
        case Query::kSegment:
          triangle = tree.first_hit_segment(view(m), q.a[i], q.b[i]).triangle;
          break;
        case Query::kSweptSphere:
          triangle = tree.first_hit_swept_sphere(view(m), q.a[i], q.b[i], kProxyRadius).triangle;
          break;
      }
      hits += triangle >= 0 ? 1 : 0;
    }
    benchmark::DoNotOptimize(hits);
  }
  set_counters(state, m, kQueries);
  state.counters["hit_fraction"] = static_cast<double>(hits) / kQueries;
}

void register_all() {
  const LiverResolution resolutions[] = {LiverResolution::kSimple, LiverResolution::kCoarse, LiverResolution::kMedium,
                                         LiverResolution::kFine};
  const std::pair<Query, const char*> queries[] = {{Query::kClosestPoint, "closest_point"},
                                                   {Query::kSegment, "first_hit_segment"},
                                                   {Query::kSweptSphere, "first_hit_swept_sphere"}};
  for (LiverResolution r : resolutions) {
    const std::string res(mesh::to_string(r));
    for (int leaf : {1, 4}) {
      benchmark::RegisterBenchmark(("build/" + res + "/leaf" + std::to_string(leaf)).c_str(), bm_build, r, leaf)
          ->Unit(benchmark::kMicrosecond);
    }
    benchmark::RegisterBenchmark(("refit/" + res).c_str(), bm_refit, r)->Unit(benchmark::kMicrosecond);
    for (const auto& [query, name] : queries) {
      for (bool use_tree : {true, false}) {
        benchmark::RegisterBenchmark((std::string(name) + "/" + res + (use_tree ? "/tree" : "/brute")).c_str(),
                                     bm_query, r, query, use_tree)
            ->Unit(benchmark::kMicrosecond);
      }
    }
  }
}

}  // namespace

int main(int argc, char** argv) {
  benchmark::Initialize(&argc, argv);
  if (benchmark::ReportUnrecognizedArguments(argc, argv)) return 1;
  register_all();
  benchmark::RunSpecifiedBenchmarks();
  benchmark::Shutdown();
  return 0;
}
