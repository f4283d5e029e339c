// stb_image and stb_image_write come from Debian's libstb (the implementation is in libstb.a).
#include "hof/render/image.h"

#include <stb_image.h>
#include <stb_image_write.h>

#include <string>
#include <system_error>

#include "hof/core/file_write.h"

namespace hof::render {

Expected<void> write_png(const Image& image, const std::filesystem::path& path) {
  if (image.width <= 0 || image.height <= 0 ||
      image.rgb.size() != static_cast<std::size_t>(image.width) * static_cast<std::size_t>(image.height) * 3) {
    return make_error(ErrorCode::kInvalidArgument, "no image to write", path.string());
  }
  std::error_code ec;
  if (path.has_parent_path()) std::filesystem::create_directories(path.parent_path(), ec);
  // Encoded in memory, then written atomically: a full disk never leaves half a PNG.
  std::string png;
  const auto append = [](void* context, void* data, int size) {
    static_cast<std::string*>(context)->append(static_cast<const char*>(data), static_cast<std::size_t>(size));
  };
  if (!stbi_write_png_to_func(append, &png, image.width, image.height, 3, image.rgb.data(), image.width * 3)) {
    return make_error(ErrorCode::kIo, "cannot encode the PNG", path.string());
  }
  return write_file_atomically(path, png);
}

Expected<Image> read_png(const std::filesystem::path& path) {
  int w = 0, h = 0, channels = 0;
  unsigned char* data = stbi_load(path.c_str(), &w, &h, &channels, 3);
  if (!data)
    return make_error(ErrorCode::kIo, std::string("cannot read the image: ") + stbi_failure_reason(), path.string());
  Image image;
  image.width = w;
  image.height = h;
  image.rgb.assign(data, data + static_cast<std::size_t>(w) * static_cast<std::size_t>(h) * 3);
  stbi_image_free(data);
  return image;
}

}  // namespace hof::render
