#pragma once
// Texel formats as GPUs store them. Conversions to float are exact: UNORM k / (2^bits - 1) correctly
// rounded, sRGB decoded through the exact IEC 61966-2-1 curve (before filtering, as hardware does).
#include <cstdint>
#include <optional>
#include <string>

namespace qdmr {

enum class TexelFormat : std::uint8_t { R8, RG8, RGBA8, R16, R32F };

constexpr int channel_count(TexelFormat f) {
  switch (f) {
    case TexelFormat::R8: return 1;
    case TexelFormat::RG8: return 2;
    case TexelFormat::RGBA8: return 4;
    case TexelFormat::R16: return 1;
    case TexelFormat::R32F: return 1;
  }
  return 0;
}

constexpr int bytes_per_texel(TexelFormat f) {
  switch (f) {
    case TexelFormat::R8: return 1;
    case TexelFormat::RG8: return 2;
    case TexelFormat::RGBA8: return 4;
    case TexelFormat::R16: return 2;
    case TexelFormat::R32F: return 4;
  }
  return 0;
}

std::string format_name(TexelFormat f);
std::optional<TexelFormat> parse_format(const std::string& name);

}  // namespace qdmr
