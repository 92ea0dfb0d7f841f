// Procedural height patterns. Every pattern is a function of the texel centre (u, v) in [0,1)^2 that is
// periodic with period 1 (cell lattices wrap modulo their count), so textures tile seamlessly. Only integer
// hashes and IEEE basic operations (+ - * / sqrt, floor) are used: the same bits on every machine.
#include <tbb/blocked_range.h>
#include <tbb/parallel_for.h>
#include <tbb/parallel_reduce.h>

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <functional>
#include <map>
#include <memory>
#include <mutex>
#include <string>
#include <utility>
#include <vector>

#include "qdmr/core/error.hpp"
#include "qdmr/core/limits.hpp"
#include "qdmr/texture/texture_level0.hpp"
#include "texture/height_rows_code.hpp"
#include "texture/internal.hpp"
#include "texture/pattern_reuse.hpp"

namespace qdmr {
namespace {

std::uint32_t mix(std::uint32_t h) {
  h ^= h >> 16;
  h *= 0x7feb352du;
  h ^= h >> 15;
  h *= 0x846ca68bu;
  h ^= h >> 16;
  return h;
}

// `mixed` = mix(seed), hoisted out of loops.
std::uint32_t hash_mixed(std::uint32_t x, std::uint32_t y, std::uint32_t mixed) { return mix(x + mix(y + mixed)); }

std::uint32_t hash(std::uint32_t x, std::uint32_t y, std::uint32_t seed) { return hash_mixed(x, y, mix(seed)); }

// [0, 1) with 24 bits.
double unit(std::uint32_t h) { return double(h >> 8) * (1.0 / 16777216.0); }

// i modulo n for i in [-n, 2n).
int wrap(int i, int n) { return i < 0 ? i + n : (i >= n ? i - n : i); }

double fract(double x) { return x - std::floor(x); }

double clamp01(double x) { return std::min(1.0, std::max(0.0, x)); }

double smoothstep(double t) { return t * t * (3.0 - 2.0 * t); }

// sin(2*pi*t) by folding to [-1/4, 1/4] and a degree-13 Taylor polynomial (error < 1e-9).
double sin_2pi(double t) {
  t = fract(t);
  if (t > 0.5) t -= 1.0;
  if (t > 0.25) t = 0.5 - t;
  if (t < -0.25) t = -0.5 - t;
  const double x = 6.283185307179586 * t, x2 = x * x;
  return x * (1 - x2 / 6 * (1 - x2 / 20 * (1 - x2 / 42 * (1 - x2 / 72 * (1 - x2 / 110 * (1 - x2 / 156))))));
}

struct Texel {
  double h;
  double cell = 0.5;
};

// Running bond: `cells` bricks per row, 2*cells rows, odd rows shifted by half a brick. Distances are in
// brick heights (a brick is 2 x 1); the mortar gap is `mortar` brick heights wide, bevels 0.25.
struct Bricks {
  int cells;
  double mortar;
  std::uint32_t seed;
  Texel operator()(double u, double v) const {
    const double py = v * (2 * cells);
    const int row = int(std::floor(py));
    const double fy = py - row;
    const double px = u * cells + ((row & 1) ? 0.5 : 0.0);
    const double col = std::floor(px);
    const double fx = px - col;
    const double edge = std::min(2.0 * std::min(fx, 1.0 - fx), std::min(fy, 1.0 - fy));
    const double c = unit(hash(std::uint32_t(wrap(int(col), cells)), std::uint32_t(row), seed));
    const double top = 1.0 - 0.1 * c;
    return {top * smoothstep(clamp01((edge - 0.5 * mortar) / 0.25)), c};
  }
};

// Voronoi stones, `cells` per side, each a dome (circular profile) over its distance to the cell border.
struct Cobbles {
  int cells;
  double mortar;
  std::vector<double> px, py, value;  // feature point (in cell units, within its cell) and value per cell

  Cobbles(int n, double m, std::uint32_t seed) : cells(n), mortar(m) {
    px.resize(std::size_t(n) * n);
    py.resize(px.size());
    value.resize(px.size());
    for (int j = 0; j < n; ++j)
      for (int i = 0; i < n; ++i) {
        const std::uint32_t h = hash(std::uint32_t(i), std::uint32_t(j), seed);
        const std::size_t k = std::size_t(j) * n + i;
        px[k] = 0.15 + 0.7 * double(h & 0xFFFFu) / 65536.0;
        py[k] = 0.15 + 0.7 * double(h >> 16) / 65536.0;
        value[k] = unit(hash(std::uint32_t(i), std::uint32_t(j), seed ^ 0x5bd1e995u));
      }
  }

  // What the texels of one cell (ix, iy) share: the nine candidate feature points around it and, once a texel
  // finds candidate n nearest, the bisectors between n and the others. fill() evaluates a row's texels in order,
  // so a Cursor computes them once per run of a cell's texels instead of once per texel; the operations are the
  // per-texel formula's, in its order, so the bits are the same.
  class Cursor {
  public:
    explicit Cursor(const Cobbles& cobbles) : c_(&cobbles) {}

    Texel operator()(double u, double v) {
      const double x = u * c_->cells, y = v * c_->cells;
      const int ix = int(std::floor(x)), iy = int(std::floor(y));
      if (!valid_ || ix != ix_ || iy != iy_) enter(ix, iy);
      int nearest = 0;
      double best = 1e30;
      for (int k = 0; k < 9; ++k) {
        const double d2 = (qx_[k] - x) * (qx_[k] - x) + (qy_[k] - y) * (qy_[k] - y);
        if (d2 < best) best = d2, nearest = k;
      }
      const Bisectors& b = bisectors(nearest);
      // Distance to the cell border: the nearest bisector between the nearest point and any other.
      double edge = 1e30;
      for (int k = 0; k < 9; ++k) {
        if (k == nearest) continue;
        const double mx = b.mid_x[k] - x, my = b.mid_y[k] - y;
        edge = std::min(edge, (mx * b.dx[k] + my * b.dy[k]) / b.len[k]);
      }
      const double t = clamp01((edge - 0.5 * c_->mortar) / 0.3);
      const double c = c_->value[id_[nearest]];
      return {(0.8 + 0.2 * c) * std::sqrt(t * (2.0 - t)), c};
    }

  private:
    // From candidate n to each candidate k: direction, its length and the midpoint.
    struct Bisectors {
      double dx[9], dy[9], len[9], mid_x[9], mid_y[9];
    };

    void enter(int ix, int iy) {
      valid_ = true, ix_ = ix, iy_ = iy, known_ = 0;
      for (int k = 0; k < 9; ++k) {
        const int cx = ix + k % 3 - 1, cy = iy + k / 3 - 1;
        id_[k] = std::size_t(wrap(cy, c_->cells)) * c_->cells + std::size_t(wrap(cx, c_->cells));
        qx_[k] = cx + c_->px[id_[k]];
        qy_[k] = cy + c_->py[id_[k]];
      }
    }

    const Bisectors& bisectors(int n) {
      Bisectors& b = bisectors_[n];
      if (known_ & (1u << n)) return b;
      known_ |= 1u << n;
      for (int k = 0; k < 9; ++k) {
        b.dx[k] = qx_[k] - qx_[n], b.dy[k] = qy_[k] - qy_[n];
        b.len[k] = std::sqrt(b.dx[k] * b.dx[k] + b.dy[k] * b.dy[k]);
        b.mid_x[k] = 0.5 * (qx_[k] + qx_[n]), b.mid_y[k] = 0.5 * (qy_[k] + qy_[n]);
      }
      return b;
    }

    const Cobbles* c_;
    bool valid_ = false;
    int ix_ = 0, iy_ = 0;
    unsigned known_ = 0;  // bit n: bisectors_[n] is computed for this cell
    double qx_[9], qy_[9];
    std::size_t id_[9];
    Bisectors bisectors_[9];
  };

  Cursor cursor() const { return Cursor(*this); }
};

struct Sine {
  int cells;
  Texel operator()(double u, double v) const {
    return {clamp01(0.5 + 0.25 * (sin_2pi(u * cells) + sin_2pi(v * cells)))};
  }
};

// `cells` terraces from 0 to 1 along a diagonal triangle wave (up then down once per repeat).
struct Steps {
  int cells;
  std::uint32_t seed;
  Texel operator()(double u, double v) const {
    const double tri = 1.0 - std::abs(2.0 * fract(u + v) - 1.0);
    const int k = std::min(int(std::floor(tri * cells)), cells - 1);
    return {cells == 1 ? 1.0 : double(k) / (cells - 1), unit(hash(std::uint32_t(k), 0, seed))};
  }
};

// cells x cells cones of radius half a cell, tip (h = 1) at each cell centre.
struct Spikes {
  int cells;
  std::uint32_t seed;
  Texel operator()(double u, double v) const {
    const double x = u * cells, y = v * cells;
    const double ix = std::floor(x), iy = std::floor(y);
    const double dx = x - ix - 0.5, dy = y - iy - 0.5;
    return {std::max(0.0, 1.0 - 2.0 * std::sqrt(dx * dx + dy * dy)),
            unit(hash(std::uint32_t(ix), std::uint32_t(iy), seed))};
  }
};

// fBm of periodic gradient noise (quintic fade, 8 gradient directions); the sum is remapped to [0,1] over
// the image afterwards. Octaves finer than a texel are skipped (they would only alias).
struct Noise {
  std::vector<std::int64_t> frequency;
  std::vector<double> amplitude;
  std::vector<std::uint32_t> mixed_seed;

  explicit Noise(const ProceduralDesc& d) {
    double a = 1.0;
    for (int o = 0; o < d.octaves; ++o, a *= d.gain) {
      const std::int64_t f = std::int64_t(d.cells) << o;
      if (o > 0 && f > d.size) break;
      frequency.push_back(f);
      amplitude.push_back(a);
      mixed_seed.push_back(mix(d.seed + std::uint32_t(o) * 0x9e3779b9u));
    }
  }

  static double fade(double t) { return t * t * t * (t * (t * 6.0 - 15.0) + 10.0); }

  // Gradient k (of 8 directions) dotted with the offset (dx, dy) from its lattice point.
  static double gradient(std::uint32_t k, double dx, double dy) {
    constexpr double r = 0.7071067811865476;
    static constexpr double gx[8] = {1, -1, 0, 0, r, -r, r, -r};
    static constexpr double gy[8] = {0, 0, 1, -1, r, r, -r, -r};
    return gx[k] * dx + gy[k] * dy;
  }

  // The raw sums of one row of texels at v, texel x at us[x]: octave after octave along the whole row, so the
  // texels' chains of dependent operations overlap (a texel at a time, each waited on the one before). Per octave
  // what depends on v alone once, and each lattice cell's corner gradients (k = hash >> 29) once per run of its
  // texels; each texel's operations are the per-texel formula's, in its order, so the bits are the same.
  void row(double v, const double* us, int n, double* sum) const {
    std::fill_n(sum, n, 0.0);
    for (std::size_t o = 0; o < frequency.size(); ++o) {
      const std::int64_t f = frequency[o];
      const std::uint32_t seed = mixed_seed[o];
      const double amp = amplitude[o];
      const double y = v * double(f), fy = std::floor(y);
      const double ty = y - fy, wy = fade(ty);
      // u, v in (0, 1): lattice indices in [0, f), only the next one wraps. hash_mixed(x, y, seed) is
      // mix(x + mix(y + seed)): its inner half depends on the row alone.
      const std::int64_t j = std::int64_t(fy), j1 = j + 1 == f ? 0 : j + 1;
      const std::uint32_t row0 = mix(std::uint32_t(j) + seed), row1 = mix(std::uint32_t(j1) + seed);
      std::int64_t cell = -1;
      std::uint32_t k0 = 0, k1 = 0, k2 = 0, k3 = 0;  // corners (i, j), (i1, j), (i, j1), (i1, j1)
      for (int x = 0; x < n; ++x) {
        const double ux = us[x] * double(f);
        const double fx = std::floor(ux);
        if (const std::int64_t i = std::int64_t(fx); i != cell) {
          const std::int64_t i1 = i + 1 == f ? 0 : i + 1;
          cell = i;
          k0 = mix(std::uint32_t(i) + row0) >> 29;
          k1 = mix(std::uint32_t(i1) + row0) >> 29;
          k2 = mix(std::uint32_t(i) + row1) >> 29;
          k3 = mix(std::uint32_t(i1) + row1) >> 29;
        }
        const double tx = ux - fx;
        const double n00 = gradient(k0, tx, ty), n10 = gradient(k1, tx - 1, ty);
        const double n01 = gradient(k2, tx, ty - 1), n11 = gradient(k3, tx - 1, ty - 1);
        const double wx = fade(tx);
        const double a = n00 + (n10 - n00) * wx, b = n01 + (n11 - n01) * wx;
        sum[x] += amp * (a + (b - a) * wy);
      }
    }
  }
};

// The top (h = 1), so a flat pattern adds no depth.
struct Flat {
  Texel operator()(double, double) const { return {1.0}; }
};

// Squares of size/cells texels; an odd `cells` puts two equal squares side by side at the wrap.
struct Checker {
  int cells;
  std::uint32_t seed;
  Texel operator()(double u, double v) const {
    const auto i = std::int64_t(std::floor(u * cells)), j = std::int64_t(std::floor(v * cells));
    return {double((i + j) & 1), unit(hash(std::uint32_t(i), std::uint32_t(j), seed))};
  }
};

// Where the pattern is read: texel centres moved back by the scroll so far (`offset`, in repeats), folded into
// [0, 1) (patterns are periodic with period 1). A zero offset reads exactly the texel centres.
struct Offset {
  double u = 0.0, v = 0.0;
};

Offset scroll_offset(const ProceduralDesc& d) {
  return {fract(double(d.scroll.x) * d.time), fract(double(d.scroll.y) * d.time)};
}

double at(double centre, double offset) { return offset == 0.0 ? centre : fract(centre - offset); }

template <class Pattern>
Image fill(int size, bool with_cells, const Pattern& pattern, Offset offset) {
  Image out(size, size, with_cells ? 2 : 1);
  tbb::parallel_for(tbb::blocked_range<int>(0, size), [&](const tbb::blocked_range<int>& rows) {
    // A pattern with a cursor evaluates a row's texels through it (it keeps what neighbouring texels share).
    auto evaluate = [&] {
      if constexpr (requires { pattern.cursor(); })
        return pattern.cursor();
      else
        return std::cref(pattern);
    }();
    for (int y = rows.begin(); y != rows.end(); ++y) {
      const double v = at((y + 0.5) / size, offset.v);
      for (int x = 0; x < size; ++x) {
        const Texel t = evaluate(at((x + 0.5) / size, offset.u), v);
        out.at(x, y, 0) = float(t.h);
        if (with_cells) out.at(x, y, 1) = float(t.cell);
      }
    }
  });
  return out;
}

// Noise: the raw sums row by row (Noise::row), remapped to [0,1] by the image's min and max (exact, so
// independent of the split).
Image fill_normalised(int size, bool with_cells, const Noise& noise, Offset offset) {
  Image out(size, size, with_cells ? 2 : 1);
  tbb::parallel_for(tbb::blocked_range<int>(0, size), [&](const tbb::blocked_range<int>& rows) {
    std::vector<double> us(static_cast<std::size_t>(size)), sums(static_cast<std::size_t>(size));
    for (int x = 0; x < size; ++x) us[std::size_t(x)] = at((x + 0.5) / size, offset.u);
    for (int y = rows.begin(); y != rows.end(); ++y) {
      noise.row(at((y + 0.5) / size, offset.v), us.data(), size, sums.data());
      for (int x = 0; x < size; ++x) {
        out.at(x, y, 0) = float(sums[std::size_t(x)]);
        if (with_cells) out.at(x, y, 1) = 0.5f;  // Texel's default cell: noise has none
      }
    }
  });
  const int c = out.channels;
  const std::size_t n = std::size_t(size) * size;
  using Range = std::pair<float, float>;
  const Range range = tbb::parallel_reduce(
      tbb::blocked_range<std::size_t>(0, n), Range{out.texels[0], out.texels[0]},
      [&](const tbb::blocked_range<std::size_t>& r, Range m) {
        for (std::size_t i = r.begin(); i != r.end(); ++i)
          m = {std::min(m.first, out.texels[i * c]), std::max(m.second, out.texels[i * c])};
        return m;
      },
      [](Range a, Range b) { return Range{std::min(a.first, b.first), std::max(a.second, b.second)}; });
  const double low = range.first, span = double(range.second) - low;
  tbb::parallel_for(tbb::blocked_range<std::size_t>(0, n), [&](const tbb::blocked_range<std::size_t>& r) {
    for (std::size_t i = r.begin(); i != r.end(); ++i) {
      float& h = out.texels[i * c];
      h = span > 0.0 ? float(clamp01((h - low) / span)) : 0.5f;
    }
  });
  return out;
}

Image fill_waves(const ProceduralDesc& d, bool with_cells) {
  const texture_detail::WaveRows waves = texture_detail::wave_rows(d);
  const int n = d.size;
  Image out(n, n, with_cells ? 2 : 1);
  tbb::parallel_for(tbb::blocked_range<int>(0, n), [&](const tbb::blocked_range<int>& rows) {
    std::vector<float> row(static_cast<std::size_t>(n));
    for (int y = rows.begin(); y != rows.end(); ++y) {
      waves.row(y, row.data(), &height_row_code::add_wave);
      for (int x = 0; x < n; ++x) {
        out.at(x, y, 0) = std::min(1.0f, std::max(0.0f, row[std::size_t(x)]));
        if (with_cells) out.at(x, y, 1) = 0.5f;
      }
    }
  });
  return out;
}

void validate(const ProceduralDesc& d) {
  const auto fail = [](const std::string& what) { return Error("procedural pattern", what); };
  if (d.size < 1 || d.size > limits::kMaxTextureSide || (d.size & (d.size - 1)) != 0)
    throw fail("size " + std::to_string(d.size) + " is not a power of two in 1.." +
               std::to_string(limits::kMaxTextureSide));
  if (d.cells < 1 || d.cells > limits::kMaxTextureSide)
    throw fail("cells " + std::to_string(d.cells) + " is outside 1.." + std::to_string(limits::kMaxTextureSide));
  if (d.octaves < 1 || d.octaves > 16) throw fail("octaves " + std::to_string(d.octaves) + " is outside 1..16");
  if (!(d.gain >= 0.0f && d.gain <= 1.0f)) throw fail("gain must be in [0, 1]");
  if (!(d.mortar >= 0.0f && d.mortar < 1.0f)) throw fail("mortar must be in [0, 1)");
  if (d.pattern == ProceduralPattern::Waves && d.waves.empty()) throw fail("waves needs at least one wave");
}

}  // namespace

namespace texture_detail {

// Waves: h = sum_i a_i ((1 + sin theta_i) / 2)^s_i / sum_i a_i, theta_i = 2 pi (k_i . (uv - scroll t) - |k_i| c_i t)
// with k_i whole cycles per repeat (so the pattern tiles). Each phase is separable, sin(alpha_u + beta_v) =
// sin alpha_u cos beta_v + cos alpha_u sin beta_v: one table per column and per row for each wave (sin_2pi in
// double), then two products and a sum per texel in float. Every texel is computed alone: the same bits on any
// thread count.
WaveRows wave_rows(const ProceduralDesc& d) {
  validate(d);
  const Offset offset = scroll_offset(d);
  const int n = d.size;
  WaveRows out;
  out.size = n;
  double total = 0.0;
  for (const WaveDesc& w : d.waves) total += w.amplitude;
  for (const WaveDesc& w : d.waves) {
    const double ku = w.cycles_u, kv = w.cycles_v, k = std::sqrt(ku * ku + kv * kv);
    const double turns = fract(k * double(w.speed) * d.time) + ku * offset.u + kv * offset.v;
    WaveRows::Wave t{std::vector<float>(std::size_t(n)), std::vector<float>(std::size_t(n)),
                     std::vector<float>(std::size_t(n)), std::vector<float>(std::size_t(n)),
                     float(total > 0.0 ? double(w.amplitude) / total : 0.0), std::clamp(w.sharpness, 1, 8)};
    for (int i = 0; i < n; ++i) {
      const double c = (i + 0.5) / n;
      const double a = fract(ku * c - turns), b = fract(kv * c);
      t.su[std::size_t(i)] = float(sin_2pi(a));
      t.cu[std::size_t(i)] = float(sin_2pi(a + 0.25));
      t.sv[std::size_t(i)] = float(sin_2pi(b));
      t.cv[std::size_t(i)] = float(sin_2pi(b + 0.25));
    }
    out.waves.push_back(std::move(t));
  }
  return out;
}

void WaveRows::row(int y, float* out, AddWave add) const {
  std::fill(out, out + size, 0.0f);
  for (const Wave& t : waves)
    add(t.sharpness, out, size, t.su.data(), t.cu.data(), t.sv[std::size_t(y)], t.cv[std::size_t(y)], t.weight);
}

namespace {

// The patterns kept while a PatternReuse names them, with their cells (channel 0 alone is the pattern without
// them: fill() writes the same heights either way).
struct KeptPatterns {
  std::mutex mutex;
  std::map<std::string, int> wanted;  // key -> how many live scopes name it
  std::map<std::string, std::shared_ptr<const Image>> patterns;
};

KeptPatterns& kept_patterns() {
  static KeptPatterns kept;
  return kept;
}

Image with_or_without_cells(const Image& pattern, bool with_cells) {
  if (with_cells) return pattern;
  Image heights(pattern.width, pattern.height, 1);
  for (std::size_t i = 0; i < heights.texels.size(); ++i) heights.texels[i] = pattern.texels[2 * i];
  return heights;
}

Image evaluate_pattern(const ProceduralDesc& d, bool with_cells) {
  const Offset o = scroll_offset(d);
  switch (d.pattern) {
    case ProceduralPattern::Bricks: return fill(d.size, with_cells, Bricks{d.cells, d.mortar, d.seed}, o);
    case ProceduralPattern::Cobbles: return fill(d.size, with_cells, Cobbles(d.cells, d.mortar, d.seed), o);
    case ProceduralPattern::Sine: return fill(d.size, with_cells, Sine{d.cells}, o);
    case ProceduralPattern::Steps: return fill(d.size, with_cells, Steps{d.cells, d.seed}, o);
    case ProceduralPattern::Spikes: return fill(d.size, with_cells, Spikes{d.cells, d.seed}, o);
    case ProceduralPattern::Noise: return fill_normalised(d.size, with_cells, Noise(d), o);
    case ProceduralPattern::Flat: return fill(d.size, with_cells, Flat{}, o);
    case ProceduralPattern::Checker: return fill(d.size, with_cells, Checker{d.cells, d.seed}, o);
    case ProceduralPattern::Waves: return fill_waves(d, with_cells);
  }
  throw Error("procedural pattern", "unknown pattern");
}

}  // namespace

Image generate_pattern(const ProceduralDesc& d, bool with_cells) {
  validate(d);
  KeptPatterns& kept = kept_patterns();
  std::string key;
  std::shared_ptr<const Image> pattern;
  {
    std::lock_guard lock(kept.mutex);
    if (!kept.wanted.empty() && d.size <= kMaxReusedPatternSide) {
      key = procedural_key(d);
      if (!kept.wanted.count(key)) key.clear();
      else if (auto it = kept.patterns.find(key); it != kept.patterns.end()) pattern = it->second;
    }
  }
  if (key.empty()) return evaluate_pattern(d, with_cells);
  if (!pattern) {  // made here (two threads asking at once may both make it: the same bits)
    pattern = std::make_shared<const Image>(evaluate_pattern(d, true));
    std::lock_guard lock(kept.mutex);
    if (kept.wanted.count(key)) kept.patterns.emplace(key, pattern);
  }
  return with_or_without_cells(*pattern, with_cells);
}

}  // namespace texture_detail

Image generate_procedural(const ProceduralDesc& desc) { return texture_detail::generate_pattern(desc, false); }

PatternReuse::PatternReuse(std::vector<std::string> keys) : keys_(std::move(keys)) {
  auto& kept = texture_detail::kept_patterns();
  std::lock_guard lock(kept.mutex);
  for (const std::string& key : keys_) ++kept.wanted[key];
}

PatternReuse::~PatternReuse() {
  auto& kept = texture_detail::kept_patterns();
  std::lock_guard lock(kept.mutex);
  for (const std::string& key : keys_)
    if (auto it = kept.wanted.find(key); it != kept.wanted.end() && --it->second == 0) {
      kept.wanted.erase(it);
      kept.patterns.erase(key);
    }
}

}  // namespace qdmr
