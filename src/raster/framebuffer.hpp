#pragma once
// The render targets of one frame: colour and depth always, AOV planes only when asked for. Allocated
// uninitialised; each tile clears its own pixels before drawing (clear_rect), so clearing runs in parallel.
#include <cstddef>

#include <glm/vec3.hpp>

#include "qdmr/render/pixel_buffer.hpp"

namespace qdmr {

struct Framebuffer {
  int width = 0, height = 0;
  glm::vec3 background{0.0f};
  PixelBuffer color;       // linear RGB, 3 per pixel, cleared to the background
  PixelBuffer depth;       // window depth in [0, 1], cleared to 1
  PixelBuffer view_depth;  // AOV "depth": distance along the view axis, 0 where empty (may be empty)
  PixelBuffer normal;      // AOV "normal": world-space shading normal, 3 per pixel (may be empty)
  PixelBuffer uv;          // AOV "uv": 2 per pixel (may be empty)

  std::size_t index(int x, int y) const { return std::size_t(y) * std::size_t(width) + std::size_t(x); }
  void clear_rect(int x0, int y0, int x1, int y1) {  // inclusive bounds
    for (int y = y0; y <= y1; ++y)
      for (int x = x0; x <= x1; ++x) {
        const std::size_t i = index(x, y);
        color[3 * i] = background.x;
        color[3 * i + 1] = background.y;
        color[3 * i + 2] = background.z;
        depth[i] = 1.0f;
        if (!view_depth.empty()) view_depth[i] = 0.0f;
        if (!normal.empty()) normal[3 * i] = normal[3 * i + 1] = normal[3 * i + 2] = 0.0f;
        if (!uv.empty()) uv[2 * i] = uv[2 * i + 1] = 0.0f;
      }
  }
  std::size_t bytes() const {
    return (color.size() + depth.size() + view_depth.size() + normal.size() + uv.size()) * sizeof(float);
  }
};

}  // namespace qdmr
