#pragma once
// Building blocks for rasterizer tests: triangles placed directly in screen space, a program that counts
// how often each pixel is shaded, and an independent scalar coverage test.
#include <cmath>
#include <cstdint>
#include <vector>

#include <tbb/parallel_for.h>

#include "kernel/batch.hpp"
#include "raster/binner.hpp"
#include "kernel/tile_raster.hpp"

namespace qdmr::test {

// Records every shaded pixel (tests run the tiles on one thread, so no synchronisation is needed).
class CountingProgram final : public ShadingProgram {
public:
  explicit CountingProgram(int width, int height)
      : ShadingProgram("counting", kBaseVaryingCount), width_(width), counts(std::size_t(width) * height, 0) {}
  void shade(const Fragments* const* in, ShadeOutput* const* out, int n) const override {
    for (int k = 0; k < n; ++k) shade_batch(*in[k], *out[k]);
  }
  void shade_batch(const Fragments& in, ShadeOutput& out) const {
    alignas(64) float x[simd::kLanes], y[simd::kLanes];
    in.pixel_x.store_aligned(x);
    in.pixel_y.store_aligned(y);
    const std::uint32_t bits = simd::to_bits(in.covered);
    for (int l = 0; l < simd::kLanes; ++l)
      if ((bits >> l) & 1u) ++counts[std::size_t(int(y[l]) * width_ + int(x[l]))];
    for (auto& c : out.color) c = simd::Float(1.0f);
    for (auto& n : out.normal) n = simd::Float(0.0f);
    out.iterations = out.hit_u = out.hit_v = out.hit_depth = out.error_texels = out.missed = simd::Float(0.0f);
    out.shadow = out.ao = simd::Float(1.0f);
  }
  int width_;
  mutable std::vector<int> counts;
};

// Screen-space triangles: each vertex (x, y) in pixels, z window depth; snapped like the geometry stage does.
struct ScreenScene {
  int width, height;
  GeometryResult geometry;

  ScreenScene(int w, int h) : width(w), height(h) {}

  // Returns false (and adds nothing) when the snapped triangle has zero area. Without an explicit z, each
  // triangle lies nearer than the previous one, so the depth test never hides a second hit on a pixel.
  bool add(double x0, double y0, double x1, double y1, double x2, double y2, float z = -1.0f) {
    if (z < 0.0f) z = 1.0f - 1e-5f * float(geometry.triangles.size() + 1);
    ScreenTriangle t;
    const double xs[3] = {x0, x1, x2}, ys[3] = {y0, y1, y2};
    for (int i = 0; i < 3; ++i) {
      t.x[i] = std::int32_t(std::floor(xs[i] * 256.0 + 0.5));
      t.y[i] = std::int32_t(std::floor(ys[i] * 256.0 + 0.5));
      ScreenVertex v{};
      v.inv_w = 1.0f;
      v.z = z;
      geometry.vertices.push_back(v);
      t.vertex[i] = std::uint32_t(geometry.vertices.size() - 1);
    }
    const std::int64_t area = std::int64_t(t.x[1] - t.x[0]) * (t.y[2] - t.y[0]) - std::int64_t(t.y[1] - t.y[0]) * (t.x[2] - t.x[0]);
    if (area == 0) return false;
    if (area < 0) {
      std::swap(t.x[1], t.x[2]);
      std::swap(t.y[1], t.y[2]);
      std::swap(t.vertex[1], t.vertex[2]);
    }
    t.material = 0;
    geometry.triangles.push_back(t);
    return true;
  }

  // Rasterizes every triangle with the counting program; returns the per-pixel shade counts.
  std::vector<int> raster_counts(int tile_size = 64) const {
    const Viewport viewport{width, height};
    const TileGrid grid(width, height, tile_size);
    TileBins bins;
    bin_triangles(geometry, viewport, grid, bins);
    Framebuffer fb;
    fb.width = width;
    fb.height = height;
    fb.color.resize(std::size_t(width) * height * 3);
    CountingProgram program(width, height);
    RasterContext context;
    context.geometry = &geometry;
    context.framebuffer = &fb;
    context.programs = {static_cast<const Program*>(&program)};
    for (int tile = 0; tile < grid.count(); ++tile) {
      TileCounters counters;
      raster_tile(context, tile, grid.rect(tile), bins, counters);
    }
    return program.counts;
  }
};

// Independent reference: does triangle t cover the centre of pixel (px, py) under the top-left rule?
// Written from the definition (orientation tests in 64-bit integers), not from the rasterizer's code.
inline bool reference_covers(const ScreenTriangle& t, int px, int py) {
  const std::int64_t X = std::int64_t(px) * 256 + 128, Y = std::int64_t(py) * 256 + 128;
  for (int e = 0; e < 3; ++e) {
    const std::int64_t ax = t.x[e], ay = t.y[e], bx = t.x[(e + 1) % 3], by = t.y[(e + 1) % 3];
    const std::int64_t side = (bx - ax) * (Y - ay) - (by - ay) * (X - ax);
    if (side > 0) continue;
    if (side < 0) return false;
    // On the edge: owned only by top edges (horizontal, interior below) and left edges (interior to the right).
    const bool top = by == ay && bx > ax;
    const bool left = by < ay;
    if (!(top || left)) return false;
  }
  return true;
}

}  // namespace qdmr::test
