#pragma once
// The sampler's code, for sampler.cpp and for the few callers that inline one key into a loop (height_surface.hpp):
// every helper is always inlined, so where the key is a constant (an instantiation) its branches fold away and
// where it is not (the generic sampler) they run per call. Coordinates are first reduced exactly to one period
// of the address mode, so texel indices stay small for any finite u; then texel indices and weights come either
// from exact float arithmetic or from fixed point with 8 or 6 fractional bits, as texture units do.
#include "core/gather.hpp"
#include "core/simd.hpp"
#include "texture/fetch_trace.hpp"
#include "texture/internal.hpp"
#include "texture/sampler.hpp"

namespace qdmr::QDMR_ISA_NAMESPACE::sampling_code {

#define QDMR_SAMPLER_INLINE [[gnu::always_inline]] inline

using simd::FetchPath;
using simd::Float;
using simd::Int;
using simd::kLanes;
using simd::Mask;

QDMR_SAMPLER_INLINE Mask is_finite(const Float& x) { return (x - x) == Float(0.0f); }

// u reduced to one period of the address mode; exact (no rounding) for finite u.
QDMR_SAMPLER_INLINE Float reduce(const Float& u, AddressMode mode) {
  switch (mode) {
    case AddressMode::Wrap: return u - xsimd::floor(u);
    case AddressMode::Mirror: return u - Float(2.0f) * xsimd::floor(u * Float(0.5f));
    case AddressMode::Clamp: break;
  }
  return xsimd::min(xsimd::max(u, Float(-1.0f)), Float(2.0f));  // further out clamps to the same texels
}

// Texel index i (within a period or two of the reduced coordinate) to a texel of [0, n).
QDMR_SAMPLER_INLINE Int address(Int i, const Int& n, AddressMode mode) {
  switch (mode) {
    case AddressMode::Wrap:
      i = xsimd::select(i < Int(0), i + n, i);
      return xsimd::select(i >= n, i - n, i);
    case AddressMode::Mirror: {
      const Int period = n + n;
      i = xsimd::select(i < Int(0), i + period, i);
      i = xsimd::select(i >= period, i - period, i);
      return xsimd::select(i >= n, period - Int(1) - i, i);
    }
    case AddressMode::Clamp: break;
  }
  return xsimd::min(xsimd::max(i, Int(0)), n - Int(1));
}

// The level of each lane and its size and storage offset.
struct LevelInfo {
  Int width, height, offset;
};

// level in [0, levels): the tables hold TextureView::kMaxLevels = 16 entries, a register permute's worth.
QDMR_SAMPLER_INLINE LevelInfo level_info(const TextureView& view, const Int& level) {
  static_assert(TextureView::kMaxLevels == 16);
  return {simd::lookup16(view.widths(), level), simd::lookup16(view.heights(), level),
          simd::lookup16(view.offsets(), level)};
}

// Level 0 for every lane (the point and bilinear filters): no table lookups.
QDMR_SAMPLER_INLINE LevelInfo level_zero(const TextureView& view) {
  return {Int(view.widths()[0]), Int(view.heights()[0]), Int(view.offsets()[0])};
}

QDMR_SAMPLER_INLINE Float decode_unorm8(const SamplerKey& k, const Int& byte, bool srgb) {
  return srgb ? simd::load_f32(texture_detail::kSrgbByteToLinear.data(), byte, k.fetch)
              : xsimd::to_float(byte) / Float(255.0f);
}

QDMR_SAMPLER_INLINE void decode(const SamplerKey& k, const Int& raw, Float* out) {
  switch (k.format) {
    case TexelFormat::R8: out[0] = decode_unorm8(k, raw & Int(0xFF), k.srgb); return;
    case TexelFormat::RG8:
      out[0] = decode_unorm8(k, raw & Int(0xFF), k.srgb);
      out[1] = decode_unorm8(k, (raw >> 8) & Int(0xFF), k.srgb);
      return;
    case TexelFormat::RGBA8:
      out[0] = decode_unorm8(k, raw & Int(0xFF), k.srgb);
      out[1] = decode_unorm8(k, (raw >> 8) & Int(0xFF), k.srgb);
      out[2] = decode_unorm8(k, (raw >> 16) & Int(0xFF), k.srgb);
      out[3] = decode_unorm8(k, xsimd::bitwise_cast<Int>(xsimd::bitwise_cast<simd::UInt>(raw) >> 24), false);
      return;
    case TexelFormat::R16: out[0] = xsimd::to_float(raw & Int(0xFFFF)) / Float(65535.0f); return;
    case TexelFormat::R32F: out[0] = xsimd::bitwise_cast<Float>(raw); return;
  }
}

// A one-channel texture (heights) with its decoded copy: Texture::linear holds float i for texel i of `storage`.
QDMR_SAMPLER_INLINE bool decoded_one_channel(const SamplerKey& k, const Texture& t) {
  return (k.format == TexelFormat::R16 || (k.format == TexelFormat::R8 && !k.srgb)) && !t.linear.empty();
}

// The index of texel (x, y) of `level` in the decoded copy of a one-channel texture.
QDMR_SAMPLER_INLINE Int decoded_index(const SamplerKey& k, const LevelInfo& level, const Int& x, const Int& y) {
  return (k.format == TexelFormat::R16 ? level.offset >> 1 : level.offset) + y * level.width + x;
}

// record false: the caller knows no texture-cache recorder listens (the recorder's test in the loop would make the
// compiler keep every vector register in memory around the call it guards).
QDMR_SAMPLER_INLINE void fetch(const TextureView& view, const SamplerKey& k, const LevelInfo& level, const Int& x, const Int& y,
                       Float* out, bool record = true) {
  const Texture& t = view.texture();
  if (record) trace_fetch(t, level.offset, x, y);
  if (decoded_one_channel(k, t)) {
    out[0] = simd::load_f32(t.linear.data(), decoded_index(k, level, x, y), k.fetch);
    return;
  }
  const Int offset = level.offset + (y * level.width + x) * Int(bytes_per_texel(k.format));
  decode(k, simd::load_bytes4(t.storage.data(), offset, k.fetch), out);
}

// fetch() of texels (xa, y) and (xb, y) = (xa + 1, y), adjacent in memory, from one load per lane: 4 bytes for
// texels of 1 or 2 bytes, 8 bytes for texels of 4.
QDMR_SAMPLER_INLINE void fetch_pair(const TextureView& view, const SamplerKey& k, const LevelInfo& level, const Int& xa,
                            const Int& xb, const Int& y, Float* a, Float* b, bool record = true) {
  const Texture& t = view.texture();
  const int bytes = bytes_per_texel(k.format);
  if (record) {
    trace_fetch(t, level.offset, xa, y);
    trace_fetch(t, level.offset, xb, y);
  }
  if (decoded_one_channel(k, t)) {
    Int first, second;
    simd::load_bytes8(reinterpret_cast<const std::uint8_t*>(t.linear.data()),
                      decoded_index(k, level, xa, y) * Int(int(sizeof(float))), k.fetch, first, second);
    a[0] = xsimd::bitwise_cast<Float>(first);
    b[0] = xsimd::bitwise_cast<Float>(second);
    return;
  }
  const Int offset = level.offset + (y * level.width + xa) * Int(bytes);
  if (bytes <= 2) {
    const Int raw = simd::load_bytes4(t.storage.data(), offset, k.fetch);
    decode(k, raw, a);
    decode(k, raw >> (8 * bytes), b);  // decode keeps the texel's low bytes only
    return;
  }
  Int first, second;
  simd::load_bytes8(t.storage.data(), offset, k.fetch, first, second);
  decode(k, first, a);
  decode(k, second, b);
}

// fetch_pair() of an RGBA8 sRGB texture from its decoded copy (Texture::linear): whole texels, no table lookups.
QDMR_SAMPLER_INLINE void fetch_linear_pair(const TextureView& view, const SamplerKey& k, const LevelInfo& level,
                                           const Int& xa, const Int& xb, const Int& y, Float* a, Float* b,
                                           bool record = true) {
  const Texture& t = view.texture();
  if (record) {
    trace_fetch(t, level.offset, xa, y);
    trace_fetch(t, level.offset, xb, y);
  }
  simd::load_f32x4_pair(t.linear.data(), level.offset + (y * level.width + xa) * Int(4), k.fetch, a, b);
}

// u * n split into the fp32 product p and its rounding error e, exactly: p + e = u * n (Dekker's product, with
// -ffp-contract=off; |u| <= 2 and n <= 16384 keep every partial product far from overflow and underflow).
QDMR_SAMPLER_INLINE void exact_product(const Float& u, const Float& n, Float& p, Float& e) {
  p = u * n;
  const Float split(4097.0f);  // 2^12 + 1: halves of 12 bits
  const Float uc = u * split, nc = n * split;
  const Float uh = uc - (uc - u), nh = nc - (nc - n);
  const Float ul = u - uh, nl = n - nh;
  e = ((uh * nh - p) + uh * nl + ul * nh) + ul * nl;
}

// Texel index and bilinear weight along one axis: the texel coordinate is x = u * n - offset (offset 0 for point
// sampling, 0.5 for bilinear taps), in fixed point with `bits` fractional bits (0: a float), rounded down.
// sm3 floors the fp32 x; with `exact`, the exact x is floored instead: the fp32 q = fl(fl(u * n) - offset) is
// off by the two rounding errors, which together are below the distance from q to any other multiple of
// 2^-bits (for the coordinates the address modes leave: u * n in [-n, 2n]), so q's floor is right unless q * 2^bits
// is an integer that the exact x lies just below (docs/sampling.md, "Math modes"). The weight is q minus the
// index in fixed point or in fp32 (1 when the exact index is the one below q). `n_power_of_two`: n is a power
// of two, so u * n is exact (no underflow or overflow for these u and n) and its rounding error e is 0 without
// Dekker's product (the same bits, 14 operations fewer).
QDMR_SAMPLER_INLINE void split(const Float& u, const Float& n, bool n_power_of_two, float offset, int bits, bool exact,
                               Int& index, Float& weight) {
  Float p, e(0.0f);
  if (exact && !n_power_of_two)
    exact_product(u, n, p, e);
  else
    p = u * n;
  const Float q = p - Float(offset);
  const Float scaled = bits == 0 ? q : q * Float(float(1 << bits));
  Float fixed = xsimd::floor(scaled);
  if (exact) {
    const Float back = q - p, d = (p - (q - back)) + (Float(0.0f) - Float(offset) - back);  // q + d = p - offset
    fixed = xsimd::select((scaled == fixed) & ((d + e) < Float(0.0f)), fixed - Float(1.0f), fixed);
  }
  if (bits == 0) {
    index = xsimd::to_int(fixed);
    weight = q - fixed;
    return;
  }
  const Int f = xsimd::to_int(fixed);
  index = f >> bits;
  weight = xsimd::to_float(f & Int((1 << bits) - 1)) * Float(1.0f / float(1 << bits));
}

QDMR_SAMPLER_INLINE void sample_level(const TextureView& view, const SamplerKey& k, const Float& u, const Float& v,
                              const LevelInfo& info, bool linear, Float* out, bool record = true) {
  const Float w = xsimd::to_float(info.width), h = xsimd::to_float(info.height);
  const bool pow2 = view.power_of_two();
  if (!linear) {
    Int x, y;
    Float unused;
    split(u, w, pow2, 0.0f, k.fraction_bits, k.exact_texel, x, unused);
    split(v, h, pow2, 0.0f, k.fraction_bits, k.exact_texel, y, unused);
    fetch(view, k, info, address(x, info.width, k.address), address(y, info.height, k.address), out, record);
    return;
  }
  Int x0, y0;
  Float wx, wy;
  split(u, w, pow2, 0.5f, k.fraction_bits, k.exact_texel, x0, wx);
  split(v, h, pow2, 0.5f, k.fraction_bits, k.exact_texel, y0, wy);
  const Int xa = address(x0, info.width, k.address), xb = address(x0 + Int(1), info.width, k.address);
  const Int ya = address(y0, info.height, k.address), yb = address(y0 + Int(1), info.height, k.address);
  Float t00[4], t10[4], t01[4], t11[4];
  // Texel xa + 1 follows texel xa in memory, so where every lane's xb is xa + 1 (all but the lanes at a wrap or
  // clamp edge) one load per row gives both texels.
  if (xsimd::all(xb == xa + Int(1))) {
    if (k.format == TexelFormat::RGBA8 && k.srgb && !view.texture().linear.empty()) {
      fetch_linear_pair(view, k, info, xa, xb, ya, t00, t10, record);
      fetch_linear_pair(view, k, info, xa, xb, yb, t01, t11, record);
    } else {
      fetch_pair(view, k, info, xa, xb, ya, t00, t10, record);
      fetch_pair(view, k, info, xa, xb, yb, t01, t11, record);
    }
  } else {
    fetch(view, k, info, xa, ya, t00, record);
    fetch(view, k, info, xb, ya, t10, record);
    fetch(view, k, info, xa, yb, t01, record);
    fetch(view, k, info, xb, yb, t11, record);
  }
  for (int c = 0; c < channel_count(k.format); ++c) {
    const Float top = t00[c] + (t10[c] - t00[c]) * wx;
    const Float bottom = t01[c] + (t11[c] - t01[c]) * wx;
    out[c] = top + (bottom - top) * wy;
  }
}

// Whether a mip-linear sample may skip its coarse level: no lane weighs it (f, the LOD's fraction, is 0 in every
// lane: magnified, or at a whole LOD), and fine + (coarse - fine) * 0 is fine's bits. That holds for the unorm
// formats, whose filtered texels are finite and never -0; an R32F texel may be infinite or NaN (then the product
// is NaN) or -0 (then -0 + 0 is +0). A listening texture-cache recorder still sees both levels' fetches (its
// statistics do not depend on this shortcut).
QDMR_SAMPLER_INLINE bool coarse_level_weightless(const SamplerKey& k, const Float& f, bool record) {
  return k.format != TexelFormat::R32F && (!record || !fetch_recorder_listens()) && xsimd::all(f == Float(0.0f));
}

// record false: the caller knows no texture-cache recorder listens (see fetch()).
QDMR_SAMPLER_INLINE void sample_with(const SamplerKey& k, const TextureView& view, const SamplerState& s, const Float& u,
                             const Float& v, const Float& lod, Float* out, bool record = true) {
  const Mask finite = is_finite(u) & is_finite(v);
  const Float ru = reduce(xsimd::select(finite, u, Float(0.0f)), k.address);
  const Float rv = reduce(xsimd::select(finite, v, Float(0.0f)), k.address);
  const bool linear = k.filter == Filter::Bilinear || k.filter == Filter::Trilinear || k.filter == Filter::LinearMipPoint;
  const int channels = channel_count(k.format);
  if (k.filter == Filter::Point || k.filter == Filter::Bilinear) {
    sample_level(view, k, ru, rv, level_zero(view), linear, out, record);
  } else {
    const Float last(float(view.levels() - 1));
    Float l = lod + Float(s.lod_bias);
    l = xsimd::select(l == l, l, last);  // NaN: the coarsest level, as for non-finite derivatives
    l = xsimd::min(xsimd::max(l, Float(s.min_lod)), Float(s.max_lod));
    l = xsimd::min(xsimd::max(l, Float(0.0f)), last);
    const int bits = k.fraction_bits;
    if (bits > 0) l = xsimd::floor(l * Float(float(1 << bits))) * Float(1.0f / float(1 << bits));
    if (k.filter == Filter::PointMipPoint || k.filter == Filter::LinearMipPoint) {
      sample_level(view, k, ru, rv, level_info(view, xsimd::to_int(xsimd::floor(l + Float(0.5f)))), linear, out,
                   record);
    } else {  // trilinear, point-mip-linear
      const Float l0 = xsimd::floor(l), f = l - l0;
      const Int i0 = xsimd::to_int(l0);
      Float fine[4], coarse[4];
      sample_level(view, k, ru, rv, level_info(view, i0), linear, fine, record);
      if (coarse_level_weightless(k, f, record)) {
        for (int c = 0; c < channels; ++c) out[c] = fine[c];
      } else {
        sample_level(view, k, ru, rv, level_info(view, xsimd::min(i0 + Int(1), Int(view.levels() - 1))), linear,
                     coarse, record);
        for (int c = 0; c < channels; ++c) out[c] = fine[c] + (coarse[c] - fine[c]) * f;
      }
    }
  }
  for (int c = 0; c < channels; ++c) out[c] = xsimd::select(finite, out[c], Float(view.first_texel()[std::size_t(c)]));
}

// wrap: x and y wrapped into the level by masking (power-of-two sizes), else clamped.
QDMR_SAMPLER_INLINE void load_with(const SamplerKey& k, bool wrap, const TextureView& view, const Int& level, const Int& x,
                           const Int& y, Float* out, bool record = true) {
  const Int l = xsimd::min(xsimd::max(level, Int(0)), Int(view.levels() - 1));
  const LevelInfo info = level_info(view, l);
  if (wrap) {
    fetch(view, k, info, x & (info.width - Int(1)), y & (info.height - Int(1)), out, record);
    return;
  }
  const Int cx = xsimd::min(xsimd::max(x, Int(0)), info.width - Int(1));
  const Int cy = xsimd::min(xsimd::max(y, Int(0)), info.height - Int(1));
  fetch(view, k, info, cx, cy, out, record);
}

// Channel 0 of sample_with() for a key fixed at compile time, inlined into the caller's loop.
template <SamplerKey K, bool Recorded = true>
QDMR_SAMPLER_INLINE Float sample_first(const TextureView& view, const SamplerState& s, const Float& u, const Float& v,
                                       const Float& lod) {
  Float out[4];
  sample_with(K, view, s, u, v, lod, out, Recorded);
  return out[0];
}

#undef QDMR_SAMPLER_INLINE

}  // namespace qdmr::QDMR_ISA_NAMESPACE::sampling_code
