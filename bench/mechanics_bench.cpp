// Mechanics step time: every force field × ODE solver on the four standard livers, implicit
// Euler with the sparse direct solver (CHOLMOD) on three of them, SOFA's
// liver demo with its own settings, and hexahedral FEM on sparse grids of the medium liver. Run:
// build/release/bin/hof_bench_mechanics (filter with --benchmark_filter=REGEX; threads with HOF_THREADS, default all
// cores).
//
// Settings: liver material E = 30 kPa (ex vivo indentation range, literature.md §6; the softer
// in vivo 5.4 kPa makes linear `small` elements invert under gravity), ν = 0.45, density
// 1060 kg/m³, gravity, three fixed nodes; springs 5000 N/m, 25 N·s/m (the thesis); implicit
// Euler with Rayleigh 0.1/0.1 and CG with 25 iterations (the reference
// configuration); explicit solvers at a step they are stable at (1e-5 s, springs 1e-7 s);
// the static solver does one Newton iteration per step.

#include <benchmark/benchmark.h>
#include <fmt/format.h>

#include <array>
#include <cstdio>
#include <cstdlib>
#include <map>
#include <string>

#include "hof/mechanics/detail/linear_solve.h"
#include "hof/mechanics/step.h"
#include "hof/mesh/boundary.h"
#include "hof/mesh/hex_grid.h"
#include "hof/mesh/liver_generator.h"
#include "hof/mesh/mesh_io.h"

namespace {

using namespace hof;
using namespace hof::mechanics;

int thread_count() {
  const char* env = std::getenv("HOF_THREADS");
  return env ? std::atoi(env) : 0;
}

const mesh::Mesh& liver(mesh::LiverResolution r) {
  static std::map<mesh::LiverResolution, mesh::Mesh> cache;
  auto it = cache.find(r);
  if (it == cache.end()) {
    auto m = mesh::generate_liver(r);
    if (!m) {
      std::fprintf(stderr, "%s\n", m.error().to_string().c_str());
      std::exit(1);
    }
    it = cache.emplace(r, std::move(*m)).first;
  }
  return it->second;
}

enum class Field { kSprings, kSmall, kLarge, kPolar, kNeoHookean };

ForceFieldConfig field_config(Field f) {
  ForceFieldConfig c;
  c.name = "tissue";
  switch (f) {
    case Field::kSprings:
      c.mesh_springs = MeshSpringConfig{5000.0, 25.0, 1.0};
      break;  // the thesis' settings
    case Field::kSmall:
      c.tetrahedron_fem = TetrahedronFemConfig{30000.0, 0.45, FemMethod::kSmall, {}, {}};
      break;
    case Field::kLarge:
      c.tetrahedron_fem = TetrahedronFemConfig{30000.0, 0.45, FemMethod::kLarge, {}, {}};
      break;
    case Field::kPolar:
      c.tetrahedron_fem = TetrahedronFemConfig{30000.0, 0.45, FemMethod::kPolar, {}, {}};
      break;
    case Field::kNeoHookean:
      c.neo_hookean = NeoHookeanConfig{30000.0, 0.45, {}, {}};
      break;
  }
  return c;
}

ModelConfig liver_config(const mesh::Mesh& m, Field field, OdeSolverKind solver) {
  ModelConfig c;
  c.name = "liver";
  c.positions = m.nodes;
  c.tets = m.tets;
  c.mass.kind = MassKind::kDiagonal;
  c.mass.mass_density_kg_per_m3 = 1060.0;
  c.gravity_m_per_s2 = Vec3(0, 0, -9.81);
  c.force_fields.push_back(field_config(field));
  // Three nodes of the top surface hold the liver.
  std::vector<std::int32_t> top;
  for (const Vec3& target : {Vec3(0.06, 0.0, 0.1), Vec3(0.0, 0.04, 0.1), Vec3(-0.03, -0.03, 0.1)}) {
    std::int32_t best = 0;
    for (std::size_t i = 0; i < m.nodes.size(); ++i) {
      if ((m.nodes[i] - target).norm() < (m.nodes[best] - target).norm()) best = static_cast<std::int32_t>(i);
    }
    top.push_back(best);
  }
  c.fixed.push_back(FixedConstraintConfig{"fixed", top, std::nullopt, false, {true, true, true}});
  c.ode.kind = solver;
  c.ode.rayleigh_mass = c.ode.rayleigh_stiffness = 0.1;
  c.ode.newton_iterations = 1;
  c.linear.iterations = 25;
  c.linear.tolerance = 1e-12;
  c.linear.threshold = 1e-12;
  const bool explicit_solver = solver == OdeSolverKind::kEulerExplicit || solver == OdeSolverKind::kRungeKutta4;
  // Spring damping (25 N·s/m on node masses of ~0.1 g) bounds the explicit step near 1e-6 s.
  c.dt_s = explicit_solver ? (field == Field::kSprings ? 1e-7 : 1e-5) : 0.02;
  c.threads = thread_count();
  return c;
}

void run_steps(benchmark::State& bench, const ModelConfig& config) {
  auto model = build_model(config);
  if (!model) {
    bench.SkipWithError(model.error().to_string().c_str());
    return;
  }
  MechanicalState state = make_state(*model);
  double force = 0, assembly = 0, solve = 0;
  for (auto _ : bench) {
    if (!step(*model, state)) {
      bench.SkipWithError(state.divergence.reason.c_str());
      break;
    }
    force += state.stats.force_s;
    assembly += state.stats.assembly_s;
    solve += state.stats.solve_s;
  }
  const auto n = static_cast<double>(bench.iterations());
  bench.counters["steps_per_s"] = benchmark::Counter(n, benchmark::Counter::kIsRate);
  bench.counters["force_us"] = 1e6 * force / n;
  bench.counters["assembly_us"] = 1e6 * assembly / n;
  bench.counters["solve_us"] = 1e6 * solve / n;
  bench.counters["tets"] = static_cast<double>(model->tets.size());
}

void BM_Liver(benchmark::State& bench, mesh::LiverResolution r, Field field, OdeSolverKind solver) {
  run_steps(bench, liver_config(liver(r), field, solver));
}

// SOFA's liver.scn: 181 nodes / 596 tets, dt 0.02, gravity −9.81 y, implicit Euler with
// Rayleigh 0.1/0.1, CG 25 iterations tolerance and threshold 1e-9, co-rotational FEM
// (large) E 3000 ν 0.3, DiagonalMass density 1, fixed 3 39 64 — its own units.
void BM_SofaLiverScn(benchmark::State& bench) {
  auto read = mesh::read_mesh(HOF_ANCHORS_DIR "/sofa/mesh/liver.msh");
  if (!read) {
    bench.SkipWithError(read.error().to_string().c_str());
    return;
  }
  ModelConfig c;
  c.positions = read->mesh.nodes;
  c.tets = read->mesh.tets;
  c.mass.kind = MassKind::kDiagonal;
  c.mass.mass_density_kg_per_m3 = 1.0;
  ForceFieldConfig fem;
  fem.name = "FEM";
  fem.tetrahedron_fem = TetrahedronFemConfig{3000.0, 0.3, FemMethod::kLarge, {}, {}};
  c.force_fields.push_back(fem);
  c.fixed.push_back(FixedConstraintConfig{"fixed", {3, 39, 64}, std::nullopt, false, {true, true, true}});
  c.ode.rayleigh_mass = c.ode.rayleigh_stiffness = 0.1;
  c.linear.iterations = 25;
  c.linear.tolerance = c.linear.threshold = 1e-9;
  c.dt_s = 0.02;
  c.threads = thread_count();
  run_steps(bench, c);
}

// Hexahedral FEM (HexahedronFEMForceField, large) on a sparse grid voxelising the medium
// liver's surface (SOFA's SparseGridTopology), with the tetrahedral benchmarks' material,
// mass, gravity, solver and three held nodes (the grid nodes nearest the same points). `n` is
// SOFA's nodes per axis: 24×16×10 gives cells of about 1 cm, 16³ SOFA's usual cubic `n`.
void BM_SparseGridLiver(benchmark::State& bench, std::array<int, 3> n) {
  const mesh::Mesh& m = liver(mesh::LiverResolution::kMedium);
  auto grid = mesh::sparse_grid(mesh::extract_boundary(m.nodes, m.tets).surface, n);
  if (!grid) {
    bench.SkipWithError(grid.error().to_string().c_str());
    return;
  }
  ModelConfig c = liver_config(m, Field::kLarge, OdeSolverKind::kEulerImplicit);
  c.positions = grid->nodes;
  c.tets.clear();
  c.hexahedra = grid->hexes;
  c.force_fields[0].tetrahedron_fem.reset();
  c.force_fields[0].hexahedron_fem = HexahedronFemConfig{};
  c.force_fields[0].hexahedron_fem->young_modulus_pa = 30000.0;
  c.force_fields[0].hexahedron_fem->poisson_ratio = 0.45;
  c.force_fields[0].hexahedron_fem->method = FemMethod::kLarge;
  for (std::int32_t& held : c.fixed[0].indices) {
    const Vec3 target = m.nodes[static_cast<std::size_t>(held)];
    std::int32_t best = 0;
    for (std::size_t i = 0; i < grid->nodes.size(); ++i) {
      if ((grid->nodes[i] - target).norm() < (grid->nodes[static_cast<std::size_t>(best)] - target).norm()) {
        best = static_cast<std::int32_t>(i);
      }
    }
    held = best;
  }
  run_steps(bench, c);
  bench.counters["nodes"] = static_cast<double>(grid->nodes.size());
  bench.counters["hexes"] = static_cast<double>(grid->hexes.size());
}

// Membrane FEM (TriangleFEMForceField, large) on the medium liver's surface alone (its 1,692
// boundary vertices, 3,380 triangles): a hollow liver, 1 mm thick, with the same E, ν, solver
// and three held nodes (the surface vertices nearest the same points); mass 1060 kg/m³ × 1 mm
// per area. Beside the volume models, what a surface model costs.
void BM_MembraneLiver(benchmark::State& bench) {
  const mesh::Mesh& m = liver(mesh::LiverResolution::kMedium);
  const mesh::BoundarySurface b = mesh::extract_boundary(m.nodes, m.tets);
  ModelConfig c = liver_config(m, Field::kLarge, OdeSolverKind::kEulerImplicit);
  c.positions = b.surface.vertices;
  c.tets.clear();
  c.triangles = b.surface.triangles;
  c.mass.mass_density_kg_per_m3 = 1060.0 * 0.001;
  c.force_fields[0].tetrahedron_fem.reset();
  TriangleFemConfig fem;
  fem.young_modulus_pa = 30000.0;
  fem.poisson_ratio = 0.45;
  fem.thickness_m = 0.001;
  c.force_fields[0].triangle_fem = fem;
  for (std::int32_t& held : c.fixed[0].indices) {
    const Vec3 target = m.nodes[static_cast<std::size_t>(held)];
    std::int32_t best = 0;
    for (std::size_t i = 0; i < c.positions.size(); ++i) {
      if ((c.positions[i] - target).norm() < (c.positions[static_cast<std::size_t>(best)] - target).norm())
        best = static_cast<std::int32_t>(i);
    }
    held = best;
  }
  run_steps(bench, c);
  bench.counters["nodes"] = static_cast<double>(c.positions.size());
  bench.counters["triangles"] = static_cast<double>(c.triangles.size());
}

// The haptic rate (issue 17): co-rotational FEM at dt = 1 ms, CG with `iterations` from zero
// or warm-started from the last step's solution (tests/mechanics/haptic_rate_fem_test.cpp
// holds the warm start's error to that of 25 iterations from zero).
void BM_HapticRateLiver(benchmark::State& bench, mesh::LiverResolution r, int iterations, bool warm_start) {
  ModelConfig c = liver_config(liver(r), Field::kLarge, OdeSolverKind::kEulerImplicit);
  c.dt_s = 1e-3;
  if (warm_start) {
    use_haptic_rate_solver(c.linear, c.ode, c.positions.size());
  } else {
    c.linear.iterations = iterations;
  }
  run_steps(bench, c);
}

// Implicit Euler with the sparse direct solver (issue 35): solve_us is the factorisation of
// the step's A = (1 + hα)M + h(h + β)K and the solve with it (h = dt, α/β Rayleigh), the
// pattern analysed once when the state was made.
void BM_LiverDirect(benchmark::State& bench, mesh::LiverResolution r) {
  ModelConfig c = liver_config(liver(r), Field::kLarge, OdeSolverKind::kEulerImplicit);
  c.linear.kind = LinearSolverKind::kSparseLdlt;
  run_steps(bench, c);
  // The factor's size and cost, from the symbolic analysis alone.
  auto model = build_model(c);
  if (!model) return;
  const detail::DirectSolverInfo info = detail::direct_solver_info(make_state(*model));
  bench.counters["L_nonzeros"] = info.factor_nonzeros;
  bench.counters["factor_Mflop"] = 1e-6 * info.factor_flops;
  bench.counters["supernodal"] = info.supernodal ? 1.0 : 0.0;
  bench.counters["ordering"] = static_cast<double>(info.ordering);
}

void register_all() {
  using R = mesh::LiverResolution;
  const std::pair<Field, const char*> fields[] = {{Field::kSprings, "MeshSprings"},
                                                  {Field::kSmall, "FEMSmall"},
                                                  {Field::kLarge, "FEMLarge"},
                                                  {Field::kPolar, "FEMPolar"},
                                                  {Field::kNeoHookean, "NeoHookean"}};
  const std::pair<OdeSolverKind, const char*> solvers[] = {{OdeSolverKind::kEulerImplicit, "ImplicitCG25"},
                                                           {OdeSolverKind::kEulerExplicit, "SymplecticEuler"},
                                                           {OdeSolverKind::kRungeKutta4, "RK4"},
                                                           {OdeSolverKind::kStatic, "StaticNewton1"}};
  for (R r : {R::kSimple, R::kCoarse, R::kMedium, R::kFine}) {
    for (const auto& [field, field_name] : fields) {
      for (const auto& [solver, solver_name] : solvers) {
        const std::string name =
            std::string("Liver/") + std::string(mesh::to_string(r)) + "/" + field_name + "/" + solver_name;
        benchmark::RegisterBenchmark(name.c_str(), BM_Liver, r, field, solver)
            ->Unit(benchmark::kMicrosecond)
            ->MinTime(0.3);
      }
    }
  }
  for (R r : {R::kSimple, R::kMedium, R::kFine}) {
    for (const auto& [iterations, warm] : {std::pair{25, false}, std::pair{kHapticRateCgIterations, true}}) {
      const std::string name = fmt::format("HapticRate/{}/FEMLarge/dt1ms/CG{}{}", mesh::to_string(r), iterations,
                                           warm ? "WarmTwoLevel" : "");
      benchmark::RegisterBenchmark(name.c_str(), BM_HapticRateLiver, r, iterations, warm)
          ->Unit(benchmark::kMicrosecond)
          ->MinTime(0.5);
    }
  }
  for (R r : {R::kCoarse, R::kMedium, R::kFine}) {
    const std::string name = fmt::format("Liver/{}/FEMLarge/ImplicitLDLT", mesh::to_string(r));
    benchmark::RegisterBenchmark(name.c_str(), BM_LiverDirect, r)->Unit(benchmark::kMillisecond)->MinTime(1.0);
  }
  benchmark::RegisterBenchmark("SofaLiverScn/FEMLarge/ImplicitCG25", BM_SofaLiverScn)
      ->Unit(benchmark::kMicrosecond)
      ->MinTime(0.5);
  benchmark::RegisterBenchmark("SparseGridLiver/medium/n24x16x10/HexFEMLarge/ImplicitCG25", BM_SparseGridLiver,
                               std::array<int, 3>{24, 16, 10})
      ->Unit(benchmark::kMicrosecond)
      ->MinTime(0.5);
  benchmark::RegisterBenchmark("SparseGridLiver/medium/n16/HexFEMLarge/ImplicitCG25", BM_SparseGridLiver,
                               std::array<int, 3>{16, 16, 16})
      ->Unit(benchmark::kMicrosecond)
      ->MinTime(0.5);
  benchmark::RegisterBenchmark("MembraneLiver/medium/TriangleFEMLarge/ImplicitCG25", BM_MembraneLiver)
      ->Unit(benchmark::kMicrosecond)
      ->MinTime(0.5);
}

}  // namespace

int main(int argc, char** argv) {
  register_all();
  benchmark::Initialize(&argc, argv);
  benchmark::RunSpecifiedBenchmarks();
  benchmark::Shutdown();
  return 0;
}
