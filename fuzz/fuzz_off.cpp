// libFuzzer target: hof::mesh::read_off on a file holding the input (docs/reliability.md).
#include <cstddef>
#include <cstdint>

#include "fuzz_common.h"
#include "hof/mesh/mesh_io.h"

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  // Through the path, as a user's file is read: opening, sizing and reading are fuzzed too.
  const auto path = hof::fuzz::write_input(data, size, "input.off");
  auto result = hof::mesh::read_off(path);
  if (!result) hof::fuzz::check_error(result.error(), path);
  return 0;
}
