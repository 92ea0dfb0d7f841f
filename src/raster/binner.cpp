#include "raster/binner.hpp"

namespace qdmr {

TileBins bin_triangles(const std::vector<TriangleSetup>& setups, const TileGrid& grid) {
  TileBins bins(std::size_t(grid.count()));
  for (std::uint32_t i = 0; i < setups.size(); ++i) {
    const PixelRect& b = setups[i].bounds;
    if (b.empty()) continue;
    const int tx0 = b.x0 / grid.tile_size, tx1 = b.x1 / grid.tile_size;
    const int ty0 = b.y0 / grid.tile_size, ty1 = b.y1 / grid.tile_size;
    for (int ty = ty0; ty <= ty1; ++ty)
      for (int tx = tx0; tx <= tx1; ++tx) bins[std::size_t(ty * grid.tiles_x + tx)].push_back(i);
  }
  return bins;
}

}  // namespace qdmr
