// codec/png_writer.cpp at its default level: rows filtered and compressed in bands, in parallel, joined into one zlib
// stream. The stream must be valid (zlib checks its Adler-32), hold exactly the filtered rows, and be the same bytes
// on any thread count.
#include <gtest/gtest.h>
#include <png.h>
#include <tbb/global_control.h>
#include <zlib.h>

#include <cstdint>
#include <cstring>
#include <string>
#include <vector>

#include "codec/png_writer.hpp"
#include "support/test_support.hpp"

namespace qdmr::test {
namespace {

// An RGB image tall enough for several bands (rows of 901 bytes: bands of 290 rows, 4 of them), of smooth runs and
// hashed noise, so the compressor finds matches and literals.
constexpr int kWidth = 300, kHeight = 1000, kChannels = 3;

std::vector<std::uint8_t> test_pixels() {
  std::vector<std::uint8_t> pixels(std::size_t(kWidth) * kHeight * kChannels);
  for (std::size_t i = 0; i < pixels.size(); ++i) {
    const std::size_t y = i / (kWidth * kChannels);
    pixels[i] = (y / 37) % 3 == 0 ? std::uint8_t(sample_hash(std::uint32_t(i))) : std::uint8_t(i % 251 + y);
  }
  return pixels;
}

std::string written(const std::vector<std::uint8_t>& pixels, const TempDir& dir, const std::string& name) {
  imageio::WriteSpec spec;
  spec.width = kWidth;
  spec.height = kHeight;
  spec.channels = kChannels;
  spec.type = imageio::PixelType::UInt8;
  std::string error;
  EXPECT_TRUE(write_png((dir / name).string(), spec, pixels.data(), error)) << error;
  return read_file(dir / name);
}

// The payload of every IDAT chunk, in order.
std::string idat_payload(const std::string& png) {
  std::string payload;
  for (std::size_t at = 8; at + 12 <= png.size();) {
    const auto byte = [&](std::size_t i) { return std::uint32_t(static_cast<unsigned char>(png[i])); };
    const std::uint32_t length = byte(at) << 24 | byte(at + 1) << 16 | byte(at + 2) << 8 | byte(at + 3);
    if (png.compare(at + 4, 4, "IDAT") == 0) payload += png.substr(at + 8, length);
    at += 12 + length;
  }
  return payload;
}

TEST(PngWriter, BandsJoinIntoOneZlibStreamOfTheFilteredRows) {
  TempDir dir;
  const std::vector<std::uint8_t> pixels = test_pixels();
  const std::string payload = idat_payload(written(pixels, dir, "bands.png"));
  const std::size_t row = std::size_t(kWidth) * kChannels;
  std::vector<unsigned char> rows((row + 1) * kHeight + 1);  // one byte more: uncompress must not fill it
  uLongf size = uLongf(rows.size());
  // uncompress fails on a damaged stream, a wrong Adler-32, or a final block missing.
  ASSERT_EQ(uncompress(rows.data(), &size, reinterpret_cast<const Bytef*>(payload.data()), uLong(payload.size())),
            Z_OK);
  ASSERT_EQ(size, (row + 1) * kHeight);
  for (std::size_t y = 0; y < std::size_t(kHeight); ++y) {
    const unsigned char* filtered = rows.data() + y * (row + 1);
    ASSERT_EQ(filtered[0], 2) << "row " << y;  // Up
    for (std::size_t i = 0; i < row; ++i) {
      const std::uint8_t above = y == 0 ? 0 : pixels[(y - 1) * row + i];
      ASSERT_EQ(std::uint8_t(filtered[1 + i] + above), pixels[y * row + i]) << "row " << y << ", byte " << i;
    }
  }
  // And libpng reads the file back to the same pixels.
  png_image image{};
  image.version = PNG_IMAGE_VERSION;
  ASSERT_TRUE(png_image_begin_read_from_file(&image, (dir / "bands.png").c_str()));
  image.format = PNG_FORMAT_RGB;
  std::vector<std::uint8_t> back(PNG_IMAGE_SIZE(image));
  ASSERT_TRUE(png_image_finish_read(&image, nullptr, back.data(), 0, nullptr));
  EXPECT_EQ(back, pixels);
}

TEST(PngWriter, SameBytesOnAnyThreadCount) {
  TempDir dir;
  const std::vector<std::uint8_t> pixels = test_pixels();
  std::string one, two;
  {
    tbb::global_control only(tbb::global_control::max_allowed_parallelism, 1);
    one = written(pixels, dir, "one.png");
  }
  {
    tbb::global_control both(tbb::global_control::max_allowed_parallelism, 2);
    two = written(pixels, dir, "two.png");
  }
  EXPECT_FALSE(one.empty());
  EXPECT_EQ(one, two);
}

}  // namespace
}  // namespace qdmr::test
