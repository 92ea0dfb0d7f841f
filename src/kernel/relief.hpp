#pragma once
// Relief mapping: linear search, then binary search.
#include "qdmr/program/program_params.hpp"
#include "kernel/trace_ray.hpp"

namespace qdmr::QDMR_ISA_NAMESPACE::trace {

// Where the linear search leaves each lane: the hit lies in [lo, hi]; the binary search runs in `searching`.
struct ReliefBracket {
  Float lo, hi, iterations;
  Mask searching;
};

// Relief's linear search: fixed steps from the top to the first sample below the surface. height(u, v, lod): the
// surface's heights (with_surface_height).
template <bool Recorded, class Height>
[[gnu::always_inline]] inline ReliefBracket relief_linear(const Height& height, const Ray& ray, const Float& ds,
                                                          const Float& lod, Mask active, const TraceParams& technique) {
  const int steps = technique.linear_steps;
  const Float step = ds / Float(float(steps));
  Float lo(0.0f), hi = ds, iterations(0.0f);
  {  // the linear search's fetch lanes end with it (the search below starts from all of them)
    LoopLanes<Recorded> lanes(FetchPhase::Trace);
    for (int i = 0; i <= steps && xsimd::any(active); ++i) {
      lanes.narrow(active);
      const Float s = step * Float(float(i));
      const Float h = height(ray.u0 + ray.du * s, ray.v0 + ray.dv * s, lod);
      const Mask found = active & (s >= ds * (Float(1.0f) - h));
      iterations += count(active);
      hi = xsimd::select(found, s, hi);
      lo = xsimd::select(found, xsimd::max(s - step, Float(0.0f)), lo);
      active = active & ~found;
    }
  }
  lo = xsimd::select(active, ds - step, lo);  // never below: the bottom (h >= 0 everywhere) is the hit
  return {lo, hi, iterations, lo < hi};
}

// One step of relief's binary search (the lanes outside b.searching keep their bracket).
template <class Height>
[[gnu::always_inline]] inline void relief_bisect(const Height& height, const Ray& ray, const Float& ds,
                                                 const Float& lod, ReliefBracket& b) {
  const Float mid = (b.lo + b.hi) * Float(0.5f);
  const Float h = height(ray.u0 + ray.du * mid, ray.v0 + ray.dv * mid, lod);
  const Mask below = mid >= ds * (Float(1.0f) - h);
  b.iterations += count(b.searching);
  b.hi = xsimd::select(b.searching & below, mid, b.hi);
  b.lo = xsimd::select(b.searching & ~below, mid, b.lo);
}

// Relief mapping (Policarpo 2005): fixed linear steps from the top, then a binary search in the last step.
// Recorded false: no texture-cache recorder listens.
template <bool Recorded, class Surface>
Hit relief(const Surface& surface, const Ray& ray, const Float& ds, const Float& lod, Mask active,
           const TraceParams& technique) {
  Hit hit;
  // s, lo, hi and the midpoints stay in [0, ds]; in every lane (the binary search runs in lanes never active)
  const bool finite = finite_along(ray, ds, Mask(true));
  with_surface_height<Recorded>(surface, finite, [&](const auto& height) __attribute__((always_inline)) {
    ReliefBracket b = relief_linear<Recorded>(height, ray, ds, lod, active, technique);
    LoopLanes<Recorded> search_lanes(FetchPhase::Refine);
    for (int i = 0; i < technique.binary_steps && xsimd::any(b.searching); ++i) {
      search_lanes.narrow(b.searching);
      relief_bisect(height, ray, ds, lod, b);
    }
    hit = {b.hi, b.iterations, Float(0.0f)};
  });
  return hit;
}

// relief() of two batches over one surface, no recorder listening: the linear searches one after the other (they
// run at the core's throughput), the binary searches side by side (each step waits on the last one's fetch, so
// one search alone leaves the core idle). The same hits and iteration counts as relief() of each.
template <class Surface>
void relief_pair(const Surface& surface, const TraceParams& technique, const Ray& ray_a, const Float& ds_a,
                 const Float& lod_a, Mask active_a, Hit& hit_a, const Ray& ray_b, const Float& ds_b,
                 const Float& lod_b, Mask active_b, Hit& hit_b) {
  const bool finite = finite_along(ray_a, ds_a, Mask(true)) && finite_along(ray_b, ds_b, Mask(true));  // as relief()'s
  with_surface_height<false>(surface, finite, [&](const auto& height) __attribute__((always_inline)) {
    ReliefBracket a = relief_linear<false>(height, ray_a, ds_a, lod_a, active_a, technique);
    ReliefBracket b = relief_linear<false>(height, ray_b, ds_b, lod_b, active_b, technique);
    const bool search_a = xsimd::any(a.searching), search_b = xsimd::any(b.searching);  // fixed through the search
    for (int i = 0; i < technique.binary_steps && (search_a || search_b); ++i) {
      if (search_a) relief_bisect(height, ray_a, ds_a, lod_a, a);
      if (search_b) relief_bisect(height, ray_b, ds_b, lod_b, b);
    }
    hit_a = {a.hi, a.iterations, Float(0.0f)};
    hit_b = {b.hi, b.iterations, Float(0.0f)};
  });
}

}  // namespace qdmr::QDMR_ISA_NAMESPACE::trace
