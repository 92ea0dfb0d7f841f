#include "write/srgb_encode.hpp"

#include <array>
#include <bit>

#include "core/det_math.hpp"

namespace qdmr {
namespace {

// srgb_code(v, 255) is a non-decreasing function of v, so it is the number of steps whose threshold (the least
// float with that code, found by bisection over the float bit patterns, which order positive floats) v reaches.
// A first guess per top-16-bit prefix of v (the code of the prefix's least float) is at most a step short
// wherever the curve is (a prefix spans under 1/128 of its value, under 0.08 of a step where the curve is
// steepest), so one comparison finishes it (SrgbEncode.* checks both sides of every threshold).
class Srgb8Table {
public:
  Srgb8Table() {
    for (int k = 1; k <= 255; ++k) {
      std::uint32_t lo = 0, hi = kOneBits;  // code(lo) < k <= code(hi)
      while (hi - lo > 1) {
        const std::uint32_t mid = lo + (hi - lo) / 2;
        (code(std::bit_cast<float>(mid)) >= std::uint32_t(k) ? hi : lo) = mid;
      }
      threshold_[std::size_t(k)] = hi;
    }
    threshold_[256] = kOneBits + 1;  // above every value that reaches the table
    for (std::uint32_t p = 0; p < first_code_.size(); ++p) first_code_[p] = std::uint8_t(code(std::bit_cast<float>(p << 16)));
  }

  std::uint8_t operator()(float v) const {
    if (!(v > 0.0f)) return 0;  // NaN, zero, negative
    if (v >= 1.0f) return 255;
    const std::uint32_t bits = std::bit_cast<std::uint32_t>(v);
    std::uint32_t c = first_code_[bits >> 16];
    c += bits >= threshold_[c + 1];
    return std::uint8_t(c);
  }

private:
  static constexpr std::uint32_t kOneBits = 0x3F800000u;  // 1.0f
  static std::uint32_t code(float v) { return srgb_code(v, 255.0f); }
  std::array<std::uint32_t, 257> threshold_{};
  std::array<std::uint8_t, (kOneBits >> 16)> first_code_{};
};

const Srgb8Table& srgb8_table() {
  static const Srgb8Table table;
  return table;
}

}  // namespace

float linear_to_srgb(float v) {
  if (!(v > 0.0f)) return 0.0f;  // also maps NaN to black
  if (v >= 1.0f) return 1.0f;
  if (v <= 0.0031308f) return 12.92f * v;
  return 1.055f * detmath::pow(v, 1.0f / 2.4f) - 0.055f;
}

std::uint8_t srgb_code8(float v) { return srgb8_table()(v); }

void srgb_codes8(const float* values, std::size_t size, std::uint8_t* out) {
  const Srgb8Table& table = srgb8_table();
  for (std::size_t i = 0; i < size; ++i) out[i] = table(values[i]);
}

}  // namespace qdmr
