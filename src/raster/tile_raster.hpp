#pragma once
// Rasterizes one screen tile: coarse 8x8 block rejection, then batches of 2x2 quads through the
// shading program with early depth test. Knows nothing about meshes or materials beyond program indices.
// Part of a draw kernel: compiled once per ISA.
#include "core/isa_namespace.hpp"
#include "raster/raster_context.hpp"

namespace qdmr::QDMR_ISA_NAMESPACE {

// Clears the tile's pixels, then draws every triangle binned to it, in submission order. The context's
// programs must be this kernel's ShadingPrograms.
void raster_tile(const RasterContext& context, int tile_index, const PixelRect& tile, const TileBins& bins,
                 TileCounters& counters);

}  // namespace qdmr::QDMR_ISA_NAMESPACE
