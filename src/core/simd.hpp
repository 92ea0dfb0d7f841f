#pragma once
// SIMD types of this build. Private to src/: the architecture is fixed by the build flags (QDMR_SIMD),
// so these types must never appear in a public header.
#include <cstdint>
#include <cstring>
#include <type_traits>

#include <xsimd/xsimd.hpp>

#include "core/isa_namespace.hpp"

namespace qdmr::QDMR_ISA_NAMESPACE::simd {

// The build flags give sse4_2, avx2 or avx512bw (4, 8 or 16 lanes), never fma3<...>, whose fma and math fuse
// (every kernel must round alike): -mno-fma for SSE4.2 and AVX2, and with AVX-512 avx512bw ranks above it.
using Arch = xsimd::default_arch;
static_assert(!std::is_same_v<Arch, xsimd::fma3<xsimd::sse4_2>> && !std::is_same_v<Arch, xsimd::fma3<xsimd::avx2>>,
              "a kernel's xsimd architecture must not fuse multiply-adds");
using Float = xsimd::batch<float, Arch>;
using Int = xsimd::batch<std::int32_t, Arch>;
using UInt = xsimd::batch<std::uint32_t, Arch>;
using Mask = xsimd::batch_bool<float, Arch>;
using IntMask = xsimd::batch_bool<std::int32_t, Arch>;

// A mask's complement is written ~m, never !m: xsimd 8's operator! compares with a batch_bool(false) built by a
// recursive constructor, which GCC refused to inline in the displacement kernel's AVX-512 build (24 calls per QDM
// step pair); ~ is one instruction in every kernel.

inline constexpr int kLanes = static_cast<int>(Float::size);
static_assert(kLanes == 4 || kLanes == 8 || kLanes == 16,
              "qdmr batches hold one (SSE4.2), two (AVX2) or four (AVX-512) 2x2 quads");
inline constexpr int kQuadsPerBatch = kLanes / 4;

// Lane layout inside one quad: 0 1 / 2 3 (x to the right, y down). Quad q occupies lanes 4q..4q+3.
inline constexpr int kQuadTopLeft = 0, kQuadTopRight = 1, kQuadBottomLeft = 2, kQuadBottomRight = 3;

// Mask conversions between float and integer lanes (xsimd 8 has no batch_bool_cast): a reinterpretation of the
// register, all-ones or all-zero lanes with SSE and AVX2, the same 16-bit mask with AVX-512. And a mask as 0/1.
template <class To, class From>
To reinterpret_mask(const From& m) {
  using ToRegister = typename To::register_type;
  using FromRegister = typename From::register_type;
  static_assert(sizeof(ToRegister) == sizeof(FromRegister));
  const FromRegister from = m;
  ToRegister to;
  std::memcpy(&to, &from, sizeof to);  // a register move (std::bit_cast of vector types trips -Wignored-attributes)
  return To(to);
}
inline IntMask int_mask(const Mask& m) { return reinterpret_mask<IntMask>(m); }
inline Mask float_mask(const IntMask& m) { return reinterpret_mask<Mask>(m); }
inline Float count(const Mask& m) { return xsimd::select(m, Float(1.0f), Float(0.0f)); }

// a & ~b. SSE and AVX2 do it in one andnot instruction, but GCC builds their ~ as an xor with all-ones and does not
// fold it into the and; AVX-512's masks are k registers (kandn). xsimd 8's bitwise_andnot is not used: it takes its
// operands in a different order on AVX2 (~a & b) and AVX-512 (a & ~b).
inline Mask and_not(const Mask& a, const Mask& b) {
#if defined(__AVX512F__)
  return a & ~b;
#elif defined(__AVX__)
  return Mask(_mm256_andnot_ps(static_cast<__m256>(b), static_cast<__m256>(a)));
#else
  return Mask(_mm_andnot_ps(static_cast<__m128>(b), static_cast<__m128>(a)));
#endif
}
inline IntMask and_not(const IntMask& a, const IntMask& b) { return int_mask(and_not(float_mask(a), float_mask(b))); }

// n + 1 (plus_one_where) or n - 1 (minus_one_where) in the lanes of m, n elsewhere: with SSE and AVX2 a true lane of
// the mask is the integer -1, so one subtraction or addition; with AVX-512 one masked addition.
inline Int plus_one_where(const Int& n, const IntMask& m) {
#if defined(__AVX512F__)
  return xsimd::select(m, n + Int(1), n);
#else
  return n - Int(typename IntMask::register_type(m));
#endif
}
inline Int minus_one_where(const Int& n, const IntMask& m) {
#if defined(__AVX512F__)
  return xsimd::select(m, n - Int(1), n);
#else
  return n + Int(typename IntMask::register_type(m));
#endif
}

// Bit i set = lane i active: the sign bits by movemask (SSE4.2, AVX2), the mask register itself (AVX-512).
inline std::uint32_t to_bits(const Mask& m) {
#if defined(__AVX512F__)
  return std::uint32_t(static_cast<__mmask16>(m));
#elif defined(__AVX__)
  return std::uint32_t(_mm256_movemask_ps(static_cast<__m256>(m)));
#else
  return std::uint32_t(_mm_movemask_ps(static_cast<__m128>(m)));
#endif
}

// Lane i active where bit i is set: each lane tests its own bit.
inline Mask from_bits(std::uint32_t bits) {
  struct LaneBit {
    static constexpr std::uint32_t get(std::size_t i, std::size_t) { return std::uint32_t(1) << i; }
  };
  const UInt lane_bit = xsimd::make_batch_constant<UInt, LaneBit>();
  const auto set = (UInt(bits) & lane_bit) != UInt(0u);
  return reinterpret_mask<Mask>(set);
}

// Two batches of doubles (half a Float's lanes each; low: lanes 0 .. kLanes / 2 - 1) rounded to floats, as
// float(double) rounds each.
inline Float narrow(const xsimd::batch<double, Arch>& low, const xsimd::batch<double, Arch>& high) {
#if defined(__AVX512F__)
  return _mm512_castpd_ps(_mm512_insertf64x4(_mm512_castps_pd(_mm512_castps256_ps512(_mm512_cvtpd_ps(low))),
                                             _mm256_castps_pd(_mm512_cvtpd_ps(high)), 1));
#elif defined(__AVX__)
  return _mm256_set_m128(_mm256_cvtpd_ps(high), _mm256_cvtpd_ps(low));
#else
  return _mm_movelh_ps(_mm_cvtpd_ps(low), _mm_cvtpd_ps(high));
#endif
}

// Every lane gets the value of corner P[c] of its own quad, c being the lane's corner (0 1 / 2 3): a register
// shuffle.
template <unsigned P0, unsigned P1, unsigned P2, unsigned P3>
inline Float from_quad_corners(const Float& v) {
  struct Corners {
    static constexpr std::uint32_t get(std::size_t i, std::size_t) {
      constexpr unsigned corner[4] = {P0, P1, P2, P3};
      return std::uint32_t(i / 4 * 4 + corner[i % 4]);
    }
  };
  return xsimd::swizzle(v, xsimd::make_batch_constant<UInt, Corners>());
}

// Coarse derivatives (what GPUs do): per quad, d/dx = top-right - top-left, d/dy = bottom-left - top-left,
// the same value broadcast to the quad's four lanes.
inline Float quad_ddx(const Float& v) { return from_quad_corners<1, 1, 1, 1>(v) - from_quad_corners<0, 0, 0, 0>(v); }
inline Float quad_ddy(const Float& v) { return from_quad_corners<2, 2, 2, 2>(v) - from_quad_corners<0, 0, 0, 0>(v); }

// Fine derivatives (per pixel): d/dx from the pixel's own row of the quad, d/dy from its own column.
inline Float pixel_ddx(const Float& v) { return from_quad_corners<1, 1, 3, 3>(v) - from_quad_corners<0, 0, 2, 2>(v); }
inline Float pixel_ddy(const Float& v) { return from_quad_corners<2, 3, 2, 3>(v) - from_quad_corners<0, 1, 0, 1>(v); }

}  // namespace qdmr::QDMR_ISA_NAMESPACE::simd
