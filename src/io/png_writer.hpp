#pragma once
// 8-bit PNG files written with libpng directly: the `qdmr` command's default output, so that a render writing a PNG
// does not load the OpenImageIO module (~0.35 s of dynamic linking, imageio/backend.hpp). The file holds what the
// OpenImageIO backend would write for the same spec: the pixels, an sRGB chunk when "oiio:ColorSpace" is sRGB,
// a tIME chunk for a DateTime, and every other non-empty string of the spec as a tEXt chunk (OpenImageIO reads
// those back as attributes).
#include <string>

#include "imageio/backend.hpp"

namespace qdmr {

// Whether write_png takes this spec: 8-bit data of 1 to 4 channels (grey, grey + alpha, RGB, RGBA).
bool png_writes(const imageio::WriteSpec& spec);

// libdeflate's compression levels: the fastest (a 1080p render in a few tens of milliseconds) and the smallest
// (about 20 % smaller, some seconds).
inline constexpr int kPngFastLevel = 1;
inline constexpr int kPngSmallestLevel = 12;

// Writes `data` (rows top-down, channels interleaved) to `path`; on failure returns false with `error` set (the
// caller removes the partial file). Compression: the spec's "png:compressionLevel" read as libdeflate's level
// (1..12), else kPngFastLevel; every row with the Up filter.
bool write_png(const std::string& path, const imageio::WriteSpec& spec, const void* data, std::string& error);

}  // namespace qdmr
