#pragma once
// 8-bit PNG files written with libpng directly: the `qdmr` command's default output, so that a render writing a PNG
// does not load the OpenImageIO module (~0.35 s of dynamic linking, codec/backend.hpp). The file holds what the
// OpenImageIO backend would write for the same spec: the pixels, an sRGB chunk when "oiio:ColorSpace" is sRGB,
// a tIME chunk for a DateTime, and every other non-empty string of the spec as a tEXt chunk (OpenImageIO reads
// those back as attributes).
#include <string>

#include "codec/backend.hpp"

namespace qdmr {

// Whether write_png takes this spec: 8-bit data of 1 to 4 channels (grey, grey + alpha, RGB, RGBA).
bool png_writes(const imageio::WriteSpec& spec);

// Compression levels, as the spec's "png:compressionLevel" gives them: 1, the default, is ISA-L's igzip at its
// level 1, on bands of rows in parallel joined into one stream (a 1080p render in about 15 ms of CPU time, 3-10 %
// larger than libdeflate's fastest level, which takes ~35 ms; the bands are fixed by the row size, so the bytes are
// the same on any thread count); 2 to 12 are libdeflate's levels, 12 the smallest (10-25 % smaller than igzip, some
// seconds), on one thread.
inline constexpr int kPngFastLevel = 1;
inline constexpr int kPngSmallestLevel = 12;

// Writes `data` (rows top-down, channels interleaved) to `path`; on failure returns false with `error` set (the
// caller removes the partial file). Compression: the spec's "png:compressionLevel" (1..12, above), else
// kPngFastLevel; every row with the Up filter.
bool write_png(const std::string& path, const imageio::WriteSpec& spec, const void* data, std::string& error);

}  // namespace qdmr
