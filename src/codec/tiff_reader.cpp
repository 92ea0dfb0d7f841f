// A TIFF read by libtiff, for the layouts OpenImageIO 2.4's TIFF reader (tiff.imageio/tiffinput.cpp) passes
// through unchanged: grey (min-is-black) or RGB samples of 8 or 16 bits unsigned or 32-bit floats, in strips or
// tiles, interleaved or in planes, with any compression libtiff decodes but JPEG (which OpenImageIO may read
// through libtiff's RGBA interface). OpenImageIO converts the other layouts (palettes, min-is-white, CMYK, 1- to
// 14-bit samples, signed or half-float samples, YCbCr), and reads the first image only, as here; they stay its to
// read, but their header, which a plan needs, is read here too, as OpenImageIO's open finds it (read_tiff_header).
#include <tiffio.h>

#include <algorithm>
#include <cstdarg>
#include <cstdio>
#include <cstring>
#include <memory>
#include <optional>
#include <string>

#include "codec/native_reader.hpp"
#include "codec/pixel_conversion.hpp"

namespace qdmr::imageio {
namespace {

constexpr int kMaxKeptMessages = 3;  // a damaged strip may be reported once per row

std::size_t size_of(PixelType type) { return type == PixelType::UInt8 ? 1 : type == PixelType::UInt16 ? 2 : 4; }

// A libtiff message unprinted (its default handlers write to stderr). OpenImageIO ignores libtiff's warnings
// (unknown tags, a missing optional field).
int ignore_message(TIFF*, void*, const char*, const char*, va_list) { return 1; }

// `path` opened by libtiff as OpenImageIO opens it ("m": read, not memory-mapped), its errors to `on_error`; null
// if libtiff cannot read its first directory.
TIFF* open_file(const std::string& path, TIFFErrorHandlerExtR on_error, void* user_data) {
  TIFFOpenOptions* options = TIFFOpenOptionsAlloc();
  if (!options) return nullptr;
  TIFFOpenOptionsSetErrorHandlerExtR(options, on_error, user_data);
  TIFFOpenOptionsSetWarningHandlerExtR(options, ignore_message, nullptr);
  TIFF* tiff = TIFFOpenExt(path.c_str(), "rm", options);
  TIFFOpenOptionsFree(options);
  return tiff;
}

class TiffReader final : public NativeReader {
public:
  ~TiffReader() override {
    if (tiff_) TIFFClose(tiff_);
  }

  // False with `claimed` false for a file libtiff cannot open or a layout left to the backend; `error` is then
  // left as it was.
  bool open(const std::string& path, ReadSpec& spec, bool& claimed) {
    claimed = false;
    tiff_ = open_file(path, on_error, this);
    if (!tiff_ || !passes_through()) return false;
    claimed = true;
    // Uniform: libtiff keeps one SampleFormat and one BitsPerSample for every channel.
    set_image(spec, int(width_), int(height_), int(channels_), "tiff", stored_);
    // OpenImageIO's TIFF writer keeps no metadata of its own names, so a "qdmr:bits_version" is never found.
    if (char* software = nullptr; TIFFGetField(tiff_, TIFFTAG_SOFTWARE, &software) == 1 && software)
      spec.software = software;
    return true;
  }

  bool read_pixels(PixelType type, void* first_row, std::ptrdiff_t row_stride, std::string& error) override {
    if (type != stored_ && stored_ == PixelType::Float) {
      error = "a TIFF of float samples is read as floats only";
      return false;
    }
    // As OpenImageIO: a read fails when libtiff's call does (its error messages alone, say from the header, do not
    // fail it), with what libtiff said from here on.
    message_.clear();
    messages_ = 0;
    type_ = type;
    first_row_ = static_cast<char*>(first_row);
    row_stride_ = row_stride;
    const bool ok = tiled_ ? read_tiles() : read_strips();
    if (!ok) error = message_.empty() ? "libtiff could not decode the pixel data" : message_;
    return ok;
  }

private:
  static int on_error(TIFF*, void* reader, const char* module, const char* format, va_list args) {
    auto& self = *static_cast<TiffReader*>(reader);
    if (self.messages_ < kMaxKeptMessages) {
      char text[512];
      std::vsnprintf(text, sizeof text, format, args);
      if (!self.message_.empty()) self.message_ += '\n';
      self.message_ += (module && *module ? std::string(module) + ": " : std::string()) + text;
    }
    ++self.messages_;
    return 1;  // handled: libtiff's default handler would print to stderr
  }

  // Whether OpenImageIO would pass this layout through as stored; also sets the fields the read uses.
  bool passes_through() {
    std::uint16_t samples = 1, bits = 1, format = SAMPLEFORMAT_UINT, compression = COMPRESSION_NONE;
    std::uint16_t planar = PLANARCONFIG_CONTIG;
    std::uint32_t depth = 1;
    TIFFGetField(tiff_, TIFFTAG_IMAGEWIDTH, &width_);
    TIFFGetField(tiff_, TIFFTAG_IMAGELENGTH, &height_);
    TIFFGetFieldDefaulted(tiff_, TIFFTAG_IMAGEDEPTH, &depth);
    TIFFGetFieldDefaulted(tiff_, TIFFTAG_SAMPLESPERPIXEL, &samples);
    TIFFGetFieldDefaulted(tiff_, TIFFTAG_BITSPERSAMPLE, &bits);
    TIFFGetFieldDefaulted(tiff_, TIFFTAG_SAMPLEFORMAT, &format);
    TIFFGetFieldDefaulted(tiff_, TIFFTAG_COMPRESSION, &compression);
    TIFFGetFieldDefaulted(tiff_, TIFFTAG_PLANARCONFIG, &planar);
    // OpenImageIO's default when the tag is missing.
    std::uint16_t photometric = samples == 1 ? PHOTOMETRIC_MINISBLACK : PHOTOMETRIC_RGB;
    TIFFGetField(tiff_, TIFFTAG_PHOTOMETRIC, &photometric);
    if (width_ == 0 || height_ == 0 || depth != 1 || samples == 0) return false;
    if (!(photometric == PHOTOMETRIC_MINISBLACK || (photometric == PHOTOMETRIC_RGB && samples >= 3))) return false;
    if (bits == 8 && format == SAMPLEFORMAT_UINT)
      stored_ = PixelType::UInt8;
    else if (bits == 16 && format == SAMPLEFORMAT_UINT)
      stored_ = PixelType::UInt16;
    else if (bits == 32 && format == SAMPLEFORMAT_IEEEFP)
      stored_ = PixelType::Float;
    else
      return false;
    if (compression == COMPRESSION_JPEG || compression == COMPRESSION_OJPEG || !TIFFIsCODECConfigured(compression))
      return false;
    channels_ = samples;
    separate_ = planar == PLANARCONFIG_SEPARATE && samples > 1;
    tiled_ = TIFFIsTiled(tiff_) != 0;
    const std::uint64_t per_pixel = separate_ ? 1 : samples;
    if (tiled_) {
      TIFFGetField(tiff_, TIFFTAG_TILEWIDTH, &tile_width_);
      TIFFGetField(tiff_, TIFFTAG_TILELENGTH, &tile_height_);
      if (tile_width_ == 0 || tile_height_ == 0) return false;
      return TIFFTileRowSize64(tiff_) == std::uint64_t(tile_width_) * per_pixel * size_of(stored_);
    }
    return TIFFScanlineSize64(tiff_) == std::uint64_t(width_) * per_pixel * size_of(stored_);
  }

  // `columns` pixels' samples as stored (one plane's, or all channels' interleaved), converted to the asked type
  // and put in image row `row` from column `column` on.
  void place(const unsigned char* samples, std::uint32_t columns, std::uint32_t row, std::uint32_t column,
             std::uint16_t plane) {
    const std::size_t out_size = size_of(type_);
    const std::size_t values = std::size_t(columns) * (separate_ ? 1 : channels_);
    if (type_ != stored_) {
      if (converted_size_ < values * out_size) {
        converted_ = std::make_unique_for_overwrite<unsigned char[]>(values * out_size);
        converted_size_ = values * out_size;
      }
      convert_values(stored_, samples, type_, converted_.get(), values);
      samples = converted_.get();
    }
    char* out = first_row_ + row_stride_ * std::ptrdiff_t(row) +
                std::ptrdiff_t((std::size_t(column) * channels_ + (separate_ ? plane : 0)) * out_size);
    if (!separate_) {
      std::memcpy(out, samples, values * out_size);
      return;
    }
    for (std::size_t i = 0; i < values; ++i, out += std::ptrdiff_t(channels_ * out_size))
      std::memcpy(out, samples + i * out_size, out_size);
  }

  // Rows in order, one plane after the other (each plane's strips are compressed apart; reading them row-major
  // would restart a strip's decoding for every plane).
  bool read_strips() {
    const auto bytes = std::size_t(TIFFScanlineSize64(tiff_));
    const auto row = std::make_unique_for_overwrite<unsigned char[]>(bytes);
    const std::uint16_t planes = separate_ ? channels_ : 1;
    for (std::uint16_t plane = 0; plane < planes; ++plane)
      for (std::uint32_t y = 0; y < height_; ++y) {
        if (TIFFReadScanline(tiff_, row.get(), y, plane) < 0) return false;
        place(row.get(), width_, y, 0, plane);
      }
    return true;
  }

  bool read_tiles() {
    const auto bytes = std::size_t(TIFFTileSize64(tiff_));
    const auto row_bytes = std::size_t(TIFFTileRowSize64(tiff_));
    // Not cleared: only what libtiff decoded is read from it.
    const auto tile = std::make_unique_for_overwrite<unsigned char[]>(bytes);
    const std::uint16_t planes = separate_ ? channels_ : 1;
    for (std::uint16_t plane = 0; plane < planes; ++plane)
      for (std::uint32_t y = 0; y < height_; y += tile_height_)
        for (std::uint32_t x = 0; x < width_; x += tile_width_) {
          if (TIFFReadTile(tiff_, tile.get(), x, y, 0, plane) < 0) return false;
          const std::uint32_t columns = std::min(tile_width_, width_ - x);
          const std::uint32_t rows = std::min(tile_height_, height_ - y);
          for (std::uint32_t r = 0; r < rows; ++r) place(tile.get() + row_bytes * r, columns, y + r, x, plane);
        }
    return true;
  }

  TIFF* tiff_ = nullptr;
  std::string message_;  // libtiff's errors, as on_error words them
  int messages_ = 0;
  std::uint32_t width_ = 0, height_ = 0, tile_width_ = 0, tile_height_ = 0;
  std::uint16_t channels_ = 0;
  PixelType stored_ = PixelType::UInt8;
  bool separate_ = false, tiled_ = false;
  // The read in progress.
  PixelType type_ = PixelType::UInt8;
  char* first_row_ = nullptr;
  std::ptrdiff_t row_stride_ = 0;
  std::unique_ptr<unsigned char[]> converted_;
  std::size_t converted_size_ = 0;
};

// The header OpenImageIO 2.4's reader gives the first image of `tiff` (tiffinput.cpp: readspec,
// readspec_photometric, seek_subimage), from the fields it reads, read as it reads them; false where its open fails
// (samples it has no type for, a layout libtiff's RGBA interface refuses) or this cannot be sure of what it gives.
bool oiio_header(TIFF* tiff, ReadSpec& spec) {
  std::uint32_t width = 0, height = 0, depth = 1;
  std::uint16_t samples = 1, bits = 8, format = SAMPLEFORMAT_UINT, compression = COMPRESSION_NONE;
  TIFFGetField(tiff, TIFFTAG_IMAGEWIDTH, &width);
  TIFFGetField(tiff, TIFFTAG_IMAGELENGTH, &height);
  TIFFGetFieldDefaulted(tiff, TIFFTAG_IMAGEDEPTH, &depth);
  TIFFGetFieldDefaulted(tiff, TIFFTAG_SAMPLESPERPIXEL, &samples);
  TIFFGetField(tiff, TIFFTAG_BITSPERSAMPLE, &bits);  // 8 without the tag, as OpenImageIO has it (libtiff says 1)
  TIFFGetFieldDefaulted(tiff, TIFFTAG_SAMPLEFORMAT, &format);
  TIFFGetFieldDefaulted(tiff, TIFFTAG_COMPRESSION, &compression);
  std::uint16_t photometric = samples == 1 ? PHOTOMETRIC_MINISBLACK : PHOTOMETRIC_RGB;
  TIFFGetField(tiff, TIFFTAG_PHOTOMETRIC, &photometric);
  if (depth != 1) return false;  // a volume (ImageDepth): left to OpenImageIO, as by the reader
  int channels = samples;
  // The samples' type, fewer bits widened (1 to 6 to 8, 10 to 14 to 16, 24 to 32); OpenImageIO's types but 8- and
  // 16-bit unsigned (signed, half, 32-bit integer, double) are floats here. None: a type OpenImageIO has none for.
  std::optional<PixelType> type;
  const bool to_8 = bits == 1 || bits == 2 || bits == 4 || bits == 6 || bits == 8;
  const bool to_16 = bits == 10 || bits == 12 || bits == 14 || bits == 16;
  const bool numbers = format == SAMPLEFORMAT_UINT || format == SAMPLEFORMAT_INT || format == SAMPLEFORMAT_IEEEFP;
  if (to_8)
    type = format == SAMPLEFORMAT_INT ? PixelType::Float : PixelType::UInt8;  // any other format read as unsigned
  else if (to_16 && format == SAMPLEFORMAT_UINT)
    type = PixelType::UInt16;
  else if (((to_16 || bits == 24 || bits == 32) && numbers) || (bits == 64 && format == SAMPLEFORMAT_IEEEFP))
    type = PixelType::Float;
  if (photometric == PHOTOMETRIC_SEPARATED) {
    std::uint16_t inks = INKSET_CMYK;
    TIFFGetFieldDefaulted(tiff, TIFFTAG_INKSET, &inks);
    if (inks == INKSET_CMYK && channels == 4) channels = 3;  // CMYK to RGB; other inks as stored
  } else if (photometric == PHOTOMETRIC_PALETTE) {
    // To 8-bit RGB, through 2^bits colours that OpenImageIO takes for granted: a palette of more than 8 bits, or
    // with no colour map, is left to it.
    std::uint16_t *red = nullptr, *green = nullptr, *blue = nullptr;
    if (bits > 8 || TIFFGetField(tiff, TIFFTAG_COLORMAP, &red, &green, &blue) != 1) return false;
    channels = 3;
    type = PixelType::UInt8;
  }
  // JPEG-compressed samples other than three, and colour spaces other than RGB (YCbCr, CIE L*a*b*, LogL, LogLuv),
  // are read through libtiff's RGBA interface: 8-bit samples, as many channels; the open fails where libtiff says
  // that interface cannot read the file. OpenImageIO asks it after reading the Exif directory and going back to the
  // image's: a file with one is left to it.
  const bool jpeg = compression == COMPRESSION_JPEG || compression == COMPRESSION_OJPEG;
  const bool not_rgb = photometric == PHOTOMETRIC_YCBCR || photometric == PHOTOMETRIC_CIELAB ||
                       photometric == PHOTOMETRIC_ICCLAB || photometric == PHOTOMETRIC_ITULAB ||
                       photometric == PHOTOMETRIC_LOGL || photometric == PHOTOMETRIC_LOGLUV;
  if ((jpeg && channels != 3) || not_rgb) {
    toff_t exif = 0;
    char why_not[1024];
    if (TIFFGetField(tiff, TIFFTAG_EXIFIFD, &exif) == 1 || TIFFRGBAImageOK(tiff, why_not) != 1) return false;
    type = PixelType::UInt8;
  }
  if (!type) return false;
  // OpenImageIO's limits (1024 channels, 32 GiB of samples) are not checked: a texture's (4 channels, 16384 pixels
  // a side, read_image_header's checks) are inside them, so a file over them is refused either way.
  set_image(spec, int(width), int(height), channels, "tiff", *type);
  return true;
}

}  // namespace

std::unique_ptr<NativeReader> open_tiff(const std::string& path, ReadSpec& spec, bool& claimed) {
  return opened<TiffReader>(path, spec, claimed);
}

bool read_tiff_header(const std::string& path, ReadSpec& spec) {
  const std::unique_ptr<TIFF, void (*)(TIFF*)> tiff(open_file(path, ignore_message, nullptr), TIFFClose);
  return tiff && oiio_header(tiff.get(), spec);
}

}  // namespace qdmr::imageio
