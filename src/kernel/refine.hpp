#pragma once
// Refinement of a box-surface hit (qdm, csm, rcsm) against the filtered surface.
#include "qdmr/program/program_params.hpp"
#include "qdmr/texture/heightfield.hpp"
#include "kernel/trace_ray.hpp"

namespace qdmr::QDMR_ISA_NAMESPACE::trace {

// The exact bilinear-patch hit (refine.cpp): from the point where the ray reached the conservative bound, the
// patches of `surface` are walked cell by cell and solved analytically in fp64 (the reference's traversal).
Float bilinear_patch(const Ray& ray, const Float& ds, const Float& s_start, Float& iterations, Mask active,
                     const HeightField& surface, int max_iterations);

// The surface's depth minus the ray's at ray depth s, from the surface height h there (positive: the ray is above
// the surface).
inline Float gap(const Float& ds, const Float& h, const Float& s) { return ds * (Float(1.0f) - h) - s; }

// The linear refinement between depths lo and hi from the gaps there: where the line through them crosses zero if
// they bracket a crossing, else the end already below the surface (lo) or hi.
inline Float linear_crossing(const Float& lo, const Float& hi, const Float& gap_lo, const Float& gap_hi,
                             const Mask& active) {
  const Mask bracket = active & (gap_lo > Float(0.0f)) & (gap_hi <= Float(0.0f));
  const Float t = gap_lo / (gap_lo - gap_hi);
  return xsimd::select(bracket, lo + (hi - lo) * t, xsimd::select(gap_lo <= Float(0.0f), lo, hi));
}

// Where the refinement of a box-surface hit at depth s starts: one level-0 texel step before it, at least 0.
template <class Surface>
Float bracket_start(const Surface& surface, const Ray& ray, const Float& s) {
  return xsimd::max(s - texel_step(ray, float(surface.width()), float(surface.height())), Float(0.0f));
}

// Between the last texel step before a box-surface hit and the hit, against the filtered (bilinear) surface.
// Recorded false: no texture-cache recorder listens (refine() picks).
template <bool Recorded, class Surface>
Float refine_as(const Surface& surface, const Ray& ray, const Float& ds, const Float& s_hit, Float& iterations,
                Mask active, const TraceParams& technique, const HeightField* patches) {
  if (technique.refinement == QdmRefinement::None) return s_hit;
  LoopLanes<Recorded> lanes(FetchPhase::Refine);
  lanes.narrow(active);
  const Float lod0(0.0f);
  Float lo = bracket_start(surface, ray, s_hit), hi = s_hit;
  const auto gap_at = [&](const Float& s) __attribute__((always_inline)) {
    return gap(ds, surface_height<Recorded>(surface, ray.u0 + ray.du * s, ray.v0 + ray.dv * s, lod0), s);
  };
  const Float gap_lo = gap_at(lo);
  const Float gap_hi = gap_at(hi);
  iterations += count(active) * Float(2.0f);
  if (technique.refinement == QdmRefinement::Linear) return linear_crossing(lo, hi, gap_lo, gap_hi, active);
  if (technique.refinement == QdmRefinement::BilinearPatch && patches)
    return bilinear_patch(ray, ds, s_hit, iterations, active, *patches, technique.max_iterations);
  // Binary (and the bilinear patch without its fp64 surface): bisection on the filtered surface.
  const int steps = technique.refinement == QdmRefinement::Binary ? 8 : 24;
  Mask searching = active & (gap_lo > Float(0.0f));
  hi = xsimd::select(gap_lo > Float(0.0f), hi, lo);
  for (int i = 0; i < steps && xsimd::any(searching); ++i) {
    lanes.narrow(searching);
    const Float mid = (lo + hi) * Float(0.5f);
    const Float gap = gap_at(mid);
    iterations += count(searching);
    const Mask below = gap <= Float(0.0f);
    hi = xsimd::select(searching & below, mid, hi);
    lo = xsimd::select(searching & ~below, mid, lo);
  }
  return hi;
}

// The linear refinement (refine_as with QdmRefinement::Linear, no recorder) of two batches' hits at once, s_a and
// s_b in, refined out: the four surface samples' loads, which often miss the cache, go side by side instead of one
// batch's after the other's (the QDM frame 1.011-1.018x). Each lane's result is refine_as's.
template <class Surface>
void refine_linear_pair(const Surface& surface, const Ray& ray_a, const Float& ds_a, Float& s_a, Float& iterations_a,
                        Mask active_a, const Ray& ray_b, const Float& ds_b, Float& s_b, Float& iterations_b,
                        Mask active_b) {
  const auto height_at = [&](const Ray& ray, const Float& s) __attribute__((always_inline)) {
    return surface_height<false>(surface, ray.u0 + ray.du * s, ray.v0 + ray.dv * s, Float(0.0f));
  };
  const Float lo_a = bracket_start(surface, ray_a, s_a), lo_b = bracket_start(surface, ray_b, s_b);
  const Float h_lo_a = height_at(ray_a, lo_a), h_hi_a = height_at(ray_a, s_a);
  const Float h_lo_b = height_at(ray_b, lo_b), h_hi_b = height_at(ray_b, s_b);
  iterations_a += count(active_a) * Float(2.0f);
  iterations_b += count(active_b) * Float(2.0f);
  s_a = linear_crossing(lo_a, s_a, gap(ds_a, h_lo_a, lo_a), gap(ds_a, h_hi_a, s_a), active_a);
  s_b = linear_crossing(lo_b, s_b, gap(ds_b, h_lo_b, lo_b), gap(ds_b, h_hi_b, s_b), active_b);
}

// refine_as without the texture-cache recorder's tests when none listens: their calls made the compiler keep the
// refinement's vector values in memory (as in POM's and relief's loops).
template <class Surface>
Float refine(const Surface& surface, const Ray& ray, const Float& ds, const Float& s_hit, Float& iterations,
             Mask active, const TraceParams& technique, const HeightField* patches) {
  return fetch_recorder_listens()
             ? refine_as<true>(surface, ray, ds, s_hit, iterations, active, technique, patches)
             : refine_as<false>(surface, ray, ds, s_hit, iterations, active, technique, patches);
}

}  // namespace qdmr::QDMR_ISA_NAMESPACE::trace
