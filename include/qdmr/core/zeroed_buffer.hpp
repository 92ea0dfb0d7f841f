#pragma once
// ZeroedBuffer: a fixed-size array of numbers whose memory starts as zero pages that the kernel commits only when
// written, so a buffer of n zeros costs nothing until it is used. A std::vector writes every zero itself, which
// commits every page at once: a 460-byte TIFF declaring 16384 x 10240 pixels cost 2 GB and 4 s of page clearing
// before the decoder found its data missing.
//
// Not a std::vector with a custom allocator: libstdc++ then constructs and destroys the elements one by one. The
// loops do nothing and -O3 removes them, but coverage instrumentation keeps them, so the fuzz build spent seconds
// per file on them. This type has no per-element step at all: one allocation, one free.
//
// Its size is set when it is made (or assigned); there is no growth, so no capacity and no old values to clear.
#include <algorithm>
#include <cstddef>
#include <initializer_list>
#include <iterator>
#include <new>
#include <type_traits>
#include <utility>

namespace qdmr {

// Blocks of at least kFreshPagesBytes are mapped from the kernel and unmapped when freed: a general-purpose
// allocator hands a block it got back earlier to calloc, and must then clear it, committing it all (jemalloc keeps
// freed pages for reuse). They are advised onto transparent huge pages. Smaller blocks come from calloc. Under
// AddressSanitizer every block comes from calloc, so its checks cover them.
inline constexpr std::size_t kFreshPagesBytes = std::size_t(32) << 20;
void* allocate_zeroed(std::size_t bytes);  // nullptr for 0 bytes; throws std::bad_alloc
void free_zeroed(void* block, std::size_t bytes) noexcept;

template <class T>
class ZeroedBuffer {
  static_assert(std::is_arithmetic_v<T>, "all-zero bytes are the zero value of arithmetic types only");

 public:
  using value_type = T;
  using iterator = T*;
  using const_iterator = const T*;

  ZeroedBuffer() noexcept = default;
  explicit ZeroedBuffer(std::size_t n) : data_(allocate(n)), size_(n) {}
  ZeroedBuffer(std::size_t n, T value) : ZeroedBuffer(n) { std::fill_n(data_, n, value); }
  template <class It, class = typename std::iterator_traits<It>::iterator_category>
  ZeroedBuffer(It first, It last) : ZeroedBuffer(std::size_t(std::distance(first, last))) {
    std::copy(first, last, data_);
  }
  ZeroedBuffer(std::initializer_list<T> values) : ZeroedBuffer(values.begin(), values.end()) {}
  ZeroedBuffer(const ZeroedBuffer& other) : ZeroedBuffer(other.begin(), other.end()) {}
  ZeroedBuffer(ZeroedBuffer&& other) noexcept
      : data_(std::exchange(other.data_, nullptr)), size_(std::exchange(other.size_, 0)) {}
  ZeroedBuffer& operator=(ZeroedBuffer other) noexcept {
    swap(other);
    return *this;
  }
  ~ZeroedBuffer() { free_zeroed(data_, size_ * sizeof(T)); }

  void assign(std::size_t n, T value) { *this = ZeroedBuffer(n, value); }
  template <class It, class = typename std::iterator_traits<It>::iterator_category>
  void assign(It first, It last) {
    *this = ZeroedBuffer(first, last);
  }
  void swap(ZeroedBuffer& other) noexcept {
    std::swap(data_, other.data_);
    std::swap(size_, other.size_);
  }

  T* data() noexcept { return data_; }
  const T* data() const noexcept { return data_; }
  std::size_t size() const noexcept { return size_; }
  bool empty() const noexcept { return size_ == 0; }
  T& operator[](std::size_t i) noexcept { return data_[i]; }
  const T& operator[](std::size_t i) const noexcept { return data_[i]; }
  T* begin() noexcept { return data_; }
  T* end() noexcept { return data_ + size_; }
  const T* begin() const noexcept { return data_; }
  const T* end() const noexcept { return data_ + size_; }

  friend bool operator==(const ZeroedBuffer& a, const ZeroedBuffer& b) {
    return std::equal(a.begin(), a.end(), b.begin(), b.end());
  }

 private:
  static T* allocate(std::size_t n) {
    if (n > std::size_t(-1) / sizeof(T)) throw std::bad_alloc();
    return static_cast<T*>(allocate_zeroed(n * sizeof(T)));
  }

  T* data_ = nullptr;
  std::size_t size_ = 0;
};

}  // namespace qdmr
