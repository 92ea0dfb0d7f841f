// A PNG read by libpng with the calls of OpenImageIO 2.4's PNG reader (png.imageio/png_pvt.h): expand, swap to
// host order, rows one by one, an interlaced image whole followed by png_read_end. Errors end in a longjmp to the
// setjmp of the call that made them; no C++ object lives in a frame that the jump leaves.
#include <png.h>
#include <strings.h>

#include <bit>
#include <cstdio>
#include <string>
#include <vector>

#include "codec/native_reader.hpp"
#include "codec/pixel_conversion.hpp"

namespace qdmr::imageio {
namespace {

// libpng's error callback must not return: the message is kept and control goes back to the step's setjmp.
[[noreturn]] void on_error(png_structp png, png_const_charp message) {
  auto* kept = static_cast<std::string*>(png_get_error_ptr(png));
  *kept = std::string("PNG read error: ") + (message ? message : "unknown error");
  png_longjmp(png, 1);
}

// OpenImageIO ignores libpng's warnings (benign errors, which libpng's reader demotes to warnings, included).
void on_warning(png_structp, png_const_charp) {}

void read_rows(png_structp png, png_uint_32 height, bool interlaced, unsigned char* const* rows) {
  if (interlaced) {
    png_read_image(png, const_cast<png_bytepp>(rows));
    png_read_end(png, nullptr);
  } else {
    for (png_uint_32 y = 0; y < height; ++y) png_read_row(png, rows[y], nullptr);
  }
}

class PngReader final : public NativeReader {
public:
  ~PngReader() override {
    if (png_) png_destroy_read_struct(&png_, info_ ? &info_ : nullptr, nullptr);
    if (file_) std::fclose(file_);
  }

  bool open(const std::string& path, ReadSpec& spec, std::string& error) {
    file_ = std::fopen(path.c_str(), "rb");
    if (!file_) {
      error = "cannot open the file";
      return false;
    }
    png_ = png_create_read_struct(PNG_LIBPNG_VER_STRING, &message_, on_error, on_warning);
    if (png_) info_ = png_create_info_struct(png_);
    if (!png_ || !info_) {
      error = "could not create libpng's read structures";
      return false;
    }
    png_init_io(png_, file_);
    if (!read_header()) {
      error = message_;
      return false;
    }
    if (bit_depth_ != 8 && bit_depth_ != 16) {
      error = "PNG of " + std::to_string(bit_depth_) + "-bit samples after expansion";
      return false;
    }
    if (png_get_rowbytes(png_, info_) != std::size_t(width_) * std::size_t(channels_) * std::size_t(bit_depth_ / 8)) {
      error = "PNG rows of an unexpected size";
      return false;
    }
    set_image(spec, int(width_), int(height_), channels_, "png", stored_type());
    // OpenImageIO's spec attributes are found case-insensitively, a later chunk replacing an earlier one.
    png_textp text = nullptr;
    const int texts = png_get_text(png_, info_, &text, nullptr);
    for (int i = 0; i < texts; ++i) {
      if (!text[i].key || !text[i].text) continue;
      if (strcasecmp(text[i].key, "Software") == 0) spec.software = text[i].text;
      if (strcasecmp(text[i].key, "qdmr:bits_version") == 0) spec.bits_version = text[i].text;
    }
    return true;
  }

  bool read_pixels(PixelType type, void* first_row, std::ptrdiff_t row_stride, std::string& error) override {
    const std::size_t row_bytes = png_get_rowbytes(png_, info_);
    const bool direct = type == stored_type();
    std::vector<unsigned char> decoded(direct ? 0 : row_bytes * height_);
    std::vector<unsigned char*> rows(height_);
    for (png_uint_32 y = 0; y < height_; ++y)
      rows[y] = direct ? static_cast<unsigned char*>(first_row) + row_stride * std::ptrdiff_t(y)
                       : decoded.data() + row_bytes * y;
    if (!read_all(rows.data())) {
      error = message_;
      return false;
    }
    if (!direct)
      for (png_uint_32 y = 0; y < height_; ++y)
        convert_values(stored_type(), rows[y], type, static_cast<char*>(first_row) + row_stride * std::ptrdiff_t(y),
                       std::size_t(width_) * std::size_t(channels_));
    return true;
  }

private:
  PixelType stored_type() const { return bit_depth_ == 16 ? PixelType::UInt16 : PixelType::UInt8; }

  // The header, and the transformations asked for; false when libpng reported an error.
  bool read_header() {
    if (setjmp(png_jmpbuf(png_))) return false;
    png_read_info(png_, info_);
    png_set_expand(png_);  // palette to RGB, 1/2/4-bit grey to 8 bits, tRNS to an alpha channel
    if constexpr (std::endian::native == std::endian::little) png_set_swap(png_);
    png_read_update_info(png_, info_);
    int color_type = 0;
    png_get_IHDR(png_, info_, &width_, &height_, &bit_depth_, &color_type, nullptr, nullptr, nullptr);
    channels_ = png_get_channels(png_, info_);
    interlaced_ = png_get_interlace_type(png_, info_) != PNG_INTERLACE_NONE;
    return true;
  }

  bool read_all(unsigned char* const* rows) {
    if (setjmp(png_jmpbuf(png_))) return false;
    read_rows(png_, height_, interlaced_, rows);
    return true;
  }

  std::FILE* file_ = nullptr;
  png_structp png_ = nullptr;
  png_infop info_ = nullptr;
  std::string message_;  // libpng's error, as on_error words it
  png_uint_32 width_ = 0, height_ = 0;
  int bit_depth_ = 0, channels_ = 0;
  bool interlaced_ = false;
};

}  // namespace

std::unique_ptr<NativeReader> open_png(const std::string& path, ReadSpec& spec, std::string& error) {
  return opened<PngReader>(path, spec, error);
}

}  // namespace qdmr::imageio
