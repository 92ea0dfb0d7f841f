#include <gtest/gtest.h>

#include <array>
#include <cstdint>
#include <random>
#include <string>

#include "kernel/kernel.hpp"
#include "qdmr/core/isa.hpp"
#include "qdmr/texture/bc3.hpp"

namespace qdmr {
namespace {

using Texels = std::array<std::uint8_t, 16>;

// Blocks that reach every branch of the search: random over the whole range, narrow ranges (endpoints moved inward
// by 0-3 steps), 0 and 255 beside mid values (the 6-value mode), constants and two values (exact), ramps.
std::vector<Texels> blocks() {
  std::mt19937 random(12345);
  std::vector<Texels> out;
  for (int n = 0; n < 4000; ++n) {
    Texels t{};
    const int kind = n % 6;
    const int base = int(random() % 256), span = 1 + int(random() % (kind == 1 ? 12 : 80));
    for (std::size_t i = 0; i < 16; ++i) {
      const int r = int(random() % 256);
      switch (kind) {
        case 0: t[i] = std::uint8_t(r); break;
        case 1:
        case 2: t[i] = std::uint8_t(std::min(255, base + r % span)); break;
        case 3: t[i] = r % 5 == 0 ? 0 : r % 5 == 1 ? 255 : std::uint8_t(std::min(255, base + r % span)); break;
        case 4: t[i] = std::uint8_t(r % 2 ? base : 255 - base); break;
        default: t[i] = std::uint8_t(std::min(255, base + int(i) * (span / 16 + 1))); break;
      }
    }
    out.push_back(t);
  }
  out.push_back(Texels{});         // all 0
  out.push_back(Texels{}), out.back().fill(255);
  return out;
}

// Each kernel's encoder (the one preparation uses) makes the blocks of the definition, encode_bc3_alpha.
TEST(Bc3Encode, EveryKernelMakesTheDefinitionsBlocks) {
  const std::vector<Texels> all = blocks();
  for (Isa isa : usable_isas()) {
    const Bc3Encode encode = kernel_for(isa).bc3_encode();
    int checked = 0;
    for (const Texels& t : all) {
      ASSERT_EQ(encode(t.data()), encode_bc3_alpha(t.data())) << isa_name(isa) << " block " << checked;
      ++checked;
    }
  }
}

// bc3_roundtrip with a kernel's encoder: the same texels and report as with the definition.
TEST(Bc3Encode, RoundtripWithAKernelEncoderIsTheDefinitions) {
  const int w = 67, h = 45;
  std::mt19937 random(7);
  std::vector<std::uint8_t> image(std::size_t(w * h));
  for (std::size_t i = 0; i < image.size(); ++i) image[i] = std::uint8_t(96 + (i % w) + random() % 24);
  for (Isa isa : usable_isas()) {
    std::vector<std::uint8_t> plain = image, kernel = image;
    const Bc3Report a = bc3_roundtrip(plain.data(), w, h), b = bc3_roundtrip(kernel.data(), w, h, kernel_for(isa).bc3_encode());
    EXPECT_EQ(plain, kernel) << isa_name(isa);
    EXPECT_EQ(a.max_error, b.max_error);
    EXPECT_EQ(a.rms_error, b.rms_error);
    EXPECT_GT(a.rms_error, 0.0);
  }
}

}  // namespace
}  // namespace qdmr
