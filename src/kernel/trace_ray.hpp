#pragma once
// What every technique shares: the view ray, the hit it reports, and texel arithmetic along the ray.
#include <type_traits>

#include "core/simd.hpp"
#include "qdmr/core/sampling.hpp"
#include "kernel/traversal.hpp"

namespace qdmr::QDMR_ISA_NAMESPACE::trace {

// The SIMD vocabulary of every technique file (they all live in this namespace and include this header).
using simd::Float;
using simd::Int;
using simd::IntMask;
using simd::kLanes;
using simd::Mask;
using simd::count;
using simd::float_mask;
using simd::int_mask;

// The view ray in UV/depth space: uv(s) = uv0 + duv * s for depth s in [0, depth_scale].
struct Ray {
  Float u0, v0, du, dv;
};

// What a technique found.
struct Hit {
  Float s;           // depth of the hit
  Float iterations;  // loop iterations per lane
  Float box_s;       // qdm, csm, rcsm: the hit on the level-0 box surface, before refinement; else s
};

// A loop's fetch lanes: FetchLanes, or nothing where the caller knows no texture-cache recorder listens.
template <bool Recorded>
using LoopLanes = std::conditional_t<Recorded, FetchLanes, UnrecordedLanes>;

// surface.height(u, v, lod); with Recorded false, without the texture-cache recorder's test where the surface
// offers that (its inline fetches): the caller knows none listens.
template <bool Recorded, class Surface>
[[gnu::always_inline]] inline Float surface_height(const Surface& surface, const Float& u, const Float& v,
                                                   const Float& lod) {
  if constexpr (requires { surface.template height<Recorded>(u, v, lod); })
    return surface.template height<Recorded>(u, v, lod);
  else
    return surface.height(u, v, lod);
}

// Whether u0 + du s and v0 + dv s are finite in the active lanes for every s with |s| <= 2 |ds|: all are far below
// the float range (a NaN fails the comparisons). The loops that step s through [0, ds] fetch only finite coordinates.
inline bool finite_along(const Ray& ray, const Float& ds, const Mask& active) {
  const Float far(0x1p100f);
  const Mask finite = (xsimd::abs(ray.u0) < far) & (xsimd::abs(ray.v0) < far) & (xsimd::abs(ray.du) < far) &
                      (xsimd::abs(ray.dv) < far) & (xsimd::abs(ds) < Float(0x1p20f));
  return xsimd::all(finite | ~active);
}

// Calls f(fetch) with fetch(u, v, lod) = surface_height<Recorded>(surface, u, v, lod) in the lanes the loop in f
// reads: the surface's fetch made once for that loop where it offers one (SingleLayerSurface::with_height).
// finite: every coordinate the loop fetches at in those lanes is finite (finite_along).
template <bool Recorded, class Surface, class F>
[[gnu::always_inline]] inline void with_surface_height(const Surface& surface, bool finite, const F& f) {
  if constexpr (requires { surface.template with_height<Recorded>(finite, f); })
    surface.template with_height<Recorded>(finite, f);
  else
    f([&](const Float& u, const Float& v, const Float& lod)
          __attribute__((always_inline)) { return surface_height<Recorded>(surface, u, v, lod); });
}

// Smallest depth step that moves the ray by one level-0 texel (the scale of refinement brackets).
inline Float texel_step(const Ray& ray, float width, float height) {
  const Float reach = xsimd::max(xsimd::abs(ray.du) * Float(width), xsimd::abs(ray.dv) * Float(height));
  return Float(1.0f) / xsimd::max(reach, Float(1e-6f));
}

// The texel a ray at texel coordinate p is over: the one ahead along the ray (direction dir) when p lies on a
// texel boundary, so a step that ends on a wall moves on. Finite for any p (a NaN clamps to the bound).
inline Int texel_ahead(const Float& p, const Float& dir) {
  const Float c = xsimd::max(xsimd::min(p, Float(kMaxTexelCoordinate)), Float(-kMaxTexelCoordinate));
  return xsimd::to_int(xsimd::select(dir < Float(0.0f), Float(-1.0f) - xsimd::floor(Float(0.0f) - c), xsimd::floor(c)));
}

// Texel index i (|i| < 2^24) to [0, n) by the address mode, as HeightField::at: wrap, clamp, mirror (period 2n).
inline Int address_texel(const Int& i, int n, AddressMode mode) {
  const Int last(n - 1);
  if (mode == AddressMode::Clamp) return xsimd::min(xsimd::max(i, Int(0)), last);
  const int period = mode == AddressMode::Mirror ? 2 * n : n;
  // i and period are exact floats and the quotient is rounded to nearest, so its floor is floor(i / period) or
  // one more: r lands in [-period, period) and one correction puts it in [0, period).
  const Int q = xsimd::to_int(xsimd::floor(xsimd::to_float(i) / Float(float(period))));
  Int r = i - q * Int(period);
  r = xsimd::select(r < Int(0), r + Int(period), r);
  if (mode == AddressMode::Mirror) r = xsimd::select(r >= Int(n), Int(period - 1) - r, r);
  return xsimd::min(xsimd::max(r, Int(0)), last);
}

}  // namespace qdmr::QDMR_ISA_NAMESPACE::trace
