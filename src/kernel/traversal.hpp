#pragma once
// What the SIMD traversals of the max-quadtree (QDM's view rays, hard shadows' light rays) share: the iteration
// budget of a capped loop, the range texel coordinates are clamped to before they become indices, and the cell
// stepping: descending into a child, the distance to a cell's exit walls, climbing after a crossing.
#include <limits>
#include <type_traits>

#include "core/simd.hpp"
#include "kernel/fetch_trace.hpp"

namespace qdmr::QDMR_ISA_NAMESPACE {

// Texel coordinates are clamped to +-2^22 before they become indices: beyond that fp32 positions are
// meaningless anyway, and indices (plus at most 2^20 capped steps) stay exact in fp32.
inline constexpr float kMaxTexelCoordinate = 4194304.0f;

// FetchLanes where the caller knows no texture-cache recorder listens: nothing to tell it.
struct UnrecordedLanes {
  explicit UnrecordedLanes(FetchPhase) {}
  void narrow(const simd::Mask&) {}
};

// The iteration budget of a capped SIMD loop, as a GPU wave runs it: a lane stops when it is done or when
// its own count reaches the cap; the loop ends when no lane is left. Only the running lanes fetch (`phase`: for
// the texture-cache recorder, unless Recorded is false).
template <bool Recorded = true>
class CappedLoop {
public:
  CappedLoop(const simd::Int& cap, FetchPhase phase) : cap_(cap), lanes_(phase) {}

  // Drops the lanes that used up their budget and counts one more iteration for the others.
  bool next(simd::Mask& active) {
    const simd::IntMask running = simd::int_mask(active) & (done_ < cap_);
    active = simd::float_mask(running);
    if (!xsimd::any(active)) return false;
    done_ = simd::plus_one_where(done_, running);
    lanes_.narrow(active);
    return true;
  }
  simd::Float iterations() const { return xsimd::to_float(done_); }

private:
  simd::Int cap_;
  simd::Int done_ = simd::Int(0);
  std::conditional_t<Recorded, FetchLanes, UnrecordedLanes> lanes_;
};

// Where the ray x(t) = origin + dir t crosses the line x = wall, per lane: in fp32 (wall - origin) * inv_dir, with
// inv_dir = fl(1 / dir) computed once per ray (as GPUs divide: a reciprocal, then a product; dividing at every
// crossing made the canonical QDM frame slower), or with Fp64 (wall - origin) / dir in fp64 rounded once
// to fp32 (the `exact` math mode's QDM walk). Either way the same line always gives the same t, and t is monotonic
// in the wall, which is what the cell stepping needs: a ray standing on a wall is never put back into the cell it
// just left.
// Lanes with dir 0 give an infinity or NaN for the caller to select away.
template <bool Fp64>
inline simd::Float crossing(const simd::Float& wall, const simd::Float& origin, const simd::Float& dir,
                            const simd::Float& inv_dir) {
  if constexpr (!Fp64) {
    (void)dir;
    return (wall - origin) * inv_dir;
  } else {
    (void)inv_dir;
    alignas(64) float w[simd::kLanes], o[simd::kLanes], d[simd::kLanes], t[simd::kLanes];
    wall.store_aligned(w);
    origin.store_aligned(o);
    dir.store_aligned(d);
    for (int i = 0; i < simd::kLanes; ++i) t[i] = float((double(w[i]) - double(o[i])) / double(d[i]));
    return simd::Float::load_aligned(t);
  }
}

// A ray over a texel grid, x(t) = x0 + dx t, y(t) = y0 + dy t (texel units), with what every cell step asks of
// it computed once: the reciprocals of its direction (crossing) and the sign of each axis, as masks and as the
// index steps they imply (vectors: a cell step adds them instead of selecting by a mask, which the loops would
// reload from memory at every step once the constant masks outnumber AVX-512's mask registers).
struct GridRay {
  GridRay(const simd::Float& x0_in, const simd::Float& y0_in, const simd::Float& dx_in, const simd::Float& dy_in)
      : x0(x0_in), y0(y0_in), dx(dx_in), dy(dy_in), inv_dx(simd::Float(1.0f) / dx), inv_dy(simd::Float(1.0f) / dy),
        pos_x(simd::int_mask(dx > simd::Float(0.0f))), pos_y(simd::int_mask(dy > simd::Float(0.0f))),
        neg_x(dx < simd::Float(0.0f)), neg_y(dy < simd::Float(0.0f)), flat_x(dx == simd::Float(0.0f)),
        flat_y(dy == simd::Float(0.0f)), exit_x(xsimd::select(pos_x, simd::Int(1), simd::Int(0))),
        exit_y(xsimd::select(pos_y, simd::Int(1), simd::Int(0))), step_x(exit_x + exit_x - simd::Int(1)),
        step_y(exit_y + exit_y - simd::Int(1)), exit_fx(xsimd::to_float(exit_x)), exit_fy(xsimd::to_float(exit_y)),
        regular(xsimd::all(~(flat_x | flat_y) & finite(inv_dx) & finite(inv_dy) & finite(x0) & finite(y0))) {}

  simd::Float x0, y0, dx, dy;
  simd::Float inv_dx, inv_dy;  // fl(1 / dx), fl(1 / dy)
  simd::IntMask pos_x, pos_y;  // dx > 0, dy > 0: the cell index steps up
  simd::Mask neg_x, neg_y;     // dx < 0, dy < 0
  simd::Mask flat_x, flat_y;   // dx == 0, dy == 0: parallel to that axis's walls
  simd::Int exit_x, exit_y;    // 1 where the index steps up, else 0: the exit wall of cell c is c + exit
  simd::Int step_x, step_y;    // +1 where the index steps up, else -1: the cell after an exit wall is c + step
  simd::Float exit_fx, exit_fy;  // exit_x, exit_y as floats
  // Every lane has a finite origin and a nonzero direction with finite reciprocals in both axes, so no crossing
  // is NaN or parallel: the cell stepping can skip the parallel lanes' rules (the same results for such rays).
  bool regular;

private:
  static simd::Mask finite(const simd::Float& f) { return xsimd::abs(f) <= simd::Float(3.4028235e38f); }
};

// Cell (cx, cy) of `level` in texel units: its indices as floats and its side 2^level, which its walls and mid
// lines are computed from: (c + 1/2) 2^level and (c + exit) 2^level are exact while |c| < 2^23 (8 M texels; fp32
// positions that far out have no fraction left anyway).
struct CellPlace {
  simd::Float x, y, size;
};
inline CellPlace cell_place(const simd::Int& level, const simd::Int& cx, const simd::Int& cy) {
  return {xsimd::to_float(cx), xsimd::to_float(cy), xsimd::to_float(simd::Int(1) << level)};
}

// Moves the `descend` lanes from their cell (`place`, at `level` >= 1) to the child holding the ray at t: t is
// compared with where the ray crosses the cell's mid lines, computed exactly as wall crossings are, so a ray standing
// on a wall is never put back into the cell it just left. t is never NaN.
template <bool Fp64 = false>
inline void descend_to_child(const simd::IntMask& descend, const simd::Float& t, const CellPlace& place,
                             const GridRay& ray, simd::Int& level, simd::Int& cx, simd::Int& cy) {
  using simd::Float;
  using simd::Int;
  const Float mid_x = (place.x + Float(0.5f)) * place.size;  // (2 cx + 1) 2^(level - 1), exactly
  const Float mid_y = (place.y + Float(0.5f)) * place.size;
  const Float tx = crossing<Fp64>(mid_x, ray.x0, ray.dx, ray.inv_dx);
  const Float ty = crossing<Fp64>(mid_y, ray.y0, ray.dy, ray.inv_dy);
  Int high_x, high_y;  // 1 for the child on the high side of the mid line
  if (ray.regular) {
    // Neither t (never NaN, the caller's promise) nor a crossing is NaN, so t < tx is exactly !(t >= tx).
    high_x = xsimd::select(simd::int_mask(t >= tx), ray.exit_x, ray.exit_x ^ Int(1));
    high_y = xsimd::select(simd::int_mask(t >= ty), ray.exit_y, ray.exit_y ^ Int(1));
  } else {
    const simd::Mask hx =
        (simd::float_mask(ray.pos_x) & (t >= tx)) | (ray.neg_x & (t < tx)) | (ray.flat_x & (ray.x0 >= mid_x));
    const simd::Mask hy =
        (simd::float_mask(ray.pos_y) & (t >= ty)) | (ray.neg_y & (t < ty)) | (ray.flat_y & (ray.y0 >= mid_y));
    high_x = xsimd::select(simd::int_mask(hx), Int(1), Int(0));
    high_y = xsimd::select(simd::int_mask(hy), Int(1), Int(0));
  }
  cx = xsimd::select(descend, cx + cx + high_x, cx);
  cy = xsimd::select(descend, cy + cy + high_y, cy);
  level = simd::minus_one_where(level, descend);
}
template <bool Fp64 = false>
inline void descend_to_child(const simd::IntMask& descend, const simd::Float& t, const GridRay& ray, simd::Int& level,
                             simd::Int& cx, simd::Int& cy) {
  descend_to_child<Fp64>(descend, t, cell_place(level, cx, cy), ray, level, cx, cy);
}

// Where the ray crosses the exit walls of cell `place` (the walls ahead in each axis), as t; infinity in an axis
// the ray is parallel to.
template <bool Fp64 = false>
inline void exit_walls(const CellPlace& place, const GridRay& ray, simd::Float& tx, simd::Float& ty) {
  using simd::Float;
  const Float inf(std::numeric_limits<float>::infinity());
  const Float wall_x = (place.x + ray.exit_fx) * place.size;
  const Float wall_y = (place.y + ray.exit_fy) * place.size;
  tx = crossing<Fp64>(wall_x, ray.x0, ray.dx, ray.inv_dx);
  ty = crossing<Fp64>(wall_y, ray.y0, ray.dy, ray.inv_dy);
  if (!ray.regular) {
    tx = xsimd::select(ray.flat_x, inf, tx);
    ty = xsimd::select(ray.flat_y, inf, ty);
  }
}
template <bool Fp64 = false>
inline void exit_walls(const simd::Int& level, const simd::Int& cx, const simd::Int& cy, const GridRay& ray,
                       simd::Float& tx, simd::Float& ty) {
  exit_walls<Fp64>(cell_place(level, cx, cy), ray, tx, ty);
}

// After a wall crossing, the `climbing` lanes go up while the wall just crossed (cross_x / cross_y) is also a
// wall of the parent: entering a cell through its low wall (+ direction) that wall is the parent's iff the index
// is even; through its high wall (- direction) iff the index is odd. Never above `top`.
inline void climb_aligned(simd::Int& level, simd::Int& cx, simd::Int& cy, simd::IntMask climbing,
                          const simd::IntMask& cross_x, const simd::IntMask& cross_y, const simd::IntMask& step_x_pos,
                          const simd::IntMask& step_y_pos, int top) {
  using simd::Int;
  using simd::IntMask;
  climbing = climbing & (level < Int(top));
  for (int k = 0; k < top && xsimd::any(climbing); ++k) {
    const IntMask odd_x = (cx & Int(1)) == Int(1), odd_y = (cy & Int(1)) == Int(1);
    const IntMask ok = climbing & ((~cross_x) | (step_x_pos ^ odd_x)) & ((~cross_y) | (step_y_pos ^ odd_y));
    level = xsimd::select(ok, level + Int(1), level);
    cx = xsimd::select(ok, cx >> 1, cx);
    cy = xsimd::select(ok, cy >> 1, cy);
    climbing = ok & (level < Int(top));
  }
}

}  // namespace qdmr::QDMR_ISA_NAMESPACE
