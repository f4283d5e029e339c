#include "hof/app/bench/plan.h"

#include <fmt/format.h>

#include <memory>
#include <optional>
#include <utility>

#include "hof/app/bench/timers.h"

namespace hof::app::bench {

using namespace hof::mechanics;

namespace {

// The body of a cell, generated on first use; its sizes go into the cell. A body that cannot
// be made fails the cell (nullptr).
struct BodyLookup {
  Bodies* bodies;
  const Body* operator()(const std::string& body_name, Cell& cell) const {
    auto b = bodies->by_name(body_name);
    if (!b) {
      cell.stable = false;
      cell.failure = b.error().to_string();
      return nullptr;
    }
    cell.nodes = (*b)->nodes.size();
    cell.elements = (*b)->tets.empty() ? (*b)->hexes.size() : (*b)->tets.size();
    cell.triangles = (*b)->surface_triangles;
    return *b;
  }
  // A cell's run on body `mesh`: the body looked up (its sizes into the cell), then `measure`
  // of it — nothing when it cannot be made.
  template <class Measure>
  std::function<void(Cell&)> on(std::string mesh_name, Measure measure_body) const {
    return [lookup = *this, mesh = std::move(mesh_name), measure = std::move(measure_body)](Cell& cell) {
      if (const Body* b = lookup(mesh, cell)) measure(*b, cell);
    };
  }
  // ... and `measure` of the physiological co-rotational liver of `setup` on that body.
  template <class Measure>
  std::function<void(Cell&)> on_corotational(std::string mesh_name, const CorotationalSetup& setup,
                                             Measure measure_model) const {
    return on(std::move(mesh_name), [setup, measure = std::move(measure_model)](const Body& b, Cell& cell) {
      measure(b, corotational_config(b, setup), cell);
    });
  }
};

// What every section of the plan reads.
struct PlanContext {
  bool quick;
  Budget budget;
  std::vector<std::string> livers;  // the standard livers measured
  std::vector<std::string> meshes;  // ... and the sparse grid
  BodyLookup with_body;
  std::filesystem::path out;
};

// A cell's description for a body_config + set_solver recipe.
Cell recipe_cell(std::string section, std::string name, const std::string& mesh, Field f, Settings s, Solver sv,
                 double dt_s, int iterations) {
  Cell c;
  c.section = std::move(section);
  c.name = std::move(name);
  c.mesh = mesh;
  c.field = field_name(f);
  c.settings = settings_name(s);
  c.solver = solver_name(sv);
  c.dt_s = dt_s;
  c.iterations = iterations;
  return c;
}

// A cell's description for a corotational_config set-up.
Cell corotational_cell(std::string section, std::string name, const std::string& mesh, const CorotationalSetup& s) {
  Cell c = recipe_cell(std::move(section), std::move(name), mesh, Field::kLarge, Settings::kPhysiological,
                       Solver::kImplicitCg, s.dt_s, s.haptic_rate_cg ? kHapticRateCgIterations : s.iterations);
  c.warm_start = s.haptic_rate_cg;
  c.coarse_correction = s.haptic_rate_cg;
  // iterations (haptic-rate CG) and matrix_reuse: set when the cell runs, from the model.
  return c;
}

void plan_meshes(const PlanContext& ctx, std::vector<PlannedCell>& cells) {
  const std::vector<std::string>& meshes = ctx.meshes;
  const BodyLookup with_body = ctx.with_body;
  // Figure 29: mesh sizes.
  for (const std::string& m : meshes) {
    Cell c;
    c.section = "meshes";
    c.name = "meshes/" + m;
    c.mesh = m;
    cells.push_back({c, [with_body, m](Cell& cell) { cell.measured = with_body(m, cell) != nullptr; }});
  }
}

void plan_force_fields(const PlanContext& ctx, std::vector<PlannedCell>& cells) {
  const Budget budget = ctx.budget;
  const std::vector<std::string>& meshes = ctx.meshes;
  const BodyLookup with_body = ctx.with_body;
  // Figure 30: force fields per mesh, implicit Euler + CG 25 at dt 0.02.
  for (Settings s : {Settings::kThesis, Settings::kPhysiological}) {
    for (const std::string& m : meshes) {
      const bool grid = m == "sparse-grid";
      for (Field f : grid ? std::vector<Field>{Field::kHexahedra}
                          : std::vector<Field>{Field::kSprings, Field::kSmall, Field::kLarge, Field::kNeoHookean}) {
        const Cell c =
            recipe_cell("force_fields", fmt::format("force_fields/{}/{}/{}", settings_name(s), m, field_name(f)), m, f,
                        s, Solver::kImplicitCg, 0.02, 25);
        cells.push_back({c, with_body.on(m, [f, s, budget](const Body& b, Cell& cell) {
                           ModelConfig config = body_config(b, f, s);
                           set_solver(config, Solver::kImplicitCg, 0.02);
                           time_cell(config, budget, cell);
                         })});
      }
    }
  }
}

void plan_solvers(const PlanContext& ctx, std::vector<PlannedCell>& cells) {
  const Budget budget = ctx.budget;
  const std::vector<std::string>& livers = ctx.livers;
  const BodyLookup with_body = ctx.with_body;
  // Figure 31: solvers on the thesis' mesh springs at dt 0.002 and 0.02 (stability marked).
  for (double dt : {0.002, 0.02}) {
    for (const std::string& m : livers) {
      for (Solver sv : {Solver::kExplicitEuler, Solver::kSymplecticEuler, Solver::kRungeKutta4, Solver::kStatic,
                        Solver::kImplicitCg, Solver::kImplicitLdlt}) {
        const Cell c = recipe_cell("solvers", fmt::format("solvers/{}/{}/{}", dt_label(dt), m, solver_name(sv)), m,
                                   Field::kSprings, Settings::kThesis, sv, dt,
                                   sv == Solver::kImplicitCg || sv == Solver::kStatic ? 25 : 0);
        cells.push_back({c, with_body.on(m, [sv, dt, budget](const Body& b, Cell& cell) {
                           ModelConfig config = body_config(b, Field::kSprings, Settings::kThesis);
                           set_solver(config, sv, dt);
                           time_cell(config, budget, cell);
                         })});
      }
    }
  }
}

void plan_threads(const PlanContext& ctx, std::vector<PlannedCell>& cells) {
  const Budget budget = ctx.budget;
  const std::vector<std::string>& livers = ctx.livers;
  const BodyLookup with_body = ctx.with_body;
  // Threads (the thesis' OpenMP test, l. 1242): one core against two, co-rotational FEM.
  for (const std::string& m : livers) {
    for (int threads : {1, 2}) {
      const CorotationalSetup setup{0.02};
      Cell c = corotational_cell("threads", fmt::format("threads/{}/corotational-fem/threads{}", m, threads), m, setup);
      c.threads = threads;
      cells.push_back(
          {c, with_body.on_corotational(m, setup, [threads, budget](const Body&, ModelConfig config, Cell& cell) {
             config.threads = threads;
             time_cell(config, budget, cell);
           })});
    }
  }
}

void plan_renderers(const PlanContext& ctx, std::vector<PlannedCell>& cells) {
  const Budget budget = ctx.budget;
  const std::vector<std::string>& livers = ctx.livers;
  const BodyLookup with_body = ctx.with_body;
  // Haptic renderers × bound tree × mesh: the cost of a tick.
  for (const std::string& m : livers) {
    for (auto [kind, renderer] : {std::pair{haptics::RendererKind::kGodObject, "god-object"},
                                  std::pair{haptics::RendererKind::kRuspini, "ruspini"},
                                  std::pair{haptics::RendererKind::kPenalty, "penalty"}}) {
      for (bool tree : {true, false}) {
        Cell c;
        c.section = "renderers";
        c.name = fmt::format("renderers/{}/{}/{}", m, renderer, tree ? "bound-tree" : "no-tree");
        c.mesh = m;
        c.renderer = renderer;
        c.bound_tree = tree;
        cells.push_back({c, with_body.on(m, [kind, tree, budget](const Body& b, Cell& cell) {
                           time_renderer(b.surface, kind, tree, budget, cell);
                         })});
      }
    }
  }
}

void plan_cg_iterations(const PlanContext& ctx, std::vector<PlannedCell>& cells) {
  const bool quick = ctx.quick;
  const Budget budget = ctx.budget;
  const BodyLookup with_body = ctx.with_body;
  // Figures 32–33: CG iterations with the static solver and implicit Euler at dt 0.02, on
  // the thesis' springs and on the physiological co-rotational FEM; error against LDLᵀ.
  const std::string cg_mesh = quick ? "simple" : "medium";
  const std::vector<int> counts =
      quick ? std::vector<int>{1, 5, 25} : std::vector<int>{1, 2, 3, 5, 7, 10, 15, 20, 25, 30, 40, 50};
  for (Solver sv : {Solver::kStatic, Solver::kImplicitCg}) {
    for (auto [f, s] :
         {std::pair{Field::kSprings, Settings::kThesis}, std::pair{Field::kLarge, Settings::kPhysiological}}) {
      for (int k : counts) {
        const Cell c = recipe_cell(
            "cg_iterations",
            fmt::format("cg_iterations/{}/{}/{}/{}/cg{}", solver_name(sv), cg_mesh, field_name(f), settings_name(s), k),
            cg_mesh, f, s, sv, 0.02, k);
        cells.push_back({c, with_body.on(cg_mesh, [sv, f, s, k, budget](const Body& b, Cell& cell) {
                           ModelConfig config = body_config(b, f, s);
                           set_solver(config, sv, 0.02);
                           config.linear.iterations = k;
                           time_cell(config, budget, cell);
                           if (cell.stable) cell.step_error = step_error(config, budget);
                         })});
      }
    }
  }
}

void plan_haptic_rate(const PlanContext& ctx, std::vector<PlannedCell>& cells) {
  const bool quick = ctx.quick;
  const Budget budget = ctx.budget;
  const BodyLookup with_body = ctx.with_body;
  // The haptic rate: co-rotational FEM, physiological, implicit Euler at dt = 1 ms; SOFA's
  // 25 CG iterations from zero against the warm-started haptic-rate CG; 1 and 2 threads.
  const std::vector<std::string> rate_meshes =
      quick ? std::vector<std::string>{"simple"} : std::vector<std::string>{"simple", "medium", "fine"};
  for (const std::string& m : rate_meshes) {
    for (bool warm : {false, true}) {
      for (int threads : {1, 2}) {
        const CorotationalSetup setup{0.001, 25, warm};
        Cell c = corotational_cell("haptic_rate", "", m, setup);
        c.name = fmt::format("haptic_rate/{}/{}/threads{}", m,
                             warm ? std::string(kHapticRateCell) : fmt::format("cg{}", c.iterations), threads);
        c.threads = threads;
        cells.push_back(
            {c, with_body.on_corotational(m, setup, [threads, budget](const Body&, ModelConfig config, Cell& cell) {
               config.threads = threads;
               time_cell(config, budget, cell);
               // The error does not depend on the thread count: measured once.
               if (cell.stable && threads == 1) cell.step_error = step_error(config, budget);
             })});
      }
    }
  }
}

void plan_framework(const PlanContext& ctx, std::vector<PlannedCell>& cells) {
  const bool quick = ctx.quick;
  const BodyLookup with_body = ctx.with_body;
  const std::filesystem::path& out = ctx.out;
  // The whole framework in real time: the thesis' set-up (dt 10 ms, CG 25, the contact force
  // spread over the triangle) and the haptic rate (dt 1 ms, the FEM's reaction felt).
  const double framework_s = quick ? 0.6 : 4.0;
  for (const std::string& m :
       quick ? std::vector<std::string>{"simple"} : std::vector<std::string>{"simple", "medium", "fine"}) {
    for (bool haptic_rate : {false, true}) {
      const CorotationalSetup setup{haptic_rate ? 0.001 : 0.01, 25, haptic_rate, false};
      Cell c = corotational_cell(
          "framework",
          fmt::format("framework/{}/{}", m, haptic_rate ? "haptic-rate-fem-reaction" : "dt10ms-barycentric"), m, setup);
      c.renderer = haptic_rate ? "ruspini, fem-reaction" : "ruspini, barycentric";
      cells.push_back({c, with_body.on_corotational(
                              m, setup, [haptic_rate, framework_s](const Body& b, ModelConfig config, Cell& cell) {
                                time_framework(b, config,
                                               haptic_rate ? coupling::ContactCoupling::kFemReaction
                                                           : coupling::ContactCoupling::kBarycentric,
                                               framework_s, cell);
                              })});
    }
  }
  // ... and with the window open, at the haptic rate on the mesh of the real-time goal.
  {
    const std::string m = quick ? "simple" : "medium";
    const CorotationalSetup setup{0.001, 25, true, false};
    Cell c = corotational_cell("framework", fmt::format("framework/{}/haptic-rate-fem-reaction/window", m), m, setup);
    c.renderer = "ruspini, fem-reaction, window";
    cells.push_back(
        {c, with_body.on_corotational(m, setup, [framework_s, out](const Body& b, ModelConfig config, Cell& cell) {
           time_framework_window(b, config, out, framework_s, cell);
         })});
  }
}

void plan_bodies(const PlanContext& ctx, std::vector<PlannedCell>& cells) {
  const bool quick = ctx.quick;
  const BodyLookup with_body = ctx.with_body;
  // Bodies: one liver against two (thesis set-up: dt 10 ms, CG 25), in virtual time.
  {
    const std::string m = quick ? "simple" : "medium";
    const double seconds = quick ? 0.2 : 2.0;
    for (int count : {1, 2}) {
      const CorotationalSetup setup{0.01, 25, false, false};
      Cell c = corotational_cell("bodies", fmt::format("bodies/{}/livers{}", m, count), m, setup);
      c.bodies = count;
      cells.push_back(
          {c, with_body.on_corotational(m, setup, [count, seconds](const Body& b, ModelConfig config, Cell& cell) {
             time_bodies(b, config, count, seconds, cell);
           })});
    }
  }
}

void plan_coupling(const PlanContext& ctx, std::vector<PlannedCell>& cells) {
  const bool quick = ctx.quick;
  const BodyLookup with_body = ctx.with_body;
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
      cells.push_back({c, with_body.on(m, [mode, reference](const Body& b, Cell& cell) {
                         if (!reference->has_value()) *reference = coupling_reference(b);
                         if (!**reference) {
                           cell.stable = false;
                           cell.failure = (**reference).error().to_string();
                           return;
                         }
                         time_coupling(b, ***reference, mode, cell);
                       })});
    }
  }
}

}  // namespace

std::vector<PlannedCell> plan(bool quick, Bodies& bodies, const std::filesystem::path& out) {
  PlanContext ctx{quick, budget_for(quick), {}, {}, BodyLookup{&bodies}, out};
  ctx.livers =
      quick ? std::vector<std::string>{"simple"} : std::vector<std::string>{"simple", "coarse", "medium", "fine"};
  ctx.meshes = ctx.livers;
  ctx.meshes.push_back("sparse-grid");
  std::vector<PlannedCell> cells;
  plan_meshes(ctx, cells);
  plan_force_fields(ctx, cells);
  plan_solvers(ctx, cells);
  plan_threads(ctx, cells);
  plan_renderers(ctx, cells);
  plan_cg_iterations(ctx, cells);
  plan_haptic_rate(ctx, cells);
  plan_framework(ctx, cells);
  plan_bodies(ctx, cells);
  plan_coupling(ctx, cells);
  return cells;
}

}  // namespace hof::app::bench
