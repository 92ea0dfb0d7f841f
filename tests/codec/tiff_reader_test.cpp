// codec/tiff_reader.cpp: a TIFF whose layout OpenImageIO passes through as stored is read by libtiff in process
// and gives what OpenImageIO's reader gives (with oiio:UnassociatedAlpha, as the backend opens files): the same
// size, channels, sample type, Software tag and every sample's bits, over strips and tiles, interleaved and planar
// samples, every compression but JPEG, both byte orders and extra channels. The layouts OpenImageIO converts are
// left to it, but their header (read_tiff_header, all a plan reads) is the one OpenImageIO's open gives, damaged
// directories included, and reading it loads no image module. Damaged pixel data fails in both readers.
#include <gtest/gtest.h>

#include <OpenImageIO/imageio.h>
#include <tiffio.h>

#include <algorithm>
#include <cstdint>
#include <cstring>
#include <filesystem>
#include <optional>
#include <string>
#include <vector>

#include "codec/native_reader.hpp"
#include "codec/read_both_ways.hpp"
#include "qdmr/core/error.hpp"
#include "qdmr/texture/image.hpp"
#include "support/test_support.hpp"

namespace qdmr::test {
namespace {

namespace fs = std::filesystem;
using imageio::PixelType;

// Odd sizes: partial strips and partial tiles on the right and at the bottom.
constexpr std::uint32_t kWidth = 37, kHeight = 23;

struct TiffLayout {
  const char* name;
  std::uint16_t channels, photometric, bits, format;
  std::uint16_t compression = COMPRESSION_NONE, predictor = PREDICTOR_NONE;
  bool separate = false;
  std::uint32_t rows_per_strip = 1;  // 0: tiled, 16 x 16 (samples of 8 bits or more)
  bool big_endian = false;
  std::uint16_t extra = EXTRASAMPLE_UNASSALPHA;  // what the channels after the colour ones are
  const char* software = nullptr;
  bool bigtiff = false;  // the 64-bit offsets of BigTIFF (libtiff's "8" mode)
  int images = 1;        // directories: the first is the image read, the others differ from it
  std::uint16_t orientation = 0;  // a TIFF Orientation tag (0: none); neither reader applies it
};

std::size_t sample_bytes(std::uint16_t bits) { return bits <= 8 ? 1 : bits / 8; }

// Image `image` of the file: samples from a hash (of the image too): every value of the sample type occurs, floats
// of any bits (NaNs, infinities, denormals) included. Written in host order, libtiff swapping them for a big-endian
// file. False if libtiff failed to write a row or tile.
bool write_tiff_image(TIFF* tiff, const TiffLayout& layout, int image) {
  TIFFSetField(tiff, TIFFTAG_IMAGEWIDTH, kWidth);
  TIFFSetField(tiff, TIFFTAG_IMAGELENGTH, kHeight);
  TIFFSetField(tiff, TIFFTAG_SAMPLESPERPIXEL, layout.channels);
  TIFFSetField(tiff, TIFFTAG_BITSPERSAMPLE, layout.bits);
  TIFFSetField(tiff, TIFFTAG_SAMPLEFORMAT, layout.format);
  TIFFSetField(tiff, TIFFTAG_PHOTOMETRIC, layout.photometric);
  TIFFSetField(tiff, TIFFTAG_PLANARCONFIG, layout.separate ? PLANARCONFIG_SEPARATE : PLANARCONFIG_CONTIG);
  TIFFSetField(tiff, TIFFTAG_COMPRESSION, layout.compression);
  if (layout.predictor != PREDICTOR_NONE) TIFFSetField(tiff, TIFFTAG_PREDICTOR, layout.predictor);
  if (layout.software) TIFFSetField(tiff, TIFFTAG_SOFTWARE, layout.software);
  if (layout.orientation != 0) TIFFSetField(tiff, TIFFTAG_ORIENTATION, layout.orientation);
  const bool three = layout.photometric == PHOTOMETRIC_RGB || layout.photometric == PHOTOMETRIC_YCBCR ||
                     layout.photometric == PHOTOMETRIC_CIELAB;
  const std::uint16_t colour = three ? 3 : layout.photometric == PHOTOMETRIC_SEPARATED ? 4 : 1;
  if (layout.channels > colour) {
    const std::vector<std::uint16_t> extra(layout.channels - colour, layout.extra);
    TIFFSetField(tiff, TIFFTAG_EXTRASAMPLES, std::uint16_t(extra.size()), extra.data());
  }
  if (layout.photometric == PHOTOMETRIC_YCBCR) {
    // A chroma sample for every pixel, so rows are written as RGB's are; JPEG takes RGB and converts it.
    TIFFSetField(tiff, TIFFTAG_YCBCRSUBSAMPLING, 1, 1);
    if (layout.compression == COMPRESSION_JPEG) TIFFSetField(tiff, TIFFTAG_JPEGCOLORMODE, JPEGCOLORMODE_RGB);
  }
  if (layout.photometric == PHOTOMETRIC_PALETTE) {
    std::vector<std::uint16_t> r(256), g(256), b(256);
    for (std::uint32_t i = 0; i < 256; ++i) {
      r[i] = std::uint16_t(sample_hash(i));
      g[i] = std::uint16_t(sample_hash(i + 300));
      b[i] = std::uint16_t(i * 257);
    }
    TIFFSetField(tiff, TIFFTAG_COLORMAP, r.data(), g.data(), b.data());
  }
  const bool tiled = layout.rows_per_strip == 0;
  const std::uint32_t tile = 16;
  if (tiled) {
    TIFFSetField(tiff, TIFFTAG_TILEWIDTH, tile);
    TIFFSetField(tiff, TIFFTAG_TILELENGTH, tile);
  } else {
    TIFFSetField(tiff, TIFFTAG_ROWSPERSTRIP, layout.rows_per_strip);
  }
  const std::size_t per_pixel = layout.separate ? 1 : layout.channels;
  const std::size_t bytes = sample_bytes(layout.bits);
  // The sample at (x, y) of `plane` (or of channel c of an interleaved pixel), its bytes in host order.
  const auto sample = [&](std::uint32_t x, std::uint32_t y, std::size_t c, unsigned char* out) {
    const std::uint32_t h =
        sample_hash((y * kWidth + x) * 8 + std::uint32_t(c) + 977u * layout.bits + 7919u * std::uint32_t(image));
    if (layout.bits < 8) {
      const std::size_t bit = (x * per_pixel + (layout.separate ? 0 : c)) * layout.bits;
      out[bit / 8 - (x * per_pixel * layout.bits) / 8] |=
          static_cast<unsigned char>((h & ((1u << layout.bits) - 1)) << (8 - layout.bits - bit % 8));
    } else {
      std::memcpy(out, &h, std::min(bytes, sizeof h));  // a double's high half left zero
    }
  };
  const std::uint16_t planes = layout.separate ? layout.channels : 1;
  bool written = true;
  if (tiled) {
    std::vector<unsigned char> buffer(std::size_t(TIFFTileSize64(tiff)));
    for (std::uint16_t plane = 0; plane < planes; ++plane)
      for (std::uint32_t y = 0; y < kHeight; y += tile)
        for (std::uint32_t x = 0; x < kWidth; x += tile) {
          std::fill(buffer.begin(), buffer.end(), 0);
          for (std::uint32_t r = 0; r < tile && y + r < kHeight; ++r)
            for (std::uint32_t col = 0; col < tile && x + col < kWidth; ++col)
              for (std::size_t c = 0; c < per_pixel; ++c)
                sample(x + col, y + r, layout.separate ? plane : c,
                       buffer.data() + ((std::size_t(r) * tile + col) * per_pixel + c) * bytes);
          written = written && TIFFWriteTile(tiff, buffer.data(), x, y, 0, plane) >= 0;
        }
  } else {
    std::vector<unsigned char> row(std::size_t(TIFFScanlineSize64(tiff)));
    for (std::uint16_t plane = 0; plane < planes; ++plane)
      for (std::uint32_t y = 0; y < kHeight; ++y) {
        std::fill(row.begin(), row.end(), 0);
        for (std::uint32_t x = 0; x < kWidth; ++x)
          for (std::size_t c = 0; c < per_pixel; ++c)
            sample(x, y, layout.separate ? plane : c,
                   layout.bits < 8 ? row.data() + (x * per_pixel * layout.bits) / 8
                                   : row.data() + (x * per_pixel + c) * bytes);
        written = written && TIFFWriteScanline(tiff, row.data(), y, plane) >= 0;
      }
  }
  return written;
}

void write_tiff_file(const fs::path& file, const TiffLayout& layout) {
  const std::string mode = std::string("w") + (layout.big_endian ? "b" : "l") + (layout.bigtiff ? "8" : "");
  TIFF* tiff = TIFFOpen(file.string().c_str(), mode.c_str());
  ASSERT_NE(tiff, nullptr) << layout.name;
  bool written = true;
  for (int image = 0; image < layout.images; ++image) {
    written = write_tiff_image(tiff, layout, image) && written;
    if (image + 1 < layout.images) written = TIFFWriteDirectory(tiff) == 1 && written;
  }
  TIFFClose(tiff);
  EXPECT_TRUE(written) << layout.name;
}

const TiffLayout kClaimed[] = {
    {"grey8", 1, PHOTOMETRIC_MINISBLACK, 8, SAMPLEFORMAT_UINT},
    {"grey16_be", 1, PHOTOMETRIC_MINISBLACK, 16, SAMPLEFORMAT_UINT, COMPRESSION_NONE, PREDICTOR_NONE, false, 1, true},
    {"grey_float", 1, PHOTOMETRIC_MINISBLACK, 32, SAMPLEFORMAT_IEEEFP, COMPRESSION_NONE, PREDICTOR_NONE, false, 5},
    {"grey_alpha8", 2, PHOTOMETRIC_MINISBLACK, 8, SAMPLEFORMAT_UINT, COMPRESSION_LZW, PREDICTOR_HORIZONTAL},
    {"grey_two_data16", 2, PHOTOMETRIC_MINISBLACK, 16, SAMPLEFORMAT_UINT, COMPRESSION_ADOBE_DEFLATE,
     PREDICTOR_NONE, true, 4, false, EXTRASAMPLE_UNSPECIFIED},
    {"rgb8", 3, PHOTOMETRIC_RGB, 8, SAMPLEFORMAT_UINT, COMPRESSION_NONE, PREDICTOR_NONE, false, 23, false,
     EXTRASAMPLE_UNASSALPHA, "qdmr 0.1.0 (bits version 5)"},
    {"rgb8_lzw", 3, PHOTOMETRIC_RGB, 8, SAMPLEFORMAT_UINT, COMPRESSION_LZW, PREDICTOR_HORIZONTAL, false, 8},
    {"rgb8_packbits_planar", 3, PHOTOMETRIC_RGB, 8, SAMPLEFORMAT_UINT, COMPRESSION_PACKBITS, PREDICTOR_NONE, true, 3},
    {"rgb16_deflate_be", 3, PHOTOMETRIC_RGB, 16, SAMPLEFORMAT_UINT, COMPRESSION_ADOBE_DEFLATE,
     PREDICTOR_HORIZONTAL, false, 7, true},
    {"rgb16_zstd_tiled", 3, PHOTOMETRIC_RGB, 16, SAMPLEFORMAT_UINT, COMPRESSION_ZSTD, PREDICTOR_NONE, false, 0},
    {"rgb_float_predictor", 3, PHOTOMETRIC_RGB, 32, SAMPLEFORMAT_IEEEFP, COMPRESSION_ADOBE_DEFLATE,
     PREDICTOR_FLOATINGPOINT, false, 6},
    {"rgb_float_lzma_tiled_be", 3, PHOTOMETRIC_RGB, 32, SAMPLEFORMAT_IEEEFP, COMPRESSION_LZMA, PREDICTOR_NONE,
     false, 0, true},
    {"rgba8_assoc", 4, PHOTOMETRIC_RGB, 8, SAMPLEFORMAT_UINT, COMPRESSION_NONE, PREDICTOR_NONE, false, 2, false,
     EXTRASAMPLE_ASSOCALPHA},
    {"rgba8_unassoc_tiled_planar", 4, PHOTOMETRIC_RGB, 8, SAMPLEFORMAT_UINT, COMPRESSION_LZW, PREDICTOR_NONE, true,
     0},
    {"rgba16_planar_be", 4, PHOTOMETRIC_RGB, 16, SAMPLEFORMAT_UINT, COMPRESSION_NONE, PREDICTOR_NONE, true, 23, true},
    {"rgba_float_tiled_planar", 4, PHOTOMETRIC_RGB, 32, SAMPLEFORMAT_IEEEFP, COMPRESSION_ZSTD,
     PREDICTOR_FLOATINGPOINT, true, 0},
    {"five_channels16", 5, PHOTOMETRIC_RGB, 16, SAMPLEFORMAT_UINT, COMPRESSION_LZW, PREDICTOR_HORIZONTAL, false, 9,
     false, EXTRASAMPLE_UNSPECIFIED},
    {"rgb8_bigtiff", 3, PHOTOMETRIC_RGB, 8, SAMPLEFORMAT_UINT, COMPRESSION_ADOBE_DEFLATE, PREDICTOR_NONE, false, 5,
     false, EXTRASAMPLE_UNASSALPHA, nullptr, true},
    {"grey16_bigtiff_tiled_be", 1, PHOTOMETRIC_MINISBLACK, 16, SAMPLEFORMAT_UINT, COMPRESSION_NONE, PREDICTOR_NONE,
     false, 0, true, EXTRASAMPLE_UNASSALPHA, nullptr, true},
    // Two images: both readers read the first (OpenImageIO's subimage 0).
    {"rgb8_two_images", 3, PHOTOMETRIC_RGB, 8, SAMPLEFORMAT_UINT, COMPRESSION_LZW, PREDICTOR_NONE, false, 4, false,
     EXTRASAMPLE_UNASSALPHA, nullptr, false, 2},
    // "Rotate 90 degrees clockwise to display": both readers give the samples as stored.
    {"grey8_orientation6", 1, PHOTOMETRIC_MINISBLACK, 8, SAMPLEFORMAT_UINT, COMPRESSION_NONE, PREDICTOR_NONE, false,
     3, false, EXTRASAMPLE_UNASSALPHA, nullptr, false, 1, ORIENTATION_RIGHTTOP},
};

TEST(TiffReader, LayoutsOpenImageIOPassesThroughReadAsItReadsThem) {
  TempDir dir;
  int compared = 0;
  for (const TiffLayout& layout : kClaimed) {
    SCOPED_TRACE(layout.name);
    const fs::path file = dir / (std::string(layout.name) + ".tif");
    write_tiff_file(file, layout);
    // The file is what the layout says: BigTIFF's version 43 in its header, every image a directory of its own.
    const std::string head = read_file(file).substr(0, 4);
    EXPECT_EQ(head[layout.big_endian ? 3 : 2], layout.bigtiff ? 43 : 42);
    TIFF* tiff = TIFFOpen(file.string().c_str(), "r");
    ASSERT_NE(tiff, nullptr);
    EXPECT_EQ(TIFFNumberOfDirectories(tiff), layout.images);
    TIFFClose(tiff);
    EXPECT_TRUE(imageio::read_natively(file.string()));
    expect_same_as_oiio(file);
    if (layout.orientation != 0) {  // the file carries the tag, and OpenImageIO reports it without applying it
      auto in = OIIO::ImageInput::open(file.string());
      ASSERT_TRUE(in);
      EXPECT_EQ(in->spec().get_int_attribute("Orientation"), int(layout.orientation));
      EXPECT_EQ(in->spec().width, int(kWidth));
    }
    ++compared;
  }
  EXPECT_EQ(compared, int(std::size(kClaimed)));
}

// The layouts OpenImageIO converts that qdmr takes as textures (1 to 4 channels), which the readers leave to it:
// every kind tiffinput.cpp treats apart (palettes; 1-, 2-, 4-, 10- and 12-bit samples; min-is-white; CMYK and other
// inks; signed, half, 32-bit integer, 24-bit float and double samples; JPEG with three samples or through libtiff's
// RGBA interface; YCbCr and CIE L*a*b*).
const TiffLayout kConverted[] = {
    {"palette8", 1, PHOTOMETRIC_PALETTE, 8, SAMPLEFORMAT_UINT},
    {"palette4_lzw", 1, PHOTOMETRIC_PALETTE, 4, SAMPLEFORMAT_UINT, COMPRESSION_LZW, PREDICTOR_NONE, false, 8},
    {"palette1_be", 1, PHOTOMETRIC_PALETTE, 1, SAMPLEFORMAT_UINT, COMPRESSION_NONE, PREDICTOR_NONE, false, 1, true},
    {"min_is_white1", 1, PHOTOMETRIC_MINISWHITE, 1, SAMPLEFORMAT_UINT},
    {"min_is_white8", 1, PHOTOMETRIC_MINISWHITE, 8, SAMPLEFORMAT_UINT},
    {"min_is_white16_alpha_deflate", 2, PHOTOMETRIC_MINISWHITE, 16, SAMPLEFORMAT_UINT, COMPRESSION_ADOBE_DEFLATE,
     PREDICTOR_NONE, false, 4},
    {"bilevel", 1, PHOTOMETRIC_MINISBLACK, 1, SAMPLEFORMAT_UINT},
    {"grey2", 1, PHOTOMETRIC_MINISBLACK, 2, SAMPLEFORMAT_UINT},
    {"grey4", 1, PHOTOMETRIC_MINISBLACK, 4, SAMPLEFORMAT_UINT},
    {"rgba4", 4, PHOTOMETRIC_RGB, 4, SAMPLEFORMAT_UINT},
    {"grey12", 1, PHOTOMETRIC_MINISBLACK, 12, SAMPLEFORMAT_UINT},
    {"rgb10_planar", 3, PHOTOMETRIC_RGB, 10, SAMPLEFORMAT_UINT, COMPRESSION_NONE, PREDICTOR_NONE, true},
    {"cmyk8", 4, PHOTOMETRIC_SEPARATED, 8, SAMPLEFORMAT_UINT},
    {"cmyk16_be", 4, PHOTOMETRIC_SEPARATED, 16, SAMPLEFORMAT_UINT, COMPRESSION_NONE, PREDICTOR_NONE, false, 1, true},
    {"three_inks8", 3, PHOTOMETRIC_SEPARATED, 8, SAMPLEFORMAT_UINT},
    {"grey_int8", 1, PHOTOMETRIC_MINISBLACK, 8, SAMPLEFORMAT_INT},
    {"grey_int16", 1, PHOTOMETRIC_MINISBLACK, 16, SAMPLEFORMAT_INT},
    {"rgb_int16", 3, PHOTOMETRIC_RGB, 16, SAMPLEFORMAT_INT},
    {"grey_half", 1, PHOTOMETRIC_MINISBLACK, 16, SAMPLEFORMAT_IEEEFP},
    {"rgba_half_tiled", 4, PHOTOMETRIC_RGB, 16, SAMPLEFORMAT_IEEEFP, COMPRESSION_NONE, PREDICTOR_NONE, false, 0},
    {"grey_uint32", 1, PHOTOMETRIC_MINISBLACK, 32, SAMPLEFORMAT_UINT},
    {"grey_int32", 1, PHOTOMETRIC_MINISBLACK, 32, SAMPLEFORMAT_INT},
    {"grey_float24", 1, PHOTOMETRIC_MINISBLACK, 24, SAMPLEFORMAT_IEEEFP},
    {"grey_double", 1, PHOTOMETRIC_MINISBLACK, 64, SAMPLEFORMAT_IEEEFP},
    {"rgb8_jpeg", 3, PHOTOMETRIC_RGB, 8, SAMPLEFORMAT_UINT, COMPRESSION_JPEG, PREDICTOR_NONE, false, 16},
    {"grey8_jpeg", 1, PHOTOMETRIC_MINISBLACK, 8, SAMPLEFORMAT_UINT, COMPRESSION_JPEG, PREDICTOR_NONE, false, 16},
    {"ycbcr8_jpeg", 3, PHOTOMETRIC_YCBCR, 8, SAMPLEFORMAT_UINT, COMPRESSION_JPEG, PREDICTOR_NONE, false, 16},
    {"ycbcr8", 3, PHOTOMETRIC_YCBCR, 8, SAMPLEFORMAT_UINT},
    {"cielab8", 3, PHOTOMETRIC_CIELAB, 8, SAMPLEFORMAT_UINT},
};

// What OpenImageIO converts (palette to RGB, min-is-white inverted, fewer bits widened, CMYK to RGB, JPEG and YCbCr
// through the RGBA interface) or reads in a type the readers do not have (signed, half float, 32-bit integers, double)
// is not claimed: the backend reads it, as before.
TEST(TiffReader, LayoutsOpenImageIOConvertsAreLeftToIt) {
  TempDir dir;
  int left = 0;
  for (const TiffLayout& layout : kConverted) {
    SCOPED_TRACE(layout.name);
    const fs::path file = dir / (std::string(layout.name) + ".tif");
    write_tiff_file(file, layout);
    Decoded oiio;
    EXPECT_TRUE(read_with_oiio(file, oiio)) << OIIO::geterror();  // a real file, which the backend reads
    EXPECT_FALSE(imageio::read_natively(file.string()));
    imageio::ReadSpec spec;
    std::string error = "untouched";
    bool claimed = true;
    EXPECT_EQ(imageio::open_native(file.string(), spec, error, claimed), nullptr);
    EXPECT_FALSE(claimed);
    EXPECT_EQ(error, "untouched");
    EXPECT_TRUE(spec.format.empty());
    ++left;
  }
  EXPECT_EQ(left, int(std::size(kConverted)));
}

// Asked for another type, the samples are converted as the PNG and JPEG readers convert them (k of b bits as
// k / (2^b - 1)), from planes and partial tiles too; a float file is read as floats only.
TEST(TiffReader, OtherSampleTypesAreTheFilesValuesConverted) {
  TempDir dir;
  const TiffLayout planar = kClaimed[13];  // rgba8_unassoc_tiled_planar
  const TiffLayout wide = kClaimed[14];    // rgba16_planar_be
  for (const TiffLayout& layout : {planar, wide}) {
    SCOPED_TRACE(layout.name);
    const fs::path file = dir / (std::string(layout.name) + ".tif");
    write_tiff_file(file, layout);
    Decoded stored, as_float;
    std::string error;
    const PixelType float_type = PixelType::Float;
    ASSERT_TRUE(read_natively(file, stored, error)) << error;
    ASSERT_TRUE(read_natively(file, as_float, error, &float_type)) << error;
    const std::size_t bytes = size_of(stored.type);
    ASSERT_EQ(as_float.bytes.size(), stored.bytes.size() / bytes * 4);
    const float max = bytes == 1 ? 255.0f : 65535.0f;
    for (std::size_t i = 0; i < stored.bytes.size() / bytes; ++i) {
      std::uint16_t k = 0;
      std::memcpy(&k, stored.bytes.data() + i * bytes, bytes);
      float f;
      std::memcpy(&f, as_float.bytes.data() + 4 * i, 4);
      ASSERT_EQ(f, float(k) / max) << i;
    }
  }
  const fs::path floats = dir / "f.tif";
  write_tiff_file(floats, kClaimed[2]);
  Decoded narrow;
  std::string error;
  const PixelType byte_type = PixelType::UInt8;
  EXPECT_FALSE(read_natively(floats, narrow, error, &byte_type));
  EXPECT_NE(error.find("read as floats only"), std::string::npos) << error;
}

// Compressed pixel data overwritten (the header intact, so libtiff opens the file): both readers fail, neither
// crashes, and the native one says what libtiff said.
TEST(TiffReader, DamagedPixelDataFailsInBothReaders) {
  TempDir dir;
  int cases = 0;
  for (const TiffLayout& layout : {kClaimed[4], kClaimed[6], kClaimed[9]}) {  // deflate, LZW strips; zstd tiles
    SCOPED_TRACE(layout.name);
    const fs::path file = dir / (std::string(layout.name) + ".tif");
    write_tiff_file(file, layout);
    // Where the first strip or tile is, from the file's own offsets.
    TIFF* tiff = TIFFOpen(file.string().c_str(), "r");
    ASSERT_NE(tiff, nullptr);
    std::uint64_t* offsets = nullptr;
    std::uint64_t* counts = nullptr;
    const bool tiled = TIFFIsTiled(tiff);
    ASSERT_EQ(TIFFGetField(tiff, tiled ? TIFFTAG_TILEOFFSETS : TIFFTAG_STRIPOFFSETS, &offsets), 1);
    ASSERT_EQ(TIFFGetField(tiff, tiled ? TIFFTAG_TILEBYTECOUNTS : TIFFTAG_STRIPBYTECOUNTS, &counts), 1);
    const std::uint64_t at = offsets[0], count = counts[0];
    TIFFClose(tiff);
    std::string bytes = read_file(file);
    ASSERT_LE(at + count, bytes.size());
    for (std::uint64_t i = at; i < at + count; ++i) bytes[i] = char(0xA5 ^ (i * 7));
    const fs::path bad = dir / (std::string("bad_") + layout.name + ".tif");
    write_file(bad, bytes);
    Decoded oiio, native;
    std::string error;
    EXPECT_FALSE(read_with_oiio(bad, oiio));
    EXPECT_TRUE(imageio::read_natively(bad.string()));  // the header is intact
    EXPECT_FALSE(read_natively(bad, native, error));
    EXPECT_FALSE(error.empty());
    EXPECT_EQ(error.find("could not decode"), std::string::npos) << error;  // libtiff's own words
    ++cases;
  }
  EXPECT_EQ(cases, 3);
}

// The header read_image_header makes of a reader's.
ImageHeader header_of(const imageio::ReadSpec& spec) {
  return {spec.width, spec.height, spec.channels,
          spec.uniform && spec.type == PixelType::UInt8 ? 8 : spec.uniform && spec.type == PixelType::UInt16 ? 16 : 32};
}

// The header OpenImageIO's open gives (the backend, linked into the tests); none, with `error`, if it fails.
std::optional<ImageHeader> oiio_header(const fs::path& file, std::string& error) {
  imageio::ReadSpec spec;
  imageio::Reader* reader = imageio::oiio_backend().open(file.string(), spec, error);
  if (!reader) return std::nullopt;
  imageio::oiio_backend().close(reader);
  EXPECT_EQ(spec.format, "tiff");
  EXPECT_EQ(spec.depth, 1);
  return header_of(spec);
}

void expect_same(const ImageHeader& header, const ImageHeader& oiio) {
  EXPECT_EQ(header.width, oiio.width);
  EXPECT_EQ(header.height, oiio.height);
  EXPECT_EQ(header.channels, oiio.channels);
  EXPECT_EQ(header.source_bits, oiio.source_bits);
}

// Their header, which a plan reads with libtiff (imageio::read_tiff_header), is the one OpenImageIO's open gives.
TEST(TiffHeader, LayoutsOpenImageIOConvertsHaveTheHeaderItGives) {
  TempDir dir;
  int compared = 0;
  for (const TiffLayout& layout : kConverted) {
    SCOPED_TRACE(layout.name);
    const fs::path file = dir / (std::string(layout.name) + ".tif");
    write_tiff_file(file, layout);
    std::string error;
    const std::optional<ImageHeader> oiio = oiio_header(file, error);
    ASSERT_TRUE(oiio) << error;
    imageio::ReadSpec spec;
    ASSERT_TRUE(imageio::read_tiff_header(file.string(), spec));
    EXPECT_EQ(spec.format, "tiff");
    expect_same(header_of(spec), *oiio);
    expect_same(read_image_header(file, "test"), *oiio);
    ++compared;
  }
  EXPECT_EQ(compared, int(std::size(kConverted)));
}

// `qdmr plan` of a scene with such a texture runs with no image module to load (QDMR_IMAGEIO_MODULE naming no file);
// rendering it still needs the module, and says so.
TEST(TiffHeader, PlanReadsThemWithoutTheImageModule) {
  TempDir dir;
  const std::string plane = (source_dir() / "scenes" / "plane.json").string();
  const std::string no_module = "QDMR_IMAGEIO_MODULE=" + (dir / "no-such-module.so").string();
  const auto albedo = [&](const fs::path& file) { return "/materials/bricks/layers/0/albedo=" + file.string(); };
  for (const TiffLayout& layout : kConverted) {
    SCOPED_TRACE(layout.name);
    const fs::path file = dir / (std::string(layout.name) + ".tif");
    write_tiff_file(file, layout);
    const CommandResult plan = run("/usr/bin/env", {no_module, cli().string(), "plan", plane, "--set", albedo(file)});
    EXPECT_EQ(plan.exit_code, 0) << plan.output;
  }
  const CommandResult render = run("/usr/bin/env", {no_module, cli().string(), "render", plane, "-o",
                                                     (dir / "p.png").string(), "--width", "32", "--height", "18",
                                                     "--set", albedo(dir / "palette8.tif")});
  EXPECT_EQ(render.exit_code, 2) << render.output;
  EXPECT_NE(render.output.find("cannot load libqdmr_imageio.so"), std::string::npos) << render.output;
}

// A TIFF libtiff opens but OpenImageIO's open refuses (samples it has no type for; a layout libtiff's RGBA interface
// refuses) is left to it, and refused as before: one error line naming the file.
TEST(TiffHeader, WhatOpenImageIORefusesIsRefusedAsBefore) {
  const TiffLayout kRefused[] = {
      {"grey_void16", 1, PHOTOMETRIC_MINISBLACK, 16, SAMPLEFORMAT_VOID},
      {"grey_uint64", 1, PHOTOMETRIC_MINISBLACK, 64, SAMPLEFORMAT_UINT},
      {"cielab_float", 3, PHOTOMETRIC_CIELAB, 32, SAMPLEFORMAT_IEEEFP},
  };
  TempDir dir;
  for (const TiffLayout& layout : kRefused) {
    SCOPED_TRACE(layout.name);
    const fs::path file = dir / (std::string(layout.name) + ".tif");
    write_tiff_file(file, layout);
    std::string error;
    EXPECT_FALSE(oiio_header(file, error));
    EXPECT_FALSE(error.empty());
    imageio::ReadSpec spec;
    EXPECT_FALSE(imageio::read_tiff_header(file.string(), spec));
    EXPECT_TRUE(spec.format.empty());
    try {
      read_image_header(file, "test");
      ADD_FAILURE() << "not refused";
    } catch (const Error& e) {
      const std::string message = e.what();
      EXPECT_NE(message.find(file.filename().string()), std::string::npos) << message;
      EXPECT_EQ(message.find('\n'), std::string::npos) << message;
    }
  }
}

// Damaged directories: every byte of a converted TIFF's directory (and of the values that follow it) overwritten in
// turn. Wherever libtiff's header is taken, OpenImageIO opens the file with the same header, or refuses it by its
// limits (1024 channels, 32 GiB of samples), which qdmr's own checks are inside: they refuse it too, with one error
// line naming the file. Any other file goes to OpenImageIO as before.
TEST(TiffHeader, DamagedDirectoriesGiveOpenImageIOsHeader) {
  TempDir dir;
  int taken = 0;
  for (const std::string name : {"palette8", "min_is_white8", "cmyk8", "grey_half", "grey8_jpeg", "ycbcr8_jpeg"}) {
    SCOPED_TRACE(name);
    const fs::path file = dir / "good.tif";
    write_tiff_file(file, *std::find_if(std::begin(kConverted), std::end(kConverted),
                                        [&](const TiffLayout& layout) { return layout.name == name; }));
    const std::string bytes = read_file(file);
    // Little-endian: the directory's offset, its entries' count, then 12 bytes an entry.
    std::uint32_t directory = 0;
    std::uint16_t entries = 0;
    std::memcpy(&directory, bytes.data() + 4, 4);
    ASSERT_LT(directory + 2, bytes.size());
    std::memcpy(&entries, bytes.data() + directory, 2);
    const std::size_t end = std::min<std::size_t>(bytes.size(), directory + 2 + 12 * entries + 4 + 64);
    for (std::size_t at = directory; at < end; ++at)
      for (const unsigned char value : {0x00, 0x03, 0xFF}) {
        if (static_cast<unsigned char>(bytes[at]) == value) continue;
        SCOPED_TRACE("byte " + std::to_string(at) + " = " + std::to_string(value));
        std::string damaged = bytes;
        damaged[at] = char(value);
        const fs::path bad = dir / "bad.tif";
        write_file(bad, damaged);
        imageio::ReadSpec spec;
        if (!imageio::read_tiff_header(bad.string(), spec)) continue;
        std::string error;
        const std::optional<ImageHeader> oiio = oiio_header(bad, error);
        if (oiio) expect_same(header_of(spec), *oiio);
        try {
          const ImageHeader header = read_image_header(bad, "test");
          ASSERT_TRUE(oiio) << "OpenImageIO refuses what libtiff's header took: " << error;
          expect_same(header, *oiio);
        } catch (const Error& e) {
          const std::string message = e.what();
          EXPECT_NE(message.find("bad.tif"), std::string::npos) << message;
          EXPECT_EQ(message.find('\n'), std::string::npos) << message;
        }
        ++taken;
      }
  }
  EXPECT_GT(taken, 1000);
}

}  // namespace
}  // namespace qdmr::test
