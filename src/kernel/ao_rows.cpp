// One row of a baked AO map with this ISA's vectors: fp64 lanes across the row's texels (2, 4 or 8), every
// operation the one the scalar definition (bake/ao_texel.hpp) performs on each lane, in its order, so each texel
// gets the definition's bits. A coarse bake without jitter reads the columns every row shares
// (ao::UniformColumns, found by the definition's code) in loops over chunks of the row; otherwise a batch falls
// back to the scalar definition, lane by lane, where the vector form would differ: a tap texel index beyond
// +-2^31 (the definition converts to int64). Either way a largest scaled rise below ao::kSmallestScaledRise is
// compared tap by tap, as the definition does. Heights stored as float are read as the doubles they convert to.
#include "kernel/ao_rows.hpp"

#include <algorithm>
#include <array>
#include <cmath>
#include <cstdint>

#include "bake/ao_texel.hpp"
#include "core/simd.hpp"
#include "kernel/kernel_calls.hpp"

namespace qdmr::QDMR_ISA_NAMESPACE {
namespace {

using Double = xsimd::batch<double, simd::Arch>;
using Int64 = xsimd::batch<std::int64_t, simd::Arch>;
using DoubleMask = xsimd::batch_bool<double, simd::Arch>;
constexpr int kWidth = int(Double::size);

// The largest integer magnitude a tap's texel index takes in the vector form.
constexpr double kIndexLimit = 0x1p31;

// An exact non-negative integer below 2^52 as int64 lanes: its bits above 2^52's mantissa.
Int64 to_index(const Double& x) {
  return xsimd::bitwise_cast<Int64>(x + Double(0x1p52)) - xsimd::bitwise_cast<Int64>(Double(0x1p52));
}

// 2^-k, k = 0 .. 31: the scale of a max pyramid level's cells.
constexpr std::array<double, 32> kCellScale = [] {
  std::array<double, 32> scale{};
  double s = 1.0;
  for (double& e : scale) e = s, s *= 0.5;
  return scale;
}();

// HeightField::texel_index on integer-valued lanes (|i| < 2^31): i - floor(i / n) n is i mod n exactly, since a
// quotient i / n of magnitude below 2^31 rounds by less than its distance 1/n to the next integer.
[[gnu::always_inline]] inline Double texel_index(const Double& i, double n, AddressMode mode) {
  const DoubleMask inside = (i >= Double(0.0)) & (i < Double(n));
  if (xsimd::all(inside)) return i;
  Double wrapped;
  switch (mode) {
    case AddressMode::Wrap: wrapped = i - xsimd::floor(i / Double(n)) * Double(n); break;
    case AddressMode::Clamp: wrapped = xsimd::min(xsimd::max(i, Double(0.0)), Double(n - 1.0)); break;
    case AddressMode::Mirror: {
      const Double m = i - xsimd::floor(i / Double(2.0 * n)) * Double(2.0 * n);
      wrapped = xsimd::select(m < Double(n), m, Double(2.0 * n - 1.0) - m);
      break;
    }
  }
  return xsimd::select(inside, i, wrapped);
}

// std::max(a, b) lane by lane: b where a < b, else a.
Double std_max(const Double& a, const Double& b) { return xsimd::select(a < b, b, a); }

struct Lanes {
  Double u, v;  // the texels' UV (v the same in every lane)
  Double s;     // their surface depth
};

// bilinear_surface_depth on lanes; ok turns false when an index leaves the vector form's range.
template <class T>
Double bilinear_depth(const ao::Bake<T>& b, const Double& u, const Double& v, bool& ok) {
  const HeightView<T>& f = b.field;
  const Double x = u * Double(double(f.width)) - Double(0.5), y = v * Double(double(f.height)) - Double(0.5);
  const Double fi = xsimd::floor(x), fj = xsimd::floor(y);
  const Double fx = x - fi, fy = y - fj;
  ok = ok && xsimd::all(xsimd::abs(fi) < Double(kIndexLimit - 1.0)) && xsimd::all(xsimd::abs(fj) < Double(kIndexLimit - 1.0));
  if (!ok) return Double(0.0);
  const double w = f.width, h = f.height;
  const Double i0 = texel_index(fi, w, f.address), i1 = texel_index(fi + Double(1.0), w, f.address);
  const Double r0 = texel_index(fj, h, f.address) * Double(w), r1 = texel_index(fj + Double(1.0), h, f.address) * Double(w);
  const T* texels = f.h;
  const Double h00 = Double::gather(texels, to_index(r0 + i0)), h10 = Double::gather(texels, to_index(r0 + i1));
  const Double h01 = Double::gather(texels, to_index(r1 + i0)), h11 = Double::gather(texels, to_index(r1 + i1));
  const Double height = h00 + (h10 - h00) * fx + (h01 - h00) * fy + (h00 - h10 - h01 + h11) * fx * fy;
  return Double(b.depth_scale) * (Double(1.0) - height);
}

// The largest scaled rise of the coarse taps along (dx, dy) per lane (coarse_slope before its division). Without
// jitter every lane of a row looks along the same direction from the same v: the taps' rows are found once
// (dy_uniform), in scalar, by the definition's own code.
template <class T>
Double coarse_rise(const ao::Bake<T>& b, const Lanes& l, const Double& dx, const Double& dy, double v, const double* dy_uniform,
                   bool& ok) {
  const HeightView<T>& f = b.field;
  const ao::MaxPyramid<T>& p = *b.pyramid;
  Double rise(0.0);
  double scale = 1.0;
  for (int k = 0; k < b.taps.count; ++k, scale *= 0.5) {
    const ao::Tap& tap = b.taps.tap[std::size_t(k)];
    const Double tu = l.u + dx * Double(double(tap.distance));
    const Double fx = xsimd::floor(tu * Double(double(f.width)));
    if (!xsimd::all(xsimd::abs(fx) < Double(kIndexLimit))) {
      ok = false;
      return rise;
    }
    const Double x = texel_index(fx, f.width, f.address);
    const int level = std::min(tap.level, p.top());
    const double cell = kCellScale[std::size_t(level)];  // x >> level on non-negative integers: floor(x 2^-level)
    const double w = p.width[std::size_t(level)], h = p.height[std::size_t(level)];
    const Double cx = xsimd::min(xsimd::floor(x * Double(cell)), Double(w - 1.0));
    Double row_start;
    if (dy_uniform) {
      const double tv = v + *dy_uniform * double(tap.distance);
      const auto y = HeightField::texel_index(std::int64_t(std::floor(tv * f.height)), f.height, f.address);
      row_start = Double(double(std::min<std::int64_t>(y >> level, p.height[std::size_t(level)] - 1)) * w);
    } else {
      const Double fy = xsimd::floor((l.v + dy * Double(double(tap.distance))) * Double(double(f.height)));
      if (!xsimd::all(xsimd::abs(fy) < Double(kIndexLimit))) {
        ok = false;
        return rise;
      }
      const Double y = texel_index(fy, f.height, f.address);
      row_start = xsimd::min(xsimd::floor(y * Double(cell)), Double(h - 1.0)) * Double(w);
    }
    const Double max = Double::gather(p.level[std::size_t(level)], to_index(row_start + cx));
    rise = std_max(rise, (l.s - Double(b.depth_scale) * (Double(1.0) - max)) * Double(scale));
  }
  return rise;
}

template <class T>
Double fine_slope(const ao::Bake<T>& b, const Lanes& l, const Double& dx, const Double& dy, bool& ok) {
  Double slope(0.0);
  for (int k = 0; k < b.taps.count && ok; ++k) {
    const ao::Tap& tap = b.taps.tap[std::size_t(k)];
    const double distance = tap.distance;
    const Double depth = bilinear_depth(b, l.u + dx * Double(distance), l.v + dy * Double(distance), ok);
    slope = std_max(slope, (l.s - depth) / Double(distance));
  }
  return slope;
}

// The raw AO of kWidth texels from i0 on row j; false where the vector form does not hold (nothing written).
template <class T>
bool batch_ao(const ao::Bake<T>& b, int i0, int j, std::array<double, kWidth>& out) {
  const int n = ao::direction_count(b.pattern);
  std::array<double, kWidth> u{};
  std::array<int, kWidth> rotation{};
  for (int lane = 0; lane < kWidth; ++lane) {
    u[std::size_t(lane)] = ao::texel_u(b, i0 + lane);
    rotation[std::size_t(lane)] =
        b.pattern.jitter ? ao::rotation(std::uint32_t(i0 + lane), std::uint32_t(j), b.pattern.seed) : 0;
  }
  bool ok = true;
  Lanes l{Double::load_unaligned(u.data()), Double(ao::texel_v(b, j)), Double(0.0)};
  l.s = bilinear_depth(b, l.u, l.v, ok);
  if (!ok) return false;
  Double visible(0.0);
  for (int d = 0; d < n; ++d) {
    std::array<double, kWidth> dx{}, dy{};
    for (int lane = 0; lane < kWidth; ++lane) {
      const int index = ao::direction_index(n, d, rotation[std::size_t(lane)]);
      dx[std::size_t(lane)] = ao::kDirections.cos[std::size_t(index)];
      dy[std::size_t(lane)] = ao::kDirections.sin[std::size_t(index)];
    }
    const Double vdx = Double::load_unaligned(dx.data()), vdy = Double::load_unaligned(dy.data());
    Double slope;
    if (b.pyramid) {
      const Double rise = coarse_rise(b, l, vdx, vdy, ao::texel_v(b, j), b.pattern.jitter ? nullptr : &dy[0], ok);
      if (!ok) return false;
      slope = rise / Double(double(b.taps.tap[0].distance));
      const DoubleMask by_tap = (rise != Double(0.0)) & (rise < Double(ao::kSmallestScaledRise));
      if (xsimd::any(by_tap)) {  // tiny rises: the definition tap by tap, in those lanes
        std::array<double, kWidth> s{}, slopes{};
        l.s.store_unaligned(s.data());
        slope.store_unaligned(slopes.data());
        for (int lane = 0; lane < kWidth; ++lane)
          if (by_tap.get(std::size_t(lane)))
            slopes[std::size_t(lane)] = ao::coarse_slope_by_tap(b, s[std::size_t(lane)], u[std::size_t(lane)], ao::texel_v(b, j),
                                                                dx[std::size_t(lane)], dy[std::size_t(lane)]);
        slope = Double::load_unaligned(slopes.data());
      }
    } else {
      slope = fine_slope(b, l, vdx, vdy, ok);
      if (!ok) return false;
    }
    visible += Double(1.0) - slope / xsimd::sqrt(Double(1.0) + slope * slope);
  }
  (visible / Double(double(n))).store_unaligned(out.data());
  return true;
}

// Texels per pass of a uniform row: its arrays (a few KiB) stay in L1.
constexpr int kChunk = 256;
static_assert(kChunk % kWidth == 0);

// A row of a coarse bake without jitter, from the columns every row shares (ao::UniformColumns): per chunk of
// texels, loops over the chunk that this ISA's vectors run, each texel's operations the definition's in its order.
// A direction's taps read one pyramid row each, found once per row by the definition's own code.
template <class T>
void uniform_row(const ao::Bake<T>& b, int j, float* row) {
  const HeightView<T>& f = b.field;
  const ao::MaxPyramid<T>& p = *b.pyramid;
  const ao::UniformColumns& c = *b.columns;
  const int n = ao::direction_count(b.pattern), taps = c.taps;
  const double v = ao::texel_v(b, j), ds = b.depth_scale, first = double(b.taps.tap[0].distance);
  // bilinear_surface_depth's rows.
  const double y = v * f.height - 0.5, fj = std::floor(y), fy = y - fj;
  const auto r = std::int64_t(fj);
  const T* row0 = f.h + std::size_t(HeightField::texel_index(r, f.height, f.address) * f.width);
  const T* row1 = f.h + std::size_t(HeightField::texel_index(r + 1, f.height, f.address) * f.width);
  // Each tap's pyramid row: [d * taps + k].
  std::array<const T*, std::size_t(ao::kMaxDirections) * ao::kMaxTaps> tap_rows{};
  std::array<double, ao::kMaxDirections> dxs{}, dys{};
  for (int d = 0; d < n; ++d) {
    const int index = ao::direction_index(n, d, 0);
    dxs[std::size_t(d)] = ao::kDirections.cos[std::size_t(index)];
    dys[std::size_t(d)] = ao::kDirections.sin[std::size_t(index)];
    for (int k = 0; k < taps; ++k) {
      const ao::Tap& tap = b.taps.tap[std::size_t(k)];
      const int level = std::min(tap.level, p.top());
      const std::int64_t cy = p.cell_y(level, ao::tap_texel(v + dys[std::size_t(d)] * double(tap.distance), f.height, f.address));
      tap_rows[std::size_t(d * taps + k)] = p.level[std::size_t(level)] + std::size_t(cy * p.width[std::size_t(level)]);
    }
  }
  // Past m: lanes of earlier chunks or zeros, computed and never stored.
  alignas(64) std::array<double, kChunk> s{}, rise{}, slope{}, visible{}, cell{};
  const Double depth_scale(ds), one(1.0);
  for (int i0 = 0; i0 < b.map_width; i0 += kChunk) {
    const int m = std::min(kChunk, b.map_width - i0);
    const std::int32_t* left = c.left.data() + i0;
    const std::int32_t* right = c.right.data() + i0;
    const double* fraction = c.fraction.data() + i0;
    for (int i = 0; i < m; ++i) {
      const double fx = fraction[i];
      const double h00 = double(row0[left[i]]), h10 = double(row0[right[i]]);
      const double h01 = double(row1[left[i]]), h11 = double(row1[right[i]]);
      const double h = h00 + (h10 - h00) * fx + (h01 - h00) * fy + (h00 - h10 - h01 + h11) * fx * fy;
      s[std::size_t(i)] = ds * (1.0 - h);
      visible[std::size_t(i)] = 0.0;
    }
    for (int d = 0; d < n; ++d) {
      std::fill_n(rise.begin(), m, 0.0);
      double scale = 1.0;
      for (int k = 0; k < taps; ++k, scale *= 0.5) {
        const T* cells = tap_rows[std::size_t(d * taps + k)];
        const std::int32_t* column = c.cell.data() + (std::size_t(d) * std::size_t(taps) + std::size_t(k)) * std::size_t(b.map_width) + std::size_t(i0);
        for (int i = 0; i < m; ++i) cell[std::size_t(i)] = double(cells[column[i]]);  // the taps' cell maxima
        const Double tap_scale(scale);
        for (int i = 0; i < m; i += kWidth) {
          const Double t = (Double::load_aligned(&s[std::size_t(i)]) -
                            depth_scale * (one - Double::load_aligned(&cell[std::size_t(i)]))) * tap_scale;
          std_max(Double::load_aligned(&rise[std::size_t(i)]), t).store_aligned(&rise[std::size_t(i)]);
        }
      }
      // coarse_slope: one division, or tap by tap where the largest scaled rise is tiny.
      DoubleMask tiny(false);
      for (int i = 0; i < m; i += kWidth) {
        const Double r = Double::load_aligned(&rise[std::size_t(i)]);
        (r / Double(first)).store_aligned(&slope[std::size_t(i)]);
        tiny = tiny | !((r == Double(0.0)) | (r >= Double(ao::kSmallestScaledRise)));
      }
      if (xsimd::any(tiny))  // also for lanes past m: those are then looked at and left alone
        for (int i = 0; i < m; ++i)
          if (!(rise[std::size_t(i)] == 0.0 || rise[std::size_t(i)] >= ao::kSmallestScaledRise))
            slope[std::size_t(i)] = ao::coarse_slope_by_tap(b, s[std::size_t(i)], ao::texel_u(b, i0 + i), v,
                                                            dxs[std::size_t(d)], dys[std::size_t(d)]);
      for (int i = 0; i < m; i += kWidth) {
        const Double sl = Double::load_aligned(&slope[std::size_t(i)]);
        (Double::load_aligned(&visible[std::size_t(i)]) + (one - sl / xsimd::sqrt(one + sl * sl)))
            .store_aligned(&visible[std::size_t(i)]);
      }
    }
    for (int i = 0; i < m; ++i) row[i0 + i] = float(visible[std::size_t(i)] / double(n));
  }
}

template <class T>
void row_of(const ao::Bake<T>& bake, int j, float* row) {
  kernel_calls.ao_rows.fetch_add(1, std::memory_order_relaxed);
  if (bake.columns) return uniform_row(bake, j, row);
  int i = 0;
  std::array<double, kWidth> ao{};
  for (; i + kWidth <= bake.map_width; i += kWidth) {
    if (batch_ao(bake, i, j, ao))
      for (int lane = 0; lane < kWidth; ++lane) row[i + lane] = float(ao[std::size_t(lane)]);
    else
      for (int lane = 0; lane < kWidth; ++lane) row[i + lane] = float(ao::texel_ao(bake, i + lane, j));
  }
  for (; i < bake.map_width; ++i) row[i] = float(ao::texel_ao(bake, i, j));
}

}  // namespace

void ao_map_row(const ao::Bake<double>& bake, int j, float* row) { row_of(bake, j, row); }
void ao_map_row(const ao::Bake<float>& bake, int j, float* row) { row_of(bake, j, row); }

}  // namespace qdmr::QDMR_ISA_NAMESPACE
