#include "kernel/ambient_occlusion.hpp"

#include "kernel/gather.hpp"
#include "bake/ao_pattern.hpp"
#include "kernel/blended_surface.hpp"
#include "kernel/height_surface.hpp"
#include "kernel/fetch_trace.hpp"

namespace qdmr::QDMR_ISA_NAMESPACE {

template <class Surface>
simd::Float ambient_occlusion(const Surface& surface, const AoParams& desc, const simd::Float& u, const simd::Float& v,
                              const simd::Float& s, const simd::Float& ds, const simd::Float& pixel_x,
                              const simd::Float& pixel_y, simd::Mask active) {
  using simd::Float;
  using simd::Int;
  const Float one(1.0f), zero(0.0f);
  if (!xsimd::any(active)) return one;
  FetchLanes lanes(FetchPhase::Occlusion);
  lanes.narrow(active);
  const ao::Pattern pattern = pattern_of(desc);
  const ao::Taps taps = ao::make_taps(pattern, surface.width(), surface.height());
  const int n = ao::direction_count(pattern);
  const Float u0 = xsimd::select(active, u, zero), v0 = xsimd::select(active, v, zero);
  const Float s0 = xsimd::select(active, s, zero), ds0 = xsimd::select(active, ds, zero);
  const Float width(float(surface.width())), height(float(surface.height()));
  const int top = surface.has_hierarchy() ? surface.top_level() : 0;
  const Int rotation = desc.jitter ? ao_rotation(pixel_x, pixel_y, desc.seed) : Int(0);
  const simd::FetchPath fetch = surface.sampler().fetch;

  Float visible = zero;
  for (int i = 0; i < n; ++i) {
    const Int index = Int(ao::direction_index(n, i, 0)) + rotation;
    const Float dx = simd::load_f32(ao::kDirections.cos.data(), index, fetch);
    const Float dy = simd::load_f32(ao::kDirections.sin.data(), index, fetch);
    Float slope = zero;  // tan(horizon), never below the polygon plane
    for (int k = 0; k < taps.count; ++k) {
      const ao::Tap& tap = taps.tap[std::size_t(k)];
      const Float tu = u0 + dx * Float(tap.distance), tv = v0 + dy * Float(tap.distance);
      Float h;
      if (desc.coarse) {
        const int level = tap.level < top ? tap.level : top;
        const Int cx = xsimd::to_int(xsimd::floor(tu * width)) >> level;
        const Int cy = xsimd::to_int(xsimd::floor(tv * height)) >> level;
        h = surface.cell_max(Int(level), cx, cy);
      } else {
        h = surface.height(tu, tv, zero);
      }
      const Float rise = s0 - ds0 * (one - h);
      slope = xsimd::max(slope, rise * Float(tap.inv_distance));
    }
    visible += one - slope / xsimd::sqrt(one + slope * slope);
  }
  return xsimd::select(active, apply_ao_strength(visible / Float(float(n)), desc.strength), one);
}

template simd::Float ambient_occlusion<SingleLayerSurface>(const SingleLayerSurface&, const AoParams&, const simd::Float&,
                                                           const simd::Float&, const simd::Float&, const simd::Float&,
                                                           const simd::Float&, const simd::Float&, simd::Mask);
template simd::Float ambient_occlusion<BlendedSurface>(const BlendedSurface&, const AoParams&, const simd::Float&,
                                                       const simd::Float&, const simd::Float&, const simd::Float&,
                                                       const simd::Float&, const simd::Float&, simd::Mask);

}  // namespace qdmr::QDMR_ISA_NAMESPACE
