// Typed mip chains: quantisation of level 0, and Box / BoxNormal / Max / Min reductions level by level.
// Max and Min are exact in the stored values and run on SIMD vectors (AVX2 or SSE4.1, whichever the build
// targets); a scalar tail computes the same operations in the same order, so every build gives the same bits.
#include "qdmr/texture/mip_texture.hpp"

#include <tbb/blocked_range.h>
#include <tbb/parallel_for.h>

#if defined(__AVX2__) || defined(__SSE4_1__)
#include <immintrin.h>
#endif

#include <algorithm>
#include <array>
#include <cmath>
#include <cstring>
#include <string>
#include <type_traits>

#include "qdmr/core/error.hpp"
#include "qdmr/core/limits.hpp"
#include "texture/internal.hpp"

namespace qdmr {
namespace {

constexpr std::size_t kLevelAlignment = 64;  // a cache line

struct Tables {
  std::array<float, 256> unorm8{};   // k / 255
  std::array<float, 256> srgb8{};    // the exact sRGB decode of k / 255, as texture.cpp decodes 8-bit albedo
  std::array<double, 255> srgb_mid{};  // decode((k + 0.5) / 255): linear values at or above it encode to k + 1
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
    return r;
  }();
  return t;
}

// Round to nearest (ties up) after clamping to [0, 1]; NaN gives 0. v * 255 and v * 65535 are exact in double.
std::uint8_t quantise_unorm8(float v) {
  if (!(v > 0.0f)) return 0;
  if (v >= 1.0f) return 255;
  return std::uint8_t(std::floor(double(v) * 255.0 + 0.5));
}

std::uint16_t quantise_unorm16(float v) {
  if (!(v > 0.0f)) return 0;
  if (v >= 1.0f) return 65535;
  return std::uint16_t(std::floor(double(v) * 65535.0 + 0.5));
}

// round(encode(v) * 255) with the exact curve, found by comparing v with the decoded midpoints between codes:
// no pow on the value itself, so the result does not depend on the machine's libm.
std::uint8_t encode_srgb8(float v) {
  if (!(v > 0.0f)) return 0;
  if (v >= 1.0f) return 255;
  const auto& mid = tables().srgb_mid;
  return std::uint8_t(std::upper_bound(mid.begin(), mid.end(), double(v)) - mid.begin());
}

template <class T>
T load(const std::uint8_t* p, std::size_t index) {
  T v;
  std::memcpy(&v, p + index * sizeof(T), sizeof(T));
  return v;
}

template <class T>
void store(std::uint8_t* p, std::size_t index, T v) {
  std::memcpy(p + index * sizeof(T), &v, sizeof(T));
}

// Channel c of a texel as float and back, for the format (and sRGB flag) of a texture.
struct Codec {
  TexelFormat format;
  bool srgb;

  float decode(const std::uint8_t* texel, int c) const {
    switch (format) {
      case TexelFormat::R16: return float(load<std::uint16_t>(texel, 0)) / 65535.0f;
      case TexelFormat::R32F: return load<float>(texel, 0);
      default: return (srgb && c < 3 ? tables().srgb8 : tables().unorm8)[texel[c]];
    }
  }

  void encode(std::uint8_t* texel, int c, float v) const {
    switch (format) {
      case TexelFormat::R16: store<std::uint16_t>(texel, 0, quantise_unorm16(v)); break;
      case TexelFormat::R32F: store<float>(texel, 0, v); break;
      default: texel[c] = srgb && c < 3 ? encode_srgb8(v) : quantise_unorm8(v); break;
    }
  }
};

struct Taps {
  int first;
  int count;  // 1 (an axis of size 1), 2, or 3 (last texel of an odd axis)
};

Taps taps(int i, int in_size, int out_size) {
  if (in_size == 1) return {0, 1};
  return {2 * i, (i == out_size - 1 && (in_size & 1)) ? 3 : 2};
}

// f(first_row, end_row) over the rows of a level; in parallel only when the level is big enough to pay for it.
// Each row is computed the same way whatever the split, so results do not depend on the thread count.
template <class F>
void for_rows(int rows, std::size_t row_bytes, F&& f) {
  // Below ~256 KB a level takes a few microseconds: splitting it costs more than it saves (measured).
  constexpr std::size_t kChunkBytes = 32 * 1024;
  if (std::size_t(rows) * row_bytes < 8 * kChunkBytes) {
    f(0, rows);
    return;
  }
  const int grain = int(std::max<std::size_t>(1, kChunkBytes / row_bytes));
  tbb::parallel_for(tbb::blocked_range<int>(0, rows, grain),
                    [&](const tbb::blocked_range<int>& r) { f(r.begin(), r.end()); });
}

// ---- SIMD primitives: the same names on 256-bit (AVX2) or 128-bit (SSE4.1) vectors ----
#if defined(__AVX2__)
#define QDMR_MIP_SIMD 1
using VecI = __m256i;
using VecF = __m256;
constexpr int kVecBytes = 32;
VecI load_i(const std::uint8_t* p) { return _mm256_loadu_si256(reinterpret_cast<const __m256i*>(p)); }
void store_i(std::uint8_t* p, VecI v) { _mm256_storeu_si256(reinterpret_cast<__m256i*>(p), v); }
VecF load_f(const std::uint8_t* p) { return _mm256_loadu_ps(reinterpret_cast<const float*>(p)); }
void store_f(std::uint8_t* p, VecF v) { _mm256_storeu_ps(reinterpret_cast<float*>(p), v); }
VecI max_u8(VecI a, VecI b) { return _mm256_max_epu8(a, b); }
VecI min_u8(VecI a, VecI b) { return _mm256_min_epu8(a, b); }
VecI max_u16(VecI a, VecI b) { return _mm256_max_epu16(a, b); }
VecI min_u16(VecI a, VecI b) { return _mm256_min_epu16(a, b); }
VecF max_f(VecF a, VecF b) { return _mm256_max_ps(a, b); }
VecF min_f(VecF a, VecF b) { return _mm256_min_ps(a, b); }
VecI shift_right_16(VecI v) { return _mm256_srli_epi16(v, 8); }
VecI shift_right_32(VecI v) { return _mm256_srli_epi32(v, 16); }
VecI shift_right_64(VecI v) { return _mm256_srli_epi64(v, 32); }
VecI low_bytes_mask() { return _mm256_set1_epi16(0x00FF); }
VecI low_words_mask() { return _mm256_set1_epi32(0xFFFF); }
VecI and_i(VecI a, VecI b) { return _mm256_and_si256(a, b); }
// pack and shuffle work within 128-bit lanes: put the 64-bit quarters back in order.
VecI lane_order(VecI v) { return _mm256_permute4x64_epi64(v, 0xD8); }
VecF lane_order(VecF v) { return _mm256_castpd_ps(_mm256_permute4x64_pd(_mm256_castps_pd(v), 0xD8)); }
VecI pack_u16(VecI a, VecI b) { return _mm256_packus_epi16(a, b); }
VecI pack_u32(VecI a, VecI b) { return _mm256_packus_epi32(a, b); }
VecF even_f(VecF a, VecF b) { return _mm256_shuffle_ps(a, b, 0x88); }
VecF odd_f(VecF a, VecF b) { return _mm256_shuffle_ps(a, b, 0xDD); }
VecF as_f(VecI v) { return _mm256_castsi256_ps(v); }
VecI as_i(VecF v) { return _mm256_castps_si256(v); }
#elif defined(__SSE4_1__)
#define QDMR_MIP_SIMD 1
using VecI = __m128i;
using VecF = __m128;
constexpr int kVecBytes = 16;
VecI load_i(const std::uint8_t* p) { return _mm_loadu_si128(reinterpret_cast<const __m128i*>(p)); }
void store_i(std::uint8_t* p, VecI v) { _mm_storeu_si128(reinterpret_cast<__m128i*>(p), v); }
VecF load_f(const std::uint8_t* p) { return _mm_loadu_ps(reinterpret_cast<const float*>(p)); }
void store_f(std::uint8_t* p, VecF v) { _mm_storeu_ps(reinterpret_cast<float*>(p), v); }
VecI max_u8(VecI a, VecI b) { return _mm_max_epu8(a, b); }
VecI min_u8(VecI a, VecI b) { return _mm_min_epu8(a, b); }
VecI max_u16(VecI a, VecI b) { return _mm_max_epu16(a, b); }
VecI min_u16(VecI a, VecI b) { return _mm_min_epu16(a, b); }
VecF max_f(VecF a, VecF b) { return _mm_max_ps(a, b); }
VecF min_f(VecF a, VecF b) { return _mm_min_ps(a, b); }
VecI shift_right_16(VecI v) { return _mm_srli_epi16(v, 8); }
VecI shift_right_32(VecI v) { return _mm_srli_epi32(v, 16); }
VecI shift_right_64(VecI v) { return _mm_srli_epi64(v, 32); }
VecI low_bytes_mask() { return _mm_set1_epi16(0x00FF); }
VecI low_words_mask() { return _mm_set1_epi32(0xFFFF); }
VecI and_i(VecI a, VecI b) { return _mm_and_si128(a, b); }
VecI lane_order(VecI v) { return v; }
VecF lane_order(VecF v) { return v; }
VecI pack_u16(VecI a, VecI b) { return _mm_packus_epi16(a, b); }
VecI pack_u32(VecI a, VecI b) { return _mm_packus_epi32(a, b); }
VecF even_f(VecF a, VecF b) { return _mm_shuffle_ps(a, b, 0x88); }
VecF odd_f(VecF a, VecF b) { return _mm_shuffle_ps(a, b, 0xDD); }
VecF as_f(VecI v) { return _mm_castsi128_ps(v); }
VecI as_i(VecF v) { return _mm_castps_si128(v); }
#endif

// The scalar forms return what MAXPS / MINPS return (the second operand unless the first wins), so the
// vector body and the scalar tail agree even on NaN and signed zeros.
struct MaxOp {
  template <class T>
  static T scalar(T a, T b) { return a > b ? a : b; }
#ifdef QDMR_MIP_SIMD
  static VecI u8(VecI a, VecI b) { return max_u8(a, b); }
  static VecI u16(VecI a, VecI b) { return max_u16(a, b); }
  static VecF f32(VecF a, VecF b) { return max_f(a, b); }
#endif
};

struct MinOp {
  template <class T>
  static T scalar(T a, T b) { return a < b ? a : b; }
#ifdef QDMR_MIP_SIMD
  static VecI u8(VecI a, VecI b) { return min_u8(a, b); }
  static VecI u16(VecI a, VecI b) { return min_u16(a, b); }
  static VecF f32(VecF a, VecF b) { return min_f(a, b); }
#endif
};

// out texel i = op over texels 2i and 2i+1 of rows a and b (vertical first, then horizontal), for the first
// pairs that fill whole vectors; returns how many were done. T is the channel type, C the channel count.
template <class Op, class T, int C>
int reduce_pairs_simd([[maybe_unused]] const std::uint8_t* a, [[maybe_unused]] const std::uint8_t* b,
                      [[maybe_unused]] std::uint8_t* out, [[maybe_unused]] int pairs) {
#ifdef QDMR_MIP_SIMD
  constexpr int kTexelBytes = C * int(sizeof(T));
  constexpr int kStep = kVecBytes / kTexelBytes;  // output texels per iteration
  int i = 0;
  for (; i + kStep <= pairs; i += kStep) {
    const std::uint8_t* pa = a + std::size_t(i) * 2 * kTexelBytes;
    const std::uint8_t* pb = b + std::size_t(i) * 2 * kTexelBytes;
    std::uint8_t* po = out + std::size_t(i) * kTexelBytes;
    if constexpr (std::is_same_v<T, float>) {
      const VecF v0 = Op::f32(load_f(pa), load_f(pb));
      const VecF v1 = Op::f32(load_f(pa + kVecBytes), load_f(pb + kVecBytes));
      store_f(po, lane_order(Op::f32(even_f(v0, v1), odd_f(v0, v1))));
    } else {
      const auto op = [](VecI x, VecI y) {
        if constexpr (sizeof(T) == 1) return Op::u8(x, y);
        else return Op::u16(x, y);
      };
      const VecI v0 = op(load_i(pa), load_i(pb));
      const VecI v1 = op(load_i(pa + kVecBytes), load_i(pb + kVecBytes));
      // Bring texel 2i+1 onto texel 2i, combine, then keep the low texel of each pair.
      if constexpr (kTexelBytes == 1) {
        const VecI h0 = and_i(op(v0, shift_right_16(v0)), low_bytes_mask());
        const VecI h1 = and_i(op(v1, shift_right_16(v1)), low_bytes_mask());
        store_i(po, lane_order(pack_u16(h0, h1)));
      } else if constexpr (kTexelBytes == 2) {
        const VecI h0 = and_i(op(v0, shift_right_32(v0)), low_words_mask());
        const VecI h1 = and_i(op(v1, shift_right_32(v1)), low_words_mask());
        store_i(po, lane_order(pack_u32(h0, h1)));
      } else {
        static_assert(kTexelBytes == 4);
        const VecI h0 = op(v0, shift_right_64(v0)), h1 = op(v1, shift_right_64(v1));
        store_i(po, as_i(lane_order(even_f(as_f(h0), as_f(h1)))));
      }
    }
  }
  return i;
#else
  return 0;
#endif
}

// One output row from input rows a and b (b == a for a single row) of in_width texels.
template <class Op, class T, int C>
void reduce_two_rows(const std::uint8_t* a, const std::uint8_t* b, int in_width, std::uint8_t* out, int out_width) {
  if (in_width == 1) {
    for (int c = 0; c < C; ++c) store<T>(out, c, Op::scalar(load<T>(a, c), load<T>(b, c)));
    return;
  }
  for (int i = reduce_pairs_simd<Op, T, C>(a, b, out, out_width); i < out_width; ++i)
    for (int c = 0; c < C; ++c) {
      const std::size_t left = std::size_t(2 * i) * C + c, right = left + C;
      const T l = Op::scalar(load<T>(a, left), load<T>(b, left));
      const T r = Op::scalar(load<T>(a, right), load<T>(b, right));
      store<T>(out, std::size_t(i) * C + c, Op::scalar(l, r));
    }
  if (in_width & 1)  // the last texel also covers the leftover column
    for (int c = 0; c < C; ++c) {
      const std::size_t last = std::size_t(in_width - 1) * C + c, o = std::size_t(out_width - 1) * C + c;
      store<T>(out, o, Op::scalar(load<T>(out, o), Op::scalar(load<T>(a, last), load<T>(b, last))));
    }
}

template <class Op, class T, int C>
void reduce_extremum(const std::uint8_t* in, int in_w, int in_h, std::uint8_t* out, int out_w, int out_h) {
  const std::size_t in_row = std::size_t(in_w) * C * sizeof(T), out_row = std::size_t(out_w) * C * sizeof(T);
  for_rows(out_h, out_row, [&](int y0, int y1) {
    for (int y = y0; y < y1; ++y) {
      const Taps ty = taps(y, in_h, out_h);
      const std::uint8_t* r0 = in + std::size_t(ty.first) * in_row;
      std::uint8_t* o = out + std::size_t(y) * out_row;
      reduce_two_rows<Op, T, C>(r0, ty.count > 1 ? r0 + in_row : r0, in_w, o, out_w);
      if (ty.count == 3) {  // the leftover row of an odd height: once per level, scalar
        const std::uint8_t* r2 = r0 + 2 * in_row;
        for (int x = 0; x < out_w; ++x) {
          const Taps tx = taps(x, in_w, out_w);
          for (int c = 0; c < C; ++c) {
            T v = load<T>(r2, std::size_t(tx.first) * C + c);
            for (int i = 1; i < tx.count; ++i) v = Op::scalar(v, load<T>(r2, std::size_t(tx.first + i) * C + c));
            const std::size_t oi = std::size_t(x) * C + c;
            store<T>(o, oi, Op::scalar(load<T>(o, oi), v));
          }
        }
      }
    }
  });
}

template <class Op>
void reduce_extremum(TexelFormat format, const std::uint8_t* in, int in_w, int in_h, std::uint8_t* out, int out_w,
                     int out_h) {
  switch (format) {
    case TexelFormat::R8: reduce_extremum<Op, std::uint8_t, 1>(in, in_w, in_h, out, out_w, out_h); break;
    case TexelFormat::RG8: reduce_extremum<Op, std::uint8_t, 2>(in, in_w, in_h, out, out_w, out_h); break;
    case TexelFormat::RGBA8: reduce_extremum<Op, std::uint8_t, 4>(in, in_w, in_h, out, out_w, out_h); break;
    case TexelFormat::R16: reduce_extremum<Op, std::uint16_t, 1>(in, in_w, in_h, out, out_w, out_h); break;
    case TexelFormat::R32F: reduce_extremum<Op, float, 1>(in, in_w, in_h, out, out_w, out_h); break;
  }
}

// Box and BoxNormal: sums of decoded values in tap order (rows, then columns), re-encoded per level.
void reduce_box(const Texture& t, int level, bool normal, std::uint8_t* out_base) {
  const TextureLevel& in = t.levels[std::size_t(level)];
  const TextureLevel& out = t.levels[std::size_t(level) + 1];
  const Codec codec{t.format, t.srgb};
  const int channels = t.channels(), texel_bytes = bytes_per_texel(t.format);
  const std::uint8_t* in_base = t.storage.data() + in.offset;
  // A texel costs about 8x more here than in a Max build: weight the row size accordingly.
  for_rows(out.height, std::size_t(out.width) * texel_bytes * 8, [&](int y0, int y1) {
    for (int y = y0; y < y1; ++y) {
      const Taps ty = taps(y, in.height, out.height);
      for (int x = 0; x < out.width; ++x) {
        const Taps tx = taps(x, in.width, out.width);
        float sum[4] = {0, 0, 0, 0};
        for (int j = ty.first; j < ty.first + ty.count; ++j)
          for (int i = tx.first; i < tx.first + tx.count; ++i) {
            const std::uint8_t* texel = in_base + (std::size_t(j) * in.width + i) * texel_bytes;
            for (int c = 0; c < channels; ++c) {
              const float v = codec.decode(texel, c);
              sum[c] += normal && c < 3 ? 2.0f * v - 1.0f : v;
            }
          }
        std::uint8_t* texel = out_base + (std::size_t(y) * out.width + x) * texel_bytes;
        const float count = float(tx.count * ty.count);
        for (int c = normal ? 3 : 0; c < channels; ++c) codec.encode(texel, c, sum[c] / count);
        if (normal) {
          const double len2 = double(sum[0]) * sum[0] + double(sum[1]) * sum[1] + double(sum[2]) * sum[2];
          const double inv = len2 > 0.0 ? 1.0 / std::sqrt(len2) : 0.0;
          const float n[3] = {len2 > 0.0 ? float(sum[0] * inv) : 0.0f, len2 > 0.0 ? float(sum[1] * inv) : 0.0f,
                              len2 > 0.0 ? float(sum[2] * inv) : 1.0f};
          for (int c = 0; c < 3; ++c) codec.encode(texel, c, 0.5f + 0.5f * n[c]);
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
  return Codec{format, srgb}.decode(texel_address(level, x, y), c);
}

Image Texture::level_image(int level) const {
  if (level < 0 || level >= level_count()) throw Error("texture", "level_image: level out of range");
  const TextureLevel& l = levels[std::size_t(level)];
  const Codec codec{format, srgb};
  Image image(l.width, l.height, channels());
  for (int y = 0; y < l.height; ++y)
    for (int x = 0; x < l.width; ++x)
      for (int c = 0; c < image.channels; ++c) image.at(x, y, c) = codec.decode(texel_address(level, x, y), c);
  return image;
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
  std::size_t offset = 0;
  for (int w = width, h = height;; w = std::max(1, w / 2), h = std::max(1, h / 2)) {
    offset = (offset + kLevelAlignment - 1) / kLevelAlignment * kLevelAlignment;
    t.levels.push_back({w, h, offset});
    offset += std::size_t(w) * std::size_t(h) * std::size_t(bytes_per_texel(format));
    if (w == 1 && h == 1) break;
  }
  const std::size_t total = offset + Texture::kTailPadding;
  if (total >= (std::size_t(1) << 31)) throw Error("texture", "the mip chain does not fit 32-bit byte offsets");
  t.storage.assign(total, 0);
  return t;
}

Texture make_mip_texture(const Image& level0, TexelFormat format, bool srgb, MipReduce reduce) {
  if (level0.channels < 1 || level0.channels > 4)
    throw Error("texture", "level 0 must have 1 to 4 channels, not " + std::to_string(level0.channels));
  Texture t = allocate_texture(level0.width, level0.height, format, srgb);
  const Codec codec{format, srgb};
  const int channels = t.channels(), texel_bytes = bytes_per_texel(format);
  for_rows(level0.height, std::size_t(level0.width) * texel_bytes * 8, [&](int y0, int y1) {
    for (int y = y0; y < y1; ++y)
      for (int x = 0; x < level0.width; ++x) {
        std::uint8_t* texel = t.storage.data() + (std::size_t(y) * level0.width + x) * texel_bytes;
        for (int c = 0; c < channels; ++c)
          codec.encode(texel, c, c < level0.channels ? level0.at(x, y, c) : c == 3 ? 1.0f : 0.0f);
      }
  });
  build_mip_levels(t, reduce);
  return t;
}

void build_mip_levels(Texture& texture, MipReduce reduce) {
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
      case MipReduce::Box: reduce_box(texture, k, false, out_base); break;
      case MipReduce::BoxNormal: reduce_box(texture, k, true, out_base); break;
      case MipReduce::Max:
        reduce_extremum<MaxOp>(texture.format, in_base, in.width, in.height, out_base, out.width, out.height);
        break;
      case MipReduce::Min:
        reduce_extremum<MinOp>(texture.format, in_base, in.width, in.height, out_base, out.width, out.height);
        break;
    }
  }
}

}  // namespace qdmr
