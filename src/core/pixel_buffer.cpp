#include "qdmr/core/pixel_buffer.hpp"

#include <new>

#if defined(__linux__)
#include <sys/mman.h>
#endif

namespace qdmr {
namespace {

constexpr std::size_t kHugePage = std::size_t(2) << 20;

std::size_t whole_huge_pages(std::size_t bytes) { return (bytes + kHugePage - 1) / kHugePage * kHugePage; }

}  // namespace

void* allocate_pixels(std::size_t bytes) {
  if (bytes < kHugePage) return ::operator new(bytes);
  const std::size_t size = whole_huge_pages(bytes);
  void* block = ::operator new(size, std::align_val_t(kHugePage));
#if defined(MADV_HUGEPAGE)
  // Advice only: where it is refused (no transparent huge pages) the block keeps ordinary pages.
  (void)::madvise(block, size, MADV_HUGEPAGE);
#endif
  return block;
}

void free_pixels(void* block, std::size_t bytes) noexcept {
  if (bytes < kHugePage)
    ::operator delete(block);
  else
    ::operator delete(block, std::align_val_t(kHugePage));
}

}  // namespace qdmr
