#include "raster/binner.hpp"

#include <algorithm>

#include <tbb/parallel_for.h>

namespace qdmr {

void bin_triangles(const GeometryResult& geometry, const Viewport& viewport, const TileGrid& grid,
                   TileBins& result) {
  const std::size_t triangles = geometry.triangles.size();
  const std::size_t chunks = (triangles + TileBins::kTrianglesPerChunk - 1) / TileBins::kTrianglesPerChunk;
  result.bins.resize(chunks);
  tbb::parallel_for(std::size_t(0), chunks, [&](std::size_t c) {
    auto& bins = result.bins[c];
    bins.resize(std::size_t(grid.count()));
    for (auto& tile : bins) tile.clear();
    const std::size_t end = std::min(triangles, (c + 1) * TileBins::kTrianglesPerChunk);
    for (std::size_t i = c * TileBins::kTrianglesPerChunk; i < end; ++i) {
      const PixelRect b = triangle_bounds(geometry.triangles[i], viewport);
      if (b.empty()) continue;
      const int tx0 = b.x0 / grid.tile_size, tx1 = b.x1 / grid.tile_size;
      const int ty0 = b.y0 / grid.tile_size, ty1 = b.y1 / grid.tile_size;
      for (int ty = ty0; ty <= ty1; ++ty)
        for (int tx = tx0; tx <= tx1; ++tx) bins[std::size_t(ty * grid.tiles_x + tx)].push_back(std::uint32_t(i));
    }
  });
}

}  // namespace qdmr
