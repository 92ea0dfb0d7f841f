#pragma once
// ZeroedAllocator: a std::vector allocator whose memory starts as zero pages that are committed only when written,
// so a vector of n value-initialised elements costs nothing until it is used. std::allocator's vector writes every
// zero itself, which commits every page at once: a 460-byte TIFF declaring 16384 x 10240 pixels cost 2 GB and 4 s
// of page clearing before the decoder found its data missing.
//
// Blocks of kFreshPagesBytes and more are mapped from the kernel and unmapped when freed: a general-purpose
// allocator hands a block it got back earlier to calloc, and must then clear it, committing it all (jemalloc keeps
// freed pages for reuse). They are advised onto transparent huge pages, as the command's allocator does for its
// own (src/cli/allocator.cpp). Smaller blocks come from calloc. Under AddressSanitizer every block comes from
// calloc, so its checks cover them; its allocator maps large blocks afresh anyway.
//
// Value-initialisation without arguments is therefore a no-op: correct for memory that is fresh zero, and for
// nothing else. A vector with this allocator is sized once, at construction (or by assign); it must never shrink
// and grow again, which would leave the old values in place of zeros.
#include <sys/mman.h>

#include <cstddef>
#include <cstdlib>
#include <new>
#include <type_traits>
#include <utility>

namespace qdmr {

inline constexpr std::size_t kFreshPagesBytes = std::size_t(32) << 20;
#if defined(__SANITIZE_ADDRESS__)
inline constexpr bool kMapLargeBlocks = false;
#elif defined(__has_feature)
#if __has_feature(address_sanitizer)
inline constexpr bool kMapLargeBlocks = false;
#else
inline constexpr bool kMapLargeBlocks = true;
#endif
#else
inline constexpr bool kMapLargeBlocks = true;
#endif

template <class T>
struct ZeroedAllocator {
  using value_type = T;

  ZeroedAllocator() = default;
  template <class U>
  ZeroedAllocator(const ZeroedAllocator<U>&) noexcept {}

  T* allocate(std::size_t n) {
    if (n > std::size_t(-1) / sizeof(T)) throw std::bad_alloc();
    if (mapped(n)) {
      void* p = ::mmap(nullptr, n * sizeof(T), PROT_READ | PROT_WRITE, MAP_PRIVATE | MAP_ANONYMOUS, -1, 0);
      if (p == MAP_FAILED) throw std::bad_alloc();
      ::madvise(p, n * sizeof(T), MADV_HUGEPAGE);  // advice only: without huge pages it still works
      return static_cast<T*>(p);
    }
    if (void* p = std::calloc(n, sizeof(T))) return static_cast<T*>(p);
    throw std::bad_alloc();
  }
  void deallocate(T* p, std::size_t n) noexcept {
    if (mapped(n))
      ::munmap(p, n * sizeof(T));
    else
      std::free(p);
  }

  template <class U>
  void construct(U*) noexcept {  // already zero (see above)
    static_assert(std::is_arithmetic_v<U>, "all-zero bytes are the value-initialised value of arithmetic types only");
  }
  template <class U, class... Args>
  void construct(U* p, Args&&... args) {
    ::new (static_cast<void*>(p)) U(std::forward<Args>(args)...);
  }

  template <class U>
  friend bool operator==(const ZeroedAllocator&, const ZeroedAllocator<U>&) noexcept {
    return true;
  }

 private:
  static bool mapped(std::size_t n) { return kMapLargeBlocks && n * sizeof(T) >= kFreshPagesBytes; }
};

}  // namespace qdmr
