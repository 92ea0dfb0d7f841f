#pragma once
// Rasterizes one screen tile: coarse 8x8 block rejection, then batches of 2x2 quads through the
// shading program with early depth test. Knows nothing about meshes or materials beyond program indices.
// Part of a draw kernel: compiled once per ISA.
#include "core/isa_namespace.hpp"
#include "raster/raster_context.hpp"

namespace qdmr::QDMR_ISA_NAMESPACE {

// Draws every triangle binned to the tile, in submission order, over the background; writes every colour pixel of
// the tile (and clears its AOV pixels first). The context's programs must be this kernel's ShadingPrograms.
void raster_tile(const RasterContext& context, int tile_index, const PixelRect& tile, const TileBins& bins,
                 TileCounters& counters);

}  // namespace qdmr::QDMR_ISA_NAMESPACE
