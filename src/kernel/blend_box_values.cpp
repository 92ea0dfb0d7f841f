// The blend's level-0 box values (texture/blend_box_values.hpp), computed by this kernel with the code its
// QDM walks run at a level-0 cell (level0_box_value), so a walk reading them keeps its bits. Preparation runs it
// (Kernel::blend_box_values).
#include <tbb/parallel_for.h>

#include <algorithm>

#include "kernel/blended_surface.hpp"
#include "kernel/kernel_calls.hpp"
#include "kernel/preparation.hpp"

namespace qdmr::QDMR_ISA_NAMESPACE {

using simd::Int;
using simd::kLanes;

void blend_box_values(const BlendBoxSource& source, float* out) {
  kernel_calls.box_values.fetch_add(1, std::memory_order_relaxed);
  const LayerHeights& heights = *source.heights;
  const int period = heights.width * source.repeats;
  const SamplerState state = weight_sampler_state(SamplerState{});
  const TextureSampler weight_view(*source.weights, state);
  WeightTexture weights;
  weights.view = &weight_view;
  weights.scale = float(source.repeats);
  weights.layer_heights = &heights;
  // Every layer: where one has no weight in a batch the walk leaves its height out, and 0 * height is 0 either way.
  const unsigned all_layers = (1u << source.layers) - 1u;
  tbb::parallel_for(0, period, [&](int y) {
    float* row = out + std::size_t(y) * std::size_t(period);
    for (int x = 0; x < period; x += kLanes) {
      alignas(64) std::int32_t cells[kLanes];
      alignas(64) float values[kLanes];
      for (int l = 0; l < kLanes; ++l) cells[l] = std::min(x + l, period - 1);
      level0_box_value(weights, source.op, source.layers, all_layers, state.fetch, Int::load_aligned(cells), Int(y))
          .store_aligned(values);
      std::copy_n(values, std::min(kLanes, period - x), row + x);
    }
  });
}

}  // namespace qdmr::QDMR_ISA_NAMESPACE
