// libFuzzer target: HoF projects (.hof). The input is an archive (fuzz_common.h): the project
// first, then the scene and meshes it links. Read, then the canonical text checked to read
// back to the same bytes (docs/project-format.md promises save → load → save is stable), then
// the world built from it as every command does (scene, meshes, models; no session).
#include <cstddef>
#include <cstdint>
#include <cstdio>
#include <cstdlib>

#include "fuzz_common.h"
#include "hof/scene/project.h"
#include "hof/scene/world.h"

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  const auto path = hof::fuzz::write_archive(data, size, "project.hof");
  auto project = hof::scene::read_project(path);
  if (!project) {
    hof::fuzz::check_error(project.error(), path);
    return 0;
  }
  const std::string text = hof::scene::to_xml(*project);
  auto again = hof::scene::parse_project(text, path);
  if (!again) {
    std::fprintf(stderr, "the canonical text of a project read does not read back: %s\n",
                 again.error().to_string().c_str());
    std::abort();
  }
  if (hof::scene::to_xml(*again) != text) {
    std::fprintf(stderr, "save -> load -> save changed the project\n");
    std::abort();
  }
  // A scripted device: the project's own could be a UDP peer or a SpaceMouse (fuzz_udp and
  // fuzz_session cover what a device spec leads to).
  auto world = hof::scene::build_world(*project, path, "scripted:poke");
  if (!world) hof::fuzz::check_error(world.error(), path);
  return 0;
}
