#pragma once
// The render targets of a frame: colour always, AOV planes only when asked for, and a depth plane only where
// something reads depth after its tile (keeps_depth_plane): the tiles test depth in a tile-sized plane of their
// own, in cache, and copy it out only then. Kept by the renderer from frame to frame (resize() keeps the memory
// when the size allows), so a warm frame touches no new pages. Never cleared as a whole: each tile clears its
// own AOV pixels before drawing (clear_aovs) and writes every colour pixel, the background where nothing covers
// it (raster_tile), in parallel.
#include <algorithm>
#include <array>
#include <cstddef>
#include <vector>

#include <glm/vec3.hpp>

#include "qdmr/core/aov.hpp"
#include "qdmr/core/pixel_buffer.hpp"

namespace qdmr {

// Whether a frame with these AOVs keeps a frame-sized depth plane: the reference summary counts the covered
// pixels (depth below the clear value), and the texture-cache replay adds misses at covered pixels only.
inline bool keeps_depth_plane(const std::vector<Aov>& aovs) {
  return std::any_of(aovs.begin(), aovs.end(), [](Aov a) { return is_reference_aov(a) || a == Aov::CacheMisses; });
}

struct Framebuffer {
  int width = 0, height = 0;
  glm::vec3 background{0.0f};
  PixelBuffer color;       // linear RGB, 3 per pixel, cleared to the background
  PixelBuffer depth;       // window depth in [0, 1] (1: uncovered), where keeps_depth_plane; else empty
  std::array<PixelBuffer, kAovCount> aov;  // indexed by Aov; aov_channels() per pixel; empty when not asked for

  // Sizes the planes for a frame. A plane keeps its memory when its size is unchanged; one larger than the frame
  // needs (a smaller frame, an AOV no longer asked for) is released, so the planes hold what the plan counts.
  void resize(int w, int h, const std::vector<Aov>& aovs) {
    width = w;
    height = h;
    const std::size_t pixels = std::size_t(w) * std::size_t(h);
    fit(color, pixels * 3);
    fit(depth, keeps_depth_plane(aovs) ? pixels : 0);
    std::array<bool, kAovCount> wanted{};
    for (Aov a : aovs) wanted[std::size_t(a)] = true;
    for (int a = 0; a < kAovCount; ++a)
      fit(aov[std::size_t(a)], wanted[std::size_t(a)] ? pixels * std::size_t(aov_channels(Aov(a))) : 0);
  }

  static void fit(PixelBuffer& plane, std::size_t size) {
    if (plane.capacity() > size) PixelBuffer().swap(plane);  // its values are overwritten by the tiles anyway
    plane.resize(size);
  }

  std::size_t index(int x, int y) const { return std::size_t(y) * std::size_t(width) + std::size_t(x); }
  void clear_aovs(int x0, int y0, int x1, int y1) {  // inclusive bounds
    const std::size_t n = std::size_t(x1 - x0 + 1);
    for (int y = y0; y <= y1; ++y) {
      const std::size_t first = index(x0, y);
      for (int a = 0; a < kAovCount; ++a) {
        PixelBuffer& plane = aov[std::size_t(a)];
        if (plane.empty()) continue;
        const std::size_t channels = std::size_t(aov_channels(Aov(a)));
        std::fill_n(plane.data() + channels * first, channels * n, 0.0f);
      }
    }
  }
  std::size_t bytes() const {
    std::size_t floats = color.size() + depth.size();
    for (const PixelBuffer& a : aov) floats += a.size();
    return floats * sizeof(float);
  }
};

}  // namespace qdmr
