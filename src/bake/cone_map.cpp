// Cone-map bakers: the exact definitions of include/qdmr/bake/cone_map.hpp, by brute force and by a pruned walk
// of a max hierarchy. Both evaluate every candidate with the same expression (Grid::ratio), so they agree bit for
// bit; the hierarchy only skips candidates it can prove are not below the current minimum.
#include "qdmr/bake/cone_map.hpp"

#include <tbb/blocked_range.h>
#include <tbb/parallel_for.h>

#include <algorithm>
#include <array>
#include <cmath>
#include <limits>
#include <string>
#include <utility>

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

// a mod n for a in (-n, n), without a division.
int wrap_once(int a, int n) { return a < 0 ? a + n : a; }

// Whole texels between texel ranges [i0, i1] (of p: one texel, or a block of them) and [x0, x1] (of q: one texel,
// or a hierarchy cell) along an axis of n texels, for a constraint of kind G: the least over pairs (p, q); -1 when
// no pair binds. Every index is in [0, n).
template <Gap G>
int gap(int i0, int i1, int x0, int x1, int n, bool wrap) {
  if (x0 <= i1 && i0 <= x1) return 0;
  if constexpr (G == Gap::Cell) {
    if (wrap) return std::min(wrap_once(x0 - i1, n), wrap_once(i0 - x1, n)) - 1;
    return (x0 > i1 ? x0 - i1 : i0 - x1) - 1;
  } else if constexpr (G == Gap::Plus) {
    return wrap ? wrap_once(x0 - i1, n) : (x0 > i1 ? x0 - i1 : -1);
  } else {
    return wrap ? wrap_once(i0 - x1, n) : (i0 > x1 ? i0 - x1 : -1);
  }
}

// The field as the bakers see it: mirror is unfolded into its 2W x 2H period and treated as wrap. Channel values
// per texel: the height (conservative) or the top of each stepping-down wall of the texel (relaxed; -1: no wall).
struct Grid {
  int width = 0, height = 0;          // of the (unfolded) field
  int out_width = 0, out_height = 0;  // of the map: texels (0..out_width-1, 0..out_height-1) are baked
  bool wrap = true;
  int channels = 1;
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
    g.value = g.heights;
    return g;
  }
  g.channels = int(kWallChannels.size());
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

template <int C>
constexpr std::array<Channel, std::size_t(C)> channel_layout() {
  if constexpr (C == 1)
    return {{{Gap::Cell, Gap::Cell}}};  // conservative: the height of the texel's square
  else
    return kWallChannels;
}

// Calls f(top, gx, gy) for each channel c of texel or cell (x0..x1, y0..y1) that may constrain texels
// (i0..i1, j0..j1) at height hp or above: its top (`tops[c]`) is above hp and the pair binds along both axes.
template <int C, class F>
void for_each_binding(const Grid& g, int i0, int i1, int j0, int j1, double hp, int x0, int x1, int y0, int y1,
                      const auto* tops, F&& f) {
  static constexpr std::array<Channel, std::size_t(C)> kLayout = channel_layout<C>();
  [&]<std::size_t... c>(std::index_sequence<c...>) {
    (
        [&] {
          const double top = double(tops[c]);
          if (!(top > hp)) return;
          const int gx = gap<kLayout[c].gx>(i0, i1, x0, x1, g.width, g.wrap);
          if (gx < 0) return;
          const int gy = gap<kLayout[c].gy>(j0, j1, y0, y1, g.height, g.wrap);
          if (gy < 0) return;
          f(top, gx, gy);
        }(),
        ...);
  }(std::make_index_sequence<std::size_t(C)>{});
}

// The least ratio found so far for one texel p, and the threshold that prunes against it without a square root.
// A candidate of ratio sqrt(s) / t (s the squared distance, t the height difference, as in Grid::ratio) with
// s > prune2 * t^2 has a computed ratio of at least `ratio`: the margin of 1e-12 covers the few ulps of the
// products, the square root and the quotient. (When prune2 * t^2 underflows, t < 1e-144 and any s > 0 gives a
// ratio far above kMaxConeRatio; s = 0 is never pruned.)
struct Best {
  double ratio = kMaxConeRatio;
  double prune2 = double(kMaxConeRatio) * double(kMaxConeRatio) * (1.0 + 1e-12);
  int x = -1, y = -1;  // the texel that gave `ratio`; -1: none yet

  bool prunes(double s, double t) const { return s > prune2 * (t * t); }
  void offer(double r, int qx, int qy) {
    if (!(r < ratio)) return;
    ratio = r;
    prune2 = r * r * (1.0 + 1e-12);
    x = qx;
    y = qy;
  }
};

// Texels are baked in blocks of kBlock x kBlock. The texels of a block that no 8-neighbour settles walk the
// hierarchy together: a cell is opened when it may narrow the widest cone among them (its distance to the block's
// texels, its top over their lowest height), and each of its texels is then tried on each of them. One walk thus
// serves up to kBlock^2 texels whose searches overlap almost entirely.
constexpr int kBlock = 4;

template <int C>
class Baker {
public:
  Baker(const Grid& g, const std::vector<Level>& levels) : g_(g), levels_(levels) {}

  // The texels of the block whose top-left texel is (bx, by); `hints` (one per row of the block, x < 0: none) are
  // where the previous block of the same rows found its minima, tried first so the walk starts with narrow cones.
  void bake_block(int bx, int by, std::array<std::array<int, 2>, kBlock>& hints, ConeMap& map) const {
    std::array<Texel, kBlock * kBlock> walking;
    int n = 0;
    const int bx1 = std::min(bx + kBlock, g_.out_width), by1 = std::min(by + kBlock, g_.out_height);
    for (int j = by; j < by1; ++j)
      for (int i = bx; i < bx1; ++i) {
        Texel p{i, j, g_.h(i, j), {}};
        for (const auto& [hx, hy] : hints)
          if (hx >= 0) visit(p, hx, hy);
        // The 8-neighbours: on rough maps they usually settle the texel (ratio 0) without a walk.
        for (int dy = -1; dy <= 1; ++dy)
          for (int dx = -1; dx <= 1; ++dx) {
            int x = i + dx, y = j + dy;
            if (g_.wrap) {
              x = x < 0 ? x + g_.width : x >= g_.width ? x - g_.width : x;
              y = y < 0 ? y + g_.height : y >= g_.height ? y - g_.height : y;
            } else if (x < 0 || y < 0 || x >= g_.width || y >= g_.height) {
              continue;
            }
            visit(p, x, y);
          }
        if (p.best.ratio > 0.0)
          walking[std::size_t(n++)] = p;
        else
          map.ratio[std::size_t(j) * std::size_t(g_.out_width) + std::size_t(i)] = 0.0f;
      }
    if (n == 0) return;
    walk(walking.data(), n);
    for (int k = 0; k < n; ++k) {
      const Texel& p = walking[std::size_t(k)];
      map.ratio[std::size_t(p.j) * std::size_t(g_.out_width) + std::size_t(p.i)] = round_toward_zero(p.best.ratio);
      if (p.best.x >= 0) hints[std::size_t(p.j - by)] = {p.best.x, p.best.y};
    }
  }

private:
  struct Texel {
    int i, j;
    double hp;
    Best best;
  };

  // Texel q = (x, y) tried on p.
  void visit(Texel& p, int x, int y) const {
    const double* tops = &g_.value[(std::size_t(y) * std::size_t(g_.width) + std::size_t(x)) * std::size_t(C)];
    for_each_binding<C>(g_, p.i, p.i, p.j, p.j, p.hp, x, x, y, y, tops, [&](double top, int gx, int gy) {
      const double s = g_.sqx[std::size_t(gx)] + g_.sqy[std::size_t(gy)];
      if (!p.best.prunes(s, top - p.hp)) p.best.offer(g_.ratio(gx, gy, top, p.hp), x, y);
    });
  }

  // The texels walking together: their bounding box, lowest height and widest cone.
  struct Group {
    int i0, i1, j0, j1;
    double hp;
    double prune2;  // the largest Best::prune2 among them: a cell pruned with it is pruned for every one
  };

  // s / t^2 of the least bound of hierarchy cell (cx, cy) of level k >= 1 on the group; +inf when the cell cannot
  // narrow any of its cones. The bound is monotone: every texel of the cell and of the group is at least as far
  // apart and differs at most as much in height, and the float tops are rounded up.
  double cell_key(int k, int cx, int cy, const Group& group) const {
    const Level& level = levels_[std::size_t(k)];
    const float* tops = &level.max[(std::size_t(cy) * std::size_t(level.width) + std::size_t(cx)) * std::size_t(C)];
    const int x0 = cx << k, x1 = std::min((cx + 1) << k, g_.width) - 1;
    const int y0 = cy << k, y1 = std::min((cy + 1) << k, g_.height) - 1;
    double key = std::numeric_limits<double>::infinity();
    for_each_binding<C>(g_, group.i0, group.i1, group.j0, group.j1, group.hp, x0, x1, y0, y1, tops,
                        [&](double top, int gx, int gy) {
                          const double s = g_.sqx[std::size_t(gx)] + g_.sqy[std::size_t(gy)], t = top - group.hp;
                          if (s > group.prune2 * (t * t)) return;
                          key = std::min(key, s == 0.0 ? 0.0 : s / (t * t));
                        });
    return key;
  }

  // Depth first from the root, the nearest-bound child first, over cells that may narrow some texel's cone.
  void walk(Texel* texels, int n) const {
    Group group{texels[0].i, texels[0].i, texels[0].j, texels[0].j, texels[0].hp, 0.0};
    for (int k = 0; k < n; ++k) {
      const Texel& p = texels[k];
      group.i0 = std::min(group.i0, p.i), group.i1 = std::max(group.i1, p.i);
      group.j0 = std::min(group.j0, p.j), group.j1 = std::max(group.j1, p.j);
      group.hp = std::min(group.hp, p.hp);
      group.prune2 = std::max(group.prune2, p.best.prune2);
    }
    struct Entry {
      int k, cx, cy;
      double key;
    };
    std::array<Entry, 4 * 32> stack;
    int top = 0;
    const int root = int(levels_.size()) - 1;
    if (root > 0) stack[std::size_t(top++)] = {root, 0, 0, 0.0};  // else a 1x1 map: its neighbourhood was all
    while (top > 0 && group.prune2 > 0.0) {
      const Entry e = stack[std::size_t(--top)];
      if (e.key > group.prune2) continue;
      const int k = e.k - 1;
      if (k == 0) {
        for (int m = 0; m < n; ++m) {  // the cell's own bound on each texel first: it often spares 4 visits
          Texel& p = texels[m];
          if (cell_key(1, e.cx, e.cy, Group{p.i, p.i, p.j, p.j, p.hp, p.best.prune2}) > p.best.prune2) continue;
          for (int y = 2 * e.cy; y < std::min(2 * e.cy + 2, g_.height); ++y)
            for (int x = 2 * e.cx; x < std::min(2 * e.cx + 2, g_.width); ++x) visit(p, x, y);
        }
        group.prune2 = 0.0;
        for (int m = 0; m < n; ++m) group.prune2 = std::max(group.prune2, texels[m].best.prune2);
        continue;
      }
      const Level& level = levels_[std::size_t(k)];
      std::array<Entry, 4> children;
      int count = 0;
      for (int y = 2 * e.cy; y < std::min(2 * e.cy + 2, level.height); ++y)
        for (int x = 2 * e.cx; x < std::min(2 * e.cx + 2, level.width); ++x) {
          const double key = cell_key(k, x, y, group);
          if (key > group.prune2) continue;
          int at = count++;  // kept in descending order of key: the nearest is pushed last, popped first
          while (at > 0 && children[std::size_t(at - 1)].key < key) {
            children[std::size_t(at)] = children[std::size_t(at - 1)];
            --at;
          }
          children[std::size_t(at)] = {k, x, y, key};
        }
      for (int c = 0; c < count; ++c) stack[std::size_t(top++)] = children[std::size_t(c)];
    }
  }

  const Grid& g_;
  const std::vector<Level>& levels_;
};

template <int C>
void bake_blocks(const Grid& g, ConeMap& map, ConeKind kind) {
  const std::vector<Level> levels = build_hierarchy(g);
  const Baker<C> baker(g, levels);
  ProgressStep step(std::string(cone_kind_name(kind)) + " cone map " + std::to_string(g.out_width) + "x" +
                        std::to_string(g.out_height),
                    g.out_height);
  const int rows_of_blocks = (g.out_height + kBlock - 1) / kBlock;
  tbb::parallel_for(0, rows_of_blocks, [&](int row) {
    step.advance();  // stops here when asked to (Ctrl-C): within kBlock rows
    std::array<std::array<int, 2>, kBlock> hints;
    hints.fill({-1, -1});
    for (int bx = 0; bx < g.out_width; bx += kBlock) baker.bake_block(bx, row * kBlock, hints, map);
    step.advance(std::min(kBlock, g.out_height - row * kBlock));
  });
}

template <int C>
void bake_brute_force(const Grid& g, ConeMap& map) {
  for (int j = 0; j < g.out_height; ++j)
    for (int i = 0; i < g.out_width; ++i) {
      const double hp = g.h(i, j);
      double best = kMaxConeRatio;
      for (int y = 0; y < g.height; ++y)
        for (int x = 0; x < g.width; ++x) {
          const double* tops = &g.value[(std::size_t(y) * std::size_t(g.width) + std::size_t(x)) * std::size_t(C)];
          for_each_binding<C>(g, i, i, j, j, hp, x, x, y, y, tops,
                              [&](double top, int gx, int gy) { best = std::min(best, g.ratio(gx, gy, top, hp)); });
        }
      map.ratio[std::size_t(j) * std::size_t(g.out_width) + std::size_t(i)] = round_toward_zero(best);
    }
}

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
  ConeMap map = empty_map(g, kind);
  if (kind == ConeKind::Conservative)
    bake_blocks<1>(g, map, kind);
  else
    bake_blocks<4>(g, map, kind);
  return map;
}

ConeMap bake_cone_map_brute_force(const HeightField& field, ConeKind kind) {
  const Grid g = make_grid(field, kind);
  ConeMap map = empty_map(g, kind);
  if (kind == ConeKind::Conservative)
    bake_brute_force<1>(g, map);
  else
    bake_brute_force<4>(g, map);
  return map;
}

}  // namespace qdmr
