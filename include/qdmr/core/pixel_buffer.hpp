#pragma once
// PixelBuffer: a std::vector<float> whose growth leaves elements uninitialised, so frame buffers are not
// zeroed serially before the tiles clear (and fill) them in parallel; and whose large blocks ask the kernel for
// transparent huge pages, so a fresh frame's first touch takes one fault per 2 MiB instead of one per 4 KiB.
#include <cstddef>
#include <memory>
#include <utility>
#include <vector>

namespace qdmr {

// Blocks of at least 2 MiB: 2 MiB-aligned, whole 2 MiB pages, marked MADV_HUGEPAGE where the system has it (the
// kernel's `madvise` mode of transparent huge pages; elsewhere ordinary pages). Smaller blocks: operator new.
void* allocate_pixels(std::size_t bytes);
void free_pixels(void* block, std::size_t bytes) noexcept;

template <class T>
struct DefaultInitAllocator : std::allocator<T> {
  template <class U>
  struct rebind {
    using other = DefaultInitAllocator<U>;
  };
  DefaultInitAllocator() noexcept = default;
  template <class U>
  DefaultInitAllocator(const DefaultInitAllocator<U>&) noexcept {}
  T* allocate(std::size_t n) { return static_cast<T*>(allocate_pixels(n * sizeof(T))); }
  void deallocate(T* p, std::size_t n) noexcept { free_pixels(p, n * sizeof(T)); }
  template <class U>
  void construct(U* p) noexcept {
    ::new (static_cast<void*>(p)) U;  // default-initialise: no zeroing
  }
  template <class U, class... Args>
  void construct(U* p, Args&&... args) {
    ::new (static_cast<void*>(p)) U(std::forward<Args>(args)...);
  }
};

using PixelBuffer = std::vector<float, DefaultInitAllocator<float>>;

}  // namespace qdmr
