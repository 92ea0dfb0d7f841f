#pragma once
// HeightSurface: what the displacement techniques, self-shadowing and ambient occlusion march through.
// Heights h in [0, 1] over the UV plane, 1 at the polygon: at depth scale ds the surface lies at depth
// ds * (1 - h). Two views of one surface:
//   height(u, v, lod)            the filtered surface as the material's technique fetches it;
//   cell_max(level, cx, cy, needed)  a conservative maximum over a cell of the level-0 texel grid (wrap
//                                addressing), exact at level 0 (the box surface QDM intersects), in the lanes of
//                                `needed` (every lane by default; the others get any value).
// SingleLayerSurface is one height texture with its max-quadtree; BlendedSurface (kernel/blended_surface.hpp) combines
// up to four. Both are small per-batch values; the algorithms are templates over the surface type.
#include <array>
#include <cstdint>

#include "core/simd.hpp"
#include "qdmr/core/material_modes.hpp"
#include "kernel/sampler.hpp"
#include "kernel/sampling_code.hpp"

namespace qdmr::QDMR_ISA_NAMESPACE {

// The height fetches inlined into the tracing loops (a call through the sampler's pointer would make each loop
// spill its vector registers): bilinear 8- and 16-bit heights with wrap addressing on a power-of-two map, the
// default fetch of the usual height map, with exact weights or 8-bit ones (precision hw8, math sm4 or exact: its
// key's exact_texel). Any other key calls its sampler.
enum class InlineHeight : std::uint8_t { None, BilinearR8, BilinearR16, BilinearR8Hw8, BilinearR16Hw8 };

// fraction_bits: 0 (exact weights) or 8 (hw8).
constexpr SamplerKey inline_height_key(TexelFormat format, int fraction_bits = 0) {
  SamplerKey k;
  k.filter = Filter::Bilinear;
  k.address = AddressMode::Wrap;
  k.fraction_bits = fraction_bits;
  k.exact_texel = fraction_bits > 0;
  k.format = format;
  k.srgb = false;
  k.fetch = simd::kHasHardwareGather ? simd::FetchPath::Gather : simd::FetchPath::Portable;
  return k;
}

// The max chain's texel loads inlined into QDM's traversal, which reads one every step, for 8- and 16-bit chains
// (max chains of 8- and 16-bit heights) fetched as inline_height_key's are; any other chain calls its sampler.
enum class InlineMaxChain : std::uint8_t { None, R8, R16 };

// Which inline texel load gives the bits of a sampler with key k's load() (it reads only the format, the sRGB
// flag and the fetch path): also used for cone stepping's height reads.
inline InlineMaxChain inline_load_for(const SamplerKey& k) {
  for (const TexelFormat format : {TexelFormat::R16, TexelFormat::R8})
    if (k.format == format && k.srgb == inline_height_key(format).srgb && k.fetch == inline_height_key(format).fetch)
      return format == TexelFormat::R16 ? InlineMaxChain::R16 : InlineMaxChain::R8;
  return InlineMaxChain::None;
}

// Texel (x, y) of `level` loaded inline as a sampler with inline_height_key(R16 or R8) loads it (wrap: indices
// wrap, else they are clamped); false, with nothing loaded, for InlineMaxChain::None (the caller then calls its
// sampler). Recorded false: no texture-cache recorder listens (sampling_code::fetch).
template <bool Recorded>
[[gnu::always_inline]] inline bool load_inline(InlineMaxChain chain, bool wrap, const TextureView& view,
                                               const simd::Int& level, const simd::Int& x, const simd::Int& y,
                                               simd::Float* texel) {
  if (chain == InlineMaxChain::None) return false;
  if (chain == InlineMaxChain::R16)
    sampling_code::load_with(inline_height_key(TexelFormat::R16), wrap, view, level, x, y, texel, Recorded);
  else
    sampling_code::load_with(inline_height_key(TexelFormat::R8), wrap, view, level, x, y, texel, Recorded);
  return true;
}

// The decoded copy of a one-channel max chain whose level sizes are level 0's shifted right (at least 1), as QDM's
// paired walks read it at every step: a texel's index from its level's start and level 0's wrap masks shifted by
// the level. No table of sizes, no level clamp (a walk stays within the chain), no test of the texture's format or
// of its decoded copy per fetch: the same texels as cell_max, in fewer instructions.
struct MaxChainCells {
  const Texture* texture = nullptr;  // null: not such a chain (the walks call cell_max)
  std::int32_t width_mask = 0, height_mask = 0;  // level 0's width - 1, height - 1
  simd::FetchPath fetch = simd::FetchPath::Portable;
  alignas(64) std::array<std::int32_t, TextureView::kMaxLevels> start{};  // each level's first texel, decoded

  // The cells of `tree` (a sampler's view of a max chain read inline, `chain`), or none.
  MaxChainCells(const TextureSampler& tree, InlineMaxChain chain);

  // The decoded texels as they are now, or null (no decoded copy: read through cell_max).
  const float* texels() const {
    return texture != nullptr && !texture->linear.empty() ? texture->linear.data() : nullptr;
  }

  // Cell (cx, cy) of `level` from texels(), 0 <= level < the chain's levels; indices wrap.
  [[gnu::always_inline]] simd::Float at(const float* texels, const simd::Int& level, const simd::Int& cx,
                                        const simd::Int& cy) const {
    using simd::Int;
    const Int wrap_x = Int(width_mask) >> level, wrap_y = Int(height_mask) >> level;
    const Int index = simd::lookup16(start.data(), level) + (cy & wrap_y) * (wrap_x + Int(1)) + (cx & wrap_x);
    return simd::load_f32(texels, index, fetch);
  }
};

// The textures of one height layer, bound once per program to the samplers its material fixes.
struct HeightLayerTextures {
  // height: box-filtered heights; quadtree: its max chain (power-of-two sizes), or null when the material needs
  // no hierarchy (then cell_max is only valid at level 0).
  HeightLayerTextures(const Texture& height, const Texture* quadtree, const SamplerState& sampler, HeightFetch fetch);

  TextureSampler height;  // sampled as the height fetch says: point, bilinear or the material's filter
  TextureSampler tree;    // the max chain (or the heights, without one), trilinear with wrap (cell_max_filtered)
  bool has_tree;
  SamplerState sampler;   // the material's
  HeightFetch fetch;
  InlineHeight inline_height;
  InlineMaxChain inline_max_chain;
  MaxChainCells max_chain_cells;
};

// An inline height fetch (key K) over a power-of-two texture's wrap footprints at finite coordinates, with what it
// reads of the texture read once, when it is made: a loop that takes one before it keeps them in registers
// (through the surface's pointer, the loop reads them again at every step). Never recorded.
template <SamplerKey K>
struct FootprintHeight {
  explicit FootprintHeight(const TextureView& view)
      : footprints(view.texture().wrap_footprints.data()), level0(sampling_code::level_zero(view)),
        w(xsimd::to_float(level0.width)), h(xsimd::to_float(level0.height)) {}
  [[gnu::always_inline]] simd::Float operator()(const simd::Float& u, const simd::Float& v, const simd::Float&) const {
    return sampling_code::sample_wrap_footprints<K>(footprints, level0, w, h, u, v);
  }
  const float* footprints;
  sampling_code::LevelInfo level0;
  simd::Float w, h;
};

class SingleLayerSurface {
public:
  explicit SingleLayerSurface(const HeightLayerTextures& textures) : textures_(&textures) {}

  int width() const { return textures_->height.texture().width(); }
  int height() const { return textures_->height.texture().height(); }
  // The surface for queries within a UV box (blended surfaces bound their weights over it; one layer has none).
  SingleLayerSurface around(const simd::Float&, const simd::Float&, const simd::Float&, const simd::Float&) const {
    return *this;
  }
  bool has_hierarchy() const { return textures_->has_tree; }
  int top_level() const { return textures_->has_tree ? textures_->tree.view().levels() - 1 : 0; }
  const SamplerState& sampler() const { return textures_->sampler; }
  HeightFetch fetch() const { return textures_->fetch; }

  // The filtered surface: the nearest or bilinear level-0 texel (the surfaces the exact reference knows), or
  // trilinear with `lod` (the talk's POM), which smooths heights with distance. Recorded false: as for cell_max.
  template <bool Recorded = true>
  [[gnu::always_inline]] simd::Float height(const simd::Float& u, const simd::Float& v, const simd::Float& lod) const {
    const TextureSampler& t = textures_->height;
    switch (textures_->inline_height) {
      case InlineHeight::BilinearR16:
        return sampling_code::sample_first<inline_height_key(TexelFormat::R16), Recorded>(t.view(), t.state(), u, v, lod);
      case InlineHeight::BilinearR8:
        return sampling_code::sample_first<inline_height_key(TexelFormat::R8), Recorded>(t.view(), t.state(), u, v, lod);
      case InlineHeight::BilinearR16Hw8:
        return sampling_code::sample_first<inline_height_key(TexelFormat::R16, 8), Recorded>(t.view(), t.state(), u, v,
                                                                                              lod);
      case InlineHeight::BilinearR8Hw8:
        return sampling_code::sample_first<inline_height_key(TexelFormat::R8, 8), Recorded>(t.view(), t.state(), u, v,
                                                                                             lod);
      case InlineHeight::None: break;
    }
    simd::Float h[4];
    t.sample(u, v, lod, h);
    return h[0];
  }

  // Calls f(fetch) with fetch(u, v, lod) = height<Recorded>(u, v, lod), the same bits: a FootprintHeight where the
  // heights are inline and have wrap footprints, no recorder listens and the caller knows that every coordinate
  // it will fetch at (in the lanes it reads) is finite (`finite`), for a loop in f to take before it starts.
  template <bool Recorded, class F>
  [[gnu::always_inline]] void with_height(bool finite, const F& f) const {
    const TextureSampler& t = textures_->height;
    if (!Recorded && finite && t.view().power_of_two() && !t.texture().wrap_footprints.empty()) {
      switch (textures_->inline_height) {
        case InlineHeight::BilinearR16: return f(FootprintHeight<inline_height_key(TexelFormat::R16)>(t.view()));
        case InlineHeight::BilinearR8: return f(FootprintHeight<inline_height_key(TexelFormat::R8)>(t.view()));
        case InlineHeight::BilinearR16Hw8: return f(FootprintHeight<inline_height_key(TexelFormat::R16, 8)>(t.view()));
        case InlineHeight::BilinearR8Hw8: return f(FootprintHeight<inline_height_key(TexelFormat::R8, 8)>(t.view()));
        case InlineHeight::None: break;
      }
    }
    f([this](const simd::Float& u, const simd::Float& v, const simd::Float& lod)
          __attribute__((always_inline)) { return height<Recorded>(u, v, lod); });
  }

  // The highest level-0 height in cell (cx, cy) of `level`; indices wrap (power-of-two level sizes). Recorded
  // false: the caller knows the texture-cache recorder does not listen (sampling_code::fetch). One load serves
  // every lane, so the lanes that need the value change nothing.
  template <bool Recorded = true>
  [[gnu::always_inline]] simd::Float cell_max(const simd::Int& level, const simd::Int& cx, const simd::Int& cy,
                                              const simd::Mask& /*needed*/ = simd::Mask(true)) const {
    const TextureSampler& t = textures_->tree;
    simd::Float texel[4];
    if (!load_inline<Recorded>(textures_->inline_max_chain, true, t.view(), level, cx, cy, texel))
      t.load_wrapped(level, cx, cy, texel);
    return texel[0];
  }

  // The max chain's cells for QDM's paired walks (see MaxChainCells::texels()).
  const MaxChainCells& max_chain_cells() const { return textures_->max_chain_cells; }

  // The highest height anywhere (a bound for early exits).
  simd::Float max_height() const { return cell_max(simd::Int(top_level()), simd::Int(0), simd::Int(0)); }

  // LinearMipMapLinear over the max chain at (u, v) on `level` (the talk: "possible but may introduce some
  // artifacts"): smooths the maxima, so it is not conservative.
  simd::Float cell_max_filtered(const simd::Float& u, const simd::Float& v, const simd::Float& level) const {
    simd::Float texel[4];
    textures_->tree.sample(u, v, level, texel);
    return texel[0];
  }

private:
  const HeightLayerTextures* textures_;
};

}  // namespace qdmr::QDMR_ISA_NAMESPACE
