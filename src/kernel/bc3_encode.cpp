// BC3 alpha encoding with this kernel's instructions (Kernel::bc3_encode): the search of texture/bc3_search.hpp with
// each candidate palette's error over the block's 16 texels computed in one vector. The errors are the definition's
// integers, so the blocks are encode_bc3_alpha's.
#include <algorithm>
#include <cstdint>
#include <type_traits>

#include "core/simd.hpp"
#include "kernel/kernel_calls.hpp"
#include "kernel/preparation.hpp"
#include "texture/bc3_search.hpp"

namespace qdmr::QDMR_ISA_NAMESPACE {
namespace {

// One block's 16 texels in one 16-byte vector of this kernel's instruction set (a palette per wider vector would
// need byte shuffles per entry that cost more than they save).
using Bytes = xsimd::make_sized_batch_t<std::uint8_t, 16>;
using Words = xsimd::make_sized_batch_t<std::uint32_t, 4>;
static_assert(!std::is_void_v<Bytes> && !std::is_void_v<Words>);

// errors[k] for the candidate palettes k in order, up to the first exact one; how many.
int candidate_errors(const std::uint8_t* texels, const bc3::Candidates& c, int* errors) {
  const Bytes t = Bytes::load_unaligned(texels);
  for (int k = 0; k < c.count; ++k) {
    Bytes nearest(std::uint8_t(255));
    for (const std::uint8_t p : c.palette(k)) {
      const Bytes entry(p);
      nearest = xsimd::min(nearest, xsimd::ssub(t, entry) | xsimd::ssub(entry, t));  // |t - p|
    }
    // The squares of the four bytes of each 32-bit word (at most 4 * 255^2 each), then the four words.
    const Words words = xsimd::bitwise_cast<Words>(nearest);
    Words squares(0u);
    for (int shift = 0; shift < 32; shift += 8) {
      const Words d = (words >> shift) & Words(0xFFu);
      squares += d * d;
    }
    errors[k] = int(xsimd::hadd(squares));
    if (errors[k] == 0) return k + 1;
  }
  return c.count;
}

Bc3AlphaBlock bc3_encode(const std::uint8_t texels[16]) { return bc3::encode(texels, candidate_errors); }

}  // namespace

Bc3Encode bc3_encoder() {
  kernel_calls.bc3_encoders.fetch_add(1, std::memory_order_relaxed);
  return &bc3_encode;
}

}  // namespace qdmr::QDMR_ISA_NAMESPACE
