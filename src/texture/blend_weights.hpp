#pragma once
// Blend weights of up to four layers: the weight map a material describes (noise, terrain rules or a file),
// the per-pixel weight texture made from it, and the per-vertex weights sampled from it.
#include <string>
#include <vector>

#include <glm/vec2.hpp>
#include <glm/vec4.hpp>

#include "qdmr/scene/scene.hpp"
#include "qdmr/texture/image.hpp"
#include "qdmr/texture/heightfield.hpp"
#include "qdmr/texture/mip_texture.hpp"
#include "texture/height_view.hpp"

namespace qdmr {

// RGBA float image over one span of the weight map (it wraps), channel i = weight of layer i in [0, 1].
// noise and terrain maps are scaled per texel so that the strongest layer has weight 1 (pure regions show
// one layer's full height under the height-blend surface max(w_i h_i)); file maps are used as stored.
// Throws qdmr::Error(where + "/...", ...) on unreadable inputs.
Image make_weight_map(const WeightsDesc& desc, int layers, const std::string& where);

// Per-vertex weights: the map sampled bilinearly (wrapping) at uv / scale.
std::vector<glm::vec4> vertex_weights(const Image& map, const std::vector<glm::vec2>& uvs, float scale);

// The talk's "small texture from vertex blend weights": the triangles (3 indices each) rasterized in weight-map
// space (uv / scale, wrapping) at the texture's resolution, each texel centre inside a triangle taking the
// interpolated vertex weights; texels no triangle covers keep their value. Later triangles overwrite.
void rasterize_vertex_weights(const std::vector<glm::vec2>& uvs, const std::vector<std::uint32_t>& indices,
                              const std::vector<glm::vec4>& weights, float scale, Image& texture);

// The per-pixel weight texture from its level 0 (resampled or rasterized): RGBA8 linear, with a max chain so
// coarse levels bound the weights of regions (reduced by `extremum`, see make_mip_texture).
Texture make_weight_texture(const Image& level0, MipExtremum extremum = nullptr);
// The map resampled (bilinear, wrapping) to resolution x resolution.
Image resample_weight_map(const Image& map, int resolution);

// The box surface of a blend with per-pixel weights (BlendedSurface's level 0) over the `scale` texture repeats
// the weight texture spans, in fp64, for the exact reference: texel (x, y) combines the layers' level-0 texel
// (x mod W, y mod H) with the weights sampled bilinearly at its centre. `scale` is a whole number of repeats.
HeightField combined_surface(const std::vector<const Texture*>& heights, const Texture& weights, int scale,
                             BlendOperator op);

// The precomputed combined quadtree of such a surface (WeightTexture::combined): level k = the maxima over cells
// of level k + 1, R16 rounded up (conservative for the fp32 box values the shader computes); levels 2.. reduced by
// `extremum` (make_mip_texture). From an fp64 surface, or from the fp32 box values the walk reads (the same tree as
// from their fp64 copy).
template <class T>
Texture combined_quadtree(const HeightView<T>& surface, MipExtremum extremum = nullptr);
inline Texture combined_quadtree(const HeightField& surface, MipExtremum extremum = nullptr) {
  return combined_quadtree(height_view(surface), extremum);
}

}  // namespace qdmr
