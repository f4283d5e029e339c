#pragma once
/// @file
/// Images the window writes (screenshots) and tests read back.

#include <cstdint>
#include <filesystem>
#include <vector>

#include "hof/core/error.h"

namespace hof::render {

struct Image {
  int width{0}, height{0};
  std::vector<std::uint8_t> rgb;  ///< rows from the top, 3 bytes a pixel
};

/// Writes a PNG (via a temporary file and a rename: never a half file).
[[nodiscard]] Expected<void> write_png(const Image& image, const std::filesystem::path& path);
/// Reads a PNG (or any format stb_image reads) as RGB.
[[nodiscard]] Expected<Image> read_png(const std::filesystem::path& path);

}  // namespace hof::render
