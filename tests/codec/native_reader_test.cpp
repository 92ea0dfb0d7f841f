// codec/native_reader.hpp: PNG and JPEG files read by libpng and libjpeg-turbo in process give what
// OpenImageIO's readers give (with oiio:UnassociatedAlpha, as the backend opens files): the same size, channels,
// sample type and every sample's bits, over the layouts each format has; and a damaged file fails in both.
#include <gtest/gtest.h>

#include <OpenImageIO/imageio.h>
#include <png.h>
#include <stdio.h>

#include <jpeglib.h>

#include <cmath>
#include <csetjmp>
#include <cstdint>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <string>
#include <vector>

#include "codec/native_reader.hpp"
#include "codec/read_both_ways.hpp"
#include "support/test_support.hpp"

namespace qdmr::test {
namespace {

namespace fs = std::filesystem;

// Odd sizes: partial bytes of 1- to 4-bit rows, partial JPEG blocks and chroma pairs.
constexpr int kWidth = 37, kHeight = 23;

// --- PNG files, written by libpng ---------------------------------------------------------------------------

struct PngLayout {
  const char* name;
  int color_type, bit_depth;
  bool transparency;  // a tRNS chunk
  bool interlaced;
};

[[noreturn]] void png_write_failed(png_structp png, png_const_charp message) {
  ADD_FAILURE() << "libpng: " << message;
  png_longjmp(png, 1);
}

struct PngParts {
  png_bytep* rows;
  png_color* palette;
  int palette_size;
  png_byte* palette_alpha;
  png_color_16* key;  // the transparent grey or colour
  png_text* text;
  int texts;
};

// The libpng calls, apart: the jump of an error leaves no C++ object behind (and nothing to clobber).
void write_png_parts(png_structp png, png_infop info, std::FILE* out, const PngLayout& layout, const PngParts& parts) {
  if (setjmp(png_jmpbuf(png))) return;
  png_init_io(png, out);
  png_set_IHDR(png, info, kWidth, kHeight, layout.bit_depth, layout.color_type,
               layout.interlaced ? PNG_INTERLACE_ADAM7 : PNG_INTERLACE_NONE, PNG_COMPRESSION_TYPE_DEFAULT,
               PNG_FILTER_TYPE_DEFAULT);
  if (layout.color_type == PNG_COLOR_TYPE_PALETTE) png_set_PLTE(png, info, parts.palette, parts.palette_size);
  if (layout.transparency) {
    if (layout.color_type == PNG_COLOR_TYPE_PALETTE)
      png_set_tRNS(png, info, parts.palette_alpha, parts.palette_size, nullptr);
    else
      png_set_tRNS(png, info, nullptr, 0, parts.key);
  }
  if (parts.texts > 0) png_set_text(png, info, parts.text, parts.texts);
  png_write_info(png, info);
  png_write_image(png, parts.rows);
  png_write_end(png, nullptr);
}

// Samples from a hash: every value of the bit depth occurs (palette indices below the palette's size); with tRNS,
// the transparent grey / colour is the first pixel's, so some pixels take it.
void write_png_file(const fs::path& file, const PngLayout& layout, const std::vector<std::pair<std::string, std::string>>& texts) {
  std::FILE* out = std::fopen(file.string().c_str(), "wb");
  ASSERT_NE(out, nullptr);
  png_structp png = png_create_write_struct(PNG_LIBPNG_VER_STRING, nullptr, png_write_failed, nullptr);
  png_infop info = png_create_info_struct(png);
  const int channels = layout.color_type == PNG_COLOR_TYPE_GRAY || layout.color_type == PNG_COLOR_TYPE_PALETTE ? 1
                       : layout.color_type == PNG_COLOR_TYPE_GRAY_ALPHA                                     ? 2
                       : layout.color_type == PNG_COLOR_TYPE_RGB                                            ? 3
                                                                                                            : 4;
  // Palettes of 8-bit indices hold fewer entries than the depth could address (3 of 4 bits' 16, 253 of 256).
  const int max = (1 << layout.bit_depth) - (layout.color_type == PNG_COLOR_TYPE_PALETTE && layout.bit_depth >= 4 ? 3 : 1);
  std::vector<std::uint32_t> samples(std::size_t(kWidth) * kHeight * channels);
  for (std::size_t i = 0; i < samples.size(); ++i)
    samples[i] = sample_hash(std::uint32_t(i) * 2654435761u + 17u) % std::uint32_t(max + 1);
  // Rows packed as PNG stores them: big-endian 16-bit samples, sub-byte samples from the high bits.
  const std::size_t row_bytes = (std::size_t(kWidth) * channels * layout.bit_depth + 7) / 8;
  std::vector<unsigned char> rows(row_bytes * kHeight, 0);
  for (int y = 0; y < kHeight; ++y)
    for (int i = 0; i < kWidth * channels; ++i) {
      const std::uint32_t v = samples[std::size_t(y) * kWidth * channels + std::size_t(i)];
      unsigned char* row = rows.data() + row_bytes * std::size_t(y);
      if (layout.bit_depth == 16) {
        row[2 * i] = static_cast<unsigned char>(v >> 8);
        row[2 * i + 1] = static_cast<unsigned char>(v);
      } else {
        const int bit = i * layout.bit_depth;
        row[bit / 8] |= static_cast<unsigned char>(v << (8 - layout.bit_depth - bit % 8));
      }
    }
  std::vector<png_bytep> pointers(kHeight);
  for (int y = 0; y < kHeight; ++y) pointers[std::size_t(y)] = rows.data() + row_bytes * std::size_t(y);
  std::vector<png_color> palette(std::size_t(max) + 1);
  std::vector<png_byte> palette_alpha(palette.size());
  for (std::size_t i = 0; i < palette.size(); ++i) {
    palette[i] = {static_cast<png_byte>(sample_hash(std::uint32_t(i))),
                  static_cast<png_byte>(sample_hash(std::uint32_t(i) + 99)), static_cast<png_byte>(i * 37)};
    palette_alpha[i] = static_cast<png_byte>(255 - i * 29);
  }
  std::vector<png_text> text(texts.size());
  for (std::size_t i = 0; i < texts.size(); ++i) {
    text[i].compression = PNG_TEXT_COMPRESSION_NONE;
    text[i].key = const_cast<char*>(texts[i].first.c_str());
    text[i].text = const_cast<char*>(texts[i].second.c_str());
  }
  png_color_16 key{};
  key.gray = static_cast<png_uint_16>(samples[0]);
  key.red = static_cast<png_uint_16>(samples[0]);
  key.green = static_cast<png_uint_16>(samples[1 % samples.size()]);
  key.blue = static_cast<png_uint_16>(samples[2 % samples.size()]);
  const PngParts parts{pointers.data(), palette.data(), int(palette.size()), palette_alpha.data(), &key, text.data(),
                       int(text.size())};
  write_png_parts(png, info, out, layout, parts);
  png_destroy_write_struct(&png, &info);
  std::fclose(out);
}

TEST(NativeReader, PngOfEveryLayoutReadsAsOpenImageIOReadsIt) {
  TempDir dir;
  const PngLayout layouts[] = {
      {"grey1", PNG_COLOR_TYPE_GRAY, 1, false, false},        {"grey2", PNG_COLOR_TYPE_GRAY, 2, false, false},
      {"grey4", PNG_COLOR_TYPE_GRAY, 4, false, false},        {"grey8", PNG_COLOR_TYPE_GRAY, 8, false, false},
      {"grey16", PNG_COLOR_TYPE_GRAY, 16, false, false},      {"grey8_trns", PNG_COLOR_TYPE_GRAY, 8, true, false},
      {"grey16_trns", PNG_COLOR_TYPE_GRAY, 16, true, false},  {"grey2_trns", PNG_COLOR_TYPE_GRAY, 2, true, false},
      {"ya8", PNG_COLOR_TYPE_GRAY_ALPHA, 8, false, false},    {"ya16", PNG_COLOR_TYPE_GRAY_ALPHA, 16, false, false},
      {"rgb8", PNG_COLOR_TYPE_RGB, 8, false, false},          {"rgb16", PNG_COLOR_TYPE_RGB, 16, false, false},
      {"rgb8_trns", PNG_COLOR_TYPE_RGB, 8, true, false},      {"rgb16_trns", PNG_COLOR_TYPE_RGB, 16, true, false},
      {"rgba8", PNG_COLOR_TYPE_RGBA, 8, false, false},        {"rgba16", PNG_COLOR_TYPE_RGBA, 16, false, false},
      {"palette1", PNG_COLOR_TYPE_PALETTE, 1, false, false},  {"palette2", PNG_COLOR_TYPE_PALETTE, 2, false, false},
      {"palette4", PNG_COLOR_TYPE_PALETTE, 4, false, false},  {"palette8", PNG_COLOR_TYPE_PALETTE, 8, false, false},
      {"palette4_trns", PNG_COLOR_TYPE_PALETTE, 4, true, false},
      {"palette8_trns", PNG_COLOR_TYPE_PALETTE, 8, true, false},
      {"grey1_adam7", PNG_COLOR_TYPE_GRAY, 1, false, true},   {"grey16_adam7", PNG_COLOR_TYPE_GRAY, 16, false, true},
      {"rgb8_adam7", PNG_COLOR_TYPE_RGB, 8, false, true},     {"rgba16_adam7", PNG_COLOR_TYPE_RGBA, 16, false, true},
      {"palette4_trns_adam7", PNG_COLOR_TYPE_PALETTE, 4, true, true},
      {"ya8_adam7", PNG_COLOR_TYPE_GRAY_ALPHA, 8, false, true}};
  for (const PngLayout& layout : layouts) {
    const fs::path file = dir / (std::string(layout.name) + ".png");
    write_png_file(file, layout, {});
    expect_same_as_oiio(file);
  }
  // Text chunks: qdmr's own stamps, which `qdmr check` reads back (a later chunk replacing an earlier one, keys
  // matched as OpenImageIO matches attribute names, without regard to case).
  const fs::path stamped = dir / "stamped.png";
  write_png_file(stamped, {"stamped", PNG_COLOR_TYPE_RGB, 8, false, false},
                 {{"Software", "someone else"}, {"qdmr:bits_version", "7"}, {"software", "qdmr 9.9 (bits version 7)"}});
  expect_same_as_oiio(stamped);
  Decoded native;
  std::string error;
  ASSERT_TRUE(read_natively(stamped, native, error)) << error;
  EXPECT_EQ(native.bits_version, "7");
  EXPECT_EQ(native.software, "qdmr 9.9 (bits version 7)");
}

// --- JPEG files, written by libjpeg ---------------------------------------------------------------------------

struct JpegLayout {
  const char* name;
  int components;            // of the input: 1 grey, 3 RGB, 4 CMYK
  J_COLOR_SPACE stored;      // the file's colour space
  int h_luma, v_luma;        // the first component's sampling factors (the others 1)
  bool progressive, arithmetic;
  int restart_rows;
};

struct JpegWriteErrors {
  jpeg_error_mgr pub;
  std::jmp_buf jump;
};

[[noreturn]] void jpeg_write_failed(j_common_ptr cinfo) {
  char text[JMSG_LENGTH_MAX];
  (*cinfo->err->format_message)(cinfo, text);
  ADD_FAILURE() << "libjpeg: " << text;
  std::longjmp(reinterpret_cast<JpegWriteErrors*>(cinfo->err)->jump, 1);
}

// The libjpeg calls, apart: the jump of an error leaves no C++ object behind (and nothing to clobber).
void write_jpeg_parts(j_compress_ptr cinfo, JpegWriteErrors* errors, std::FILE* out, const JpegLayout& layout,
                      const unsigned char* pixels) {
  if (setjmp(errors->jump)) return;
  jpeg_create_compress(cinfo);
  jpeg_stdio_dest(cinfo, out);
  cinfo->image_width = kWidth;
  cinfo->image_height = kHeight;
  cinfo->input_components = layout.components;
  cinfo->in_color_space = layout.components == 1 ? JCS_GRAYSCALE : layout.components == 3 ? JCS_RGB : JCS_CMYK;
  jpeg_set_defaults(cinfo);
  jpeg_set_colorspace(cinfo, layout.stored);
  jpeg_set_quality(cinfo, 85, TRUE);
  cinfo->comp_info[0].h_samp_factor = layout.h_luma;
  cinfo->comp_info[0].v_samp_factor = layout.v_luma;
  for (int c = 1; c < cinfo->num_components; ++c) cinfo->comp_info[c].h_samp_factor = cinfo->comp_info[c].v_samp_factor = 1;
  cinfo->arith_code = layout.arithmetic ? TRUE : FALSE;
  cinfo->restart_in_rows = layout.restart_rows;
  if (layout.progressive) jpeg_simple_progression(cinfo);
  jpeg_start_compress(cinfo, TRUE);
  while (cinfo->next_scanline < cinfo->image_height) {
    JSAMPROW row = const_cast<unsigned char*>(pixels) + std::size_t(cinfo->next_scanline) * kWidth * std::size_t(layout.components);
    jpeg_write_scanlines(cinfo, &row, 1);
  }
  jpeg_finish_compress(cinfo);
}

void write_jpeg_file(const fs::path& file, const JpegLayout& layout) {
  std::vector<unsigned char> pixels(std::size_t(kWidth) * kHeight * std::size_t(layout.components));
  // A smooth field with some noise: quantisation and chroma subsampling have work to do.
  for (int y = 0; y < kHeight; ++y)
    for (int x = 0; x < kWidth; ++x)
      for (int c = 0; c < layout.components; ++c)
        pixels[(std::size_t(y) * kWidth + std::size_t(x)) * std::size_t(layout.components) + std::size_t(c)] =
            static_cast<unsigned char>(
                (x * 6 + y * (3 + c * 2) + c * 50 + int(sample_hash(std::uint32_t(x * 131 + y * 7 + c)) % 24)) & 255);
  std::FILE* out = std::fopen(file.string().c_str(), "wb");
  ASSERT_NE(out, nullptr);
  jpeg_compress_struct cinfo{};
  JpegWriteErrors errors{};
  cinfo.err = jpeg_std_error(&errors.pub);
  errors.pub.error_exit = jpeg_write_failed;
  write_jpeg_parts(&cinfo, &errors, out, layout, pixels.data());
  jpeg_destroy_compress(&cinfo);
  std::fclose(out);
}

const JpegLayout kJpegLayouts[] = {
    {"grey", 1, JCS_GRAYSCALE, 1, 1, false, false, 0},   {"ycc444", 3, JCS_YCbCr, 1, 1, false, false, 0},
    {"ycc422", 3, JCS_YCbCr, 2, 1, false, false, 0},     {"ycc420", 3, JCS_YCbCr, 2, 2, false, false, 0},
    {"ycc440", 3, JCS_YCbCr, 1, 2, false, false, 0},     {"ycc411", 3, JCS_YCbCr, 4, 1, false, false, 0},
    {"rgb", 3, JCS_RGB, 1, 1, false, false, 0},          {"progressive420", 3, JCS_YCbCr, 2, 2, true, false, 0},
    {"progressive_grey", 1, JCS_GRAYSCALE, 1, 1, true, false, 0},
    {"arithmetic420", 3, JCS_YCbCr, 2, 2, false, true, 0},
    {"restarts420", 3, JCS_YCbCr, 2, 2, false, false, 1}, {"cmyk", 4, JCS_CMYK, 1, 1, false, false, 0},
    {"ycck", 4, JCS_YCCK, 2, 2, false, false, 0}};

TEST(NativeReader, JpegOfEveryLayoutReadsAsOpenImageIOReadsIt) {
  TempDir dir;
  for (const JpegLayout& layout : kJpegLayouts) {
    const fs::path file = dir / (std::string(layout.name) + ".jpg");
    write_jpeg_file(file, layout);
    expect_same_as_oiio(file);
  }
}

// --- damaged files -------------------------------------------------------------------------------------------

// Damage in the pixel data (not in the headers image.cpp checks first): both readers fail, neither crashes.
TEST(NativeReader, DamagedPixelDataFailsInBothReaders) {
  TempDir dir;
  write_png_file(dir / "p.png", {"p", PNG_COLOR_TYPE_RGB, 8, false, false}, {});
  write_png_file(dir / "i.png", {"i", PNG_COLOR_TYPE_RGB, 8, false, true}, {});
  write_jpeg_file(dir / "j.jpg", kJpegLayouts[3]);
  write_jpeg_file(dir / "pj.jpg", kJpegLayouts[7]);
  int cases = 0;
  for (const char* name : {"p.png", "i.png"}) {
    // The IDAT's zlib data overwritten from its middle on (the CRC then fails too).
    std::string bytes = read_file(dir / name);
    const std::size_t idat = bytes.find("IDAT");
    ASSERT_NE(idat, std::string::npos);
    for (std::size_t i = idat + 30; i < idat + 60 && i < bytes.size(); ++i) bytes[i] = char(0xA5 ^ i);
    write_file(dir / (std::string("bad_") + name), bytes);
  }
  for (const char* name : {"j.jpg", "pj.jpg"}) {
    // The entropy-coded data cut after its first half and the end marker put back: libjpeg warns and pads.
    std::string bytes = read_file(dir / name);
    const std::size_t scan = bytes.find("\xFF\xDA");
    ASSERT_NE(scan, std::string::npos);
    bytes = bytes.substr(0, scan + (bytes.size() - scan) / 2) + "\xFF\xD9";
    write_file(dir / (std::string("bad_") + name), bytes);
  }
  for (const char* name : {"bad_p.png", "bad_i.png", "bad_j.jpg", "bad_pj.jpg"}) {
    Decoded oiio, native;
    std::string error;
    EXPECT_FALSE(read_with_oiio(dir / name, oiio)) << name;
    EXPECT_FALSE(read_natively(dir / name, native, error)) << name;
    EXPECT_FALSE(error.empty()) << name;
    ++cases;
  }
  EXPECT_EQ(cases, 4);
}

// Every sample of `file` as `type`, top row first.
std::vector<unsigned char> read_as(const fs::path& file, imageio::PixelType type) {
  Decoded decoded;
  std::string error;
  EXPECT_TRUE(read_natively(file, decoded, error, &type)) << error;
  return decoded.bytes;
}

// Asked for another type than the file's, a reader converts: k of b bits stands for k / (2^b - 1), as a float
// correctly rounded, as an integer of the other width the nearest one.
TEST(NativeReader, OtherSampleTypesAreTheFilesValuesConverted) {
  TempDir dir;
  write_png_file(dir / "g16.png", {"g16", PNG_COLOR_TYPE_GRAY, 16, false, false}, {});
  write_png_file(dir / "rgb8.png", {"rgb8", PNG_COLOR_TYPE_RGB, 8, false, false}, {});
  using imageio::PixelType;
  const auto wide = read_as(dir / "g16.png", PixelType::UInt16);
  const auto wide_f = read_as(dir / "g16.png", PixelType::Float);
  const auto wide_8 = read_as(dir / "g16.png", PixelType::UInt8);
  ASSERT_EQ(wide.size(), std::size_t(kWidth) * kHeight * 2);
  ASSERT_EQ(wide_f.size(), wide.size() * 2);
  for (std::size_t i = 0; i < wide.size() / 2; ++i) {
    std::uint16_t k;
    float f;
    std::memcpy(&k, wide.data() + 2 * i, 2);
    std::memcpy(&f, wide_f.data() + 4 * i, 4);
    ASSERT_EQ(f, float(k) / 65535.0f) << i;
    ASSERT_EQ(int(wide_8[i]), int(std::lround(k * 255.0 / 65535.0))) << i;
  }
  const auto narrow = read_as(dir / "rgb8.png", PixelType::UInt8);
  const auto narrow_f = read_as(dir / "rgb8.png", PixelType::Float);
  const auto narrow_16 = read_as(dir / "rgb8.png", PixelType::UInt16);
  ASSERT_EQ(narrow.size(), std::size_t(kWidth) * kHeight * 3);
  for (std::size_t i = 0; i < narrow.size(); ++i) {
    float f;
    std::uint16_t k16;
    std::memcpy(&f, narrow_f.data() + 4 * i, 4);
    std::memcpy(&k16, narrow_16.data() + 2 * i, 2);
    ASSERT_EQ(f, float(narrow[i]) / 255.0f) << i;
    ASSERT_EQ(int(k16), narrow[i] * 257) << i;
  }
  write_jpeg_file(dir / "j.jpg", kJpegLayouts[3]);
  const auto jpeg = read_as(dir / "j.jpg", PixelType::UInt8);
  const auto jpeg_f = read_as(dir / "j.jpg", PixelType::Float);
  ASSERT_EQ(jpeg.size(), std::size_t(kWidth) * kHeight * 3);
  for (std::size_t i = 0; i < jpeg.size(); ++i) {
    float f;
    std::memcpy(&f, jpeg_f.data() + 4 * i, 4);
    ASSERT_EQ(f, float(jpeg[i]) / 255.0f) << i;
  }
}

// A file of neither format is not claimed (the backend reads it); nothing is decoded.
TEST(NativeReader, OtherFilesAreLeftToTheBackend) {
  TempDir dir;
  write_file(dir / "x.png", "II*\0not really a TIFF");
  imageio::ReadSpec spec;
  std::string error;
  bool claimed = true;
  EXPECT_EQ(imageio::open_native((dir / "x.png").string(), spec, error, claimed), nullptr);
  EXPECT_FALSE(claimed);
  EXPECT_TRUE(error.empty());
}

}  // namespace
}  // namespace qdmr::test
