#include "hof/app/evaluation.h"

#include <fmt/format.h>
#include <sys/utsname.h>

#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <ctime>
#include <fstream>
#include <functional>
#include <numbers>
#include <limits>
#include <map>
#include <memory>
#include <optional>
#include <nlohmann/json.hpp>
#include <regex>
#include <thread>
#include <vector>

#include "hof/app/detail/cli_failure.h"
#include "hof/app/detail/plots.h"
#include "hof/app/gui/gui_app.h"
#include "hof/core/file_write.h"
#include "hof/core/progress.h"
#include "hof/coupling/session.h"
#include "hof/haptics/device_backends/scripted_device.h"
#include "hof/haptics/haptic_renderer.h"
#include "hof/haptics/surface_snapshot.h"
#include "hof/mechanics/step.h"
#include "hof/mesh/boundary.h"
#include "hof/mesh/hex_grid.h"
#include "hof/mesh/liver_generator.h"
#include "hof/mesh/mesh_io.h"

namespace hof::app {
namespace {

using namespace hof::mechanics;
using mesh::LiverResolution;
using Clock = std::chrono::steady_clock;

constexpr double kNaN = std::numeric_limits<double>::quiet_NaN();

// How long each cell is measured. Full: five batches of at least 0.2 s (the median of five
// is robust to one descheduled batch on a loaded machine), stability over 1 s of simulated
// time (the thesis' runs went on until the liver rested, l. 1260), three error samples.
struct Budget {
  int batches;
  double batch_s;
  double horizon_s;         // simulated time a cell must survive to count as stable
  double stability_wall_s;  // ... unless checking it would take longer than this
  int error_samples;
  int steps_between_samples;
};

Budget budget_for(bool quick) { return quick ? Budget{3, 0.02, 0.1, 0.3, 2, 5} : Budget{5, 0.2, 1.0, 4.0, 3, 10}; }

// One measurement of the matrix. Fields that do not apply stay NaN / empty.
struct Cell {
  std::string section, name;
  std::string mesh, field, settings, solver;
  double dt_s{kNaN};
  int iterations{0};
  bool warm_start{false};
  bool coarse_correction{false};  // the CG's two-level preconditioner
  int matrix_reuse{1};  // implicit Euler: steps one assembled matrix serves
  int threads{0};
  std::size_t nodes{0}, elements{0}, triangles{0};
  double median{kNaN}, min{kNaN}, max{kNaN};  // steps/s
  long steps{0};
  bool measured{false};
  bool stable{true};
  double stable_over_s{0.0};  // simulated time it ran without diverging
  std::string failure;
  double step_error{kNaN};  // relative, against an exact LDLᵀ solve of the same step
  double forces_us{kNaN}, assembly_us{kNaN}, solve_us{kNaN};
  // Haptic renderers: the cost of one tick (µs) and the share of ticks in contact.
  std::string renderer;
  bool bound_tree{true};
  double tick_p50_us{kNaN}, tick_p99_us{kNaN}, tick_max_us{kNaN};
  double contact_fraction{kNaN};
  // The whole framework in real time: the simulation's rates in the thesis' three states
  // (steps/s of wall time), and how much simulated time the wall time held.
  double rate_untouched{kNaN}, rate_deforming{kNaN}, rate_contact{kNaN};
  double simulated_s{kNaN}, wall_s{kNaN};
  double frames_per_s{kNaN};  // with the window open
  int bodies{0};              // livers in the world
  // Coupling schemes: the felt force's largest relative error against the static FEM
  // reaction over the press's depths.
  double force_error{kNaN};
  double force_error_settled{kNaN};  // at the deepest point, after the hold
};

// ---------------------------------------------------------------------------------------
// Bodies: the four standard livers, and a hexahedral sparse grid over the medium one.

struct Body {
  std::string name;
  std::vector<Vec3> nodes;
  std::vector<mesh::Tet> tets;
  std::vector<mesh::Hex> hexes;
  std::size_t surface_triangles{0};
  mesh::TriMesh surface;
};

class Bodies {
 public:
  Expected<const Body*> liver(LiverResolution r) {
    const std::string name(mesh::to_string(r));
    if (auto it = bodies_.find(name); it != bodies_.end()) return &it->second;
    auto m = mesh::generate_liver(r);
    if (!m) return std::unexpected(m.error());
    mesh::TriMesh surface = mesh::extract_boundary(m->nodes, m->tets).surface;
    Body b{name, m->nodes, m->tets, {}, surface.triangles.size(), surface};
    return &bodies_.emplace(name, std::move(b)).first->second;
  }
  // SOFA's SparseGridTopology over the medium liver's surface, 24×16×10 nodes: cells of about 1 cm.
  Expected<const Body*> sparse_grid() {
    const std::string name = "sparse-grid";
    if (auto it = bodies_.find(name); it != bodies_.end()) return &it->second;
    auto medium = liver(LiverResolution::kMedium);
    if (!medium) return std::unexpected(medium.error());
    auto grid = mesh::sparse_grid(mesh::extract_boundary((*medium)->nodes, (*medium)->tets).surface, {24, 16, 10});
    if (!grid) return std::unexpected(grid.error());
    mesh::TriMesh surface = mesh::hex_boundary(grid->nodes, grid->hexes).surface;
    Body b{name, grid->nodes, {}, grid->hexes, surface.triangles.size(), surface};
    return &bodies_.emplace(name, std::move(b)).first->second;
  }
  Expected<const Body*> by_name(const std::string& name) {
    if (name == "sparse-grid") return sparse_grid();
    return liver(*mesh::parse_liver_resolution(name));
  }

 private:
  std::map<std::string, Body> bodies_;
};

// ---------------------------------------------------------------------------------------
// Model settings.

enum class Field { kSprings, kSmall, kLarge, kNeoHookean, kHexahedra };
enum class Settings { kThesis, kPhysiological };

const char* field_name(Field f) {
  switch (f) {
    case Field::kSprings: return "springs";
    case Field::kSmall: return "linear-fem";
    case Field::kLarge: return "corotational-fem";
    case Field::kNeoHookean: return "neo-hookean";
    case Field::kHexahedra: return "hexahedral-fem";
  }
  return "?";
}

const char* settings_name(Settings s) { return s == Settings::kThesis ? "thesis" : "physiological"; }

enum class Solver { kExplicitEuler, kSymplecticEuler, kRungeKutta4, kStatic, kImplicitCg, kImplicitLdlt };

const char* solver_name(Solver s) {
  switch (s) {
    case Solver::kExplicitEuler: return "explicit-euler";
    case Solver::kSymplecticEuler: return "symplectic-euler";
    case Solver::kRungeKutta4: return "rk4";
    case Solver::kStatic: return "static-cg";
    case Solver::kImplicitCg: return "implicit-cg";
    case Solver::kImplicitLdlt: return "implicit-ldlt";
  }
  return "?";
}

// The thesis' settings (l. 1254, 1271): gravity 9.8, total mass 1 kg, mesh springs 10,000 /
// 15, FEM E = 100, ν = 0.4, in SOFA's unit-free scenes. The physiological ones: liver
// E ≈ 5 kPa, ν ≈ 0.45, 1060 kg/m³ (literature.md §6). Our livers are in metres with z up, so
// gravity points along −z (the thesis' liver was y-up). Both rest on their lowest 4 mm (a
// table under the organ), which keeps every model's motion bounded under gravity.
ModelConfig body_config(const Body& b, Field field, Settings s) {
  ModelConfig c;
  c.name = "liver";
  c.positions = b.nodes;
  c.tets = b.tets;
  c.hexahedra = b.hexes;
  const bool thesis = s == Settings::kThesis;
  if (thesis) {
    c.mass.kind = MassKind::kUniform;
    c.mass.total_mass_kg = 1.0;
  } else {
    c.mass.kind = MassKind::kDiagonal;
    c.mass.mass_density_kg_per_m3 = 1060.0;
  }
  c.gravity_m_per_s2 = Vec3(0, 0, thesis ? -9.8 : -9.81);
  const double young = thesis ? 100.0 : 5000.0;
  const double poisson = thesis ? 0.4 : 0.45;
  ForceFieldConfig f;
  f.name = field_name(field);
  switch (field) {
    case Field::kSprings: {
      double stiffness = 10000.0, damping = 15.0;
      if (!thesis) {
        // Springs have no Young's modulus; a spring over an edge of length l standing for a
        // rod of section l² gives k ≈ E·l (a dimensional estimate, not a fitted law), with
        // the thesis' damping ratio to stiffness kept.
        double length = 0.0;
        for (const mesh::Tet& t : b.tets) length += (b.nodes[static_cast<std::size_t>(t[0])] - b.nodes[static_cast<std::size_t>(t[1])]).norm();
        stiffness = young * length / static_cast<double>(std::max<std::size_t>(b.tets.size(), 1));
        damping = 15.0 * stiffness / 10000.0;
      }
      f.mesh_springs = MeshSpringConfig{stiffness, damping, 1.0};
      break;
    }
    case Field::kSmall: f.tetrahedron_fem = TetrahedronFemConfig{young, poisson, FemMethod::kSmall, {}, {}}; break;
    case Field::kLarge: f.tetrahedron_fem = TetrahedronFemConfig{young, poisson, FemMethod::kLarge, {}, {}}; break;
    case Field::kNeoHookean: f.neo_hookean = NeoHookeanConfig{young, poisson, {}, {}}; break;
    case Field::kHexahedra: {
      HexahedronFemConfig h;
      h.young_modulus_pa = young;
      h.poisson_ratio = poisson;
      h.method = FemMethod::kLarge;
      f.hexahedron_fem = h;
      break;
    }
  }
  c.force_fields.push_back(f);
  double lowest = std::numeric_limits<double>::infinity();
  for (const Vec3& p : b.nodes) lowest = std::min(lowest, p.z());
  FixedConstraintConfig fixed;
  fixed.name = "table";
  for (std::size_t i = 0; i < b.nodes.size(); ++i) {
    if (b.nodes[i].z() < lowest + 0.004) fixed.indices.push_back(static_cast<std::int32_t>(i));
  }
  c.fixed.push_back(fixed);
  c.ode.rayleigh_mass = c.ode.rayleigh_stiffness = 0.1;
  c.ode.newton_iterations = 1;
  c.linear.iterations = 25;
  // The iteration count is what is measured: no early stop on the residual.
  c.linear.tolerance = c.linear.threshold = 1e-12;
  c.dt_s = 0.02;
  c.threads = 0;
  return c;
}

void set_solver(ModelConfig& c, Solver s, double dt_s) {
  c.dt_s = dt_s;
  switch (s) {
    case Solver::kExplicitEuler: c.ode.kind = OdeSolverKind::kEulerExplicit; c.ode.symplectic = false; break;
    case Solver::kSymplecticEuler: c.ode.kind = OdeSolverKind::kEulerExplicit; c.ode.symplectic = true; break;
    case Solver::kRungeKutta4: c.ode.kind = OdeSolverKind::kRungeKutta4; break;
    case Solver::kStatic:
      // Every step makes its Newton iteration, as SOFA's StaticSolver with a fixed count
      // does: a step skipped because the residual is already small would time nothing.
      c.ode.kind = OdeSolverKind::kStatic;
      c.ode.newton_residual_tolerance_n = 0.0;
      break;
    case Solver::kImplicitCg: c.ode.kind = OdeSolverKind::kEulerImplicit; break;
    case Solver::kImplicitLdlt:
      c.ode.kind = OdeSolverKind::kEulerImplicit;
      c.linear.kind = LinearSolverKind::kSparseLdlt;
      break;
  }
}

// The haptic-rate CG: few warm-started iterations, the matrix assembled every few steps.
// The haptic-rate cells' name: warm-started two-level CG (use_haptic_rate_solver).
constexpr const char* kHapticRateCell = "two-level-warm";

void use_haptic_rate_cg(ModelConfig& c) { use_haptic_rate_solver(c.linear, c.ode, c.positions.size()); }

// The physiological co-rotational liver with implicit Euler + CG at dt: most of the matrix
// past the thesis' own figures. Gravity off where the organ is pressed (carried by the tissue
// around it, as in the example scenes).
struct CorotationalSetup {
  double dt_s;
  int iterations{25};
  bool haptic_rate_cg{false};
  bool gravity{true};
};

ModelConfig corotational_config(const Body& b, const CorotationalSetup& s) {
  ModelConfig config = body_config(b, Field::kLarge, Settings::kPhysiological);
  set_solver(config, Solver::kImplicitCg, s.dt_s);
  config.linear.iterations = s.iterations;
  if (s.haptic_rate_cg) use_haptic_rate_cg(config);
  if (!s.gravity) config.gravity_m_per_s2 = Vec3::Zero();
  return config;
}

// ---------------------------------------------------------------------------------------
// Measuring a cell.

double seconds_since(Clock::time_point t0) { return std::chrono::duration<double>(Clock::now() - t0).count(); }

// A step that diverged, or a node more than 1 m from where it started (a liver is 0.2 m: it
// has left the scene even if every number is still finite).
bool checked_step(const MechanicalModel& model, MechanicalState& state, const Eigen::VectorXd& start, Cell& cell) {
  if (!step(model, state)) {
    cell.failure = fmt::format("{}: {}", state.divergence.component, state.divergence.reason);
    return false;
  }
  if ((state.x - start).cwiseAbs().maxCoeff() > 1.0) {
    cell.failure = fmt::format("a node moved more than 1 m at step {}", state.steps);
    return false;
  }
  return true;
}

void time_cell(const ModelConfig& config, const Budget& budget, Cell& cell) {
  cell.matrix_reuse = config.ode.matrix_reuse_steps;  // as the model runs (it depends on the mesh)
  if (config.linear.warm_start) cell.iterations = config.linear.iterations;  // the haptic-rate CG's depend on the mesh too
  auto model = build_model(config);
  if (!model) {
    cell.stable = false;
    cell.failure = model.error().to_string();
    return;
  }
  cell.nodes = model->node_count();
  MechanicalState state = make_state(*model);
  const Eigen::VectorXd start = state.x;
  std::vector<double> rates;
  double forces = 0, assembly = 0, solve = 0;
  long timed = 0;
  bool ok = checked_step(*model, state, start, cell) && checked_step(*model, state, start, cell);  // warm-up
  for (int b = 0; ok && b < budget.batches; ++b) {
    const auto t0 = Clock::now();
    long n = 0;
    double elapsed = 0.0;
    do {
      ok = checked_step(*model, state, start, cell);
      if (!ok) break;
      forces += state.stats.force_s;
      assembly += state.stats.assembly_s;
      solve += state.stats.solve_s;
      ++n;
      elapsed = seconds_since(t0);
    } while (elapsed < budget.batch_s);
    // A batch cut short by a divergence still tells how fast the steps ran until then.
    if (n > 0 && elapsed > 0.0) rates.push_back(static_cast<double>(n) / elapsed);
    timed += n;
  }
  const auto t_check = Clock::now();
  while (ok && static_cast<double>(state.steps) * model->dt_s < budget.horizon_s && seconds_since(t_check) < budget.stability_wall_s) {
    ok = checked_step(*model, state, start, cell);
  }
  cell.stable = ok;
  cell.stable_over_s = static_cast<double>(ok ? state.steps : std::max<std::int64_t>(state.steps - 1, 0)) * model->dt_s;
  cell.steps = timed;
  if (!rates.empty()) {
    std::sort(rates.begin(), rates.end());
    cell.median = rates[rates.size() / 2];
    cell.min = rates.front();
    cell.max = rates.back();
    cell.measured = true;
  }
  if (timed > 0) {
    const auto n = static_cast<double>(timed);
    cell.forces_us = 1e6 * forces / n;
    cell.assembly_us = 1e6 * assembly / n;
    cell.solve_us = 1e6 * solve / n;
  }
}

// The largest relative error of a step made by `config` (an iterative solve) against an exact
// LDLᵀ solve of the same step from the same state: |Δ − Δ_exact| / |Δ_exact|, Δ the change of
// velocity (dynamic solvers) or of position (static). The inexact model follows its own
// trajectory, so a warm start has its own history; samples are `steps_between_samples` apart.
double step_error(const ModelConfig& config, const Budget& budget) {
  ModelConfig exact_config = config;
  exact_config.linear.kind = LinearSolverKind::kSparseLdlt;
  // The exact side assembles every step: it is stepped once per sample, so a reused matrix
  // would be one from the previous sample's state.
  exact_config.ode.matrix_reuse_steps = 1;
  auto model = build_model(config);
  auto exact = build_model(exact_config);
  if (!model || !exact) return kNaN;
  MechanicalState state = make_state(*model);
  MechanicalState exact_state = make_state(*exact);
  const bool static_solver = config.ode.kind == OdeSolverKind::kStatic;
  double worst = 0.0;
  for (int s = 0; s < budget.error_samples; ++s) {
    // The static solver's steps are Newton iterations towards one equilibrium: the first
    // ones, from rest, are the solves that matter (later ones correct almost nothing).
    const int between = static_solver ? (s == 0 ? 0 : 1) : budget.steps_between_samples;
    for (int i = 0; i < between; ++i) {
      if (!step(*model, state)) return kNaN;
    }
    const Eigen::VectorXd x0 = state.x, v0 = state.v;
    exact_state.x = x0;
    exact_state.v = v0;
    if (!step(*model, state) || !step(*exact, exact_state)) return kNaN;
    const Eigen::VectorXd d = static_solver ? Eigen::VectorXd(state.x - x0) : Eigen::VectorXd(state.v - v0);
    const Eigen::VectorXd d_exact = static_solver ? Eigen::VectorXd(exact_state.x - x0) : Eigen::VectorXd(exact_state.v - v0);
    const double scale = d_exact.norm();
    if (!(scale > 0.0)) continue;
    worst = std::max(worst, (d - d_exact).norm() / scale);
  }
  return worst;
}

// One haptic tick per device reading, as the haptic loop makes it: the device slides along
// a loop over the liver's top, 3 mm under the surface (a contact every tick), the surface at
// rest (the thesis' useBoundTree test, l. 1221). Each tick is timed alone: p50/p99/max.
void time_renderer(const mesh::TriMesh& surface, haptics::RendererKind kind, bool bound_tree, const Budget& budget, Cell& cell) {
  collision::AabbTreeOptions tree;
  tree.use_bound_tree = bound_tree;
  const haptics::SurfaceSnapshot snapshot = haptics::make_snapshot(surface, tree);
  Vec3 lo = surface.vertices.front(), hi = lo;
  for (const Vec3& p : surface.vertices) {
    lo = lo.cwiseMin(p);
    hi = hi.cwiseMax(p);
  }
  const Vec3 centre = 0.5 * (lo + hi), half = 0.5 * (hi - lo);
  auto top = [&](double x, double y) {
    const collision::SweepHit hit = snapshot.tree.first_hit_segment(snapshot.view(), Vec3(x, y, hi.z() + 1.0), Vec3(x, y, lo.z() - 1.0));
    return hit.triangle >= 0 ? std::optional<double>(hit.point.z()) : std::nullopt;
  };
  constexpr int kPath = 2000;
  std::vector<Vec3> path;
  path.reserve(kPath);
  for (int i = 0; i < kPath; ++i) {
    const double a = 2 * std::numbers::pi * i / kPath;
    const double x = centre.x() + 0.4 * half.x() * std::cos(a), y = centre.y() + 0.4 * half.y() * std::sin(a);
    if (auto z = top(x, y)) path.emplace_back(x, y, *z - 0.003);
  }
  if (path.empty()) {
    cell.stable = false;
    cell.failure = "no point of the surface under the device's path";
    return;
  }
  haptics::RendererConfig config;
  config.kind = kind;
  haptics::SurfaceMaterial material;
  material.stiffness = 1.0;
  haptics::HapticRenderer renderer(config, material, 1000.0);
  renderer.reset(path[0] + Vec3(0, 0, 0.02));  // from above, as a hand arrives
  std::vector<double> ticks;
  ticks.reserve(1 << 20);
  std::size_t contacts = 0;
  const auto t_start = Clock::now();
  const double total_s = budget.batches * budget.batch_s;
  for (std::size_t i = 0; ticks.size() < ticks.capacity() && seconds_since(t_start) < total_s; ++i) {
    const auto t0 = Clock::now();
    const haptics::ContactState& c = renderer.update(path[i % path.size()], Vec3::Zero(), snapshot, false, 1e-3);
    const auto t1 = Clock::now();
    contacts += c.in_contact ? 1 : 0;
    ticks.push_back(std::chrono::duration<double, std::micro>(t1 - t0).count());
  }
  std::sort(ticks.begin(), ticks.end());
  auto quantile = [&](double q) { return ticks[static_cast<std::size_t>(q * static_cast<double>(ticks.size() - 1))]; };
  cell.steps = static_cast<long>(ticks.size());
  cell.tick_p50_us = quantile(0.5);
  cell.tick_p99_us = quantile(0.99);
  cell.tick_max_us = ticks.back();
  cell.contact_fraction = static_cast<double>(contacts) / static_cast<double>(ticks.size());
  cell.measured = true;
}

// The surface vertex every press comes down on: the highest near the middle of the top.
std::size_t pressed_vertex(const Body& b, const mesh::BoundarySurface& boundary) {
  Vec3 lo = b.nodes.front(), hi = lo;
  for (const Vec3& p : b.nodes) {
    lo = lo.cwiseMin(p);
    hi = hi.cwiseMax(p);
  }
  const Eigen::Vector2d middle = 0.5 * (lo + hi).head<2>();
  std::size_t top = 0;
  double best = std::numeric_limits<double>::infinity();
  for (std::size_t i = 0; i < boundary.surface.vertices.size(); ++i) {
    const Vec3& v = boundary.surface.vertices[i];
    const double score = (v.head<2>() - middle).norm() - 0.5 * (v.z() - lo.z());
    if (score < best) {
      best = score;
      top = i;
    }
  }
  return top;
}

// The press of the framework cells: from 1 cm above the point, 8 mm deep at 2 cm/s, held.
haptics::MotionConfig framework_press(const Vec3& top) {
  return haptics::MotionConfig::poke(top + Vec3(0, 0, 0.01), Vec3(0, 0, -1), 0.01, 0.008, 0.02, 10.0);
}

coupling::SessionConfig framework_session_config(coupling::ContactCoupling mode) {
  coupling::SessionConfig config;
  config.coupling = mode;
  config.haptics.rate_hz = 1000.0;
  config.haptics.renderer.kind = haptics::RendererKind::kRuspini;
  config.haptics.material.stiffness = 0.2;
  return config;
}

void fill_framework_cell(const coupling::SessionReport& report, Cell& cell);

// The whole framework (thesis Figure 34): a real-time session, the haptic loop and the
// simulation each on its own thread, a scripted hand pressing the liver's top from 1 cm above
// (contact after about 0.5 s, then held). Its rates, and the haptic period's p50/p99/max.
void time_framework(const Body& b, const ModelConfig& config, coupling::ContactCoupling mode, double seconds, Cell& cell) {
  cell.matrix_reuse = config.ode.matrix_reuse_steps;  // as the model runs (it depends on the mesh)
  const mesh::BoundarySurface boundary = mesh::extract_boundary(b.nodes, b.tets);
  auto model = build_model(config);
  auto mapping = coupling::SurfaceMapping::by_index(b.nodes, boundary.surface.vertices, boundary.surface_to_volume);
  if (!model || !mapping) {
    cell.stable = false;
    cell.failure = !model ? model.error().to_string() : mapping.error().to_string();
    return;
  }
  auto scripted = haptics::ScriptedMotion::make(framework_press(boundary.surface.vertices[pressed_vertex(b, boundary)]));
  if (!scripted) {
    cell.stable = false;
    cell.failure = scripted.error().to_string();
    return;
  }
  auto session = coupling::Session::make(coupling::SessionBody{"liver", std::move(*model), boundary.surface, std::move(*mapping), {}, {}},
                                         std::make_unique<haptics::ScriptedDevice>(*scripted), framework_session_config(mode));
  if (!session) {
    cell.stable = false;
    cell.failure = session.error().to_string();
    return;
  }
  fill_framework_cell((*session)->run_realtime(seconds, {}), cell);
}

void fill_framework_cell(const coupling::SessionReport& report, Cell& cell) {
  cell.stable = !report.diverged;
  cell.failure = report.divergence;
  cell.steps = report.simulation_steps;
  cell.median = cell.min = cell.max = report.simulation_steps_per_s;
  cell.simulated_s = report.simulated_s;
  cell.wall_s = report.wall_s;
  cell.rate_untouched = report.rate_untouched > 0.0 ? report.rate_untouched : kNaN;
  cell.rate_deforming = report.rate_deforming > 0.0 ? report.rate_deforming : kNaN;
  cell.rate_contact = report.rate_in_contact > 0.0 ? report.rate_in_contact : kNaN;
  cell.tick_p50_us = 1e6 * report.haptic_periods.quantile_s(0.5);
  cell.tick_p99_us = 1e6 * report.haptic_periods.quantile_s(0.99);
  cell.tick_max_us = 1e6 * report.haptic_periods.max_s();
  cell.contact_fraction = report.contact_time_s / std::max(report.wall_s, 1e-9);  // haptic ticks keep wall time
  cell.measured = report.simulation_steps > 0;
}

// The framework with the window open (thesis Figure 34 was a window): the haptic-rate press
// of time_framework, written out as a project (the liver as Gmsh, a SOFA scene, a `.hof`
// naming the scripted hand as its device) into DIR/window and opened by `hof gui` in this
// process, which draws it for `seconds` and stops. Needs a display (Xvfb will do).
void time_framework_window(const Body& b, const ModelConfig& config, const std::filesystem::path& dir, double seconds, Cell& cell) {
  cell.matrix_reuse = config.ode.matrix_reuse_steps;  // as the model runs (it depends on the mesh)
  const char* display = std::getenv("DISPLAY");
  if (!display || !*display) {
    cell.failure = "no display: run `xvfb-run -a hof bench` (or from a desktop) to measure the window";
    return;
  }
  const std::filesystem::path at = dir / "window";
  std::error_code ec;
  std::filesystem::create_directories(at, ec);
  mesh::Mesh liver;
  liver.nodes = b.nodes;
  liver.tets = b.tets;
  if (auto w = mesh::write_msh(liver, at / "liver.msh", mesh::MshVersion::k2_2); !w) {
    cell.stable = false;
    cell.failure = w.error().to_string();
    return;
  }
  const TetrahedronFemConfig& fem = *config.force_fields.front().tetrahedron_fem;
  std::string fixed;
  for (const std::int32_t i : config.fixed.front().indices) fixed += fmt::format("{}{}", fixed.empty() ? "" : " ", i);
  const std::string scene = fmt::format(
      "<?xml version=\"1.0\"?>\n<!-- Written by hof bench: the framework cell with the window open. -->\n"
      "<Node name=\"root\" dt=\"{}\" gravity=\"0 0 0\">\n  <Node name=\"Liver\">\n"
      "    <EulerImplicitSolver name=\"solver\" rayleighStiffness=\"{}\" rayleighMass=\"{}\"/>\n"
      "    <CGLinearSolver name=\"cg\" iterations=\"{}\" tolerance=\"1e-12\" threshold=\"1e-12\" warmStart=\"{}\" "
      "coarseCorrection=\"{}\"/>\n"
      "    <MeshGmshLoader name=\"loader\" filename=\"liver.msh\"/>\n    <MeshTopology name=\"topology\" src=\"@loader\"/>\n"
      "    <MechanicalObject name=\"dofs\" src=\"@loader\"/>\n    <DiagonalMass name=\"mass\" massDensity=\"{}\"/>\n"
      "    <TetrahedronFEMForceField name=\"FEM\" youngModulus=\"{}\" poissonRatio=\"{}\" method=\"large\"/>\n"
      "    <FixedProjectiveConstraint name=\"base\" indices=\"{}\"/>\n  </Node>\n</Node>\n",
      config.dt_s, config.ode.rayleigh_stiffness, config.ode.rayleigh_mass, config.linear.iterations,
      config.linear.warm_start ? "true" : "false", config.linear.coarse_correction ? "true" : "false", config.mass.mass_density_kg_per_m3, fem.young_modulus_pa, fem.poisson_ratio, fixed);
  const mesh::BoundarySurface boundary = mesh::extract_boundary(b.nodes, b.tets);
  const haptics::MotionConfig press = framework_press(boundary.surface.vertices[pressed_vertex(b, boundary)]);
  const std::string device = fmt::format("scripted:poke,start={};{};{},direction=0;0;-1,approach={},depth={},speed={},hold={}", press.start_m.x(),
                                         press.start_m.y(), press.start_m.z(), press.approach_m, press.depth_m, press.speed_m_per_s, press.hold_s);
  const std::string project = fmt::format(
      "<?xml version=\"1.0\" encoding=\"UTF-8\"?>\n<hof version=\"1\" name=\"hof bench: the framework with the window open\">\n"
      "  <mechanics scene=\"liver.scn\">\n"
      "    <set body=\"Liver\" component=\"solver\" parameter=\"matrixReuseSteps\" value=\"{}\"/>\n  </mechanics>\n"
      "  <haptics device=\"{}\" hapticRate=\"1000\" renderer=\"RuspiniRenderer\" coupling=\"fem-reaction\">\n"
      "    <surface type=\"SmoothSurface\" stiffness=\"0.2\" damping=\"0\" useRelativeValues=\"true\"/>\n  </haptics>\n</hof>\n",
      config.ode.matrix_reuse_steps, device);
  const std::string script = fmt::format("wait {}\nquit\n", seconds);
  for (const auto& [file, text] : {std::pair{"liver.scn", scene}, std::pair{"liver.hof", project}, std::pair{"script.txt", script}}) {
    if (auto w = write_file_atomically(at / file, text); !w) {
      cell.stable = false;
      cell.failure = w.error().to_string();
      return;
    }
  }
  GuiRunResult result;
  GuiOptions options;
  options.file = at / "liver.hof";
  options.script = at / "script.txt";
  options.quiet = true;
  options.result = &result;
  if (run_gui(options) != 0 || !result.session) {
    cell.stable = false;
    cell.failure = fmt::format("the window did not run the project {} (see the messages above)", options.file->string());
    return;
  }
  fill_framework_cell(*result.session, cell);
  cell.frames_per_s = static_cast<double>(result.frames) / std::max(result.wall_s, 1e-9);
}

// Several bodies (the world of issue 12): one liver against two side by side, 25 cm apart,
// the first pressed, in virtual time so that the rate is the machine's, not the clock's. The
// bodies of a world step in parallel, each with its own threads.
void time_bodies(const Body& b, const ModelConfig& config, int count, double seconds, Cell& cell) {
  cell.matrix_reuse = config.ode.matrix_reuse_steps;  // as the model runs (it depends on the mesh)
  const mesh::BoundarySurface boundary = mesh::extract_boundary(b.nodes, b.tets);
  std::vector<coupling::SessionBody> bodies;
  for (int i = 0; i < count; ++i) {
    const Vec3 offset(0.25 * i, 0.0, 0.0);
    ModelConfig c = config;
    for (Vec3& p : c.positions) p += offset;
    mesh::TriMesh surface = boundary.surface;
    for (Vec3& v : surface.vertices) v += offset;
    auto model = build_model(c);
    auto mapping = coupling::SurfaceMapping::by_index(c.positions, surface.vertices, boundary.surface_to_volume);
    if (!model || !mapping) {
      cell.stable = false;
      cell.failure = !model ? model.error().to_string() : mapping.error().to_string();
      return;
    }
    bodies.push_back(coupling::SessionBody{fmt::format("liver{}", i + 1), std::move(*model), std::move(surface), std::move(*mapping), {}, {}});
  }
  auto scripted = haptics::ScriptedMotion::make(framework_press(boundary.surface.vertices[pressed_vertex(b, boundary)]));
  if (!scripted) {
    cell.stable = false;
    cell.failure = scripted.error().to_string();
    return;
  }
  coupling::SessionConfig session_config = framework_session_config(coupling::ContactCoupling::kBarycentric);
  session_config.haptics.realtime_priority = false;
  auto session = coupling::Session::make(std::move(bodies), std::make_unique<haptics::ScriptedDevice>(*scripted), session_config);
  if (!session) {
    cell.stable = false;
    cell.failure = session.error().to_string();
    return;
  }
  const auto t0 = Clock::now();
  const coupling::SessionReport report = (*session)->run_virtual(seconds, {});
  const double wall = seconds_since(t0);
  cell.stable = !report.diverged;
  cell.failure = report.divergence;
  cell.steps = report.simulation_steps;
  cell.simulated_s = report.simulated_s;
  cell.wall_s = wall;
  cell.median = cell.min = cell.max = static_cast<double>(report.simulation_steps) / std::max(wall, 1e-9);
  cell.contact_fraction = report.contact_time_s / std::max(report.simulated_s, 1e-9);
  cell.measured = report.simulation_steps > 0;
}

// The coupling schemes against the static FEM reaction (the set-up of
// tests/coupling/compliance_test.cpp): a slow press (4 mm at 4 mm/s, then held) straight down
// onto the top's surface node, in virtual time, strongly damped so that the tissue follows
// quasi-statically. At 1, 2, 3 and 4 mm below the rest surface the felt force is compared
// with the static FEM reaction of the node held at that depth (Newton with an exact LDLT
// solve); the cell's error is the largest |felt − reaction| / |reaction|. The contact
// schemes render the proxy's spring (stiffness × penetration of the displaced surface); the
// compliance and fem-reaction schemes render the FEM's own response.
struct CouplingReference {
  std::int32_t node{-1};
  Vec3 top{Vec3::Zero()};
  std::vector<double> depths;
  std::vector<Vec3> reactions;
};

ModelConfig coupling_press_config(const Body& b) {
  ModelConfig c = body_config(b, Field::kLarge, Settings::kPhysiological);
  c.gravity_m_per_s2 = Vec3::Zero();
  c.ode.rayleigh_mass = 1.0;  // strongly damped: the press is quasi-static
  c.ode.rayleigh_stiffness = 0.1;
  c.linear.iterations = 100;
  c.linear.tolerance = c.linear.threshold = 1e-9;
  return c;
}

Expected<CouplingReference> coupling_reference(const Body& b) {
  CouplingReference ref;
  const mesh::BoundarySurface boundary = mesh::extract_boundary(b.nodes, b.tets);
  const std::size_t vertex = pressed_vertex(b, boundary);
  ref.node = boundary.surface_to_volume[vertex];
  ref.top = b.nodes[static_cast<std::size_t>(ref.node)];
  for (const double depth : {0.001, 0.002, 0.003, 0.004}) {
    ModelConfig c = coupling_press_config(b);
    c.fixed.push_back(FixedConstraintConfig{"probe", {ref.node}, std::nullopt, false, {true, true, true}});
    c.ode.kind = OdeSolverKind::kStatic;
    c.ode.newton_iterations = 30;
    c.ode.newton_residual_tolerance_n = 1e-9;
    c.linear.kind = LinearSolverKind::kSparseLdlt;
    auto model = build_model(c);
    if (!model) return std::unexpected(model.error());
    MechanicalState state = make_state(*model);
    state.x.segment<3>(3 * static_cast<Eigen::Index>(ref.node)) = ref.top - Vec3(0, 0, depth);
    if (!step(*model, state)) return make_error(ErrorCode::kInvalidArgument, fmt::format("the static reference at {} mm did not converge", 1e3 * depth));
    Eigen::VectorXd internal = Eigen::VectorXd::Zero(state.x.size());
    model->force_fields[0]->add_force(state.x, state.v, state.field_states[0], internal);
    ref.depths.push_back(depth);
    ref.reactions.push_back(internal.segment<3>(3 * static_cast<Eigen::Index>(ref.node)));
  }
  return ref;
}

void time_coupling(const Body& b, const CouplingReference& ref, coupling::ContactCoupling mode, Cell& cell) {
  const mesh::BoundarySurface boundary = mesh::extract_boundary(b.nodes, b.tets);
  ModelConfig config = coupling_press_config(b);
  if (mode == coupling::ContactCoupling::kFemReaction) {
    config.dt_s = 0.001;
    use_haptic_rate_cg(config);
  }
  cell.matrix_reuse = config.ode.matrix_reuse_steps;
  auto model = build_model(config);
  auto mapping = coupling::SurfaceMapping::by_index(b.nodes, boundary.surface.vertices, boundary.surface_to_volume);
  if (!model || !mapping) {
    cell.stable = false;
    cell.failure = !model ? model.error().to_string() : mapping.error().to_string();
    return;
  }
  // Held 1 s: the run ends 0.6 s into the hold.
  const haptics::MotionConfig motion = haptics::MotionConfig::poke(ref.top + Vec3(0, 0, 0.004), Vec3(0, 0, -1), 0.004, 0.004, 0.004, 1.0);
  auto scripted = haptics::ScriptedMotion::make(motion);
  if (!scripted) {
    cell.stable = false;
    cell.failure = scripted.error().to_string();
    return;
  }
  haptics::DeviceSpec spec;
  spec.max_force_n = 50.0;
  spec.max_stiffness_n_per_m = 2000.0;
  coupling::SessionConfig session_config;
  session_config.coupling = mode;
  session_config.haptics.renderer.kind = haptics::RendererKind::kGodObject;
  session_config.haptics.material.stiffness = 1.0;  // the device's stiffest: 2,000 N/m
  session_config.haptics.safety.fade_in_s = 0.0;
  session_config.haptics.realtime_priority = false;
  auto session = coupling::Session::make(coupling::SessionBody{"liver", std::move(*model), boundary.surface, std::move(*mapping), {}, {}},
                                         std::make_unique<haptics::ScriptedDevice>(*scripted, spec), session_config);
  if (!session) {
    cell.stable = false;
    cell.failure = session.error().to_string();
    return;
  }
  // The samples nearest each reference depth, in contact, after the approach.
  std::vector<haptics::HapticSample> nearest(ref.depths.size());
  std::vector<double> distance(ref.depths.size(), std::numeric_limits<double>::infinity());
  const auto t0 = Clock::now();
  haptics::HapticSample settled;
  bool have_settled = false;
  const coupling::SessionReport report = (*session)->run_virtual(2.6, [&](const haptics::HapticSample& s) {
    if (!s.contact || s.time_s < 0.5) return;
    settled = s;  // the last in contact: 0.6 s into the hold at 4 mm
    have_settled = true;
    for (std::size_t k = 0; k < ref.depths.size(); ++k) {
      const double d = std::abs(ref.top.z() - s.device.z() - ref.depths[k]);
      if (d < distance[k]) {
        distance[k] = d;
        nearest[k] = s;
      }
    }
  });
  const double wall = seconds_since(t0);
  cell.stable = !report.diverged;
  cell.failure = report.divergence;
  cell.steps = report.simulation_steps;
  cell.simulated_s = report.simulated_s;
  cell.wall_s = wall;
  cell.median = cell.min = cell.max = static_cast<double>(report.simulation_steps) / std::max(wall, 1e-9);
  cell.measured = report.simulation_steps > 0;
  double worst = 0.0;
  for (std::size_t k = 0; k < ref.depths.size(); ++k) {
    if (!std::isfinite(distance[k])) {
      cell.failure = fmt::format("no contact at {} mm", 1e3 * ref.depths[k]);
      return;
    }
    worst = std::max(worst, (nearest[k].force - ref.reactions[k]).norm() / std::max(ref.reactions[k].norm(), 1e-12));
  }
  cell.force_error = worst;
  if (have_settled && std::abs(ref.top.z() - settled.device.z() - ref.depths.back()) < 1e-6) {
    cell.force_error_settled = (settled.force - ref.reactions.back()).norm() / std::max(ref.reactions.back().norm(), 1e-12);
  }
}

// ---------------------------------------------------------------------------------------
// The plan: every cell with the code that measures it, filtered by --only before running.

struct PlannedCell {
  Cell cell;
  std::function<void(Cell&)> run;
};

std::string dt_label(double dt) { return fmt::format("dt{:g}", dt); }

// A cell's description for a corotational_config set-up.
Cell corotational_cell(std::string section, std::string name, const std::string& mesh, const CorotationalSetup& s) {
  Cell c;
  c.section = std::move(section);
  c.name = std::move(name);
  c.mesh = mesh;
  c.field = field_name(Field::kLarge);
  c.settings = settings_name(Settings::kPhysiological);
  c.solver = solver_name(Solver::kImplicitCg);
  c.dt_s = s.dt_s;
  c.iterations = s.haptic_rate_cg ? kHapticRateCgIterations : s.iterations;
  c.warm_start = s.haptic_rate_cg;
  c.coarse_correction = s.haptic_rate_cg;
  // iterations (haptic-rate CG) and matrix_reuse: set when the cell runs, from the model.
  return c;
}

std::vector<PlannedCell> plan(bool quick, Bodies& bodies, const std::filesystem::path& out) {
  const Budget budget = budget_for(quick);
  std::vector<PlannedCell> cells;
  const std::vector<std::string> livers =
      quick ? std::vector<std::string>{"simple"} : std::vector<std::string>{"simple", "coarse", "medium", "fine"};

  auto with_body = [&bodies](const std::string& body_name, Cell& cell) -> const Body* {
    auto b = bodies.by_name(body_name);
    if (!b) {
      cell.stable = false;
      cell.failure = b.error().to_string();
      return nullptr;
    }
    cell.nodes = (*b)->nodes.size();
    cell.elements = (*b)->tets.empty() ? (*b)->hexes.size() : (*b)->tets.size();
    cell.triangles = (*b)->surface_triangles;
    return *b;
  };

  // Figure 29: mesh sizes.
  std::vector<std::string> meshes = livers;
  meshes.push_back("sparse-grid");
  for (const std::string& m : meshes) {
    Cell c;
    c.section = "meshes";
    c.name = "meshes/" + m;
    c.mesh = m;
    cells.push_back({c, [with_body, m](Cell& cell) { cell.measured = with_body(m, cell) != nullptr; }});
  }

  // Figure 30: force fields per mesh, implicit Euler + CG 25 at dt 0.02.
  for (Settings s : {Settings::kThesis, Settings::kPhysiological}) {
    for (const std::string& m : meshes) {
      const bool grid = m == "sparse-grid";
      for (Field f : grid ? std::vector<Field>{Field::kHexahedra}
                          : std::vector<Field>{Field::kSprings, Field::kSmall, Field::kLarge, Field::kNeoHookean}) {
        Cell c;
        c.section = "force_fields";
        c.name = fmt::format("force_fields/{}/{}/{}", settings_name(s), m, field_name(f));
        c.mesh = m;
        c.field = field_name(f);
        c.settings = settings_name(s);
        c.solver = solver_name(Solver::kImplicitCg);
        c.dt_s = 0.02;
        c.iterations = 25;
        cells.push_back({c, [with_body, m, f, s, budget](Cell& cell) {
                           const Body* b = with_body(m, cell);
                           if (!b) return;
                           ModelConfig config = body_config(*b, f, s);
                           set_solver(config, Solver::kImplicitCg, 0.02);
                           time_cell(config, budget, cell);
                         }});
      }
    }
  }

  // Figure 31: solvers on the thesis' mesh springs at dt 0.002 and 0.02 (stability marked).
  for (double dt : {0.002, 0.02}) {
    for (const std::string& m : livers) {
      for (Solver sv : {Solver::kExplicitEuler, Solver::kSymplecticEuler, Solver::kRungeKutta4, Solver::kStatic,
                        Solver::kImplicitCg, Solver::kImplicitLdlt}) {
        Cell c;
        c.section = "solvers";
        c.name = fmt::format("solvers/{}/{}/{}", dt_label(dt), m, solver_name(sv));
        c.mesh = m;
        c.field = field_name(Field::kSprings);
        c.settings = settings_name(Settings::kThesis);
        c.solver = solver_name(sv);
        c.dt_s = dt;
        c.iterations = sv == Solver::kImplicitCg || sv == Solver::kStatic ? 25 : 0;
        cells.push_back({c, [with_body, m, sv, dt, budget](Cell& cell) {
                           const Body* b = with_body(m, cell);
                           if (!b) return;
                           ModelConfig config = body_config(*b, Field::kSprings, Settings::kThesis);
                           set_solver(config, sv, dt);
                           time_cell(config, budget, cell);
                         }});
      }
    }
  }

  // Threads (the thesis' OpenMP test, l. 1242): one core against two, co-rotational FEM.
  for (const std::string& m : livers) {
    for (int threads : {1, 2}) {
      const CorotationalSetup setup{0.02};
      Cell c = corotational_cell("threads", fmt::format("threads/{}/corotational-fem/threads{}", m, threads), m, setup);
      c.threads = threads;
      cells.push_back({c, [with_body, m, setup, threads, budget](Cell& cell) {
                         const Body* b = with_body(m, cell);
                         if (!b) return;
                         ModelConfig config = corotational_config(*b, setup);
                         config.threads = threads;
                         time_cell(config, budget, cell);
                       }});
    }
  }

  // Haptic renderers × bound tree × mesh: the cost of a tick.
  for (const std::string& m : livers) {
    for (auto [kind, renderer] : {std::pair{haptics::RendererKind::kGodObject, "god-object"}, std::pair{haptics::RendererKind::kRuspini, "ruspini"},
                                  std::pair{haptics::RendererKind::kPenalty, "penalty"}}) {
      for (bool tree : {true, false}) {
        Cell c;
        c.section = "renderers";
        c.name = fmt::format("renderers/{}/{}/{}", m, renderer, tree ? "bound-tree" : "no-tree");
        c.mesh = m;
        c.renderer = renderer;
        c.bound_tree = tree;
        cells.push_back({c, [with_body, m, kind, tree, budget](Cell& cell) {
                           const Body* b = with_body(m, cell);
                           if (!b) return;
                           time_renderer(b->surface, kind, tree, budget, cell);
                         }});
      }
    }
  }

  // Figures 32–33: CG iterations with the static solver and implicit Euler at dt 0.02, on
  // the thesis' springs and on the physiological co-rotational FEM; error against LDLᵀ.
  const std::string cg_mesh = quick ? "simple" : "medium";
  const std::vector<int> counts = quick ? std::vector<int>{1, 5, 25} : std::vector<int>{1, 2, 3, 5, 7, 10, 15, 20, 25, 30, 40, 50};
  for (Solver sv : {Solver::kStatic, Solver::kImplicitCg}) {
    for (auto [f, s] : {std::pair{Field::kSprings, Settings::kThesis}, std::pair{Field::kLarge, Settings::kPhysiological}}) {
      for (int k : counts) {
        Cell c;
        c.section = "cg_iterations";
        c.name = fmt::format("cg_iterations/{}/{}/{}/{}/cg{}", solver_name(sv), cg_mesh, field_name(f), settings_name(s), k);
        c.mesh = cg_mesh;
        c.field = field_name(f);
        c.settings = settings_name(s);
        c.solver = solver_name(sv);
        c.dt_s = 0.02;
        c.iterations = k;
        cells.push_back({c, [with_body, cg_mesh, sv, f, s, k, budget](Cell& cell) {
                           const Body* b = with_body(cg_mesh, cell);
                           if (!b) return;
                           ModelConfig config = body_config(*b, f, s);
                           set_solver(config, sv, 0.02);
                           config.linear.iterations = k;
                           time_cell(config, budget, cell);
                           if (cell.stable) cell.step_error = step_error(config, budget);
                         }});
      }
    }
  }

  // The haptic rate: co-rotational FEM, physiological, implicit Euler at dt = 1 ms; SOFA's
  // 25 CG iterations from zero against the warm-started haptic-rate CG; 1 and 2 threads.
  const std::vector<std::string> rate_meshes =
      quick ? std::vector<std::string>{"simple"} : std::vector<std::string>{"simple", "medium", "fine"};
  for (const std::string& m : rate_meshes) {
    for (bool warm : {false, true}) {
      for (int threads : {1, 2}) {
        const CorotationalSetup setup{0.001, 25, warm};
        Cell c = corotational_cell("haptic_rate", "", m, setup);
        c.name = fmt::format("haptic_rate/{}/{}/threads{}", m, warm ? std::string(kHapticRateCell) : fmt::format("cg{}", c.iterations), threads);
        c.threads = threads;
        cells.push_back({c, [with_body, m, setup, threads, budget](Cell& cell) {
                           const Body* b = with_body(m, cell);
                           if (!b) return;
                           ModelConfig config = corotational_config(*b, setup);
                           config.threads = threads;
                           time_cell(config, budget, cell);
                           // The error does not depend on the thread count: measured once.
                           if (cell.stable && threads == 1) cell.step_error = step_error(config, budget);
                         }});
      }
    }
  }
  // The whole framework in real time: the thesis' set-up (dt 10 ms, CG 25, the contact force
  // spread over the triangle) and the haptic rate (dt 1 ms, the FEM's reaction felt).
  const double framework_s = quick ? 0.6 : 4.0;
  for (const std::string& m : quick ? std::vector<std::string>{"simple"} : std::vector<std::string>{"simple", "medium", "fine"}) {
    for (bool haptic_rate : {false, true}) {
      const CorotationalSetup setup{haptic_rate ? 0.001 : 0.01, 25, haptic_rate, false};
      Cell c = corotational_cell("framework", fmt::format("framework/{}/{}", m, haptic_rate ? "haptic-rate-fem-reaction" : "dt10ms-barycentric"),
                                 m, setup);
      c.renderer = haptic_rate ? "ruspini, fem-reaction" : "ruspini, barycentric";
      cells.push_back({c, [with_body, m, setup, haptic_rate, framework_s](Cell& cell) {
                         const Body* b = with_body(m, cell);
                         if (!b) return;
                         time_framework(*b, corotational_config(*b, setup),
                                        haptic_rate ? coupling::ContactCoupling::kFemReaction : coupling::ContactCoupling::kBarycentric, framework_s,
                                        cell);
                       }});
    }
  }
  // ... and with the window open, at the haptic rate on the mesh of the real-time goal.
  {
    const std::string m = quick ? "simple" : "medium";
    const CorotationalSetup setup{0.001, 25, true, false};
    Cell c = corotational_cell("framework", fmt::format("framework/{}/haptic-rate-fem-reaction/window", m), m, setup);
    c.renderer = "ruspini, fem-reaction, window";
    cells.push_back({c, [with_body, m, setup, framework_s, out](Cell& cell) {
                       const Body* b = with_body(m, cell);
                       if (!b) return;
                       time_framework_window(*b, corotational_config(*b, setup), out, framework_s, cell);
                     }});
  }

  // Bodies: one liver against two (thesis set-up: dt 10 ms, CG 25), in virtual time.
  {
    const std::string m = quick ? "simple" : "medium";
    const double seconds = quick ? 0.2 : 2.0;
    for (int count : {1, 2}) {
      const CorotationalSetup setup{0.01, 25, false, false};
      Cell c = corotational_cell("bodies", fmt::format("bodies/{}/livers{}", m, count), m, setup);
      c.bodies = count;
      cells.push_back({c, [with_body, m, setup, count, seconds](Cell& cell) {
                         const Body* b = with_body(m, cell);
                         if (!b) return;
                         time_bodies(*b, corotational_config(*b, setup), count, seconds, cell);
                       }});
    }
  }

  // Coupling schemes: the felt force against the static FEM reaction, and the cost. The
  // reference (four static LDLT solves) is computed once per mesh, by the first cell.
  {
    const std::string m = quick ? "simple" : "medium";
    auto reference = std::make_shared<std::optional<Expected<CouplingReference>>>();
    for (auto [mode, label] : {std::pair{coupling::ContactCoupling::kClosestVertex, "closest-vertex"},
                               std::pair{coupling::ContactCoupling::kBarycentric, "barycentric"},
                               std::pair{coupling::ContactCoupling::kCompliance, "compliance"},
                               std::pair{coupling::ContactCoupling::kFemReaction, "fem-reaction"}}) {
      // Described as time_coupling sets it up (coupling_press_config).
      const bool haptic_rate = mode == coupling::ContactCoupling::kFemReaction;
      Cell c = corotational_cell("coupling", fmt::format("coupling/{}/{}", m, label), m,
                                 CorotationalSetup{haptic_rate ? 0.001 : 0.02, 100, haptic_rate, false});
      c.renderer = fmt::format("god-object, {}", label);
      cells.push_back({c, [with_body, m, mode, reference](Cell& cell) {
                         const Body* b = with_body(m, cell);
                         if (!b) return;
                         if (!reference->has_value()) *reference = coupling_reference(*b);
                         if (!**reference) {
                           cell.stable = false;
                           cell.failure = (**reference).error().to_string();
                           return;
                         }
                         time_coupling(*b, ***reference, mode, cell);
                       }});
    }
  }
  return cells;
}

// ---------------------------------------------------------------------------------------
// Derived results: the springs / FEM ratios and the haptic-rate goals.

const Cell* find(const std::vector<Cell>& cells, const std::string& name) {
  for (const Cell& c : cells) {
    if (c.name == name) return &c;
  }
  return nullptr;
}

struct Ratio {
  std::string settings;
  std::string mesh;
  double force_field{kNaN};  // co-rotational FEM cost / springs cost, forces + assembly
  double step{kNaN};         // whole step: springs steps/s / FEM steps/s
};

// Both models must have run stably: a collapsing liver's steps time something else.
std::vector<Ratio> springs_over_fem(const std::vector<Cell>& cells) {
  std::vector<Ratio> out;
  for (const char* s : {"thesis", "physiological"}) {
    for (const char* m : {"simple", "coarse", "medium", "fine"}) {
      const Cell* springs = find(cells, fmt::format("force_fields/{}/{}/springs", s, m));
      const Cell* fem = find(cells, fmt::format("force_fields/{}/{}/corotational-fem", s, m));
      if (!springs || !fem || !springs->measured || !fem->measured || !springs->stable || !fem->stable) continue;
      out.push_back({s, m, (fem->forces_us + fem->assembly_us) / (springs->forces_us + springs->assembly_us),
                     springs->median / fem->median});
    }
  }
  return out;
}

struct Goal {
  std::string what;
  std::string unit;
  double target{kNaN};
  double measured{kNaN};
  bool higher_is_better{true};
  [[nodiscard]] bool known() const { return std::isfinite(measured); }
  [[nodiscard]] bool met() const { return known() && (higher_is_better ? measured >= target : measured <= target); }
};

std::vector<Goal> goals(const std::vector<Cell>& cells, const std::vector<Ratio>& ratios) {
  std::vector<Goal> out;
  const std::string warm = kHapticRateCell;
  auto rate = [&](const std::string& m, int threads) {
    const Cell* c = find(cells, fmt::format("haptic_rate/{}/{}/threads{}", m, warm, threads));
    return c && c->measured && c->stable ? c->median : kNaN;
  };
  out.push_back({"medium liver, co-rotational FEM, dt 1 ms, one thread (a session's simulation core)", "steps/s", 1000.0, rate("medium", 1)});
  out.push_back({"medium liver, two threads", "steps/s", 2000.0, rate("medium", 2)});
  out.push_back({"fine liver, two threads", "steps/s", 500.0, rate("fine", 2)});
  out.push_back({"simple liver, two threads", "steps/s", 20000.0, rate("simple", 2)});
  if (const Cell* rt = find(cells, "framework/medium/haptic-rate-fem-reaction"); rt && rt->measured && rt->stable) {
    out.push_back({"medium liver in a real-time session at dt 1 ms (fem-reaction): simulated time kept with wall time", "x", 1.0,
                   rt->simulated_s / rt->wall_s});
    out.push_back({"... while the haptic period's p99 stays within 10% of 1 ms", "us", 1100.0, rt->tick_p99_us, false});
  }
  for (const Cell& w : cells) {
    if (!w.name.starts_with("framework/medium/") || !w.name.ends_with("/window") || !w.measured || !w.stable) continue;
    out.push_back({"... with the window open: simulated time kept with wall time", "x", 1.0, w.simulated_s / w.wall_s});
    out.push_back({"... the window's frames/s", "frames/s", 30.0, w.frames_per_s});
    out.push_back({"... the haptic period's p99 with the window open", "us", 1100.0, w.tick_p99_us, false});
  }
  for (const char* m : {"simple", "medium", "fine"}) {
    const Cell* w = find(cells, fmt::format("haptic_rate/{}/{}/threads1", m, warm));
    const Cell* cold = find(cells, fmt::format("haptic_rate/{}/cg25/threads1", m));
    if (!w || !cold) continue;
    out.push_back({fmt::format("{} liver: step error of the haptic-rate CG at most that of 25 cold iterations ({:.3g})", m, cold->step_error),
                   "relative", cold->step_error, w->step_error, false});
  }
  for (const Ratio& r : ratios) {
    out.push_back({fmt::format("{} liver, {} settings: co-rotational FEM / springs, force field's own cost (thesis: springs 2x faster)",
                               r.mesh, r.settings), "x", 2.0,
                   r.force_field});
  }
  return out;
}

// ---------------------------------------------------------------------------------------
// Output.

std::string number(double v, const char* format = "{:.4g}") { return std::isfinite(v) ? fmt::format(fmt::runtime(format), v) : "-"; }

std::string machine_description() {
  std::string cpu = "unknown CPU";
  std::ifstream info("/proc/cpuinfo");
  for (std::string line; std::getline(info, line);) {
    if (line.rfind("model name", 0) == 0) {
      cpu = line.substr(line.find(':') + 2);
      break;
    }
  }
  utsname u{};
  uname(&u);
  return fmt::format("{}, {} hardware threads, {} {}", cpu, std::thread::hardware_concurrency(), u.sysname, u.release);
}

nlohmann::json cell_json(const Cell& c) {
  auto num = [](double v) { return std::isfinite(v) ? nlohmann::json(v) : nlohmann::json(nullptr); };
  return {{"section", c.section},
          {"name", c.name},
          {"mesh", c.mesh},
          {"field", c.field},
          {"settings", c.settings},
          {"solver", c.solver},
          {"dt_s", num(c.dt_s)},
          {"cg_iterations", c.iterations},
          {"warm_start", c.warm_start},
          {"coarse_correction", c.coarse_correction},
          {"matrix_reuse_steps", c.matrix_reuse},
          {"threads", c.threads},
          {"nodes", c.nodes},
          {"elements", c.elements},
          {"surface_triangles", c.triangles},
          {"steps_per_s", {{"median", num(c.median)}, {"min", num(c.min)}, {"max", num(c.max)}}},
          {"timed_steps", c.steps},
          {"stable", c.stable},
          {"stable_over_s", c.stable_over_s},
          {"failure", c.failure},
          {"step_error", num(c.step_error)},
          {"split_us", {{"forces", num(c.forces_us)}, {"assembly", num(c.assembly_us)}, {"solve", num(c.solve_us)}}},
          {"renderer", c.renderer},
          {"bound_tree", c.bound_tree},
          {"tick_us", {{"p50", num(c.tick_p50_us)}, {"p99", num(c.tick_p99_us)}, {"max", num(c.tick_max_us)}}},
          {"contact_fraction", num(c.contact_fraction)},
          {"realtime", {{"simulated_s", num(c.simulated_s)}, {"wall_s", num(c.wall_s)}, {"rate_untouched", num(c.rate_untouched)},
                        {"rate_deforming", num(c.rate_deforming)}, {"rate_in_contact", num(c.rate_contact)},
                        {"frames_per_s", num(c.frames_per_s)}}},
          {"bodies", c.bodies},
          {"force_error", num(c.force_error)},
          {"force_error_settled", num(c.force_error_settled)}};
}

std::string csv(const std::vector<Cell>& cells) {
  std::string out =
      "section,name,mesh,field,settings,solver,dt_s,cg_iterations,warm_start,threads,nodes,elements,surface_triangles,"
      "steps_per_s_median,steps_per_s_min,steps_per_s_max,timed_steps,stable,stable_over_s,step_error,forces_us,assembly_us,"
      "solve_us,renderer,bound_tree,tick_p50_us,tick_p99_us,tick_max_us,contact_fraction,bodies,force_error,force_error_settled,frames_per_s\n";
  auto n = [](double v) { return std::isfinite(v) ? fmt::format("{:.9g}", v) : std::string(); };
  for (const Cell& c : cells) {
    out += fmt::format("{},{},{},{},{},{},{},{},{},{},{},{},{},{},{},{},{},{},{},{},{},{},{},{},{},{},{},{},{},{},{},{},{}\n", c.section, c.name, c.mesh,
                       c.field, c.settings, c.solver, n(c.dt_s), c.iterations, c.warm_start ? 1 : 0, c.threads, c.nodes, c.elements,
                       c.triangles, n(c.median), n(c.min), n(c.max), c.steps, c.stable ? 1 : 0, n(c.stable_over_s),
                       n(c.step_error), n(c.forces_us), n(c.assembly_us), n(c.solve_us), c.renderer,
                       c.renderer.empty() ? "" : (c.bound_tree ? "1" : "0"), n(c.tick_p50_us), n(c.tick_p99_us), n(c.tick_max_us),
                       n(c.contact_fraction), c.bodies, n(c.force_error), n(c.force_error_settled), n(c.frames_per_s));
  }
  return out;
}

std::string rate_text(const Cell& c) {
  if (!c.measured) return c.stable ? "-" : "unstable";
  // Whole steps/s where they are many, three digits where a step takes seconds.
  const char* format = c.min >= 100.0 ? "{:.0f}" : "{:.3g}";
  return fmt::format("{} [{}..{}]{}", number(c.median, format), number(c.min, format), number(c.max, format),
                     c.stable ? "" : " unstable");
}

// Markdown tables (also printed on stdout: they read as plain text too).
std::string tables(const std::vector<Cell>& cells, const std::vector<Ratio>& ratios, const std::vector<Goal>& goal_list) {
  std::string out;
  auto section = [&](const char* name) {
    std::vector<const Cell*> in;
    for (const Cell& c : cells) {
      if (c.section == name) in.push_back(&c);
    }
    return in;
  };
  if (auto m = section("meshes"); !m.empty()) {
    out += "## Meshes (thesis Figure 29)\n\n| mesh | nodes | elements | surface triangles |\n|---|---:|---:|---:|\n";
    for (const Cell* c : m) out += fmt::format("| {} | {} | {} {} | {} |\n", c->mesh, c->nodes, c->elements, c->mesh == "sparse-grid" ? "hexahedra" : "tetrahedra", c->triangles);
    out += "\n";
  }
  if (auto f = section("force_fields"); !f.empty()) {
    out += "## Force fields (thesis Figure 30): implicit Euler, CG 25, dt 0.02 s\n\nsteps/s median [min..max]; the split is "
           "per step (forces / assembly / solve, us).\n\n";
    if (std::ranges::any_of(f, [](const Cell* c) { return c->settings == "thesis" && !c->stable; })) {
      out += "With the thesis' settings the FEM models collapse: E = 100 Pa cannot carry a 1 kg liver of this size under "
             "gravity (the stress of its own weight is about a hundred times E), so a node soon leaves by a metre. The "
             "thesis' scenes were unit-free; its numbers do not carry over to SI. Their rates, until the collapse, are "
             "shown and marked; the physiological rows are the comparison that holds.\n\n";
    }
    out += "| settings | mesh | force field | steps/s | forces | assembly | solve |\n|---|---|---|---|---:|---:|---:|\n";
    for (const Cell* c : f) {
      out += fmt::format("| {} | {} | {} | {} | {} | {} | {} |\n", c->settings, c->mesh, c->field, rate_text(*c), number(c->forces_us, "{:.1f}"),
                         number(c->assembly_us, "{:.1f}"), number(c->solve_us, "{:.1f}"));
    }
    out += "\n";
  }
  if (!ratios.empty()) {
    out += "### Springs against co-rotational FEM (where both ran stably)\n\n| settings | mesh | FEM / springs, force field's own "
           "cost | springs / FEM, whole step |\n|---|---|---:|---:|\n";
    for (const Ratio& r : ratios) {
      out += fmt::format("| {} | {} | {} | {} |\n", r.settings, r.mesh, number(r.force_field, "{:.2f}"), number(r.step, "{:.2f}"));
    }
    out += "\nThe thesis measured springs about twice as fast as co-rotational FEM on Liver Medium (l. 1262): SOFA's "
           "matrix-free CG re-applied each element's stiffness at every iteration, so the force field's cost was paid 25 "
           "times per step. HoF assembles one matrix with the same pattern for both models and solves it once, so the "
           "shared solve hides the difference in the whole step; the force field's own cost (forces + assembly) is where "
           "the models differ.\n\n";
  }
  if (auto s = section("solvers"); !s.empty()) {
    out += "## Solvers (thesis Figure 31): mesh springs, thesis settings\n\n| dt (s) | mesh | solver | steps/s | stable over |\n"
           "|---:|---|---|---|---|\n";
    for (const Cell* c : s) {
      out += fmt::format("| {:g} | {} | {} | {} | {} |\n", c->dt_s, c->mesh, c->solver, rate_text(*c),
                         c->stable ? fmt::format("{:.3g} s", c->stable_over_s) : fmt::format("diverged after {:.3g} s: {}", c->stable_over_s, c->failure));
    }
    out += "\n";
  }
  if (auto t = section("threads"); !t.empty()) {
    out += "## Threads (thesis: the OpenMP test): co-rotational FEM, physiological, implicit Euler, CG 25, dt 0.02 s\n\n"
           "| mesh | threads | steps/s | forces | assembly | solve (us) | speed-up |\n|---|---:|---|---:|---:|---:|---:|\n";
    for (const Cell* c : t) {
      const Cell* one = find(cells, fmt::format("threads/{}/corotational-fem/threads1", c->mesh));
      out += fmt::format("| {} | {} | {} | {} | {} | {} | {} |\n", c->mesh, c->threads, rate_text(*c), number(c->forces_us, "{:.0f}"),
                         number(c->assembly_us, "{:.0f}"), number(c->solve_us, "{:.0f}"),
                         one && one->measured ? number(c->median / one->median, "{:.2f}x") : std::string("-"));
    }
    out += "\n";
  }
  if (auto r = section("renderers"); !r.empty()) {
    out += "## Haptic renderers: the cost of one tick (thesis: useBoundTree)\n\nThe device slides 3 mm under the liver's top, "
           "the surface at rest.\n\n| mesh | renderer | bound tree | tick p50 (us) | p99 | max | ticks in contact |\n"
           "|---|---|---|---:|---:|---:|---:|\n";
    for (const Cell* c : r) {
      out += fmt::format("| {} | {} | {} | {} | {} | {} | {} |\n", c->mesh, c->renderer, c->bound_tree ? "on" : "off",
                         number(c->tick_p50_us, "{:.2f}"), number(c->tick_p99_us, "{:.2f}"), number(c->tick_max_us, "{:.1f}"),
                         std::isfinite(c->contact_fraction) ? fmt::format("{:.0f}%", 100.0 * c->contact_fraction) : std::string("-"));
    }
    out += "\n";
  }
  if (auto g = section("cg_iterations"); !g.empty()) {
    out += "## CG iterations (thesis Figures 32–33): dt 0.02 s\n\n| solver | mesh | model | CG iterations | steps/s | step error vs LDLT | stable |\n"
           "|---|---|---|---:|---|---:|---|\n";
    for (const Cell* c : g) {
      out += fmt::format("| {} | {} | {} {} | {} | {} | {} | {} |\n", c->solver, c->mesh, c->field, c->settings, c->iterations, rate_text(*c),
                         number(c->step_error, "{:.3g}"), c->stable ? "yes" : "no");
    }
    out += "\n";
  }
  if (auto h = section("haptic_rate"); !h.empty()) {
    out += "## The haptic rate: co-rotational FEM, physiological, implicit Euler, dt 1 ms\n\n| mesh | CG | threads | steps/s | "
           "step error vs LDLT | split forces / assembly / solve (us) |\n|---|---|---:|---|---:|---|\n";
    for (const Cell* c : h) {
      out += fmt::format("| {} | {}{} | {} | {} | {} | {} / {} / {} |\n", c->mesh, c->iterations,
                         !c->warm_start ? std::string(" from zero")
                         : fmt::format(" warm-started{}, matrix every {}", c->coarse_correction ? ", two-level" : "",
                                       c->matrix_reuse > 1 ? fmt::format("{} steps", c->matrix_reuse) : std::string("step")),
                         c->threads, rate_text(*c), number(c->step_error, "{:.3g}"), number(c->forces_us, "{:.0f}"),
                         number(c->assembly_us, "{:.0f}"), number(c->solve_us, "{:.0f}"));
    }
    out += "\n";
  }
  if (auto w = section("framework"); !w.empty()) {
    out += "## The whole framework in real time (thesis Figure 34): haptic loop and simulation on their threads\n\n"
           "A scripted hand presses the liver's top (co-rotational FEM, 5 kPa) from 1 cm above and holds. Rates are simulation "
           "steps per second of wall time; real time is 1/dt. The window row draws the same press in `hof gui` (a project "
           "written to DIR/window), the three loops sharing the cores.\n\n"
           "| mesh | set-up | dt (s) | steps/s | simulated / wall | untouched / deforming / in contact (steps/s) | haptic period "
           "p50 / p99 / max (us) | in contact | window frames/s |\n|---|---|---:|---:|---:|---|---|---:|---:|\n";
    for (const Cell* c : w) {
      const bool window = c->name.ends_with("/window");
      if (window && !c->measured) {
        out += fmt::format("| {} | haptic rate, fem-reaction, window | {:g} | not measured: {} |||||\n", c->mesh, c->dt_s, c->failure);
        continue;
      }
      out += fmt::format("| {} | {}{} | {:g} | {} | {} | {} / {} / {} | {} / {} / {} | {} | {} |\n", c->mesh,
                         c->dt_s < 0.005 ? "haptic rate, fem-reaction" : "dt 10 ms, barycentric", window ? ", window" : "", c->dt_s,
                         number(c->median, "{:.0f}"),
                         std::isfinite(c->simulated_s) && c->wall_s > 0.0 ? fmt::format("{:.2f}", c->simulated_s / c->wall_s) : std::string("-"),
                         number(c->rate_untouched, "{:.0f}"), number(c->rate_deforming, "{:.0f}"), number(c->rate_contact, "{:.0f}"),
                         number(c->tick_p50_us, "{:.0f}"), number(c->tick_p99_us, "{:.0f}"), number(c->tick_max_us, "{:.0f}"),
                         std::isfinite(c->contact_fraction) ? fmt::format("{:.0f}%", 100.0 * c->contact_fraction) : std::string("-"),
                         number(c->frames_per_s, "{:.0f}"));
    }
    out += "\n";
  }
  if (auto bs = section("bodies"); !bs.empty()) {
    out += "## Bodies: one liver against two\n\nCo-rotational FEM, 5 kPa, implicit Euler, CG 25, dt 10 ms; the livers side by "
           "side, the first pressed; virtual time (the haptic loop ticks in lock-step), so the rate is the machine's. The bodies "
           "of a world step in parallel.\n\n| mesh | livers | world steps/s | liver steps/s | cost of a world step against one liver |\n"
           "|---|---:|---:|---:|---:|\n";
    for (const Cell* c : bs) {
      const Cell* one = find(cells, fmt::format("bodies/{}/livers1", c->mesh));
      out += fmt::format("| {} | {} | {} | {} | {} |\n", c->mesh, c->bodies, c->measured ? number(c->median, "{:.0f}") : (c->stable ? "-" : "unstable"),
                         number(c->median * c->bodies, "{:.0f}"),
                         one && one->measured && c->measured ? number(one->median / c->median, "{:.2f}x") : std::string("-"));
    }
    out += "\n";
  }
  if (auto cs = section("coupling"); !cs.empty()) {
    out += "## Coupling schemes against the static FEM reaction\n\nA slow press (4 mm at 4 mm/s, then held 0.6 s) straight down "
           "onto the top's surface node of the co-rotational liver (5 kPa, Rayleigh 1.0 / 0.1), god-object proxy at the device's "
           "stiffest (2,000 N/m), virtual time. The reference is the static FEM solve (LDLT) with that node held at the device's "
           "depth. Errors are |felt - reaction| / |reaction|: the largest at 1, 2, 3 and 4 mm during the press (the tissue's "
           "damping still adds to the felt force), and at 4 mm once held. The reference holds the node in all three directions "
           "while the frictionless proxy slides on the tilting surface, so a sideways part of the difference is there by "
           "construction. closest-vertex and barycentric render the proxy's spring: at dt 20 ms the spring, far stiffer than the "
           "tissue under it, and the tissue exchange their force a step apart, and the felt force swings around the reaction; "
           "compliance renders the FEM's local response at 1 kHz; fem-reaction steps the FEM at 1 kHz and renders its own "
           "elastic force. Cost: simulation steps per second of wall time, and wall time per simulated second.\n\n"
           "| mesh | scheme | dt (s) | error during the press | error held at 4 mm | steps/s | wall s per simulated s |\n"
           "|---|---|---:|---:|---:|---:|---:|\n";
    auto percent = [](double v) { return std::isfinite(v) ? fmt::format("{:.1f}%", 100.0 * v) : std::string("-"); };
    for (const Cell* c : cs) {
      const std::string scheme = c->name.substr(c->name.rfind('/') + 1);
      out += fmt::format("| {} | {} | {:g} | {} | {} | {} | {} |\n", c->mesh, scheme, c->dt_s,
                         std::isfinite(c->force_error) || c->failure.empty() ? percent(c->force_error) : c->failure,
                         percent(c->force_error_settled), c->measured ? number(c->median, "{:.0f}") : std::string("-"),
                         c->measured && c->simulated_s > 0.0 ? number(c->wall_s / c->simulated_s, "{:.2f}") : std::string("-"));
    }
    out += "\n";
  }
  if (!goal_list.empty()) {
    out += "## Goals\n\n| goal | target | measured | met |\n|---|---:|---:|---|\n";
    for (const Goal& g : goal_list) {
      std::string verdict = "not measured";
      if (g.known()) {
        const double factor = g.higher_is_better ? g.measured / g.target : g.target / g.measured;
        verdict = g.met() ? fmt::format("yes ({:.2f}x)", factor) : fmt::format("no: missed by {:.2f}x", 1.0 / factor);
      }
      out += fmt::format("| {} | {} {} | {} | {} |\n", g.what, number(g.target), g.unit, number(g.measured), verdict);
    }
    out += "\n";
  }
  return out;
}

// Plot data: one .dat per figure beside its PNG/SVG, `?` where a cell was not measured.
std::string dat_value(double v) { return std::isfinite(v) && v > 0.0 ? fmt::format("{:.6g}", v) : "?"; }

std::vector<detail::Plot> write_plot_data(const std::filesystem::path& dir, const std::vector<Cell>& cells, const std::vector<Ratio>& ratios) {
  std::vector<detail::Plot> plots;
  const std::string histogram =
      "set datafile missing '?'\nset datafile columnheaders\nset style data histograms\nset style histogram cluster gap 1\nset style fill solid 0.8 border -1\n"
      "set boxwidth 0.9\nset logscale y\nset key top left\n";
  // Figure 29.
  {
    std::ofstream d(dir / "fig29_meshes.dat");
    d << "mesh nodes elements triangles\n";
    int rows = 0;
    for (const Cell& c : cells) {
      if (c.section == "meshes" && c.measured) {
        d << c.mesh << " " << c.nodes << " " << c.elements << " " << c.triangles << "\n";
        ++rows;
      }
    }
    if (rows) {
      plots.push_back({"fig29_meshes", histogram + "set ylabel 'count'\nset title 'Figure 29: mesh sizes (the sparse grid counts hexahedra)'\n"
                                                   "plot 'fig29_meshes.dat' using 2:xtic(1) title 'nodes', '' using 3 title 'elements', "
                                                   "'' using 4 title 'surface triangles'\n"});
    }
  }
  // Figure 30, each settings.
  for (const char* s : {"thesis", "physiological"}) {
    const std::string name = fmt::format("fig30_force_fields_{}", s);
    std::ofstream d(dir / (name + ".dat"));
    d << "mesh springs linear-fem corotational-fem neo-hookean hexahedral-fem\n";
    int rows = 0;
    for (const char* m : {"simple", "coarse", "medium", "fine", "sparse-grid"}) {
      std::string line = m;
      bool any = false;
      for (const char* f : {"springs", "linear-fem", "corotational-fem", "neo-hookean", "hexahedral-fem"}) {
        const Cell* c = find(cells, fmt::format("force_fields/{}/{}/{}", s, m, f));
        const bool ok = c && c->measured && c->stable;
        any = any || ok;
        line += " " + (ok ? dat_value(c->median) : std::string("?"));
      }
      if (any) {
        d << line << "\n";
        ++rows;
      }
    }
    if (rows) {
      plots.push_back({name, histogram + fmt::format("set ylabel 'steps/s (median; unstable cells left out)'\nset title 'Figure 30: force "
                                                     "fields, implicit Euler + CG 25, dt 0.02 s, {} settings'\n"
                                                     "plot for [k=2:6] '{}.dat' using k:xtic(1) title columnheader(k)\n",
                                                     s, name)});
    }
  }
  if (!ratios.empty()) {
    std::ofstream d(dir / "fig30_springs_vs_fem.dat");
    d << "case force_field step thesis\n";
    for (const Ratio& r : ratios) {
      d << r.mesh << "/" << r.settings << " " << dat_value(r.force_field) << " " << dat_value(r.step) << " "
        << (r.mesh == "medium" && r.settings == "thesis" ? "2" : "?") << "\n";
    }
    plots.push_back({"fig30_springs_vs_fem",
                     "set datafile missing '?'\nset datafile columnheaders\nset style data histograms\nset style histogram cluster gap 1\nset style fill solid 0.8 border -1\n"
                     "set yrange [0:*]\nset ylabel 'springs faster by (x)'\nset title 'Mesh springs against co-rotational FEM (mesh/settings)'\n"
                     "plot 'fig30_springs_vs_fem.dat' using 2:xtic(1) title 'force field own cost (forces + assembly)', "
                     "'' using 3 title 'whole step (steps/s)', '' using ($0):4 with points pt 7 ps 2 lc rgb 'black' title 'thesis (SOFA, Liver Medium)'\n"});
  }
  // Figure 31, each dt: steps/s per mesh per solver; unstable cells as red crosses at the rate
  // they ran at before diverging (or at the bottom when they never completed a batch).
  for (double dt : {0.002, 0.02}) {
    const std::string name = fmt::format("fig31_solvers_dt{:g}", dt);
    std::ofstream d(dir / (name + ".dat"));
    std::ofstream u(dir / (name + "_unstable.dat"));
    const char* solvers[] = {"explicit-euler", "symplectic-euler", "rk4", "static-cg", "implicit-cg", "implicit-ldlt"};
    d << "index mesh";
    for (const char* sv : solvers) d << " " << sv;
    d << "\n";
    int rows = 0, index = 0, unstable = 0;
    for (const char* m : {"simple", "coarse", "medium", "fine"}) {
      std::string line = fmt::format("{} {}", index, m);
      bool any = false;
      int stacked = 0;
      for (const char* sv : solvers) {
        const Cell* c = find(cells, fmt::format("solvers/{}/{}/{}", dt_label(dt), m, sv));
        if (c) any = true;
        line += " " + (c && c->stable && c->measured ? dat_value(c->median) : std::string("?"));
        if (c && !c->stable) {
          // At the rate it ran before diverging; one that diverged before a batch finished
          // sits at the bottom, stacked with the others so that each label stays readable.
          u << index << " " << (c->measured ? dat_value(c->median) : fmt::format("{:g}", std::pow(2.0, stacked++))) << " " << sv << "\n";
          ++unstable;
        }
      }
      if (any) {
        d << line << "\n";
        ++rows;
        ++index;
      }
    }
    if (rows) {
      std::string body = fmt::format("set datafile missing '?'\nset logscale y\nset xrange [-0.5:{}]\nset yrange [0.7:*]\nset ylabel 'steps/s (median)'\nset key outside right\n"
                                     "set title 'Figure 31: solvers on mesh springs (thesis settings), dt {:g} s'\n"
                                     "plot for [k=3:8] '{}.dat' using 1:k:xtic(2) with linespoints lw 2 pt 7 title columnheader(k)",
                                     index - 0.5, dt, name);
      if (unstable) {
        body += fmt::format(", '{0}_unstable.dat' using 1:2 with points pt 2 ps 2 lw 2 lc rgb 'red' title 'unstable (diverged)', "
                            "'{0}_unstable.dat' using 1:2:3 with labels left offset 1.2,0 tc rgb 'red' notitle",
                            name);
      }
      plots.push_back({name, body + "\n"});
    }
  }
  // Threads: steps/s per mesh, one against two.
  {
    std::ofstream d(dir / "threads.dat");
    d << "mesh one-thread two-threads\n";
    int rows = 0;
    for (const char* m : {"simple", "coarse", "medium", "fine"}) {
      const Cell* one = find(cells, fmt::format("threads/{}/corotational-fem/threads1", m));
      const Cell* two = find(cells, fmt::format("threads/{}/corotational-fem/threads2", m));
      if (!one && !two) continue;
      auto rate = [](const Cell* c) { return c && c->measured && c->stable ? dat_value(c->median) : std::string("?"); };
      d << m << " " << rate(one) << " " << rate(two) << "\n";
      ++rows;
    }
    if (rows) {
      plots.push_back({"threads", histogram + "set ylabel 'steps/s (median)'\nset title 'One thread against two: co-rotational FEM, "
                                              "implicit Euler + CG 25, dt 0.02 s'\n"
                                              "plot 'threads.dat' using 2:xtic(1) title 'one thread', '' using 3 title 'two threads'\n"});
    }
  }
  // Renderers: p99 tick cost per mesh, each renderer with and without the bound tree.
  {
    std::ofstream d(dir / "renderers.dat");
    const char* renderers[] = {"god-object", "ruspini", "penalty"};
    d << "mesh";
    for (const char* r : renderers) d << " " << r << "-tree " << r << "-no-tree";
    d << "\n";
    int rows = 0;
    for (const char* m : {"simple", "coarse", "medium", "fine"}) {
      std::string line = m;
      bool any = false;
      for (const char* r : renderers) {
        for (const char* t : {"bound-tree", "no-tree"}) {
          const Cell* c = find(cells, fmt::format("renderers/{}/{}/{}", m, r, t));
          any = any || (c && c->measured);
          line += " " + (c && c->measured ? dat_value(c->tick_p99_us) : std::string("?"));
        }
      }
      if (any) {
        d << line << "\n";
        ++rows;
      }
    }
    if (rows) {
      plots.push_back({"renderers", histogram + "set ylabel 'tick cost p99 (us)'\nset key outside right\nset title 'Haptic renderers, "
                                                "one tick (device 3 mm under the top surface)'\n"
                                                "plot for [k=2:7] 'renderers.dat' using k:xtic(1) title columnheader(k)\n"});
    }
  }
  // Figures 32–33: steps/s and error against CG iterations.
  for (const char* sv : {"static-cg", "implicit-cg"}) {
    const std::string name = fmt::format("fig{}_{}_cg_iterations", std::string(sv) == "static-cg" ? 32 : 33, sv);
    std::ofstream d(dir / (name + ".dat"));
    d << "iterations springs_rate springs_error fem_rate fem_error\n";
    std::map<int, std::array<double, 4>> rows;
    std::string mesh_name;
    for (const Cell& c : cells) {
      if (c.section != "cg_iterations" || c.solver != sv) continue;
      auto& row = rows.try_emplace(c.iterations, std::array<double, 4>{kNaN, kNaN, kNaN, kNaN}).first->second;
      const int col = c.field == "springs" ? 0 : 2;
      if (c.stable) {
        row[static_cast<std::size_t>(col)] = c.median;
        row[static_cast<std::size_t>(col + 1)] = c.step_error;
      }
      mesh_name = c.mesh;
    }
    for (const auto& [k, r] : rows) d << k << " " << dat_value(r[0]) << " " << dat_value(r[1]) << " " << dat_value(r[2]) << " " << dat_value(r[3]) << "\n";
    if (!rows.empty()) {
      plots.push_back({name, fmt::format("set datafile missing '?'\nset xlabel 'CG iterations'\nset ylabel 'steps/s'\nset y2label 'step error "
                                         "against an exact LDLT solve (relative)'\nset logscale y2\nset y2tics\nset ytics nomirror\n"
                                         "set key below\nset title 'Figure {}: {} on the {} liver, dt 0.02 s'\n"
                                         "plot '{}.dat' using 1:2 with linespoints lw 2 pt 7 title 'steps/s, springs (thesis)', "
                                         "'' using 1:4 with linespoints lw 2 pt 5 title 'steps/s, co-rotational FEM (5 kPa)', "
                                         "'' using 1:3 axes x1y2 with linespoints dt 2 pt 7 title 'error, springs', "
                                         "'' using 1:5 axes x1y2 with linespoints dt 2 pt 5 title 'error, co-rotational FEM'\n",
                                         std::string(sv) == "static-cg" ? 32 : 33, sv, mesh_name, name)});
    }
  }
  // The haptic rate against its goals.
  {
    std::ofstream d(dir / "haptic_rate.dat");
    d << "mesh cold25_1 cold25_2 warm_1 warm_2 goal_2threads\n";
    const std::map<std::string, double> goal_2 = {{"simple", 20000.0}, {"medium", 2000.0}, {"fine", 500.0}};
    int rows = 0;
    for (const char* m : {"simple", "medium", "fine"}) {
      std::string line = m;
      bool any = false;
      for (const std::string& cg : {std::string("cg25"), std::string(kHapticRateCell)}) {
        for (int t : {1, 2}) {
          const Cell* c = find(cells, fmt::format("haptic_rate/{}/{}/threads{}", m, cg, t));
          any = any || c;
          line += " " + (c && c->measured && c->stable ? dat_value(c->median) : std::string("?"));
        }
      }
      if (any) {
        d << line << " " << goal_2.at(m) << "\n";
        ++rows;
      }
    }
    if (rows) {
      plots.push_back({"haptic_rate",
                       histogram + fmt::format("set ylabel 'steps/s (median)'\nset key outside right\nset title 'Co-rotational FEM at dt 1 ms "
                                               "(5 kPa liver): the haptic rate is 1000 steps/s'\n"
                                               "plot 'haptic_rate.dat' using 2:xtic(1) title 'CG 25 from zero, 1 thread', '' using 3 title "
                                               "'CG 25 from zero, 2 threads', '' using 4 title 'two-level CG warm, 1 thread', '' using 5 title "
                                               "'two-level CG warm, 2 threads', '' using ($0+0.3):6 with points pt 6 ps 2 lw 2 lc rgb 'black' "
                                               "title 'goal, 2 threads', 1000 with lines dt 2 lc rgb 'red' title '1 kHz'\n")});
    }
  }
  // Figure 34: the whole framework's rates in the thesis' three states, against real time.
  {
    std::ofstream d(dir / "fig34_framework.dat");
    d << "setup untouched deforming contact real_time\n";
    int rows = 0;
    for (const Cell& c : cells) {
      if (c.section != "framework" || !c.measured) continue;
      const bool window = c.name.ends_with("/window");
      d << fmt::format("\"{} {}{}\" {} {} {} {}\n", c.mesh, c.dt_s < 0.005 ? "1ms" : "10ms", window ? " window" : "", dat_value(c.rate_untouched),
                       dat_value(c.rate_deforming), dat_value(c.rate_contact), dat_value(1.0 / c.dt_s));
      ++rows;
    }
    if (rows) {
      plots.push_back({"fig34_framework",
                       histogram + "set ylabel 'simulation steps/s of wall time'\nset key outside right\nset xtics rotate by -25\nset yrange [10:*]\n"
                                   "set title 'Figure 34: the whole framework in real time (scripted press; mesh, dt, window)'\n"
                                   "plot 'fig34_framework.dat' using 2:xtic(1) title 'untouched', '' using 3 title 'deforming', '' "
                                   "using 4 title 'in contact', '' using ($0):5 with points pt 6 ps 2 lw 2 lc rgb 'black' title "
                                   "'real time (1/dt)'\n"});
    }
  }
  // The coupling schemes' felt force against the static FEM reaction.
  {
    std::ofstream d(dir / "coupling.dat");
    d << "scheme press_error_percent held_error_percent\n";
    int rows = 0;
    std::string mesh_name;
    for (const Cell& c : cells) {
      if (c.section != "coupling" || !std::isfinite(c.force_error)) continue;
      d << fmt::format("{} {} {}\n", c.name.substr(c.name.rfind('/') + 1), dat_value(100.0 * c.force_error),
                       dat_value(100.0 * c.force_error_settled));
      mesh_name = c.mesh;
      ++rows;
    }
    if (rows) {
      plots.push_back({"coupling",
                       histogram + "set ylabel '|felt - static FEM reaction| / |reaction| (%)'\nset key outside right\nset yrange [0.5:*]\nset xtics rotate by -25\n" +
                           fmt::format("set title 'Coupling schemes on the {} liver: the force felt against the static FEM reaction'\n", mesh_name) +
                           "plot 'coupling.dat' using 2:xtic(1) title 'largest, during the press', '' using 3 title "
                                   "'held at 4 mm'\n"});
    }
  }
  return plots;
}

}  // namespace

int run_evaluation(const EvaluationOptions& options) {
  std::regex only;
  try {
    only = std::regex(options.only.empty() ? std::string(".") : options.only);
  } catch (const std::regex_error& e) {
    return detail::fail(fmt::format("--only '{}': not a regular expression ({})", options.only, e.what()));
  }
  std::error_code ec;
  std::filesystem::create_directories(options.out, ec);
  if (ec) return detail::fail(fmt::format("{}: cannot create the report folder: {}", options.out.string(), ec.message()));

  Bodies bodies;
  std::vector<PlannedCell> planned;
  for (PlannedCell& p : plan(options.quick, bodies, options.out)) {
    if (std::regex_search(p.cell.name, only)) planned.push_back(std::move(p));
  }
  if (planned.empty()) return detail::fail(fmt::format("--only '{}' matches no cell (names look like force_fields/thesis/medium/springs)", options.only));

  const ProgressSink progress = make_terminal_progress(false);
  const auto started = Clock::now();
  std::vector<Cell> cells;
  for (std::size_t i = 0; i < planned.size(); ++i) {
    progress(fmt::format("hof bench: {} ({}/{})", planned[i].cell.name, i + 1, planned.size()), static_cast<double>(i) / static_cast<double>(planned.size()));
    Cell cell = planned[i].cell;
    planned[i].run(cell);
    cells.push_back(std::move(cell));
  }
  progress("hof bench: done", 1.0);
  const double total_s = seconds_since(started);

  const std::vector<Ratio> ratios = springs_over_fem(cells);
  const std::vector<Goal> goal_list = goals(cells, ratios);
  const std::string table_text = tables(cells, ratios, goal_list);
  std::fputs(table_text.c_str(), stdout);

  const std::string machine = machine_description();
  std::time_t now = std::time(nullptr);
  char date[32];
  std::strftime(date, sizeof date, "%Y-%m-%d %H:%M UTC", std::gmtime(&now));

  nlohmann::json results = {{"command", options.command_line},
                            {"date", date},
                            {"machine", machine},
                            {"quick", options.quick},
                            {"only", options.only},
                            {"seconds", total_s},
                            {"haptic_rate_cg_iterations", kHapticRateCgIterations},
                            {"cells", nlohmann::json::array()},
                            {"springs_vs_fem", nlohmann::json::array()},
                            {"goals", nlohmann::json::array()}};
  for (const Cell& c : cells) results["cells"].push_back(cell_json(c));
  for (const Ratio& r : ratios) {
    results["springs_vs_fem"].push_back({{"settings", r.settings},
                                         {"mesh", r.mesh},
                                         {"fem_over_springs_force_field_cost", std::isfinite(r.force_field) ? nlohmann::json(r.force_field) : nlohmann::json()},
                                         {"springs_over_fem_step_rate", std::isfinite(r.step) ? nlohmann::json(r.step) : nlohmann::json()}});
  }
  for (const Goal& g : goal_list) {
    results["goals"].push_back({{"goal", g.what},
                                {"unit", g.unit},
                                {"target", std::isfinite(g.target) ? nlohmann::json(g.target) : nlohmann::json()},
                                {"measured", g.known() ? nlohmann::json(g.measured) : nlohmann::json()},
                                {"met", g.known() ? nlohmann::json(g.met()) : nlohmann::json()}});
  }

  const std::vector<detail::Plot> plots = write_plot_data(options.out, cells, ratios);
  const std::vector<std::string> failed = detail::render_plots(options.out, "", plots);

  std::string report = fmt::format(
      "# HoF evaluation\n\nMade by `{}` on {} in {:.0f} s.\n\nMachine: {}.\n\n"
      "Each cell: steps/s as the median [min..max] of {} timed batches of at least {} s; stable means no divergence and no node "
      "moving more than 1 m over {} s of simulated time (or as much as {} s of checking allowed). Step errors are against an "
      "exact LDLT solve of the same step from the same state (relative norm of the velocity change; of the displacement for "
      "the static solver). Thesis settings: gravity 9.8, total mass 1 kg, springs 10,000 / 15, FEM E = 100, nu = 0.4 "
      "(unit-free in SOFA, here SI on a liver in metres); physiological: E = 5 kPa, nu = 0.45, 1060 kg/m3. Every body rests "
      "on its lowest 4 mm.\n\n",
      options.command_line, date, total_s, machine, budget_for(options.quick).batches, budget_for(options.quick).batch_s,
      budget_for(options.quick).horizon_s, budget_for(options.quick).stability_wall_s);
  report += table_text;
  report += "## Plots\n\n";
  for (const detail::Plot& p : plots) {
    if (std::find(failed.begin(), failed.end(), p.name) == failed.end()) report += fmt::format("![{0}]({0}.png)\n\n", p.name);
  }
  report +=
      "## Not measured by this version\n\nSOFA side by side: `hof bench --scene FILE` runs a SOFA scene as `runSofa -g batch -n N "
      "FILE` does; run both on the same machine to compare (SOFA is not a Debian package, so this run cannot). The window "
      "row needs a display: without one it is listed as not measured.\n";

  std::string write_errors;
  for (const auto& [file, text] : {std::pair{"results.json", results.dump(2) + "\n"}, std::pair{"results.csv", csv(cells)},
                                   std::pair{"report.md", report}}) {
    if (auto w = write_file_atomically(options.out / file, text); !w) write_errors += w.error().to_string() + "\n";
  }
  if (!write_errors.empty()) return detail::fail("the report could not be written:\n" + write_errors);
  if (!failed.empty()) {
    std::string names;
    for (const std::string& f : failed) names += (names.empty() ? "" : ", ") + f;
    std::fprintf(stderr, "hof: note: no plot for %s (gnuplot missing?); plots.gp is in %s\n", names.c_str(), options.out.c_str());
  }
  std::fprintf(stderr, "hof bench: %zu cells in %.0f s; report in %s/report.md\n", cells.size(), total_s, options.out.c_str());
  return 0;
}

}  // namespace hof::app
