#pragma once
// What the SIMD traversals (view rays, light rays) share: the iteration budget of a capped loop and the range
// texel coordinates are clamped to before they become indices.
#include "core/simd.hpp"

namespace qdmr {

// Texel coordinates are clamped to +-2^22 before they become indices: beyond that fp32 positions are
// meaningless anyway, and indices (plus at most 2^20 capped steps) stay exact in fp32.
inline constexpr float kMaxTexelCoordinate = 4194304.0f;

// The iteration budget of a capped SIMD loop, as a GPU wave runs it: a lane stops when it is done or when
// its own count reaches the cap; the loop ends when no lane is left.
struct CappedLoop {
  simd::Int cap;
  simd::Int done = simd::Int(0);

  // Drops the lanes that used up their budget and counts one more iteration for the others.
  bool next(simd::Mask& active) {
    const simd::IntMask running = simd::int_mask(active) & (done < cap);
    active = simd::float_mask(running);
    if (!xsimd::any(active)) return false;
    done += xsimd::select(running, simd::Int(1), simd::Int(0));
    return true;
  }
  simd::Float iterations() const { return xsimd::to_float(done); }
};

}  // namespace qdmr
