#include <gtest/gtest.h>

#include <OpenImageIO/imageio.h>

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <filesystem>
#include <string>
#include <vector>

#include "qdmr/core/error.hpp"
#include "qdmr/texture/image.hpp"
#include "qdmr/texture/texture_level0.hpp"
#include "support/test_support.hpp"
#include "texture/internal.hpp"

namespace qdmr {
namespace {

template <class T>
void write_png(const std::filesystem::path& file, int w, int h, int channels, const std::vector<T>& data) {
  auto out = OIIO::ImageOutput::create(file.string());
  ASSERT_TRUE(out);
  const OIIO::ImageSpec spec(w, h, channels, sizeof(T) == 1 ? OIIO::TypeDesc::UINT8 : OIIO::TypeDesc::UINT16);
  ASSERT_TRUE(out->open(file.string(), spec));
  // data holds texel rows (row 0 = v = 0); files store the top row first and qdmr reads them bottom-up,
  // so the rows are written in reverse.
  const OIIO::stride_t row = OIIO::stride_t(sizeof(T)) * channels * w;
  ASSERT_TRUE(out->write_image(spec.format, reinterpret_cast<const char*>(data.data()) + row * (h - 1),
                               OIIO::AutoStride, -row));
  ASSERT_TRUE(out->close());
}

// 8-bit RGB ramp: texel (x, y) = (x + 16y, 255 - x, 7 * y) in a 16x16 image.
std::vector<std::uint8_t> ramp8() {
  std::vector<std::uint8_t> data;
  for (int y = 0; y < 16; ++y)
    for (int x = 0; x < 16; ++x) data.insert(data.end(), {std::uint8_t(x + 16 * y), std::uint8_t(255 - x), std::uint8_t(7 * y)});
  return data;
}

TEST(TextureImage, Reads8BitPngExactly) {
  test::TempDir dir;
  const auto data = ramp8();
  write_png(dir / "a.png", 16, 16, 3, data);
  const Image img = read_image(dir / "a.png", "test");
  ASSERT_EQ(img.width, 16);
  ASSERT_EQ(img.height, 16);
  ASSERT_EQ(img.channels, 3);
  for (std::size_t i = 0; i < data.size(); ++i) ASSERT_EQ(img.texels[i], data[i] / 255.0f) << i;
}

TEST(TextureImage, LastRowOfTheFileIsRowZero) {
  test::TempDir dir;
  const std::vector<std::uint8_t> top_first = {10, 20, 30, 40, 50, 60};  // 2 wide, 3 tall, as stored in the file
  auto out = OIIO::ImageOutput::create((dir / "rows.png").string());
  ASSERT_TRUE(out->open((dir / "rows.png").string(), OIIO::ImageSpec(2, 3, 1, OIIO::TypeDesc::UINT8)));
  ASSERT_TRUE(out->write_image(OIIO::TypeDesc::UINT8, top_first.data()));
  ASSERT_TRUE(out->close());
  const Image img = read_image(dir / "rows.png", "test");
  EXPECT_EQ(img.at(0, 0, 0), 50 / 255.0f);
  EXPECT_EQ(img.at(1, 0, 0), 60 / 255.0f);
  EXPECT_EQ(img.at(0, 2, 0), 10 / 255.0f);
}

TEST(TextureImage, Reads16BitPngExactly) {
  test::TempDir dir;
  std::vector<std::uint16_t> data;
  for (int i = 0; i < 8 * 4; ++i) data.push_back(std::uint16_t(i * 2047 + (i == 31 ? 1 : 0)));  // 0 .. 65535
  write_png(dir / "b.png", 8, 4, 1, data);
  const Image img = read_image(dir / "b.png", "test");
  ASSERT_EQ(img.channels, 1);
  for (std::size_t i = 0; i < data.size(); ++i) ASSERT_EQ(img.texels[i], data[i] / 65535.0f) << i;
}

// RGBA texels whose alpha is data (a height, a roughness): written as stored, with every alpha from 0 to 255
// beside colours that premultiplying would change.
std::vector<std::uint8_t> rgba_with_data_in_alpha() {
  std::vector<std::uint8_t> data;
  for (int i = 0; i < 256; ++i) data.insert(data.end(), {200, std::uint8_t(i), 77, std::uint8_t(255 - i)});
  return data;
}

// Alpha is read as stored and the other channels are not multiplied by it: OpenImageIO's PNG and TIFF readers
// do that unless asked not to, which darkened an albedo by the height packed in its alpha (real_terrain.json).
TEST(TextureImage, AlphaIsDataNotCoverage) {
  test::TempDir dir;
  const auto data = rgba_with_data_in_alpha();
  for (const char* name : {"a.png", "a.tif"}) {
    const std::filesystem::path file = dir / name;
    auto out = OIIO::ImageOutput::create(file.string());
    ASSERT_TRUE(out);
    OIIO::ImageSpec spec(16, 16, 4, OIIO::TypeDesc::UINT8);
    spec.attribute("oiio:UnassociatedAlpha", 1);  // the values as given, unassociated, as PNG defines them
    ASSERT_TRUE(out->open(file.string(), spec));
    ASSERT_TRUE(out->write_image(OIIO::TypeDesc::UINT8, data.data()));
    ASSERT_TRUE(out->close());
    const Image img = read_image(file, "test");
    ASSERT_EQ(img.channels, 4);
    // Rows come back bottom-up: the file's row r is texel row 15 - r.
    for (int y = 0; y < 16; ++y)
      for (int x = 0; x < 16; ++x)
        for (int c = 0; c < 4; ++c)
          ASSERT_EQ(img.at(x, 15 - y, c), data[std::size_t((16 * y + x) * 4 + c)] / 255.0f) << name << " " << x << "," << y << "," << c;
  }
}

// A TIFF of 8-bit samples, `channels` per pixel (the second and later ones unspecified extra samples), whose
// photometric interpretation is "min is white", in deflate-compressed strips of `rows_per_strip` rows (zlib streams
// of stored blocks: valid deflate without a compressor). `top_first` holds the samples as the file stores them.
std::vector<char> min_is_white_tiff(int w, int h, int channels, int rows_per_strip,
                                    const std::vector<std::uint8_t>& top_first) {
  std::vector<char> out;
  const auto u16 = [&](unsigned v) { out.insert(out.end(), {char(v & 0xFF), char(v >> 8)}); };
  const auto u32 = [&](std::uint32_t v) {
    u16(v & 0xFFFF);
    u16(v >> 16);
  };
  const int strips = (h + rows_per_strip - 1) / rows_per_strip;
  std::vector<std::uint32_t> offsets, counts;
  out.insert(out.end(), {'I', 'I', 42, 0, 0, 0, 0, 0});  // the IFD's offset is patched below
  for (int s = 0; s < strips; ++s) {
    const std::size_t row = std::size_t(w) * std::size_t(channels);
    const std::size_t begin = std::size_t(s) * std::size_t(rows_per_strip) * row;
    const std::size_t end = std::min(top_first.size(), begin + std::size_t(rows_per_strip) * row);
    offsets.push_back(std::uint32_t(out.size()));
    out.insert(out.end(), {char(0x78), char(0x01), char(0x01)});  // zlib header; one final stored block
    const unsigned length = unsigned(end - begin);
    u16(length);
    u16(~length & 0xFFFF);
    std::uint32_t a = 1, b = 0;  // Adler-32 of the data, stored big-endian
    for (std::size_t i = begin; i < end; ++i) {
      out.push_back(char(top_first[i]));
      a = (a + top_first[i]) % 65521;
      b = (b + a) % 65521;
    }
    const std::uint32_t adler = (b << 16) | a;
    out.insert(out.end(), {char(adler >> 24), char(adler >> 16), char(adler >> 8), char(adler)});
    counts.push_back(std::uint32_t(out.size()) - offsets.back());
  }
  const auto array_at = [&](const std::vector<std::uint32_t>& values) {
    const auto at = std::uint32_t(out.size());
    for (const std::uint32_t v : values) u32(v);
    return at;
  };
  const std::uint32_t offsets_at = array_at(offsets), counts_at = array_at(counts);
  const auto bits_at = std::uint32_t(out.size());
  for (int c = 0; c < channels; ++c) u16(8);
  const auto extra_at = std::uint32_t(out.size());
  for (int c = 1; c < channels; ++c) u16(0);
  if (out.size() % 2) out.push_back(0);
  const auto ifd = std::uint32_t(out.size());
  for (int i = 0; i < 4; ++i) out[std::size_t(4 + i)] = char(ifd >> (8 * i));
  struct Entry {
    unsigned tag, type;
    std::uint32_t count, value;
  };
  // Values of up to 4 bytes sit in the entry itself (SHORT pairs: the first in the low half); longer arrays at
  // their offset.
  std::vector<Entry> entries = {
      {256, 3, 1, std::uint32_t(w)},
      {257, 3, 1, std::uint32_t(h)},
      {258, 3, std::uint32_t(channels), channels == 1 ? 8u : channels == 2 ? 8u | (8u << 16) : bits_at},
      {259, 3, 1, 8},  // Adobe deflate
      {262, 3, 1, 0},  // min is white
      {273, 4, std::uint32_t(strips), strips == 1 ? offsets[0] : offsets_at},
      {277, 3, 1, std::uint32_t(channels)},
      {278, 3, 1, std::uint32_t(rows_per_strip)},
      {279, 4, std::uint32_t(strips), strips == 1 ? counts[0] : counts_at},
      {284, 3, 1, 1}};  // contiguous samples
  if (channels > 1) entries.push_back({338, 3, std::uint32_t(channels - 1), channels <= 3 ? 0u : extra_at});
  u16(unsigned(entries.size()));
  for (const Entry& e : entries) {
    u16(e.tag);
    u16(e.type);
    u32(e.count);
    u32(e.value);
  }
  u32(0);  // no next IFD
  return out;
}

// OpenImageIO 2.4 inverted a "min is white" TIFF's deflate strips over `channels` times their size, past the end of
// the rows it was asked for (a heap overflow fuzz_image found; oiio_backend.cpp reads such files a scanline at a
// time). Every sample must come back inverted once. The overflow itself is written by uninstrumented library code,
// which AddressSanitizer does not see here; fuzz_image's seed
// fuzz/corpus/image/regression_tiff_min_is_white_four_channels_deflate (254 x 160, five strips) makes ASan's
// allocator fail its own check when the overflow is back, and the next test shows the library's.
TEST(TextureImage, MinIsWhiteTiffOfSeveralChannelsReadsEachSampleInvertedOnce) {
  test::TempDir dir;
  for (const int channels : {1, 2, 4}) {
    const int w = 5, h = 9, rows_per_strip = 2;  // 5 strips, the last one short
    std::vector<std::uint8_t> top_first;
    for (int y = 0; y < h; ++y)
      for (int x = 0; x < w; ++x)
        for (int c = 0; c < channels; ++c) top_first.push_back(std::uint8_t((y * 37 + x * 11 + c * 101) % 256));
    const std::filesystem::path file = dir / ("white" + std::to_string(channels) + ".tif");
    const std::vector<char> bytes = min_is_white_tiff(w, h, channels, rows_per_strip, top_first);
    test::write_file(file, std::string(bytes.begin(), bytes.end()));
    const Image img = read_image(file, "test");
    ASSERT_EQ(img.width, w);
    ASSERT_EQ(img.height, h);
    ASSERT_EQ(img.channels, channels);
    for (int y = 0; y < h; ++y)
      for (int x = 0; x < w; ++x)
        for (int c = 0; c < channels; ++c) {
          const std::uint8_t stored = top_first[(std::size_t(y) * w + x) * channels + c];
          ASSERT_EQ(img.at(x, h - 1 - y, c), float(255 - stored) / 255.0f) << channels << " " << x << " " << y << " " << c;
        }
  }
}

// Why oiio_backend.cpp reads such a file a scanline at a time: asked for all its rows at once, OpenImageIO 2.4 (as
// Debian 12 ships it) inverts each strip's samples over `channels` times the strip, past the rows it was asked for.
// The bytes after the rows are checked here. Should this fail, the OpenImageIO in use has fixed it, and the
// one-scanline reads of "min is white" files can go.
TEST(TextureImage, OpenImageIOWritesPastTheRowsOfAMinIsWhiteTiffReadAsStrips) {
  test::TempDir dir;
  const int w = 5, h = 8, channels = 4, rows_per_strip = 2;
  const std::vector<std::uint8_t> top_first(std::size_t(w) * h * channels, 7);
  const std::vector<char> bytes = min_is_white_tiff(w, h, channels, rows_per_strip, top_first);
  test::write_file(dir / "white.tif", std::string(bytes.begin(), bytes.end()));
  auto in = OIIO::ImageInput::open((dir / "white.tif").string());
  ASSERT_TRUE(in);
  const std::size_t rows_bytes = top_first.size(), slack = 4 * rows_bytes;
  std::vector<std::uint8_t> buffer(rows_bytes + slack, 0x55);
  ASSERT_TRUE(in->read_scanlines(0, 0, 0, h, 0, 0, channels, OIIO::TypeUnknown, buffer.data()));
  EXPECT_EQ(buffer[0], 255 - 7);
  const auto written_past = std::count_if(buffer.begin() + std::ptrdiff_t(rows_bytes), buffer.end(),
                                          [](std::uint8_t b) { return b != 0x55; });
  EXPECT_GT(written_past, 0) << "OpenImageIO no longer writes past the rows it reads";
}

TEST(TextureImage, BadFilesThrow) {
  test::TempDir dir;
  write_png(dir / "good.png", 16, 16, 3, ramp8());
  const std::string bytes = test::read_file(dir / "good.png");
  test::write_file(dir / "truncated.png", bytes.substr(0, bytes.size() / 2));
  test::write_file(dir / "garbage.png", std::string(300, 'x'));
  write_png(dir / "wide.png", 16385, 1, 1, std::vector<std::uint8_t>(16385, 0));  // over the texture limit
  for (const char* name : {"truncated.png", "garbage.png", "wide.png"}) {
    try {
      read_image(dir / name, "scene.json: /materials/0");
      ADD_FAILURE() << name << " did not throw";
    } catch (const Error& e) {
      const std::string message = e.what();
      EXPECT_NE(message.find("scene.json: /materials/0: cannot read '" + (dir / name).string() + "': "), std::string::npos)
          << message;
    }
  }
  try {
    read_image(dir / "missing.png", "scene.json: /materials/0");
    ADD_FAILURE() << "missing.png did not throw";
  } catch (const Error& e) {
    EXPECT_EQ(std::string(e.what()), "scene.json: /materials/0: file not found: " + (dir / "missing.png").string());
  }
}

// Small files of the bad-input corpus that declare images of 0.8 to 4 GB: each is refused, after its header, when
// its pixels run out. The input tests run under AddressSanitizer in CI, so this is where blocks of that size are
// allocated, poisoned and freed under it (fuzz_image reads pixels only up to 8 MiB; the bad-input corpus test
// runs in the release build). The ASCII PNM ones are refused from the header (the data cannot be that long).
TEST(TextureImage, SmallFilesThatDeclareLargeImagesThrowAfterTheirHeader) {
  const std::filesystem::path images = std::filesystem::path(QDMR_SOURCE_DIR) / "tests/bad_inputs/files/images";
  int past_header = 0;
  for (const auto& entry : std::filesystem::directory_iterator(images)) {
    const std::string name = entry.path().filename().string();
    if (name.find("_declares_") == std::string::npos) continue;
    try {
      const ImageHeader header = read_image_header(entry.path(), "scene.json: /materials/0");
      EXPECT_GE(read_image_bytes(header), std::uint64_t(512) << 20) << name;
      ++past_header;
    } catch (const Error&) {
      continue;
    }
    EXPECT_THROW(static_cast<void>(read_image(entry.path(), "scene.json: /materials/0")), Error) << name;
  }
  EXPECT_GE(past_header, 4);  // EXR, JPEG, PNG and TIFF
}

TEST(TextureImage, SrgbDecodeExact) {
  using texture_detail::srgb_to_linear;
  EXPECT_EQ(srgb_to_linear(0.0f), 0.0f);
  EXPECT_EQ(srgb_to_linear(1.0f), 1.0f);
  EXPECT_EQ(srgb_to_linear(0.04045f), float(double(0.04045f) / 12.92));
  EXPECT_EQ(srgb_to_linear(0.5f), float(std::pow(0.555 / 1.055, 2.4)));
  EXPECT_NEAR(srgb_to_linear(0.5f), 0.21404114f, 1e-7f);
  EXPECT_NEAR(srgb_to_linear(188 / 255.0f), 0.5028865f, 1e-6f);
}

TEST(TextureImage, AlbedoFromFileDecodesAndSelects) {
  test::TempDir dir;
  const auto data = ramp8();
  write_png(dir / "a.png", 16, 16, 3, data);
  TextureDesc d;
  d.source = TextureSource::File;
  d.file = dir / "a.png";
  const LayerDesc layer;
  const Image srgb = make_texture(d, TexturePurpose::Albedo, layer, nullptr, "t");
  ASSERT_EQ(srgb.channels, 3);
  EXPECT_EQ(srgb.at(5, 2, 1), texture_detail::srgb_to_linear(250 / 255.0f));
  d.srgb = false;
  d.channel = Channel::B;
  const Image blue = make_texture(d, TexturePurpose::Albedo, layer, nullptr, "t");
  for (int c = 0; c < 3; ++c) EXPECT_EQ(blue.at(5, 2, c), 14 / 255.0f);
  d.channel = Channel::A;
  EXPECT_THROW(make_texture(d, TexturePurpose::Albedo, layer, nullptr, "t"), Error);
}

// An albedo file's factor (glTF's baseColorFactor) multiplies each decoded linear channel.
TEST(TextureImage, AlbedoFactorMultipliesTheLinearColour) {
  test::TempDir dir;
  write_png(dir / "a.png", 16, 16, 3, ramp8());
  TextureDesc d;
  d.source = TextureSource::File;
  d.file = dir / "a.png";
  const Image plain = make_texture(d, TexturePurpose::Albedo, LayerDesc{}, nullptr, "t");
  d.factor = glm::vec3(0.5f, 0.25f, 0.8f);
  const Image tinted = make_texture(d, TexturePurpose::Albedo, LayerDesc{}, nullptr, "t");
  ASSERT_EQ(tinted.texels.size(), plain.texels.size());
  for (std::size_t i = 0; i < plain.texels.size(); ++i) ASSERT_EQ(tinted.texels[i], plain.texels[i] * d.factor[int(i % 3)]);
}

TEST(TextureImage, HeightChannelScaleOffset) {
  test::TempDir dir;
  write_png(dir / "a.png", 16, 16, 3, ramp8());
  LayerDesc layer;
  layer.height.source = TextureSource::File;
  layer.height.file = dir / "a.png";
  layer.height.channel = Channel::R;
  layer.height_scale = 2.0f;
  layer.height_offset = -1.0f;
  const Image h = make_layer_height(layer, "t");
  ASSERT_EQ(h.channels, 1);
  EXPECT_EQ(h.at(0, 0, 0), 0.0f);  // 2 * 0 - 1, clamped
  EXPECT_EQ(h.at(15, 15, 0), 1.0f);
  EXPECT_EQ(h.at(4, 8, 0), 132 / 255.0f * 2.0f - 1.0f);
  layer.height.channel = Channel::RGB;
  EXPECT_THROW(make_layer_height(layer, "t"), Error);
  // No height: flat at the top.
  const Image flat = make_layer_height(LayerDesc{}, "t");
  EXPECT_EQ(flat.width, 1);
  EXPECT_EQ(flat.texels, Texels{1.0f});
}

TEST(TextureImage, NormalsFromFile) {
  test::TempDir dir;
  // (128, 64, 255): x = 1/255, y = -127/255 (GL), z = 1, before normalisation.
  write_png(dir / "n.png", 1, 1, 3, std::vector<std::uint8_t>{128, 64, 255});
  LayerDesc layer;
  layer.normal.source = TextureSource::File;
  layer.normal.file = dir / "n.png";
  for (NormalConvention convention : {NormalConvention::GL, NormalConvention::DX}) {
    layer.normal_convention = convention;
    layer.normal_strength = 2.0f;
    const Image n = make_texture(layer.normal, TexturePurpose::Normal, layer, nullptr, "t");
    const double x = (2.0 * 128 / 255.0 - 1) * 2, y = (2.0 * 64 / 255.0 - 1) * 2 * (convention == NormalConvention::DX ? -1 : 1);
    const double z = 1.0, len = std::sqrt(x * x + y * y + z * z);
    EXPECT_NEAR(n.at(0, 0, 0), x / len, 1e-6);
    EXPECT_NEAR(n.at(0, 0, 1), y / len, 1e-6);
    EXPECT_NEAR(n.at(0, 0, 2), z / len, 1e-6);
  }
  const Image flat = make_texture(TextureDesc{}, TexturePurpose::Normal, layer, nullptr, "t");
  EXPECT_EQ(flat.texels, (Texels{0, 0, 1}));
}

TEST(TextureImage, NormalsFromHeight) {
  // A ramp h = x / 4 on 4 texels wraps: central differences 0.5 except at the wrap.
  Image h(4, 2, 1);
  for (int y = 0; y < 2; ++y)
    for (int x = 0; x < 4; ++x) h.at(x, y, 0) = x / 4.0f;
  LayerDesc layer;
  layer.normal.source = TextureSource::FromHeight;
  const Image n = make_texture(layer.normal, TexturePurpose::Normal, layer, &h, "t");
  ASSERT_EQ(n.width, 4);
  ASSERT_EQ(n.channels, 3);
  // Strength 1: depth range 1/16 of a repeat. dz/du = 0.5 / 2 * 4 / 16 = 1/16 at x = 1.
  const double s = 0.5 / 2 * 4 * texture_detail::kFromHeightDepth, len = std::sqrt(s * s + 1);
  EXPECT_NEAR(n.at(1, 0, 0), -s / len, 1e-7);
  EXPECT_EQ(n.at(1, 0, 1), 0.0f);
  EXPECT_NEAR(n.at(1, 0, 2), 1 / len, 1e-7);
  EXPECT_GT(n.at(0, 1, 0), 0.0f);  // the wrap: h falls from 0.75 to 0
  EXPECT_THROW(make_texture(layer.normal, TexturePurpose::Normal, layer, nullptr, "t"), Error);
}

TEST(TextureImage, ProceduralAlbedo) {
  TextureDesc d;
  d.source = TextureSource::Procedural;
  d.procedural.pattern = ProceduralPattern::Bricks;
  d.procedural.size = 64;
  const Image a = make_texture(d, TexturePurpose::Albedo, LayerDesc{}, nullptr, "t");
  const Image b = make_texture(d, TexturePurpose::Albedo, LayerDesc{}, nullptr, "t");
  ASSERT_EQ(a.channels, 3);
  EXPECT_EQ(a.texels, b.texels);
  d.variation = 0.0f;
  const Image plain = make_texture(d, TexturePurpose::Albedo, LayerDesc{}, nullptr, "t");
  const Image h = generate_procedural(d.procedural);
  for (int i = 0; i < 64 * 64; ++i)
    ASSERT_EQ(plain.texels[3 * std::size_t(i) + 1], d.color_low.g + (d.color_high.g - d.color_low.g) * h.texels[std::size_t(i)]);
}

}  // namespace
}  // namespace qdmr
