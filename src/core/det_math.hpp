#pragma once
// Deterministic log2 / exp2 / pow from IEEE basic operations only: libm and xsimd's transcendental
// functions may pick FMA or non-FMA code per CPU, which would change image bits between machines.
// Every function exists for scalars and for batches, with the same operations in the same order,
// so a lane of a batch gives exactly the scalar result.
#include <bit>
#include <cstdint>

#include "core/simd.hpp"

namespace qdmr::QDMR_ISA_NAMESPACE::detmath {

namespace detail {
inline constexpr float kInvLn2x2 = 2.8853900817779268f;  // 2 / ln 2
inline constexpr float kLn2 = 0.69314718055994531f;
}  // namespace detail

// log2(x) for finite x > 0 (denormals flushed to the smallest normal); x <= 0 gives -126.
// Absolute error below 2e-7 over the normal range.
inline float log2(float x) {
  std::uint32_t bits = std::bit_cast<std::uint32_t>(x > 1.17549435e-38f ? x : 1.17549435e-38f);
  // Mantissa scaled into [sqrt(0.5), sqrt(2)) so the atanh series converges fast.
  const std::uint32_t shifted = bits - 0x3f3504f3u;
  const float e = float(std::int32_t(shifted) >> 23);
  const float m = std::bit_cast<float>((shifted & 0x007fffffu) + 0x3f3504f3u);
  const float s = (m - 1.0f) / (m + 1.0f);
  const float s2 = s * s;
  const float series = s * (1.0f + s2 * (1.0f / 3 + s2 * (1.0f / 5 + s2 * (1.0f / 7 + s2 * (1.0f / 9 + s2 * (1.0f / 11))))));
  return e + series * detail::kInvLn2x2;
}

inline simd::Float log2(const simd::Float& x) {
  const simd::Float clamped = xsimd::max(x, simd::Float(1.17549435e-38f));
  const simd::UInt bits = xsimd::bitwise_cast<simd::UInt>(clamped);
  const simd::UInt shifted = bits - simd::UInt(0x3f3504f3u);
  const simd::Float e = xsimd::batch_cast<float>(xsimd::bitwise_cast<simd::Int>(shifted) >> 23);
  const simd::Float m = xsimd::bitwise_cast<simd::Float>((shifted & simd::UInt(0x007fffffu)) + simd::UInt(0x3f3504f3u));
  const simd::Float one(1.0f);
  const simd::Float s = (m - one) / (m + one);
  const simd::Float s2 = s * s;
  const simd::Float series =
      s * (one + s2 * (simd::Float(1.0f / 3) +
                       s2 * (simd::Float(1.0f / 5) +
                             s2 * (simd::Float(1.0f / 7) + s2 * (simd::Float(1.0f / 9) + s2 * simd::Float(1.0f / 11))))));
  return e + series * simd::Float(detail::kInvLn2x2);
}

// 2^x, clamped to [2^-126, 2^127]; relative error below 3e-7.
inline float exp2(float x) {
  x = x < -126.0f ? -126.0f : (x > 127.0f ? 127.0f : x);
  const float n = float(std::int32_t(x + (x >= 0.0f ? 0.5f : -0.5f)));
  const float f = (x - n) * detail::kLn2;  // |f| <= ln2/2
  const float p =
      1.0f + f * (1.0f + f * (1.0f / 2 + f * (1.0f / 6 + f * (1.0f / 24 + f * (1.0f / 120 + f * (1.0f / 720 + f * (1.0f / 5040)))))));
  const float scale = std::bit_cast<float>(std::uint32_t(std::int32_t(n) + 127) << 23);
  return p * scale;
}

inline simd::Float exp2(const simd::Float& x_in) {
  const simd::Float x = xsimd::min(xsimd::max(x_in, simd::Float(-126.0f)), simd::Float(127.0f));
  const simd::Float half = xsimd::select(x >= simd::Float(0.0f), simd::Float(0.5f), simd::Float(-0.5f));
  const simd::Int ni = xsimd::batch_cast<std::int32_t>(x + half);  // truncates, as the scalar cast does
  const simd::Float n = xsimd::batch_cast<float>(ni);
  const simd::Float f = (x - n) * simd::Float(detail::kLn2);
  const simd::Float one(1.0f);
  const simd::Float p =
      one + f * (one + f * (simd::Float(1.0f / 2) +
                            f * (simd::Float(1.0f / 6) +
                                 f * (simd::Float(1.0f / 24) +
                                      f * (simd::Float(1.0f / 120) + f * (simd::Float(1.0f / 720) + f * simd::Float(1.0f / 5040)))))));
  const simd::Float scale = xsimd::bitwise_cast<simd::Float>((ni + simd::Int(127)) << 23);
  return p * scale;
}

// x^y for x >= 0 (0^y = 0 for y > 0).
inline float pow(float x, float y) { return x > 0.0f ? exp2(y * log2(x)) : 0.0f; }

inline simd::Float pow(const simd::Float& x, const simd::Float& y) {
  return xsimd::select(x > simd::Float(0.0f), exp2(y * log2(x)), simd::Float(0.0f));
}

// The largest exponent pow_uniform() raises to by multiplication: x^1024 takes 10 squarings and 1 product.
inline constexpr float kMaxProductExponent = 1024.0f;

// x^n for a whole n >= 1 by binary exponentiation: x^(2^k) by squaring, multiplied into the result low bit first;
// one template for scalars and batches, so a lane of a batch gives exactly the scalar result. Its n - 1 roundings
// leave x^n within about (n - 1) 2^-24 relative (while the result is a normal float), where exp2(n log2 x) is
// within n * 1.4e-7 + 3e-7.
template <class T>
inline T pow_whole(const T& x, unsigned n) {
  T result(1.0f), square = x;
  for (;;) {
    if (n & 1u) result *= square;
    n >>= 1;
    if (n == 0) return result;
    square *= square;
  }
}

// Whether pow_uniform() raises to y by products: a whole y in [1, kMaxProductExponent].
inline bool is_product_exponent(float y) { return y >= 1.0f && y <= kMaxProductExponent && y == float(int(y)); }

// x^y for x >= 0 with one exponent y for every lane (a material's shininess, say): by pow_whole (a handful of
// products instead of a log2 and an exp2) where is_product_exponent(y), else as pow. 0^y = 0 for y > 0; a lane
// with x NaN or <= 0 gives 0, as pow's.
inline float pow_uniform(float x, float y) {
  if (!is_product_exponent(y)) return pow(x, y);
  return x > 0.0f ? pow_whole(x, unsigned(y)) : 0.0f;
}

inline simd::Float pow_uniform(const simd::Float& x, float y) {
  if (!is_product_exponent(y)) return pow(x, simd::Float(y));
  return xsimd::select(x > simd::Float(0.0f), pow_whole(x, unsigned(y)), simd::Float(0.0f));
}

}  // namespace qdmr::QDMR_ISA_NAMESPACE::detmath
