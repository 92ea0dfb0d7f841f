// codec/exr_reader.cpp: an OpenEXR file read by the OpenEXR library in process gives what OpenImageIO's reader
// gives: the same size, channels in the same order, every sample's bits as floats, and the Software and
// qdmr:bits_version attributes, over scanline and tiled files, every compression, half, float and 32-bit integer
// channels (mixed too), layers, data windows away from the origin, MIP-mapped and multi-part files; what OpenImageIO
// refuses (subsampled channels) and damaged files fail in both, and deep data is refused.
#include <gtest/gtest.h>

#include <ImfChannelList.h>
#include <ImfDeepFrameBuffer.h>
#include <ImfDeepScanLineOutputFile.h>
#include <ImfFrameBuffer.h>
#include <ImfHeader.h>
#include <ImfOutputFile.h>
#include <ImfPartType.h>
#include <OpenImageIO/imageio.h>

#include <algorithm>
#include <cstdint>
#include <cstring>
#include <filesystem>
#include <string>
#include <vector>

#include "codec/native_reader.hpp"
#include "codec/read_both_ways.hpp"
#include "support/test_support.hpp"

namespace qdmr::test {
namespace {

namespace fs = std::filesystem;
using imageio::PixelType;

constexpr int kExrWidth = 37, kExrHeight = 23;

struct ExrLayout {
  const char* name;
  std::vector<std::string> channels;
  std::vector<OIIO::TypeDesc> types;  // one for all, or one per channel
  const char* compression = "zip";
  int tile = 0;  // tiled, tile x tile, when > 0
  int x = 0, y = 0;  // the data window's corner
  std::vector<std::pair<std::string, std::string>> strings = {};
  int parts = 1;
  bool mipmapped = false;  // tiled, with every MIP level (level 0 is the image; the others other samples)
};

// Samples from a hash, written as floats and 32-bit integers (OpenImageIO stores them as each channel's type):
// floats of every sign and exponent, NaN and infinity included, so a half channel holds every kind of half too.
void write_exr_file(const fs::path& file, const ExrLayout& layout) {
  OIIO::ImageSpec spec(kExrWidth, kExrHeight, int(layout.channels.size()), layout.types[0]);
  spec.channelnames = layout.channels;
  if (layout.types.size() > 1) spec.channelformats = layout.types;
  spec.x = layout.x;
  spec.y = layout.y;
  spec.full_x = 0;
  spec.full_y = 0;
  spec.full_width = 64;
  spec.full_height = 64;
  spec.attribute("compression", layout.compression);
  if (layout.tile > 0) {
    spec.tile_width = layout.tile;
    spec.tile_height = layout.tile;
  }
  if (layout.mipmapped) spec.attribute("textureformat", "Plain Texture");  // OpenImageIO then writes MIP levels
  for (const auto& [name, value] : layout.strings) spec.attribute(name, value);
  const std::size_t channels = layout.channels.size();
  const std::size_t pixel = 4 * channels;  // every sample 4 bytes: a float or a 32-bit integer
  std::vector<unsigned char> pixels(pixel * kExrWidth * kExrHeight);
  for (std::size_t p = 0; p < std::size_t(kExrWidth) * kExrHeight; ++p)
    for (std::size_t c = 0; c < channels; ++c) {
      const std::uint32_t h = sample_hash(std::uint32_t(p * 16 + c));
      float value;
      if (spec.channelformat(int(c)) == OIIO::TypeDesc::UINT) {
        std::memcpy(pixels.data() + p * pixel + 4 * c, &h, 4);
        continue;
      }
      // Mostly ordinary values, some of any bits.
      if (h % 5 == 0) {
        std::memcpy(&value, &h, 4);
      } else {
        value = float(int(h % 20001) - 10000) / 997.0f;
      }
      std::memcpy(pixels.data() + p * pixel + 4 * c, &value, 4);
    }
  // The buffer's own types: float for the half and float channels, 32-bit integers for the others.
  std::vector<OIIO::TypeDesc> buffer_types;
  for (std::size_t c = 0; c < channels; ++c)
    buffer_types.push_back(spec.channelformat(int(c)) == OIIO::TypeDesc::UINT ? OIIO::TypeDesc::UINT
                                                                               : OIIO::TypeDesc::FLOAT);
  auto out = OIIO::ImageOutput::create(file.string());
  ASSERT_TRUE(out);
  std::vector<OIIO::ImageSpec> specs(std::size_t(layout.parts), spec);
  if (layout.parts > 1)
    for (int part = 0; part < layout.parts; ++part)
      specs[std::size_t(part)].attribute("name", "part" + std::to_string(part));
  ASSERT_TRUE(out->open(file.string(), layout.parts, specs.data())) << out->geterror();
  for (int part = 0; part < layout.parts; ++part) {
    if (part > 0) {
      ASSERT_TRUE(out->open(file.string(), specs[std::size_t(part)], OIIO::ImageOutput::AppendSubimage));
    }
    // Each part its own samples (the second part's reversed), so reading the wrong part shows.
    std::vector<unsigned char> data = pixels;
    if (part > 0) std::reverse(data.begin(), data.end());
    const bool uniform = layout.types.size() == 1;
    if (uniform) {
      ASSERT_TRUE(out->write_image(buffer_types[0], data.data())) << out->geterror();
    } else {
      // Mixed types: OpenImageIO takes them as TypeUnknown ("as the file's"), so convert each channel to its type.
      std::vector<unsigned char> native;
      for (std::size_t p = 0; p < std::size_t(kExrWidth) * kExrHeight; ++p)
        for (std::size_t c = 0; c < channels; ++c) {
          const unsigned char* from = data.data() + p * pixel + 4 * c;
          const OIIO::TypeDesc type = spec.channelformat(int(c));
          std::vector<unsigned char> value(type.size());
          ASSERT_TRUE(OIIO::convert_pixel_values(buffer_types[c], from, type, value.data(), 1));
          native.insert(native.end(), value.begin(), value.end());
        }
      ASSERT_TRUE(out->write_image(OIIO::TypeUnknown, native.data())) << out->geterror();
    }
  }
  // The smaller levels, as OpenEXR rounds them down (18x11, 9x5, 4x2, 2x1, 1x1), each from the end of the
  // samples: not level 0's.
  for (int width = kExrWidth, height = kExrHeight; layout.mipmapped && (width > 1 || height > 1);) {
    width = std::max(1, width / 2);
    height = std::max(1, height / 2);
    OIIO::ImageSpec level = spec;
    level.width = level.full_width = width;
    level.height = level.full_height = height;
    ASSERT_TRUE(out->open(file.string(), level, OIIO::ImageOutput::AppendMIPLevel)) << out->geterror();
    ASSERT_TRUE(out->write_image(buffer_types[0], pixels.data() + pixels.size() - pixel * std::size_t(width * height)))
        << out->geterror();
  }
  ASSERT_TRUE(out->close());
}

const OIIO::TypeDesc kHalf = OIIO::TypeDesc::HALF, kFloat = OIIO::TypeDesc::FLOAT, kUint = OIIO::TypeDesc::UINT;

TEST(ExrReader, FilesReadAsOpenImageIOReadsThem) {
  const ExrLayout layouts[] = {
      {"rgba_half_zip", {"R", "G", "B", "A"}, {kHalf}},
      {"grey_float_none", {"Y"}, {kFloat}, "none"},
      {"height_float_tiled", {"height"}, {kFloat}, "zip", 16},
      {"rgb_half_piz_tiled_offset", {"R", "G", "B"}, {kHalf}, "piz", 16, 5, -3},
      {"bgra_named_in_reverse", {"B", "G", "R", "A"}, {kHalf}, "rle"},
      {"lowercase_and_odd_names", {"a", "b", "g", "r", "zeta", "Alpha"}, {kHalf}, "zips"},
      {"layers_and_xyz", {"diffuse.R", "diffuse.G", "diffuse.B", "N.X", "N.Y", "N.Z", "depth"}, {kFloat}, "pxr24"},
      {"mixed_half_float", {"R", "G", "B", "height"}, {kHalf, kHalf, kHalf, kFloat}, "b44"},
      {"with_integer_id", {"R", "id"}, {kFloat, kUint}, "zip"},
      {"integers_only", {"id"}, {kUint}, "none"},
      {"dwaa", {"R", "G", "B"}, {kHalf}, "dwaa"},
      {"metadata", {"R", "G", "B"}, {kFloat}, "zip", 0, 0, 0,
       {{"Software", "qdmr 0.1.0"}, {"qdmr:bits_version", "5"}}},
      {"two_parts", {"R", "G", "B"}, {kHalf}, "zip", 0, 0, 0, {}, 2},
      {"mipmapped", {"R", "G", "B", "A"}, {kHalf}, "zip", 16, 0, 0, {}, 1, true},
  };
  TempDir dir;
  int compared = 0;
  for (const ExrLayout& layout : layouts) {
    SCOPED_TRACE(layout.name);
    const fs::path file = dir / (std::string(layout.name) + ".exr");
    write_exr_file(file, layout);
    if (layout.mipmapped) {  // the file has the levels the test is about
      auto in = OIIO::ImageInput::open(file.string());
      ASSERT_TRUE(in && in->seek_subimage(0, 5)) << "no sixth MIP level";
      EXPECT_EQ(in->spec().width, 1);
    }
    EXPECT_TRUE(imageio::read_natively(file.string()));
    expect_same_as_oiio(file);
    ++compared;
  }
  EXPECT_EQ(compared, int(std::size(layouts)));
}

// A file with a channel sampled every other pixel, written by OpenEXR itself (OpenImageIO writes none).
void write_subsampled_exr(const fs::path& file) {
  Imf::Header header(kExrWidth + 1, kExrHeight + 1);
  header.channels().insert("Y", Imf::Channel(Imf::HALF));
  header.channels().insert("C", Imf::Channel(Imf::HALF, 2, 2));
  std::vector<std::uint16_t> y(std::size_t(kExrWidth + 1) * (kExrHeight + 1), 0x3C00), c(y.size() / 4, 0x3800);
  Imf::FrameBuffer frame;
  frame.insert("Y", Imf::Slice(Imf::HALF, reinterpret_cast<char*>(y.data()), 2, 2 * std::size_t(kExrWidth + 1)));
  frame.insert("C", Imf::Slice(Imf::HALF, reinterpret_cast<char*>(c.data()), 2, std::size_t(kExrWidth + 1), 2, 2));
  Imf::OutputFile out(file.string().c_str(), header);
  out.setFrameBuffer(frame);
  out.writePixels(kExrHeight + 1);
}

// Deep data, one Z sample in every pixel of a 4x4 scanline file.
void write_deep_exr(const fs::path& file) {
  Imf::Header header(4, 4);
  header.channels().insert("Z", Imf::Channel(Imf::FLOAT));
  header.setType(Imf::DEEPSCANLINE);
  header.compression() = Imf::ZIPS_COMPRESSION;
  std::vector<unsigned int> counts(16, 1);
  std::vector<float> z(16, 1.0f);
  std::vector<float*> samples(16);
  for (std::size_t i = 0; i < 16; ++i) samples[i] = &z[i];
  Imf::DeepFrameBuffer frame;
  frame.insertSampleCountSlice(Imf::Slice(Imf::UINT, reinterpret_cast<char*>(counts.data()), sizeof(unsigned int),
                                          4 * sizeof(unsigned int)));
  frame.insert("Z", Imf::DeepSlice(Imf::FLOAT, reinterpret_cast<char*>(samples.data()), sizeof(float*),
                                   4 * sizeof(float*), sizeof(float)));
  Imf::DeepScanLineOutputFile out(file.string().c_str(), header);
  out.setFrameBuffer(frame);
  out.writePixels(4);
}

// What OpenImageIO refuses (subsampled channels) and damaged files (cut in half; pixel data overwritten) fail in
// both readers, with a message and no crash.
TEST(ExrReader, RefusedAndDamagedFilesFailInBothReaders) {
  TempDir dir;
  write_subsampled_exr(dir / "subsampled.exr");
  write_exr_file(dir / "good.exr", {"good", {"R", "G", "B"}, {kHalf}, "zip"});
  const std::string good = read_file(dir / "good.exr");
  write_file(dir / "cut.exr", good.substr(0, good.size() / 2));
  std::string overwritten = good;
  for (std::size_t i = overwritten.size() / 2; i < overwritten.size(); ++i) overwritten[i] = char(0x5A ^ (i * 13));
  write_file(dir / "overwritten.exr", overwritten);
  int cases = 0;
  for (const char* name : {"subsampled.exr", "cut.exr", "overwritten.exr"}) {
    SCOPED_TRACE(name);
    Decoded oiio, native;
    std::string error;
    EXPECT_FALSE(read_with_oiio(dir / name, oiio));
    EXPECT_FALSE(read_natively(dir / name, native, error));
    EXPECT_FALSE(error.empty());
    ++cases;
  }
  EXPECT_EQ(cases, 3);
  Decoded native;
  std::string error;
  read_natively(dir / "subsampled.exr", native, error);
  EXPECT_NE(error.find("subsampled OpenEXR channels are not supported (channel 'C' has sampling 2,2)"),
            std::string::npos)
      << error;
  // Deep data is not an image of one value per channel and pixel: refused, not flattened, as OpenImageIO's
  // read_image refuses it too (the backend read it that way before).
  write_deep_exr(dir / "deep.exr");
  error.clear();
  EXPECT_FALSE(read_natively(dir / "deep.exr", native, error));
  EXPECT_NE(error.find("deep"), std::string::npos) << error;
  Decoded oiio;
  EXPECT_FALSE(read_with_oiio(dir / "deep.exr", oiio));
}

}  // namespace
}  // namespace qdmr::test
