#include "io/png_writer.hpp"

#include <isa-l/igzip_lib.h>
#include <libdeflate.h>
#include <png.h>

#include <cerrno>
#include <csetjmp>
#include <cstdio>
#include <cstdint>
#include <cstring>
#include <memory>
#include <string>
#include <vector>

#include "qdmr/core/pixel_buffer.hpp"

namespace qdmr {
namespace {

// libpng reports errors by longjmp back to write_png's setjmp; the message is kept for the caller.
[[noreturn]] void on_error(png_structp png, png_const_charp message) {
  *static_cast<std::string*>(png_get_error_ptr(png)) = message;
  png_longjmp(png, 1);
}

void on_warning(png_structp, png_const_charp) {}

using Bytes = std::vector<unsigned char, DefaultInitAllocator<unsigned char>>;

// `in` as one zlib stream from ISA-L's igzip at its level 1, in one call; empty if it did not fit `out`'s bound
// (then the caller takes libdeflate).
Bytes igzip_zlib(const Bytes& in) {
  // igzip's level 1 wants a work buffer of this size (its "large" default: the best ratio of the level), zeroed
  // (about 300 KB): what it holds must not depend on what the allocator gave back, or the bytes written might.
  std::vector<unsigned char> work(ISAL_DEF_LVL1_DEFAULT);
  // Room for stored blocks (5 bytes per 64 KiB) on incompressible rows, the zlib header and trailer, and slack.
  Bytes out(in.size() + in.size() / 64 + 1024);
  isal_zstream stream;
  isal_deflate_stateless_init(&stream);
  stream.level = 1;
  stream.level_buf = work.data();
  stream.level_buf_size = std::uint32_t(work.size());
  stream.gzip_flag = IGZIP_ZLIB;
  stream.end_of_stream = 1;
  stream.flush = NO_FLUSH;
  stream.next_in = const_cast<unsigned char*>(in.data());
  stream.avail_in = std::uint32_t(in.size());
  stream.next_out = out.data();
  stream.avail_out = std::uint32_t(out.size());
  if (isal_deflate_stateless(&stream) != COMP_OK) return {};
  out.resize(stream.total_out);
  return out;
}

// The IDAT payload: every row with PNG's "Up" filter (byte 2, then each byte less the one above it; the first row
// less zeros), as one zlib stream: from igzip at kPngFastLevel, else from libdeflate at `level`. Up is the fastest
// filter to apply; on the canonical 1080p render it gives 1.67 MB with libdeflate's level 1, where libpng's
// per-row choice among all five with zlib level 3 gave 1.71 MB (docs/performance.md). Empty on failure. Its
// buffers are not zeroed first (every byte is written) and take huge pages where they are large
// (DefaultInitAllocator): fresh pages cost a fault each otherwise.
Bytes compressed_rows(const unsigned char* data, std::size_t row_bytes, std::size_t rows, int level) {
  Bytes filtered((row_bytes + 1) * rows);
  for (std::size_t y = 0; y < rows; ++y) {
    unsigned char* out = filtered.data() + y * (row_bytes + 1);
    const unsigned char* row = data + y * row_bytes;
    out[0] = 2;
    if (y == 0) {
      std::memcpy(out + 1, row, row_bytes);
      continue;
    }
    const unsigned char* above = row - row_bytes;
    for (std::size_t i = 0; i < row_bytes; ++i) out[1 + i] = static_cast<unsigned char>(row[i] - above[i]);
  }
  // igzip takes 32-bit sizes: from 2 GiB of rows on (the output's bound must fit too), and should its bound not
  // fit, libdeflate.
  if (level == kPngFastLevel && filtered.size() < (std::size_t(1) << 31)) {
    Bytes fast = igzip_zlib(filtered);
    if (!fast.empty()) return fast;
  }
  const std::unique_ptr<libdeflate_compressor, decltype(&libdeflate_free_compressor)> compressor(
      libdeflate_alloc_compressor(level), libdeflate_free_compressor);
  if (!compressor) return {};
  Bytes out(libdeflate_zlib_compress_bound(compressor.get(), filtered.size()));
  out.resize(libdeflate_zlib_compress(compressor.get(), filtered.data(), filtered.size(), out.data(), out.size()));
  return out;
}

}  // namespace

bool png_writes(const imageio::WriteSpec& spec) {
  return spec.type == imageio::PixelType::UInt8 && spec.channels >= 1 && spec.channels <= 4 && spec.width > 0 &&
         spec.height > 0;
}

bool write_png(const std::string& path, const imageio::WriteSpec& spec, const void* data, std::string& error) {
  if (!png_writes(spec)) {
    error = "not an 8-bit image of 1 to 4 channels";
    return false;
  }
  // Everything with a destructor exists before setjmp: a longjmp skips the destructors of what is made after it.
  int level = kPngFastLevel;
  bool srgb = false;
  std::vector<png_text> texts;
  for (const auto& [name, value] : spec.ints)
    if (name == "png:compressionLevel") level = value;
  png_time time{};
  bool has_time = false;
  for (const auto& [name, value] : spec.strings) {
    if (name == "oiio:ColorSpace") {
      srgb = value == "sRGB";
      continue;
    }
    // "YYYY:MM:DD hh:mm:ss" (WriteOptions::timestamp) goes into a tIME chunk, as OpenImageIO writes it.
    if (name == "DateTime") {
      unsigned year = 0, month = 0, day = 0, hour = 0, minute = 0, second = 0;
      has_time = std::sscanf(value.c_str(), "%4u:%2u:%2u %2u:%2u:%2u", &year, &month, &day, &hour, &minute,
                             &second) == 6;
      time = {png_uint_16(year), png_byte(month), png_byte(day), png_byte(hour), png_byte(minute), png_byte(second)};
      continue;
    }
    if (value.empty() || name.empty() || name.size() > 79) continue;  // PNG keywords: 1 to 79 bytes
    png_text t{};
    t.compression = PNG_TEXT_COMPRESSION_NONE;
    t.key = const_cast<char*>(name.c_str());
    t.text = const_cast<char*>(value.c_str());
    t.text_length = value.size();
    texts.push_back(t);
  }
  if (level < 1 || level > kPngSmallestLevel) {
    error = "PNG compression level " + std::to_string(level) + " is outside 1.." + std::to_string(kPngSmallestLevel);
    return false;
  }
  const std::size_t row_bytes = std::size_t(spec.width) * std::size_t(spec.channels);
  const Bytes idat =
      compressed_rows(static_cast<const unsigned char*>(data), row_bytes, std::size_t(spec.height), level);
  if (idat.empty()) {
    error = "libdeflate could not compress the pixels (out of memory)";
    return false;
  }
  static constexpr int kColorTypes[] = {PNG_COLOR_TYPE_GRAY, PNG_COLOR_TYPE_GRAY_ALPHA, PNG_COLOR_TYPE_RGB,
                                        PNG_COLOR_TYPE_RGB_ALPHA};

  std::FILE* file = std::fopen(path.c_str(), "wb");
  if (!file) {
    error = std::strerror(errno);
    return false;
  }
  png_structp png = png_create_write_struct(PNG_LIBPNG_VER_STRING, &error, on_error, on_warning);
  png_infop info = png ? png_create_info_struct(png) : nullptr;
  if (!png || !info) {
    png_destroy_write_struct(png ? &png : nullptr, nullptr);
    std::fclose(file);
    error = "libpng could not start (out of memory)";
    return false;
  }
  if (setjmp(png_jmpbuf(png))) {
    png_destroy_write_struct(&png, &info);
    std::fclose(file);
    return false;
  }
  png_init_io(png, file);
  png_set_IHDR(png, info, png_uint_32(spec.width), png_uint_32(spec.height), 8, kColorTypes[spec.channels - 1],
               PNG_INTERLACE_NONE, PNG_COMPRESSION_TYPE_DEFAULT, PNG_FILTER_TYPE_DEFAULT);
  if (srgb) png_set_sRGB_gAMA_and_cHRM(png, info, PNG_sRGB_INTENT_PERCEPTUAL);
  if (!texts.empty()) png_set_text(png, info, texts.data(), int(texts.size()));
  if (has_time) png_set_tIME(png, info, &time);
  // libpng writes the signature and the chunks before the pixels; the pixels go as one IDAT chunk of the stream
  // compressed above (libpng's own path filters and compresses row by row with zlib, several times slower).
  png_write_info(png, info);
  png_write_chunk(png, reinterpret_cast<png_const_bytep>("IDAT"), idat.data(), idat.size());
  png_write_chunk(png, reinterpret_cast<png_const_bytep>("IEND"), nullptr, 0);
  png_destroy_write_struct(&png, &info);
  if (std::fflush(file) != 0 || std::ferror(file)) {
    error = std::strerror(errno);
    std::fclose(file);
    return false;
  }
  if (std::fclose(file) != 0) {
    error = std::strerror(errno);
    return false;
  }
  return true;
}

}  // namespace qdmr
