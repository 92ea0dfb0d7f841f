#include "texture/blend_weights.hpp"

#include <algorithm>
#include <cmath>

#include <tbb/blocked_range.h>
#include <tbb/parallel_for.h>

#include "qdmr/texture/texture_level0.hpp"

namespace qdmr {
namespace {

double wrap(double x, int n) {
  const double r = std::fmod(x, double(n));
  return r < 0.0 ? r + n : r;
}

// Bilinear sample of channel c at texel coordinates (x, y) (centres at i + 0.5), wrapping.
float bilinear(const Image& map, double x, double y, int c) {
  x = wrap(x - 0.5, map.width);
  y = wrap(y - 0.5, map.height);
  const int x0 = int(x), y0 = int(y);
  const int x1 = (x0 + 1) % map.width, y1 = (y0 + 1) % map.height;
  const double fx = x - x0, fy = y - y0;
  const double top = map.at(x0, y0, c) * (1.0 - fx) + map.at(x1, y0, c) * fx;
  const double bottom = map.at(x0, y1, c) * (1.0 - fx) + map.at(x1, y1, c) * fx;
  return float(top * (1.0 - fy) + bottom * fy);
}

double clamp01(double x) { return std::clamp(x, 0.0, 1.0); }

// Scales each texel's weights so that the largest is 1 (all-zero texels go to layer 0).
void normalise_to_strongest(Image& map, int layers) {
  for (int y = 0; y < map.height; ++y)
    for (int x = 0; x < map.width; ++x) {
      float top = 0.0f;
      for (int i = 0; i < layers; ++i) top = std::max(top, map.at(x, y, i));
      if (!(top > 0.0f)) {
        map.at(x, y, 0) = 1.0f;
        continue;
      }
      for (int i = 0; i < layers; ++i) map.at(x, y, i) /= top;
    }
}

Image noise_map(const WeightsDesc& desc, int layers) {
  const int side = std::max(desc.resolution, 64);
  Image map(side, side, 4);
  for (int i = 0; i < layers; ++i) {
    ProceduralDesc p;
    p.pattern = ProceduralPattern::Noise;
    p.size = 1;
    while (p.size < side) p.size *= 2;
    p.seed = desc.seed * 4u + std::uint32_t(i);
    p.cells = desc.cells;
    p.octaves = 2;
    const Image noise = generate_procedural(p);
    for (int y = 0; y < side; ++y)
      for (int x = 0; x < side; ++x) {
        double w = bilinear(noise, (x + 0.5) * noise.width / side, (y + 0.5) * noise.height / side, 0);
        double powered = 1.0;
        for (int k = 0; k < desc.sharpness; ++k) powered *= w;  // integer power: exact and the same everywhere
        map.at(x, y, i) = float(powered);
      }
  }
  normalise_to_strongest(map, layers);
  return map;
}

// Terrain rules over a height map: rock (layer 0) on slopes, sand (2) low down, dirt (3) in noise patches,
// grass (1) elsewhere, each rule a linear ramp so the weights change smoothly.
Image terrain_map(const WeightsDesc& desc, int layers, const std::string& where) {
  LayerDesc layer;
  layer.height = desc.height;
  const Image h = make_layer_height(layer, where + "/height");
  float lo = 1.0f, hi = 0.0f;
  for (float v : h.texels) lo = std::min(lo, v), hi = std::max(hi, v);
  const double range = hi > lo ? double(hi) - lo : 1.0;
  ProceduralDesc p;
  p.pattern = ProceduralPattern::Noise;
  p.size = 256;
  p.seed = desc.seed;
  p.cells = desc.cells;
  p.octaves = 3;
  const Image noise = generate_procedural(p);
  Image map(h.width, h.height, 4);
  tbb::parallel_for(0, h.height, [&](int y) {  // texels alone: the same bits on any thread count
    for (int x = 0; x < h.width; ++x) {
      const auto at = [&](int i, int j) { return double(h.at(std::clamp(i, 0, h.width - 1), std::clamp(j, 0, h.height - 1), 0)); };
      // Slope in height units per map width, times the relief (vertical extent over width).
      const double gx = (at(x + 1, y) - at(x - 1, y)) * 0.5 * h.width * desc.relief;
      const double gy = (at(x, y + 1) - at(x, y - 1)) * 0.5 * h.height * desc.relief;
      const double slope = std::sqrt(gx * gx + gy * gy);
      const double elevation = (at(x, y) - lo) / range;
      const double rock = clamp01((slope - desc.slope) / (0.5 * desc.slope) + 0.5);
      const double sand = clamp01((desc.low - elevation) / (0.25 * std::max(desc.low, 1e-3f)) + 0.5);
      const double patch = bilinear(noise, (x + 0.5) * noise.width / h.width, (y + 0.5) * noise.height / h.height, 0);
      const double dirt = clamp01((patch - 0.55) * 8.0);
      const double w[4] = {rock, (1 - rock) * (1 - sand) * (1 - dirt), (1 - rock) * sand, (1 - rock) * (1 - sand) * dirt};
      for (int i = 0; i < layers; ++i) map.at(x, y, i) = float(w[i]);
    }
  });
  normalise_to_strongest(map, layers);
  return map;
}

}  // namespace

Image make_weight_map(const WeightsDesc& desc, int layers, const std::string& where) {
  switch (desc.source) {
    case WeightSource::Noise: return noise_map(desc, layers);
    case WeightSource::Terrain: return terrain_map(desc, layers, where);
    case WeightSource::File: {
      const Image file = read_image(desc.file, where + "/file");
      Image map(file.width, file.height, 4);
      for (int y = 0; y < file.height; ++y)
        for (int x = 0; x < file.width; ++x)
          for (int i = 0; i < std::min(file.channels, 4); ++i) map.at(x, y, i) = std::clamp(file.at(x, y, i), 0.0f, 1.0f);
      return map;
    }
  }
  return {};
}

Image resample_weight_map(const Image& map, int resolution) {
  Image level0(resolution, resolution, 4);
  tbb::parallel_for(0, resolution, [&](int y) {  // texels alone: the same bits on any thread count
    for (int x = 0; x < resolution; ++x)
      for (int c = 0; c < 4; ++c)
        level0.at(x, y, c) = bilinear(map, (x + 0.5) * map.width / resolution, (y + 0.5) * map.height / resolution, c);
  });
  return level0;
}

Texture make_weight_texture(const Image& level0, MipExtremum extremum) {
  return make_mip_texture(level0, TexelFormat::RGBA8, false, MipReduce::Max, extremum);
}

void rasterize_vertex_weights(const std::vector<glm::vec2>& uvs, const std::vector<std::uint32_t>& indices,
                              const std::vector<glm::vec4>& weights, float scale, Image& texture) {
  const double sx = texture.width / double(scale), sy = texture.height / double(scale);
  for (std::size_t t = 0; t + 2 < indices.size(); t += 3) {
    glm::dvec2 p[3];
    for (int k = 0; k < 3; ++k) p[k] = glm::dvec2(uvs[indices[t + std::size_t(k)]].x * sx, uvs[indices[t + std::size_t(k)]].y * sy);
    const double area = (p[1].x - p[0].x) * (p[2].y - p[0].y) - (p[2].x - p[0].x) * (p[1].y - p[0].y);
    if (!(std::abs(area) > 0.0) || !std::isfinite(area)) continue;
    const double lo_x = std::min({p[0].x, p[1].x, p[2].x}), hi_x = std::max({p[0].x, p[1].x, p[2].x});
    const double lo_y = std::min({p[0].y, p[1].y, p[2].y}), hi_y = std::max({p[0].y, p[1].y, p[2].y});
    if (hi_x - lo_x > 4.0 * texture.width || hi_y - lo_y > 4.0 * texture.height) continue;  // wraps many times: skip
    for (int j = int(std::ceil(lo_y - 0.5)); j + 0.5 <= hi_y; ++j)
      for (int i = int(std::ceil(lo_x - 0.5)); i + 0.5 <= hi_x; ++i) {
        const glm::dvec2 c(i + 0.5, j + 0.5);
        // Barycentrics by edge functions; centres on an edge belong to both triangles (the later one wins).
        const double b0 = ((p[1].x - c.x) * (p[2].y - c.y) - (p[2].x - c.x) * (p[1].y - c.y)) / area;
        const double b1 = ((p[2].x - c.x) * (p[0].y - c.y) - (p[0].x - c.x) * (p[2].y - c.y)) / area;
        const double b2 = 1.0 - b0 - b1;
        if (b0 < 0.0 || b1 < 0.0 || b2 < 0.0) continue;
        const int x = ((i % texture.width) + texture.width) % texture.width;
        const int y = ((j % texture.height) + texture.height) % texture.height;
        const glm::vec4& w0 = weights[indices[t]];
        const glm::vec4& w1 = weights[indices[t + 1]];
        const glm::vec4& w2 = weights[indices[t + 2]];
        for (int ch = 0; ch < 4; ++ch) texture.at(x, y, ch) = float(b0 * w0[ch] + b1 * w1[ch] + b2 * w2[ch]);
      }
  }
}

std::vector<glm::vec4> vertex_weights(const Image& map, const std::vector<glm::vec2>& uvs, float scale) {
  std::vector<glm::vec4> out(uvs.size());
  for (std::size_t k = 0; k < uvs.size(); ++k) {
    const double x = double(uvs[k].x) / scale * map.width, y = double(uvs[k].y) / scale * map.height;
    for (int c = 0; c < 4; ++c) out[k][c] = bilinear(map, x, y, c);
  }
  return out;
}

HeightField combined_surface(const std::vector<const Texture*>& heights, const Texture& weights, int scale,
                             BlendOperator op) {
  // Level 0 of the textures decoded once: the layers' heights and the RGBA weights.
  const int lw = heights[0]->width(), lh = heights[0]->height(), layers = int(heights.size());
  std::vector<float> h(std::size_t(layers) * std::size_t(lw) * std::size_t(lh));
  tbb::parallel_for(0, layers * lh, [&](int row) {
    const int i = row / lh, y = row % lh;
    for (int x = 0; x < lw; ++x) h[(std::size_t(i) * lh + y) * lw + x] = heights[std::size_t(i)]->texel(0, x, y, 0);
  });
  Image w(weights.width(), weights.height(), 4);
  tbb::parallel_for(0, w.height, [&](int y) {
    for (int x = 0; x < w.width; ++x)
      for (int c = 0; c < 4; ++c) w.at(x, y, c) = weights.texel(0, x, y, c);
  });
  // Weight-texture indices: floor(x) of a coordinate in [-0.5, n - 0.5) lies in [-1, n - 1], and its successor in
  // [0, n]: one step wraps them (no integer division per texel: those were most of this loop's time).
  const auto wrap_index = [](int i, int n) { return i < 0 ? i + n : i >= n ? i - n : i; };

  HeightField field;
  field.width = lw * scale;
  field.height = lh * scale;
  field.h = ZeroedBuffer<double>(std::size_t(field.width) * std::size_t(field.height));  // zero pages: the rows' threads commit them
  // The weights at the texel centre, bilinear at weight-texture coordinates (x + 0.5) / (W scale) - 0.5; the
  // fraction is taken before wrapping, so it is exact on both sides of 0 (the texture unit's arithmetic). What
  // depends on x alone is the same in every row: computed once per column.
  struct Column {
    int xa, xb;  // weight texels left and right
    double fx;
  };
  std::vector<Column> columns(std::size_t(field.width));
  for (int x = 0; x < field.width; ++x) {
    const double wx = (x + 0.5) / field.width * w.width - 0.5;
    const int x0 = int(std::floor(wx));
    columns[std::size_t(x)] = {wrap_index(x0, w.width), wrap_index(x0 + 1, w.width), wx - x0};
  }
  const std::size_t width = std::size_t(field.width), repeat = std::size_t(lw);
  // The first step of the bilinear weights, along weight row r: w(xa, r, i) (1 - fx) + w(xb, r, i) fx for every
  // layer i and column. A field row interpolates two of them (rows ya and yb) by fy; the `scale` field rows between
  // two weight rows share them, so a band of rows makes them again only when ya changes.
  const auto along_row = [&](int r, std::vector<double>& out) {
    for (int i = 0; i < layers; ++i)
      for (std::size_t x = 0; x < width; ++x) {
        const Column& c = columns[x];
        out[std::size_t(i) * width + x] = double(w.at(c.xa, r, i)) * (1 - c.fx) + double(w.at(c.xb, r, i)) * c.fx;
      }
  };
  tbb::parallel_for(tbb::blocked_range<int>(0, field.height), [&](const tbb::blocked_range<int>& rows) {
    std::vector<double> a(std::size_t(layers) * width), b(a.size()), sum_wh, sum_w;
    int held = -1;  // the ya of a and b
    for (int y = rows.begin(); y < rows.end(); ++y) {
      const double wy = (y + 0.5) / field.height * w.height - 0.5;
      const int y0 = int(std::floor(wy));
      const double fy = wy - y0;
      const int ya = wrap_index(y0, w.height), yb = wrap_index(y0 + 1, w.height);  // yb follows from ya
      if (ya != held) along_row(ya, a), along_row(yb, b), held = ya;
      const float* layer_row = h.data() + std::size_t(y % lh) * repeat;
      // Layer after layer, each texel's operations those of the per-texel formula, in its order; the layers'
      // texels repeat every lw columns.
      const auto each = [&](auto&& add) {
        for (int i = 0; i < layers; ++i) {
          const double* ai = a.data() + std::size_t(i) * width;
          const double* bi = b.data() + std::size_t(i) * width;
          const float* hi = layer_row + std::size_t(i) * std::size_t(lh) * repeat;
          for (std::size_t x0 = 0; x0 < width; x0 += repeat)
            for (std::size_t x = x0; x < x0 + repeat; ++x) {
              const double wi = ai[x] * (1 - fy) + bi[x] * fy;
              add(x, wi, wi * double(hi[x - x0]));
            }
        }
      };
      double* out = field.h.data() + std::size_t(y) * width;  // zero until written
      if (op != BlendOperator::Alpha) {
        each([&](std::size_t x, double, double p) { out[x] = out[x] < p ? p : out[x]; });  // std::max, from 0
      } else {
        sum_wh.assign(width, 0.0), sum_w.assign(width, 0.0);
        each([&](std::size_t x, double wi, double p) { sum_wh[x] += p, sum_w[x] += wi; });
        for (std::size_t x = 0; x < width; ++x) out[x] = sum_w[x] > 0.0 ? sum_wh[x] / sum_w[x] : 0.0;
      }
    }
  });
  return field;
}

template <class T>
Texture combined_quadtree(const HeightView<T>& surface, MipExtremum extremum) {
  Image level1(surface.width / 2, surface.height / 2, 1);
  const auto at = [&](int x, int y) {
    return double(surface.h[std::size_t(y) * std::size_t(surface.width) + std::size_t(x)]);
  };
  tbb::parallel_for(0, level1.height, [&](int y) {
    for (int x = 0; x < level1.width; ++x) {
      const double top = std::max(std::max(at(2 * x, 2 * y), at(2 * x + 1, 2 * y)),
                                  std::max(at(2 * x, 2 * y + 1), at(2 * x + 1, 2 * y + 1)));
      // Rounded up to a 16-bit step, with a margin over the shader's fp32 arithmetic (errors ~1e-7), so the
      // quantisation in make_mip_texture keeps it: the tree stays above the surface.
      level1.at(x, y, 0) = float(std::min(1.0, std::ceil((top + 1e-6) * 65535.0) / 65535.0));
    }
  });
  return make_mip_texture(level1, TexelFormat::R16, false, MipReduce::Max, extremum);
}

template Texture combined_quadtree(const HeightView<double>&, MipExtremum);
template Texture combined_quadtree(const HeightView<float>&, MipExtremum);

}  // namespace qdmr
