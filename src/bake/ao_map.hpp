#pragma once
// Baked ambient occlusion (the talk: AO "need[s] to calculate only when height field changes ... use at content
// generation"): the per-frame horizon AO of kernel/ambient_occlusion.hpp evaluated once per texel of a map, in
// double precision, to be sampled bilinearly at the hit UV.
//
// Texel (i, j) of a W' x H' map holds the AO of the surface point above UV ((i + 0.5) / W', (j + 0.5) / H'):
// W' x H' = the field's size when desc.resolution is 0, else resolution x max(1, resolution * H / W).
// The point lies on the bilinear surface through the texel centres (surface_depth, ReferenceSurface::Bilinear)
// and the directions and tap distances are those of the per-frame AO (one texel = 1 / max(W, H) UV):
//   fine:   taps read the bilinear surface (what bilinear and trilinear fetch see near LOD 0);
//   coarse: the tap at 2^k texels reads the maximum of the level-k cell of a max pyramid of the heights built
//           like the max-quadtree (level k+1 = max(1, floor(n/2)) per axis, the last cell covering the leftover),
//           the tap's texel found with the field's address mode.
// With jitter, texel (i, j) uses the rotation of pixel (i, j) with desc.seed. The stored value is the raw
// average visibility in [0, 1], 1 = open: desc.strength is not applied (apply it when shading, so changing
// it needs no rebake). depth_scale is the material's technique depth scale (depth in UV units).
#include <cstdint>
#include <filesystem>

#include "bake/ao_map_row.hpp"
#include "bake/ao_pattern.hpp"
#include "bake/ao_texel.hpp"
#include "qdmr/scene/scene.hpp"
#include "qdmr/texture/heightfield.hpp"
#include "qdmr/texture/image.hpp"

namespace qdmr {

// The directions and taps a material's AO looks along (bake/ao_pattern.hpp).
inline ao::Pattern pattern_of(const AoDesc& desc) {
  return {.directions = desc.directions, .jitter = desc.jitter, .seed = desc.seed, .radius = desc.radius,
          .coarse = desc.coarse};
}

// A one-channel fp32 image, row 0 at v = 0. Parallel over rows with oneTBB; the same bits for any thread count,
// and for float heights the same as for a HeightField of the same values. Throws qdmr::Error on an empty field.
template <class T>
Image bake_ao_map(const HeightView<T>& field, double depth_scale, const AoDesc& desc, AoMapRow row = {});
inline Image bake_ao_map(const HeightField& field, double depth_scale, const AoDesc& desc, AoMapRow row = {}) {
  return bake_ao_map(height_view(field), depth_scale, desc, row);
}

// Rows first, first + step, ... of `map` (sized as bake_ao_map makes it) baked as bake_ao_map bakes them; the other
// rows are left as they are (an amortized map's rows of earlier frames: AoDesc::amortize_frames).
template <class T>
void bake_ao_rows(const HeightView<T>& field, double depth_scale, const AoDesc& desc, Image& map, int first, int step,
                  AoMapRow row = {});

struct AoMapSize {
  int width, height;
};
// The map's size for a field of this size: desc.resolution wide with the field's aspect, else the field's size.
AoMapSize ao_map_size(int field_width, int field_height, const AoDesc& desc);

// What a bake (or a cache read) holds besides the field and the stored map: the map in floats and, for coarse
// taps, the max pyramid of the heights above level 0 (height_bytes per cell: as the heights are stored) and, without jitter, the tap columns every row shares
// (bake/ao_texel.hpp's UniformColumns). For memory plans; nothing is baked.
std::uint64_t ao_bake_bytes(int field_width, int field_height, const AoDesc& desc,
                            int height_bytes = sizeof(double));

// XXH3-64 of the format version, W, H, address mode, heights (as doubles, whatever they are stored as: float
// heights have the key of their fp64 copy), depth scale, direction count (clamped to 4..16), radius, coarse,
// jitter, the seed (when jittered) and the map's size. Not strength or mode.
template <class T>
std::uint64_t ao_map_key(const HeightView<T>& field, double depth_scale, const AoDesc& desc);
inline std::uint64_t ao_map_key(const HeightField& field, double depth_scale, const AoDesc& desc) {
  return ao_map_key(height_view(field), depth_scale, desc);
}

// The cached map of (field, depth_scale, desc) from cache_dir (e.g. default_cache_dir() of cone_map.hpp), or
// the bake, stored there through a temporary file and a rename. A cached file is used only if its header
// (magic, version, key, size) and payload checksum match and every value lies in [0, 1]; anything else is
// rebuilt and overwritten. A cache that cannot be written is not an error: a
// warning (qdmr/core/warning.hpp) names the entry and the OS reason.
template <class T>
Image load_or_bake_ao_map(const HeightView<T>& field, double depth_scale, const AoDesc& desc,
                          const std::filesystem::path& cache_dir, AoMapRow row = {});
inline Image load_or_bake_ao_map(const HeightField& field, double depth_scale, const AoDesc& desc,
                                 const std::filesystem::path& cache_dir, AoMapRow row = {}) {
  return load_or_bake_ao_map(height_view(field), depth_scale, desc, cache_dir, row);
}

}  // namespace qdmr
