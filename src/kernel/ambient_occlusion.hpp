#pragma once
// Per-frame ambient occlusion of the displaced surface from horizon queries (the talk's "Ambient Occlusion":
// n equally spaced horizon queries per pixel, averaged, optionally rotated per pixel by a random angle).
//
// For each direction of ao_pattern.hpp, the horizon slope over the search radius is
//   tan(horizon) = max(0, max over taps of rise / t),   rise = s - ds * (1 - h(tap)),
// the height of the surface at the tap above the point, in depth units, over the horizontal UV distance t.
// The direction's visibility is the cosine-weighted unoccluded part of its vertical slice of the hemisphere
// around the polygon normal, 1 - sin(horizon), with sin(atan(x)) = x / sqrt(1 + x^2) (no trigonometry);
// ao = the average over the directions, and the result is apply_ao_strength(ao, strength).
//   coarse: the tap at 2^k texels reads cell_max(k, cell of the tap) (capped at the surface's top level, level 0
//           without a hierarchy): a conservative height for the cell, log2(radius in texels) fetches;
//   fine:   every tap reads the filtered surface height(u, v, lod 0), as the material's technique fetches it.
// Cell addressing wraps (the max-quadtree's rule); the filtered surface uses the material's address mode.
// A flat surface (h(tap) equal to the point's height, s = ds * (1 - h)) gives exactly 1.
#include "bake/ao_pattern.hpp"
#include "core/simd.hpp"
#include "qdmr/program/program_params.hpp"

namespace qdmr::QDMR_ISA_NAMESPACE {

// ao::rotation per lane, from pixel centres (x + 0.5, y + 0.5).
inline simd::Int ao_rotation(const simd::Float& pixel_x, const simd::Float& pixel_y, std::uint32_t seed) {
  using simd::UInt;
  const UInt x = xsimd::bitwise_cast<UInt>(xsimd::to_int(xsimd::floor(pixel_x)));
  const UInt y = xsimd::bitwise_cast<UInt>(xsimd::to_int(xsimd::floor(pixel_y)));
  UInt h = (x * UInt(0x8da6b343u)) ^ (y * UInt(0xd8163841u)) ^ UInt(seed * 0xcb1ab31fu);
  h ^= h >> 16;
  h *= UInt(0x85ebca6bu);
  h ^= h >> 13;
  h *= UInt(0xc2b2ae35u);
  h ^= h >> 16;
  return xsimd::bitwise_cast<simd::Int>(h >> 28);
}

// The directions and taps of bake/ao_pattern.hpp the parameters ask for.
inline ao::Pattern pattern_of(const AoParams& params) {
  return {.directions = params.directions, .jitter = params.jitter, .seed = params.seed, .radius = params.radius,
          .coarse = params.coarse};
}

// ao' = 1 - strength * (1 - ao): strength 0 disables the darkening, 1 keeps it (for baked maps too).
inline simd::Float apply_ao_strength(const simd::Float& ao, float strength) {
  const simd::Float one(1.0f);
  return one - simd::Float(strength) * (one - ao);
}

// Ambient visibility in [0, 1] (1 = open) of the surface point at (u, v) and depth s (0 = polygon, ds = deepest),
// ds the depth scale, per lane. Jitter rotates the directions by a hash of (floor(pixel_x), floor(pixel_y),
// desc.seed), nothing else. Inactive lanes return 1. Instantiated for SingleLayerSurface and BlendedSurface; the
// taps reach up to desc.radius from (u, v), so a BlendedSurface with per-pixel weights needs its UV box to cover
// [u - radius, u + radius] x [v - radius, v + radius].
template <class Surface>
simd::Float ambient_occlusion(const Surface& surface, const AoParams& desc, const simd::Float& u, const simd::Float& v,
                              const simd::Float& s, const simd::Float& ds, const simd::Float& pixel_x,
                              const simd::Float& pixel_y, simd::Mask active);

}  // namespace qdmr::QDMR_ISA_NAMESPACE
