// codec/exr_writer.cpp: float OpenEXR files written by the OpenEXR library directly must be the bytes the
// OpenImageIO backend writes for the same spec (the files qdmr wrote before, and what the backend still writes for
// specs the writer leaves to it), on sizes of one and several ZIP chunks (16 rows each), 1 to 4 channels, named or
// not, with the metadata qdmr writes, and every kind of float (NaN, infinities, -0, subnormals).
// A full disk is reported with the OS's reason (the command without the module: cli/image_module_test.cpp).
#include <gtest/gtest.h>

#include <bit>
#include <cstdint>
#include <filesystem>
#include <limits>
#include <string>
#include <vector>

#include "codec/exr_writer.hpp"
#include "support/test_support.hpp"

namespace qdmr::test {
namespace {

namespace fs = std::filesystem;

std::vector<float> test_values(std::size_t count) {
  std::vector<float> values(count);
  for (std::size_t i = 0; i < count; ++i) {
    const std::uint32_t h = sample_hash(std::uint32_t(i));
    // Mostly smooth (ZIP finds matches), some raw bit patterns: NaNs, infinities, -0 and subnormals among them.
    values[i] = h % 7 == 0 ? std::bit_cast<float>(h) : float(i % 97) * 0.125f;
  }
  values[0] = -0.0f;
  if (count > 3) {
    values[1] = std::bit_cast<float>(0x7fc00001u);  // a NaN with a payload
    values[2] = -std::numeric_limits<float>::infinity();
    values[3] = std::numeric_limits<float>::denorm_min();
  }
  return values;
}

imageio::WriteSpec float_spec(int width, int height, int channels) {
  return imageio::WriteSpec{width, height, channels, imageio::PixelType::Float, {}, {}, {}};
}

TEST(ExrWriter, SameBytesAsTheOpenImageIOBackend) {
  TempDir dir;
  struct Case {
    int width, height, channels;
    std::vector<std::string> names;
    std::vector<std::pair<std::string, std::string>> strings;
  };
  const std::vector<std::pair<std::string, std::string>> qdmr_strings = {
      {"qdmr:bits_version", "12"}, {"Software", "qdmr 0.1.0 (bits version 12)"}, {"DateTime", ""}};
  const Case cases[] = {
      {1, 1, 1, {}, {{"DateTime", ""}}},
      {5, 3, 2, {}, qdmr_strings},
      {97, 301, 1, {"R"}, {{"DateTime", ""}}},  // a cone map: one channel named R, several chunks
      {480, 270, 3, {}, qdmr_strings},
      {480, 270, 1, {}, qdmr_strings},
      {33, 17, 4, {}, {{"DateTime", "2026:12:07 01:02:03"}, {"Software", "qdmr"}}},
      {64, 40, 3, {"Z", "A", "M"}, {{"DateTime", ""}}},
  };
  for (const Case& c : cases) {
    SCOPED_TRACE(std::to_string(c.width) + "x" + std::to_string(c.height) + "x" + std::to_string(c.channels));
    imageio::WriteSpec spec = float_spec(c.width, c.height, c.channels);
    spec.channel_names = c.names;
    spec.strings = c.strings;
    ASSERT_TRUE(exr_writes(spec));
    const std::vector<float> values = test_values(std::size_t(c.width) * c.height * c.channels);
    const fs::path mine = dir / "mine.exr", theirs = dir / "theirs.exr";
    write_file(mine, "");  // write_exr writes into an existing file (the caller's temporary), as the backend does
    write_file(theirs, "");
    std::string error;
    ASSERT_TRUE(write_exr(mine.string(), spec, values.data(), error)) << error;
    ASSERT_TRUE(imageio::oiio_backend().write(theirs.string(), spec, values.data(), error)) << error;
    const std::string bytes = read_file(mine);
    EXPECT_GT(bytes.size(), 100u);
    EXPECT_EQ(bytes, read_file(theirs));
  }
}

TEST(ExrWriter, LeavesOtherSpecsToTheBackend) {
  const auto dated = [](imageio::WriteSpec spec) {  // as write_image_file hands specs on
    spec.strings.emplace_back("DateTime", "");
    return spec;
  };
  EXPECT_TRUE(exr_writes(dated(float_spec(4, 4, 3))));
  EXPECT_FALSE(exr_writes(float_spec(4, 4, 3)));  // no DateTime: OpenImageIO writes the current time
  imageio::WriteSpec spec = dated(float_spec(4, 4, 3));
  spec.type = imageio::PixelType::UInt16;
  EXPECT_FALSE(exr_writes(spec));
  EXPECT_FALSE(exr_writes(dated(float_spec(4, 4, 5))));
  EXPECT_FALSE(exr_writes(dated(float_spec(0, 4, 1))));
  spec = dated(float_spec(4, 4, 1));
  spec.strings.emplace_back("oiio:ColorSpace", "sRGB");  // OpenImageIO turns it into other attributes
  EXPECT_FALSE(exr_writes(spec));
  spec = dated(float_spec(4, 4, 1));
  spec.ints = {{"png:compressionLevel", 1}};
  EXPECT_FALSE(exr_writes(spec));
  spec = dated(float_spec(4, 4, 2));
  spec.channel_names = {"R", "R"};
  EXPECT_FALSE(exr_writes(spec));
  spec.channel_names = {"R", "G"};
  EXPECT_TRUE(exr_writes(spec));
}

TEST(ExrWriter, AFullDiskIsReportedWithTheOSReason) {
  if (!fs::exists("/dev/full")) GTEST_SKIP() << "no /dev/full";
  const imageio::WriteSpec spec = float_spec(64, 64, 3);
  const std::vector<float> values = test_values(64 * 64 * 3);
  std::string error;
  EXPECT_FALSE(write_exr("/dev/full", spec, values.data(), error));
  EXPECT_EQ(error, "No space left on device");
}

}  // namespace
}  // namespace qdmr::test
