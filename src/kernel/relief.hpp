#pragma once
// Relief mapping: linear search, then binary search.
#include "qdmr/program/program_params.hpp"
#include "kernel/trace_ray.hpp"

namespace qdmr::QDMR_ISA_NAMESPACE::trace {

// Relief mapping (Policarpo 2005): fixed linear steps from the top, then a binary search in the last step.
// Recorded false: no texture-cache recorder listens.
template <bool Recorded, class Surface>
Hit relief(const Surface& surface, const Ray& ray, const Float& ds,
                                                    const Float& lod, Mask active,
           const TraceParams& technique) {
  const int steps = technique.linear_steps;
  const Float step = ds / Float(float(steps));
  Float lo(0.0f), hi = ds, iterations(0.0f);
  {  // the linear search's fetch lanes end with it (the search below starts from all of them)
    LoopLanes<Recorded> lanes(FetchPhase::Trace);
    for (int i = 0; i <= steps && xsimd::any(active); ++i) {
      lanes.narrow(active);
      const Float s = step * Float(float(i));
      const Float h = surface_height<Recorded>(surface, ray.u0 + ray.du * s, ray.v0 + ray.dv * s, lod);
      const Mask found = active & (s >= ds * (Float(1.0f) - h));
      iterations += count(active);
      hi = xsimd::select(found, s, hi);
      lo = xsimd::select(found, xsimd::max(s - step, Float(0.0f)), lo);
      active = active & ~found;
    }
  }
  lo = xsimd::select(active, ds - step, lo);  // never below: the bottom (h >= 0 everywhere) is the hit
  Mask searching = lo < hi;
  LoopLanes<Recorded> search_lanes(FetchPhase::Refine);
  for (int i = 0; i < technique.binary_steps && xsimd::any(searching); ++i) {
    search_lanes.narrow(searching);
    const Float mid = (lo + hi) * Float(0.5f);
    const Float h = surface_height<Recorded>(surface, ray.u0 + ray.du * mid, ray.v0 + ray.dv * mid, lod);
    const Mask below = mid >= ds * (Float(1.0f) - h);
    iterations += count(searching);
    hi = xsimd::select(searching & below, mid, hi);
    lo = xsimd::select(searching & ~below, mid, lo);
  }
  return {hi, iterations, Float(0.0f)};
}

}  // namespace qdmr::QDMR_ISA_NAMESPACE::trace
