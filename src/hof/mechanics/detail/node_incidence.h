#pragma once
/// @file
/// For each node, the elements that use it and at which corner: the map that lets force and
/// stiffness assembly run as a gather over nodes (each node's force and each block row of the
/// matrix written by exactly one thread, in a fixed order), with no atomics, no colouring and
/// results that do not depend on the number of threads.

#include <array>
#include <cstddef>
#include <cstdint>
#include <span>
#include <vector>

namespace hof::mechanics {

struct NodeIncidence {
  std::vector<std::int32_t> start;    ///< (N+1) offsets into `entries`
  std::vector<std::int32_t> entries;  ///< element·K + corner, by node, elements ascending

  [[nodiscard]] std::span<const std::int32_t> of(std::size_t node) const {
    return {entries.data() + start[node], static_cast<std::size_t>(start[node + 1] - start[node])};
  }
};

template <std::size_t K>
NodeIncidence make_node_incidence(std::span<const std::array<std::int32_t, K>> elements, std::size_t node_count) {
  NodeIncidence out;
  out.start.assign(node_count + 1, 0);
  for (const auto& e : elements) {
    for (std::int32_t n : e) ++out.start[static_cast<std::size_t>(n) + 1];
  }
  for (std::size_t n = 0; n < node_count; ++n) out.start[n + 1] += out.start[n];
  out.entries.resize(static_cast<std::size_t>(out.start[node_count]));
  std::vector<std::int32_t> next(out.start.begin(), out.start.end() - 1);
  for (std::size_t e = 0; e < elements.size(); ++e) {
    for (std::size_t c = 0; c < K; ++c) {
      out.entries[static_cast<std::size_t>(next[elements[e][c]]++)] = static_cast<std::int32_t>(e * K + c);
    }
  }
  return out;
}

}  // namespace hof::mechanics
