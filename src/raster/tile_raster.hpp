#pragma once
// Rasterizes one screen tile: coarse 8x8 block rejection, then batches of 2x2 quads through the
// shading program with early depth test. Knows nothing about meshes or materials beyond program indices.
#include <array>
#include <cstdint>
#include <vector>

#include "raster/binner.hpp"
#include "raster/framebuffer.hpp"
#include "shade/program.hpp"

namespace qdmr {

struct TileCounters {
  std::uint64_t bin_entries = 0;       // triangles visited by this tile
  std::uint64_t blocks_rejected = 0;   // 8x8 blocks skipped by the coarse test
  std::uint64_t blocks_full = 0;       // 8x8 blocks entirely inside a triangle (no per-pixel edge test)
  std::uint64_t blocks_partial = 0;
  std::uint64_t batches_shaded = 0;    // program invocations
  std::uint64_t quads_shaded = 0;      // 2x2 quads with at least one written pixel
  std::uint64_t pixels_shaded = 0;     // lanes written (covered and passed the depth test)
  std::uint64_t pixels_depth_failed = 0;
  // Intersection loop iterations of the written pixels: histogram (last bin: that many or more), and lane
  // use: useful = sum of the lanes' own iterations, executed = the batch's longest lane times the lane count.
  static constexpr int kIterationBins = 1024;
  std::array<std::uint64_t, kIterationBins + 1> iteration_histogram{};
  std::uint64_t iterations_useful = 0, iterations_executed = 0;

  TileCounters& operator+=(const TileCounters& o);
};

struct RasterContext {
  const GeometryResult* geometry = nullptr;
  const TriangleSetups* setups = nullptr;
  std::vector<const ShadingProgram*> programs;  // indexed by TriangleSetup::material
  Framebuffer* framebuffer = nullptr;
};

// Clears the tile's pixels, then draws every triangle binned to it, in submission order.
void raster_tile(const RasterContext& context, int tile_index, const PixelRect& tile, const TileBins& bins,
                 TileCounters& counters);

}  // namespace qdmr
