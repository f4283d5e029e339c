#include "hof/app/bench/report.h"

#include <fmt/format.h>
#include <sys/utsname.h>

#include <algorithm>
#include <cmath>
#include <fstream>
#include <nlohmann/json.hpp>
#include <thread>

#include "hof/mechanics/mechanical_model.h"

namespace hof::app::bench {

using mechanics::kHapticRateCgIterations;

namespace {

std::string number(double v, const char* format = "{:.4g}") {
  return std::isfinite(v) ? fmt::format(fmt::runtime(format), v) : "-";
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
          {"realtime",
           {{"simulated_s", num(c.simulated_s)},
            {"wall_s", num(c.wall_s)},
            {"rate_untouched", num(c.rate_untouched)},
            {"rate_deforming", num(c.rate_deforming)},
            {"rate_in_contact", num(c.rate_contact)},
            {"frames_per_s", num(c.frames_per_s)}}},
          {"bodies", c.bodies},
          {"force_error", num(c.force_error)},
          {"force_error_settled", num(c.force_error_settled)}};
}

std::string rate_text(const Cell& c) {
  if (!c.measured) return c.stable ? "-" : "unstable";
  // Whole steps/s where they are many, three digits where a step takes seconds.
  const char* format = c.min >= 100.0 ? "{:.0f}" : "{:.3g}";
  return fmt::format("{} [{}..{}]{}", number(c.median, format), number(c.min, format), number(c.max, format),
                     c.stable ? "" : " unstable");
}

void meshes_table(const std::vector<const Cell*>& m, std::string& out) {
  out += "## Meshes (thesis Figure 29)\n\n| mesh | nodes | elements | surface triangles |\n|---|---:|---:|---:|\n";
  for (const Cell* c : m)
    out += fmt::format("| {} | {} | {} {} | {} |\n", c->mesh, c->nodes, c->elements,
                       c->mesh == "sparse-grid" ? "hexahedra" : "tetrahedra", c->triangles);
  out += "\n";
}

void force_fields_table(const std::vector<const Cell*>& f, std::string& out) {
  out +=
      "## Force fields (thesis Figure 30): implicit Euler, CG 25, dt 0.02 s\n\nsteps/s median [min..max]; the split is "
      "per step (forces / assembly / solve, us).\n\n";
  if (std::ranges::any_of(f, [](const Cell* c) { return c->settings == "thesis" && !c->stable; })) {
    out +=
        "With the thesis' settings the FEM models collapse: E = 100 Pa cannot carry a 1 kg liver of this size under "
        "gravity (the stress of its own weight is about a hundred times E), so a node soon leaves by a metre. The "
        "thesis' scenes were unit-free; its numbers do not carry over to SI. Their rates, until the collapse, are "
        "shown and marked; the physiological rows are the comparison that holds.\n\n";
  }
  out += "| settings | mesh | force field | steps/s | forces | assembly | solve |\n|---|---|---|---|---:|---:|---:|\n";
  for (const Cell* c : f) {
    out += fmt::format("| {} | {} | {} | {} | {} | {} | {} |\n", c->settings, c->mesh, c->field, rate_text(*c),
                       number(c->forces_us, "{:.1f}"), number(c->assembly_us, "{:.1f}"), number(c->solve_us, "{:.1f}"));
  }
  out += "\n";
}

void ratios_table(const std::vector<Ratio>& ratios, std::string& out) {
  out +=
      "### Springs against co-rotational FEM (where both ran stably)\n\n| settings | mesh | FEM / springs, force "
      "field's own "
      "cost | springs / FEM, whole step |\n|---|---|---:|---:|\n";
  for (const Ratio& r : ratios) {
    out += fmt::format("| {} | {} | {} | {} |\n", r.settings, r.mesh, number(r.force_field, "{:.2f}"),
                       number(r.step, "{:.2f}"));
  }
  out +=
      "\nThe thesis measured springs about twice as fast as co-rotational FEM on Liver Medium (l. 1262): SOFA's "
      "matrix-free CG re-applied each element's stiffness at every iteration, so the force field's cost was paid 25 "
      "times per step. HoF assembles one matrix with the same pattern for both models and solves it once, so the "
      "shared solve hides the difference in the whole step; the force field's own cost (forces + assembly) is where "
      "the models differ.\n\n";
}

void solvers_table(const std::vector<const Cell*>& s, std::string& out) {
  out +=
      "## Solvers (thesis Figure 31): mesh springs, thesis settings\n\n| dt (s) | mesh | solver | steps/s | stable "
      "over |\n"
      "|---:|---|---|---|---|\n";
  for (const Cell* c : s) {
    out += fmt::format("| {:g} | {} | {} | {} | {} |\n", c->dt_s, c->mesh, c->solver, rate_text(*c),
                       c->stable ? fmt::format("{:.3g} s", c->stable_over_s)
                                 : fmt::format("diverged after {:.3g} s: {}", c->stable_over_s, c->failure));
  }
  out += "\n";
}

void threads_table(const std::vector<const Cell*>& t, const std::vector<Cell>& cells, std::string& out) {
  out +=
      "## Threads (thesis: the OpenMP test): co-rotational FEM, physiological, implicit Euler, CG 25, dt 0.02 s\n\n"
      "| mesh | threads | steps/s | forces | assembly | solve (us) | speed-up |\n|---|---:|---|---:|---:|---:|---:|\n";
  for (const Cell* c : t) {
    const Cell* one = find(cells, fmt::format("threads/{}/corotational-fem/threads1", c->mesh));
    out += fmt::format("| {} | {} | {} | {} | {} | {} | {} |\n", c->mesh, c->threads, rate_text(*c),
                       number(c->forces_us, "{:.0f}"), number(c->assembly_us, "{:.0f}"), number(c->solve_us, "{:.0f}"),
                       one && one->measured ? number(c->median / one->median, "{:.2f}x") : std::string("-"));
  }
  out += "\n";
}

void renderers_table(const std::vector<const Cell*>& r, std::string& out) {
  out +=
      "## Haptic renderers: the cost of one tick (thesis: useBoundTree)\n\nThe device slides 3 mm under the liver's "
      "top, "
      "the surface at rest.\n\n| mesh | renderer | bound tree | tick p50 (us) | p99 | max | ticks in contact |\n"
      "|---|---|---|---:|---:|---:|---:|\n";
  for (const Cell* c : r) {
    out += fmt::format(
        "| {} | {} | {} | {} | {} | {} | {} |\n", c->mesh, c->renderer, c->bound_tree ? "on" : "off",
        number(c->tick_p50_us, "{:.2f}"), number(c->tick_p99_us, "{:.2f}"), number(c->tick_max_us, "{:.1f}"),
        std::isfinite(c->contact_fraction) ? fmt::format("{:.0f}%", 100.0 * c->contact_fraction) : std::string("-"));
  }
  out += "\n";
}

void cg_iterations_table(const std::vector<const Cell*>& g, std::string& out) {
  out +=
      "## CG iterations (thesis Figures 32–33): dt 0.02 s\n\n| solver | mesh | model | CG iterations | steps/s | step "
      "error vs LDLT | stable |\n"
      "|---|---|---|---:|---|---:|---|\n";
  for (const Cell* c : g) {
    out += fmt::format("| {} | {} | {} {} | {} | {} | {} | {} |\n", c->solver, c->mesh, c->field, c->settings,
                       c->iterations, rate_text(*c), number(c->step_error, "{:.3g}"), c->stable ? "yes" : "no");
  }
  out += "\n";
}

void haptic_rate_table(const std::vector<const Cell*>& h, std::string& out) {
  out +=
      "## The haptic rate: co-rotational FEM, physiological, implicit Euler, dt 1 ms\n\n| mesh | CG | threads | "
      "steps/s | "
      "step error vs LDLT | split forces / assembly / solve (us) |\n|---|---|---:|---|---:|---|\n";
  for (const Cell* c : h) {
    out += fmt::format(
        "| {} | {}{} | {} | {} | {} | {} / {} / {} |\n", c->mesh, c->iterations,
        !c->warm_start
            ? std::string(" from zero")
            : fmt::format(" warm-started{}, matrix every {}", c->coarse_correction ? ", two-level" : "",
                          c->matrix_reuse > 1 ? fmt::format("{} steps", c->matrix_reuse) : std::string("step")),
        c->threads, rate_text(*c), number(c->step_error, "{:.3g}"), number(c->forces_us, "{:.0f}"),
        number(c->assembly_us, "{:.0f}"), number(c->solve_us, "{:.0f}"));
  }
  out += "\n";
}

void framework_table(const std::vector<const Cell*>& w, std::string& out) {
  out +=
      "## The whole framework in real time (thesis Figure 34): haptic loop and simulation on their threads\n\n"
      "A scripted hand presses the liver's top (co-rotational FEM, 5 kPa) from 1 cm above and holds. Rates are "
      "simulation "
      "steps per second of wall time; real time is 1/dt. The window row draws the same press in `hof gui` (a project "
      "written to DIR/window), the three loops sharing the cores.\n\n"
      "| mesh | set-up | dt (s) | steps/s | simulated / wall | untouched / deforming / in contact (steps/s) | haptic "
      "period "
      "p50 / p99 / max (us) | in contact | window frames/s |\n|---|---|---:|---:|---:|---|---|---:|---:|\n";
  for (const Cell* c : w) {
    const bool window = c->name.ends_with("/window");
    if (window && !c->measured) {
      out += fmt::format("| {} | haptic rate, fem-reaction, window | {:g} | not measured: {} |||||\n", c->mesh, c->dt_s,
                         c->failure);
      continue;
    }
    out += fmt::format(
        "| {} | {}{} | {:g} | {} | {} | {} / {} / {} | {} / {} / {} | {} | {} |\n", c->mesh,
        c->dt_s < 0.005 ? "haptic rate, fem-reaction" : "dt 10 ms, barycentric", window ? ", window" : "", c->dt_s,
        number(c->median, "{:.0f}"),
        std::isfinite(c->simulated_s) && c->wall_s > 0.0 ? fmt::format("{:.2f}", c->simulated_s / c->wall_s)
                                                         : std::string("-"),
        number(c->rate_untouched, "{:.0f}"), number(c->rate_deforming, "{:.0f}"), number(c->rate_contact, "{:.0f}"),
        number(c->tick_p50_us, "{:.0f}"), number(c->tick_p99_us, "{:.0f}"), number(c->tick_max_us, "{:.0f}"),
        std::isfinite(c->contact_fraction) ? fmt::format("{:.0f}%", 100.0 * c->contact_fraction) : std::string("-"),
        number(c->frames_per_s, "{:.0f}"));
  }
  out += "\n";
}

void bodies_table(const std::vector<const Cell*>& bs, const std::vector<Cell>& cells, std::string& out) {
  out +=
      "## Bodies: one liver against two\n\nCo-rotational FEM, 5 kPa, implicit Euler, CG 25, dt 10 ms; the livers side "
      "by "
      "side, the first pressed; virtual time (the haptic loop ticks in lock-step), so the rate is the machine's. The "
      "bodies "
      "of a world step in parallel.\n\n| mesh | livers | world steps/s | liver steps/s | cost of a world step against "
      "one liver |\n"
      "|---|---:|---:|---:|---:|\n";
  for (const Cell* c : bs) {
    const Cell* one = find(cells, fmt::format("bodies/{}/livers1", c->mesh));
    out += fmt::format(
        "| {} | {} | {} | {} | {} |\n", c->mesh, c->bodies,
        c->measured ? number(c->median, "{:.0f}") : (c->stable ? "-" : "unstable"),
        number(c->median * c->bodies, "{:.0f}"),
        one && one->measured && c->measured ? number(one->median / c->median, "{:.2f}x") : std::string("-"));
  }
  out += "\n";
}

void coupling_table(const std::vector<const Cell*>& cs, std::string& out) {
  out +=
      "## Coupling schemes against the static FEM reaction\n\nA slow press (4 mm at 4 mm/s, then held 0.6 s) straight "
      "down "
      "onto the top's surface node of the co-rotational liver (5 kPa, Rayleigh 1.0 / 0.1), god-object proxy at the "
      "device's "
      "stiffest (2,000 N/m), virtual time. The reference is the static FEM solve (LDLT) with that node held at the "
      "device's "
      "depth. Errors are |felt - reaction| / |reaction|: the largest at 1, 2, 3 and 4 mm during the press (the "
      "tissue's "
      "damping still adds to the felt force), and at 4 mm once held. The reference holds the node in all three "
      "directions "
      "while the frictionless proxy slides on the tilting surface, so a sideways part of the difference is there by "
      "construction. closest-vertex and barycentric render the proxy's spring: at dt 20 ms the spring, far stiffer "
      "than the "
      "tissue under it, and the tissue exchange their force a step apart, and the felt force swings around the "
      "reaction; "
      "compliance renders the FEM's local response at 1 kHz; fem-reaction steps the FEM at 1 kHz and renders its own "
      "elastic force. Cost: simulation steps per second of wall time, and wall time per simulated second.\n\n"
      "| mesh | scheme | dt (s) | error during the press | error held at 4 mm | steps/s | wall s per simulated s |\n"
      "|---|---|---:|---:|---:|---:|---:|\n";
  auto percent = [](double v) { return std::isfinite(v) ? fmt::format("{:.1f}%", 100.0 * v) : std::string("-"); };
  for (const Cell* c : cs) {
    const std::string scheme = c->name.substr(c->name.rfind('/') + 1);
    out += fmt::format(
        "| {} | {} | {:g} | {} | {} | {} | {} |\n", c->mesh, scheme, c->dt_s,
        std::isfinite(c->force_error) || c->failure.empty() ? percent(c->force_error) : c->failure,
        percent(c->force_error_settled), c->measured ? number(c->median, "{:.0f}") : std::string("-"),
        c->measured && c->simulated_s > 0.0 ? number(c->wall_s / c->simulated_s, "{:.2f}") : std::string("-"));
  }
  out += "\n";
}

void goals_table(const std::vector<Goal>& goal_list, std::string& out) {
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

}  // namespace

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

// Markdown tables (also printed on stdout: they read as plain text too).
std::string tables(const std::vector<Cell>& cells, const std::vector<Ratio>& ratios,
                   const std::vector<Goal>& goal_list) {
  std::string out;
  auto section = [&](const char* name) {
    std::vector<const Cell*> in;
    for (const Cell& c : cells) {
      if (c.section == name) in.push_back(&c);
    }
    return in;
  };
  if (auto m = section("meshes"); !m.empty()) meshes_table(m, out);
  if (auto f = section("force_fields"); !f.empty()) force_fields_table(f, out);
  if (!ratios.empty()) ratios_table(ratios, out);
  if (auto s = section("solvers"); !s.empty()) solvers_table(s, out);
  if (auto t = section("threads"); !t.empty()) threads_table(t, cells, out);
  if (auto r = section("renderers"); !r.empty()) renderers_table(r, out);
  if (auto g = section("cg_iterations"); !g.empty()) cg_iterations_table(g, out);
  if (auto h = section("haptic_rate"); !h.empty()) haptic_rate_table(h, out);
  if (auto w = section("framework"); !w.empty()) framework_table(w, out);
  if (auto bs = section("bodies"); !bs.empty()) bodies_table(bs, cells, out);
  if (auto cs = section("coupling"); !cs.empty()) coupling_table(cs, out);
  if (!goal_list.empty()) goals_table(goal_list, out);
  return out;
}

std::string csv(const std::vector<Cell>& cells) {
  std::string out =
      "section,name,mesh,field,settings,solver,dt_s,cg_iterations,warm_start,threads,nodes,elements,surface_triangles,"
      "steps_per_s_median,steps_per_s_min,steps_per_s_max,timed_steps,stable,stable_over_s,step_error,forces_us,"
      "assembly_us,"
      "solve_us,renderer,bound_tree,tick_p50_us,tick_p99_us,tick_max_us,contact_fraction,bodies,force_error,force_"
      "error_settled,frames_per_s\n";
  auto n = [](double v) { return std::isfinite(v) ? fmt::format("{:.9g}", v) : std::string(); };
  for (const Cell& c : cells) {
    out += fmt::format(
        "{},{},{},{},{},{},{},{},{},{},{},{},{},{},{},{},{},{},{},{},{},{},{},{},{},{},{},{},{},{},{},{},{}\n",
        c.section, c.name, c.mesh, c.field, c.settings, c.solver, n(c.dt_s), c.iterations, c.warm_start ? 1 : 0,
        c.threads, c.nodes, c.elements, c.triangles, n(c.median), n(c.min), n(c.max), c.steps, c.stable ? 1 : 0,
        n(c.stable_over_s), n(c.step_error), n(c.forces_us), n(c.assembly_us), n(c.solve_us), c.renderer,
        c.renderer.empty() ? "" : (c.bound_tree ? "1" : "0"), n(c.tick_p50_us), n(c.tick_p99_us), n(c.tick_max_us),
        n(c.contact_fraction), c.bodies, n(c.force_error), n(c.force_error_settled), n(c.frames_per_s));
  }
  return out;
}

std::string results_json(const RunInfo& run, const std::vector<Cell>& cells, const std::vector<Ratio>& ratios,
                         const std::vector<Goal>& goal_list) {
  nlohmann::json results = {{"command", run.command_line},
                            {"date", run.date},
                            {"machine", run.machine},
                            {"quick", run.quick},
                            {"only", run.only},
                            {"seconds", run.seconds},
                            {"haptic_rate_cg_iterations", kHapticRateCgIterations},
                            {"cells", nlohmann::json::array()},
                            {"springs_vs_fem", nlohmann::json::array()},
                            {"goals", nlohmann::json::array()}};
  for (const Cell& c : cells) results["cells"].push_back(cell_json(c));
  for (const Ratio& r : ratios) {
    results["springs_vs_fem"].push_back(
        {{"settings", r.settings},
         {"mesh", r.mesh},
         {"fem_over_springs_force_field_cost",
          std::isfinite(r.force_field) ? nlohmann::json(r.force_field) : nlohmann::json()},
         {"springs_over_fem_step_rate", std::isfinite(r.step) ? nlohmann::json(r.step) : nlohmann::json()}});
  }
  for (const Goal& g : goal_list) {
    results["goals"].push_back({{"goal", g.what},
                                {"unit", g.unit},
                                {"target", std::isfinite(g.target) ? nlohmann::json(g.target) : nlohmann::json()},
                                {"measured", g.known() ? nlohmann::json(g.measured) : nlohmann::json()},
                                {"met", g.known() ? nlohmann::json(g.met()) : nlohmann::json()}});
  }

  return results.dump(2) + "\n";
}

std::string report_markdown(const RunInfo& run, const std::string& table_text, const std::vector<detail::Plot>& plots,
                            const std::vector<std::string>& failed) {
  const Budget budget = budget_for(run.quick);
  std::string report = fmt::format(
      "# HoF evaluation\n\nMade by `{}` on {} in {:.0f} s.\n\nMachine: {}.\n\n"
      "Each cell: steps/s as the median [min..max] of {} timed batches of at least {} s; stable means no divergence "
      "and no node "
      "moving more than 1 m over {} s of simulated time (or as much as {} s of checking allowed). Step errors are "
      "against an "
      "exact LDLT solve of the same step from the same state (relative norm of the velocity change; of the "
      "displacement for "
      "the static solver). Thesis settings: gravity 9.8, total mass 1 kg, springs 10,000 / 15, FEM E = 100, nu = 0.4 "
      "(unit-free in SOFA, here SI on a liver in metres); physiological: E = 5 kPa, nu = 0.45, 1060 kg/m3. Every body "
      "rests "
      "on its lowest 4 mm.\n\n",
      run.command_line, run.date, run.seconds, run.machine, budget.batches, budget.batch_s, budget.horizon_s,
      budget.stability_wall_s);
  report += table_text;
  report += "## Plots\n\n";
  for (const detail::Plot& p : plots) {
    if (std::find(failed.begin(), failed.end(), p.name) == failed.end())
      report += fmt::format("![{0}]({0}.png)\n\n", p.name);
  }
  report +=
      "## Not measured by this version\n\nSOFA side by side: `hof bench --scene FILE` runs a SOFA scene as `runSofa -g "
      "batch -n N "
      "FILE` does; run both on the same machine to compare (SOFA is not a Debian package, so this run cannot). The "
      "window "
      "row needs a display: without one it is listed as not measured.\n";

  return report;
}

}  // namespace hof::app::bench
