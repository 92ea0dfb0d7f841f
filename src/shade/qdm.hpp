#pragma once
// Quadtree displacement mapping over a max-quadtree; V is the trace variant (shade/displacement.hpp).
#include <limits>

#include "qdmr/scene/scene.hpp"
#include "shade/trace_ray.hpp"

namespace qdmr::QDMR_ISA_NAMESPACE::trace {

// Quadtree displacement mapping (Drobot 2009) over the max-quadtree: from the root, advance to the nearer of
// the cell's top plane and its wall while the ray is above the cell's highest point, descend otherwise; a
// level-0 cell the ray is at or below is the hit on the box surface. Cells are integer indices stepped exactly
// across walls (sm4, exact), or recomputed from the fp32 position (sm3 emulation); where the ray crosses walls and
// mid lines is computed in fp32, or in fp64 and rounded once (exact).
template <class V, class Surface>
Hit qdm(const Surface& surface, const Ray& ray, const Float& ds,
                                                 const Float& stop_level, const Int& cap, Mask active) {
  constexpr bool fp64 = V::math == MathMode::Exact;
  const int top = surface.top_level();
  const float width = float(surface.width()), height = float(surface.height());
  const IntMask none = Int(0) != Int(0);
  const Float x0 = ray.u0 * Float(width), y0 = ray.v0 * Float(height);
  const Float dx = ray.du * Float(width), dy = ray.dv * Float(height);  // texels per unit of depth
  const IntMask step_x_pos = int_mask(dx > Float(0.0f)), step_y_pos = int_mask(dy > Float(0.0f));

  Int level(top);
  Int cx = xsimd::to_int(xsimd::floor(x0)) >> top, cy = xsimd::to_int(xsimd::floor(y0)) >> top;
  Float s(0.0f);
  const Int stop = xsimd::to_int(stop_level);
  CappedLoop loop(cap, FetchPhase::Trace);
  while (loop.next(active)) {

    // The cell's highest point (wrap addressing: power-of-two level sizes), or LinearMipMapLinear at the ray's
    // position on this level, which smooths the maxima and so can miss features.
    Float hmax;
    if constexpr (V::filtered_max)
      hmax = surface.cell_max_filtered(ray.u0 + ray.du * s, ray.v0 + ray.dv * s, xsimd::to_float(level));
    else
      hmax = surface.cell_max(level, cx, cy);
    const Float top_depth = ds * (Float(1.0f) - hmax);
    const Mask below = active & (s >= top_depth);
    const IntMask at_stop = level <= stop;
    const Mask hit = below & float_mask(at_stop);
    active = active & !hit;
    // Below the cell's top but not at the last level: descend into the child that holds the ray.
    const IntMask descend = int_mask(below & !hit);
    if (xsimd::any(descend)) descend_to_child<fp64>(descend, s, x0, y0, dx, dy, level, cx, cy);
    // Above the cell's top: advance to its top plane or its wall, whichever comes first.
    const Mask above = active & !below;
    if (!xsimd::any(above)) continue;
    Float tx, ty;
    exit_walls<fp64>(level, cx, cy, x0, y0, dx, dy, step_x_pos, step_y_pos, tx, ty);
    const Float t_wall = xsimd::max(xsimd::min(tx, ty), s);
    const Mask to_plane = above & (top_depth <= t_wall);
    s = xsimd::select(to_plane, top_depth, s);
    if constexpr (!V::filtered_max) {
      // On the cell's top plane the ray is at its highest point: the hit at the last level, else descend now, as
      // the next iteration would after reading the same cell again (a filtered max moves with the ray: it reads).
      const Mask plane_hit = to_plane & float_mask(at_stop);
      active = active & !plane_hit;
      const IntMask plane_descend = int_mask(to_plane & !plane_hit);
      if (xsimd::any(plane_descend)) descend_to_child<fp64>(plane_descend, s, x0, y0, dx, dy, level, cx, cy);
    }
    const Mask cross = above & !to_plane;
    s = xsimd::select(cross, t_wall, s);
    const IntMask cross_i = int_mask(cross);
    const IntMask cross_x = cross_i & int_mask(tx <= ty);
    const IntMask cross_y = cross_i & int_mask(ty <= tx);
    if constexpr (V::math == MathMode::Sm3) {
      // fp32 emulation: the cell is found again from the position, nudged 1/64 texel along the ray.
      const Float nudge = Float(1.0f / 64.0f);
      const Float cell = xsimd::to_float(Int(1) << level);
      const Float px = x0 + dx * s + xsimd::select(dx > Float(0.0f), nudge, Float(0.0f) - nudge);
      const Float py = y0 + dy * s + xsimd::select(dy > Float(0.0f), nudge, Float(0.0f) - nudge);
      cx = xsimd::select(cross_x, xsimd::to_int(xsimd::floor(px / cell)), cx);
      cy = xsimd::select(cross_y, xsimd::to_int(xsimd::floor(py / cell)), cy);
    } else {
      cx = xsimd::select(cross_x, xsimd::select(step_x_pos, cx + Int(1), cx - Int(1)), cx);
      cy = xsimd::select(cross_y, xsimd::select(step_y_pos, cy + Int(1), cy - Int(1)), cy);
    }
    // After a crossing: stay, go up one level (the talk's fix for degeneration into linear search), or go up
    // while the wall just crossed is also a wall of the parent.
    IntMask up = cross_i & (level < Int(top));
    if constexpr (V::level_up == QdmLevelUp::Stay) {
      up = none;
    } else if constexpr (V::level_up == QdmLevelUp::Aligned) {
      climb_aligned(level, cx, cy, up, cross_x, cross_y, step_x_pos, step_y_pos, top);
      up = none;
    }
    level = xsimd::select(up, level + Int(1), level);
    cx = xsimd::select(up, cx >> 1, cx);
    cy = xsimd::select(up, cy >> 1, cy);
  }
  return {xsimd::min(s, ds), loop.iterations(), Float(0.0f)};
}

}  // namespace qdmr::QDMR_ISA_NAMESPACE::trace
