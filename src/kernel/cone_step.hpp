#pragma once
// Cone step mapping (CSM) and relaxed cone step mapping (RCSM) over the box surface.
#include <limits>

#include "qdmr/bake/cone_map.hpp"
#include "qdmr/program/program_params.hpp"
#include "kernel/height_surface.hpp"
#include "kernel/trace_ray.hpp"
#include "kernel/sampler.hpp"
#include "kernel/sampling_code.hpp"

namespace qdmr::QDMR_ISA_NAMESPACE::trace {

// The level-0 texels cone stepping reads: a height and a cone ratio each, addressed like the height map.
// The height is read inline for 8- and 16-bit height maps (a call per step would keep the loop's vector values
// in memory); Recorded false: no texture-cache recorder listens.
struct ConeTexels {
  const ConeMap* cones;
  const TextureSampler* height;
  AddressMode address;
  simd::FetchPath fetch;
  InlineMaxChain inline_load = inline_load_for(height->key());

  template <bool Recorded>
  [[gnu::always_inline]] void at(const Int& x, const Int& y, Float& h, Float& ratio) const {
    const Int ax = address_texel(x, cones->width, address);
    const Int ay = address_texel(y, cones->height, address);
    Float texel[4];
    // The clamped load, as height->load() does (ax and ay are in range already).
    if (!load_inline<Recorded>(inline_load, false, height->view(), Int(0), ax, ay, texel))
      height->load(Int(0), ax, ay, texel);
    h = texel[0];
    ratio = simd::load_f32(cones->ratio.data(), ay * Int(cones->width) + ax, fetch);
  }
};

// Cone step mapping over the box surface (Dummer 2006; relaxed cones: Policarpo & Oliveira 2007). The ray reads
// the cone of the level-0 texel p it is over; the cone stands for S_p, the union of cones with apex anywhere on
// p's top face (cone_map.hpp), and the ray steps to where it leaves S_p. Along the ray S_p is: p's air column
// up to the first wall, then, outside one wall, distance (alpha (s - sa)) <= r (top - s) / depth_scale, then,
// outside both, the Euclidean distance to p's square; so the exit is p's top (a hit), a linear solve or a
// quadratic. With r = 0 the step still reaches p's wall (or top): the march never stalls on rough maps.
// Conservative cones never let a step pass through the surface: the first texel top the ray is at or below is
// the hit. Relaxed cones let a step enter the surface at most once and not leave it before the step's end: a
// step that ends below the surface brackets the first hit, found by binary search on the box surface.
template <bool relaxed, bool Recorded>
Hit cone_step(const ConeTexels& texels, const Ray& ray, const Float& ds, Mask active, const TraceParams& technique) {
  const float width = float(texels.cones->width), height = float(texels.cones->height);
  const Float zero(0.0f), inf(std::numeric_limits<float>::infinity());
  const Float x0 = ray.u0 * Float(width), y0 = ray.v0 * Float(height);
  const Float dx = ray.du * Float(width), dy = ray.dv * Float(height);  // texels per unit of depth
  const Float ax = xsimd::abs(ray.du) * ds, ay = xsimd::abs(ray.dv) * ds;  // UV per unit of height, as the ratios
  const IntMask step_x_pos = int_mask(dx > zero), step_y_pos = int_mask(dy > zero);
  const Int step_x = xsimd::select(step_x_pos, Int(1), Int(-1)), step_y = xsimd::select(step_y_pos, Int(1), Int(-1));

  Int cx = texel_ahead(x0, dx), cy = texel_ahead(y0, dy);
  Float s(0.0f), s_prev(0.0f);
  Mask search = zero != zero;  // rcsm: the last step entered the surface
  Float iterations;
  {  // the loop's fetch lanes end with it (the search below starts from all of them)
    CappedLoop<Recorded> loop(Int(technique.max_iterations), FetchPhase::Trace);
    while (loop.next(active)) {

      Float hp, r;
      texels.at<Recorded>(cx, cy, hp, r);
      const Float top = ds * (Float(1.0f) - hp);
      // At or below the top of the texel the ray is over: the hit (conservative, and any ray starting on or in
      // the surface), or a relaxed step that went in.
      const Mask below = active & (s >= top);
      if constexpr (relaxed) search = search | (below & (s_prev < s));
      active = active & ~below;

      // The walls of p ahead, each crossing computed from the integer wall as in QDM.
      const Float wall_x = xsimd::to_float(xsimd::select(step_x_pos, cx + Int(1), cx));
      const Float wall_y = xsimd::to_float(xsimd::select(step_y_pos, cy + Int(1), cy));
      const Float sx = xsimd::select(dx != zero, xsimd::max((wall_x - x0) / dx, s), inf);
      const Float sy = xsimd::select(dy != zero, xsimd::max((wall_y - y0) / dy, s), inf);
      const Mask x_first = sx <= sy;
      const Float alpha = xsimd::select(x_first, ax, ay), beta = xsimd::select(x_first, ay, ax);
      const Mask to_top = active & (top <= xsimd::min(sx, sy));
      // Finite stand-ins (a wall never crossed lies beyond the top): lanes going to the top ignore the rest.
      const Float sa = xsimd::min(xsimd::min(sx, sy), top), sb = xsimd::min(xsimd::max(sx, sy), top);
      // Outside the first wall only: alpha (s - sa) = r (top - s).
      const Float exit1 =
          xsimd::max((alpha * sa + r * top) / xsimd::max(alpha + r, Float(1e-30f)), sa);
      // Outside both: with tau = s - sb, delta = sb - sa, T = top - sb,
      //   alpha^2 (tau + delta)^2 + beta^2 tau^2 = r^2 (T - tau)^2,
      // a2 tau^2 + 2 b1 tau + c0 = 0 with c0 <= 0 (the ray is in S_p at sb): the root in [0, T] in the stable form.
      const Float delta = sb - sa, T = top - sb;
      const Float a2 = alpha * alpha + beta * beta - r * r;
      const Float b1 = alpha * alpha * delta + r * r * T;
      const Float c0 = (alpha * delta - r * T) * (alpha * delta + r * T);
      const Float disc = xsimd::max(b1 * b1 - a2 * c0, zero);
      const Float tau = xsimd::min(xsimd::max((zero - c0) / xsimd::max(b1 + xsimd::sqrt(disc), Float(1e-30f)), zero), T);
      const Float next = xsimd::select(to_top, top, xsimd::min(xsimd::select(exit1 <= sb, exit1, sb + tau), top));
      active = active & ~to_top;  // on p's top while over p: the hit

      // The texel at the step's end: the one ahead of the position, at least one past each wall crossed.
      const Mask stepping = active;
      const Int ahead_x = texel_ahead(x0 + dx * next, dx), ahead_y = texel_ahead(y0 + dy * next, dy);
      const Int moved_x = xsimd::select(step_x_pos, xsimd::max(ahead_x, cx + step_x), xsimd::min(ahead_x, cx + step_x));
      const Int moved_y = xsimd::select(step_y_pos, xsimd::max(ahead_y, cy + step_y), xsimd::min(ahead_y, cy + step_y));
      cx = xsimd::select(int_mask(stepping & (next >= sx)), moved_x, cx);
      cy = xsimd::select(int_mask(stepping & (next >= sy)), moved_y, cy);
      s_prev = xsimd::select(stepping, s, s_prev);
      s = xsimd::select(stepping | to_top, next, s);
    }
    iterations = loop.iterations();
  }
  if constexpr (relaxed) {
    // The first hit lies in (s_prev, s]: below the surface is false before it and true after it up to s.
    Float lo = s_prev, hi = s;
    LoopLanes<Recorded> lanes(FetchPhase::Refine);
    for (int i = 0; i < technique.binary_steps && xsimd::any(search); ++i) {
      lanes.narrow(search);
      const Float mid = (lo + hi) * Float(0.5f);
      Float h, unused;
      texels.at<Recorded>(texel_ahead(x0 + dx * mid, zero), texel_ahead(y0 + dy * mid, zero), h, unused);
      const Mask below = mid >= ds * (Float(1.0f) - h);
      iterations += count(search);
      hi = xsimd::select(search & below, mid, hi);
      lo = xsimd::select(search & ~below, mid, lo);
    }
    s = xsimd::select(search, hi, s);
  }
  return {xsimd::min(s, ds), iterations, Float(0.0f)};
}

}  // namespace qdmr::QDMR_ISA_NAMESPACE::trace
