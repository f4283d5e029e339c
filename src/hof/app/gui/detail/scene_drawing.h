#pragma once
/// @file
/// The 3D scene's helpers shared by the window's drawing and its panels.

#include <string>
#include <vector>

#include "hof/core/types.h"
#include "hof/procedures/needle.h"
#include "hof/render/gl_renderer.h"

namespace hof::app::gui {

/// The colour of each needle phase (the tip marker, the Touch panel).
[[nodiscard]] render::Rgba phase_colour(procedures::NeedlePhase phase);
/// The twelve edges of the box [lo, hi] as line-segment end points, appended to `lines`.
void add_box_edges(std::vector<Vec3>& lines, const Vec3& lo, const Vec3& hi);

}  // namespace hof::app::gui
