#pragma once
// Cone maps for cone step mapping (Dummer 2006) and relaxed cone step mapping (Policarpo & Oliveira 2007,
// GPU Gems 3 ch. 18), exact for the box surface (each level-0 texel a flat-topped column, what point sampling
// sees).
//
// Units. Heights h in [0,1] (depth 1 - h); horizontal distances in UV units (texel (i, j) is the square
// [i/W, (i+1)/W] x [j/H, (j+1)/H]); the stored ratio r is horizontal UV distance per unit of height for a depth
// range of 1 (a renderer with depth_scale s uses r / s per unit of depth). Capped at kMaxConeRatio.
//
// The region a ratio describes. Rays read the cone of the texel they are over, so the cone must hold for an apex
// anywhere on the texel's top face: the region is the union of those cones,
//   S_p = { X : dist(X.uv, square of p) <= r_p * (h(X) - h_p), h(X) >= h_p },
// the square's air column widening upward with slope r_p. A ray at a point of S_p over texel p may advance to
// where it leaves S_p (its convex boundary); with r_p = 0 that is still the air column above p, so marching never
// stalls. (A circular cone with its apex below the ray is a subset of S_p: also valid, but stalls at r_p = 0.)
//
//   Conservative: no surface point lies strictly inside S_p:
//       r_p = min over texels q with h_q > h_p of d(p, q) / (h_q - h_p),
//     d(p, q) = the distance between the squares of p and q (0 for 8-neighbours). A ray marching with these steps
//     never passes through the surface.
//   Relaxed (the exact, continuous form of Policarpo & Oliveira's bake, which casts rays from the top of the
//     texel's axis through each texel and bounds the cone by the point where the ray leaves the surface again):
//     no descending ray that starts above p's square leaves the surface (passes from below it to above it)
//     strictly inside S_p. Then a ray stepping from a point of S_p to S_p's boundary enters the surface at most
//     once on the way, and a step that ends below the surface brackets the first hit for a binary search.
//     A descending ray leaves the box surface only through a wall where the height steps down in its direction of
//     travel, at any height between the two tops, so
//       r_p = min over walls w (between 4-neighbours a, b with h_a > h_b, p's square on a's side of w's line,
//                              h_a > h_p) of dist(square of p, segment w) / (h_a - h_p).
//     Every such wall bounds a column higher than p, so relaxed ratios are never below conservative ones.
//   No constraint (flat map, the highest texels): kMaxConeRatio.
//
// Address modes. Wrap: the plane tiled with the map (toroidal distances; for walls, the nearest copy with p on the
// high side). Mirror: the same over the 2W x 2H reflected tile. Clamp: the map extended by its edge texels; the
// extension adds no constraint (its columns and walls are never nearer than the edge texels they copy).
//
// Rounding. Distances and ratios are computed in double, the same expression in both bakers, and the minimum is
// exact and order independent, so the fast baker equals the brute-force baker bit for bit. The stored float is
// the double rounded toward zero: the stored cone is never wider than the exact one.
#include <cstdint>
#include <filesystem>
#include <string>

#include "qdmr/core/zeroed_buffer.hpp"

#include "qdmr/texture/heightfield.hpp"

namespace qdmr {

enum class ConeKind { Conservative, Relaxed };

struct ConeMap {
  int width = 0, height = 0;
  ConeKind kind = ConeKind::Conservative;
  ZeroedBuffer<float> ratio;  // row-major, row 0 at v = 0; >= 0; capped at kMaxConeRatio
};

inline constexpr float kMaxConeRatio = 64.0f;

const char* cone_kind_name(ConeKind kind);  // "conservative", "relaxed"

// The fast baker: a depth-first walk of a max hierarchy over the heights (for relaxed: over the wall tops, per
// direction of the step), nearest cells first, pruning every cell whose lower bound on the ratio (distance to the
// cell / (cell max - h_p)) cannot narrow the current cone. The texels of a 4x4 block that their 8-neighbours do
// not settle walk together (one walk, each reached texel tried on each of them), starting from the minima the
// previous block found. Parallel over rows of blocks with oneTBB; the same bits for any thread count. Throws
// qdmr::Error on empty fields and heights outside [0,1].
ConeMap bake_cone_map(const HeightField& field, ConeKind kind);

// The most memory bake_cone_map allocates at once for a width x height field (its working grid of doubles, per
// texel one value per channel: 1 conservative, 4 relaxed; mirror unfolded to 2W x 2H; the max hierarchy; the
// map), in bytes, not counting the field it is given. For memory limits checked before anything is read
// (`qdmr bake cone --max-memory`).
std::uint64_t cone_bake_bytes(int width, int height, ConeKind kind, AddressMode address);

// The brute-force baker (every texel against every texel or wall), for tests on small maps.
ConeMap bake_cone_map_brute_force(const HeightField& field, ConeKind kind);

// The cache folder: $QDMR_CACHE_DIR, else $XDG_CACHE_HOME/qdmr, else $HOME/.cache/qdmr (else a relative .qdmr-cache).
std::filesystem::path default_cache_dir();

// XXH3-64 of a format version, W, H, the address mode, the kind and the heights (as doubles).
std::uint64_t cone_map_key(const HeightField& field, ConeKind kind);

// Returns the cached map of (field, kind) from cache_dir, or bakes it and stores it there (temporary file and
// rename). A cached file is used only if its header (magic, version, key, size, kind) and payload checksum
// match; anything else is rebuilt and overwritten. A cache that cannot be written is not an error: a
// warning (qdmr/core/warning.hpp) names the entry and the OS reason.
ConeMap load_or_bake_cone_map(const HeightField& field, ConeKind kind, const std::filesystem::path& cache_dir);

// Writes the ratios as a one-channel 32-bit float EXR (row 0 at v = 0, i.e. the last row of the file) through a
// temporary file and a rename. Throws qdmr::Error when the folder is missing or the file cannot be written.
void write_cone_map_exr(const ConeMap& map, const std::filesystem::path& file);

}  // namespace qdmr
