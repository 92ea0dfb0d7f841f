#include "qdmr/core/isa.hpp"
#include "texture/mip_reduce.hpp"

namespace qdmr {
// The reducers this binary holds (defined by the build for each ISA compiled, as the draw kernels).
#ifdef QDMR_KERNEL_AVX2
namespace avx2::mip {
void reduce_extremum(bool max, TexelFormat format, const std::uint8_t* in, int in_w, int in_h, std::uint8_t* out,
                     int out_w, int out_h);
}
#endif
#ifdef QDMR_KERNEL_SSE42
namespace sse42::mip {
void reduce_extremum(bool max, TexelFormat format, const std::uint8_t* in, int in_w, int in_h, std::uint8_t* out,
                     int out_w, int out_h);
}
#endif

void reduce_extremum_best(bool max, TexelFormat format, const std::uint8_t* in, int in_w, int in_h, std::uint8_t* out,
                          int out_w, int out_h) {
  static const bool avx2 = cpu_supports(Isa::Avx2);
#ifdef QDMR_KERNEL_AVX2
  if (avx2) return avx2::mip::reduce_extremum(max, format, in, in_w, in_h, out, out_w, out_h);
#endif
#ifdef QDMR_KERNEL_SSE42
  if (cpu_supports(Isa::Sse42)) return sse42::mip::reduce_extremum(max, format, in, in_w, in_h, out, out_w, out_h);
#endif
  (void)avx2;
  baseline::mip::reduce_extremum(max, format, in, in_w, in_h, out, out_w, out_h);
}

}  // namespace qdmr
