#include "hof/app/bench_command.h"

#include <fmt/format.h>

#include <algorithm>
#include <chrono>
#include <cstdio>
#include <vector>

#include "hof/mechanics/step.h"
#include "hof/scene/project.h"
#include "hof/scene/sofa_scene.h"

namespace hof::app {

int run_bench(const BenchOptions& options) {
  std::filesystem::path scene_path = options.scene;
  if (options.scene.extension() == ".hof") {
    auto project = scene::read_project(options.scene);
    if (!project) {
      std::fprintf(stderr, "hof: %s\n", project.error().to_string().c_str());
      return 1;
    }
    scene_path = scene::scene_file(*project, options.scene);
  }
  auto sofa = scene::read_sofa_scene(scene_path);
  if (!sofa) {
    std::fprintf(stderr, "hof: %s\n", sofa.error().to_string().c_str());
    return 1;
  }
  if (sofa->models.empty()) {
    std::fprintf(stderr, "hof: %s: no simulated body in the scene\n", scene_path.c_str());
    return 1;
  }
  if (options.steps < 10) {
    std::fprintf(stderr, "hof: --steps must be at least 10\n");
    return 1;
  }
  for (const scene::SofaSceneModel& m : sofa->models) {
    mechanics::ModelConfig config = m.config;
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
      rates.push_back(static_cast<double>(per_batch) / std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count());
    }
    std::sort(rates.begin(), rates.end());
    const double median = 0.5 * (rates[rates.size() / 2 - 1] + rates[rates.size() / 2]);
    const double n = static_cast<double>(done);
    if (options.json) {
      std::printf("{\"scene\": \"%s\", \"model\": \"%s\", \"nodes\": %zu, \"tetrahedra\": %zu, \"steps\": %ld, "
                  "\"steps_per_s\": {\"min\": %.1f, \"median\": %.1f, \"max\": %.1f}, "
                  "\"split_us\": {\"forces\": %.2f, \"assembly\": %.2f, \"solve\": %.2f}}\n",
                  scene_path.c_str(), m.node_path.c_str(), model->node_count(), model->tets.size(), done, rates.front(), median,
                  rates.back(), 1e6 * force / n, 1e6 * assembly / n, 1e6 * solve / n);
    } else {
      std::printf("%s: model '%s' (%zu nodes, %zu tetrahedra), %ld steps of %.4g s\n", scene_path.c_str(),
                  m.node_path.c_str(), model->node_count(), model->tets.size(), done, model->dt_s);
      std::printf("  steps/s   min %.1f, median %.1f, max %.1f\n", rates.front(), median, rates.back());
      std::printf("  per step  forces %.1f us, assembly %.1f us, solve %.1f us\n", 1e6 * force / n, 1e6 * assembly / n,
                  1e6 * solve / n);
    }
  }
  return 0;
}

}  // namespace hof::app
