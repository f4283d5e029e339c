#include "hof/render/colormap.h"

#include <algorithm>
#include <array>
#include <cmath>

namespace hof::render {

Eigen::Vector3f viridis(float t) {
  // viridis at t = 0, 1/8, ..., 1 (matplotlib's published table, rounded).
  static constexpr std::array<std::array<float, 3>, 9> kStops{{{0.267f, 0.005f, 0.329f},
                                                               {0.283f, 0.141f, 0.458f},
                                                               {0.254f, 0.265f, 0.530f},
                                                               {0.207f, 0.372f, 0.553f},
                                                               {0.164f, 0.471f, 0.558f},
                                                               {0.128f, 0.567f, 0.551f},
                                                               {0.135f, 0.659f, 0.518f},
                                                               {0.478f, 0.821f, 0.318f},
                                                               {0.993f, 0.906f, 0.144f}}};
  if (!std::isfinite(t)) t = 0.0f;
  const float x = std::clamp(t, 0.0f, 1.0f) * 8.0f;
  const auto i = std::min(static_cast<std::size_t>(x), std::size_t{7});
  const float f = x - static_cast<float>(i);
  const auto& a = kStops[i];
  const auto& b = kStops[i + 1];
  return {a[0] + f * (b[0] - a[0]), a[1] + f * (b[1] - a[1]), a[2] + f * (b[2] - a[2])};
}

}  // namespace hof::render
