// codec/pnm_reader.cpp: PBM, PGM and PPM files read in process as Netpbm defines them. Where OpenImageIO's
// reader got them right (maxval 255 and 65535 below its overflow, bitmaps with separated samples), the same size,
// channels, type and bits as it; where it did not, the values Netpbm means: 16-bit samples above 32768 as stored,
// any other maxval as k / maxval, a plain bitmap's digits without separators one pixel each. PFM files as
// OpenImageIO reads them: rows bottom-up, the scale's sign the byte order, its magnitude a factor.
#include <gtest/gtest.h>

#include <cstdint>
#include <cstring>
#include <filesystem>
#include <initializer_list>
#include <string>
#include <utility>
#include <vector>

#include "codec/native_reader.hpp"
#include "codec/read_both_ways.hpp"
#include "support/test_support.hpp"

namespace qdmr::test {
namespace {

namespace fs = std::filesystem;
using imageio::PixelType;

constexpr int kPnmWidth = 37, kPnmHeight = 23;  // bitmap rows of 4 bytes and 5 bits

// A P1-P6 file of hashed samples in [0, limit] (limit <= maxval), with a comment in its header.
std::string pnm_file(int kind, std::uint32_t maxval, std::uint32_t limit) {
  const int channels = kind == 3 || kind == 6 ? 3 : 1;
  const bool bitmap = kind == 1 || kind == 4;
  std::string out = "P" + std::to_string(kind) + "\n# written by pnm_reader_test\n" + std::to_string(kPnmWidth) + " " +
                    std::to_string(kPnmHeight) + (bitmap ? "\n" : "\n" + std::to_string(maxval) + "\n");
  for (int y = 0; y < kPnmHeight; ++y) {
    std::vector<unsigned char> bits((kPnmWidth + 7) / 8, 0);
    for (int i = 0; i < kPnmWidth * channels; ++i) {
      const std::uint32_t k = sample_hash(std::uint32_t(y * 1000 + i) * 7u + maxval) % (limit + 1);
      if (kind == 4) {
        bits[std::size_t(i / 8)] |= static_cast<unsigned char>(k << (7 - i % 8));
      } else if (kind <= 3) {
        out += std::to_string(k) + (i % 9 == 8 ? "\n" : " ");
      } else if (maxval > 255) {
        out += char(k >> 8);
        out += char(k & 255);
      } else {
        out += char(k);
      }
    }
    if (kind == 4) out.append(bits.begin(), bits.end());
    if (kind <= 3) out += "\n";
  }
  return out;
}

// A PFM file ("Pf" or "PF") of hashed 32-bit patterns (every kind of float: NaN, infinities, denormals, -0 among
// them), `scale` written as given, the samples in the byte order its sign says.
std::string pfm_file(bool rgb, const std::string& scale) {
  const bool little = scale[0] == '-';
  std::string out = rgb ? "PF" : "Pf";  // appended piece by piece: GCC 12 warns wrongly on a chain of + here
  out += "\n# written by pnm_reader_test\n";
  out += std::to_string(kPnmWidth) + " " + std::to_string(kPnmHeight) + "\n" + scale + "\n";
  for (int i = 0; i < kPnmWidth * kPnmHeight * (rgb ? 3 : 1); ++i) {
    std::uint32_t bits = sample_hash(std::uint32_t(i) * 13u + (rgb ? 1u : 0u));
    if (i % 5 == 0) bits &= 0x807FFFFFu;  // denormals and zeros
    if (i % 7 == 0) bits |= 0x7F800000u;  // infinities and NaNs
    for (int b = 0; b < 4; ++b) out += char(bits >> (little ? 8 * b : 24 - 8 * b));
  }
  return out;
}

TEST(PnmReader, FilesOpenImageIOReadsRightReadAsItReadsThem) {
  struct Case {
    const char* name;
    int kind;
    std::uint32_t maxval, limit;
  };
  // OpenImageIO's 16-bit scaling overflows from 32769 on: those files keep below it here (see the next test).
  const Case cases[] = {{"plain_bitmap.pbm", 1, 1, 1},          {"bitmap.pbm", 4, 1, 1},
                        {"plain_grey.pgm", 2, 255, 255},        {"plain_grey16.pgm", 2, 65535, 32768},
                        {"plain_rgb.ppm", 3, 255, 255},         {"grey.pgm", 5, 255, 255},
                        {"grey16.pgm", 5, 65535, 32768},        {"rgb.ppm", 6, 255, 255},
                        {"rgb16.ppm", 6, 65535, 32768}};
  TempDir dir;
  for (const Case& c : cases) {
    write_file(dir / c.name, pnm_file(c.kind, c.maxval, c.limit));
    EXPECT_TRUE(imageio::read_natively((dir / c.name).string()));
    expect_same_as_oiio(dir / c.name);
  }
  // PFM: both byte orders, grey and RGB, scales of 1 (the usual) and others, which multiply every sample.
  const std::pair<const char*, std::string> pfm_cases[] = {
      {"grey_little.pfm", pfm_file(false, "-1.0")}, {"grey_big.pfm", pfm_file(false, "1")},
      {"rgb_little.pfm", pfm_file(true, "-1.000000")}, {"rgb_big.pfm", pfm_file(true, "+1.0")},
      {"rgb_scaled.pfm", pfm_file(true, "-2.5")}, {"grey_scaled.pfm", pfm_file(false, "0.3e-1")}};
  for (const auto& [name, bytes] : pfm_cases) {
    write_file(dir / name, bytes);
    EXPECT_TRUE(imageio::read_natively((dir / name).string())) << name;
    expect_same_as_oiio(dir / name);
  }
}

// A PFM's first row in the file is the image's last, and its values are the samples times the scale's magnitude.
TEST(PnmReader, PfmRowsRunBottomUp) {
  TempDir dir;
  const auto floats = [](std::initializer_list<float> values, bool little) {
    std::string out;
    for (const float v : values) {
      std::uint32_t bits;
      std::memcpy(&bits, &v, 4);
      for (int b = 0; b < 4; ++b) out += char(bits >> (little ? 8 * b : 24 - 8 * b));
    }
    return out;
  };
  write_file(dir / "two_rows.pfm", "Pf\n2 2\n-1.0\n" + floats({1.0f, 2.0f, 3.0f, 4.0f}, true));
  write_file(dir / "big_scaled.pfm", "Pf 2 2 4 " + floats({1.0f, 2.0f, 3.0f, 0.1f}, false));
  const std::pair<const char*, std::vector<float>> cases[] = {{"two_rows.pfm", {3.0f, 4.0f, 1.0f, 2.0f}},
                                                              {"big_scaled.pfm", {12.0f, 4.0f * 0.1f, 4.0f, 8.0f}}};
  for (const auto& [name, expected] : cases) {
    Decoded d;
    std::string error;
    ASSERT_TRUE(read_natively(dir / name, d, error)) << name << ": " << error;
    ASSERT_EQ(d.type, PixelType::Float);
    ASSERT_EQ(d.bytes.size(), 16u);
    std::vector<float> got(4);
    std::memcpy(got.data(), d.bytes.data(), 16);
    EXPECT_EQ(got, expected) << name;
  }
}

// The values Netpbm means where OpenImageIO's reader differs.
TEST(PnmReader, SamplesAreWhatNetpbmMeans) {
  TempDir dir;
  std::string error;
  Decoded d;
  // 16-bit samples above 32768 as stored (OpenImageIO: 65535 -> 65534, 40000 -> 39999).
  write_file(dir / "high.pgm", std::string("P5 4 1 65535\n") + std::string("\xFF\xFF\x9C\x40\x80\x01\x00\x07", 8));
  ASSERT_TRUE(read_natively(dir / "high.pgm", d, error)) << error;
  ASSERT_EQ(d.type, PixelType::UInt16);
  std::uint16_t k[4];
  std::memcpy(k, d.bytes.data(), 8);
  EXPECT_EQ(k[0], 65535);
  EXPECT_EQ(k[1], 40000);
  EXPECT_EQ(k[2], 32769);
  EXPECT_EQ(k[3], 7);
  // Another maxval: k / maxval as a float, correctly rounded (OpenImageIO: floor(k * 255 / 100) / 255); a sample
  // above maxval counts as maxval.
  write_file(dir / "percent.pgm", "P2\n3 2\n100\n0 1 33\n99 100 250\n");
  ASSERT_TRUE(read_natively(dir / "percent.pgm", d, error)) << error;
  ASSERT_EQ(d.type, PixelType::Float);
  const float expected[] = {0.0f, 1.0f / 100.0f, 33.0f / 100.0f, 99.0f / 100.0f, 1.0f, 1.0f};
  for (int i = 0; i < 6; ++i) {
    float v;
    std::memcpy(&v, d.bytes.data() + 4 * i, 4);
    EXPECT_EQ(v, expected[i]) << i;
  }
  write_file(dir / "wide.ppm", std::string("P6 1 1 1023\n") + std::string("\x03\xFF\x02\x00\x00\x01", 6));
  ASSERT_TRUE(read_natively(dir / "wide.ppm", d, error)) << error;
  ASSERT_EQ(d.channels, 3);
  float rgb[3];
  std::memcpy(rgb, d.bytes.data(), 12);
  EXPECT_EQ(rgb[0], 1.0f);
  EXPECT_EQ(rgb[1], 512.0f / 1023.0f);
  EXPECT_EQ(rgb[2], 1.0f / 1023.0f);
  // A plain bitmap's digits need no separators: "0110" is four pixels (1 is black).
  write_file(dir / "packed.pbm", "P1\n4 2\n0110\n1 0 0 1\n");
  ASSERT_TRUE(read_natively(dir / "packed.pbm", d, error)) << error;
  EXPECT_EQ(d.bytes, (std::vector<unsigned char>{255, 0, 0, 255, 0, 255, 255, 0}));
}

TEST(PnmReader, MalformedPixelDataFails) {
  TempDir dir;
  const std::pair<const char*, std::string> cases[] = {
      {"letter.pgm", "P2\n2 2\n255\n1 2\n3 x\n"},
      {"two_in_bitmap.pbm", "P1\n2 1\n0 2\n"},
      {"short.pgm", "P2\n2 2\n255\n1 2 3\n"},
      {"short_binary.ppm", std::string("P6\n2 1\n255\n") + "\x01\x02\x03"},
      {"short_bitmap.pbm", "P4\n9 2\n\xFF\x80"},
      {"short.pfm", "Pf\n2 1\n-1.0\n" + std::string(7, '\0')},
      {"zero_scale.pfm", "Pf\n1 1\n0.0\n" + std::string(4, '\0')},
      {"word_scale.pfm", "PF\n1 1\nbig\n" + std::string(12, '\0')},
      {"huge_scale.pfm", "Pf\n1 1\n-1e99\n" + std::string(4, '\0')},
      {"no_scale.pfm", "Pf\n1 1"},
  };
  for (const auto& [name, bytes] : cases) {
    SCOPED_TRACE(name);
    write_file(dir / name, bytes);
    Decoded d;
    std::string error;
    EXPECT_FALSE(read_natively(dir / name, d, error));
    EXPECT_FALSE(error.empty());
  }
}

}  // namespace
}  // namespace qdmr::test
