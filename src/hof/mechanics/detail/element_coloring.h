#pragma once
/// @file
/// Greedy colouring of elements so that no two elements of one colour share a node. Element
/// loops that scatter into node forces or matrix blocks run one colour after the other, each
/// colour in parallel, with plain stores (no atomics, no locks) and in an order that does not
/// depend on the number of threads, so sums are bitwise reproducible.

#include <array>
#include <cstddef>
#include <cstdint>
#include <span>
#include <vector>

#include "hof/mechanics/detail/parallel.h"

namespace hof::mechanics {

struct ElementColoring {
  std::vector<std::int32_t> order;        ///< (E) element indices grouped by colour, ascending within
  std::vector<std::int32_t> color_start;  ///< (colours+1) offsets into `order`

  [[nodiscard]] std::size_t colors() const { return color_start.empty() ? 0 : color_start.size() - 1; }

  /// Runs body(element) for every element, colour by colour, each colour in parallel.
  template <class Body>
  void for_each(const Body& body) const {
    for (std::size_t c = 0; c + 1 < color_start.size(); ++c) {
      const std::size_t first = static_cast<std::size_t>(color_start[c]);
      const std::size_t count = static_cast<std::size_t>(color_start[c + 1]) - first;
      parallel_chunks(
          count, 32,
          [&](std::size_t b, std::size_t e) {
            for (std::size_t i = b; i < e; ++i) body(order[first + i]);
          },
          /*min_parallel=*/128);
    }
  }
};

/// Colours elements given as fixed-size node lists (K nodes each).
template <std::size_t K>
ElementColoring color_elements(std::span<const std::array<std::int32_t, K>> elements, std::size_t node_count) {
  // Each node remembers the colours of its elements as a bit mask (first 64 colours), with a
  // slow path beyond. Meshes of tetrahedra need about 20-40 colours.
  std::vector<std::uint64_t> used(node_count, 0);
  std::vector<std::int32_t> color(elements.size(), -1);
  std::int32_t colors = 0;
  std::vector<std::vector<std::int32_t>> overflow_used;  // colours >= 64, per node (rare)
  for (std::size_t e = 0; e < elements.size(); ++e) {
    std::uint64_t mask = 0;
    for (std::int32_t n : elements[e]) mask |= used[n];
    std::int32_t c = 0;
    if (~mask != 0) {
      c = static_cast<std::int32_t>(__builtin_ctzll(~mask));
    } else {
      if (overflow_used.empty()) overflow_used.resize(node_count);
      c = 64;
      bool clash = true;
      while (clash) {
        clash = false;
        for (std::int32_t n : elements[e]) {
          for (std::int32_t u : overflow_used[n]) clash = clash || u == c;
        }
        if (clash) ++c;
      }
    }
    color[e] = c;
    colors = std::max(colors, c + 1);
    for (std::int32_t n : elements[e]) {
      if (c < 64)
        used[n] |= std::uint64_t{1} << c;
      else
        overflow_used[n].push_back(c);
    }
  }
  ElementColoring out;
  out.color_start.assign(static_cast<std::size_t>(colors) + 1, 0);
  for (std::int32_t c : color) ++out.color_start[c + 1];
  for (std::size_t c = 0; c < static_cast<std::size_t>(colors); ++c) out.color_start[c + 1] += out.color_start[c];
  out.order.resize(elements.size());
  std::vector<std::int32_t> next(out.color_start.begin(), out.color_start.end() - 1);
  for (std::size_t e = 0; e < elements.size(); ++e) out.order[next[color[e]]++] = static_cast<std::int32_t>(e);
  return out;
}

}  // namespace hof::mechanics
