// libFuzzer target: SOFA scenes (hof::scene::read_sofa_scene), both syntaxes, with the files
// they link (meshes, the 2008 .mesh/.xs3 files): the input is an archive (fuzz_common.h)
// whose first file is the scene.
#include <cstddef>
#include <cstdint>

#include "fuzz_common.h"
#include "hof/scene/sofa_scene.h"

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  const auto path = hof::fuzz::write_archive(data, size, "scene.scn");
  auto scene = hof::scene::read_sofa_scene(path);
  if (!scene) hof::fuzz::check_error(scene.error(), path);
  return 0;
}
