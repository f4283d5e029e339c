#include "hof/app/bench/plots.h"

#include <fmt/format.h>

#include <array>
#include <cmath>
#include <fstream>
#include <map>

#include "hof/app/bench/recipes.h"

namespace hof::app::bench {

namespace {

// Plot data: one .dat per figure beside its PNG/SVG, `?` where a cell was not measured.
std::string dat_value(double v) { return std::isfinite(v) && v > 0.0 ? fmt::format("{:.6g}", v) : "?"; }

void plot_meshes(const std::filesystem::path& dir, const std::vector<Cell>& cells, const std::string& histogram,
                 std::vector<detail::Plot>& plots) {
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
      plots.push_back({"fig29_meshes",
                       histogram +
                           "set ylabel 'count'\nset title 'Figure 29: mesh sizes (the sparse grid counts hexahedra)'\n"
                           "plot 'fig29_meshes.dat' using 2:xtic(1) title 'nodes', '' using 3 title 'elements', "
                           "'' using 4 title 'surface triangles'\n"});
    }
  }
}

void plot_force_fields(const std::filesystem::path& dir, const std::vector<Cell>& cells, const std::string& histogram,
                       std::vector<detail::Plot>& plots) {
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
      plots.push_back(
          {name, histogram +
                     fmt::format("set ylabel 'steps/s (median; unstable cells left out)'\nset title 'Figure 30: force "
                                 "fields, implicit Euler + CG 25, dt 0.02 s, {} settings'\n"
                                 "plot for [k=2:6] '{}.dat' using k:xtic(1) title columnheader(k)\n",
                                 s, name)});
    }
  }
}

void plot_springs_vs_fem(const std::filesystem::path& dir, const std::vector<Ratio>& ratios,
                         std::vector<detail::Plot>& plots) {
  if (!ratios.empty()) {
    std::ofstream d(dir / "fig30_springs_vs_fem.dat");
    d << "case force_field step thesis\n";
    for (const Ratio& r : ratios) {
      d << r.mesh << "/" << r.settings << " " << dat_value(r.force_field) << " " << dat_value(r.step) << " "
        << (r.mesh == "medium" && r.settings == "thesis" ? "2" : "?") << "\n";
    }
    plots.push_back(
        {"fig30_springs_vs_fem",
         "set datafile missing '?'\nset datafile columnheaders\nset style data histograms\nset style histogram cluster "
         "gap 1\nset style fill solid 0.8 border -1\n"
         "set yrange [0:*]\nset ylabel 'springs faster by (x)'\nset title 'Mesh springs against co-rotational FEM "
         "(mesh/settings)'\n"
         "plot 'fig30_springs_vs_fem.dat' using 2:xtic(1) title 'force field own cost (forces + assembly)', "
         "'' using 3 title 'whole step (steps/s)', '' using ($0):4 with points pt 7 ps 2 lc rgb 'black' title 'thesis "
         "(SOFA, Liver Medium)'\n"});
  }
}

void plot_solvers(const std::filesystem::path& dir, const std::vector<Cell>& cells, std::vector<detail::Plot>& plots) {
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
          u << index << " " << (c->measured ? dat_value(c->median) : fmt::format("{:g}", std::pow(2.0, stacked++)))
            << " " << sv << "\n";
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
      std::string body = fmt::format(
          "set datafile missing '?'\nset logscale y\nset xrange [-0.5:{}]\nset yrange [0.7:*]\nset ylabel 'steps/s "
          "(median)'\nset key outside right\n"
          "set title 'Figure 31: solvers on mesh springs (thesis settings), dt {:g} s'\n"
          "plot for [k=3:8] '{}.dat' using 1:k:xtic(2) with linespoints lw 2 pt 7 title columnheader(k)",
          index - 0.5, dt, name);
      if (unstable) {
        body += fmt::format(
            ", '{0}_unstable.dat' using 1:2 with points pt 2 ps 2 lw 2 lc rgb 'red' title 'unstable (diverged)', "
            "'{0}_unstable.dat' using 1:2:3 with labels left offset 1.2,0 tc rgb 'red' notitle",
            name);
      }
      plots.push_back({name, body + "\n"});
    }
  }
}

void plot_threads(const std::filesystem::path& dir, const std::vector<Cell>& cells, const std::string& histogram,
                  std::vector<detail::Plot>& plots) {
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
      plots.push_back(
          {"threads", histogram +
                          "set ylabel 'steps/s (median)'\nset title 'One thread against two: co-rotational FEM, "
                          "implicit Euler + CG 25, dt 0.02 s'\n"
                          "plot 'threads.dat' using 2:xtic(1) title 'one thread', '' using 3 title 'two threads'\n"});
    }
  }
}

void plot_renderers(const std::filesystem::path& dir, const std::vector<Cell>& cells, const std::string& histogram,
                    std::vector<detail::Plot>& plots) {
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
      plots.push_back(
          {"renderers", histogram +
                            "set ylabel 'tick cost p99 (us)'\nset key outside right\nset title 'Haptic renderers, "
                            "one tick (device 3 mm under the top surface)'\n"
                            "plot for [k=2:7] 'renderers.dat' using k:xtic(1) title columnheader(k)\n"});
    }
  }
}

void plot_cg_iterations(const std::filesystem::path& dir, const std::vector<Cell>& cells,
                        std::vector<detail::Plot>& plots) {
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
    for (const auto& [k, r] : rows)
      d << k << " " << dat_value(r[0]) << " " << dat_value(r[1]) << " " << dat_value(r[2]) << " " << dat_value(r[3])
        << "\n";
    if (!rows.empty()) {
      plots.push_back(
          {name,
           fmt::format(
               "set datafile missing '?'\nset xlabel 'CG iterations'\nset ylabel 'steps/s'\nset y2label 'step error "
               "against an exact LDLT solve (relative)'\nset logscale y2\nset y2tics\nset ytics nomirror\n"
               "set key below\nset title 'Figure {}: {} on the {} liver, dt 0.02 s'\n"
               "plot '{}.dat' using 1:2 with linespoints lw 2 pt 7 title 'steps/s, springs (thesis)', "
               "'' using 1:4 with linespoints lw 2 pt 5 title 'steps/s, co-rotational FEM (5 kPa)', "
               "'' using 1:3 axes x1y2 with linespoints dt 2 pt 7 title 'error, springs', "
               "'' using 1:5 axes x1y2 with linespoints dt 2 pt 5 title 'error, co-rotational FEM'\n",
               std::string(sv) == "static-cg" ? 32 : 33, sv, mesh_name, name)});
    }
  }
}

void plot_haptic_rate(const std::filesystem::path& dir, const std::vector<Cell>& cells, const std::string& histogram,
                      std::vector<detail::Plot>& plots) {
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
      plots.push_back(
          {"haptic_rate",
           histogram +
               fmt::format(
                   "set ylabel 'steps/s (median)'\nset key outside right\nset title 'Co-rotational FEM at dt 1 ms "
                   "(5 kPa liver): the haptic rate is 1000 steps/s'\n"
                   "plot 'haptic_rate.dat' using 2:xtic(1) title 'CG 25 from zero, 1 thread', '' using 3 title "
                   "'CG 25 from zero, 2 threads', '' using 4 title 'two-level CG warm, 1 thread', '' using 5 title "
                   "'two-level CG warm, 2 threads', '' using ($0+0.3):6 with points pt 6 ps 2 lw 2 lc rgb 'black' "
                   "title 'goal, 2 threads', 1000 with lines dt 2 lc rgb 'red' title '1 kHz'\n")});
    }
  }
}

void plot_framework(const std::filesystem::path& dir, const std::vector<Cell>& cells, const std::string& histogram,
                    std::vector<detail::Plot>& plots) {
  // Figure 34: the whole framework's rates in the thesis' three states, against real time.
  {
    std::ofstream d(dir / "fig34_framework.dat");
    d << "setup untouched deforming contact real_time\n";
    int rows = 0;
    for (const Cell& c : cells) {
      if (c.section != "framework" || !c.measured) continue;
      const bool window = c.name.ends_with("/window");
      d << fmt::format("\"{} {}{}\" {} {} {} {}\n", c.mesh, c.dt_s < 0.005 ? "1ms" : "10ms", window ? " window" : "",
                       dat_value(c.rate_untouched), dat_value(c.rate_deforming), dat_value(c.rate_contact),
                       dat_value(1.0 / c.dt_s));
      ++rows;
    }
    if (rows) {
      plots.push_back(
          {"fig34_framework",
           histogram + "set ylabel 'simulation steps/s of wall time'\nset key outside right\nset xtics rotate by "
                       "-25\nset yrange [10:*]\n"
                       "set title 'Figure 34: the whole framework in real time (scripted press; mesh, dt, window)'\n"
                       "plot 'fig34_framework.dat' using 2:xtic(1) title 'untouched', '' using 3 title 'deforming', '' "
                       "using 4 title 'in contact', '' using ($0):5 with points pt 6 ps 2 lw 2 lc rgb 'black' title "
                       "'real time (1/dt)'\n"});
    }
  }
}

void plot_coupling(const std::filesystem::path& dir, const std::vector<Cell>& cells, const std::string& histogram,
                   std::vector<detail::Plot>& plots) {
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
      plots.push_back(
          {"coupling",
           histogram +
               "set ylabel '|felt - static FEM reaction| / |reaction| (%)'\nset key outside right\nset yrange "
               "[0.5:*]\nset xtics rotate by -25\n" +
               fmt::format(
                   "set title 'Coupling schemes on the {} liver: the force felt against the static FEM reaction'\n",
                   mesh_name) +
               "plot 'coupling.dat' using 2:xtic(1) title 'largest, during the press', '' using 3 title "
               "'held at 4 mm'\n"});
    }
  }
}

}  // namespace

std::vector<detail::Plot> write_plot_data(const std::filesystem::path& dir, const std::vector<Cell>& cells,
                                          const std::vector<Ratio>& ratios) {
  std::vector<detail::Plot> plots;
  const std::string histogram =
      "set datafile missing '?'\nset datafile columnheaders\nset style data histograms\nset style histogram cluster "
      "gap 1\nset style fill solid 0.8 border -1\n"
      "set boxwidth 0.9\nset logscale y\nset key top left\n";
  plot_meshes(dir, cells, histogram, plots);
  plot_force_fields(dir, cells, histogram, plots);
  plot_springs_vs_fem(dir, ratios, plots);
  plot_solvers(dir, cells, plots);
  plot_threads(dir, cells, histogram, plots);
  plot_renderers(dir, cells, histogram, plots);
  plot_cg_iterations(dir, cells, plots);
  plot_haptic_rate(dir, cells, histogram, plots);
  plot_framework(dir, cells, histogram, plots);
  plot_coupling(dir, cells, histogram, plots);
  return plots;
}

}  // namespace hof::app::bench
