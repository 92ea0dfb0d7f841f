#include "raster/raster_context.hpp"

#include <algorithm>

namespace qdmr {

void TileCounters::reset() {
  static_cast<TileCounts&>(*this) = TileCounts{};
  std::fill_n(iteration_histogram.begin(), histogram_bins, std::uint64_t(0));
  histogram_bins = 0;
}

TileCounters& TileCounters::operator+=(const TileCounters& o) {
  bin_entries += o.bin_entries;
  blocks_rejected += o.blocks_rejected;
  blocks_full += o.blocks_full;
  blocks_partial += o.blocks_partial;
  batches_shaded += o.batches_shaded;
  quads_shaded += o.quads_shaded;
  pixels_shaded += o.pixels_shaded;
  pixels_depth_failed += o.pixels_depth_failed;
  for (int i = 0; i < o.histogram_bins; ++i) iteration_histogram[std::size_t(i)] += o.iteration_histogram[std::size_t(i)];
  histogram_bins = std::max(histogram_bins, o.histogram_bins);
  iterations_useful += o.iterations_useful;
  iterations_executed += o.iterations_executed;
  cache_accesses += o.cache_accesses;
  cache_hits += o.cache_hits;
  return *this;
}

}  // namespace qdmr
