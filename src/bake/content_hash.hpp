#pragma once
// Content hashes of the bake caches: XXH3's 64-bit hash (xxHash) over raw bytes, and its 16-digit hex form for file
// names. Byte-wise FNV-1a, which they used before, took ~110 ms for the default scene's 72 MiB blended surface, on
// one thread of its prepare; XXH3 takes a few (docs/performance-history.md, session 28).
#include <cstddef>
#include <cstdint>
#include <string>

#define XXH_INLINE_ALL  // header-only: every call inlined, nothing to link
#include <xxhash.h>

namespace qdmr {

// The hash of everything passed to bytes() and value(), in order (a streaming XXH3-64 with seed 0).
class ContentHash {
public:
  ContentHash() { XXH3_64bits_reset(&state_); }
  void bytes(const void* data, std::size_t size) { XXH3_64bits_update(&state_, data, size); }
  template <class T>
  void value(const T& v) {
    bytes(&v, sizeof v);
  }
  std::uint64_t digest() const { return XXH3_64bits_digest(&state_); }

private:
  XXH3_state_t state_;
};

inline std::string hex(std::uint64_t v) {
  static const char* digits = "0123456789abcdef";
  std::string s(16, '0');
  for (int k = 15; k >= 0; --k, v >>= 4) s[std::size_t(k)] = digits[v & 15];
  return s;
}

}  // namespace qdmr
