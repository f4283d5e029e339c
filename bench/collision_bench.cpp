// Collision queries on the boundary surfaces of the four standard livers: tree build (leaf
// sizes 1 and 4), refit, and the three haptic queries with the tree and by brute force.
// Run: build/release/bin/hof_bench_collision (filter with --benchmark_filter=REGEX).
//
// Workload (the haptic use case): 1024 fixed motions per iteration, each starting within
// 5 mm of the surface (a random point of a random triangle, moved along its normal) and
// moving 1 cm in a random direction, so about half of them cross the surface.
// closest_point searches up to 1 cm (H3D HapticsOptions.maxDistance), the swept sphere has
// the RuspiniRenderer proxy radius 2.5 mm. `per_query` is the time of one query.
//
// detect/…: ContactDetector::detect() on two copies of a liver surface (the second shifted
// along x by 85% of the liver's width and raised 1 cm, so their lobes interpenetrate), each
// iteration alternating between two poses 1 mm apart (so the trees are refitted, as in a
// simulation), alarm distance 2 mm; "continuous" also passes the previous positions. "apart"
// shifts the second copy by twice the width (the broad phase rejects the pair).

#include <benchmark/benchmark.h>

#include <cstdio>
#include <cstdlib>
#include <limits>
#include <map>
#include <random>
#include <string>
#include <vector>

#include "hof/collision/aabb_tree.h"
#include "hof/collision/body_contacts.h"
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

enum class Placement { kOverlapping, kApart };

void bm_detect(benchmark::State& state, const mesh::TriMesh& m, Placement placement, bool continuous) {
  Vec3 lo = Vec3::Constant(std::numeric_limits<double>::infinity());
  Vec3 hi = -lo;
  for (const Vec3& v : m.vertices) {
    lo = lo.cwiseMin(v);
    hi = hi.cwiseMax(v);
  }
  const double width = hi.x() - lo.x();
  const Vec3 shift(placement == Placement::kOverlapping ? 0.85 * width : 2.0 * width, 0.0, 0.01);
  // Poses: [0] and [1] of each body, 1 mm apart along z and toward each other.
  std::vector<Vec3> a[2] = {m.vertices, m.vertices};
  std::vector<Vec3> b[2] = {m.vertices, m.vertices};
  for (std::size_t k = 0; k < m.vertices.size(); ++k) {
    a[1][k] += Vec3(0.0005, 0.0, 0.001);
    b[0][k] += shift;
    b[1][k] += shift - Vec3(0.0005, 0.0, 0.001);
  }
  std::vector<collision::CollisionBody> bodies(2);
  bodies[0].surface = {a[0], m.triangles};
  bodies[1].surface = {b[0], m.triangles};
  ContactDetector detector;
  detector.reset(bodies);
  std::vector<BodyContact> contacts;
  contacts.reserve(1 << 16);
  int pose = 0;
  for (auto _ : state) {
    const int previous = pose;
    pose = 1 - pose;
    bodies[0].surface.vertices = a[pose];
    bodies[1].surface.vertices = b[pose];
    if (continuous) {
      bodies[0].previous_vertices = a[previous];
      bodies[1].previous_vertices = b[previous];
    }
    detector.detect(bodies, DetectionSettings{0.002}, contacts);
    benchmark::DoNotOptimize(contacts.data());
  }
  state.counters["triangles"] = static_cast<double>(2 * m.triangles.size());
  state.counters["contacts"] = static_cast<double>(contacts.size());
}

void register_all() {
  const LiverResolution resolutions[] = {LiverResolution::kSimple, LiverResolution::kCoarse, LiverResolution::kMedium,
                                         LiverResolution::kFine};
  const std::pair<Query, const char*> queries[] = {{Query::kClosestPoint, "closest_point"},
                                                   {Query::kSegment, "first_hit_segment"},
                                                   {Query::kSweptSphere, "first_hit_swept_sphere"}};
  static const mesh::TriMesh sphere_liver = mesh::make_liver_surface(10);  // 2,000 triangles
  for (const bool continuous : {false, true}) {
    const std::string mode = continuous ? "/continuous" : "/discrete";
    benchmark::RegisterBenchmark(("detect/liver2000/overlapping" + mode).c_str(), bm_detect, sphere_liver,
                                 Placement::kOverlapping, continuous)
        ->Unit(benchmark::kMicrosecond);
    benchmark::RegisterBenchmark(("detect/medium/overlapping" + mode).c_str(), bm_detect,
                                 surface(LiverResolution::kMedium), Placement::kOverlapping, continuous)
        ->Unit(benchmark::kMicrosecond);
  }
  benchmark::RegisterBenchmark("detect/liver2000/apart/discrete", bm_detect, sphere_liver, Placement::kApart, false)
      ->Unit(benchmark::kMicrosecond);
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
