#pragma once
// Self-shadowing of a displaced point towards one directional light (the talk's "Self-shadowing" and "QDM
// Self-shadowing"): a hard shadow traced through the box surface, the POM horizon soft shadow, and the talk's
// mip-based soft shadow. Templates over the surface type (height_surface.hpp); instantiated in self_shadow.cpp.
//
// The light ray climbs from the start point: after climbing c (depth units), it is at
//   (u + du c, v + dv c, s - c),
// so it reaches the polygon (depth 0), above which nothing can occlude, at c = s.
//
// Modes (ShadowMode; the numbers are ShadowParams, scene.hpp's ShadowDesc documents them):
// - Off: visibility 1, 0 iterations.
// - Hard: the box surface (each level-0 texel a closed column down from depth ds (1 - h); texel indices wrap)
//   as the exact reference light_visibility() (qdmr/reference/reference.hpp) defines it: visibility 0 iff the
//   ray passes through the interior of a column other than the start texel T0, i.e. enters a texel strictly
//   below its top (a rising ray is lowest where it enters). Grazing a top face, an edge or a corner, or
//   running along a wall, is lit. T0 is the texel holding (u, v); on a texel boundary, the one behind along
//   the light direction: a start on a wall is then shadowed by the column behind that wall when the light is
//   on the far side of the wall, and a start a rounding error inside its own column (a filtered or rounded
//   hit) is never shadowed by that column. With a hierarchy: a max-quadtree traversal that skips a cell when
//   the ray enters it at or above the cell's maximum (climbing while the wall crossed is also the parent's,
//   so every cell is tested from where the ray enters it) and descends otherwise; without one, a level-0
//   texel walk. At most desc.max_iterations cell visits (one height fetch each); a lane that runs out
//   counts as lit. Iterations: cell visits.
// - Horizon (Tatarchuk 2006): desc.samples samples at climbs c_k = c_max k / n, k = 1..n, where
//   c_max = s, or min(s, desc.length / |(du, dv)|) when desc.length > 0 (the horizontal reach in UV units).
//   Each sample reads surface.height(u_k, v_k, lod) (the material's filtered surface) and its occlusion is
//     o_k = max(0, (ray depth - surface depth) / ds) / (1 + penumbra c_k / ds),
//   how far the surface rises above the light ray, in depth-scale units, softened linearly with the
//   blocker's distance along the ray (c_k / ds in (0, 1] is the fraction of the relief climbed).
//   The profile operator combines the samples taken (max, min, or their mean):
//     visibility = 1 - saturate(strength * combined).
//   Iterations: samples taken (n, or 0 when s = 0: a start at the polygon is lit).
// - QdmSoft (the talk's mip-based shadow): tap k at level-0 texel distance 2^k along the light direction
//   (measured in texel space), reading the max-quadtree cell of level k that holds it (coarse levels stand
//   for the far profile, log2 fetches instead of one per texel); its occlusion is o_k as above with the cell
//   maximum as height, times tap_weights[k]. Taps: tap_weights.size(), capped by the quadtree's levels;
//   taps beyond c_max (as Horizon) are not taken. Same combination and strength rule as Horizon.
//   Iterations: taps taken.
// Hard with a point-fetch surface bounds Horizon from below: when the hard ray is lit it enters no column
// below its top, so every point sample along it is at or below the ray (o_k = 0) and Horizon is lit too.
// QdmSoft has no such bound: cell maxima can darken a lit point, and the sparse taps can miss a blocker.
//
// Input guards: (du, dv) longer than kMaxLightSlope (light below ~0.22 degrees elevation) is scaled down to
// it; s is clamped to [0, ds]. Lanes with a non-finite input, or ds <= 0, are lit with 0 iterations.
#include "core/simd.hpp"
#include "qdmr/program/program_params.hpp"

namespace qdmr::QDMR_ISA_NAMESPACE {

// A ray from the displaced point towards one directional light, in UV/depth space.
struct ShadowRay {
  simd::Float u, v, s;  // start: the hit's UV and depth (0 = polygon, ds = deepest)
  simd::Float du, dv;   // UV change per unit of depth climbed towards the light: light_tangent.xy / light_tangent.z
  simd::Float ds;       // depth scale
};

struct ShadowResult {
  simd::Float visibility;  // 0 shadowed .. 1 lit
  simd::Float iterations;  // height fetches per lane (see the modes above)
};

// Longest (du, dv) used: 256 UV per unit of depth, the light at atan(1/256) = 0.22 degrees above the polygon.
inline constexpr float kMaxLightSlope = 256.0f;

// Inactive lanes return visibility 1 and 0 iterations.
template <class Surface>
ShadowResult self_shadow(const Surface& surface, ShadowMode mode, const ShadowParams& desc, const ShadowRay& ray,
                         const simd::Float& lod, simd::Mask active);

}  // namespace qdmr::QDMR_ISA_NAMESPACE
