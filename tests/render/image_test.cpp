// PNG files (src/hof/render/image.cpp): pixels written and read back exactly, rows from the top,
// folders made on the way, and clear errors for an empty image or an unreadable file.

#include "hof/render/image.h"

#include <gtest/gtest.h>

#include <cstdint>
#include <filesystem>
#include <fstream>
#include <string>

#include "support/temp_dir.h"

namespace hof::render {
namespace {

Image gradient(int width, int height) {
  Image image;
  image.width = width;
  image.height = height;
  for (int y = 0; y < height; ++y) {
    for (int x = 0; x < width; ++x) {
      image.rgb.push_back(static_cast<std::uint8_t>(x * 255 / (width - 1)));
      image.rgb.push_back(static_cast<std::uint8_t>(y * 255 / (height - 1)));
      image.rgb.push_back(static_cast<std::uint8_t>((x * 7 + y * 13) & 0xff));
    }
  }
  return image;
}

TEST(Png, PixelsRoundTripExactlyWithRowsFromTheTop) {
  const hof::testing::TempDir dir;
  const Image image = gradient(17, 9);  // odd sizes: no row padding assumed
  const auto path = dir.path() / "made" / "on the way" / "shot.png";
  ASSERT_TRUE(write_png(image, path));
  std::ifstream in(path, std::ios::binary);
  std::string signature(8, '\0');
  in.read(signature.data(), 8);
  EXPECT_EQ(signature, "\x89PNG\r\n\x1a\n");
  const auto back = read_png(path);
  ASSERT_TRUE(back) << back.error().to_string();
  EXPECT_EQ(back->width, 17);
  EXPECT_EQ(back->height, 9);
  EXPECT_EQ(back->rgb, image.rgb);
  // The first row is the top one: green 0 there, 255 at the bottom.
  EXPECT_EQ(back->rgb[1], 0);
  EXPECT_EQ(back->rgb[(8 * 17) * 3 + 1], 255);
}

TEST(Png, AnEmptyOrMisSizedImageIsRefusedAndNothingIsWritten) {
  const hof::testing::TempDir dir;
  Image empty;
  Image short_buffer = gradient(4, 4);
  short_buffer.rgb.pop_back();
  for (const Image* image : {&empty, &short_buffer}) {
    const auto path = dir.path() / "bad.png";
    const auto written = write_png(*image, path);
    ASSERT_FALSE(written);
    EXPECT_EQ(written.error().code, ErrorCode::kInvalidArgument);
    EXPECT_FALSE(std::filesystem::exists(path));
  }
}

TEST(Png, AMissingOrBrokenFileIsAnIoErrorNamingIt) {
  const hof::testing::TempDir dir;
  const auto missing = read_png(dir.path() / "none.png");
  ASSERT_FALSE(missing);
  EXPECT_EQ(missing.error().code, ErrorCode::kIo);
  EXPECT_NE(missing.error().to_string().find("none.png"), std::string::npos);
  const auto broken = read_png(dir.write("broken.png", "\x89PNG\r\n\x1a\nnot really"));
  ASSERT_FALSE(broken);
  EXPECT_EQ(broken.error().code, ErrorCode::kIo);
}

}  // namespace
}  // namespace hof::render
