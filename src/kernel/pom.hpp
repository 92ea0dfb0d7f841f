#pragma once
// Parallax occlusion mapping: view-dependent step count, linear intersection of the last two samples.
#include "qdmr/program/program_params.hpp"
#include "kernel/trace_ray.hpp"

namespace qdmr::QDMR_ISA_NAMESPACE::trace {

// Parallax occlusion mapping (Tatarchuk 2006): step count lerped by the view angle, then the intersection of
// the ray with the line through the last two height samples. Recorded false: no texture-cache recorder listens.
template <bool Recorded, class Surface>
Hit pom(const Surface& surface, const Ray& ray, const Float& ds,
                                                 const Float& lod, const Float& cos_view, Mask active,
        const TraceParams& technique) {
  const Float lerp = xsimd::min(xsimd::max(cos_view, Float(0.0f)), Float(1.0f));
  const Float n = xsimd::floor(Float(float(technique.max_steps)) +
                               (Float(float(technique.min_steps)) - Float(float(technique.max_steps))) * lerp +
                               Float(0.5f));
  const Float step = ds / n;
  Float prev_s(0.0f), prev_gap(0.0f), s_hit = ds, iterations(0.0f);
  LoopLanes<Recorded> lanes(FetchPhase::Trace);
  lanes.narrow(active);
  // Only the running lanes' fetches matter, at s in [0, ds] (i <= n).
  const bool finite = finite_along(ray, ds, active);
  with_surface_height<Recorded>(surface, finite, [&](const auto& height) __attribute__((always_inline)) {
    // gap = surface depth - ray depth: > 0 while the ray is above the surface.
    {
      const Float gap0 = ds * (Float(1.0f) - height(ray.u0, ray.v0, lod));
      iterations += count(active);
      const Mask at_top = active & (gap0 <= Float(0.0f));
      s_hit = xsimd::select(at_top, Float(0.0f), s_hit);
      active = active & ~at_top;
      prev_gap = gap0;
    }
    for (int i = 1; i <= technique.max_steps && xsimd::any(active); ++i) {
      const Float fi = Float(static_cast<float>(i));
      const Mask in_range = active & (fi <= n);
      lanes.narrow(in_range);
      const Float s = step * fi;
      const Float gap = ds * (Float(1.0f) - height(ray.u0 + ray.du * s, ray.v0 + ray.dv * s, lod)) - s;
      iterations += count(in_range);
      const Mask found = in_range & (gap <= Float(0.0f));
      const Float t = prev_gap / (prev_gap - gap);  // prev_gap > 0 >= gap: denominator > 0
      s_hit = xsimd::select(found, prev_s + (s - prev_s) * t, s_hit);
      active = in_range & ~found;
      prev_s = s;
      prev_gap = gap;
    }
  });
  return {s_hit, iterations, Float(0.0f)};
}

}  // namespace qdmr::QDMR_ISA_NAMESPACE::trace
