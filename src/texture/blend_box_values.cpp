#include "qdmr/texture/blend_box_values.hpp"

#include "qdmr/core/isa.hpp"

namespace qdmr {
// The builders this binary holds: one per draw kernel (shade/blend_box_values.cpp, compiled with the kernels).
#ifdef QDMR_KERNEL_AVX512
namespace avx512 {
void blend_box_values(const BlendBoxSource& source, float* out);
}
#endif
#ifdef QDMR_KERNEL_AVX2
namespace avx2 {
void blend_box_values(const BlendBoxSource& source, float* out);
}
#endif
#ifdef QDMR_KERNEL_SSE42
namespace sse42 {
void blend_box_values(const BlendBoxSource& source, float* out);
}
#endif

std::uint64_t blend_box_values_bytes(int width, int height, int repeats, std::uint64_t layer_heights_bytes) {
  if (layer_heights_bytes == 0 || width != height || repeats < 1) return 0;
  const std::uint64_t period = std::uint64_t(width) * std::uint64_t(repeats);
  return period * period * sizeof(float);
}

std::vector<float> blend_box_values(const BlendBoxSource& source) {
  const LayerHeights& heights = *source.heights;
  const std::uint64_t bytes = blend_box_values_bytes(heights.width, heights.height, source.repeats,
                                                     heights.texels.size() * sizeof(float));
  if (bytes == 0) return {};
  std::vector<float> out(bytes / sizeof(float));
#ifdef QDMR_KERNEL_AVX512
  if (cpu_supports(Isa::Avx512)) {
    avx512::blend_box_values(source, out.data());
    return out;
  }
#endif
#ifdef QDMR_KERNEL_AVX2
  if (cpu_supports(Isa::Avx2)) {
    avx2::blend_box_values(source, out.data());
    return out;
  }
#endif
#ifdef QDMR_KERNEL_SSE42
  if (cpu_supports(Isa::Sse42)) {
    sse42::blend_box_values(source, out.data());
    return out;
  }
#endif
  return {};  // no kernel runs here, so no frame is drawn either
}

}  // namespace qdmr
