#include "hof/app/bench/goals.h"

#include <fmt/format.h>

#include "hof/app/bench/recipes.h"

namespace hof::app::bench {

const Cell* find(const std::vector<Cell>& cells, const std::string& name) {
  for (const Cell& c : cells) {
    if (c.name == name) return &c;
  }
  return nullptr;
}

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

std::vector<Goal> goals(const std::vector<Cell>& cells, const std::vector<Ratio>& ratios) {
  std::vector<Goal> out;
  const std::string warm = kHapticRateCell;
  auto rate = [&](const std::string& m, int threads) {
    const Cell* c = find(cells, fmt::format("haptic_rate/{}/{}/threads{}", m, warm, threads));
    return c && c->measured && c->stable ? c->median : kNaN;
  };
  out.push_back({"medium liver, co-rotational FEM, dt 1 ms, one thread (a session's simulation core)", "steps/s",
                 1000.0, rate("medium", 1)});
  out.push_back({"medium liver, two threads", "steps/s", 2000.0, rate("medium", 2)});
  out.push_back({"fine liver, two threads", "steps/s", 500.0, rate("fine", 2)});
  out.push_back({"simple liver, two threads", "steps/s", 20000.0, rate("simple", 2)});
  if (const Cell* rt = find(cells, "framework/medium/haptic-rate-fem-reaction"); rt && rt->measured && rt->stable) {
    out.push_back({"medium liver in a real-time session at dt 1 ms (fem-reaction): simulated time kept with wall time",
                   "x", 1.0, rt->simulated_s / rt->wall_s});
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
    out.push_back({fmt::format("{} liver: step error of the haptic-rate CG at most that of 25 cold iterations ({:.3g})",
                               m, cold->step_error),
                   "relative", cold->step_error, w->step_error, false});
  }
  for (const Ratio& r : ratios) {
    out.push_back(
        {fmt::format(
             "{} liver, {} settings: co-rotational FEM / springs, force field's own cost (thesis: springs 2x faster)",
             r.mesh, r.settings),
         "x", 2.0, r.force_field});
  }
  return out;
}

}  // namespace hof::app::bench
