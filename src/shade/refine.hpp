#pragma once
// Refinement of a box-surface hit (qdm, csm, rcsm) against the filtered surface.
#include "qdmr/scene/scene.hpp"
#include "qdmr/texture/heightfield.hpp"
#include "shade/trace_ray.hpp"

namespace qdmr::QDMR_ISA_NAMESPACE::trace {

// The exact bilinear-patch hit (refine.cpp): from the point where the ray reached the conservative bound, the
// patches of `surface` are walked cell by cell and solved analytically in fp64 (the reference's traversal).
Float bilinear_patch(const Ray& ray, const Float& ds, const Float& s_start, Float& iterations, Mask active,
                     const HeightField& surface, int max_iterations);

// Between the last texel step before a box-surface hit and the hit, against the filtered (bilinear) surface.
template <class Surface>
Float refine(const Surface& surface, const Ray& ray, const Float& ds, const Float& s_hit,
                                  Float& iterations, Mask active,
             const TechniqueDesc& technique, const HeightField* patches) {
  if (technique.refinement == QdmRefinement::None) return s_hit;
  FetchLanes lanes(FetchPhase::Refine);
  lanes.narrow(active);
  const Float lod0(0.0f);
  const Float step = texel_step(ray, float(surface.width()), float(surface.height()));
  Float lo = xsimd::max(s_hit - step, Float(0.0f)), hi = s_hit;
  const Float gap_lo = ds * (Float(1.0f) - surface.height(ray.u0 + ray.du * lo, ray.v0 + ray.dv * lo, lod0)) - lo;
  const Float gap_hi = ds * (Float(1.0f) - surface.height(ray.u0 + ray.du * hi, ray.v0 + ray.dv * hi, lod0)) - hi;
  iterations += count(active) * Float(2.0f);
  if (technique.refinement == QdmRefinement::Linear) {
    const Mask bracket = active & (gap_lo > Float(0.0f)) & (gap_hi <= Float(0.0f));
    const Float t = gap_lo / (gap_lo - gap_hi);
    return xsimd::select(bracket, lo + (hi - lo) * t, xsimd::select(gap_lo <= Float(0.0f), lo, hi));
  }
  if (technique.refinement == QdmRefinement::BilinearPatch && patches)
    return bilinear_patch(ray, ds, s_hit, iterations, active, *patches, technique.max_iterations);
  // Binary (and the bilinear patch without its fp64 surface): bisection on the filtered surface.
  const int steps = technique.refinement == QdmRefinement::Binary ? 8 : 24;
  Mask searching = active & (gap_lo > Float(0.0f));
  hi = xsimd::select(gap_lo > Float(0.0f), hi, lo);
  for (int i = 0; i < steps && xsimd::any(searching); ++i) {
    lanes.narrow(searching);
    const Float mid = (lo + hi) * Float(0.5f);
    const Float gap = ds * (Float(1.0f) - surface.height(ray.u0 + ray.du * mid, ray.v0 + ray.dv * mid, lod0)) - mid;
    iterations += count(searching);
    const Mask below = gap <= Float(0.0f);
    hi = xsimd::select(searching & below, mid, hi);
    lo = xsimd::select(searching & !below, mid, lo);
  }
  return hi;
}

}  // namespace qdmr::QDMR_ISA_NAMESPACE::trace
