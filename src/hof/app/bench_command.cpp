#include "hof/app/bench_command.h"

#include <fmt/format.h>

#include <algorithm>
#include <chrono>
#include <cstdio>
#include <vector>

#include "hof/mechanics/step.h"
#include "hof/scene/world.h"

namespace hof::app {

int run_bench(const BenchOptions& options) {
  if (options.steps < 10) {
    std::fprintf(stderr, "hof: --steps must be at least 10\n");
    return 1;
  }
  if (options.threads < 0) {
    std::fprintf(stderr, "hof: --threads must be >= 0 (0 = all cores)\n");
    return 1;
  }
  // The one builder, as `hof run` and `hof check` use it.
  auto world = scene::build_world(options.scene);
  if (!world) {
    std::fprintf(stderr, "hof: %s\n", world.error().to_string().c_str());
    return 1;
  }
  const std::filesystem::path& scene_path = world->scene_path;
  bool any = false;
  for (const coupling::SessionBody& body : world->bodies) {
    if (!body.deformable() || !body.config) continue;
    any = true;
    mechanics::ModelConfig config = *body.config;
    const std::string& node_path = body.name;
    config.threads = options.threads;
    auto model = mechanics::build_model(config);
    if (!model) {
      std::fprintf(stderr, "hof: %s\n", model.error().to_string().c_str());
      return 1;
    }
    mechanics::MechanicalState state = mechanics::make_state(*model);
    // Ten batches: steps/s of each gives min/median/max; the split is summed over all steps.
    const long batches = 10;
    const long per_batch = std::max(1L, options.steps / batches);
    std::vector<double> rates;
    double force = 0, assembly = 0, solve = 0;
    long done = 0;
    for (long b = 0; b < batches; ++b) {
      const auto t0 = std::chrono::steady_clock::now();
      for (long i = 0; i < per_batch; ++i) {
        if (!mechanics::step(*model, state)) {
          std::fprintf(stderr, "hof: %s diverged at step %lld: %s\n", state.divergence.component.c_str(),
                       static_cast<long long>(state.divergence.step), state.divergence.reason.c_str());
          return 2;
        }
        force += state.stats.force_s;
        assembly += state.stats.assembly_s;
        solve += state.stats.solve_s;
        ++done;
      }
      rates.push_back(static_cast<double>(per_batch) /
                      std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count());
    }
    std::sort(rates.begin(), rates.end());
    const double median = 0.5 * (rates[rates.size() / 2 - 1] + rates[rates.size() / 2]);
    const double n = static_cast<double>(done);
    if (options.json) {
      std::printf(
          "{\"scene\": \"%s\", \"model\": \"%s\", \"nodes\": %zu, \"tetrahedra\": %zu, \"hexahedra\": %zu, "
          "\"triangles\": %zu, \"steps\": %ld, "
          "\"steps_per_s\": {\"min\": %.1f, \"median\": %.1f, \"max\": %.1f}, "
          "\"split_us\": {\"forces\": %.2f, \"assembly\": %.2f, \"solve\": %.2f}}\n",
          scene_path.c_str(), node_path.c_str(), model->node_count(), model->tets.size(), model->hexahedra.size(),
          model->tets.empty() && model->hexahedra.empty() ? model->triangles.size() : std::size_t{0}, done,
          rates.front(), median, rates.back(), 1e6 * force / n, 1e6 * assembly / n, 1e6 * solve / n);
    } else {
      const std::string elements = model->element_summary();
      std::printf("%s: model '%s' (%zu nodes, %s), %ld steps of %.4g s\n", scene_path.c_str(), node_path.c_str(),
                  model->node_count(), elements.c_str(), done, model->dt_s);
      std::printf("  steps/s   min %.1f, median %.1f, max %.1f\n", rates.front(), median, rates.back());
      std::printf("  per step  forces %.1f us, assembly %.1f us, solve %.1f us\n", 1e6 * force / n, 1e6 * assembly / n,
                  1e6 * solve / n);
    }
  }
  if (!any) {
    std::fprintf(stderr, "hof: %s: no deformable body to time (the world has only rigid shapes or force effects)\n",
                 options.scene.c_str());
    return 1;
  }
  return 0;
}

}  // namespace hof::app
