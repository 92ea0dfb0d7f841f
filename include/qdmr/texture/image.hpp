#pragma once
// Image: a level of texels as 32-bit floats, row-major, interleaved channels, row 0 at v = 0.
// Files are read bottom-up: the last row of an image file is row 0 (OpenGL convention).
#include <cstddef>
#include <cstdint>
#include <filesystem>
#include <string>

#include "qdmr/core/zeroed_buffer.hpp"

namespace qdmr {

// Zero until written; pages are committed as they are written (qdmr/core/zeroed_buffer.hpp), so reading a
// file that declares more pixels than it holds fails before its size in memory is ever touched.
using Texels = ZeroedBuffer<float>;

struct Image {
  int width = 0;
  int height = 0;
  int channels = 0;
  int source_bits = 32;  // bits per channel of the data it came from: 8 or 16 for integer files, 32 otherwise
  Texels texels;

  Image() = default;
  Image(int w, int h, int c) : width(w), height(h), channels(c), texels(std::size_t(w) * h * c) {}
  float& at(int x, int y, int c) { return texels[(std::size_t(y) * width + x) * channels + c]; }
  float at(int x, int y, int c) const { return texels[(std::size_t(y) * width + x) * channels + c]; }
  std::size_t bytes() const { return texels.size() * sizeof(float); }
};

// Reads any image OpenImageIO can read (8/16-bit, half, float) as normalised floats, no colour conversion.
// Throws qdmr::Error(where, ...) for missing, unreadable or corrupt files and sizes over the limits.
// Every check on the file and its header is made before any pixel is decoded (see docs/scene-format.md, "What
// qdmr accepts as an input file"): a regular file within the size limit, PNG, JPEG, OpenEXR, TIFF or PNM,
// 1..16384 pixels a side, 1 to 4 channels, sane PNM fields, a JPEG with whole segments and its end marker (its
// metadata segments are dropped unread: codec/jpeg_segments.hpp). Then a decoder error or warning, or a short
// read, is an error too: never a partial image. An OpenEXR file is decompressed on the threads of the caller's
// task arena (tbb::this_task_arena::max_concurrency(); 1: the calling thread alone).
Image read_image(const std::filesystem::path& file, const std::string& where);

struct ImageHeader {
  int width = 0, height = 0, channels = 0;
  int source_bits = 32;  // as Image::source_bits
};
// The checks of read_image up to the header; nothing decoded (for plans and memory estimates).
ImageHeader read_image_header(const std::filesystem::path& file, const std::string& where);

// The most memory read_image holds at once for a file with this header: the float image it returns and the
// decoder's own buffer (a PNG decoder holds the whole image, as the file stores it).
std::uint64_t read_image_bytes(const ImageHeader& header);

}  // namespace qdmr
