#pragma once
// The render targets of one frame: colour and depth always, AOV planes only when asked for.
#include <cstddef>
#include <vector>

namespace qdmr {

struct Framebuffer {
  int width = 0, height = 0;
  std::vector<float> color;       // linear RGB, 3 per pixel
  std::vector<float> depth;       // window depth in [0, 1], cleared to 1
  std::vector<float> view_depth;  // AOV "depth": distance along the view axis, 0 where empty (may be empty)
  std::vector<float> normal;      // AOV "normal": world-space shading normal, 3 per pixel (may be empty)
  std::vector<float> uv;          // AOV "uv": 2 per pixel (may be empty)

  std::size_t index(int x, int y) const { return std::size_t(y) * std::size_t(width) + std::size_t(x); }
  std::size_t bytes() const {
    return (color.size() + depth.size() + view_depth.size() + normal.size() + uv.size()) * sizeof(float);
  }
};

}  // namespace qdmr
