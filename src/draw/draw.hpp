#pragma once
// The draw stage: a prepared frame into a framebuffer — geometry, triangle setup, binning, then the tiles in
// parallel through the chosen kernel's rasterizer and programs. Reads the plan and the assets, writes only the
// framebuffer and the stats.
#include <functional>
#include <memory>
#include <vector>

#include "kernel/kernel.hpp"
#include "prepare/assets.hpp"
#include "qdmr/core/stats.hpp"
#include "raster/binner.hpp"
#include "raster/framebuffer.hpp"
#include "raster/geometry.hpp"
#include "raster/triangle_setup.hpp"

namespace qdmr {

struct DrawOptions {
  int tile_size = 64;  // pixels, a multiple of 8
  // Called with the fraction of tiles done, from any worker thread, never concurrently with itself. Optional.
  std::function<void(double fraction)> progress;
};

// One program per plan material, made by `kernel` from the prepared assets; their exact reference hits are
// remembered in `memo` when one is given.
std::vector<std::unique_ptr<Program>> make_programs(const FramePlan& plan, const Assets& assets, const Kernel& kernel,
                                                    ReferenceMemo* memo = nullptr);

// The per-triangle arrays of a frame (screen vertices and triangles, tile bins). Kept between draws (of
// one scene or the next), their pages are reused: a frame of a million triangles otherwise faults in ~270 MB of
// fresh pages.
struct DrawScratch {
  GeometryScratch geometry_scratch;
  GeometryResult geometry;
  TileBins bins;
  std::vector<TileCounters> tile_counters;  // one per tile, zeroed by its tile at the start of each draw

  std::uint64_t bytes() const;  // the arrays' capacity
};

// Draws into `fb` (sized and its background set here; its memory is kept when large enough) and fills the draw
// part of `stats` (timings, counters, the reference summary), with `scratch`'s arrays. Runs in the caller's task
// arena.
void draw(const FramePlan& plan, const Assets& assets, const Kernel& kernel,
          const std::vector<std::unique_ptr<Program>>& programs, Framebuffer& fb, DrawScratch& scratch,
          const DrawOptions& options, RenderStats& stats);

}  // namespace qdmr
