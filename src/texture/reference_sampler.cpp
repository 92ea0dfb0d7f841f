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

// Nearest texel index along an axis: floor(t), with t = u' * size in texels.
std::int64_t point_index(float t, int bits) {
  if (bits == 0) return std::int64_t(std::floor(t));
  const std::int64_t fixed = std::int64_t(std::floor(t * float(1 << bits)));
  return floor_div(fixed, bits);
}

// First bilinear tap and the weight of the second, for p = u' * size - 0.5.
void bilinear_taps(float p, int bits, std::int64_t& first, float& weight) {
  if (bits == 0) {
    const float f = std::floor(p);
    first = std::int64_t(f);
    weight = p - f;
    return;
  }
  const std::int64_t fixed = std::int64_t(std::floor(p * float(1 << bits)));
  first = floor_div(fixed, bits);
  weight = float(fixed - first * (std::int64_t(1) << bits)) / float(1 << bits);
}

void sample_level(const Texture& t, const SamplingDesc& s, float u, float v, int level, bool linear, float* out) {
  const int w = level_size(t.width(), level), h = level_size(t.height(), level);
  const int bits = fraction_bits(s.precision);
  if (!linear) {
    const int x = address(point_index(u * float(w), bits), w, s.address);
    const int y = address(point_index(v * float(h), bits), h, s.address);
    for (int c = 0; c < t.channels(); ++c) out[c] = t.texel(level, x, y, c);
    return;
  }
  std::int64_t x0, y0;
  float wx, wy;
  bilinear_taps(u * float(w) - 0.5f, bits, x0, wx);
  bilinear_taps(v * float(h) - 0.5f, bits, y0, wy);
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
