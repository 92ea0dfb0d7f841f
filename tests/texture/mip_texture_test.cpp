#include <gtest/gtest.h>
#include <tbb/task_arena.h>

#include <algorithm>
#include <cmath>
#include <cstring>
#include <limits>
#include <random>
#include <vector>

#include "kernel/kernel.hpp"
#include "qdmr/core/error.hpp"
#include "qdmr/texture/mip_texture.hpp"
#include "texture/internal.hpp"

namespace qdmr {
namespace {

std::uint8_t byte_at(const Texture& t, int level, int x, int y, int c = 0) { return t.texel_address(level, x, y)[c]; }

std::uint16_t r16_at(const Texture& t, int level, int x, int y) {
  std::uint16_t v;
  std::memcpy(&v, t.texel_address(level, x, y), sizeof v);
  return v;
}

// A w x h image of one row of values per channel, channel-major in `values`.
Image row_image(const std::vector<float>& values, int channels = 1) {
  Image img(int(values.size()) / channels, 1, channels);
  img.texels.assign(values.begin(), values.end());
  return img;
}

Image random_image(int w, int h, int channels, std::mt19937& rng) {
  std::uniform_real_distribution<float> u(0.0f, 1.0f);
  Image img(w, h, channels);
  for (float& v : img.texels) v = u(rng);
  return img;
}

TEST(TextureFormat, NamesRoundTrip) {
  for (TexelFormat f : {TexelFormat::R8, TexelFormat::RG8, TexelFormat::RGBA8, TexelFormat::R16, TexelFormat::R32F})
    EXPECT_EQ(parse_format(format_name(f)), f);
  EXPECT_EQ(format_name(TexelFormat::RGBA8), "rgba8");
  EXPECT_EQ(parse_format("r32f"), TexelFormat::R32F);
  EXPECT_FALSE(parse_format("rgb8").has_value());
  EXPECT_FALSE(parse_format("").has_value());
}

TEST(MipTexture, LayoutOfNonPowerOfTwo) {
  const Texture t = allocate_texture(5, 3, TexelFormat::R8, false);
  ASSERT_EQ(t.level_count(), 3);
  EXPECT_EQ(t.levels[0].width, 5);
  EXPECT_EQ(t.levels[0].height, 3);
  EXPECT_EQ(t.levels[1].width, 2);
  EXPECT_EQ(t.levels[1].height, 1);
  EXPECT_EQ(t.levels[2].width, 1);
  EXPECT_EQ(t.levels[2].height, 1);
  EXPECT_EQ(t.levels[0].offset, 0u);
  EXPECT_EQ(t.levels[1].offset, 64u);
  EXPECT_EQ(t.levels[2].offset, 128u);
  EXPECT_EQ(t.bytes(), 128u + 1u + Texture::kTailPadding);

  const Texture rgba = allocate_texture(8, 8, TexelFormat::RGBA8, true);
  ASSERT_EQ(rgba.level_count(), 4);
  EXPECT_EQ(rgba.levels[1].offset, 256u);
  EXPECT_EQ(rgba.levels[2].offset, 320u);
  EXPECT_EQ(rgba.levels[3].offset, 384u);
  EXPECT_EQ(rgba.bytes(), 388u + Texture::kTailPadding);
}

TEST(MipTexture, LayoutOfThinTextures) {
  const Texture one = allocate_texture(1, 1, TexelFormat::R32F, false);
  ASSERT_EQ(one.level_count(), 1);
  EXPECT_EQ(one.bytes(), 4u + Texture::kTailPadding);

  const Texture column = allocate_texture(1, 7, TexelFormat::R16, false);
  ASSERT_EQ(column.level_count(), 3);
  EXPECT_EQ(column.levels[1].width, 1);
  EXPECT_EQ(column.levels[1].height, 3);
  EXPECT_EQ(column.levels[2].height, 1);
  EXPECT_EQ(column.bytes(), 128u + 2u + Texture::kTailPadding);
}

TEST(MipTexture, LayoutInvariants) {
  std::mt19937 rng(7);
  std::uniform_int_distribution<int> side(1, 700);
  for (int n = 0; n < 100; ++n) {
    const int w = side(rng), h = side(rng);
    const auto format = TexelFormat(n % 5);
    const Texture t = allocate_texture(w, h, format, false);
    const std::size_t bpt = std::size_t(bytes_per_texel(format));
    std::size_t end = 0;
    for (int k = 0; k < t.level_count(); ++k) {
      const TextureLevel& l = t.levels[std::size_t(k)];
      EXPECT_EQ(l.width, k == 0 ? w : std::max(1, t.levels[std::size_t(k) - 1].width / 2));
      EXPECT_EQ(l.height, k == 0 ? h : std::max(1, t.levels[std::size_t(k) - 1].height / 2));
      EXPECT_EQ(l.offset % 64, 0u);
      EXPECT_GE(l.offset, end);
      EXPECT_LT(l.offset, end + 64);
      end = l.offset + std::size_t(l.width) * std::size_t(l.height) * bpt;
    }
    EXPECT_EQ(t.levels.back().width, 1);
    EXPECT_EQ(t.levels.back().height, 1);
    EXPECT_EQ(t.bytes(), end + Texture::kTailPadding);
    EXPECT_TRUE(std::all_of(t.storage.begin(), t.storage.end(), [](std::uint8_t b) { return b == 0; }));
  }
}

TEST(MipTexture, RejectsBadSizesAndFormats) {
  EXPECT_THROW(allocate_texture(0, 4, TexelFormat::R8, false), Error);
  EXPECT_THROW(allocate_texture(4, -1, TexelFormat::R8, false), Error);
  EXPECT_THROW(allocate_texture(16385, 1, TexelFormat::R8, false), Error);
  EXPECT_THROW(allocate_texture(4, 4, TexelFormat::R16, true), Error);
  EXPECT_THROW(make_mip_texture(Image(2, 2, 1), TexelFormat::R8, false, MipReduce::BoxNormal), Error);
  EXPECT_THROW(make_mip_texture(Image(2, 2, 5), TexelFormat::RGBA8, false, MipReduce::Box), Error);
}

TEST(MipTexture, QuantisesToNearest) {
  const float nan = std::numeric_limits<float>::quiet_NaN();
  const std::vector<float> values = {0.0f, 1.0f, 0.5f, -1.0f, 2.0f, nan, 1.0f / 255.0f, 0.4f / 255.0f, 0.6f / 255.0f};
  const Texture r8 = make_mip_texture(row_image(values), TexelFormat::R8, false, MipReduce::Box);
  const std::vector<int> want8 = {0, 255, 128, 0, 255, 0, 1, 0, 1};  // 0.5 * 255 = 127.5 rounds up
  for (int i = 0; i < int(values.size()); ++i) {
    EXPECT_EQ(byte_at(r8, 0, i, 0), want8[std::size_t(i)]) << i;
    EXPECT_EQ(r8.texel(0, i, 0, 0), float(want8[std::size_t(i)]) / 255.0f) << i;
  }

  const Texture r16 = make_mip_texture(row_image(values), TexelFormat::R16, false, MipReduce::Box);
  const std::vector<int> want16 = {0, 65535, 32768, 0, 65535, 0, 257, 103, 154};
  for (int i = 0; i < int(values.size()); ++i) {
    EXPECT_EQ(r16_at(r16, 0, i, 0), want16[std::size_t(i)]) << i;
    EXPECT_EQ(r16.texel(0, i, 0, 0), float(want16[std::size_t(i)]) / 65535.0f) << i;
  }

  const Texture r32 = make_mip_texture(row_image({-0.25f, 3.5f}), TexelFormat::R32F, false, MipReduce::Box);
  EXPECT_EQ(r32.texel(0, 0, 0, 0), -0.25f);
  EXPECT_EQ(r32.texel(0, 1, 0, 0), 3.5f);
  EXPECT_EQ(r32.texel(1, 0, 0, 0), 1.625f);
}

TEST(MipTexture, FillsMissingChannels) {
  const Texture t = make_mip_texture(row_image({0.2f, 0.6f}, 2), TexelFormat::RGBA8, false, MipReduce::Box);
  EXPECT_EQ(byte_at(t, 0, 0, 0, 0), 51);
  EXPECT_EQ(byte_at(t, 0, 0, 0, 1), 153);
  EXPECT_EQ(byte_at(t, 0, 0, 0, 2), 0);
  EXPECT_EQ(byte_at(t, 0, 0, 0, 3), 255);
}

TEST(MipTexture, SrgbRoundTripsEveryCode) {
  std::vector<float> linear(256);
  for (int k = 0; k < 256; ++k) linear[std::size_t(k)] = texture_detail::srgb_to_linear(float(k) / 255.0f);
  const Texture t = make_mip_texture(row_image(linear), TexelFormat::R8, true, MipReduce::Max);
  for (int k = 0; k < 256; ++k) {
    EXPECT_EQ(byte_at(t, 0, k, 0), k);
    EXPECT_EQ(t.texel(0, k, 0, 0), linear[std::size_t(k)]);
  }
}

TEST(MipTexture, SrgbEncodeRoundsInTheEncodedDomain) {
  std::mt19937 rng(3);
  std::uniform_real_distribution<float> u(0.0f, 1.0f);
  std::vector<float> values(4096);
  for (float& v : values) v = u(rng);
  const Texture t = make_mip_texture(row_image(values), TexelFormat::R8, true, MipReduce::Max);
  for (int i = 0; i < int(values.size()); ++i) {
    const double v = values[std::size_t(i)];
    const double encoded = v <= 0.0031308 ? v * 12.92 : 1.055 * std::pow(v, 1.0 / 2.4) - 0.055;
    EXPECT_EQ(byte_at(t, 0, i, 0), int(std::floor(encoded * 255.0 + 0.5))) << v;
  }
}

// At every code boundary: the floats within 4 ulps of each decoded midpoint between two codes encode to the
// number of midpoints at or below them (the definition of rounding in the encoded domain).
TEST(MipTexture, SrgbEncodeIsExactAtEveryCodeBoundary) {
  const auto decode = [](double e) { return e <= 0.04045 ? e / 12.92 : std::pow((e + 0.055) / 1.055, 2.4); };
  std::vector<double> mid(255);
  for (int k = 0; k < 255; ++k) mid[std::size_t(k)] = decode((k + 0.5) / 255.0);
  std::vector<float> values;
  for (const double m : mid) {
    float v = float(m);
    for (int step = 0; step < 4; ++step) v = std::nextafter(v, 0.0f);
    for (int step = 0; step < 9; ++step, v = std::nextafter(v, 1.0f)) values.push_back(v);
  }
  const Texture t = make_mip_texture(row_image(values), TexelFormat::R8, true, MipReduce::Max);
  for (int i = 0; i < int(values.size()); ++i) {
    const double v = values[std::size_t(i)];
    const int expected = int(std::upper_bound(mid.begin(), mid.end(), v) - mid.begin());
    ASSERT_EQ(byte_at(t, 0, i, 0), expected) << v;
  }
}

TEST(MipTexture, SrgbAlphaIsLinear) {
  const Texture t = make_mip_texture(row_image({0.5f, 0.5f, 0.5f, 0.5f}, 4), TexelFormat::RGBA8, true, MipReduce::Box);
  EXPECT_EQ(byte_at(t, 0, 0, 0, 0), 188);  // encode(0.5) = 0.7354
  EXPECT_EQ(byte_at(t, 0, 0, 0, 3), 128);
}

// Level 0 with the given 8-bit codes, row-major.
Texture r8_texture(int w, int h, const std::vector<int>& codes, bool srgb = false) {
  Texture t = allocate_texture(w, h, TexelFormat::R8, srgb);
  for (std::size_t i = 0; i < codes.size(); ++i) t.storage[i] = std::uint8_t(codes[i]);
  return t;
}

TEST(MipTexture, BoxFourByFour) {
  std::vector<int> codes(16);
  for (int i = 0; i < 16; ++i) codes[std::size_t(i)] = 10 * i;
  Texture t = r8_texture(4, 4, codes);
  build_mip_levels(t, MipReduce::Box);
  EXPECT_EQ(byte_at(t, 1, 0, 0), 25);  // (0 + 10 + 40 + 50) / 4
  EXPECT_EQ(byte_at(t, 1, 1, 0), 45);
  EXPECT_EQ(byte_at(t, 1, 0, 1), 105);
  EXPECT_EQ(byte_at(t, 1, 1, 1), 125);
  EXPECT_EQ(byte_at(t, 2, 0, 0), 75);
}

TEST(MipTexture, BoxThreeByThreeUsesAllNine) {
  Texture t = r8_texture(3, 3, {0, 10, 20, 30, 40, 50, 60, 70, 80});
  build_mip_levels(t, MipReduce::Box);
  ASSERT_EQ(t.level_count(), 2);
  EXPECT_EQ(byte_at(t, 1, 0, 0), 40);
  Texture row = r8_texture(5, 1, {0, 10, 20, 30, 100});
  build_mip_levels(row, MipReduce::Box);
  EXPECT_EQ(byte_at(row, 1, 0, 0), 5);
  EXPECT_EQ(byte_at(row, 1, 1, 0), 50);  // (20 + 30 + 100) / 3
}

TEST(MipTexture, SrgbBoxAveragesLinearLight) {
  Texture t = r8_texture(2, 1, {0, 255}, true);
  build_mip_levels(t, MipReduce::Box);
  EXPECT_EQ(byte_at(t, 1, 0, 0), 188);  // linear 0.5, not code 128
}

TEST(MipTexture, BoxNormalRenormalises) {
  // +x, +z, +x, +z stored as 0.5 + 0.5 n: codes (255, 128, 128) and (128, 128, 255).
  const Image normals = row_image({1, 0.5f, 0.5f, 1, 0.5f, 0.5f, 1, 1, 1, 0.5f, 0.5f, 1, 0.5f, 0.5f, 1, 1}, 4);
  Image square(2, 2, 4);
  square.texels = normals.texels;
  const Texture t = make_mip_texture(square, TexelFormat::RGBA8, false, MipReduce::BoxNormal);
  EXPECT_EQ(byte_at(t, 1, 0, 0, 0), 218);  // 0.5 + 0.5 * 0.70708
  EXPECT_EQ(byte_at(t, 1, 0, 0, 1), 128);
  EXPECT_EQ(byte_at(t, 1, 0, 0, 2), 218);
  EXPECT_EQ(byte_at(t, 1, 0, 0, 3), 255);

  const Texture opposite =
      make_mip_texture(row_image({0, 0, 0, 0.2f, 1, 1, 1, 0.4f}, 4), TexelFormat::RGBA8, false, MipReduce::BoxNormal);
  EXPECT_EQ(byte_at(opposite, 1, 0, 0, 0), 128);  // zero sum: (0, 0, 1)
  EXPECT_EQ(byte_at(opposite, 1, 0, 0, 1), 128);
  EXPECT_EQ(byte_at(opposite, 1, 0, 0, 2), 255);
  EXPECT_EQ(byte_at(opposite, 1, 0, 0, 3), 77);  // (51 + 102) / 2 = 76.5
}

// Level-0 index range [first, last] covered by each texel of each level, along one axis.
std::vector<std::vector<std::pair<int, int>>> footprints(const Texture& t, bool x_axis) {
  std::vector<std::vector<std::pair<int, int>>> out;
  for (int k = 0; k < t.level_count(); ++k) {
    const int n = x_axis ? t.levels[std::size_t(k)].width : t.levels[std::size_t(k)].height;
    std::vector<std::pair<int, int>> level(static_cast<std::size_t>(n));
    for (int i = 0; i < n; ++i) {
      if (k == 0) {
        level[std::size_t(i)] = {i, i};
        continue;
      }
      const auto& child = out.back();
      const int child_n = int(child.size());
      const int first = child_n == 1 ? 0 : 2 * i;
      const int last = child_n == 1 ? 0 : (i == n - 1 ? child_n - 1 : 2 * i + 1);
      level[std::size_t(i)] = {child[std::size_t(first)].first, child[std::size_t(last)].second};
    }
    out.push_back(std::move(level));
  }
  return out;
}

// Every parent is the max (min) of exactly its children; hence of its whole level-0 footprint.
void expect_extremum_chain(const Texture& t, bool is_max) {
  const auto pick = [is_max](float a, float b) { return is_max ? std::max(a, b) : std::min(a, b); };
  for (int k = 1; k < t.level_count(); ++k) {
    const TextureLevel& in = t.levels[std::size_t(k) - 1];
    const TextureLevel& out = t.levels[std::size_t(k)];
    for (int y = 0; y < out.height; ++y)
      for (int x = 0; x < out.width; ++x) {
        const int x0 = in.width == 1 ? 0 : 2 * x, y0 = in.height == 1 ? 0 : 2 * y;
        const int x1 = in.width == 1 ? 0 : (x == out.width - 1 ? in.width - 1 : 2 * x + 1);
        const int y1 = in.height == 1 ? 0 : (y == out.height - 1 ? in.height - 1 : 2 * y + 1);
        for (int c = 0; c < t.channels(); ++c) {
          float want = t.texel(k - 1, x0, y0, c);
          for (int j = y0; j <= y1; ++j)
            for (int i = x0; i <= x1; ++i) want = pick(want, t.texel(k - 1, i, j, c));
          ASSERT_EQ(t.texel(k, x, y, c), want) << "level " << k << " (" << x << ", " << y << ") of " << t.width()
                                               << "x" << t.height() << " " << format_name(t.format);
        }
      }
  }
  const auto fx = footprints(t, true), fy = footprints(t, false);
  for (int k = 1; k < t.level_count(); ++k)
    for (int y = 0; y < t.levels[std::size_t(k)].height; ++y)
      for (int x = 0; x < t.levels[std::size_t(k)].width; ++x)
        for (int c = 0; c < t.channels(); ++c) {
          const float v = t.texel(k, x, y, c);
          const auto [x0, x1] = fx[std::size_t(k)][std::size_t(x)];
          const auto [y0, y1] = fy[std::size_t(k)][std::size_t(y)];
          for (int j = y0; j <= y1; ++j)
            for (int i = x0; i <= x1; ++i) {
              const float v0 = t.texel(0, i, j, c);
              ASSERT_TRUE(is_max ? v >= v0 : v <= v0) << "level " << k << " misses level-0 texel " << i << ", " << j;
            }
        }
}

// The portable reducer's chains, and every kernel's this CPU runs: the same bits.
void check_sizes(TexelFormat format, const std::vector<std::pair<int, int>>& sizes) {
  std::mt19937 rng(11);
  for (const auto& [w, h] : sizes) {
    const Image level0 = random_image(w, h, channel_count(format), rng);
    const Texture max = make_mip_texture(level0, format, false, MipReduce::Max);
    const Texture min = make_mip_texture(level0, format, false, MipReduce::Min);
    expect_extremum_chain(max, true);
    expect_extremum_chain(min, false);
    for (const Isa isa : usable_isas()) {
      const MipExtremum extremum = kernel_for(isa).mip_extremum();
      ASSERT_EQ(make_mip_texture(level0, format, false, MipReduce::Max, extremum).storage, max.storage)
          << isa_name(isa) << " max, " << w << "x" << h << " " << format_name(format);
      ASSERT_EQ(make_mip_texture(level0, format, false, MipReduce::Min, extremum).storage, min.storage)
          << isa_name(isa) << " min, " << w << "x" << h << " " << format_name(format);
    }
  }
}

std::vector<std::pair<int, int>> small_sizes() {
  std::vector<std::pair<int, int>> sizes;
  for (int h = 1; h <= 37; ++h)
    for (int w = 1; w <= 37; ++w) sizes.emplace_back(w, h);
  return sizes;
}

// Wide enough for whole vectors (and a scalar tail) in every format.
std::vector<std::pair<int, int>> wide_sizes() {
  std::mt19937 rng(5);
  std::uniform_int_distribution<int> side(1, 300);
  std::vector<std::pair<int, int>> sizes = {{64, 64}, {128, 2}, {129, 3}, {256, 1}, {1, 256}, {255, 257}};
  for (int i = 0; i < 24; ++i) sizes.emplace_back(side(rng), side(rng));
  return sizes;
}

TEST(MipTextureExtremum, R8EveryParentCoversItsChildren) {
  check_sizes(TexelFormat::R8, small_sizes());
  check_sizes(TexelFormat::R8, wide_sizes());
}

TEST(MipTextureExtremum, R16EveryParentCoversItsChildren) {
  check_sizes(TexelFormat::R16, small_sizes());
  check_sizes(TexelFormat::R16, wide_sizes());
}

TEST(MipTextureExtremum, R32FEveryParentCoversItsChildren) {
  check_sizes(TexelFormat::R32F, small_sizes());
  check_sizes(TexelFormat::R32F, wide_sizes());
}

TEST(MipTextureExtremum, MultiChannelPerChannel) {
  check_sizes(TexelFormat::RG8, wide_sizes());
  check_sizes(TexelFormat::RGBA8, wide_sizes());
}

TEST(MipTexture, ThreadCountDoesNotChangeTheResult) {
  std::mt19937 rng(13);
  const Image gray = random_image(1000, 777, 1, rng), colour = random_image(601, 403, 4, rng);
  const auto build = [&](int threads) {
    std::vector<std::vector<std::uint8_t>> out;
    tbb::task_arena(threads).execute([&] {
      const MipExtremum extremum = kernel_for(resolve_isa(Isa::Auto)).mip_extremum();
      out.push_back(make_mip_texture(gray, TexelFormat::R8, false, MipReduce::Max, extremum).storage);
      out.push_back(make_mip_texture(gray, TexelFormat::R32F, false, MipReduce::Min, extremum).storage);
      out.push_back(make_mip_texture(colour, TexelFormat::RGBA8, true, MipReduce::Box).storage);
      out.push_back(make_mip_texture(colour, TexelFormat::RGBA8, false, MipReduce::BoxNormal).storage);
    });
    return out;
  };
  EXPECT_EQ(build(1), build(2));
}

TEST(MipTexture, LevelImageDecodes) {
  Texture t = r8_texture(2, 2, {0, 51, 102, 255});
  const Image img = t.level_image(0);
  EXPECT_EQ(img.texels, (Texels{0.0f, 0.2f, 0.4f, 1.0f}));
  EXPECT_THROW(t.texel(0, 2, 0, 0), Error);
  EXPECT_THROW(t.level_image(2), Error);
}

}  // namespace
}  // namespace qdmr
