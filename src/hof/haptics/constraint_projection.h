#pragma once
/// @file
/// The closest point to a goal that satisfies up to three half-space constraints n·x ≥ c —
/// the proxy's target in a god-object/Ruspini renderer (Zilles & Salisbury 1995 solve the same
/// problem with Lagrange multipliers). Every subset of the planes is tried as the active set;
/// the nearest feasible candidate wins, so the answer is exact and the cost bounded.

#include <array>
#include <cstddef>

#include "hof/core/types.h"

namespace hof::haptics {

struct HalfSpace {
  Vec3 normal{Vec3::UnitZ()};  ///< unit
  double offset{0.0};          ///< the constraint is normal·x ≥ offset
};

/// Nearest point to `goal` inside all `count` (≤ 3) half-spaces. When no candidate is
/// feasible (planes that cannot all be met), returns `fallback`.
[[nodiscard]] Vec3 project_onto_half_spaces(const Vec3& goal, const std::array<HalfSpace, 3>& planes, std::size_t count,
                                            const Vec3& fallback);

}  // namespace hof::haptics
