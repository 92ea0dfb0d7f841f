#pragma once
// Linear colour to the sRGB codes image files store: the exact transfer curve with the deterministic pow (every
// machine writes the same bytes), and its 8-bit codes by table, which PNG output takes for every channel.
#include <algorithm>
#include <cstddef>
#include <cstdint>

namespace qdmr {

// The sRGB transfer curve of v in [0, 1]; NaN and v <= 0 give 0, v >= 1 gives 1.
float linear_to_srgb(float v);

// The code of v in `max_code` steps: floor(linear_to_srgb(v) * max_code + 0.5), the curve clamped to [0, 1] first
// (its pow may stray an ulp past 1).
inline std::uint32_t srgb_code(float v, float max_code) {
  return std::uint32_t(std::clamp(linear_to_srgb(v), 0.0f, 1.0f) * max_code + 0.5f);  // >= 0: truncation is floor
}

// srgb_code(v, 255), bit for bit, from a table of the 255 steps' thresholds (no pow per value).
std::uint8_t srgb_code8(float v);
// srgb_code8 of every value, into out[0 .. size): the table looked up once, the loop inlined.
void srgb_codes8(const float* values, std::size_t size, std::uint8_t* out);

}  // namespace qdmr
