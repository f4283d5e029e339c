#pragma once
/// @file
/// Names the project file uses, shared by its reader (project.cpp) and writer (project_write.cpp).

#include "hof/haptics/haptic_renderer.h"

namespace hof::scene::detail {

/// The renderer's element name in a project (RuspiniRenderer, GodObjectRenderer, PenaltyRenderer).
[[nodiscard]] const char* renderer_name(haptics::RendererKind k);

}  // namespace hof::scene::detail
