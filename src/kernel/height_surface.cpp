#include "kernel/height_surface.hpp"

#include <utility>

namespace qdmr::QDMR_ISA_NAMESPACE {
namespace {

SamplerState height_fetch_state(SamplerState state, HeightFetch fetch) {
  if (fetch != HeightFetch::Trilinear) state.filter = fetch == HeightFetch::Point ? Filter::Point : Filter::Bilinear;
  return state;
}

SamplerState max_chain_state(SamplerState state) {
  state.filter = Filter::Trilinear;
  state.address = AddressMode::Wrap;
  state.lod_bias = 0.0f;
  state.min_lod = 0.0f;
  state.max_lod = 16.0f;
  return state;
}

InlineHeight inline_height_for(const SamplerKey& k) {
  constexpr std::pair<SamplerKey, InlineHeight> kInline[] = {
      {inline_height_key(TexelFormat::R16), InlineHeight::BilinearR16},
      {inline_height_key(TexelFormat::R8), InlineHeight::BilinearR8},
      {inline_height_key(TexelFormat::R16, 8), InlineHeight::BilinearR16Hw8},
      {inline_height_key(TexelFormat::R8, 8), InlineHeight::BilinearR8Hw8}};
  for (const auto& [key, inline_height] : kInline)
    if (k == key) return inline_height;
  return InlineHeight::None;
}

}  // namespace

HeightLayerTextures::HeightLayerTextures(const Texture& height_texture, const Texture* quadtree,
                                         const SamplerState& material_sampler, HeightFetch height_fetch)
    : height(height_texture, height_fetch_state(material_sampler, height_fetch)),
      tree(quadtree ? *quadtree : height_texture, max_chain_state(material_sampler)),
      has_tree(quadtree != nullptr),
      sampler(material_sampler),
      fetch(height_fetch),
      inline_height(inline_height_for(height.key())),
      inline_max_chain(inline_load_for(tree.key())),
      max_chain_cells(tree, has_tree ? inline_max_chain : InlineMaxChain::None) {}

MaxChainCells::MaxChainCells(const TextureSampler& tree, InlineMaxChain chain) {
  const TextureView& view = tree.view();
  const Texture& t = view.texture();
  const SamplerKey key = inline_height_key(chain == InlineMaxChain::R16 ? TexelFormat::R16 : TexelFormat::R8);
  // An inline chain is R16 or linear R8: decoded_one_channel() whenever it has a decoded copy (texels()).
  if (chain == InlineMaxChain::None) return;
  const std::int32_t w = view.widths()[0], h = view.heights()[0];
  if ((w & (w - 1)) != 0 || (h & (h - 1)) != 0) return;
  for (int level = 0; level < view.levels(); ++level) {
    if (view.widths()[level] - 1 != (w - 1) >> level || view.heights()[level] - 1 != (h - 1) >> level) return;
    // The decoded copy's index of the level's first texel (sampling_code::decoded_index).
    start[std::size_t(level)] = chain == InlineMaxChain::R16 ? view.offsets()[level] >> 1 : view.offsets()[level];
  }
  width_mask = w - 1;
  height_mask = h - 1;
  fetch = key.fetch;
  texture = &t;
}

}  // namespace qdmr::QDMR_ISA_NAMESPACE
