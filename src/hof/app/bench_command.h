#pragma once
/// @file
/// `hof bench --scene FILE`: times the mechanics of any scene (a `.hof` project or a SOFA
/// `.scn`) as fast as it goes — no real-time pacing, no device — and prints steps/s (min,
/// median, max over batches) and the split of a step (forces, assembly, solve). The way to
/// compare with SOFA's `runSofa -g batch -n N FILE` on the same file.

#include <filesystem>

namespace hof::app {

struct BenchOptions {
  std::filesystem::path scene;
  long steps{1000};
  int threads{0};  ///< 0 = all cores
  bool json{false};
};

int run_bench(const BenchOptions& options);

}  // namespace hof::app
