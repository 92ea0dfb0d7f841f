#pragma once
// Content hashes of the bake caches: 64-bit FNV-1a over raw bytes, and its 16-digit hex form for file names.
#include <cstddef>
#include <cstdint>
#include <string>

namespace qdmr {

struct Fnv1a {
  std::uint64_t hash = 0xcbf29ce484222325ull;
  void bytes(const void* data, std::size_t size) {
    const auto* p = static_cast<const unsigned char*>(data);
    for (std::size_t k = 0; k < size; ++k) hash = (hash ^ p[k]) * 0x100000001b3ull;
  }
  template <class T>
  void value(const T& v) {
    bytes(&v, sizeof v);
  }
};

inline std::string hex(std::uint64_t v) {
  static const char* digits = "0123456789abcdef";
  std::string s(16, '0');
  for (int k = 15; k >= 0; --k, v >>= 4) s[std::size_t(k)] = digits[v & 15];
  return s;
}

}  // namespace qdmr
