// Cone-map bakers: the exact definitions of include/qdmr/bake/cone_map.hpp, by brute force and by a pruned walk
// of a max hierarchy. Both evaluate every candidate with the same expression (candidate_ratio), so they agree
// bit for bit; the hierarchy only skips candidates it can prove are not below the current minimum.
#include "qdmr/bake/cone_map.hpp"

#include <tbb/blocked_range.h>
#include <tbb/parallel_for.h>

#include <algorithm>
#include <array>
#include <cmath>
#include <limits>
#include <string>

#include "qdmr/core/error.hpp"
#include "qdmr/core/progress.hpp"

namespace qdmr {
namespace {

// Along one axis, where a candidate's constraint lies relative to its texel q:
//   Cell   the texel's square (conservative; and the cross axis of a wall)
//   Plus   the wall on q's +side, which binds p only when p's square is on q's side of it (p <= q)
//   Minus  the wall on q's -side, binding when p >= q
enum class Gap : std::uint8_t { Cell, Plus, Minus };

struct Channel {
  Gap gx, gy;
};

// Relaxed walls, one channel per direction of the step down: the wall at q's +x, -x, +y, -y side.
constexpr std::array<Channel, 4> kWallChannels{
    {{Gap::Plus, Gap::Cell}, {Gap::Minus, Gap::Cell}, {Gap::Cell, Gap::Plus}, {Gap::Cell, Gap::Minus}}};

int positive_mod(int a, int n) {
  const int m = a % n;
  return m < 0 ? m + n : m;
}

// Whole texels between p (index i) and the constraint of texel x along an axis of n texels; -1: no constraint.
int texel_gap(Gap gap, int i, int x, int n, bool wrap) {
  switch (gap) {
    case Gap::Cell: {
      int c = std::abs(x - i);
      if (wrap) c = std::min(c, n - c);
      return std::max(0, c - 1);
    }
    case Gap::Plus:
      return wrap ? positive_mod(x - i, n) : (x >= i ? x - i : -1);
    case Gap::Minus:
      return wrap ? positive_mod(i - x, n) : (i >= x ? i - x : -1);
  }
  return -1;
}

// The least texel_gap over texels x0..x1 (a lower bound the hierarchy prunes with); -1: none of them binds.
int range_gap(Gap gap, int i, int x0, int x1, int n, bool wrap) {
  if (i >= x0 && i <= x1) return 0;
  switch (gap) {
    case Gap::Cell:
      if (wrap) return std::min(positive_mod(x0 - i, n), positive_mod(i - x1, n)) - 1;
      return (x0 > i ? x0 - i : i - x1) - 1;
    case Gap::Plus:
      return wrap ? positive_mod(x0 - i, n) : (x0 > i ? x0 - i : -1);
    case Gap::Minus:
      return wrap ? positive_mod(i - x1, n) : (x1 < i ? i - x1 : -1);
  }
  return -1;
}

// The field as the bakers see it: mirror is unfolded into its 2W x 2H period and treated as wrap. Channel values
// per texel: the height (conservative) or the top of each stepping-down wall of the texel (relaxed; -1: no wall).
struct Grid {
  int width = 0, height = 0;          // of the (unfolded) field
  int out_width = 0, out_height = 0;  // of the map: texels (0..out_width-1, 0..out_height-1) are baked
  bool wrap = true;
  int channels = 1;
  std::vector<Channel> layout;
  std::vector<double> heights;   // y * width + x
  std::vector<double> value;     // (y * width + x) * channels + c
  std::vector<double> sqx, sqy;  // squared UV length of g whole texels, g = 0..width (height)

  double h(int x, int y) const { return heights[std::size_t(y) * std::size_t(width) + std::size_t(x)]; }
  // The one expression both bakers use; monotone in the gaps and the top, so a cell's bound never exceeds it.
  double ratio(int gx, int gy, double top, double hp) const {
    return std::sqrt(sqx[std::size_t(gx)] + sqy[std::size_t(gy)]) / (top - hp);
  }
};

void validate(const HeightField& field) {
  if (field.width <= 0 || field.height <= 0) throw Error("cone map", "empty height field");
  if (field.h.size() != std::size_t(field.width) * std::size_t(field.height))
    throw Error("cone map", "height field has " + std::to_string(field.h.size()) + " values for " +
                                std::to_string(field.width) + "x" + std::to_string(field.height) + " texels");
  for (std::size_t k = 0; k < field.h.size(); ++k)
    if (!(field.h[k] >= 0.0 && field.h[k] <= 1.0))
      throw Error("cone map", "height " + std::to_string(field.h[k]) + " at texel (" +
                                  std::to_string(k % std::size_t(field.width)) + ", " +
                                  std::to_string(k / std::size_t(field.width)) + ") is outside [0, 1]");
}

Grid make_grid(const HeightField& field, ConeKind kind) {
  validate(field);
  Grid g;
  g.out_width = field.width;
  g.out_height = field.height;
  const bool mirror = field.address == AddressMode::Mirror;
  g.wrap = field.address != AddressMode::Clamp;
  g.width = mirror ? 2 * field.width : field.width;
  g.height = mirror ? 2 * field.height : field.height;
  g.heights.resize(std::size_t(g.width) * std::size_t(g.height));
  for (int y = 0; y < g.height; ++y) {
    const int sy = y < field.height ? y : 2 * field.height - 1 - y;
    for (int x = 0; x < g.width; ++x) {
      const int sx = x < field.width ? x : 2 * field.width - 1 - x;
      g.heights[std::size_t(y) * std::size_t(g.width) + std::size_t(x)] =
          field.h[std::size_t(sy) * std::size_t(field.width) + std::size_t(sx)];
    }
  }
  // Lengths in UV units of the map (an unfolded mirror period spans two).
  g.sqx.resize(std::size_t(g.width) + 1);
  g.sqy.resize(std::size_t(g.height) + 1);
  for (std::size_t k = 0; k < g.sqx.size(); ++k) g.sqx[k] = (double(k) / field.width) * (double(k) / field.width);
  for (std::size_t k = 0; k < g.sqy.size(); ++k) g.sqy[k] = (double(k) / field.height) * (double(k) / field.height);

  if (kind == ConeKind::Conservative) {
    g.channels = 1;
    g.layout = {{Gap::Cell, Gap::Cell}};
    g.value = g.heights;
    return g;
  }
  g.channels = int(kWallChannels.size());
  g.layout.assign(kWallChannels.begin(), kWallChannels.end());
  g.value.assign(g.heights.size() * kWallChannels.size(), -1.0);
  // The neighbour across a wall; clamp's extension repeats the edge texel (no wall at the border).
  auto neighbour = [&](int x, int y, int dx, int dy) -> double {
    int nx = x + dx, ny = y + dy;
    if (g.wrap) {
      nx = positive_mod(nx, g.width);
      ny = positive_mod(ny, g.height);
    } else {
      nx = std::clamp(nx, 0, g.width - 1);
      ny = std::clamp(ny, 0, g.height - 1);
    }
    return g.h(nx, ny);
  };
  constexpr std::array<std::array<int, 2>, 4> kStep{{{1, 0}, {-1, 0}, {0, 1}, {0, -1}}};
  for (int y = 0; y < g.height; ++y)
    for (int x = 0; x < g.width; ++x)
      for (std::size_t c = 0; c < kStep.size(); ++c) {
        const double hq = g.h(x, y);
        if (hq > neighbour(x, y, kStep[c][0], kStep[c][1]))
          g.value[(std::size_t(y) * std::size_t(g.width) + std::size_t(x)) * kStep.size() + c] = hq;
      }
  return g;
}

// The exact constraint of texel (x, y) on p = (i, j): the least candidate ratio over its channels, or `best`.
double visit_texel(const Grid& g, int i, int j, double hp, int x, int y, double best) {
  const double* v = &g.value[(std::size_t(y) * std::size_t(g.width) + std::size_t(x)) * std::size_t(g.channels)];
  for (int c = 0; c < g.channels; ++c) {
    if (!(v[c] > hp)) continue;
    const int gx = texel_gap(g.layout[std::size_t(c)].gx, i, x, g.width, g.wrap);
    if (gx < 0) continue;
    const int gy = texel_gap(g.layout[std::size_t(c)].gy, j, y, g.height, g.wrap);
    if (gy < 0) continue;
    best = std::min(best, g.ratio(gx, gy, v[c], hp));
  }
  return best;
}

float round_toward_zero(double r) {
  float f = float(r);
  if (double(f) > r) f = std::nextafter(f, 0.0f);
  return f;
}

// Level k >= 1 of the hierarchy: cell (cx, cy) covers texels [cx 2^k, min((cx+1) 2^k, W) - 1] (and likewise in y);
// per channel, a float upper bound of the channel's maximum over the cell.
struct Level {
  int width = 0, height = 0;
  std::vector<float> max;  // (cy * width + cx) * channels + c
};

float round_up(double v) {
  float f = float(v);
  if (double(f) < v) f = std::nextafter(f, std::numeric_limits<float>::infinity());
  return f;
}

std::vector<Level> build_hierarchy(const Grid& g) {
  std::vector<Level> levels(1);  // levels[0] stays empty: level 0 is Grid::value itself
  const std::size_t C = std::size_t(g.channels);
  int w = g.width, h = g.height;
  while (w > 1 || h > 1) {
    Level next;
    next.width = (w + 1) / 2;
    next.height = (h + 1) / 2;
    next.max.assign(std::size_t(next.width) * std::size_t(next.height) * C, -1.0f);
    const Level& below = levels.back();
    const bool from_texels = levels.size() == 1;
    tbb::parallel_for(0, next.height, [&](int cy) {
      for (int cx = 0; cx < next.width; ++cx) {
        float* out = &next.max[(std::size_t(cy) * std::size_t(next.width) + std::size_t(cx)) * C];
        for (int y = 2 * cy; y < std::min(2 * cy + 2, h); ++y)
          for (int x = 2 * cx; x < std::min(2 * cx + 2, w); ++x)
            for (std::size_t c = 0; c < C; ++c) {
              const std::size_t k = (std::size_t(y) * std::size_t(w) + std::size_t(x)) * C + c;
              out[c] = std::max(out[c], from_texels ? round_up(g.value[k]) : below.max[k]);
            }
      }
    });
    levels.push_back(std::move(next));
    w = levels.back().width;
    h = levels.back().height;
  }
  return levels;
}

struct Baker {
  const Grid& g;
  const std::vector<Level>& levels;

  // Lower bound of the ratio over cell (cx, cy) of level k; +inf when no texel in it can bind.
  double cell_bound(int k, int cx, int cy, int i, int j, double hp) const {
    const Level& level = levels[std::size_t(k)];
    const float* m =
        &level.max[(std::size_t(cy) * std::size_t(level.width) + std::size_t(cx)) * std::size_t(g.channels)];
    const int x0 = cx << k, x1 = std::min((cx + 1) << k, g.width) - 1;
    const int y0 = cy << k, y1 = std::min((cy + 1) << k, g.height) - 1;
    double bound = std::numeric_limits<double>::infinity();
    for (int c = 0; c < g.channels; ++c) {
      const double top = m[c];
      if (!(top > hp)) continue;
      const int gx = range_gap(g.layout[std::size_t(c)].gx, i, x0, x1, g.width, g.wrap);
      if (gx < 0) continue;
      const int gy = range_gap(g.layout[std::size_t(c)].gy, j, y0, y1, g.height, g.wrap);
      if (gy < 0) continue;
      bound = std::min(bound, g.ratio(gx, gy, top, hp));
    }
    return bound;
  }

  double bake_texel(int i, int j) const {
    const double hp = g.h(i, j);
    double best = kMaxConeRatio;
    // The 3x3 neighbourhood first: on rough maps it usually settles the texel (ratio 0) without a walk.
    for (int dy = -1; dy <= 1; ++dy)
      for (int dx = -1; dx <= 1; ++dx) {
        int x = i + dx, y = j + dy;
        if (g.wrap) {
          x = positive_mod(x, g.width);
          y = positive_mod(y, g.height);
        } else if (x < 0 || y < 0 || x >= g.width || y >= g.height) {
          continue;
        }
        best = visit_texel(g, i, j, hp, x, y, best);
      }
    struct Entry {
      int k, cx, cy;
      double bound;
    };
    std::array<Entry, 4 * 32> stack;
    int top = 0;
    const int root = int(levels.size()) - 1;
    if (root == 0) {  // a 1x1 map
      return best;
    }
    stack[std::size_t(top++)] = {root, 0, 0, 0.0};
    while (top > 0 && best > 0.0) {
      const Entry e = stack[std::size_t(--top)];
      if (e.bound >= best) continue;
      const int k = e.k - 1;
      const int w = k == 0 ? g.width : levels[std::size_t(k)].width;
      const int h = k == 0 ? g.height : levels[std::size_t(k)].height;
      if (k == 0) {
        for (int y = 2 * e.cy; y < std::min(2 * e.cy + 2, h); ++y)
          for (int x = 2 * e.cx; x < std::min(2 * e.cx + 2, w); ++x) best = visit_texel(g, i, j, hp, x, y, best);
        continue;
      }
      // Children nearest-bound first: pushed in descending order of bound.
      std::array<Entry, 4> children;
      int n = 0;
      for (int y = 2 * e.cy; y < std::min(2 * e.cy + 2, h); ++y)
        for (int x = 2 * e.cx; x < std::min(2 * e.cx + 2, w); ++x) {
          const double b = cell_bound(k, x, y, i, j, hp);
          if (b >= best) continue;
          int at = n++;
          while (at > 0 && children[std::size_t(at - 1)].bound < b) {
            children[std::size_t(at)] = children[std::size_t(at - 1)];
            --at;
          }
          children[std::size_t(at)] = {k, x, y, b};
        }
      for (int c = 0; c < n; ++c) stack[std::size_t(top++)] = children[std::size_t(c)];
    }
    return best;
  }
};

ConeMap empty_map(const Grid& g, ConeKind kind) {
  ConeMap map;
  map.width = g.out_width;
  map.height = g.out_height;
  map.kind = kind;
  map.ratio.assign(std::size_t(map.width) * std::size_t(map.height), kMaxConeRatio);
  return map;
}

}  // namespace

const char* cone_kind_name(ConeKind kind) { return kind == ConeKind::Relaxed ? "relaxed" : "conservative"; }

std::uint64_t cone_bake_bytes(int width, int height, ConeKind kind, AddressMode address) {
  // As make_grid, build_hierarchy and empty_map allocate them.
  const bool mirror = address == AddressMode::Mirror;
  const std::uint64_t w = std::uint64_t(std::max(width, 0)), h = std::uint64_t(std::max(height, 0));
  const std::uint64_t gw = mirror ? 2 * w : w, gh = mirror ? 2 * h : h;  // the (unfolded) grid
  const std::uint64_t channels = kind == ConeKind::Relaxed ? kWallChannels.size() : 1;
  std::uint64_t bytes = gw * gh * sizeof(double)              // Grid::heights
                        + gw * gh * channels * sizeof(double)  // Grid::value
                        + (gw + gh + 2) * sizeof(double)       // Grid::sqx, sqy
                        + w * h * sizeof(float);               // the map
  for (std::uint64_t lw = gw, lh = gh; lw > 1 || lh > 1;) {  // the hierarchy's levels 1, 2, ...
    lw = (lw + 1) / 2;
    lh = (lh + 1) / 2;
    bytes += lw * lh * channels * sizeof(float);
  }
  return bytes;
}

ConeMap bake_cone_map(const HeightField& field, ConeKind kind) {
  const Grid g = make_grid(field, kind);
  const std::vector<Level> levels = build_hierarchy(g);
  ConeMap map = empty_map(g, kind);
  const Baker baker{g, levels};
  ProgressStep step(std::string(cone_kind_name(kind)) + " cone map " + std::to_string(g.out_width) + "x" +
                        std::to_string(g.out_height),
                    g.out_height);
  tbb::parallel_for(tbb::blocked_range<int>(0, g.out_height, 2), [&](const tbb::blocked_range<int>& rows) {
    step.advance();  // stops here when asked to (Ctrl-C): within two rows
    for (int j = rows.begin(); j < rows.end(); ++j)
      for (int i = 0; i < g.out_width; ++i)
        map.ratio[std::size_t(j) * std::size_t(g.out_width) + std::size_t(i)] =
            round_toward_zero(baker.bake_texel(i, j));
    step.advance(rows.size());
  });
  return map;
}

ConeMap bake_cone_map_brute_force(const HeightField& field, ConeKind kind) {
  const Grid g = make_grid(field, kind);
  ConeMap map = empty_map(g, kind);
  for (int j = 0; j < g.out_height; ++j)
    for (int i = 0; i < g.out_width; ++i) {
      const double hp = g.h(i, j);
      double best = kMaxConeRatio;
      for (int y = 0; y < g.height; ++y)
        for (int x = 0; x < g.width; ++x) best = visit_texel(g, i, j, hp, x, y, best);
      map.ratio[std::size_t(j) * std::size_t(g.out_width) + std::size_t(i)] = round_toward_zero(best);
    }
  return map;
}

}  // namespace qdmr
