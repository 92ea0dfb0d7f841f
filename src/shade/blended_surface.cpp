#include "shade/blended_surface.hpp"

namespace qdmr {
namespace {

using simd::Float;
using simd::Int;

// Texel coordinates are clamped before they become integers (beyond this the query box is the whole map).
constexpr float kMaxCoordinate = 4194304.0f;
Int floor_index(const Float& x) {
  return xsimd::to_int(xsimd::floor(xsimd::max(xsimd::min(x, Float(kMaxCoordinate)), Float(-kMaxCoordinate))));
}

SamplerState weight_sampler(const SamplerState& layer) {
  SamplerState s;
  s.filter = Filter::Bilinear;
  s.address = AddressMode::Wrap;
  s.fetch = layer.fetch;
  return s;
}

}  // namespace

BlendedSurface::BlendedSurface(const SingleLayerSurface* layers, int count, BlendOperator op, const Float* w)
    : layers_(layers), count_(count), op_(op) {
  for (int i = 0; i < kMaxLayers; ++i) weights_[i] = i < count ? w[i] : Float(0.0f);
}

BlendedSurface::BlendedSurface(const SingleLayerSurface* layers, int count, BlendOperator op, const WeightTexture& weights,
                               const Float& u_lo, const Float& u_hi, const Float& v_lo, const Float& v_hi)
    : layers_(layers), count_(count), op_(op), texture_(weights) {
  bound_weights(u_lo, u_hi, v_lo, v_hi);
}

// The largest weight of each layer that bilinear sampling can return inside the box: the maximum over the weight
// texels whose footprint touches it, read from the max chain at the first level where they fit in 2x2 texels.
void BlendedSurface::bound_weights(const Float& u_lo, const Float& u_hi, const Float& v_lo, const Float& v_hi) {
  const TextureView& view = *texture_.view;
  const float texels_per_uv_x = float(view.texture().width()) / texture_.scale;
  const float texels_per_uv_y = float(view.texture().height()) / texture_.scale;
  // A layer texel of padding: box-surface queries read weights at texel centres up to half a texel outside.
  const float pad_u = 1.0f / float(width()), pad_v = 1.0f / float(height());
  Int x0 = floor_index((u_lo - Float(pad_u)) * Float(texels_per_uv_x) - Float(0.5f));
  Int x1 = floor_index((u_hi + Float(pad_u)) * Float(texels_per_uv_x) - Float(0.5f)) + Int(1);
  Int y0 = floor_index((v_lo - Float(pad_v)) * Float(texels_per_uv_y) - Float(0.5f));
  Int y1 = floor_index((v_hi + Float(pad_v)) * Float(texels_per_uv_y) - Float(0.5f)) + Int(1);
  const int top = view.levels() - 1;
  Int level(0);
  for (int k = 0; k < top; ++k) {
    const simd::IntMask wide = ((x1 - x0) > Int(1)) | ((y1 - y0) > Int(1));
    if (!xsimd::any(wide)) break;
    level = xsimd::select(wide, level + Int(1), level);
    x0 = xsimd::select(wide, x0 >> 1, x0);
    x1 = xsimd::select(wide, x1 >> 1, x1);
    y0 = xsimd::select(wide, y0 >> 1, y0);
    y1 = xsimd::select(wide, y1 >> 1, y1);
  }
  const Int size_x = simd::load_i32(view.widths(), level, sampler().fetch);
  const Int size_y = simd::load_i32(view.heights(), level, sampler().fetch);
  const Int mask_x = size_x - Int(1), mask_y = size_y - Int(1);
  for (int i = 0; i < kMaxLayers; ++i) weights_[i] = Float(0.0f);
  for (int corner = 0; corner < 4; ++corner) {
    const Int x = ((corner & 1) ? x1 : x0) & mask_x, y = ((corner & 2) ? y1 : y0) & mask_y;
    Float texel[4];
    load(view, level, x, y, sampler().fetch, texel);
    for (int i = 0; i < count_; ++i) weights_[i] = xsimd::max(weights_[i], texel[i]);
  }
}

void BlendedSurface::weights_at(const Float& u, const Float& v, Float* w) const {
  if (!texture_.view) {
    for (int i = 0; i < count_; ++i) w[i] = weights_[i];
    return;
  }
  const Float inv(1.0f / texture_.scale);
  Float texel[4];
  sample(*texture_.view, weight_sampler(sampler()), u * inv, v * inv, Float(0.0f), texel);
  for (int i = 0; i < count_; ++i) w[i] = texel[i];
}

Float BlendedSurface::combine(const Float* h, const Float* w) const {
  if (op_ == BlendOperator::Alpha) {
    Float sum_wh(0.0f), sum_w(0.0f);
    for (int i = 0; i < count_; ++i) {
      sum_wh += w[i] * h[i];
      sum_w += w[i];
    }
    return xsimd::select(sum_w > Float(0.0f), sum_wh / sum_w, Float(0.0f));
  }
  Float top(0.0f);
  for (int i = 0; i < count_; ++i) top = xsimd::max(top, w[i] * h[i]);
  return top;
}

Float BlendedSurface::height(const Float& u, const Float& v, const Float& lod) const {
  Float h[kMaxLayers], w[kMaxLayers];
  for (int i = 0; i < count_; ++i) h[i] = layers_[i].height(u, v, lod);
  weights_at(u, v, w);
  return combine(h, w);
}

// Above level 0: the height operator's max(hmax_i * wmax_i); for alpha blending, a weighted average never exceeds
// the highest layer with any weight (the exact weighted form when the weights are the vertex constants).
Float BlendedSurface::bound(const Float* hmax) const {
  if (op_ == BlendOperator::Alpha) {
    if (!texture_.view) return combine(hmax, weights_);
    Float top(0.0f);
    for (int i = 0; i < count_; ++i) top = xsimd::max(top, xsimd::select(weights_[i] > Float(0.0f), hmax[i], Float(0.0f)));
    return top;
  }
  return combine(hmax, weights_);
}

Float BlendedSurface::cell_max(const Int& level, const Int& cx, const Int& cy) const {
  Float hmax[kMaxLayers];
  for (int i = 0; i < count_; ++i) hmax[i] = layers_[i].cell_max(level, cx, cy);
  Float result = bound(hmax);
  const simd::IntMask texel = level == Int(0);
  if (texture_.view && xsimd::any(texel)) {
    // Level 0: the box value with the weights at the texel centre (unwrapped: the weight map does not repeat
    // with the layers).
    Float w[kMaxLayers];
    weights_at((xsimd::to_float(cx) + Float(0.5f)) / Float(float(width())),
               (xsimd::to_float(cy) + Float(0.5f)) / Float(float(height())), w);
    result = xsimd::select(simd::float_mask(texel), combine(hmax, w), result);
  }
  return result;
}

Float BlendedSurface::cell_max_filtered(const Float& u, const Float& v, const Float& level) const {
  Float hmax[kMaxLayers];
  for (int i = 0; i < count_; ++i) hmax[i] = layers_[i].cell_max_filtered(u, v, level);
  return bound(hmax);
}

}  // namespace qdmr
