#pragma once
// PNG, JPEG, OpenEXR and most TIFF files decoded in this process by libpng, libjpeg-turbo, OpenEXR and libtiff, the
// libraries OpenImageIO's own readers call, in the same way: the same pixels, refusals and header; PBM, PGM and
// PPM files as Netpbm defines them (codec/pnm_reader.cpp: where OpenImageIO's reader got them wrong), and PFM
// files as OpenImageIO read them. They are the formats of textures, and reading them without OpenImageIO spares a
// job the loading of the image module (~260 shared libraries, 0.3-0.5 s: docs/performance-history.md). Every other file
// goes to the backend (codec/backend.hpp): the TIFF layouts OpenImageIO converts (codec/tiff_reader.cpp says
// which; their header alone is read here: read_header), and formats qdmr does not take as textures (refused after
// the backend names them).
//
// What OpenImageIO 2.4 does and these readers do too: libpng expands palettes, low bit depths and tRNS to 8-bit
// channels (and alpha), 16-bit samples in host order, an interlaced file read whole, a JPEG's CMYK or YCCK
// converted to RGB as OpenImageIO converts it (R = C·K in float, rounded), a libjpeg warning (damaged data) a
// failure of the read that follows. Alpha is kept as stored (oiio:UnassociatedAlpha, as the backend asks).
// Metadata: a PNG's text chunks and an OpenEXR file's string attributes only (Software, qdmr:bits_version); a
// TIFF's Software tag; a JPEG's none (its metadata segments are dropped first: codec/jpeg_segments.hpp).
#include <cstddef>
#include <memory>
#include <string>
#include <utility>

#include "codec/backend.hpp"

namespace qdmr::imageio {

class NativeReader {
public:
  virtual ~NativeReader() = default;
  // As Backend::read. `type` other than the file's own converts k to k / (2^bits - 1), correctly rounded; a file
  // of float samples (a TIFF's, an OpenEXR file, a PFM file, a PNM file of a maxval other than 255 and 65535) is
  // read as floats only. A file is read once: a second call fails.
  bool read(PixelType type, void* first_row, std::ptrdiff_t row_stride, std::string& error) {
    if (read_) {
      error = "the image file was read already";
      return false;
    }
    read_ = true;
    return read_pixels(type, first_row, row_stride, error);
  }

private:
  virtual bool read_pixels(PixelType type, void* first_row, std::ptrdiff_t row_stride, std::string& error) = 0;
  bool read_ = false;
};

// For a file that starts with PNG's, JPEG's, OpenEXR's or PBM/PGM/PPM/PFM's signature, or a TIFF that libtiff opens
// in a layout OpenImageIO reads as stored: `claimed` is true, and the reader with `spec` filled in, or null with
// `error` set. For any other file `claimed` is false, `error` is left as it was and the backend is the file's
// reader.
std::unique_ptr<NativeReader> open_native(const std::string& path, ReadSpec& spec, std::string& error, bool& claimed);

// Whether open_native claims `path`: reading it loads no image module.
bool read_natively(const std::string& path);

// `spec` of a 2D image as a native reader found it (its metadata left as it was).
inline void set_image(ReadSpec& spec, int width, int height, int channels, const char* format, PixelType type,
                      bool uniform = true) {
  spec.width = width;
  spec.height = height;
  spec.depth = 1;
  spec.channels = channels;
  spec.format = format;
  spec.uniform = uniform;
  spec.type = type;
}

// A new reader of type R, opened with `arguments`; null when its open() fails (having said why).
template <class R, class... Arguments>
std::unique_ptr<NativeReader> opened(Arguments&&... arguments) {
  auto reader = std::make_unique<R>();
  if (!reader->open(std::forward<Arguments>(arguments)...)) return nullptr;
  return reader;
}

// The readers open_native chooses from, by signature. A TIFF is claimed only after libtiff read its header.
std::unique_ptr<NativeReader> open_png(const std::string& path, ReadSpec& spec, std::string& error);
std::unique_ptr<NativeReader> open_jpeg(const std::string& path, ReadSpec& spec, std::string& error);
std::unique_ptr<NativeReader> open_tiff(const std::string& path, ReadSpec& spec, bool& claimed);
// The header (size, channels, sample type; no metadata) that OpenImageIO's open gives a TIFF, read by libtiff as
// OpenImageIO reads it: for the layouts open_tiff leaves to the backend, which a plan need not load for them. False,
// `spec` left as it was, for a file libtiff cannot open, one OpenImageIO refuses, or one this cannot be sure of.
bool read_tiff_header(const std::string& path, ReadSpec& spec);
std::unique_ptr<NativeReader> open_exr(const std::string& path, ReadSpec& spec, std::string& error);
std::unique_ptr<NativeReader> open_pnm(const std::string& path, ReadSpec& spec, std::string& error);

}  // namespace qdmr::imageio
