#include "io/png_writer.hpp"

#include <png.h>

#include <cerrno>
#include <csetjmp>
#include <cstdio>
#include <cstring>
#include <vector>

namespace qdmr {
namespace {

// libpng reports errors by longjmp back to write_png's setjmp; the message is kept for the caller.
[[noreturn]] void on_error(png_structp png, png_const_charp message) {
  *static_cast<std::string*>(png_get_error_ptr(png)) = message;
  png_longjmp(png, 1);
}

void on_warning(png_structp, png_const_charp) {}

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
  int level = 6;
  bool srgb = false;
  std::vector<png_text> texts;
  for (const auto& [name, value] : spec.ints)
    if (name == "png:compressionLevel") level = value;
  for (const auto& [name, value] : spec.strings) {
    if (name == "oiio:ColorSpace") {
      srgb = value == "sRGB";
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
  const std::size_t row_bytes = std::size_t(spec.width) * std::size_t(spec.channels);
  std::vector<png_bytep> rows(std::size_t(spec.height));
  for (std::size_t y = 0; y < rows.size(); ++y)
    rows[y] = const_cast<png_bytep>(static_cast<const png_byte*>(data) + y * row_bytes);
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
  png_set_compression_level(png, level);
  if (srgb) png_set_sRGB_gAMA_and_cHRM(png, info, PNG_sRGB_INTENT_PERCEPTUAL);
  if (!texts.empty()) png_set_text(png, info, texts.data(), int(texts.size()));
  png_write_info(png, info);
  png_write_image(png, rows.data());
  png_write_end(png, info);
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
