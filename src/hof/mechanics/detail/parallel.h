#pragma once
/// @file
/// Deterministic data-parallel loops for the mechanics. Work is cut into fixed chunks that do
/// not depend on the number of threads, and reductions add the per-chunk partial sums in chunk
/// order, so results are bitwise identical for 1, 2 or N threads.

#include <tbb/blocked_range.h>
#include <tbb/parallel_for.h>
#include <tbb/partitioner.h>

#include <algorithm>
#include <cstddef>
#include <vector>

namespace hof::mechanics {

/// Below this many items a loop runs serially: thread start-up would cost more than it saves.
inline constexpr std::size_t kParallelThreshold = 2048;

/// Calls body(begin, end) over [0, n) in chunks of `chunk` items, in parallel when n reaches
/// `min_parallel` (lower it for loops whose items are expensive, such as elements).
template <class Body>
void parallel_chunks(std::size_t n, std::size_t chunk, const Body& body,
                     std::size_t min_parallel = kParallelThreshold) {
  if (n == 0) return;
  const std::size_t chunks = (n + chunk - 1) / chunk;
  if (n < min_parallel || chunks == 1) {
    body(std::size_t{0}, n);
    return;
  }
  tbb::parallel_for(
      tbb::blocked_range<std::size_t>(0, chunks),
      [&](const tbb::blocked_range<std::size_t>& r) {
        for (std::size_t c = r.begin(); c != r.end(); ++c) {
          body(c * chunk, std::min(n, (c + 1) * chunk));
        }
      },
      tbb::static_partitioner());
}

/// Sum over [0, n) of term(begin, end) per fixed chunk, added in chunk order (deterministic).
/// `partials` is caller-owned scratch so that the loop does not allocate.
template <class Term>
double deterministic_sum(std::size_t n, std::size_t chunk, std::vector<double>& partials, const Term& term) {
  if (n == 0) return 0.0;
  const std::size_t chunks = (n + chunk - 1) / chunk;
  if (partials.size() < chunks) partials.resize(chunks);
  auto run = [&](std::size_t c) { partials[c] = term(c * chunk, std::min(n, (c + 1) * chunk)); };
  if (n < kParallelThreshold || chunks == 1) {
    for (std::size_t c = 0; c < chunks; ++c) run(c);
  } else {
    tbb::parallel_for(
        tbb::blocked_range<std::size_t>(0, chunks),
        [&](const tbb::blocked_range<std::size_t>& r) {
          for (std::size_t c = r.begin(); c != r.end(); ++c) run(c);
        },
        tbb::static_partitioner());
  }
  double sum = 0.0;
  for (std::size_t c = 0; c < chunks; ++c) sum += partials[c];
  return sum;
}

}  // namespace hof::mechanics
