#pragma once
// What a draw kernel's tile rasterizer reads and writes, and the counters it keeps per tile. ISA-independent:
// the draw stage fills it, any kernel consumes it.
#include <algorithm>
#include <array>
#include <bit>
#include <cstdint>
#include <vector>

#include "program/program.hpp"
#include "qdmr/core/texture_cache.hpp"
#include "texture/cache_model.hpp"
#include "raster/binner.hpp"
#include "raster/framebuffer.hpp"
#include "raster/geometry.hpp"

namespace qdmr {

// A tile's scalar counters (TileCounters adds its iteration histogram).
struct TileCounts {
  std::uint64_t bin_entries = 0;       // triangles visited by this tile
  std::uint64_t blocks_rejected = 0;   // 8x8 blocks skipped by the coarse test
  std::uint64_t blocks_full = 0;       // 8x8 blocks entirely inside a triangle (no per-pixel edge test)
  std::uint64_t blocks_partial = 0;
  std::uint64_t batches_shaded = 0;    // program invocations
  std::uint64_t quads_shaded = 0;      // 2x2 quads with at least one written pixel
  std::uint64_t pixels_shaded = 0;     // lanes written (covered and passed the depth test)
  std::uint64_t pixels_depth_failed = 0;
  // Intersection loop iterations' lane use: useful = sum of the lanes' own iterations, executed = the batch's
  // longest lane times the lane count.
  std::uint64_t iterations_useful = 0, iterations_executed = 0;
  // The emulated texture cache (when on): texel reads replayed through it, and how many hit.
  std::uint64_t cache_accesses = 0, cache_hits = 0;
};

struct TileCounters : TileCounts {
  // Intersection loop iterations of the written pixels: histogram (last bin: that many or more). Bins
  // [0, histogram_bins) hold every count made since the counters were zero, so zeroing and summing touch only
  // those (a frame's tiles are kept and zeroed in parallel; most programs fill bin 0 alone).
  static constexpr int kIterationBins = 1024;
  std::array<std::uint64_t, kIterationBins + 1> iteration_histogram{};
  int histogram_bins = 0;

  static int bin_of(std::uint64_t n) { return int(std::min<std::uint64_t>(n, kIterationBins)); }
  // `lanes` written pixels that ran n iterations each.
  void count_iterations(std::uint64_t n, std::uint64_t lanes) {
    const int bin = bin_of(n);
    iteration_histogram[std::size_t(bin)] += lanes;
    histogram_bins = std::max(histogram_bins, bin + 1);
  }
  // The lanes set in `pass`, lane l having run iterations[l] (whole numbers): each in its bin, and their sum in
  // iterations_useful. The sum and the histogram's bound stay in registers and are stored once: updated in the
  // members lane by lane (the histogram may alias them), each lane waited on the last one's store, a third of
  // the tile write's time in a QDM frame.
  void count_lanes(const float* iterations, std::uint32_t pass) {
    std::uint64_t useful = 0;
    int bins = histogram_bins;
    for (; pass != 0; pass &= pass - 1) {
      const auto n = std::uint64_t(iterations[std::countr_zero(pass)]);
      const int bin = bin_of(n);
      useful += n;
      ++iteration_histogram[std::size_t(bin)];
      bins = std::max(bins, bin + 1);
    }
    iterations_useful += useful;
    histogram_bins = bins;
  }
  // Back to all zero.
  void reset();
  TileCounters& operator+=(const TileCounters& o);
};

struct RasterContext {
  const GeometryResult* geometry = nullptr;
  std::vector<const Program*> programs;  // indexed by ScreenTriangle::material; made by the kernel that rasterizes
  Framebuffer* framebuffer = nullptr;
  // The emulated texture cache, or null (off): its settings and the address of every texture the programs read.
  const TextureCacheDesc* cache = nullptr;
  const TextureAddressMap* cache_addresses = nullptr;
};

}  // namespace qdmr
