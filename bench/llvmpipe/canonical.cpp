// The textures of bench/llvmpipe/canonical.json, generated the way qdmr generates them, so both renderers march
// through the same height texels:
//   heights: qdmr's "cobbles" pattern (src/texture/procedural.cpp, copied below: integer hashes and IEEE
//            + - * / sqrt floor only, so the same bits on every machine), size 512, cells 8, seed 1,
//            mortar 0.08; stored as r16 (round to nearest of h * 65535) and sampled as code / 65535;
//   max chain: each texel of level k + 1 the largest of its 2x2 texels of level k (qdmr's max-quadtree);
//   normals: "from_height", central differences of the stored heights with wrap (src/texture/texture_level0.cpp);
//   albedo: lerp(color_low, color_high, h) times the per-stone brightness jitter, sRGB 8-bit.
// Normals and albedo only colour the image (the texel check compares hit UVs; their content does not change
// what a fetch costs), and their mip chains are glGenerateMipmap's rather than qdmr's box chains.
#include <algorithm>
#include <cmath>
#include <cstdint>
#include <vector>

#include "scene.hpp"

namespace llvmpipe_bench {
namespace {

// canonical.json's /materials/cobbles/layers/0: keep in step.
constexpr int kSide = 512, kCells = 8;
constexpr std::uint32_t kSeed = 1;
constexpr double kMortar = double(0.08f);  // qdmr reads the JSON number into a float
constexpr float kColorLow[3] = {0.2f, 0.19f, 0.18f}, kColorHigh[3] = {0.62f, 0.55f, 0.46f}, kVariation = 0.15f;
constexpr double kFromHeightDepth = 1.0 / 16.0;  // qdmr's texture_detail::kFromHeightDepth; normal_strength 1

// --- qdmr's src/texture/procedural.cpp ---
std::uint32_t mix(std::uint32_t h) {
  h ^= h >> 16;
  h *= 0x7feb352du;
  h ^= h >> 15;
  h *= 0x846ca68bu;
  h ^= h >> 16;
  return h;
}

std::uint32_t hash(std::uint32_t x, std::uint32_t y, std::uint32_t seed) { return mix(x + mix(y + mix(seed))); }

double unit(std::uint32_t h) { return double(h >> 8) * (1.0 / 16777216.0); }

int wrap(int i, int n) { return i < 0 ? i + n : (i >= n ? i - n : i); }

double clamp01(double x) { return std::min(1.0, std::max(0.0, x)); }

// Voronoi stones, `cells` per side, each a dome (circular profile) over its distance to the cell border.
struct Cobbles {
  int cells;
  double mortar;
  std::vector<double> px, py, value;  // feature point (in cell units, within its cell) and value per cell

  Cobbles(int n, double m, std::uint32_t seed) : cells(n), mortar(m) {
    px.resize(std::size_t(n) * std::size_t(n));
    py.resize(px.size());
    value.resize(px.size());
    for (int j = 0; j < n; ++j)
      for (int i = 0; i < n; ++i) {
        const std::uint32_t h = hash(std::uint32_t(i), std::uint32_t(j), seed);
        const std::size_t k = std::size_t(j) * std::size_t(n) + std::size_t(i);
        px[k] = 0.15 + 0.7 * double(h & 0xFFFFu) / 65536.0;
        py[k] = 0.15 + 0.7 * double(h >> 16) / 65536.0;
        value[k] = unit(hash(std::uint32_t(i), std::uint32_t(j), seed ^ 0x5bd1e995u));
      }
  }

  // Height and the stone's value (the albedo's jitter) at (u, v).
  void operator()(double u, double v, double& height, double& cell) const {
    const double x = u * cells, y = v * cells;
    const int ix = int(std::floor(x)), iy = int(std::floor(y));
    double qx[9], qy[9];
    std::size_t id[9];
    int nearest = 0;
    double best = 1e30;
    for (int k = 0; k < 9; ++k) {
      const int cx = ix + k % 3 - 1, cy = iy + k / 3 - 1;
      id[k] = std::size_t(wrap(cy, cells)) * std::size_t(cells) + std::size_t(wrap(cx, cells));
      qx[k] = cx + px[id[k]];
      qy[k] = cy + py[id[k]];
      const double d2 = (qx[k] - x) * (qx[k] - x) + (qy[k] - y) * (qy[k] - y);
      if (d2 < best) best = d2, nearest = k;
    }
    double edge = 1e30;
    for (int k = 0; k < 9; ++k) {
      if (k == nearest) continue;
      const double dx = qx[k] - qx[nearest], dy = qy[k] - qy[nearest];
      const double len = std::sqrt(dx * dx + dy * dy);
      const double mx = 0.5 * (qx[k] + qx[nearest]) - x, my = 0.5 * (qy[k] + qy[nearest]) - y;
      edge = std::min(edge, (mx * dx + my * dy) / len);
    }
    const double t = clamp01((edge - 0.5 * mortar) / 0.3);
    cell = value[id[nearest]];
    height = (0.8 + 0.2 * cell) * std::sqrt(t * (2.0 - t));
  }
};
// --- end of procedural.cpp ---

// qdmr's quantise_unorm16 (src/texture/mip_texture.cpp): round to nearest, ties up, after clamping to [0, 1].
std::uint16_t quantise_unorm16(float v) {
  if (!(v > 0.0f)) return 0;
  if (v >= 1.0f) return 65535;
  return std::uint16_t(std::floor(double(v) * 65535.0 + 0.5));
}

std::uint8_t unorm8(float v) { return std::uint8_t(std::floor(std::min(1.0f, std::max(0.0f, v)) * 255.0f + 0.5f)); }

std::uint8_t srgb8(float linear) {
  const float v = std::min(1.0f, std::max(0.0f, linear));
  return unorm8(v <= 0.0031308f ? v * 12.92f : 1.055f * std::pow(v, 1.0f / 2.4f) - 0.055f);
}

// qdmr's normals_from_height (src/texture/texture_level0.cpp) on the stored heights, as RGBA8 0.5 + 0.5 n.
std::vector<std::uint8_t> normals_from_height(const std::vector<float>& h, int side) {
  std::vector<std::uint8_t> out(std::size_t(side) * std::size_t(side) * 4);
  const double k = kFromHeightDepth * side * 0.5;
  const auto at = [&](int x, int y) { return double(h[std::size_t(y) * std::size_t(side) + std::size_t(x)]); };
  for (int y = 0; y < side; ++y)
    for (int x = 0; x < side; ++x) {
      const int up = (y + side - 1) % side, down = (y + 1) % side, left = (x + side - 1) % side, right = (x + 1) % side;
      const double nx = float(-k * (at(right, y) - at(left, y))), ny = float(-k * (at(x, down) - at(x, up)));
      const double inv = 1.0 / std::sqrt(nx * nx + ny * ny + 1.0);
      std::uint8_t* t = &out[(std::size_t(y) * std::size_t(side) + std::size_t(x)) * 4];
      t[0] = unorm8(0.5f + 0.5f * float(nx * inv));
      t[1] = unorm8(0.5f + 0.5f * float(ny * inv));
      t[2] = unorm8(0.5f + 0.5f * float(inv));
      t[3] = 255;
    }
  return out;
}

// Level k + 1 of the max chain from level k (power-of-two sides: every texel has exactly 2x2 children).
std::vector<float> max_reduce(const std::vector<float>& level, int side) {
  const int half = side / 2;
  std::vector<float> out(std::size_t(half) * std::size_t(half));
  const auto at = [&](int x, int y) { return level[std::size_t(y) * std::size_t(side) + std::size_t(x)]; };
  for (int y = 0; y < half; ++y)
    for (int x = 0; x < half; ++x)
      out[std::size_t(y) * std::size_t(half) + std::size_t(x)] = std::max(
          std::max(at(2 * x, 2 * y), at(2 * x + 1, 2 * y)), std::max(at(2 * x, 2 * y + 1), at(2 * x + 1, 2 * y + 1)));
  return out;
}

}  // namespace

SceneTextures canonical_textures() {
  SceneTextures t;
  t.side = kSide;
  t.albedo_srgb = true;
  t.albedo.resize(std::size_t(kSide) * kSide * 4);
  std::vector<float> stored(std::size_t(kSide) * kSide);
  const Cobbles cobbles(kCells, kMortar, kSeed);
  for (int y = 0; y < kSide; ++y) {
    const double v = (y + 0.5) / kSide;
    for (int x = 0; x < kSide; ++x) {
      double h = 0, cell = 0;
      cobbles((x + 0.5) / kSide, v, h, cell);
      const std::size_t i = std::size_t(y) * kSide + std::size_t(x);
      // qdmr keeps the pattern as float, then stores it as r16 and samples code / 65535.
      stored[i] = float(quantise_unorm16(float(h))) / 65535.0f;
      const float jitter = 1.0f + kVariation * (float(cell) - 0.5f);
      for (int c = 0; c < 3; ++c)
        t.albedo[i * 4 + std::size_t(c)] = srgb8((kColorLow[c] + (kColorHigh[c] - kColorLow[c]) * float(h)) * jitter);
      t.albedo[i * 4 + 3] = 255;
    }
  }
  t.normal = normals_from_height(stored, kSide);
  t.max_chain.push_back(std::move(stored));
  for (int side = kSide; side > 1; side /= 2) t.max_chain.push_back(max_reduce(t.max_chain.back(), side));
  return t;
}

}  // namespace llvmpipe_bench
