#pragma once
// The code of HeightRows (texture/height_rows.hpp): plain loops over a row, written so that the compiler
// vectorises them (one lane per texel, the generic builders' IEEE operations in their order: the same bits on any
// vector width). In the ISA namespace: kernel/height_rows.cpp compiles it per ISA, texture/height_family.cpp for
// the baseline.
#include <algorithm>
#include <bit>
#include <cfloat>
#include <cmath>
#include <cstdint>
#include <cstring>

#include "core/isa_namespace.hpp"
#include "texture/height_rows.hpp"
#include "texture/mip_reduce.hpp"

namespace qdmr::QDMR_ISA_NAMESPACE::height_row_code {

template <int Sharpness>
void add_wave_n(float* row, int n, const float* su, const float* cu, float sv, float cv, float weight) {
  for (int x = 0; x < n; ++x) {
    const float w = 0.5f + 0.5f * (su[x] * cv + cu[x] * sv);
    float p = w;
    for (int k = 1; k < Sharpness; ++k) p = p * w;
    row[x] = row[x] + weight * p;
  }
}

inline void add_wave(int sharpness, float* row, int n, const float* su, const float* cu, float sv, float cv,
                     float weight) {
  using F = void (*)(float*, int, const float*, const float*, float, float, float);
  static constexpr F kBySharpness[] = {add_wave_n<1>, add_wave_n<2>, add_wave_n<3>, add_wave_n<4>,
                                       add_wave_n<5>, add_wave_n<6>, add_wave_n<7>, add_wave_n<8>};
  kBySharpness[std::clamp(sharpness, 1, 8) - 1](row, n, su, cu, sv, cv, weight);
}

inline void finish_waves(float* row, int n, float scale, float offset) {
  for (int x = 0; x < n; ++x) {
    const float h = std::min(1.0f, std::max(0.0f, row[x]));
    row[x] = std::clamp(h * scale + offset, 0.0f, 1.0f);
  }
}

// make_mip_texture's quantisation: clamp to [0, 1] (NaN to 0), round to nearest, ties up (exact in double). As
// v Max + 0.5 clamped to [0, Max] and truncated, without a call to floor: the same code (at or below 0, or NaN, it
// is 0; at or above 1, Max; in between the truncation of a positive number is its floor).
template <int Max>
inline int code_of(float v) {
  const double x = double(v) * double(Max) + 0.5;
  const double above = 0.0 < x ? x : 0.0;  // std::max(0.0, x): NaN to 0
  return int(above < double(Max) ? above : double(Max));
}

template <class Code>
inline Code load_code(const std::uint8_t* p, int i) {
  Code c;
  std::memcpy(&c, p + std::size_t(i) * sizeof(Code), sizeof(Code));
  return c;
}

template <class Code>
inline void store_code(std::uint8_t* p, int i, Code c) {
  std::memcpy(p + std::size_t(i) * sizeof(Code), &c, sizeof(Code));
}

template <class Code, int Max>
void quantise_n(const float* h, int n, std::uint8_t* codes, float* decoded) {
  for (int x = 0; x < n; ++x) {
    const Code c = Code(code_of<Max>(h[x]));
    store_code<Code>(codes, x, c);
    decoded[x] = float(c) / float(Max);
  }
}

inline void quantise(TexelFormat format, const float* h, int n, std::uint8_t* codes, float* decoded) {
  if (format == TexelFormat::R16) quantise_n<std::uint16_t, 65535>(h, n, codes, decoded);
  else quantise_n<std::uint8_t, 255>(h, n, codes, decoded);
}

template <class Code, int Max>
void decode_n(const std::uint8_t* codes, int n, float* decoded) {
  for (int x = 0; x < n; ++x) decoded[x] = float(load_code<Code>(codes, x)) / float(Max);
}

inline void decode(TexelFormat format, const std::uint8_t* codes, int n, float* decoded) {
  if (format == TexelFormat::R16) decode_n<std::uint16_t, 65535>(codes, n, decoded);
  else decode_n<std::uint8_t, 255>(codes, n, decoded);
}

// reduce_box<false>: the sum of the taps in tap order (rows, then columns), divided by their count.
template <class Code, int Max>
void box_n(const float* const* in, int rows, int in_w, int out_w, std::uint8_t* codes, float* decoded) {
  const auto put = [&](int x, float sum, float count) {
    const Code c = Code(code_of<Max>(sum / count));
    store_code<Code>(codes, x, c);
    decoded[x] = float(c) / float(Max);
  };
  // Texels of two taps per row, in vectors where the rows are two (every level of an even-sided map).
  int x = 0;
  if (in_w > 1) {
    const int pairs = out_w - (in_w & 1);
    if (rows == 2) {
      const float *a = in[0], *b = in[1];
      for (; x < pairs; ++x) put(x, 0.0f + a[2 * x] + a[2 * x + 1] + b[2 * x] + b[2 * x + 1], 4.0f);
    }
  }
  for (; x < out_w; ++x) {  // the rest, with the generic taps
    const mip::Taps tx = mip::taps(x, in_w, out_w);
    float sum = 0.0f;
    for (int j = 0; j < rows; ++j)
      for (int i = tx.first; i < tx.first + tx.count; ++i) sum += in[j][i];
    put(x, sum, float(tx.count * rows));
  }
}

inline void box(TexelFormat format, const float* const* in, int rows, int in_w, int out_w, std::uint8_t* codes,
                float* decoded) {
  if (format == TexelFormat::R16) box_n<std::uint16_t, 65535>(in, rows, in_w, out_w, codes, decoded);
  else box_n<std::uint8_t, 255>(in, rows, in_w, out_w, codes, decoded);
}

// 0.5 + 0.5 n of a unit normal component, as an RGBA8 code.
inline std::uint8_t unorm8_of_normal(float n) { return std::uint8_t(code_of<255>(0.5f + 0.5f * n)); }

// normals_from_height and the from_height slot's normalise (a zero or non-finite length gives (0, 0, 1)).
inline void normal_texel(float nx, float ny, std::uint8_t* rgba) {
  const float nz = 1.0f;
  const double len2 = double(nx) * nx + double(ny) * ny + double(nz) * nz;
  const bool ok = (len2 > 0.0) & (len2 <= DBL_MAX);
  const double inv = 1.0 / std::sqrt(ok ? len2 : 1.0);
  rgba[0] = unorm8_of_normal(ok ? float(nx * inv) : 0.0f);
  rgba[1] = unorm8_of_normal(ok ? float(ny * inv) : 0.0f);
  rgba[2] = unorm8_of_normal(ok ? float(nz * inv) : 1.0f);
  rgba[3] = 255;
}

// A normal's components are first computed in float: without normal_texel's double square root and division, the
// level-0 normals of scenes/water.json take half the time (perf of qdmr_dynamic_height_bench). Each float component
// c' gives x' = (0.5 + 0.5 c') 255 + 0.5 within 1.6e-4 of the x that normal_texel truncates (a first-order bound in
// units of u = 2^-24: the scaled central difference 4 u, the squared length 11 u, its inverse square root 7.5 u, c'
// 13.5 u, the half 8.75 u, times 255, plus x's own roundings 511 u: 2742 u; at most 3.8e-5 seen over 10^8 random
// texels and strengths). Where every x' lies more than kFastNormalMargin (6x the bound) from an integer, both
// truncate to the same code; the other texels (about 0.6 %, and any with a component beyond kFastNormalLimit, a NaN
// or an infinity) are made by the exact texel. So the bits are normal_texel's (and box_normal_texel's) on every path.
inline constexpr float kFastNormalMargin = 1.0f / 1024.0f;
inline constexpr float kFastNormalLimit = 1e18f;  // |n| below it: the float squares cannot overflow
inline constexpr int kFastNormalChunk = 256;      // texels per pass before the exact ones are redone

// One component's code from its float value, and whether x' lies far enough from an integer to be trusted.
inline std::uint32_t fast_unorm8_of_normal(float c, bool& far) {
  const float x = (0.5f + 0.5f * c) * 255.0f + 0.5f;
  const float clamped = std::min(0.0f < x ? x : 0.0f, 256.0f);  // NaN to 0 (such a texel is redone)
  const int t = int(clamped);
  const float fraction = clamped - float(t);
  far = far & (fraction > kFastNormalMargin) & (fraction < 1.0f - kFastNormalMargin);
  return std::uint32_t(std::min(t, 255));
}

// An RGBA8 texel as the 32 bits that store it (little-endian: red in the lowest byte).
inline std::uint32_t rgba8_bits(std::uint32_t r, std::uint32_t g, std::uint32_t b, std::uint32_t a) {
  static_assert(std::endian::native == std::endian::little);
  return r | g << 8 | b << 16 | a << 24;
}

// Calls redo(i) for each i < n with flags[i] set (few: memchr skips the rest in vectors).
template <class Redo>
inline void for_each_flagged(const std::uint8_t* flags, int n, Redo&& redo) {
  for (const std::uint8_t* p = flags; p < flags + n; ++p) {
    p = static_cast<const std::uint8_t*>(std::memchr(p, 1, std::size_t(flags + n - p)));
    if (p == nullptr) return;
    redo(int(p - flags));
  }
}

inline void normals(const float* up, const float* row, const float* down, int w, double kx, double ky,
                    std::uint8_t* rgba) {
  const auto at = [&](int x, int left, int right) {
    normal_texel(float(-kx * (double(row[right]) - row[left])), float(-ky * (double(down[x]) - up[x])), rgba + 4 * x);
  };
  at(0, w - 1, w > 1 ? 1 : 0);
  const float fkx = float(kx), fky = float(ky);
  for (int x0 = 1; x0 < w - 1; x0 += kFastNormalChunk) {
    const int n = std::min(kFastNormalChunk, w - 1 - x0);
    std::uint32_t texels[kFastNormalChunk];
    std::uint8_t redo[kFastNormalChunk];
    for (int i = 0; i < n; ++i) {
      const int x = x0 + i;
      const float nx = -fkx * (row[x + 1] - row[x - 1]), ny = -fky * (down[x] - up[x]);
      const float inv = 1.0f / std::sqrt(nx * nx + ny * ny + 1.0f);
      bool far = (std::fabs(nx) <= kFastNormalLimit) & (std::fabs(ny) <= kFastNormalLimit);
      const std::uint32_t r = fast_unorm8_of_normal(nx * inv, far), g = fast_unorm8_of_normal(ny * inv, far),
                          b = fast_unorm8_of_normal(inv, far);
      texels[i] = rgba8_bits(r, g, b, 255);
      redo[i] = !far;
    }
    std::memcpy(rgba + 4 * std::size_t(x0), texels, 4 * std::size_t(n));
    for_each_flagged(redo, n, [&](int i) { at(x0 + i, x0 + i - 1, x0 + i + 1); });
  }
  if (w > 1) at(w - 1, w - 2, 0);
}

// reduce_box<true> on RGBA8: the taps' 2v - 1 summed per channel (alpha: v), renormalised.
inline void box_normal_texel(const float* sum, float count, std::uint8_t* rgba) {
  const double len2 = double(sum[0]) * sum[0] + double(sum[1]) * sum[1] + double(sum[2]) * sum[2];
  const double inv = len2 > 0.0 ? 1.0 / std::sqrt(len2 > 0.0 ? len2 : 1.0) : 0.0;
  rgba[0] = unorm8_of_normal(len2 > 0.0 ? float(sum[0] * inv) : 0.0f);
  rgba[1] = unorm8_of_normal(len2 > 0.0 ? float(sum[1] * inv) : 0.0f);
  rgba[2] = unorm8_of_normal(len2 > 0.0 ? float(sum[2] * inv) : 1.0f);
  rgba[3] = std::uint8_t(code_of<255>(sum[3] / count));
}

inline float unorm8(std::uint8_t c) { return float(c) / 255.0f; }

// A tap's 2v - 1.
inline float signed_unorm8(std::uint8_t c) { return 2.0f * unorm8(c) - 1.0f; }

inline void box_normals(const std::uint8_t* const* in, int rows, int in_w, int out_w, std::uint8_t* rgba) {
  int x = 0;
  if (in_w > 1 && rows == 2) {
    const std::uint8_t *a = in[0], *b = in[1];
    const auto sum_of = [&](int x, int c) {
      const std::uint8_t *a0 = a + 8 * x + c, *a1 = a0 + 4, *b0 = b + 8 * x + c, *b1 = b0 + 4;
      return c < 3 ? 0.0f + signed_unorm8(*a0) + signed_unorm8(*a1) + signed_unorm8(*b0) + signed_unorm8(*b1)
                   : 0.0f + unorm8(*a0) + unorm8(*a1) + unorm8(*b0) + unorm8(*b1);
    };
    // In float first, as normals does (the same error bound, smaller: the sums are the exact texel's).
    for (const int pairs = out_w - (in_w & 1); x < pairs; x += kFastNormalChunk) {
      const int n = std::min(kFastNormalChunk, pairs - x);
      std::uint32_t texels[kFastNormalChunk];
      std::uint8_t redo[kFastNormalChunk];
      for (int i = 0; i < n; ++i) {
        const float s0 = sum_of(x + i, 0), s1 = sum_of(x + i, 1), s2 = sum_of(x + i, 2);
        const float len2 = s0 * s0 + s1 * s1 + s2 * s2;
        const float inv = 1.0f / std::sqrt(len2);
        bool far = len2 >= 1e-30f;  // a zero length (and nothing near it) is the exact texel's
        const std::uint32_t r = fast_unorm8_of_normal(s0 * inv, far), g = fast_unorm8_of_normal(s1 * inv, far),
                            b = fast_unorm8_of_normal(s2 * inv, far);
        texels[i] = rgba8_bits(r, g, b, std::uint32_t(code_of<255>(sum_of(x + i, 3) / 4.0f)));
        redo[i] = !far;
      }
      std::memcpy(rgba + 4 * std::size_t(x), texels, 4 * std::size_t(n));
      for_each_flagged(redo, n, [&](int i) {
        const float sum[4] = {sum_of(x + i, 0), sum_of(x + i, 1), sum_of(x + i, 2), sum_of(x + i, 3)};
        box_normal_texel(sum, 4.0f, rgba + 4 * (x + i));
      });
    }
    x = out_w - (in_w & 1);
  }
  for (; x < out_w; ++x) {  // the rest, with the generic taps
    const mip::Taps tx = mip::taps(x, in_w, out_w);
    float sum[4] = {0.0f, 0.0f, 0.0f, 0.0f};
    for (int j = 0; j < rows; ++j)
      for (int i = tx.first; i < tx.first + tx.count; ++i)
        for (int c = 0; c < 4; ++c) {
          const float v = unorm8(in[j][4 * i + c]);
          sum[c] += c < 3 ? 2.0f * v - 1.0f : v;
        }
    box_normal_texel(sum, float(tx.count * rows), rgba + 4 * x);
  }
}

inline void footprints(const float* row, const float* below, int w, float* out) {
  for (int x = 0; x + 1 < w; ++x) {
    out[4 * x] = row[x];
    out[4 * x + 1] = row[x + 1];
    out[4 * x + 2] = below[x];
    out[4 * x + 3] = below[x + 1];
  }
  float* last = out + 4 * std::size_t(w - 1);
  last[0] = row[w - 1], last[1] = row[0], last[2] = below[w - 1], last[3] = below[0];
}

// The table of this ISA's rows.
inline const HeightRows& table() {
  static constexpr HeightRows rows{&add_wave, &finish_waves, &quantise, &decode, &box, &normals, &box_normals,
                                   &footprints};
  return rows;
}

}  // namespace qdmr::QDMR_ISA_NAMESPACE::height_row_code
