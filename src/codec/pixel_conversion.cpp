#include "codec/pixel_conversion.hpp"

#include <cstdint>
#include <cstring>

namespace qdmr::imageio {

void convert_values(PixelType from, const void* in, PixelType to, void* out, std::size_t count) {
  const auto* bytes = static_cast<const unsigned char*>(in);
  const bool wide = from == PixelType::UInt16;
  for (std::size_t i = 0; i < count; ++i) {
    std::uint32_t k = bytes[i];
    if (wide) {
      std::uint16_t sample;
      std::memcpy(&sample, bytes + 2 * i, 2);
      k = sample;
    }
    const std::uint32_t max = wide ? 65535 : 255;
    switch (to) {
      case PixelType::Float: {
        const float value = float(k) / float(max);  // both exact in float: one correctly rounded division
        std::memcpy(static_cast<char*>(out) + 4 * i, &value, 4);
        break;
      }
      case PixelType::UInt8: {
        const auto value = std::uint8_t(wide ? (k * 255 + 32767) / 65535 : k);
        static_cast<std::uint8_t*>(out)[i] = value;
        break;
      }
      case PixelType::UInt16: {
        const auto value = std::uint16_t(wide ? k : k * 257);
        std::memcpy(static_cast<char*>(out) + 2 * i, &value, 2);
        break;
      }
    }
  }
}

}  // namespace qdmr::imageio
