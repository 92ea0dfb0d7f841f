// Image comparison (qdmr/check/compare.hpp) and the canonical hash, on hand-made images with known answers.
#include <gtest/gtest.h>

#include <bit>
#include <cmath>
#include <cstdint>
#include <limits>

#include "check/canonical_hash.hpp"
#include "qdmr/check/compare.hpp"

namespace qdmr {
namespace {

Image flat(int w, int h, int c, float value) {
  Image image(w, h, c);
  for (float& v : image.texels) v = value;
  return image;
}

TEST(CanonicalHash, MatchesAnIndependentSha1OfTheDocumentedBytes) {
  // Expected values from Python: hashlib.sha1(b"qdmr-canonical-1 2 1 1\n" + struct.pack("<ff", 1.0, -0.0)), and
  // for the second, 0.5, a NaN written as 0x7fc00000, and +inf.
  const float a[] = {1.0f, -0.0f};
  EXPECT_EQ(canonical_hash(2, 1, 1, a), "sha1:38f61bf7b54fcd92b75c1db5f2762afa41f351bf");
  const float b[] = {0.5f, std::numeric_limits<float>::quiet_NaN(), std::numeric_limits<float>::infinity()};
  EXPECT_EQ(canonical_hash(1, 1, 3, b), "sha1:92427fa46605e3dc2f98823e0870797da75e2226");
}

TEST(CanonicalHash, CanonicalisesNaNButKeepsTheSignOfZeroAndTheShape) {
  const float nan1[] = {std::bit_cast<float>(0x7fc00001u)}, nan2[] = {std::bit_cast<float>(0xffc12345u)};
  EXPECT_EQ(canonical_hash(1, 1, 1, nan1), canonical_hash(1, 1, 1, nan2));
  const float plus[] = {0.0f}, minus[] = {-0.0f};
  EXPECT_NE(canonical_hash(1, 1, 1, plus), canonical_hash(1, 1, 1, minus));
  const float pair[] = {1.0f, 2.0f};
  EXPECT_NE(canonical_hash(2, 1, 1, pair), canonical_hash(1, 2, 1, pair));
}

TEST(Compare, IdenticalImagesPassWithInfinitePsnr) {
  const Image a = flat(8, 4, 3, 0.25f);
  const Comparison c = compare_images(a, a, Tolerance{});
  EXPECT_TRUE(c.passed());
  EXPECT_EQ(c.max_abs, 0.0);
  EXPECT_EQ(c.pixels_differing, 0);
  EXPECT_TRUE(std::isinf(c.psnr));
}

TEST(Compare, NamesTheWorstPixelFromTheTopLeftAndCountsPixelsOver) {
  const Image golden = flat(10, 10, 3, 0.5f);
  Image rendered = golden;
  rendered.at(7, 2, 1) = 0.9f;   // 0.4 off in G at x 7, row 2 from the top
  rendered.at(1, 1, 0) = 0.51f;  // 0.01 off: over the default bound (1/255)
  rendered.at(3, 3, 2) = 0.501f; // 0.001 off: within it
  const Comparison c = compare_images(rendered, golden, Tolerance{});
  EXPECT_FALSE(c.passed());
  EXPECT_EQ(c.pixels_differing, 3);
  EXPECT_EQ(c.pixels_over, 2);
  EXPECT_NEAR(c.max_abs, 0.4, 1e-6);  // float 0.9 - 0.5, exact to float rounding
  EXPECT_EQ(c.worst_x, 7);
  EXPECT_EQ(c.worst_y, 2);
  EXPECT_EQ(c.worst_channel, 1);
  ASSERT_EQ(c.failures.size(), 1u);
  EXPECT_NE(c.failures[0].find("at (7, 2) G"), std::string::npos) << c.failures[0];

  Tolerance two;
  two.max_pixels = 2;
  EXPECT_TRUE(compare_images(rendered, golden, two).passed());
  Tolerance fraction;
  fraction.max_fraction = 0.02;  // 2 of 100 pixels
  EXPECT_TRUE(compare_images(rendered, golden, fraction).passed());
  fraction.max_fraction = 0.019;
  EXPECT_FALSE(compare_images(rendered, golden, fraction).passed());
  Tolerance loose;
  loose.max_abs = 0.5;
  EXPECT_TRUE(compare_images(rendered, golden, loose).passed());
}

TEST(Compare, RadiusForgivesAOnePixelShift) {
  // A vertical edge at x = 4 in the golden, at x = 5 in the render: one column differs by 1.
  Image golden(10, 6, 1), rendered(10, 6, 1);
  for (int y = 0; y < 6; ++y)
    for (int x = 0; x < 10; ++x) {
      golden.at(x, y, 0) = x >= 4 ? 1.0f : 0.0f;
      rendered.at(x, y, 0) = x >= 5 ? 1.0f : 0.0f;
    }
  Tolerance strict;
  const Comparison c0 = compare_images(rendered, golden, strict);
  EXPECT_EQ(c0.pixels_over, 6);
  Tolerance shifted;
  shifted.radius = 1;
  const Comparison c1 = compare_images(rendered, golden, shifted);
  EXPECT_EQ(c1.pixels_over, 0);
  EXPECT_TRUE(c1.passed());
  EXPECT_EQ(c1.max_abs, 1.0);  // the metrics still see the raw difference
}

TEST(Compare, RmseAndPsnrBounds) {
  const Image golden = flat(4, 4, 3, 0.5f);
  const Image rendered = flat(4, 4, 3, 0.75f);  // every value 0.25 off: rmse 0.25, psnr 20 log10(4) dB
  Tolerance t;
  t.max_abs = 1;
  t.max_rmse = 0.3;
  t.min_psnr = 12.0;
  const Comparison pass = compare_images(rendered, golden, t);
  EXPECT_NEAR(pass.rmse, 0.25, 1e-12);
  EXPECT_NEAR(pass.psnr, 20.0 * std::log10(4.0), 1e-9);
  EXPECT_TRUE(pass.passed());
  t.max_rmse = 0.2;
  t.min_psnr = 13.0;
  const Comparison fail = compare_images(rendered, golden, t);
  ASSERT_EQ(fail.failures.size(), 2u);
  EXPECT_NE(fail.failures[0].find("rmse 0.25 > max_rmse 0.2"), std::string::npos) << fail.failures[0];
  EXPECT_NE(fail.failures[1].find("psnr"), std::string::npos);
}

TEST(Compare, NonFiniteValuesAreAlwaysAFailureEvenWhenBothImagesHaveThem) {
  Image golden = flat(4, 4, 1, 0.0f);
  golden.at(2, 3, 0) = std::numeric_limits<float>::quiet_NaN();
  const Image rendered = golden;
  const Comparison c = compare_images(rendered, golden, Tolerance{});
  EXPECT_EQ(c.pixels_over, 0);  // NaN against NaN is no difference...
  EXPECT_EQ(c.nonfinite_rendered, 1);
  EXPECT_EQ(c.nonfinite_golden, 1);
  ASSERT_EQ(c.failures.size(), 2u);  // ...but each image's NaN is reported
  EXPECT_NE(c.failures[0].find("first at (2, 3)"), std::string::npos) << c.failures[0];
  Image finite = flat(4, 4, 1, 0.0f);
  const Comparison d = compare_images(finite, golden, Tolerance{});
  EXPECT_EQ(d.pixels_over, 1);
  EXPECT_TRUE(std::isinf(d.max_abs));
}

TEST(Compare, ASizeOrChannelMismatchIsAFailureNotACrash) {
  const Comparison size = compare_images(flat(4, 4, 3, 0), flat(4, 5, 3, 0), Tolerance{});
  EXPECT_FALSE(size.comparable);
  ASSERT_EQ(size.failures.size(), 1u);
  EXPECT_EQ(size.failures[0], "size: rendered 4x4 with 3 channel(s), golden 4x5 with 3");
  EXPECT_FALSE(compare_images(flat(4, 4, 3, 0), flat(4, 4, 4, 0), Tolerance{}).passed());
}

TEST(Compare, HistogramCountsPixelsByDecadeOfTheirLargestDifference) {
  Image golden = flat(6, 1, 1, 0.0f), rendered = golden;
  rendered.at(1, 0, 0) = 5e-8f;  // (0, 1e-7]
  rendered.at(2, 0, 0) = 0.05f;  // (0.01, 0.1]
  rendered.at(3, 0, 0) = 0.5f;   // (0.1, 1]
  rendered.at(4, 0, 0) = 2.0f;   // > 1
  rendered.at(5, 0, 0) = std::numeric_limits<float>::infinity();
  const std::vector<std::int64_t> bins = delta_histogram(rendered, golden);
  const std::vector<std::int64_t> expected{1, 1, 0, 0, 0, 0, 0, 1, 1, 2};
  EXPECT_EQ(bins, expected);
  EXPECT_EQ(delta_bin_label(0), "0");
  EXPECT_EQ(delta_bin_label(9), ">1");
}

TEST(Compare, HeatmapIsDarkWhereImagesAgreeBrightWhereTheyDifferWhiteWhereNotFinite) {
  Image golden = flat(3, 1, 1, 0.0f), rendered = golden;
  rendered.at(1, 0, 0) = 1.0f;
  rendered.at(2, 0, 0) = std::numeric_limits<float>::quiet_NaN();
  const Image heat = difference_heatmap(rendered, golden, 1.0);
  ASSERT_EQ(heat.channels, 3);
  const auto luma = [&](int x) { return heat.at(x, 0, 0) + heat.at(x, 0, 1) + heat.at(x, 0, 2); };
  EXPECT_LT(luma(0), 0.1f);  // magma starts near black
  EXPECT_GT(luma(1), 1.5f);  // and ends in a light yellow
  EXPECT_EQ(luma(2), 3.0f);
}

}  // namespace
}  // namespace qdmr
