// A JPEG read by libjpeg-turbo with the calls of OpenImageIO 2.4's JPEG reader (jpeg.imageio/jpeginput.cpp):
// jpeg_read_header without requiring an image, CMYK and YCCK decoded as CMYK and converted to RGB, rows one by
// one, no jpeg_finish_decompress. libjpeg's fatal errors end in a longjmp to the setjmp of the call that made
// them; no C++ object lives in a frame that the jump leaves.
#include <stdio.h>  // jpeglib.h needs FILE and size_t first

#include <jpeglib.h>

#include <csetjmp>
#include <fstream>
#include <iterator>
#include <string>
#include <vector>

#include "codec/jpeg_segments.hpp"
#include "codec/native_reader.hpp"
#include "codec/pixel_conversion.hpp"

namespace qdmr::imageio {
namespace {

struct ErrorManager {
  jpeg_error_mgr pub;  // first: libjpeg sees a jpeg_error_mgr
  std::jmp_buf jump;
  std::string* error;    // a fatal error
  std::string* warning;  // the first warning (corrupt data that libjpeg decoded around)
};

std::string message_of(j_common_ptr cinfo) {
  char text[JMSG_LENGTH_MAX];
  (*cinfo->err->format_message)(cinfo, text);
  return std::string("JPEG error: ") + text;
}

[[noreturn]] void on_error(j_common_ptr cinfo) {
  auto* manager = reinterpret_cast<ErrorManager*>(cinfo->err);
  *manager->error = message_of(cinfo);
  std::longjmp(manager->jump, 1);
}

// libjpeg calls this for the first warning only (emit_message); OpenImageIO records it as an error.
void on_message(j_common_ptr cinfo) {
  auto* manager = reinterpret_cast<ErrorManager*>(cinfo->err);
  if (manager->warning->empty()) *manager->warning = message_of(cinfo);
}

// OpenImageIO's cmyk_to_rgb: each channel by convert_type (k · fl(1/255) in float), R = C·K, back by its
// scaled_conversion (·255, +0.5, clamped, truncated), all in float.
void cmyk_to_rgb(const unsigned char* cmyk, unsigned char* rgb, JDIMENSION width) {
  const float scale = 1.0f / 255.0f;
  for (JDIMENSION x = 0; x < width; ++x, cmyk += 4, rgb += 3) {
    const float k = float(cmyk[3]) * scale;
    for (int c = 0; c < 3; ++c) {
      float s = float(cmyk[c]) * scale * k * 255.0f;
      s += s < 0 ? -0.5f : 0.5f;
      rgb[c] = static_cast<unsigned char>(s < 0.0f ? 0.0f : s > 255.0f ? 255.0f : s);
    }
  }
}

// Every row into `rows`, through `cmyk_row` (4 samples a pixel) when the file is CMYK. False, with `error` set,
// if a call returned no row or at the first warning (libjpeg's fatal errors jump instead): a file that declares a
// large image and holds little data stops at its first rows, before the rest of the image is touched.
bool decode_rows(j_decompress_ptr cinfo, unsigned char* const* rows, unsigned char* cmyk_row, const std::string& warning,
                 std::string& error) {
  for (JDIMENSION y = 0; y < cinfo->output_height; ++y) {
    JSAMPROW row = cmyk_row ? cmyk_row : rows[y];
    if (jpeg_read_scanlines(cinfo, &row, 1) != 1) {
      error = "JPEG failed scanline read";
      return false;
    }
    if (!warning.empty()) {
      error = warning;
      return false;
    }
    if (cmyk_row) cmyk_to_rgb(cmyk_row, rows[y], cinfo->output_width);
  }
  return true;
}

class JpegReader final : public NativeReader {
public:
  JpegReader() {
    cinfo_.err = jpeg_std_error(&errors_.pub);
    errors_.pub.error_exit = on_error;
    errors_.pub.output_message = on_message;
    errors_.error = &error_;
    errors_.warning = &warning_;
  }
  ~JpegReader() override {
    if (created_) jpeg_destroy_decompress(&cinfo_);
  }

  bool open(const std::string& path, ReadSpec& spec, std::string& error) {
    if (!jpeg_without_metadata(path, bytes_, error)) return false;
    if (bytes_.empty()) {
      std::ifstream in(path, std::ios::binary);
      if (!in) {
        error = "cannot open the file";
        return false;
      }
      bytes_.assign(std::istreambuf_iterator<char>(in), {});
    }
    if (!start()) {
      error = error_;
      return false;
    }
    const int expected = cmyk_ ? 4 : cinfo_.num_components;
    if (cinfo_.output_components != expected) {
      error = "JPEG of " + std::to_string(cinfo_.num_components) + " components decoded to " +
              std::to_string(cinfo_.output_components);
      return false;
    }
    set_image(spec, int(cinfo_.output_width), int(cinfo_.output_height), cmyk_ ? 3 : cinfo_.num_components, "jpeg",
              PixelType::UInt8);
    return true;
  }

  bool read_pixels(PixelType type, void* first_row, std::ptrdiff_t row_stride, std::string& error) override {
    const std::size_t row_values = std::size_t(cinfo_.output_width) * std::size_t(cmyk_ ? 3 : cinfo_.num_components);
    const bool direct = type == PixelType::UInt8;
    std::vector<unsigned char> decoded(direct ? 0 : row_values * cinfo_.output_height);
    std::vector<unsigned char> cmyk_row(cmyk_ ? std::size_t(cinfo_.output_width) * 4 : 0);
    std::vector<unsigned char*> rows(cinfo_.output_height);
    for (JDIMENSION y = 0; y < cinfo_.output_height; ++y)
      rows[y] = direct ? static_cast<unsigned char*>(first_row) + row_stride * std::ptrdiff_t(y)
                       : decoded.data() + row_values * y;
    // A warning (data libjpeg could not decode, padded) while opening or reading fails the read.
    if (!warning_.empty()) {
      error = warning_;
      return false;
    }
    if (!decode(rows.data(), cmyk_ ? cmyk_row.data() : nullptr)) {
      error = error_;
      return false;
    }
    if (!direct)
      for (JDIMENSION y = 0; y < cinfo_.output_height; ++y)
        convert_values(PixelType::UInt8, rows[y], type, static_cast<char*>(first_row) + row_stride * std::ptrdiff_t(y),
                       row_values);
    return true;
  }

private:
  // The header, and the decompression started; false when libjpeg reported an error.
  bool start() {
    if (setjmp(errors_.jump)) return false;
    jpeg_create_decompress(&cinfo_);
    created_ = true;
    jpeg_mem_src(&cinfo_, bytes_.data(), static_cast<unsigned long>(bytes_.size()));
    if (jpeg_read_header(&cinfo_, FALSE) != JPEG_HEADER_OK) {
      error_ = "Bad JPEG header";
      return false;
    }
    if (cinfo_.jpeg_color_space == JCS_CMYK || cinfo_.jpeg_color_space == JCS_YCCK) {
      cinfo_.out_color_space = JCS_CMYK;  // YCCK decoded to CMYK by libjpeg
      cmyk_ = true;
    }
    jpeg_start_decompress(&cinfo_);
    return true;
  }

  bool decode(unsigned char* const* rows, unsigned char* cmyk_row) {
    if (setjmp(errors_.jump)) return false;
    return decode_rows(&cinfo_, rows, cmyk_row, warning_, error_);
  }

  jpeg_decompress_struct cinfo_{};
  ErrorManager errors_{};
  std::vector<unsigned char> bytes_;  // the file, or its bytes without metadata segments
  std::string error_, warning_;
  bool created_ = false;
  bool cmyk_ = false;
};

}  // namespace

std::unique_ptr<NativeReader> open_jpeg(const std::string& path, ReadSpec& spec, std::string& error) {
  return opened<JpegReader>(path, spec, error);
}

}  // namespace qdmr::imageio
