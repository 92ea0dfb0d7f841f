#pragma once
// BlendedSurface: up to four layers' heights combined by blend weights into the one surface the techniques
// march (see height_surface.hpp for the interface). The talk's operators:
//   alpha:  H = sum(w_i h_i) / sum(w_i)    (the usual reconstruction, an aggregate)
//   height: H = max(w_i h_i)               ("HB = max(h1..h4)", weighted as in the QDMHB slide)
// The weights come from the vertices (constant along a pixel's ray: the talk's view-dependent "floating"
// artifact), or from a weight texture sampled where the surface is evaluated (exact).
// cell_max is conservative: the level-0 box value is exact (weights at the texel centre), coarser cells use
// max(hmax_i * wmax_i) — "QDM1 * QDM2 = conservative QDM" — with wmax_i the largest weight over the UV box the
// queries of this batch stay in (from the weight texture's max chain), so QDM stays exact over the blend.
#include "texture/layer_heights.hpp"
#include "kernel/height_surface.hpp"
#include "kernel/fetch_trace.hpp"

namespace qdmr::QDMR_ISA_NAMESPACE {

struct WeightTexture {
  // RGBA8 linear, power-of-two, max chain; level 0 sampled bilinearly with wrap (weight_sampler_state)
  const TextureSampler* view = nullptr;
  float scale = 1.0f;                 // weight-map UV = layer UV / scale
  // Optional precomputed combined quadtree: level k holds the maxima of the blended box surface over cells of
  // level k + 1, over one period of period_u x period_v level-0 texels (the layers' size times the whole number
  // of repeats the weights span); values rounded up, so it stays conservative.
  const TextureSampler* combined = nullptr;
  int period_u = 0, period_v = 0;
  // With it, optional: the layers' level-0 heights side by side, read at the walk's level-0 cells (one load per
  // lane for every layer) while no texture-cache recorder listens (it sees each layer's chain read).
  const LayerHeights* layer_heights = nullptr;
  // With those, optional: the blended box surface's level-0 value of every cell of one (square) period (period_u²
  // floats, row by row; texture/blend_box_values.hpp), which the walk's level-0 cells inside that period read
  // instead of blending the layers' heights and the weights there (while no recorder listens).
  const float* box_values = nullptr;
};

// The state weight textures are sampled with, from the material's.
SamplerState weight_sampler_state(const SamplerState& material);

// The blend operator applied to layer heights h and weights w of `count` layers.
simd::Float combine_layers(BlendOperator op, int count, const simd::Float* h, const simd::Float* w);

// The blended box surface's value at level-0 cells (cx, cy) of the layers' texel grid: the layers' level-0
// heights (weights.layer_heights, whose size is the grid's) and the weight texture sampled bilinearly at the
// cell's centre, blended by `op`. Layers outside `present` count as height 0 (every lane's weight of them is 0).
simd::Float level0_box_value(const WeightTexture& weights, BlendOperator op, int count, unsigned present,
                             simd::FetchPath fetch, const simd::Int& cx, const simd::Int& cy);

class BlendedSurface {
public:
  static constexpr int kMaxLayers = 4;

  // Per-vertex weights: w[0..count) per lane.
  BlendedSurface(const SingleLayerSurface* layers, int count, BlendOperator op, const simd::Float* w);
  // Per-pixel weights; every query lies within [u_lo, u_hi] x [v_lo, v_hi] (layer UV).
  BlendedSurface(const SingleLayerSurface* layers, int count, BlendOperator op, const WeightTexture& weights,
                 const simd::Float& u_lo, const simd::Float& u_hi, const simd::Float& v_lo, const simd::Float& v_hi);

  // The same surface for queries within another UV box (per-pixel weights: their maxima over that box).
  BlendedSurface around(const simd::Float& u_lo, const simd::Float& u_hi, const simd::Float& v_lo,
                        const simd::Float& v_hi) const {
    if (!texture_.view) return *this;
    return BlendedSurface(layers_, count_, op_, texture_, u_lo, u_hi, v_lo, v_hi);
  }

  int width() const { return layers_[0].width(); }
  int height() const { return layers_[0].height(); }
  bool has_hierarchy() const { return layers_[0].has_hierarchy(); }
  int top_level() const { return layers_[0].top_level(); }
  const SamplerState& sampler() const { return layers_[0].sampler(); }
  HeightFetch fetch() const { return layers_[0].fetch(); }
  int layer_count() const { return count_; }
  const SingleLayerSurface& layer(int i) const { return layers_[i]; }

  simd::Float height(const simd::Float& u, const simd::Float& v, const simd::Float& lod) const;
  // Recorded false: the caller knows no texture-cache recorder listens (a paired walk); the blend's fetches ask
  // for themselves either way, so both give the same code. Only the lanes in `needed` get their value: the
  // level-0 box value and the coarse cells are each read only where a needed lane is at such a level.
  template <bool Recorded = true>
  simd::Float cell_max(const simd::Int& level, const simd::Int& cx, const simd::Int& cy,
                       const simd::Mask& needed = simd::Mask(true)) const {
    return tree_max(level, cx, cy, needed);
  }
  // The highest height anywhere the batch's queries go.
  simd::Float max_height() const;
  simd::Float cell_max_filtered(const simd::Float& u, const simd::Float& v, const simd::Float& level) const;

  // The layer weights at (u, v): the vertex weights, or the weight texture sampled bilinearly.
  void weights_at(const simd::Float& u, const simd::Float& v, simd::Float* w) const;
  // The blend operator applied to layer heights h and weights w.
  simd::Float combine(const simd::Float* h, const simd::Float* w) const;

private:
  // The largest weights bilinear sampling can return at layer-texel centres inside the UV box.
  void bound_weights(const simd::Float& u_lo, const simd::Float& u_hi, const simd::Float& v_lo, const simd::Float& v_hi,
                     simd::Float* w) const;
  simd::Float bound(const simd::Float* hmax, const simd::Float* wmax) const;
  void find_present();
  simd::Float tree_max(const simd::Int& level, const simd::Int& cx, const simd::Int& cy,
                       const simd::Mask& needed) const;
  simd::Float combined_cell_max(const simd::Int& level, const simd::Int& cx, const simd::Int& cy,
                                const simd::Mask& needed) const;
  bool present(int i) const { return (present_ >> i) & 1u; }
  // fetch(layer i), recorded for the texture cache only in the lanes where layer i has weight: on its own, the
  // batch reads a layer for every lane as soon as one lane needs it.
  template <class Fetch>
  simd::Float layer_fetch(int i, const Fetch& fetch) const {
    FetchLanes lanes;
    lanes.narrow(weights_[i] > simd::Float(0.0f));
    return fetch(layers_[i]);
  }

  const SingleLayerSurface* layers_;
  int count_;
  BlendOperator op_;
  WeightTexture texture_;        // view == nullptr: per-vertex weights
  simd::Float weights_[kMaxLayers];  // per-vertex: the weights; per-pixel: their maxima over the query box
  unsigned present_ = 0;             // bit i: layer i has weight in some lane
};

}  // namespace qdmr::QDMR_ISA_NAMESPACE
