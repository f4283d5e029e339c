#pragma once
/// @file
/// Gmsh node tags → 0-based node indices, for the .msh reader (tags are any positive
/// integers, in any order; most files number them 1..N).

#include <algorithm>
#include <cstdint>
#include <utility>
#include <vector>

#include "hof/mesh/mesh.h"

namespace hof::mesh::detail {

/// Node tag → 0-based index. Dense array when the tags are compact (the usual 1..N),
/// sorted pairs with binary search otherwise.
class TagMap {
 public:
  /// Builds the map from tags in file order; on a repeated tag returns false and sets it.
  bool build(const std::vector<std::int64_t>& tags, std::int64_t& duplicate) {
    dense_.clear();
    sorted_.clear();
    const std::int64_t max_tag = tags.empty() ? 0 : *std::max_element(tags.begin(), tags.end());
    use_dense_ = max_tag <= 2 * static_cast<std::int64_t>(tags.size()) + 1024;
    if (use_dense_) {
      dense_.assign(static_cast<std::size_t>(max_tag) + 1, -1);
      for (std::size_t i = 0; i < tags.size(); ++i) {
        NodeIndex& slot = dense_[static_cast<std::size_t>(tags[i])];
        if (slot >= 0) {
          duplicate = tags[i];
          return false;
        }
        slot = static_cast<NodeIndex>(i);
      }
      return true;
    }
    sorted_.reserve(tags.size());
    for (std::size_t i = 0; i < tags.size(); ++i) sorted_.emplace_back(tags[i], static_cast<NodeIndex>(i));
    std::sort(sorted_.begin(), sorted_.end());
    for (std::size_t i = 1; i < sorted_.size(); ++i) {
      if (sorted_[i].first == sorted_[i - 1].first) {
        duplicate = sorted_[i].first;
        return false;
      }
    }
    return true;
  }

  /// Index of the node with `tag`, or -1 when there is none.
  [[nodiscard]] NodeIndex find(std::int64_t tag) const {
    if (use_dense_) {
      return tag >= 0 && tag < static_cast<std::int64_t>(dense_.size()) ? dense_[static_cast<std::size_t>(tag)] : -1;
    }
    const auto it = std::lower_bound(sorted_.begin(), sorted_.end(), std::pair<std::int64_t, NodeIndex>{tag, -1});
    return it != sorted_.end() && it->first == tag ? it->second : -1;
  }

 private:
  bool use_dense_{true};
  std::vector<NodeIndex> dense_;
  std::vector<std::pair<std::int64_t, NodeIndex>> sorted_;
};

}  // namespace hof::mesh::detail
