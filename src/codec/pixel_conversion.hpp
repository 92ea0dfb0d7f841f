#pragma once
// Samples of one type as another, for the native readers (codec/native_reader.hpp): an integer k of b bits
// stands for k / (2^b - 1); a float is that value correctly rounded, an integer of other width the nearest one.
#include <cstddef>

#include "codec/backend.hpp"

namespace qdmr::imageio {

// `count` samples from `in` (of type `from`, 8- or 16-bit unsigned) to `out` (of type `to`).
void convert_values(PixelType from, const void* in, PixelType to, void* out, std::size_t count);

}  // namespace qdmr::imageio
