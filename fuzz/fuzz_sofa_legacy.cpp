// libFuzzer target: the 2008 SOFA data files old scenes link (src/hof/scene/
// sofa_legacy_formats.h): the text mesh `.mesh` and the Xsp mass-spring `.xs3`, both read from
// the same bytes.
#include <cstddef>
#include <cstdint>

#include "fuzz_common.h"
#include "hof/scene/sofa_legacy_formats.h"

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  const auto mesh_path = hof::fuzz::write_input(data, size, "input.mesh");
  const auto xs3_path = hof::fuzz::scratch() / "input.xs3";
  hof::fuzz::write_file(xs3_path, std::string_view(reinterpret_cast<const char*>(data), size));
  if (auto mesh = hof::scene::detail::read_legacy_mesh(mesh_path); !mesh)
    hof::fuzz::check_error(mesh.error(), mesh_path);
  if (auto xs3 = hof::scene::detail::read_xs3(xs3_path); !xs3) hof::fuzz::check_error(xs3.error(), xs3_path);
  return 0;
}
