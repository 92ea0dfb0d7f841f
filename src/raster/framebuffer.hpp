#pragma once
// The render targets of one frame: colour and depth always, AOV planes only when asked for. Allocated
// uninitialised; each tile clears its own pixels before drawing (clear_rect), so clearing runs in parallel.
#include <array>
#include <cstddef>

#include <glm/vec3.hpp>

#include "qdmr/render/pixel_buffer.hpp"
#include "qdmr/render/render.hpp"

namespace qdmr {

struct Framebuffer {
  int width = 0, height = 0;
  glm::vec3 background{0.0f};
  PixelBuffer color;       // linear RGB, 3 per pixel, cleared to the background
  PixelBuffer depth;       // window depth in [0, 1], cleared to 1
  std::array<PixelBuffer, kAovCount> aov;  // indexed by Aov; aov_channels() per pixel; empty when not asked for

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
