#pragma once
// Quadtree displacement mapping over a max-quadtree; V is the trace variant (kernel/displacement.hpp).
#include <limits>

#include "qdmr/core/material_modes.hpp"
#include "kernel/height_surface.hpp"
#include "kernel/trace_ray.hpp"

namespace qdmr::QDMR_ISA_NAMESPACE::trace {

// Quadtree displacement mapping (Drobot 2009) over the max-quadtree: from the root, advance to the nearer of
// the cell's top plane and its wall while the ray is above the cell's highest point, descend otherwise; a
// level-0 cell the ray is at or below is the hit on the box surface. Cells are integer indices stepped exactly
// across walls (sm4, exact), or recomputed from the fp32 position (sm3 emulation); where the ray crosses walls and
// mid lines is computed in fp32, or in fp64 and rounded once (exact).
//
// One walk is one batch of rays, advanced one iteration per step(). Each step waits on the max-chain fetch of
// the step before, so one walk per thread leaves the core idle most of the time: qdm_pair() advances two walks in
// one loop, whose independent steps the core overlaps. Every lane's result is the same either way. Recorded
// false: no texture-cache recorder listens (the rasterizer pairs batches only then), so the steps do not ask it.
template <class V, class Surface, bool Recorded = true>
class QdmWalk {
public:
  QdmWalk(const Surface& surface, const Ray& ray, const Float& ds, const Float& stop_level, const Int& cap,
          const Mask& active)
      : surface_(surface), ray_(ray), ds_(ds), top_(surface.top_level()),
        grid_(ray.u0 * Float(float(surface.width())), ray.v0 * Float(float(surface.height())),
              ray.du * Float(float(surface.width())), ray.dv * Float(float(surface.height()))),
        level_(top_), cx_(xsimd::to_int(xsimd::floor(grid_.x0)) >> top_),
        cy_(xsimd::to_int(xsimd::floor(grid_.y0)) >> top_),
        stop_end_(xsimd::to_int(stop_level) + Int(1)), active_(active), loop_(cap, FetchPhase::Trace) {
    if constexpr (requires { surface.max_chain_cells(); }) {
      texels_ = surface.max_chain_cells().texels();
      if (texels_ != nullptr) cells_ = &surface.max_chain_cells();
    }
  }
  QdmWalk(const QdmWalk&) = delete;
  QdmWalk& operator=(const QdmWalk&) = delete;

  // One iteration of every running lane; false (and nothing done) once no lane is left.
  [[gnu::always_inline]] bool step() {
    constexpr bool fp64 = V::math == MathMode::Exact;
    if (!loop_.next(active_)) return false;
    // The cell's highest point (wrap addressing: power-of-two level sizes), or LinearMipMapLinear at the ray's
    // position on this level, which smooths the maxima and so can miss features.
    Float hmax;
    if constexpr (V::filtered_max)
      hmax = surface_.cell_max_filtered(ray_.u0 + ray_.du * s_, ray_.v0 + ray_.dv * s_, xsimd::to_float(level_));
    else if constexpr (Recorded)
      hmax = surface_.cell_max(level_, cx_, cy_, active_);
    else if (cells_ != nullptr)
      hmax = cells_->at(texels_, level_, cx_, cy_);
    else
      hmax = surface_.template cell_max<false>(level_, cx_, cy_, active_);
    const Float top_depth = ds_ * (Float(1.0f) - hmax);
    const Mask below = active_ & (s_ >= top_depth);
    const Mask at_stop = float_mask(level_ < stop_end_);
    const Mask hit = below & at_stop;
    active_ = simd::and_not(active_, hit);
    // Above the cell's top: advance to its top plane or its wall, whichever comes first.
    const Mask above = simd::and_not(active_, below);
    const CellPlace place = cell_place(level_, cx_, cy_);
    Float tx, ty;
    exit_walls<fp64>(place, grid_, tx, ty);
    const Float t_wall = xsimd::max(xsimd::min(tx, ty), s_);
    const Mask to_plane = above & (top_depth <= t_wall);
    s_ = xsimd::select(to_plane, top_depth, s_);
    // Below the cell's top but not at the last level: descend into the child that holds the ray. On the cell's
    // top plane the ray is at its highest point: the hit at the last level, else descend now, as the next
    // iteration would after reading the same cell again (a filtered max moves with the ray: it reads again).
    Mask descend = simd::and_not(below, hit);
    if constexpr (!V::filtered_max) {
      const Mask plane_hit = to_plane & at_stop;
      active_ = simd::and_not(active_, plane_hit);
      descend = descend | simd::and_not(to_plane, plane_hit);
    }
    // No branch on whether any lane descends or crosses: a mispredicted one would also throw away the other
    // walk's steps in flight (qdm_pair).
    descend_to_child<fp64>(int_mask(descend), s_, place, grid_, level_, cx_, cy_);
    const Mask cross = simd::and_not(above, to_plane);
    s_ = xsimd::select(cross, t_wall, s_);
    const IntMask cross_i = int_mask(cross);
    const IntMask cross_x = cross_i & int_mask(tx <= ty);
    const IntMask cross_y = cross_i & int_mask(ty <= tx);
    if constexpr (V::math == MathMode::Sm3) {
      // fp32 emulation: the cell is found again from the position, nudged 1/64 texel along the ray.
      const Float nudge = Float(1.0f / 64.0f);
      const Float cell = xsimd::to_float(Int(1) << level_);
      const Float px = grid_.x0 + grid_.dx * s_ + xsimd::select(float_mask(grid_.pos_x), nudge, Float(0.0f) - nudge);
      const Float py = grid_.y0 + grid_.dy * s_ + xsimd::select(float_mask(grid_.pos_y), nudge, Float(0.0f) - nudge);
      cx_ = xsimd::select(cross_x, xsimd::to_int(xsimd::floor(px / cell)), cx_);
      cy_ = xsimd::select(cross_y, xsimd::to_int(xsimd::floor(py / cell)), cy_);
    } else {
      cx_ = xsimd::select(cross_x, cx_ + grid_.step_x, cx_);
      cy_ = xsimd::select(cross_y, cy_ + grid_.step_y, cy_);
    }
    // After a crossing: stay, go up one level (the talk's fix for degeneration into linear search), or go up
    // while the wall just crossed is also a wall of the parent.
    if constexpr (V::level_up == QdmLevelUp::One) {
      const IntMask up = cross_i & (level_ < Int(top_));
      level_ = simd::plus_one_where(level_, up);
      cx_ = xsimd::select(up, cx_ >> 1, cx_);
      cy_ = xsimd::select(up, cy_ >> 1, cy_);
    } else if constexpr (V::level_up == QdmLevelUp::Aligned) {
      climb_aligned(level_, cx_, cy_, cross_i, cross_x, cross_y, grid_.pos_x, grid_.pos_y, top_);
    }
    return true;
  }

  // The hit on the box surface (depth_scale where the ray found none), and the iterations per lane.
  Hit hit() const { return {xsimd::min(s_, ds_), loop_.iterations(), Float(0.0f)}; }

private:
  const Surface& surface_;
  const Ray& ray_;
  const Float ds_;
  const int top_;
  const GridRay grid_;  // the ray in texels per unit of depth
  Int level_, cx_, cy_;
  const Int stop_end_;  // one past the last level (stop_level): a lane below it is at its last level
  Float s_ = Float(0.0f);
  Mask active_;
  CappedLoop<Recorded> loop_;
  // The max chain read inline by unrecorded walks (MaxChainCells), or null: through the surface's cell_max.
  const MaxChainCells* cells_ = nullptr;
  const float* texels_ = nullptr;
};

template <class V, class Surface>
Hit qdm(const Surface& surface, const Ray& ray, const Float& ds, const Float& stop_level, const Int& cap, Mask active) {
  QdmWalk<V, Surface> walk(surface, ray, ds, stop_level, cap, active);
  while (walk.step()) {
  }
  return walk.hit();
}

// Two walks to their ends, a step of each per round while both run. Never inlined: inlined into its caller (as an
// unrelated change to the texel loads once made GCC do), the loop's register allocation got worse and the
// canonical QDM frame much slower (docs/performance-history.md).
template <class V, class Surface>
[[gnu::noinline]] void qdm_pair(QdmWalk<V, Surface, false>& a, QdmWalk<V, Surface, false>& b) {
  bool a_runs = true, b_runs = true;
  while (a_runs && b_runs) {
    a_runs = a.step();
    b_runs = b.step();
  }
  while (a_runs && a.step()) {
  }
  while (b_runs && b.step()) {
  }
}

}  // namespace qdmr::QDMR_ISA_NAMESPACE::trace
