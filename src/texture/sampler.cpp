// The SIMD sampler. Only lane-wise IEEE operations (no FMA, no libm), so 4- and 8-lane builds agree bit for
// bit. Coordinates are first reduced to one period of the address mode (exactly), so texel indices stay
// small; texels are then fetched lane by lane.
#include "texture/sampler.hpp"

#include <cstdint>
#include <vector>

namespace qdmr {
namespace {

using simd::Float;
using simd::Int;
using simd::kLanes;
using simd::Mask;

constexpr float kMinLod = -64.0f;  // LOD of a zero (or denormal) footprint

Mask is_finite(const Float& x) { return (x - x) == Float(0.0f); }

// log2(x) for normal x > 0: the exponent bits plus log2 of the mantissa m in [sqrt(1/2), sqrt(2)) by the odd
// series 2/ln2 * (t + t^3/3 + ... + t^9/9), t = (m-1)/(m+1), |t| <= 0.172: truncation error < 2e-9.
Float log2_normal(const Float& x) {
  const Int bits = xsimd::bitwise_cast<Int>(x);
  Float m = xsimd::bitwise_cast<Float>((bits & Int(0x007FFFFF)) | Int(0x3F800000));
  Float e = xsimd::to_float((bits >> 23) - Int(127));
  const Mask high = m > Float(1.41421356f);
  m = xsimd::select(high, m * Float(0.5f), m);
  e = xsimd::select(high, e + Float(1.0f), e);
  const Float t = (m - Float(1.0f)) / (m + Float(1.0f)), t2 = t * t;
  constexpr float c = 2.88539008177792681f;  // 2 / ln 2
  Float p = Float(c / 9.0f);
  p = p * t2 + Float(c / 7.0f);
  p = p * t2 + Float(c / 5.0f);
  p = p * t2 + Float(c / 3.0f);
  p = p * t2 + Float(c);
  return e + t * p;
}

// Size of each lane's level: max(1, floor(size0 * 2^-level)), exact in float.
Float level_size(float size0, const Float& level) {
  const Float scale = xsimd::bitwise_cast<Float>((Int(127) - xsimd::to_int(level)) << 23);
  return xsimd::max(Float(1.0f), xsimd::floor(Float(size0) * scale));
}

// u reduced to one period of the address mode; exact (no rounding) for finite u.
Float reduce(const Float& u, AddressMode mode) {
  switch (mode) {
    case AddressMode::Wrap: return u - xsimd::floor(u);
    case AddressMode::Mirror: return u - Float(2.0f) * xsimd::floor(u * Float(0.5f));
    case AddressMode::Clamp: break;
  }
  return xsimd::min(xsimd::max(u, Float(-1.0f)), Float(2.0f));  // further out clamps to the same texels
}

// Integer-valued texel index i (within a period or two of the reduced coordinate) to a texel of [0, n).
Float address(Float i, const Float& n, AddressMode mode) {
  switch (mode) {
    case AddressMode::Wrap:
      i = xsimd::select(i < Float(0.0f), i + n, i);
      return xsimd::select(i >= n, i - n, i);
    case AddressMode::Mirror: {
      const Float period = n + n;
      i = xsimd::select(i < Float(0.0f), i + period, i);
      i = xsimd::select(i >= period, i - period, i);
      return xsimd::select(i >= n, period - Float(1.0f) - i, i);
    }
    case AddressMode::Clamp: break;
  }
  return xsimd::min(xsimd::max(i, Float(0.0f)), n - Float(1.0f));
}

// One mip level per lane with its size and the lane's reduced coordinates.
struct LevelCoords {
  alignas(64) std::int32_t level[kLanes];
  Float width, height;
  Int row_stride;  // width * channels
};

LevelCoords level_coords(const MipChain& chain, const Float& level) {
  LevelCoords lc;
  xsimd::to_int(level).store_aligned(lc.level);
  lc.width = level_size(float(chain.levels[0].width), level);
  lc.height = level_size(float(chain.levels[0].height), level);
  lc.row_stride = xsimd::to_int(lc.width) * Int(chain.levels[0].channels);
  return lc;
}

// out[c] = texel (x, y) of each lane's level, channel c.
void fetch(const MipChain& chain, const LevelCoords& lc, const Float& x, const Float& y, Float* out) {
  const int channels = chain.levels[0].channels;
  alignas(64) std::int32_t index[kLanes];
  (xsimd::to_int(y) * lc.row_stride + xsimd::to_int(x) * Int(channels)).store_aligned(index);
  alignas(64) float texel[4][kLanes];
  for (int lane = 0; lane < kLanes; ++lane) {
    const float* p = chain.levels[std::size_t(lc.level[lane])].texels.data() + index[lane];
    for (int c = 0; c < channels; ++c) texel[c][lane] = p[c];
  }
  for (int c = 0; c < channels; ++c) out[c] = Float::load_aligned(texel[c]);
}

void sample_point(const MipChain& chain, const SamplerState& s, const Float& u, const Float& v, const Float& level,
                  Float* out) {
  const LevelCoords lc = level_coords(chain, level);
  const Float x = address(xsimd::floor(u * lc.width), lc.width, s.address);
  const Float y = address(xsimd::floor(v * lc.height), lc.height, s.address);
  fetch(chain, lc, x, y, out);
}

void sample_bilinear(const MipChain& chain, const SamplerState& s, const Float& u, const Float& v,
                     const Float& level, Float* out) {
  const LevelCoords lc = level_coords(chain, level);
  const Float px = u * lc.width - Float(0.5f), py = v * lc.height - Float(0.5f);
  const Float fx0 = xsimd::floor(px), fy0 = xsimd::floor(py);
  const Float wx = px - fx0, wy = py - fy0;
  const Float x0 = address(fx0, lc.width, s.address), x1 = address(fx0 + Float(1.0f), lc.width, s.address);
  const Float y0 = address(fy0, lc.height, s.address), y1 = address(fy0 + Float(1.0f), lc.height, s.address);
  const int channels = chain.levels[0].channels;
  Float t00[4], t10[4], t01[4], t11[4];
  fetch(chain, lc, x0, y0, t00);
  fetch(chain, lc, x1, y0, t10);
  fetch(chain, lc, x0, y1, t01);
  fetch(chain, lc, x1, y1, t11);
  for (int c = 0; c < channels; ++c) {
    const Float top = t00[c] + (t10[c] - t00[c]) * wx;
    const Float bottom = t01[c] + (t11[c] - t01[c]) * wx;
    out[c] = top + (bottom - top) * wy;
  }
}

}  // namespace

Float lod_from_derivatives(const MipChain& chain, const Float& dudx, const Float& dvdx, const Float& dudy,
                           const Float& dvdy) {
  const Float w(float(chain.levels[0].width)), h(float(chain.levels[0].height));
  const Float ax = dudx * w, ay = dvdx * h, bx = dudy * w, by = dvdy * h;
  const Float px = ax * ax + ay * ay, py = bx * bx + by * by;
  const Float rho2 = xsimd::select(px > py, px, py);
  const Mask tiny = rho2 < Float(1.17549435e-38f);  // zero or denormal
  // 0.5 * log2(rho^2) = log2(rho): exact integers for power-of-two footprints.
  const Float lod = Float(0.5f) * log2_normal(xsimd::select(tiny, Float(1.0f), rho2));
  const Float last(float(chain.levels.size() - 1));
  return xsimd::select(is_finite(px) & is_finite(py), xsimd::select(tiny, Float(kMinLod), lod), last);
}

void sample(const MipChain& chain, const SamplerState& state, const Float& u, const Float& v, const Float& lod,
            Float* out) {
  const Mask finite = is_finite(u) & is_finite(v);
  const Float ru = reduce(xsimd::select(finite, u, Float(0.0f)), state.address);
  const Float rv = reduce(xsimd::select(finite, v, Float(0.0f)), state.address);
  const Float last(float(chain.levels.size() - 1));
  Float l = lod + Float(state.lod_bias);
  l = xsimd::select(l == l, l, last);  // NaN: the coarsest level, as for non-finite derivatives
  l = xsimd::min(xsimd::max(l, Float(0.0f)), last);
  switch (state.filter) {
    case Filter::Point:
    case Filter::PointMipPoint: sample_point(chain, state, ru, rv, xsimd::floor(l + Float(0.5f)), out); break;
    case Filter::Bilinear:
    case Filter::LinearMipPoint: sample_bilinear(chain, state, ru, rv, xsimd::floor(l + Float(0.5f)), out); break;
    case Filter::PointMipLinear:
    case Filter::Trilinear: {
      const Float l0 = xsimd::floor(l), f = l - l0;
      Float fine[4], coarse[4];
      sample_bilinear(chain, state, ru, rv, l0, fine);
      sample_bilinear(chain, state, ru, rv, xsimd::min(l0 + Float(1.0f), last), coarse);
      for (int c = 0; c < chain.levels[0].channels; ++c) out[c] = fine[c] + (coarse[c] - fine[c]) * f;
      break;
    }
  }
  const Image& base = chain.levels[0];
  for (int c = 0; c < base.channels; ++c) out[c] = xsimd::select(finite, out[c], Float(base.at(0, 0, c)));
}

}  // namespace qdmr
