#pragma once
// The render targets of a frame: colour and depth always, AOV planes only when asked for. Kept by the renderer
// from frame to frame (resize() keeps the memory when the size allows), so a warm frame touches no new pages.
// Never cleared as a whole: each tile clears its own pixels before drawing (clear_rect), in parallel.
#include <array>
#include <cstddef>
#include <vector>

#include <glm/vec3.hpp>

#include "qdmr/core/aov.hpp"
#include "qdmr/core/pixel_buffer.hpp"

namespace qdmr {

struct Framebuffer {
  int width = 0, height = 0;
  glm::vec3 background{0.0f};
  PixelBuffer color;       // linear RGB, 3 per pixel, cleared to the background
  PixelBuffer depth;       // window depth in [0, 1], cleared to 1
  std::array<PixelBuffer, kAovCount> aov;  // indexed by Aov; aov_channels() per pixel; empty when not asked for

  // Sizes the planes for a frame; AOV planes not asked for are emptied but keep their memory.
  void resize(int w, int h, const std::vector<Aov>& aovs) {
    width = w;
    height = h;
    const std::size_t pixels = std::size_t(w) * std::size_t(h);
    color.resize(pixels * 3);
    depth.resize(pixels);
    std::array<bool, kAovCount> wanted{};
    for (Aov a : aovs) wanted[std::size_t(a)] = true;
    for (int a = 0; a < kAovCount; ++a)
      aov[std::size_t(a)].resize(wanted[std::size_t(a)] ? pixels * std::size_t(aov_channels(Aov(a))) : 0);
  }

  std::size_t index(int x, int y) const { return std::size_t(y) * std::size_t(width) + std::size_t(x); }
  void clear_rect(int x0, int y0, int x1, int y1) {  // inclusive bounds
    for (int y = y0; y <= y1; ++y)
      for (int x = x0; x <= x1; ++x) {
        const std::size_t i = index(x, y);
        color[3 * i] = background.x;
        color[3 * i + 1] = background.y;
        color[3 * i + 2] = background.z;
        depth[i] = 1.0f;
        for (int a = 0; a < kAovCount; ++a) {
          if (aov[std::size_t(a)].empty()) continue;
          const std::size_t n = std::size_t(aov_channels(Aov(a)));
          for (std::size_t c = 0; c < n; ++c) aov[std::size_t(a)][n * i + c] = 0.0f;
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
