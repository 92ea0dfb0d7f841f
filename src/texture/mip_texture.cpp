// Typed mip chains: quantisation of level 0, and Box / BoxNormal / Max / Min reductions level by level.
// Max and Min are exact in the stored values: a kernel's reducer (on its vectors) and the portable one (scalar)
// give the same bits.
#include "qdmr/texture/mip_texture.hpp"

#include <tbb/blocked_range.h>
#include <tbb/parallel_for.h>


#include <algorithm>
#include <array>
#include <cmath>
#include <cstring>
#include <string>
#include <type_traits>

#include "qdmr/core/error.hpp"
#include "qdmr/core/limits.hpp"
#include "texture/internal.hpp"
#include "texture/mip_reduce.hpp"

namespace qdmr {
namespace {

using mip::for_rows;
using mip::load;
using mip::store;
using mip::taps;
using mip::Taps;

constexpr std::size_t kLevelAlignment = 64;  // a cache line

struct Tables {
  std::array<float, 256> unorm8{};   // k / 255
  std::array<float, 256> srgb8{};    // the exact sRGB decode of k / 255, as texture.cpp decodes 8-bit albedo
  std::array<double, 255> srgb_mid{};  // decode((k + 0.5) / 255): linear values at or above it encode to k + 1
  // srgb_first[b]: how many midpoints lie at or below b / kSrgbBuckets, where encode_srgb8's count of midpoints
  // at or below v starts for v in [b, b + 1) / kSrgbBuckets (no bucket holds more than one midpoint).
  static constexpr int kSrgbBuckets = 4096;
  std::array<std::uint8_t, kSrgbBuckets> srgb_first{};
};

double srgb_decode(double v) { return v <= 0.04045 ? v / 12.92 : std::pow((v + 0.055) / 1.055, 2.4); }

const Tables& tables() {
  static const Tables t = [] {
    Tables r;
    for (int k = 0; k < 256; ++k) {
      r.unorm8[std::size_t(k)] = float(k) / 255.0f;
      r.srgb8[std::size_t(k)] = texture_detail::srgb_to_linear(float(k) / 255.0f);
    }
    for (int k = 0; k < 255; ++k) r.srgb_mid[std::size_t(k)] = srgb_decode((k + 0.5) / 255.0);
    for (int b = 0, k = 0; b < Tables::kSrgbBuckets; ++b) {
      while (k < 255 && r.srgb_mid[std::size_t(k)] <= double(b) / Tables::kSrgbBuckets) ++k;
      r.srgb_first[std::size_t(b)] = std::uint8_t(k);
    }
    return r;
  }();
  return t;
}

// Round to nearest (ties up) after clamping to [0, 1]; NaN gives 0. v * 255 and v * 65535 are exact in double,
// and the sum with 1/2 is positive, so truncation is its floor: no branches, no floor emulation (this file is
// compiled for the baseline ISA, which has no rounding instruction).
float clamp_unit(float v) {
  const float positive = v > 0.0f ? v : 0.0f;  // NaN too
  return positive < 1.0f ? positive : 1.0f;
}

std::uint8_t quantise_unorm8(float v) { return std::uint8_t(std::int32_t(double(clamp_unit(v)) * 255.0 + 0.5)); }

std::uint16_t quantise_unorm16(float v) {
  return std::uint16_t(std::int32_t(double(clamp_unit(v)) * 65535.0 + 0.5));
}

// round(encode(v) * 255) with the exact curve: the number of decoded midpoints between codes at or below v (no
// pow on the value itself, so the result does not depend on the machine's libm), counted from v's bucket on.
// v * kSrgbBuckets is exact (a power of two), so v's bucket starts at or below v.
std::uint8_t encode_srgb8(const Tables& t, float v) {
  if (!(v > 0.0f)) return 0;
  if (v >= 1.0f) return 255;
  int k = t.srgb_first[std::size_t(v * float(Tables::kSrgbBuckets))];
  while (k < 255 && t.srgb_mid[std::size_t(k)] <= double(v)) ++k;
  return std::uint8_t(k);
}

// The texel codec of one format, fixed at compile time: the loops over texels below are instantiated per codec
// (with_codec), so no texel pays for a switch on the format, an sRGB test per channel or the tables' guard.
template <TexelFormat Format, bool Srgb>
struct Codec {
  static constexpr int kChannels = channel_count(Format);
  static constexpr int kTexelBytes = bytes_per_texel(Format);
  const Tables& t = tables();

  float decode(const std::uint8_t* texel, int c) const {
    if constexpr (Format == TexelFormat::R16) return float(load<std::uint16_t>(texel, 0)) / 65535.0f;
    else if constexpr (Format == TexelFormat::R32F) return load<float>(texel, 0);
    else return (Srgb && c < 3 ? t.srgb8 : t.unorm8)[texel[c]];
  }

  void encode(std::uint8_t* texel, int c, float v) const {
    if constexpr (Format == TexelFormat::R16) store<std::uint16_t>(texel, 0, quantise_unorm16(v));
    else if constexpr (Format == TexelFormat::R32F) store<float>(texel, 0, v);
    else texel[c] = Srgb && c < 3 ? encode_srgb8(t, v) : quantise_unorm8(v);
  }
};

// f(codec) with the codec of `format` (sRGB only where the format's channels are bytes: allocate_texture's rule).
template <class F>
decltype(auto) with_codec(TexelFormat format, bool srgb, F&& f) {
  switch (format) {
    case TexelFormat::R8: return srgb ? f(Codec<TexelFormat::R8, true>{}) : f(Codec<TexelFormat::R8, false>{});
    case TexelFormat::RG8: return srgb ? f(Codec<TexelFormat::RG8, true>{}) : f(Codec<TexelFormat::RG8, false>{});
    case TexelFormat::RGBA8:
      return srgb ? f(Codec<TexelFormat::RGBA8, true>{}) : f(Codec<TexelFormat::RGBA8, false>{});
    case TexelFormat::R16: return f(Codec<TexelFormat::R16, false>{});
    case TexelFormat::R32F: return f(Codec<TexelFormat::R32F, false>{});
  }
  throw Error("texture", "unknown texel format");
}

// Box and BoxNormal: sums of decoded values in tap order (rows, then columns), re-encoded per level.
template <bool Normal, class C>
void reduce_box(const Texture& t, int level, const C& codec, std::uint8_t* out_base) {
  constexpr int channels = C::kChannels, texel_bytes = C::kTexelBytes;
  const TextureLevel& in = t.levels[std::size_t(level)];
  const TextureLevel& out = t.levels[std::size_t(level) + 1];
  const std::uint8_t* in_base = t.storage.data() + in.offset;
  // A texel costs about 8x more here than in a Max build: weight the row size accordingly.
  for_rows(out.height, std::size_t(out.width) * texel_bytes * 8, [&](int y0, int y1) {
    // Locals: a byte store may alias anything in memory, so members and captures would be read again per texel.
    const C local_codec = codec;
    const std::uint8_t* const in_texels = in_base;
    std::uint8_t* const out_texels = out_base;
    const int iw = in.width, ih = in.height, ow = out.width, oh = out.height;
    for (int y = y0; y < y1; ++y) {
      const Taps ty = taps(y, ih, oh);
      for (int x = 0; x < ow; ++x) {
        const Taps tx = taps(x, iw, ow);
        float sum[4] = {0, 0, 0, 0};
        for (int j = ty.first; j < ty.first + ty.count; ++j)
          for (int i = tx.first; i < tx.first + tx.count; ++i) {
            const std::uint8_t* texel = in_texels + (std::size_t(j) * iw + i) * texel_bytes;
            for (int c = 0; c < channels; ++c) {
              const float v = local_codec.decode(texel, c);
              sum[c] += Normal && c < 3 ? 2.0f * v - 1.0f : v;
            }
          }
        std::uint8_t* texel = out_texels + (std::size_t(y) * ow + x) * texel_bytes;
        const float count = float(tx.count * ty.count);
        for (int c = Normal ? 3 : 0; c < channels; ++c) local_codec.encode(texel, c, sum[c] / count);
        if constexpr (Normal) {
          const double len2 = double(sum[0]) * sum[0] + double(sum[1]) * sum[1] + double(sum[2]) * sum[2];
          const double inv = len2 > 0.0 ? 1.0 / std::sqrt(len2) : 0.0;
          const float n[3] = {len2 > 0.0 ? float(sum[0] * inv) : 0.0f, len2 > 0.0 ? float(sum[1] * inv) : 0.0f,
                              len2 > 0.0 ? float(sum[2] * inv) : 1.0f};
          for (int c = 0; c < 3; ++c) local_codec.encode(texel, c, 0.5f + 0.5f * n[c]);
        }
      }
    }
  });
}

}  // namespace

float Texture::texel(int level, int x, int y, int c) const {
  if (level < 0 || level >= level_count() || c < 0 || c >= channels())
    throw Error("texture", "texel: level or channel out of range");
  const TextureLevel& l = levels[std::size_t(level)];
  if (x < 0 || y < 0 || x >= l.width || y >= l.height) throw Error("texture", "texel: position out of range");
  return with_codec(format, srgb, [&](const auto& codec) { return codec.decode(texel_address(level, x, y), c); });
}

Image Texture::level_image(int level) const {
  if (level < 0 || level >= level_count()) throw Error("texture", "level_image: level out of range");
  const TextureLevel& l = levels[std::size_t(level)];
  Image image(l.width, l.height, channels());
  with_codec(format, srgb, [&](const auto& codec) {
    for (int y = 0; y < l.height; ++y)
      for (int x = 0; x < l.width; ++x)
        for (int c = 0; c < image.channels; ++c) image.at(x, y, c) = codec.decode(texel_address(level, x, y), c);
  });
  return image;
}

namespace {

// The levels of a chain (into `levels` when not null) and its storage bytes, tail padding included.
std::uint64_t chain_layout(int width, int height, TexelFormat format, std::vector<TextureLevel>* levels) {
  std::uint64_t offset = 0;
  for (int w = width, h = height;; w = std::max(1, w / 2), h = std::max(1, h / 2)) {
    offset = (offset + kLevelAlignment - 1) / kLevelAlignment * kLevelAlignment;
    if (levels) levels->push_back({w, h, std::size_t(offset)});
    offset += std::uint64_t(w) * std::uint64_t(h) * std::uint64_t(bytes_per_texel(format));
    if (w == 1 && h == 1) break;
  }
  return offset + Texture::kTailPadding;
}

}  // namespace

std::uint64_t mip_chain_bytes(int width, int height, TexelFormat format) {
  return chain_layout(width, height, format, nullptr);
}

std::uint64_t linear_copy_bytes(int width, int height, TexelFormat format, bool srgb) {
  const bool decoded = format == TexelFormat::RGBA8 ? srgb : format == TexelFormat::R16 || (format == TexelFormat::R8 && !srgb);
  if (!decoded) return 0;
  const std::uint64_t bytes = mip_chain_bytes(width, height, format) / bytes_per_texel(format) *
                              std::uint64_t(channel_count(format)) * sizeof(float);
  return bytes <= kLinearCopyMaxBytes ? bytes : 0;
}

void add_linear_copy(Texture& texture) {
  if (texture.levels.empty() || linear_copy_bytes(texture.width(), texture.height(), texture.format, texture.srgb) == 0)
    return;
  texture.linear.assign(texture.storage.size() / std::size_t(bytes_per_texel(texture.format)) *
                            std::size_t(texture.channels()),
                        0.0f);
  with_codec(texture.format, texture.srgb, [&](const auto& codec) {
    constexpr std::size_t channels = std::decay_t<decltype(codec)>::kChannels;
    constexpr std::size_t texel_bytes = std::decay_t<decltype(codec)>::kTexelBytes;
    for (int k = 0; k < texture.level_count(); ++k) {
      const TextureLevel& l = texture.levels[std::size_t(k)];
      for_rows(l.height, std::size_t(l.width) * 4 * channels, [&](int y0, int y1) {
        const auto local_codec = codec;  // locals, read once (as in make_mip_texture)
        const std::uint8_t* const storage = texture.storage.data();
        float* const linear = texture.linear.data();
        const std::size_t width = std::size_t(l.width), first = l.offset / texel_bytes;
        for (int y = y0; y < y1; ++y)
          for (std::size_t x = 0; x < width; ++x) {
            const std::size_t texel = first + std::size_t(y) * width + x;
            for (std::size_t c = 0; c < channels; ++c)
              linear[texel * channels + c] = local_codec.decode(storage + texel * texel_bytes, int(c));
          }
      });
    }
  });
}

std::uint64_t wrap_footprint_bytes(int width, int height, TexelFormat format, bool srgb) {
  if (channel_count(format) != 1 || linear_copy_bytes(width, height, format, srgb) == 0) return 0;
  const std::uint64_t bytes = std::uint64_t(width) * std::uint64_t(height) * 4 * sizeof(float);
  return bytes <= kWrapFootprintsMaxBytes ? bytes : 0;
}

void add_wrap_footprints(Texture& texture) {
  const int w = texture.width(), h = texture.height();
  if (texture.levels.empty() || texture.linear.empty() ||
      wrap_footprint_bytes(w, h, texture.format, texture.srgb) == 0)
    return;
  texture.wrap_footprints.assign(std::size_t(w) * std::size_t(h) * 4, 0.0f);
  const float* level0 = texture.linear.data() + texture.levels[0].offset / std::size_t(bytes_per_texel(texture.format));
  for_rows(h, std::size_t(w) * 16, [&](int y0, int y1) {
    for (int y = y0; y < y1; ++y) {
      const float* row = level0 + std::size_t(y) * std::size_t(w);
      const float* below = level0 + std::size_t(y + 1 == h ? 0 : y + 1) * std::size_t(w);
      float* out = texture.wrap_footprints.data() + std::size_t(y) * std::size_t(w) * 4;
      for (int x = 0; x < w; ++x, out += 4) {
        const int right = x + 1 == w ? 0 : x + 1;
        out[0] = row[x];
        out[1] = row[right];
        out[2] = below[x];
        out[3] = below[right];
      }
    }
  });
}

Texture allocate_texture(int width, int height, TexelFormat format, bool srgb) {
  if (width < 1 || height < 1 || width > limits::kMaxTextureSide || height > limits::kMaxTextureSide)
    throw Error("texture", "size " + std::to_string(width) + "x" + std::to_string(height) + " is outside 1.." +
                               std::to_string(limits::kMaxTextureSide));
  if (srgb && bytes_per_texel(format) != channel_count(format))
    throw Error("texture", "sRGB needs an 8-bit format, not " + format_name(format));
  Texture t;
  t.format = format;
  t.srgb = srgb;
  const std::uint64_t total = chain_layout(width, height, format, &t.levels);
  if (total >= (std::uint64_t(1) << 31)) throw Error("texture", "the mip chain does not fit 32-bit byte offsets");
  t.storage.assign(std::size_t(total), 0);
  return t;
}

Texture make_mip_texture(const Image& level0, TexelFormat format, bool srgb, MipReduce reduce, MipExtremum extremum) {
  if (level0.channels < 1 || level0.channels > 4)
    throw Error("texture", "level 0 must have 1 to 4 channels, not " + std::to_string(level0.channels));
  Texture t = allocate_texture(level0.width, level0.height, format, srgb);
  with_codec(format, srgb, [&](const auto& codec) {
    constexpr int channels = std::decay_t<decltype(codec)>::kChannels;
    constexpr int texel_bytes = std::decay_t<decltype(codec)>::kTexelBytes;
    for_rows(level0.height, std::size_t(level0.width) * texel_bytes * 8, [&](int y0, int y1) {
      // Locals: a byte store may alias anything in memory, so members and captures would be read again per texel.
      const auto local_codec = codec;
      std::uint8_t* const storage = t.storage.data();
      const float* const texels = level0.texels.data();
      const int width = level0.width, in_channels = level0.channels;
      for (int y = y0; y < y1; ++y) {
        const float* in = texels + std::size_t(y) * std::size_t(width) * std::size_t(in_channels);
        std::uint8_t* texel = storage + std::size_t(y) * std::size_t(width) * texel_bytes;
        for (int x = 0; x < width; ++x, in += in_channels, texel += texel_bytes)
          for (int c = 0; c < channels; ++c) local_codec.encode(texel, c, c < in_channels ? in[c] : c == 3 ? 1.0f : 0.0f);
      }
    });
  });
  build_mip_levels(t, reduce, extremum);
  return t;
}

void build_mip_levels(Texture& texture, MipReduce reduce, MipExtremum extremum) {
  if (extremum == nullptr) extremum = &mip::extremum<mip::NoVectors>;
  if (texture.levels.empty()) throw Error("texture", "build_mip_levels: the texture has no level 0");
  if (reduce == MipReduce::BoxNormal && (texture.format != TexelFormat::RGBA8 || texture.srgb))
    throw Error("texture", "normal maps need the rgba8 format without sRGB, not " + format_name(texture.format) +
                               (texture.srgb ? " sRGB" : ""));
  for (int k = 0; k + 1 < texture.level_count(); ++k) {
    const TextureLevel& in = texture.levels[std::size_t(k)];
    const TextureLevel& out = texture.levels[std::size_t(k) + 1];
    std::uint8_t* out_base = texture.storage.data() + out.offset;
    const std::uint8_t* in_base = texture.storage.data() + in.offset;
    switch (reduce) {
      case MipReduce::Box:
        with_codec(texture.format, texture.srgb,
                   [&](const auto& codec) { reduce_box<false>(texture, k, codec, out_base); });
        break;
      case MipReduce::BoxNormal:  // rgba8 without sRGB, checked above
        reduce_box<true>(texture, k, Codec<TexelFormat::RGBA8, false>{}, out_base);
        break;
      case MipReduce::Max:
        extremum(true, texture.format, in_base, in.width, in.height, out_base, out.width, out.height);
        break;
      case MipReduce::Min:
        extremum(false, texture.format, in_base, in.width, in.height, out_base, out.width, out.height);
        break;
    }
  }
}

}  // namespace qdmr
