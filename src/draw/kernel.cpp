#include "kernel/kernel.hpp"

#include "qdmr/core/error.hpp"

// The kernels this binary holds (QDMR_KERNEL_<ISA> is defined by the build for each one compiled).
namespace qdmr {
#ifdef QDMR_KERNEL_AVX512
namespace avx512 {
const Kernel& kernel();
}
#endif
#ifdef QDMR_KERNEL_AVX2
namespace avx2 {
const Kernel& kernel();
}
#endif
#ifdef QDMR_KERNEL_SSE42
namespace sse42 {
const Kernel& kernel();
}
#endif

const Kernel& kernel_for(Isa isa) {
  switch (isa) {
#ifdef QDMR_KERNEL_AVX512
    case Isa::Avx512: return avx512::kernel();
#endif
#ifdef QDMR_KERNEL_AVX2
    case Isa::Avx2: return avx2::kernel();
#endif
#ifdef QDMR_KERNEL_SSE42
    case Isa::Sse42: return sse42::kernel();
#endif
    default: break;
  }
  throw Error("isa", std::string("no ") + isa_name(isa) + " kernel in this binary");
}

}  // namespace qdmr
