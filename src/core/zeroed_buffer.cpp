#include "qdmr/core/zeroed_buffer.hpp"

#include "core/address_sanitizer.hpp"

#include <sys/mman.h>

#include <cstdlib>
#include <new>

namespace qdmr {
namespace {

// AddressSanitizer only checks memory that came from its own allocator.
#ifdef QDMR_ADDRESS_SANITIZER
constexpr bool kMapLargeBlocks = false;
#else
constexpr bool kMapLargeBlocks = true;
#endif

bool mapped(std::size_t bytes) { return kMapLargeBlocks && bytes >= kFreshPagesBytes; }

}  // namespace

void* allocate_zeroed(std::size_t bytes) {
  if (bytes == 0) return nullptr;
  if (mapped(bytes)) {
    void* block = ::mmap(nullptr, bytes, PROT_READ | PROT_WRITE, MAP_PRIVATE | MAP_ANONYMOUS, -1, 0);
    if (block == MAP_FAILED) throw std::bad_alloc();
    ::madvise(block, bytes, MADV_HUGEPAGE);  // advice only: without huge pages it still works
    return block;
  }
  if (void* block = std::calloc(1, bytes)) return block;
  throw std::bad_alloc();
}

void free_zeroed(void* block, std::size_t bytes) noexcept {
  if (block == nullptr) return;
  if (mapped(bytes))
    ::munmap(block, bytes);
  else
    std::free(block);
}

}  // namespace qdmr
