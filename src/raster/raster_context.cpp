#include "raster/raster_context.hpp"

namespace qdmr {

TileCounters& TileCounters::operator+=(const TileCounters& o) {
  bin_entries += o.bin_entries;
  blocks_rejected += o.blocks_rejected;
  blocks_full += o.blocks_full;
  blocks_partial += o.blocks_partial;
  batches_shaded += o.batches_shaded;
  quads_shaded += o.quads_shaded;
  pixels_shaded += o.pixels_shaded;
  pixels_depth_failed += o.pixels_depth_failed;
  for (std::size_t i = 0; i < iteration_histogram.size(); ++i) iteration_histogram[i] += o.iteration_histogram[i];
  iterations_useful += o.iterations_useful;
  iterations_executed += o.iterations_executed;
  cache_accesses += o.cache_accesses;
  cache_hits += o.cache_hits;
  return *this;
}

}  // namespace qdmr
