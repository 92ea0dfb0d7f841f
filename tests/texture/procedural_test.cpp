#include <gtest/gtest.h>

#include <algorithm>
#include <bit>
#include <chrono>
#include <cmath>
#include <cstdint>
#include <cstdio>
#include <vector>

#include "qdmr/core/error.hpp"
#include "qdmr/texture/texture_level0.hpp"
#include "texture/internal.hpp"
#include "texture/pattern_reuse.hpp"

namespace qdmr {
namespace {

constexpr ProceduralPattern kAll[] = {ProceduralPattern::Bricks, ProceduralPattern::Cobbles, ProceduralPattern::Sine,
                                      ProceduralPattern::Steps,  ProceduralPattern::Spikes,  ProceduralPattern::Noise,
                                      ProceduralPattern::Flat,   ProceduralPattern::Checker};

ProceduralDesc desc(ProceduralPattern p, int size, std::uint32_t seed = 7, int cells = 4) {
  ProceduralDesc d;
  d.pattern = p;
  d.size = size;
  d.seed = seed;
  d.cells = cells;
  return d;
}

TEST(TextureProcedural, DeterministicAndInRange) {
  for (ProceduralPattern p : kAll)
    for (int size : {1, 2, 4, 64}) {
      const Image a = generate_procedural(desc(p, size));
      const Image b = generate_procedural(desc(p, size));
      ASSERT_EQ(a.width, size);
      ASSERT_EQ(a.height, size);
      ASSERT_EQ(a.channels, 1);
      EXPECT_EQ(a.texels, b.texels) << int(p) << " size " << size;
      for (float h : a.texels) ASSERT_TRUE(h >= 0.0f && h <= 1.0f) << int(p) << " size " << size << ": " << h;
    }
}

TEST(TextureProcedural, SeedsChangeRandomPatterns) {
  for (ProceduralPattern p : {ProceduralPattern::Bricks, ProceduralPattern::Cobbles, ProceduralPattern::Noise}) {
    const Image a = generate_procedural(desc(p, 64, 1));
    const Image b = generate_procedural(desc(p, 64, 2));
    EXPECT_NE(a.texels, b.texels) << int(p);
  }
}

TEST(TextureProcedural, KnownValues) {
  EXPECT_EQ(generate_procedural(desc(ProceduralPattern::Flat, 4)).texels, Texels(16, 1.0f));
  // Checker: squares of size / cells texels, texel (0, 0) black.
  const Image checker = generate_procedural(desc(ProceduralPattern::Checker, 8, 1, 4));
  for (int y = 0; y < 8; ++y)
    for (int x = 0; x < 8; ++x) EXPECT_EQ(checker.at(x, y, 0), float((x / 2 + y / 2) % 2)) << x << "," << y;
  // Spikes: a cone per cell, highest next to the tip, zero at the cell corners.
  const Image spikes = generate_procedural(desc(ProceduralPattern::Spikes, 16, 1, 2));
  EXPECT_NEAR(spikes.at(3, 3, 0), 1.0f - 2.0f * std::sqrt(2.0f) * 0.5f / 8.0f, 1e-6f);
  EXPECT_EQ(spikes.at(0, 0, 0), 0.0f);
  // Steps: `cells` levels, 0 and 1 both present.
  const Image steps = generate_procedural(desc(ProceduralPattern::Steps, 64, 1, 5));
  std::vector<float> levels(steps.texels.begin(), steps.texels.end());
  std::sort(levels.begin(), levels.end());
  levels.erase(std::unique(levels.begin(), levels.end()), levels.end());
  EXPECT_EQ(levels, (std::vector<float>{0.0f, 0.25f, 0.5f, 0.75f, 1.0f}));
  // Noise spans the full range after normalisation.
  const Image noise = generate_procedural(desc(ProceduralPattern::Noise, 64));
  EXPECT_EQ(*std::min_element(noise.texels.begin(), noise.texels.end()), 0.0f);
  EXPECT_EQ(*std::max_element(noise.texels.begin(), noise.texels.end()), 1.0f);
}

// Tileable: differences across the wrap edges look like differences between interior neighbours.
TEST(TextureProcedural, Tileable) {
  for (ProceduralPattern p : kAll) {
    if (p == ProceduralPattern::Checker) continue;  // hard edges by design; exact values tested above
    const int n = 128;
    const Image img = generate_procedural(desc(p, n, 3, 4));
    double interior_max = 0, interior_sum = 0, edge_max = 0, edge_sum = 0;
    for (int a = 0; a < n; ++a) {
      for (int b = 0; b + 1 < n; ++b) {
        const double dx = std::abs(img.at(b + 1, a, 0) - img.at(b, a, 0));
        const double dy = std::abs(img.at(a, b + 1, 0) - img.at(a, b, 0));
        interior_max = std::max({interior_max, dx, dy});
        interior_sum += dx + dy;
      }
      const double ex = std::abs(img.at(0, a, 0) - img.at(n - 1, a, 0));
      const double ey = std::abs(img.at(a, 0, 0) - img.at(a, n - 1, 0));
      edge_max = std::max({edge_max, ex, ey});
      edge_sum += ex + ey;
    }
    const double interior_mean = interior_sum / (2.0 * n * (n - 1)), edge_mean = edge_sum / (2.0 * n);
    EXPECT_LE(edge_max, interior_max) << int(p);
    EXPECT_LE(edge_mean, 3.0 * interior_mean + 1e-6) << int(p);
  }
}

// FNV-1a over the texels' bits.
std::uint64_t digest(const Texels& texels) {
  std::uint64_t h = 0xcbf29ce484222325u;
  for (const float t : texels)
    for (int byte = 0; byte < 4; ++byte) h = (h ^ ((std::bit_cast<std::uint32_t>(t) >> (8 * byte)) & 0xFFu)) * 0x100000001b3u;
  return h;
}

// The generator shares each cell's candidate points and bisectors between the texels of the cell; these digests
// were taken from the per-texel formula it replaced (every texel searching its nine neighbouring cells and
// measuring its distance to every bisector; bench/llvmpipe/canonical.cpp keeps a copy of it), so they pin the
// bits to that definition. Cell runs of 64, 12 or 13 texels (cells not dividing the size), 1, and cells smaller
// than a texel.
TEST(TextureProcedural, CobblesKeepTheBitsOfTheirPerTexelDefinition) {
  struct Case {
    int size, cells;
    float mortar;
    std::uint32_t seed;
    std::uint64_t digest;
  };
  for (const Case& c : {Case{512, 8, 0.08f, 1, 11195767796147320576u}, Case{64, 5, 0.0f, 7, 5350268023807079165u},
                        Case{32, 32, 0.3f, 3, 699436979478964970u}, Case{4, 16, 0.1f, 9, 479590760850544356u}}) {
    ProceduralDesc d = desc(ProceduralPattern::Cobbles, c.size, c.seed, c.cells);
    d.mortar = c.mortar;
    EXPECT_EQ(digest(generate_procedural(d).texels), c.digest) << "size " << c.size << " cells " << c.cells;
  }
}

// The noise generator hashes each lattice cell's corners once per run of the cell's texels, and what depends on the
// row once per row and octave; these digests were taken from the per-texel formula before (every texel hashing
// its four corners in every octave), so they pin the bits to it. Cells of 10 and 51 texels, of 2 and less than
// one (octaves finer than a texel are skipped), 1 to 8 octaves, gains of 0.5 and 0.7.
TEST(TextureProcedural, NoiseKeepsTheBitsOfItsPerTexelDefinition) {
  struct Case {
    int size, cells, octaves;
    float gain;
    std::uint32_t seed;
    std::uint64_t digest;
  };
  for (const Case& c : {Case{512, 48, 3, 0.5f, 7, 15387201144539149381u}, Case{512, 10, 5, 0.5f, 9, 6890770884524919827u},
                        Case{64, 3, 6, 0.5f, 11, 8486516405577459036u}, Case{32, 5, 8, 0.7f, 2, 8161278169913949614u},
                        Case{16, 16, 2, 0.5f, 4, 12990914483460179784u}}) {
    ProceduralDesc d = desc(ProceduralPattern::Noise, c.size, c.seed, c.cells);
    d.octaves = c.octaves;
    d.gain = c.gain;
    EXPECT_EQ(digest(generate_procedural(d).texels), c.digest) << "size " << c.size << " cells " << c.cells;
  }
}

TEST(TextureProcedural, ReusedPatternsHaveTheBitsOfAFreshEvaluation) {
  // Outside a PatternReuse every call evaluates; inside, the second call of a spec it names copies the first,
  // whichever of the two (heights alone or with cells) came first; another seed (named too) or size (not named) is
  // another pattern.
  std::vector<ProceduralDesc> descs;
  for (ProceduralPattern p : kAll) descs.push_back(desc(p, 32));
  ProceduralDesc waves = desc(ProceduralPattern::Waves, 32);
  waves.waves = {WaveDesc{}, WaveDesc{0.5f, 0.1f, 30.0f, 0.2f, 3, 2, 1}};
  waves.time = 1.5;
  descs.push_back(waves);
  for (const ProceduralDesc& d : descs) {
    const Image heights = texture_detail::generate_pattern(d, false);
    const Image cells = texture_detail::generate_pattern(d, true);
    ProceduralDesc other_seed = d, other_size = d;
    other_seed.seed += 1;
    other_size.size = 16;
    const Image seed_heights = texture_detail::generate_pattern(other_seed, false);
    const Image size_heights = texture_detail::generate_pattern(other_size, false);
    for (bool cells_first : {false, true}) {
      const PatternReuse reuse({procedural_key(d), procedural_key(other_seed)});
      const Image first = texture_detail::generate_pattern(d, cells_first);
      const Image again = texture_detail::generate_pattern(d, !cells_first);
      EXPECT_EQ((cells_first ? first : again).texels, cells.texels) << int(d.pattern);
      EXPECT_EQ((cells_first ? again : first).texels, heights.texels) << int(d.pattern);
      EXPECT_EQ(texture_detail::generate_pattern(other_seed, false).texels, seed_heights.texels) << int(d.pattern);
      EXPECT_EQ(texture_detail::generate_pattern(other_size, false).texels, size_heights.texels) << int(d.pattern);
    }
  }
}

TEST(TextureProcedural, RejectsBadParameters) {
  EXPECT_THROW(generate_procedural(desc(ProceduralPattern::Noise, 3)), Error);
  EXPECT_THROW(generate_procedural(desc(ProceduralPattern::Noise, 0)), Error);
  EXPECT_THROW(generate_procedural(desc(ProceduralPattern::Noise, 32768)), Error);
  EXPECT_THROW(generate_procedural(desc(ProceduralPattern::Bricks, 64, 1, 0)), Error);
}

TEST(TextureProcedural, Large4096) {
  const auto start = std::chrono::steady_clock::now();
  const Image img = generate_procedural(desc(ProceduralPattern::Cobbles, 4096, 5, 16));
  const double ms = std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - start).count();
  std::printf("cobbles 4096^2: %.0f ms\n", ms);
  ASSERT_EQ(img.texels.size(), 4096u * 4096u);
  const auto [lo, hi] = std::minmax_element(img.texels.begin(), img.texels.end());
  EXPECT_EQ(*lo, 0.0f);  // mortar
  EXPECT_GT(*hi, 0.75f);
  EXPECT_LE(*hi, 1.0f);
}

}  // namespace
}  // namespace qdmr
