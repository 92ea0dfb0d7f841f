#include <gtest/gtest.h>

#include <tbb/task_arena.h>

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <random>
#include <vector>

#include "qdmr/texture/bc3.hpp"

namespace qdmr {
namespace {

using Texels = std::array<std::uint8_t, 16>;

Bc3AlphaBlock make_block(int a0, int a1, std::uint64_t index_bits) {
  Bc3AlphaBlock block{std::uint8_t(a0), std::uint8_t(a1)};
  for (int b = 0; b < 6; ++b) block[std::size_t(2 + b)] = std::uint8_t(index_bits >> (8 * b));
  return block;
}

Texels decode(const Bc3AlphaBlock& block) {
  Texels out{};
  decode_bc3_alpha(block, out.data());
  return out;
}

// Texel i holds index i % 8: octal 76543210 twice.
constexpr std::uint64_t kEachIndexTwice = 076543210ull | (076543210ull << 24);

TEST(TextureBc3, DecodesEightValueBlocksRoundingToNearest) {
  // (6*255)/7 = 218.57 -> 219, (5*255)/7 = 182.14, (4*255)/7 = 145.71 -> 146, 109.29, 72.86 -> 73, 36.43.
  const Texels full = decode(make_block(255, 0, kEachIndexTwice));
  EXPECT_EQ(full, (Texels{255, 0, 219, 182, 146, 109, 73, 36, 255, 0, 219, 182, 146, 109, 73, 36}));
  // 6/7, 5/7, 4/7 round up to 1; 3/7, 2/7, 1/7 down to 0.
  const Texels tiny = decode(make_block(1, 0, kEachIndexTwice));
  EXPECT_EQ(tiny, (Texels{1, 0, 1, 1, 1, 0, 0, 0, 1, 0, 1, 1, 1, 0, 0, 0}));
  // (6*200 + 100)/7 = 185.71 -> 186, 171.43, 157.14, 142.86 -> 143, 128.57 -> 129, 114.29.
  const Texels mid = decode(make_block(200, 100, kEachIndexTwice));
  EXPECT_EQ(mid, (Texels{200, 100, 186, 171, 157, 143, 129, 114, 200, 100, 186, 171, 157, 143, 129, 114}));
}

TEST(TextureBc3, DecodesSixValueBlocksWithZeroAndOne) {
  // (4*10 + 23)/5 = 12.6 -> 13, (3*10 + 2*23)/5 = 15.2, 17.8 -> 18, 20.4; then 0 and 255.
  const Texels six = decode(make_block(10, 23, kEachIndexTwice));
  EXPECT_EQ(six, (Texels{10, 23, 13, 15, 18, 20, 0, 255, 10, 23, 13, 15, 18, 20, 0, 255}));
  // a0 == a1 is the 6-value mode too.
  const Texels equal = decode(make_block(77, 77, kEachIndexTwice));
  EXPECT_EQ(equal, (Texels{77, 77, 77, 77, 77, 77, 0, 255, 77, 77, 77, 77, 77, 77, 0, 255}));
}

TEST(TextureBc3, IndexOfTexelXYIsAtBit16Plus3TimesXPlus4Y) {
  for (int t = 0; t < 16; ++t) {
    const Bc3AlphaBlock block = make_block(200, 100, 7ull << (3 * t));  // texel t: index 7, (200 + 6*100)/7 = 114.29
    Texels expected{};
    expected.fill(200);
    expected[std::size_t(t)] = 114;
    EXPECT_EQ(decode(block), expected) << "texel " << t;
  }
}

Texels roundtrip(const Texels& texels) { return decode(encode_bc3_alpha(texels.data())); }

std::int64_t squared_error(const Texels& a, const Texels& b) {
  std::int64_t sum = 0;
  for (std::size_t i = 0; i < 16; ++i) sum += (int(a[i]) - int(b[i])) * (int(a[i]) - int(b[i]));
  return sum;
}

int max_error(const Texels& a, const Texels& b) {
  int m = 0;
  for (std::size_t i = 0; i < 16; ++i) m = std::max(m, std::abs(int(a[i]) - int(b[i])));
  return m;
}

// The texels replaced by their nearest entries in the palette of endpoints (a0, a1), by brute force.
Texels nearest_in_palette(const Texels& texels, int a0, int a1) {
  const Texels palette = decode(make_block(a0, a1, kEachIndexTwice));
  Texels out{};
  for (std::size_t i = 0; i < 16; ++i) {
    int best = palette[0];
    for (std::size_t k = 1; k < 8; ++k)
      if (std::abs(int(palette[k]) - int(texels[i])) < std::abs(best - int(texels[i]))) best = palette[k];
    out[i] = std::uint8_t(best);
  }
  return out;
}

TEST(TextureBc3, ConstantBlocksAreLossless) {
  for (int v = 0; v < 256; ++v) {
    Texels texels{};
    texels.fill(std::uint8_t(v));
    EXPECT_EQ(roundtrip(texels), texels) << "value " << v;
  }
}

TEST(TextureBc3, TwoValueBlocksAreLossless) {
  std::mt19937 rng(7);
  for (int n = 0; n < 5000; ++n) {
    const std::uint8_t a = std::uint8_t(rng() % 256), b = std::uint8_t(rng() % 256);
    const std::uint32_t pattern = rng();
    Texels texels{};
    for (std::size_t i = 0; i < 16; ++i) texels[i] = (pattern >> i) & 1 ? a : b;
    ASSERT_EQ(roundtrip(texels), texels) << int(a) << " " << int(b) << " pattern " << pattern;
  }
  const Texels extremes{0, 255, 0, 255, 255, 0, 255, 0, 0, 0, 255, 255, 255, 255, 0, 0};
  EXPECT_EQ(roundtrip(extremes), extremes);
}

TEST(TextureBc3, PicksTheSixValueModeWhenItIsBetter) {
  // 0 and 255 plus values on the 6-value grid of (50, 100): exact only in 6-value mode.
  const Texels specials{0, 255, 50, 60, 70, 80, 90, 100, 100, 90, 80, 70, 60, 50, 255, 0};
  const Bc3AlphaBlock block = encode_bc3_alpha(specials.data());
  EXPECT_LE(block[0], block[1]);
  EXPECT_EQ(decode(block), specials);

  // No 0 or 255, but six evenly spaced values 2 apart: the 8-value grid (20, 10) misses 12 and 18.
  const Texels grid{10, 12, 14, 16, 18, 20, 10, 12, 14, 16, 18, 20, 10, 12, 14, 16};
  EXPECT_GT(squared_error(nearest_in_palette(grid, 20, 10), grid), 0);
  const Bc3AlphaBlock grid_block = encode_bc3_alpha(grid.data());
  EXPECT_LE(grid_block[0], grid_block[1]);
  EXPECT_EQ(decode(grid_block), grid);

  // A smooth ramp is served better by 8 values.
  Texels ramp{};
  for (std::size_t i = 0; i < 16; ++i) ramp[i] = std::uint8_t(100 + 5 * i);
  EXPECT_GT(encode_bc3_alpha(ramp.data())[0], encode_bc3_alpha(ramp.data())[1]);
}

// Random blocks of varied ranges and spreads, some with 0 or 255 thrown in.
Texels random_block(std::mt19937& rng) {
  const int lo = int(rng() % 256);
  const int span = int(rng() % std::uint32_t(256 - lo));
  Texels texels{};
  for (std::size_t i = 0; i < 16; ++i) texels[i] = std::uint8_t(lo + int(rng() % std::uint32_t(span + 1)));
  if (rng() % 4 == 0) texels[rng() % 16] = 0;
  if (rng() % 4 == 0) texels[rng() % 16] = 255;
  return texels;
}

TEST(TextureBc3, ErrorIsBoundedAndNeverWorseThanThePlainEightValuePair) {
  std::mt19937 rng(2024);
  for (int n = 0; n < 20000; ++n) {
    const Texels texels = random_block(rng);
    const auto [lo, hi] = std::minmax_element(texels.begin(), texels.end());
    const double bound = double(*hi - *lo) / 14.0 + 1.0;

    const Bc3AlphaBlock block = encode_bc3_alpha(texels.data());
    const Texels decoded = decode(block);
    // Indices are the nearest palette entries of the chosen endpoints.
    ASSERT_EQ(squared_error(decoded, texels), squared_error(nearest_in_palette(texels, block[0], block[1]), texels));
    if (*hi == *lo) {
      ASSERT_EQ(decoded, texels);
      continue;
    }
    const Texels plain = nearest_in_palette(texels, *hi, *lo);
    ASSERT_LE(max_error(plain, texels), bound) << "block " << n;
    ASSERT_LE(squared_error(decoded, texels), squared_error(plain, texels)) << "block " << n;
    if (block[0] > block[1]) {
      ASSERT_LE(max_error(decoded, texels), bound) << "block " << n;
    }
  }
}

// Pads the image with guard bytes on both sides to show that only the w x h texels are touched.
struct GuardedImage {
  static constexpr std::size_t kGuard = 64;
  static constexpr std::uint8_t kGuardValue = 0xA5;
  std::vector<std::uint8_t> storage;
  int width, height;

  GuardedImage(int w, int h, std::uint32_t seed) : storage(std::size_t(w) * std::size_t(h) + 2 * kGuard, kGuardValue), width(w), height(h) {
    std::mt19937 rng(seed);
    for (int y = 0; y < h; ++y)
      for (int x = 0; x < w; ++x) data()[std::size_t(y) * std::size_t(w) + std::size_t(x)] = std::uint8_t((x * 13 + y * 7 + int(rng() % 40)) % 256);
  }
  std::uint8_t* data() { return storage.data() + kGuard; }
  std::vector<std::uint8_t> texels() const {
    return {storage.begin() + std::ptrdiff_t(kGuard), storage.end() - std::ptrdiff_t(kGuard)};
  }
  bool guards_intact() const {
    return std::all_of(storage.begin(), storage.begin() + std::ptrdiff_t(kGuard), [](std::uint8_t b) { return b == kGuardValue; }) &&
           std::all_of(storage.end() - std::ptrdiff_t(kGuard), storage.end(), [](std::uint8_t b) { return b == kGuardValue; });
  }
};

TEST(TextureBc3, RoundtripOfOddSizesTouchesOnlyExistingTexelsAndReportsTheirError) {
  for (const auto& [w, h] : {std::pair{1, 1}, {3, 5}, {17, 9}, {4, 4}, {8, 12}}) {
    GuardedImage image(w, h, std::uint32_t(w * 100 + h));
    const std::vector<std::uint8_t> original = image.texels();
    const Bc3Report report = bc3_roundtrip(image.data(), w, h);
    const std::vector<std::uint8_t> result = image.texels();
    EXPECT_TRUE(image.guards_intact()) << w << "x" << h;
    EXPECT_EQ(report.blocks, std::size_t((w + 3) / 4) * std::size_t((h + 3) / 4));

    // Each block again by hand: edge texels replicated into the missing ones.
    int max = 0;
    double squared = 0;
    for (int by = 0; by < (h + 3) / 4; ++by) {
      for (int bx = 0; bx < (w + 3) / 4; ++bx) {
        Texels source{};
        for (int y = 0; y < 4; ++y)
          for (int x = 0; x < 4; ++x)
            source[std::size_t(x + 4 * y)] = original[std::size_t(std::min(4 * by + y, h - 1) * w + std::min(4 * bx + x, w - 1))];
        const Texels decoded = roundtrip(source);
        for (int y = 4 * by; y < std::min(4 * by + 4, h); ++y) {
          for (int x = 4 * bx; x < std::min(4 * bx + 4, w); ++x) {
            const std::size_t i = std::size_t(y * w + x);
            ASSERT_EQ(result[i], decoded[std::size_t(x - 4 * bx + 4 * (y - 4 * by))]) << w << "x" << h << " at " << x << "," << y;
            const int error = std::abs(int(result[i]) - int(original[i]));
            max = std::max(max, error);
            squared += double(error * error);
          }
        }
      }
    }
    EXPECT_EQ(report.max_error, double(max)) << w << "x" << h;
    EXPECT_NEAR(report.rms_error, std::sqrt(squared / double(w * h)), 1e-12) << w << "x" << h;
  }
}

TEST(TextureBc3, RoundtripIsIndependentOfTheThreadCount) {
  const int w = 257, h = 131;
  GuardedImage one(w, h, 99), two(w, h, 99);
  Bc3Report report_one, report_two;
  tbb::task_arena(1).execute([&] { report_one = bc3_roundtrip(one.data(), w, h); });
  tbb::task_arena(2).execute([&] { report_two = bc3_roundtrip(two.data(), w, h); });
  EXPECT_EQ(one.texels(), two.texels());
  EXPECT_EQ(report_one.max_error, report_two.max_error);
  EXPECT_EQ(report_one.rms_error, report_two.rms_error);
  EXPECT_EQ(report_one.blocks, report_two.blocks);
  EXPECT_GT(report_one.rms_error, 0.0);
}

}  // namespace
}  // namespace qdmr
