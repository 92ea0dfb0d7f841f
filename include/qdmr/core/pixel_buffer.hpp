#pragma once
// PixelBuffer: a std::vector<float> whose growth leaves elements uninitialised, so frame buffers are not
// zeroed serially before the tiles clear (and fill) them in parallel.
#include <memory>
#include <utility>
#include <vector>

namespace qdmr {

template <class T>
struct DefaultInitAllocator : std::allocator<T> {
  template <class U>
  struct rebind {
    using other = DefaultInitAllocator<U>;
  };
  DefaultInitAllocator() noexcept = default;
  template <class U>
  DefaultInitAllocator(const DefaultInitAllocator<U>&) noexcept {}
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
