#pragma once
// What the SIMD traversals (view rays, light rays) share: the iteration budget of a capped loop and the range
// texel coordinates are clamped to before they become indices.
#include "core/simd.hpp"

namespace qdmr::QDMR_ISA_NAMESPACE {

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

// Moves the `descend` lanes from cell (cx, cy) of `level` to the child holding the ray x(t) = x0 + dx t,
// y(t) = y0 + dy t (texel units) at t: t is compared with where the ray crosses the parent's mid lines, computed
// exactly as wall crossings are, so a ray standing on a wall is never put back into the cell it just left.
inline void descend_to_child(const simd::IntMask& descend, const simd::Float& t, const simd::Float& x0,
                             const simd::Float& y0, const simd::Float& dx, const simd::Float& dy, simd::Int& level,
                             simd::Int& cx, simd::Int& cy) {
  using simd::Float;
  using simd::Int;
  const Int child_level = xsimd::max(level - Int(1), Int(0));
  const Float child_cell = xsimd::to_float(Int(1) << child_level);
  const Float mid_x = xsimd::to_float(cx * Int(2) + Int(1)) * child_cell;
  const Float mid_y = xsimd::to_float(cy * Int(2) + Int(1)) * child_cell;
  const Float zero(0.0f);
  const simd::Mask high_x = ((dx > zero) & (t >= (mid_x - x0) / dx)) | ((dx < zero) & (t < (mid_x - x0) / dx)) |
                            ((dx == zero) & (x0 >= mid_x));
  const simd::Mask high_y = ((dy > zero) & (t >= (mid_y - y0) / dy)) | ((dy < zero) & (t < (mid_y - y0) / dy)) |
                            ((dy == zero) & (y0 >= mid_y));
  cx = xsimd::select(descend, cx * Int(2) + xsimd::select(simd::int_mask(high_x), Int(1), Int(0)), cx);
  cy = xsimd::select(descend, cy * Int(2) + xsimd::select(simd::int_mask(high_y), Int(1), Int(0)), cy);
  level = xsimd::select(descend, child_level, level);
}

}  // namespace qdmr::QDMR_ISA_NAMESPACE
