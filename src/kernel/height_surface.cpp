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
      inline_max_chain(inline_load_for(tree.key())) {}

}  // namespace qdmr::QDMR_ISA_NAMESPACE
