#pragma once
// The sampler's code, for sampler.cpp and for the few callers that inline one key into a loop (height_surface.hpp):
// every helper is always inlined, so where the key is a constant (an instantiation) its branches fold away and
// where it is not (the generic sampler) they run per call. Coordinates are first reduced exactly to one period
// of the address mode, so texel indices stay small for any finite u; then texel indices and weights come either
// from exact float arithmetic or from fixed point with 8 or 6 fractional bits, as texture units do.
#include <algorithm>

#include "kernel/gather.hpp"
#include "core/simd.hpp"
#include "kernel/fetch_trace.hpp"
#include "texture/srgb_decode.hpp"
#include "kernel/sampler.hpp"

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

// Texel index i (within a period or two of the reduced coordinate) to a texel of [0, n). `n_power_of_two`: wrap
// by masking, which gives the same texel for every i in [-n, 2n) (the reduced coordinates give [-1, n]).
QDMR_SAMPLER_INLINE Int address(Int i, const Int& n, AddressMode mode, bool n_power_of_two) {
  switch (mode) {
    case AddressMode::Wrap:
      if (n_power_of_two) return i & (n - Int(1));
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

// channels: how many of the texel's channels to decode (the others are left as they are).
QDMR_SAMPLER_INLINE void decode(const SamplerKey& k, const Int& raw, Float* out, int channels = 4) {
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
      if (channels > 3)
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

// Texels (x, y) and (x + 1, y) of every lane of a texture with 4-byte texels, from one 8-byte load per lane, o: the
// lanes' byte offsets of texel (x, y).
QDMR_SAMPLER_INLINE void fetch_texel_pair_at(const Texture& t, const SamplerKey& k, const std::int32_t* o, Float* a,
                                             Float* b, int channels = 4) {
  Int first, second;
  simd::load_bytes8_at(t.storage.data(), o, k.fetch, first, second);
  decode(k, first, a, channels);
  decode(k, second, b, channels);
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
  alignas(64) std::int32_t o[kLanes];
  offset.store_aligned(o);
  fetch_texel_pair_at(t, k, o, a, b);
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

// split() of a bilinear tap (offset 1/2) with `bits` > 0 fractional bits and the exact texel coordinate, for a
// reduced coordinate ru in [0, 2] (wrap or mirror) and a power-of-two n: ru n 2^bits is exact (a product with a
// power of two), so the exact coordinate's fixed point floor((ru n - 1/2) 2^bits) is its floor minus 2^(bits - 1),
// with no correction step: the same index and weight as split(), about a dozen operations fewer.
QDMR_SAMPLER_INLINE void split_fixed_power_of_two(const Float& ru, const Float& n, int bits, Int& index,
                                                  Float& weight) {
  const Int f = xsimd::to_int(xsimd::floor(ru * (n * Float(float(1 << bits))))) - Int(1 << (bits - 1));
  index = f >> bits;
  weight = xsimd::to_float(f & Int((1 << bits) - 1)) * Float(1.0f / float(1 << bits));
}

// The four texels of a bilinear footprint on one level and the weights between them: texels (xa | xb, ya | yb).
struct BilinearTaps {
  Int xa, xb, ya, yb;
  Float wx, wy;
  // Every lane's xb is xa + 1, so texel xb follows texel xa in memory (all but the lanes at a wrap or clamp edge)
  // and one load per row gives both.
  bool adjacent;
};

QDMR_SAMPLER_INLINE BilinearTaps bilinear_taps(const TextureView& view, const SamplerKey& k, const Float& u,
                                               const Float& v, const LevelInfo& info) {
  const Float w = xsimd::to_float(info.width), h = xsimd::to_float(info.height);
  const bool pow2 = view.power_of_two();
  Int x0, y0;
  BilinearTaps t;
  if (k.fraction_bits > 0 && k.exact_texel && pow2 && k.address != AddressMode::Clamp) {  // u, v reduced: in [0, 2]
    split_fixed_power_of_two(u, w, k.fraction_bits, x0, t.wx);
    split_fixed_power_of_two(v, h, k.fraction_bits, y0, t.wy);
  } else {
    split(u, w, pow2, 0.5f, k.fraction_bits, k.exact_texel, x0, t.wx);
    split(v, h, pow2, 0.5f, k.fraction_bits, k.exact_texel, y0, t.wy);
  }
  t.xa = address(x0, info.width, k.address, pow2);
  t.xb = address(x0 + Int(1), info.width, k.address, pow2);
  t.ya = address(y0, info.height, k.address, pow2);
  t.yb = address(y0 + Int(1), info.height, k.address, pow2);
  t.adjacent = xsimd::all(t.xb == t.xa + Int(1));
  return t;
}

// The point-sampled texel of each lane.
QDMR_SAMPLER_INLINE void point_texel(const TextureView& view, const SamplerKey& k, const Float& u, const Float& v,
                                     const LevelInfo& info, Int& x, Int& y) {
  const bool pow2 = view.power_of_two();
  Float unused;
  split(u, xsimd::to_float(info.width), pow2, 0.0f, k.fraction_bits, k.exact_texel, x, unused);
  split(v, xsimd::to_float(info.height), pow2, 0.0f, k.fraction_bits, k.exact_texel, y, unused);
  x = address(x, info.width, k.address, pow2);
  y = address(y, info.height, k.address, pow2);
}

// The taps' texels one by one (any lane at an edge).
QDMR_SAMPLER_INLINE void fetch_taps(const TextureView& view, const SamplerKey& k, const LevelInfo& info,
                                    const BilinearTaps& t, Float* t00, Float* t10, Float* t01, Float* t11,
                                    bool record) {
  fetch(view, k, info, t.xa, t.ya, t00, record);
  fetch(view, k, info, t.xb, t.ya, t10, record);
  fetch(view, k, info, t.xa, t.yb, t01, record);
  fetch(view, k, info, t.xb, t.yb, t11, record);
}

// channels: how many of the format's channels to filter (all by default).
QDMR_SAMPLER_INLINE void filter_taps(const SamplerKey& k, const BilinearTaps& t, const Float* t00, const Float* t10,
                                     const Float* t01, const Float* t11, Float* out, int channels = 4) {
  for (int c = 0; c < std::min(channel_count(k.format), channels); ++c) {
    const Float top = t00[c] + (t10[c] - t00[c]) * t.wx;
    const Float bottom = t01[c] + (t11[c] - t01[c]) * t.wx;
    out[c] = top + (bottom - top) * t.wy;
  }
}

// The taps of a bilinear sample of level 0 with wrap addressing from the texture's wrap footprints (Texture::
// wrap_footprints): one 16-byte load per lane, neighbours already wrapped, so no lane at the edge needs its own.
QDMR_SAMPLER_INLINE void fetch_wrap_footprints(const TextureView& view, const SamplerKey& k, const LevelInfo& level0,
                                               const BilinearTaps& t, Float* t00, Float* t10, Float* t01, Float* t11,
                                               bool record) {
  const Texture& texture = view.texture();
  if (record) {  // the texels a GPU reads, in fetch_taps' order
    trace_fetch(texture, level0.offset, t.xa, t.ya);
    trace_fetch(texture, level0.offset, t.xb, t.ya);
    trace_fetch(texture, level0.offset, t.xa, t.yb);
    trace_fetch(texture, level0.offset, t.xb, t.yb);
  }
  Float footprint[4];
  simd::load_f32x4(texture.wrap_footprints.data(), (t.ya * level0.width + t.xa) * Int(4), k.fetch, footprint);
  t00[0] = footprint[0];
  t10[0] = footprint[1];
  t01[0] = footprint[2];
  t11[0] = footprint[3];
}

// Channel 0 of sample_with() for a bilinear key with wrap addressing on a power-of-two texture with wrap footprints
// (never recorded) at finite coordinates, from values of the texture that the caller reads once: footprints
// (Texture::wrap_footprints) and level 0's size as integers and floats. sample_levels(), bilinear_taps(),
// fetch_wrap_footprints() and filter_taps() in one line without the test for non-finite coordinates, so the same
// bits where u and v are finite; elsewhere any value (the addresses stay in the level: indices wrap by masking).
template <SamplerKey K>
QDMR_SAMPLER_INLINE Float sample_wrap_footprints(const float* footprints, const LevelInfo& level0, const Float& w,
                                                 const Float& h, const Float& u, const Float& v) {
  static_assert(K.filter == Filter::Bilinear && K.address == AddressMode::Wrap && channel_count(K.format) == 1);
  Int x0, y0;
  Float wx, wy;
  if constexpr (K.fraction_bits > 0 && K.exact_texel) {
    split_fixed_power_of_two(reduce(u, K.address), w, K.fraction_bits, x0, wx);
    split_fixed_power_of_two(reduce(v, K.address), h, K.fraction_bits, y0, wy);
  } else {
    split(reduce(u, K.address), w, true, 0.5f, K.fraction_bits, K.exact_texel, x0, wx);
    split(reduce(v, K.address), h, true, 0.5f, K.fraction_bits, K.exact_texel, y0, wy);
  }
  const Int xa = address(x0, level0.width, K.address, true), ya = address(y0, level0.height, K.address, true);
  Float t[4];  // (xa, ya), (xb, ya), (xa, yb), (xb, yb)
  simd::load_f32x4(footprints, (ya * level0.width + xa) * Int(4), K.fetch, t);
  const Float top = t[0] + (t[1] - t[0]) * wx;
  const Float bottom = t[2] + (t[3] - t[2]) * wx;
  return top + (bottom - top) * wy;
}

QDMR_SAMPLER_INLINE void sample_level(const TextureView& view, const SamplerKey& k, const Float& u, const Float& v,
                              const LevelInfo& info, bool linear, Float* out, bool record = true) {
  if (!linear) {
    Int x, y;
    point_texel(view, k, u, v, info, x, y);
    fetch(view, k, info, x, y, out, record);
    return;
  }
  const BilinearTaps t = bilinear_taps(view, k, u, v, info);
  Float t00[4], t10[4], t01[4], t11[4];
  // Bilinear filtering samples level 0 only (sample_levels), the level the footprints are of.
  if (k.filter == Filter::Bilinear && k.address == AddressMode::Wrap && !view.texture().wrap_footprints.empty()) {
    fetch_wrap_footprints(view, k, info, t, t00, t10, t01, t11, record);
  } else if (t.adjacent) {
    if (k.format == TexelFormat::RGBA8 && k.srgb && !view.texture().linear.empty()) {
      fetch_linear_pair(view, k, info, t.xa, t.xb, t.ya, t00, t10, record);
      fetch_linear_pair(view, k, info, t.xa, t.xb, t.yb, t01, t11, record);
    } else {
      fetch_pair(view, k, info, t.xa, t.xb, t.ya, t00, t10, record);
      fetch_pair(view, k, info, t.xa, t.xb, t.yb, t01, t11, record);
    }
  } else {
    fetch_taps(view, k, info, t, t00, t10, t01, t11, record);
  }
  filter_taps(k, t, t00, t10, t01, t11, out);
}

// Two RGBA8 textures whose chains have one size (so one layout) sampled at the same coordinates: twin_keys()
// says where that holds. A texel sits at the same byte offset in both chains, and in texels of 4 floats at that
// float index of the decoded sRGB copy, so one texel offset per lane serves both textures.
QDMR_SAMPLER_INLINE bool twin_keys(const SamplerKey& a, const SamplerKey& b) {
  return a.format == TexelFormat::RGBA8 && b.format == TexelFormat::RGBA8 && a.filter == b.filter &&
         a.address == b.address && a.fraction_bits == b.fraction_bits && a.exact_texel == b.exact_texel &&
         a.fetch == b.fetch;
}

// Texels (x, y) and (x + 1, y) of every lane of an RGBA8 texture, o: the lanes' byte offsets of texel (x, y).
QDMR_SAMPLER_INLINE void fetch_rgba8_pair_at(const TextureView& view, const SamplerKey& k, const std::int32_t* o,
                                             Float* first, Float* second, int channels = 4) {
  const Texture& t = view.texture();
  if (k.srgb && !t.linear.empty())
    simd::load_f32x4_pair_at(t.linear.data(), o, k.fetch, first, second);
  else
    fetch_texel_pair_at(t, k, o, first, second, channels);
}

// Prefetches, in each lane, the bilinear footprint's row that a sample at (u, v) on `info`'s level reads and a
// sample at (u - du, v - dv) does not (its top row if dv < 0, its bottom row otherwise), in both twin textures (a's
// decoded copy where its samples read that; the interleaved texels where there are some): a hint for a later
// sample there (UvAhead), made where the rasterizer moves by (du, dv) per quad row. u and v reduced by the address
// mode. Plain float arithmetic: a prefetch changes no result, and a texel off by one costs at most a miss.
QDMR_SAMPLER_INLINE void prefetch_twin_texels(const TextureView& va, const SamplerKey& ka, const TextureView& vb,
                                              const float* interleaved, const Float& u, const Float& v,
                                              const Float& dv, const LevelInfo& info) {
  const Float w = xsimd::to_float(info.width), h = xsimd::to_float(info.height);
  const Int x = xsimd::to_int(xsimd::floor(u * w - Float(0.5f)));
  const Int y = xsimd::to_int(xsimd::floor(v * h + xsimd::select(dv > Float(0.0f), Float(0.5f), Float(-0.5f))));
  alignas(64) std::int32_t o[kLanes];
  const bool pow2 = va.power_of_two();
  (info.offset + (address(y, info.height, ka.address, pow2) * info.width + address(x, info.width, ka.address, pow2)) *
                     Int(4))
      .store_aligned(o);
  if (interleaved != nullptr) {
    for (int lane = 0; lane < kLanes; ++lane) __builtin_prefetch(interleaved + o[lane]);
    return;
  }
  const Texture &a = va.texture(), &b = vb.texture();
  const bool a_decoded = ka.srgb && !a.linear.empty();
  for (int lane = 0; lane < kLanes; ++lane) {
    if (a_decoded)
      __builtin_prefetch(a.linear.data() + o[lane]);
    else
      __builtin_prefetch(a.storage.data() + o[lane]);
    __builtin_prefetch(b.storage.data() + o[lane]);
  }
}

// sample_level() of two textures (twin_keys) at once: out[0..2] texture a's rgb, out[3..5] texture b's rgb (the
// alphas are not filtered). interleaved: the two interleaved (twin_texels.hpp), or null.
// Never recorded: the caller knows no texture-cache recorder listens.
QDMR_SAMPLER_INLINE void sample_level_twin(const TextureView& va, const SamplerKey& ka, const TextureView& vb,
                                           const SamplerKey& kb, const float* interleaved, const Float& u,
                                           const Float& v, const LevelInfo& info, bool linear, Float* out) {
  if (!linear) {
    Int x, y;
    point_texel(va, ka, u, v, info, x, y);
    Float a[4], b[4];
    fetch(va, ka, info, x, y, a, false);
    fetch(vb, kb, info, x, y, b, false);
    for (int c = 0; c < 3; ++c) out[c] = a[c], out[3 + c] = b[c];
    return;
  }
  const BilinearTaps t = bilinear_taps(va, ka, u, v, info);
  if (t.adjacent && interleaved != nullptr) {
    // Per tap one 16-byte texel: a's rgb, then b's code, decoded as its chain's texel would be. Each row is
    // blended across as soon as it is read (filter_taps' operations, so its bits): the four taps of both textures
    // at once (28 vectors) outgrew the registers, and their spills were a fifth of the sample's instructions.
    alignas(64) std::int32_t top[kLanes], bottom[kLanes];
    (info.offset + (t.ya * info.width + t.xa) * Int(4)).store_aligned(top);
    (info.offset + (t.yb * info.width + t.xa) * Int(4)).store_aligned(bottom);
    const auto across = [&](const std::int32_t* row, Float* rgb_a, Float* rgb_b) __attribute__((always_inline)) {
      Float left[4], right[4], left_b[3], right_b[3];
      simd::load_f32x4_pair_at(interleaved, row, ka.fetch, left, right);
      decode(kb, xsimd::bitwise_cast<Int>(left[3]), left_b, 3);
      decode(kb, xsimd::bitwise_cast<Int>(right[3]), right_b, 3);
      for (int c = 0; c < 3; ++c) {
        rgb_a[c] = left[c] + (right[c] - left[c]) * t.wx;
        rgb_b[c] = left_b[c] + (right_b[c] - left_b[c]) * t.wx;
      }
    };
    Float top_a[3], top_b[3], bottom_a[3], bottom_b[3];
    across(top, top_a, top_b);
    across(bottom, bottom_a, bottom_b);
    for (int c = 0; c < 3; ++c) {
      out[c] = top_a[c] + (bottom_a[c] - top_a[c]) * t.wy;
      out[3 + c] = top_b[c] + (bottom_b[c] - top_b[c]) * t.wy;
    }
    return;
  }
  Float a00[4], a10[4], a01[4], a11[4], b00[4], b10[4], b01[4], b11[4];
  if (t.adjacent) {
    alignas(64) std::int32_t top[kLanes], bottom[kLanes];
    (info.offset + (t.ya * info.width + t.xa) * Int(4)).store_aligned(top);
    (info.offset + (t.yb * info.width + t.xa) * Int(4)).store_aligned(bottom);
    fetch_rgba8_pair_at(va, ka, top, a00, a10);
    fetch_rgba8_pair_at(vb, kb, top, b00, b10, 3);
    fetch_rgba8_pair_at(va, ka, bottom, a01, a11);
    fetch_rgba8_pair_at(vb, kb, bottom, b01, b11, 3);
  } else {
    fetch_taps(va, ka, info, t, a00, a10, a01, a11, false);
    fetch_taps(vb, kb, info, t, b00, b10, b01, b11, false);
  }
  filter_taps(ka, t, a00, a10, a01, a11, out, 3);
  filter_taps(kb, t, b00, b10, b01, b11, out + 3, 3);
}

// Whether a mip-linear sample may skip its coarse level: no lane weighs it (f, the LOD's fraction, is 0 in every
// lane: magnified, or at a whole LOD), and fine + (coarse - fine) * 0 is fine's bits. That holds for the unorm
// formats, whose filtered texels are finite and never -0; an R32F texel may be infinite or NaN (then the product
// is NaN) or -0 (then -0 + 0 is +0). A listening texture-cache recorder still sees both levels' fetches (its
// statistics do not depend on this shortcut).
QDMR_SAMPLER_INLINE bool coarse_level_weightless(const SamplerKey& k, const Float& f, bool record) {
  return k.format != TexelFormat::R32F && (!record || !fetch_recorder_listens()) && xsimd::all(f == Float(0.0f));
}

// The filter's levels and their blend, for one texture or two alike (sample_twin_with): at_level(ru, rv, info,
// linear, out) samples `channels` channels of one level, first_texel[c] is channel c's value for lanes with
// non-finite coordinates. k's filter, address mode, fraction bits and format decide; view gives the levels.
template <class AtLevel>
QDMR_SAMPLER_INLINE void sample_levels(const SamplerKey& k, const TextureView& view, const SamplerState& s,
                                       const Float& u, const Float& v, const Float& lod, int channels,
                                       const float* first_texel, bool record, const AtLevel& at_level, Float* out) {
  const Mask finite = is_finite(u) & is_finite(v);
  const Float ru = reduce(xsimd::select(finite, u, Float(0.0f)), k.address);
  const Float rv = reduce(xsimd::select(finite, v, Float(0.0f)), k.address);
  const bool linear = k.filter == Filter::Bilinear || k.filter == Filter::Trilinear || k.filter == Filter::LinearMipPoint;
  if (k.filter == Filter::Point || k.filter == Filter::Bilinear) {
    at_level(ru, rv, level_zero(view), linear, out);
  } else {
    const Float last(float(view.levels() - 1));
    Float l = lod + Float(s.lod_bias);
    l = xsimd::select(l == l, l, last);  // NaN: the coarsest level, as for non-finite derivatives
    l = xsimd::min(xsimd::max(l, Float(s.min_lod)), Float(s.max_lod));
    l = xsimd::min(xsimd::max(l, Float(0.0f)), last);
    const int bits = k.fraction_bits;
    if (bits > 0) l = xsimd::floor(l * Float(float(1 << bits))) * Float(1.0f / float(1 << bits));
    if (k.filter == Filter::PointMipPoint || k.filter == Filter::LinearMipPoint) {
      at_level(ru, rv, level_info(view, xsimd::to_int(xsimd::floor(l + Float(0.5f)))), linear, out);
    } else {  // trilinear, point-mip-linear
      const Float l0 = xsimd::floor(l), f = l - l0;
      const Int i0 = xsimd::to_int(l0);
      Float fine[8], coarse[8];
      at_level(ru, rv, level_info(view, i0), linear, fine);
      if (coarse_level_weightless(k, f, record)) {
        for (int c = 0; c < channels; ++c) out[c] = fine[c];
      } else {
        at_level(ru, rv, level_info(view, xsimd::min(i0 + Int(1), Int(view.levels() - 1))), linear, coarse);
        for (int c = 0; c < channels; ++c) out[c] = fine[c] + (coarse[c] - fine[c]) * f;
      }
    }
  }
  for (int c = 0; c < channels; ++c) out[c] = xsimd::select(finite, out[c], Float(first_texel[c]));
}

// record false: the caller knows no texture-cache recorder listens (see fetch()).
QDMR_SAMPLER_INLINE void sample_with(const SamplerKey& k, const TextureView& view, const SamplerState& s, const Float& u,
                             const Float& v, const Float& lod, Float* out, bool record = true) {
  sample_levels(k, view, s, u, v, lod, channel_count(k.format), view.first_texel().data(), record,
                [&](const Float& ru, const Float& rv, const LevelInfo& info, bool linear,
                    Float* level_out) __attribute__((always_inline)) {
                  sample_level(view, k, ru, rv, info, linear, level_out, record);
                },
                out);
}

// sample_with() of two textures alike (twin_keys, one chain layout) at the same coordinates and LOD: the rgb of
// out_a and out_b get what sample_with() gives each, from one address computation; both alphas are 1 (an albedo's
// and a normal map's, which nothing reads). interleaved: the two interleaved (twin_texels.hpp), or null. Never
// recorded. ahead (optional): where the quad below samples, prefetched on the finest level this sample reads.
QDMR_SAMPLER_INLINE void sample_twin_with(const SamplerKey& ka, const SamplerKey& kb, const TextureView& va,
                                          const TextureView& vb, const float* interleaved, const SamplerState& s,
                                          const Float& u, const Float& v, const Float& lod, const UvAhead* ahead,
                                          Float* out_a, Float* out_b) {
  float first_texel[6];  // a's rgb, then b's
  for (int c = 0; c < 3; ++c) {
    first_texel[c] = va.first_texel()[std::size_t(c)];
    first_texel[3 + c] = vb.first_texel()[std::size_t(c)];
  }
  Float out[6];
  bool finest = true;  // sample_levels() reads the finer level first
  sample_levels(ka, va, s, u, v, lod, 6, first_texel, false,
                [&](const Float& ru, const Float& rv, const LevelInfo& info, bool linear,
                    Float* level_out) __attribute__((always_inline)) {
                  if (finest && ahead != nullptr) {
                    const Float au = u + ahead->du, av = v + ahead->dv;
                    const Mask finite = is_finite(au) & is_finite(av);
                    prefetch_twin_texels(va, ka, vb, interleaved,
                                         reduce(xsimd::select(finite, au, Float(0.0f)), ka.address),
                                         reduce(xsimd::select(finite, av, Float(0.0f)), ka.address), ahead->dv,
                                         info);
                  }
                  finest = false;
                  sample_level_twin(va, ka, vb, kb, interleaved, ru, rv, info, linear, level_out);
                },
                out);
  // Read before the first store: out_a and out_b might overlap as far as the compiler knows, and a copy loop
  // became a byte copy in 16-byte halves behind an overlap test.
  const Float ar = out[0], ag = out[1], ab = out[2], br = out[3], bg = out[4], bb = out[5];
  out_a[0] = ar, out_a[1] = ag, out_a[2] = ab, out_a[3] = Float(1.0f);
  out_b[0] = br, out_b[1] = bg, out_b[2] = bb, out_b[3] = Float(1.0f);
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
