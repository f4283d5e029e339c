// libFuzzer target: X3D scenes for H3D (hof::scene::read_x3d_scene). An archive input
// (fuzz_common.h), so that a scene's references to other files have something to find.
#include <cstddef>
#include <cstdint>

#include "fuzz_common.h"
#include "hof/scene/x3d_scene.h"

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  const auto path = hof::fuzz::write_archive(data, size, "scene.x3d");
  auto scene = hof::scene::read_x3d_scene(path);
  if (!scene) hof::fuzz::check_error(scene.error(), path);
  return 0;
}
