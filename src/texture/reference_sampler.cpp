// The scalar reference sampler, written from the documented behaviour (see reference_sampler.hpp), not from
// the SIMD code. Plain float arithmetic in the documented order (the build compiles with -ffp-contract=off,
// so no multiply-add is fused) and 64-bit integers for texel indices.
#include "texture/reference_sampler.hpp"

#include <algorithm>
#include <cmath>
#include <cstdint>

#include "core/det_math.hpp"

namespace qdmr {
namespace {

int fraction_bits(SamplePrecision precision) {
  switch (precision) {
    case SamplePrecision::Exact: return 0;
    case SamplePrecision::Hw8: return 8;
    case SamplePrecision::Hw6: return 6;
  }
  return 0;
}

// Floor division by 2^bits (the arithmetic right shift of hardware fixed point).
std::int64_t floor_div(std::int64_t value, int bits) {
  const std::int64_t d = std::int64_t(1) << bits;
  const std::int64_t q = value / d;
  return (value % d != 0 && value < 0) ? q - 1 : q;
}

float reduce(float u, AddressMode mode) {
  switch (mode) {
    case AddressMode::Wrap: return u - std::floor(u);
    case AddressMode::Mirror: return u - 2.0f * std::floor(u / 2.0f);
    case AddressMode::Clamp: return std::min(std::max(u, -1.0f), 2.0f);
  }
  return u;
}

// Any integer texel index to a texel of [0, n).
int address(std::int64_t i, int n, AddressMode mode) {
  switch (mode) {
    case AddressMode::Wrap: return int(((i % n) + n) % n);
    case AddressMode::Mirror: {
      const std::int64_t m = ((i % (2 * n)) + 2 * n) % (2 * n);
      return int(m < n ? m : 2 * n - 1 - m);
    }
    case AddressMode::Clamp: return int(std::clamp<std::int64_t>(i, 0, n - 1));
  }
  return 0;
}

// Size of level k along an axis of n level-0 texels.
int level_size(int n, int k) { return std::max(1, n >> k); }

// Texel index along an axis and the weight of the next texel: the texel coordinate x = u * n - offset (offset 0
// for point sampling, 0.5 for the first bilinear tap) in fixed point with `bits` fractional bits, rounded down:
// from the fp32 x (sm3) or from the exact x (sm4, exact; in fp64, where u * n - offset is exact or, for
// |u * n| < 1, far from every multiple of 2^-8 it could round onto). Weight: the fixed-point fraction, or
// the fp32 x minus the index.
std::int64_t texel_index(float u, int n, float offset, int bits, MathMode math, float& weight) {
  const float q = u * float(n) - offset;
  const double scale = double(std::int64_t(1) << bits);
  const std::int64_t fixed = math == MathMode::Sm3 ? std::int64_t(std::floor(double(q) * scale))
                                                   : std::int64_t(std::floor((double(u) * n - offset) * scale));
  if (bits == 0) {
    weight = q - float(fixed);
    return fixed;
  }
  const std::int64_t index = floor_div(fixed, bits);
  weight = float(fixed - index * (std::int64_t(1) << bits)) / float(1 << bits);
  return index;
}

void sample_level(const Texture& t, const SamplingDesc& s, float u, float v, int level, bool linear, float* out) {
  const int w = level_size(t.width(), level), h = level_size(t.height(), level);
  const int bits = fraction_bits(s.precision);
  float wx, wy;
  if (!linear) {
    const int x = address(texel_index(u, w, 0.0f, bits, s.math, wx), w, s.address);
    const int y = address(texel_index(v, h, 0.0f, bits, s.math, wy), h, s.address);
    for (int c = 0; c < t.channels(); ++c) out[c] = t.texel(level, x, y, c);
    return;
  }
  const std::int64_t x0 = texel_index(u, w, 0.5f, bits, s.math, wx);
  const std::int64_t y0 = texel_index(v, h, 0.5f, bits, s.math, wy);
  const int xa = address(x0, w, s.address), xb = address(x0 + 1, w, s.address);
  const int ya = address(y0, h, s.address), yb = address(y0 + 1, h, s.address);
  for (int c = 0; c < t.channels(); ++c) {
    const float t00 = t.texel(level, xa, ya, c), t10 = t.texel(level, xb, ya, c);
    const float t01 = t.texel(level, xa, yb, c), t11 = t.texel(level, xb, yb, c);
    const float top = t00 + (t10 - t00) * wx;
    const float bottom = t01 + (t11 - t01) * wx;
    out[c] = top + (bottom - top) * wy;
  }
}

}  // namespace

void reference_sample(const Texture& t, const SamplingDesc& s, float u, float v, float lod, float out[4]) {
  if (!std::isfinite(u) || !std::isfinite(v)) {
    for (int c = 0; c < t.channels(); ++c) out[c] = t.texel(0, 0, 0, c);
    return;
  }
  const float ru = reduce(u, s.address), rv = reduce(v, s.address);
  const int last = t.level_count() - 1;

  float l = lod + s.lod_bias;
  if (std::isnan(l)) l = float(last);
  l = std::min(std::max(l, s.min_lod), s.max_lod);
  l = std::min(std::max(l, 0.0f), float(last));
  if (const int bits = fraction_bits(s.precision); bits > 0)
    l = std::floor(l * float(1 << bits)) / float(1 << bits);

  switch (s.filter) {
    case Filter::Point: sample_level(t, s, ru, rv, 0, false, out); return;
    case Filter::Bilinear: sample_level(t, s, ru, rv, 0, true, out); return;
    case Filter::PointMipPoint:
    case Filter::LinearMipPoint:
      sample_level(t, s, ru, rv, int(std::floor(l + 0.5f)), s.filter == Filter::LinearMipPoint, out);
      return;
    case Filter::Trilinear:
    case Filter::PointMipLinear: {
      const bool linear = s.filter == Filter::Trilinear;
      const float base = std::floor(l), f = l - base;
      float fine[4], coarse[4];
      sample_level(t, s, ru, rv, int(base), linear, fine);
      sample_level(t, s, ru, rv, std::min(int(base) + 1, last), linear, coarse);
      for (int c = 0; c < t.channels(); ++c) out[c] = fine[c] + (coarse[c] - fine[c]) * f;
      return;
    }
  }
}

float reference_lod(const Texture& t, float dudx, float dvdx, float dudy, float dvdy) {
  const float w = float(t.width()), h = float(t.height());
  const float ax = dudx * w, ay = dvdx * h, bx = dudy * w, by = dvdy * h;
  const float px = ax * ax + ay * ay, py = bx * bx + by * by;
  if (!std::isfinite(px) || !std::isfinite(py)) return float(t.level_count() - 1);
  const float rho2 = px > py ? px : py;
  if (rho2 < 0x1p-126f) return -64.0f;
  return 0.5f * detmath::log2(rho2);
}

}  // namespace qdmr
