#pragma once
// Binning: each triangle goes to every screen tile its bounds touch, in submission order.
#include <cstdint>
#include <vector>

#include "raster/triangle_setup.hpp"

namespace qdmr {

struct TileGrid {
  int width = 0, height = 0;  // viewport in pixels
  int tile_size = 64;
  int tiles_x = 0, tiles_y = 0;

  TileGrid(int w, int h, int tile) : width(w), height(h), tile_size(tile), tiles_x((w + tile - 1) / tile), tiles_y((h + tile - 1) / tile) {}
  int count() const { return tiles_x * tiles_y; }
  PixelRect rect(int tile) const {
    const int tx = tile % tiles_x, ty = tile / tiles_x;
    PixelRect r;
    r.x0 = tx * tile_size;
    r.y0 = ty * tile_size;
    r.x1 = std::min(width, r.x0 + tile_size) - 1;
    r.y1 = std::min(height, r.y0 + tile_size) - 1;
    return r;
  }
};

// Triangle indices (into the geometry's triangles) per chunk of consecutive triangles and per tile: bins[chunk][tile].
// Chunks are binned in parallel; a tile reads its lists chunk by chunk, which is submission order.
struct TileBins {
  static constexpr std::size_t kTrianglesPerChunk = 32768;
  std::vector<std::vector<std::vector<std::uint32_t>>> bins;

  template <class F>
  void for_each_in_tile(int tile, F&& f) const {
    for (const auto& chunk : bins)
      for (std::uint32_t index : chunk[std::size_t(tile)]) f(index);
  }
};

// Bins every triangle of `geometry` by its bounds. Replaces the lists of `bins`; their memory is kept, so a caller
// that keeps `bins` between frames allocates nothing in a warm frame.
void bin_triangles(const GeometryResult& geometry, const Viewport& viewport, const TileGrid& grid, TileBins& bins);

}  // namespace qdmr
