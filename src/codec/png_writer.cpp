#include "codec/png_writer.hpp"

#include <isa-l/igzip_lib.h>
#include <libdeflate.h>
#include <png.h>
#include <tbb/parallel_for.h>

#include <algorithm>
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

// Bands of rows, each filtered and compressed on its own (in parallel) and joined into one zlib stream: at least
// 256 KiB of filtered rows each, so a band costs far more than its task and its lost history (a 32 KiB window at
// its start) costs a few bytes. The split depends on the row size only, so the bytes written do not depend on the
// thread count.
std::size_t rows_per_band(std::size_t row_bytes) {
  return std::max<std::size_t>(1, (std::size_t(1) << 18) / (row_bytes + 1));
}

// Rows [first, end) of `data` with PNG's "Up" filter (byte 2, then each byte less the one above it; the first row
// of the image less zeros) into `out`, row `first` at its start.
void filter_up(const unsigned char* data, std::size_t row_bytes, std::size_t first, std::size_t end,
               unsigned char* out) {
  for (std::size_t y = first; y < end; ++y, out += row_bytes + 1) {
    const unsigned char* row = data + y * row_bytes;
    out[0] = 2;
    if (y == 0) {
      std::memcpy(out + 1, row, row_bytes);
      continue;
    }
    const unsigned char* above = row - row_bytes;
    for (std::size_t i = 0; i < row_bytes; ++i) out[1 + i] = static_cast<unsigned char>(row[i] - above[i]);
  }
}

// `in` as raw deflate blocks from ISA-L's igzip at its level 1, in one call: the final blocks of the stream when
// `last`, else ending in a full flush (byte-aligned, nothing referring back before it), so that the next band's
// blocks follow it. Empty if they did not fit `out`'s bound.
Bytes igzip_band(const unsigned char* in, std::size_t size, bool last) {
  // igzip's level 1 wants a work buffer of this size (its "large" default: the best ratio of the level), zeroed
  // (about 300 KB): what it holds must not depend on what the allocator gave back, or the bytes written might.
  std::vector<unsigned char> work(ISAL_DEF_LVL1_DEFAULT);
  // Room for stored blocks (5 bytes per 64 KiB) on incompressible rows, the flush, and slack.
  Bytes out(size + size / 64 + 1024);
  isal_zstream stream;
  isal_deflate_stateless_init(&stream);
  stream.level = 1;
  stream.level_buf = work.data();
  stream.level_buf_size = std::uint32_t(work.size());
  stream.gzip_flag = IGZIP_DEFLATE;
  stream.end_of_stream = last ? 1 : 0;
  stream.flush = last ? NO_FLUSH : FULL_FLUSH;
  stream.next_in = const_cast<unsigned char*>(in);
  stream.avail_in = std::uint32_t(size);
  stream.next_out = out.data();
  stream.avail_out = std::uint32_t(out.size());
  if (isal_deflate_stateless(&stream) != COMP_OK) return {};
  out.resize(stream.total_out);
  return out;
}

// The IDAT payload: every row with the Up filter, as one zlib stream: from igzip at kPngFastLevel, in bands
// (rows_per_band), else from libdeflate at `level`. Up is the fastest filter to apply; on the canonical 1080p
// render it gives 1.67 MB with libdeflate's level 1, where libpng's per-row choice among all five with zlib level 3
// gave 1.71 MB (docs/performance-history.md). Empty on failure. Its buffers are not zeroed first (every byte is written)
// and take huge pages where they are large (DefaultInitAllocator): fresh pages cost a fault each otherwise.
Bytes compressed_rows(const unsigned char* data, std::size_t row_bytes, std::size_t rows, int level) {
  const std::size_t filtered_row = row_bytes + 1;
  Bytes filtered(filtered_row * rows);
  // igzip takes 32-bit sizes: a band's bound must fit (else libdeflate).
  const std::size_t band_rows = rows_per_band(row_bytes);
  if (level == kPngFastLevel && band_rows * filtered_row < (std::size_t(1) << 31)) {
    const std::size_t bands = (rows + band_rows - 1) / band_rows;
    std::vector<Bytes> compressed(bands);
    tbb::parallel_for(std::size_t(0), bands, [&](std::size_t b) {
      const std::size_t first = b * band_rows, end = std::min(rows, first + band_rows);
      unsigned char* in = filtered.data() + first * filtered_row;
      filter_up(data, row_bytes, first, end, in);
      compressed[b] = igzip_band(in, (end - first) * filtered_row, b + 1 == bands);
    });
    std::size_t size = 2 + 4;
    for (const Bytes& band : compressed) {
      if (band.empty()) return {};
      size += band.size();
    }
    // zlib's header (deflate, 32 KiB window, "fastest"; 0x7801 is a multiple of 31), the bands, the Adler-32 of
    // all the filtered rows, most significant byte first.
    Bytes out;
    out.reserve(size);
    out.push_back(0x78);
    out.push_back(0x01);
    for (const Bytes& band : compressed) out.insert(out.end(), band.begin(), band.end());
    const std::uint32_t adler = isal_adler32(1, filtered.data(), filtered.size());
    for (int shift = 24; shift >= 0; shift -= 8) out.push_back(static_cast<unsigned char>(adler >> shift));
    return out;
  }
  filter_up(data, row_bytes, 0, rows, filtered.data());
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
