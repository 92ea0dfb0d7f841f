#pragma once
// HeightSurface: what the displacement techniques, self-shadowing and ambient occlusion march through.
// Heights h in [0, 1] over the UV plane, 1 at the polygon: at depth scale ds the surface lies at depth
// ds * (1 - h). Two views of one surface:
//   height(u, v, lod)            the filtered surface as the material's technique fetches it;
//   cell_max(level, cx, cy)      a conservative maximum over a cell of the level-0 texel grid (wrap addressing),
//                                exact at level 0 (the box surface QDM intersects).
// SingleLayerSurface is one height texture with its max-quadtree; BlendedSurface (shade/blend.hpp) combines
// up to four. Both are small per-batch values; the algorithms are templates over the surface type.
#include <optional>

#include "core/simd.hpp"
#include "qdmr/scene/scene.hpp"
#include "texture/sampler.hpp"

namespace qdmr::QDMR_ISA_NAMESPACE {

class SingleLayerSurface {
public:
  // height: box-filtered heights; quadtree: its max chain (power-of-two sizes), or null when the material
  // needs no hierarchy (then cell_max is only valid at level 0).
  SingleLayerSurface(const TextureView& height, const TextureView* quadtree, const SamplerState& sampler,
                     HeightFetch fetch)
      : height_(&height), quadtree_(quadtree), sampler_(sampler), fetch_(fetch) {}

  int width() const { return height_->texture().width(); }
  int height() const { return height_->texture().height(); }
  // The surface for queries within a UV box (blended surfaces bound their weights over it; one layer has none).
  SingleLayerSurface around(const simd::Float&, const simd::Float&, const simd::Float&, const simd::Float&) const {
    return *this;
  }
  bool has_hierarchy() const { return quadtree_ != nullptr; }
  int top_level() const { return quadtree_ ? quadtree_->levels() - 1 : 0; }
  const SamplerState& sampler() const { return sampler_; }
  HeightFetch fetch() const { return fetch_; }

  // The filtered surface: the nearest or bilinear level-0 texel (the surfaces the exact reference knows), or
  // trilinear with `lod` (the talk's POM), which smooths heights with distance.
  simd::Float height(const simd::Float& u, const simd::Float& v, const simd::Float& lod) const {
    SamplerState state = sampler_;
    if (fetch_ != HeightFetch::Trilinear) state.filter = fetch_ == HeightFetch::Point ? Filter::Point : Filter::Bilinear;
    simd::Float h[4];
    sample(*height_, state, u, v, lod, h);
    return h[0];
  }

  // The highest level-0 height in cell (cx, cy) of `level`; indices wrap (power-of-two level sizes).
  simd::Float cell_max(const simd::Int& level, const simd::Int& cx, const simd::Int& cy) const {
    const TextureView& tree = quadtree_ ? *quadtree_ : *height_;
    const simd::Int size_x = simd::load_i32(tree.widths(), level, sampler_.fetch);
    const simd::Int size_y = simd::load_i32(tree.heights(), level, sampler_.fetch);
    simd::Float texel[4];
    load(tree, level, cx & (size_x - simd::Int(1)), cy & (size_y - simd::Int(1)), sampler_.fetch, texel);
    return texel[0];
  }

  // The highest height anywhere (a bound for early exits).
  simd::Float max_height() const { return cell_max(simd::Int(top_level()), simd::Int(0), simd::Int(0)); }

  // LinearMipMapLinear over the max chain at (u, v) on `level` (the talk: "possible but may introduce some
  // artifacts"): smooths the maxima, so it is not conservative.
  simd::Float cell_max_filtered(const simd::Float& u, const simd::Float& v, const simd::Float& level) const {
    SamplerState trilinear = sampler_;
    trilinear.filter = Filter::Trilinear;
    trilinear.address = AddressMode::Wrap;
    trilinear.lod_bias = 0.0f;
    trilinear.min_lod = 0.0f;
    trilinear.max_lod = 16.0f;
    simd::Float texel[4];
    sample(quadtree_ ? *quadtree_ : *height_, trilinear, u, v, level, texel);
    return texel[0];
  }

private:
  const TextureView* height_;
  const TextureView* quadtree_;
  SamplerState sampler_;
  HeightFetch fetch_;
};

}  // namespace qdmr::QDMR_ISA_NAMESPACE
