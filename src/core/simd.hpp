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

// Bit i set = lane i active.
inline std::uint32_t to_bits(const Mask& m) {
  alignas(64) bool lanes[kLanes];
  m.store_aligned(lanes);
  std::uint32_t bits = 0;
  for (int i = 0; i < kLanes; ++i) bits |= std::uint32_t(lanes[i]) << i;
  return bits;
}

inline Mask from_bits(std::uint32_t bits) {
  alignas(64) float lanes[kLanes];
  for (int i = 0; i < kLanes; ++i) lanes[i] = ((bits >> i) & 1u) ? 1.0f : 0.0f;
  return Float::load_aligned(lanes) != Float(0.0f);
}

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

// Coarse derivatives (what GPUs do): per quad, d/dx = top-right - top-left, d/dy = bottom-left - top-left,
// the same value broadcast to the quad's four lanes.
inline Float quad_ddx(const Float& v) {
  alignas(64) float a[kLanes];
  v.store_aligned(a);
  for (int q = 0; q < kQuadsPerBatch; ++q) {
    const float d = a[4 * q + kQuadTopRight] - a[4 * q + kQuadTopLeft];
    for (int i = 0; i < 4; ++i) a[4 * q + i] = d;
  }
  return Float::load_aligned(a);
}

inline Float quad_ddy(const Float& v) {
  alignas(64) float a[kLanes];
  v.store_aligned(a);
  for (int q = 0; q < kQuadsPerBatch; ++q) {
    const float d = a[4 * q + kQuadBottomLeft] - a[4 * q + kQuadTopLeft];
    for (int i = 0; i < 4; ++i) a[4 * q + i] = d;
  }
  return Float::load_aligned(a);
}

// Fine derivatives (per pixel): d/dx from the pixel's own row of the quad, d/dy from its own column.
inline Float pixel_ddx(const Float& v) {
  alignas(64) float a[kLanes], d[kLanes];
  v.store_aligned(a);
  for (int q = 0; q < kQuadsPerBatch; ++q) {
    const float top = a[4 * q + kQuadTopRight] - a[4 * q + kQuadTopLeft];
    const float bottom = a[4 * q + kQuadBottomRight] - a[4 * q + kQuadBottomLeft];
    d[4 * q + kQuadTopLeft] = d[4 * q + kQuadTopRight] = top;
    d[4 * q + kQuadBottomLeft] = d[4 * q + kQuadBottomRight] = bottom;
  }
  return Float::load_aligned(d);
}

inline Float pixel_ddy(const Float& v) {
  alignas(64) float a[kLanes], d[kLanes];
  v.store_aligned(a);
  for (int q = 0; q < kQuadsPerBatch; ++q) {
    const float left = a[4 * q + kQuadBottomLeft] - a[4 * q + kQuadTopLeft];
    const float right = a[4 * q + kQuadBottomRight] - a[4 * q + kQuadTopRight];
    d[4 * q + kQuadTopLeft] = d[4 * q + kQuadBottomLeft] = left;
    d[4 * q + kQuadTopRight] = d[4 * q + kQuadBottomRight] = right;
  }
  return Float::load_aligned(d);
}

}  // namespace qdmr::QDMR_ISA_NAMESPACE::simd
