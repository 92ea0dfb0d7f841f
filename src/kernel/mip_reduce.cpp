// A kernel's max/min reducer (Kernel::mip_extremum): the scalar reduction of texture/mip_reduce.hpp around a loop
// over whole vectors of texel pairs, in xsimd at the kernel's width.
#include <cstddef>
#include <cstdint>
#include <type_traits>

#include <immintrin.h>

#include "core/simd.hpp"
#include "kernel/kernel_calls.hpp"
#include "kernel/preparation.hpp"
#include "texture/mip_reduce.hpp"

namespace qdmr::QDMR_ISA_NAMESPACE::mip {
namespace {

template <class T>
using Batch = xsimd::batch<T, simd::Arch>;
constexpr int kVecBytes = int(Batch<std::uint8_t>::size);

template <class To, class From>
Batch<To> as(const Batch<From>& v) {
  return xsimd::bitwise_cast<Batch<To>>(v);
}

template <class Op, class T>
Batch<T> op(const Batch<T>& a, const Batch<T>& b) {
  if constexpr (Op::kMax)
    return xsimd::max(a, b);
  else
    return xsimd::min(a, b);
}

// The even (or odd) 32-bit lanes of a, then those of b.
template <int First, class T>
Batch<T> every_other_lane(const Batch<T>& a, const Batch<T>& b) {
  static_assert(sizeof(T) == 4);
  struct Index {  // lanes First, First + 2, ... in each half
    static constexpr std::uint32_t get(std::size_t i, std::size_t n) { return std::uint32_t((2 * i + First) % n); }
  };
  struct LowHalf {
    static constexpr bool get(std::size_t i, std::size_t n) { return i < n / 2; }
  };
  const auto index = xsimd::make_batch_constant<Batch<std::uint32_t>, Index>();
  return xsimd::select(xsimd::make_batch_bool_constant<Batch<T>, LowHalf>(), xsimd::swizzle(a, index),
                       xsimd::swizzle(b, index));
}

// The lanes of a, then those of b, each cut to its low half (the values fit in it).
template <class Wide>
Batch<std::uint8_t> narrow(const Batch<Wide>& a, const Batch<Wide>& b) {
  static_assert(std::is_same_v<Wide, std::uint16_t> || std::is_same_v<Wide, std::uint32_t>);
  constexpr bool k16 = std::is_same_v<Wide, std::uint16_t>;
  // Raw intrinsics: xsimd 8 has no narrowing conversion of integer lanes. The packs work per 128-bit block (a's
  // and b's halves alternate by 64-bit quarters); the swizzle puts the quarters back in order.
#if defined(__AVX512BW__)
  const Batch<std::uint64_t> packed(k16 ? _mm512_packus_epi16(a, b) : _mm512_packus_epi32(a, b));
#elif defined(__AVX2__)
  const Batch<std::uint64_t> packed(k16 ? _mm256_packus_epi16(a, b) : _mm256_packus_epi32(a, b));
#else
  const Batch<std::uint64_t> packed(k16 ? _mm_packus_epi16(a, b) : _mm_packus_epi32(a, b));
#endif
  if constexpr (Batch<std::uint64_t>::size == 2) return as<std::uint8_t>(packed);  // one block: in order
  struct Quarters {  // the even quarters (a's), then the odd ones (b's)
    static constexpr std::uint64_t get(std::size_t i, std::size_t n) { return 2 * i % n + (2 * i >= n ? 1 : 0); }
  };
  return as<std::uint8_t>(xsimd::swizzle(packed, xsimd::make_batch_constant<Batch<std::uint64_t>, Quarters>()));
}

// out texel i = op over texels 2i and 2i+1 of rows a and b (vertical first, then horizontal), for the first
// pairs that fill whole vectors; returns how many were done. T is the channel type, C the channel count.
struct Vectors {
  template <class Op, class T, int C>
  static int pairs(const std::uint8_t* a, const std::uint8_t* b, std::uint8_t* out, int pairs) {
    constexpr int kTexelBytes = C * int(sizeof(T));
    constexpr int kStep = kVecBytes / kTexelBytes;  // output texels per iteration
    const auto load = [](const std::uint8_t* p) { return Batch<T>::load_unaligned(reinterpret_cast<const T*>(p)); };
    int i = 0;
    for (; i + kStep <= pairs; i += kStep) {
      const std::uint8_t* pa = a + std::size_t(i) * 2 * kTexelBytes;
      const std::uint8_t* pb = b + std::size_t(i) * 2 * kTexelBytes;
      std::uint8_t* po = out + std::size_t(i) * kTexelBytes;
      const Batch<T> v0 = op<Op>(load(pa), load(pb));
      const Batch<T> v1 = op<Op>(load(pa + kVecBytes), load(pb + kVecBytes));
      if constexpr (std::is_same_v<T, float>) {
        op<Op>(every_other_lane<0>(v0, v1), every_other_lane<1>(v0, v1)).store_unaligned(reinterpret_cast<float*>(po));
      } else if constexpr (kTexelBytes == 4) {
        // Bring texel 2i+1 onto texel 2i, combine, then keep the even texels.
        const auto h0 = as<std::uint32_t>(op<Op>(v0, as<T>(as<std::uint64_t>(v0) >> 32)));
        const auto h1 = as<std::uint32_t>(op<Op>(v1, as<T>(as<std::uint64_t>(v1) >> 32)));
        every_other_lane<0>(h0, h1).store_unaligned(reinterpret_cast<std::uint32_t*>(po));
      } else {
        // Bring texel 2i+1 onto texel 2i, combine, then keep the low texel of each pair.
        using Pair = std::conditional_t<kTexelBytes == 1, std::uint16_t, std::uint32_t>;
        const Batch<Pair> low(Pair(kTexelBytes == 1 ? 0xFFu : 0xFFFFu));
        const auto h0 = as<Pair>(op<Op>(v0, as<T>(as<Pair>(v0) >> (8 * kTexelBytes)))) & low;
        const auto h1 = as<Pair>(op<Op>(v1, as<T>(as<Pair>(v1) >> (8 * kTexelBytes)))) & low;
        narrow(h0, h1).store_unaligned(po);
      }
    }
    return i;
  }
};

}  // namespace
}  // namespace qdmr::QDMR_ISA_NAMESPACE::mip

namespace qdmr::QDMR_ISA_NAMESPACE {

void mip_extremum(bool max, TexelFormat format, const std::uint8_t* in, int in_w, int in_h, std::uint8_t* out,
                  int out_w, int out_h) {
  kernel_calls.mip_levels.fetch_add(1, std::memory_order_relaxed);
  mip::extremum<mip::Vectors>(max, format, in, in_w, in_h, out, out_w, out_h);
}

}  // namespace qdmr::QDMR_ISA_NAMESPACE
