#include "check/canonical_hash.hpp"

#include <bit>
#include <cstdint>
#include <cstring>
#include <vector>

#include "core/sha1.hpp"

namespace qdmr {

std::string canonical_hash(int width, int height, int channels, std::span<const float> pixels) {
  Sha1 sha;
  const std::string header = "qdmr-canonical-1 " + std::to_string(width) + " " + std::to_string(height) + " " +
                             std::to_string(channels) + "\n";
  sha.append(header.data(), header.size());
  // Canonical bytes a block at a time, so a 1080p image needs no second copy.
  constexpr std::size_t kBlock = 1 << 14;
  std::vector<unsigned char> bytes(kBlock * 4);
  for (std::size_t begin = 0; begin < pixels.size(); begin += kBlock) {
    const std::size_t count = std::min(kBlock, pixels.size() - begin);
    for (std::size_t i = 0; i < count; ++i) {
      const float v = pixels[begin + i];
      const std::uint32_t bits = v != v ? 0x7fc00000u : std::bit_cast<std::uint32_t>(v);
      for (int b = 0; b < 4; ++b) bytes[4 * i + std::size_t(b)] = static_cast<unsigned char>(bits >> (8 * b));
    }
    sha.append(bytes.data(), count * 4);
  }
  return "sha1:" + sha.hex_digest();
}

}  // namespace qdmr
