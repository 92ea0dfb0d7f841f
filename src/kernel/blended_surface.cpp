#include "kernel/blended_surface.hpp"

#include "kernel/traversal.hpp"

namespace qdmr::QDMR_ISA_NAMESPACE {
namespace {

using simd::Float;
using simd::Int;

Int floor_index(const Float& x) {
  return xsimd::to_int(xsimd::floor(xsimd::max(xsimd::min(x, Float(kMaxTexelCoordinate)), Float(-kMaxTexelCoordinate))));
}

// Cell index i of a level whose period is p cells, wrapped into [0, p) (|i| < 2^24, as in the traversals).
Int wrap_cell(const Int& i, const Int& p) {
  const Int q = xsimd::to_int(xsimd::floor(xsimd::to_float(i) / xsimd::to_float(p)));
  Int r = i - q * p;
  r = xsimd::select(r < Int(0), r + p, r);
  return xsimd::select(r >= p, r - p, r);
}

// The weights of `count` layers at (u, v) (layer UV), sampled bilinearly from the weight texture.
void sample_weights(const WeightTexture& t, int count, const Float& u, const Float& v, Float* w) {
  const Float inv(1.0f / t.scale);
  Float texel[4];
  t.view->sample(u * inv, v * inv, Float(0.0f), texel);
  for (int i = 0; i < count; ++i) w[i] = texel[i];
}

}  // namespace

Float combine_layers(BlendOperator op, int count, const Float* h, const Float* w) {
  if (op == BlendOperator::Alpha) {
    Float sum_wh(0.0f), sum_w(0.0f);
    for (int i = 0; i < count; ++i) {
      sum_wh += w[i] * h[i];
      sum_w += w[i];
    }
    return xsimd::select(sum_w > Float(0.0f), sum_wh / sum_w, Float(0.0f));
  }
  Float top(0.0f);
  for (int i = 0; i < count; ++i) top = xsimd::max(top, w[i] * h[i]);
  return top;
}

Float level0_box_value(const WeightTexture& weights, BlendOperator op, int count, unsigned present,
                       simd::FetchPath fetch, const Int& cx, const Int& cy) {
  // The same decoded heights as each layer's chain holds at level 0 (wrap: power-of-two sizes).
  const LayerHeights& lh = *weights.layer_heights;
  const Int texel = (cy & Int(lh.height - 1)) * Int(lh.width) + (cx & Int(lh.width - 1));
  Float all[BlendedSurface::kMaxLayers], h[BlendedSurface::kMaxLayers], w[BlendedSurface::kMaxLayers];
  simd::load_f32x4(lh.texels.data(), texel * Int(4), fetch, all);
  for (int i = 0; i < count; ++i) h[i] = (present >> i) & 1u ? all[i] : Float(0.0f);
  sample_weights(weights, count, (xsimd::to_float(cx) + Float(0.5f)) / Float(float(lh.width)),
                 (xsimd::to_float(cy) + Float(0.5f)) / Float(float(lh.height)), w);
  return combine_layers(op, count, h, w);
}

SamplerState weight_sampler_state(const SamplerState& material) {
  SamplerState s;
  s.filter = Filter::Bilinear;
  s.address = AddressMode::Wrap;
  s.fetch = material.fetch;
  return s;
}

BlendedSurface::BlendedSurface(const SingleLayerSurface* layers, int count, BlendOperator op, const Float* w)
    : layers_(layers), count_(count), op_(op) {
  for (int i = 0; i < kMaxLayers; ++i) weights_[i] = i < count ? w[i] : Float(0.0f);
  find_present();
}

BlendedSurface::BlendedSurface(const SingleLayerSurface* layers, int count, BlendOperator op, const WeightTexture& weights,
                               const Float& u_lo, const Float& u_hi, const Float& v_lo, const Float& v_hi)
    : layers_(layers), count_(count), op_(op), texture_(weights) {
  // Half a layer texel of padding: box-surface queries read the weights at texel centres.
  const Float pad_u(0.5f / float(width())), pad_v(0.5f / float(height()));
  bound_weights(u_lo - pad_u, u_hi + pad_u, v_lo - pad_v, v_hi + pad_v, weights_);
  find_present();
}

// A layer whose weight is 0 in every lane adds nothing to either operator: its heights are not fetched.
void BlendedSurface::find_present() {
  present_ = 0;
  for (int i = 0; i < count_; ++i)
    if (xsimd::any(weights_[i] > Float(0.0f))) present_ |= 1u << i;
}

// The largest weight of each layer that bilinear sampling can return inside the box: the maximum over the weight
// texels whose footprint touches it (floor of the low end, ceiling of the high end: a sample exactly on a texel
// centre reads that texel alone), read from the max chain at the first level where they fit in 2x2 texels.
void BlendedSurface::bound_weights(const Float& u_lo, const Float& u_hi, const Float& v_lo, const Float& v_hi,
                                   Float* w) const {
  const TextureView& view = texture_.view->view();
  const float texels_per_uv_x = float(view.texture().width()) / texture_.scale;
  const float texels_per_uv_y = float(view.texture().height()) / texture_.scale;
  Int x0 = floor_index(u_lo * Float(texels_per_uv_x) - Float(0.5f));
  Int x1 = Int(0) - floor_index(Float(0.5f) - u_hi * Float(texels_per_uv_x));
  Int y0 = floor_index(v_lo * Float(texels_per_uv_y) - Float(0.5f));
  Int y1 = Int(0) - floor_index(Float(0.5f) - v_hi * Float(texels_per_uv_y));
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
  for (int i = 0; i < kMaxLayers; ++i) w[i] = Float(0.0f);
  for (int corner = 0; corner < 4; ++corner) {
    Float texel[4];
    texture_.view->load_wrapped(level, (corner & 1) ? x1 : x0, (corner & 2) ? y1 : y0, texel);
    for (int i = 0; i < count_; ++i) w[i] = xsimd::max(w[i], texel[i]);
  }
}

void BlendedSurface::weights_at(const Float& u, const Float& v, Float* w) const {
  if (!texture_.view) {
    for (int i = 0; i < count_; ++i) w[i] = weights_[i];
    return;
  }
  sample_weights(texture_, count_, u, v, w);
}

Float BlendedSurface::combine(const Float* h, const Float* w) const { return combine_layers(op_, count_, h, w); }

Float BlendedSurface::height(const Float& u, const Float& v, const Float& lod) const {
  Float h[kMaxLayers], w[kMaxLayers];
  for (int i = 0; i < count_; ++i) h[i] = present(i) ? layer_fetch(i, [&](const auto& l) { return l.height(u, v, lod); }) : Float(0.0f);
  weights_at(u, v, w);
  return combine(h, w);
}

// Above level 0: the height operator's max(hmax_i * wmax_i); for alpha blending, a weighted average never exceeds
// the highest layer with any weight (the exact weighted form when the weights are the vertex constants).
Float BlendedSurface::bound(const Float* hmax, const Float* wmax) const {
  if (op_ == BlendOperator::Alpha) {
    if (!texture_.view) return combine(hmax, wmax);
    Float top(0.0f);
    for (int i = 0; i < count_; ++i) top = xsimd::max(top, xsimd::select(wmax[i] > Float(0.0f), hmax[i], Float(0.0f)));
    return top;
  }
  return combine(hmax, wmax);
}

Float BlendedSurface::combined_cell_max(const Int& level, const Int& cell_x, const Int& cell_y,
                                        const simd::Mask& needed) const {
  const simd::IntMask coarse = level >= Int(1);
  const simd::Mask fine = ~simd::float_mask(coarse);
  Float result(0.0f);
  if (xsimd::any(~fine & needed)) {
    FetchLanes lanes;  // the batch reads the tree for every lane; only the coarse ones need it
    lanes.narrow(simd::float_mask(coarse));
    Float texel[4];
    texture_.combined->load(xsimd::max(level - Int(1), Int(0)), wrap_cell(cell_x, Int(texture_.period_u) >> level),
                            wrap_cell(cell_y, Int(texture_.period_v) >> level), texel);
    result = texel[0];
  }
  if (!xsimd::any(fine & needed)) return result;
  // Level 0: the exact box value, as the combined tree was built from.
  const bool fast = texture_.layer_heights != nullptr && !fetch_recorder_listens();
  if (fast && texture_.box_values != nullptr) {
    // From the period's table where every needed level-0 lane is inside the period (a cell outside it reads its
    // weights at other coordinates than the cell it repeats, so its value may differ in the last bit).
    const int period = texture_.period_u;  // = period_v: the table is made for square periods only
    const simd::IntMask inside =
        (cell_x >= Int(0)) & (cell_x < Int(period)) & (cell_y >= Int(0)) & (cell_y < Int(period));
    if (!xsimd::any(fine & needed & ~simd::float_mask(inside))) {
      const Int cell = xsimd::select(inside & ~coarse, cell_y * Int(period) + cell_x, Int(0));
      const Float value = simd::load_f32(texture_.box_values, cell, sampler().fetch);
      return xsimd::select(simd::float_mask(coarse), result, value);
    }
  }
  FetchLanes lanes;
  lanes.narrow(fine);
  // The coarse lanes' values are dropped below; they read one fixed cell instead of their own small indices,
  // which sit at the weight map's wrap edge and sent most batches' bilinear weight samples to the per-texel path
  // (3 in 5 on the terrain).
  const Int middle(width() / 2);
  const Int cx = xsimd::select(coarse, middle, cell_x), cy = xsimd::select(coarse, middle, cell_y);
  if (fast)
    return xsimd::select(simd::float_mask(coarse), result,
                         level0_box_value(texture_, op_, count_, present_, sampler().fetch, cx, cy));
  Float h[kMaxLayers], w[kMaxLayers];
  for (int i = 0; i < count_; ++i)
    h[i] = present(i) ? layer_fetch(i, [&](const auto& l) { return l.cell_max(Int(0), cx, cy); }) : Float(0.0f);
  weights_at((xsimd::to_float(cx) + Float(0.5f)) / Float(float(width())),
             (xsimd::to_float(cy) + Float(0.5f)) / Float(float(height())), w);
  return xsimd::select(simd::float_mask(coarse), result, combine(h, w));
}

Float BlendedSurface::tree_max(const Int& level, const Int& cx, const Int& cy, const simd::Mask& needed) const {
  if (texture_.combined) return combined_cell_max(level, cx, cy, needed);
  Float hmax[kMaxLayers];
  for (int i = 0; i < count_; ++i)
    hmax[i] = present(i) ? layer_fetch(i, [&](const auto& l) { return l.cell_max(level, cx, cy); }) : Float(0.0f);
  if (!texture_.view) return bound(hmax, weights_);
  // Per pixel: the weights' maxima over the cell (from the weight texture's max chain), within those over the
  // batch's query box — "QDM1 * QDM2", each cell bounded by its own maxima.
  // The box surface reads weights at the centres of the cell's level-0 texels.
  const Float cell = xsimd::to_float(Int(1) << level);
  const Float first_x = xsimd::to_float(cx) * cell + Float(0.5f), first_y = xsimd::to_float(cy) * cell + Float(0.5f);
  const Float inv_w(1.0f / float(width())), inv_h(1.0f / float(height()));
  Float wmax[kMaxLayers];
  bound_weights(first_x * inv_w, (first_x + cell - Float(1.0f)) * inv_w, first_y * inv_h,
                (first_y + cell - Float(1.0f)) * inv_h, wmax);
  for (int i = 0; i < count_; ++i) wmax[i] = xsimd::min(wmax[i], weights_[i]);
  Float result = bound(hmax, wmax);
  const simd::IntMask texel = level == Int(0);
  if (xsimd::any(simd::float_mask(texel) & needed)) {
    FetchLanes lanes;
    lanes.narrow(simd::float_mask(texel));
    // Level 0: the box value with the weights at the texel centre (unwrapped: the weight map does not repeat
    // with the layers).
    Float w[kMaxLayers];
    weights_at((xsimd::to_float(cx) + Float(0.5f)) / Float(float(width())),
               (xsimd::to_float(cy) + Float(0.5f)) / Float(float(height())), w);
    result = xsimd::select(simd::float_mask(texel), combine(hmax, w), result);
  }
  return result;
}

Float BlendedSurface::max_height() const {
  Float hmax[kMaxLayers];
  for (int i = 0; i < count_; ++i) hmax[i] = present(i) ? layer_fetch(i, [](const auto& l) { return l.max_height(); }) : Float(0.0f);
  return bound(hmax, weights_);
}

Float BlendedSurface::cell_max_filtered(const Float& u, const Float& v, const Float& level) const {
  Float hmax[kMaxLayers];
  for (int i = 0; i < count_; ++i)
    hmax[i] = present(i) ? layer_fetch(i, [&](const auto& l) { return l.cell_max_filtered(u, v, level); }) : Float(0.0f);
  return bound(hmax, weights_);
}

}  // namespace qdmr::QDMR_ISA_NAMESPACE
