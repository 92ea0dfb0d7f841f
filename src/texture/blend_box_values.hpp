#pragma once
// The level 0 of a per-pixel blend's combined quadtree: the blended box surface's value at every level-0 cell of
// one period (the layers' size times the repeats the weights span), as the draw kernels compute it in fp32 — the
// layers' level-0 heights (LayerHeights) and the weight texture sampled bilinearly at the cell's centre, blended
// by the operator. A QDM walk over the blend then reads one float per lane at a level-0 cell where it would
// blend there (about 200 instructions per batch, the same for 4 lanes as for 8): the same bits, and the walk's
// level-0 steps stop costing what its coarse steps do not.
#include <cstddef>
#include <cstdint>

#include "qdmr/core/zeroed_buffer.hpp"
#include "qdmr/core/material_modes.hpp"
#include "texture/height_view.hpp"
#include "texture/layer_heights.hpp"
#include "qdmr/texture/mip_texture.hpp"

namespace qdmr {

// What the box values keep for layers of width x height whose weights span `repeats` repeats, with
// interleaved level-0 heights of layer_heights_bytes: 4 bytes per cell of the period, where those heights exist
// (layer_heights_bytes > 0) and the period is square; else 0 (the walk blends at its level-0 cells).
std::uint64_t blend_box_values_bytes(int width, int height, int repeats, std::uint64_t layer_heights_bytes);

struct BlendBoxSource {
  const Texture* weights = nullptr;       // the RGBA8 weight texture (make_weight_texture)
  int repeats = 1;                        // the weight texture spans this many repeats of the layers
  const LayerHeights* heights = nullptr;  // the layers' level-0 heights, interleaved
  BlendOperator op = BlendOperator::Height;
  int layers = 1;
};

// How many floats the values of `source` are: period x period (period = heights->width * repeats), row by row,
// or 0 where blend_box_values_bytes() is 0. A draw kernel computes them (Kernel::blend_box_values, src/kernel/).
std::size_t blend_box_value_count(const BlendBoxSource& source);

// The values of a blend of these layer heights over `repeats` repeats (blend_box_value_count's layout: period =
// heights.width * repeats, square) as a height field that wraps: the surface the walk intersects, from which the
// combined quadtree and the blend's baked AO map are made. Throws when the values do not fill the period.
HeightView<float> box_value_view(const ZeroedBuffer<float>& values, const LayerHeights& heights, int repeats);

}  // namespace qdmr
