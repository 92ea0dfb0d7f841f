#pragma once
// Image files go through one narrow interface to OpenImageIO, so that the `qdmr` command can load OpenImageIO
// (and the ~260 shared libraries it pulls in, about 0.3 s of dynamic linking) only when a job reads or writes an
// image that qdmr does not handle itself: PNG, JPEG, OpenEXR, PBM/PGM/PPM and most TIFF are read in process
// (codec/native_reader.hpp), PNG and float OpenEXR written so too (codec/png_writer.hpp, codec/exr_writer.hpp). The library and the tests link the backend
// directly (codec/direct.cpp); the command loads it from libqdmr_imageio.so on first use (codec/lazy.cpp).
// Both run the same code (codec/oiio_backend.cpp).
#include <cstddef>
#include <memory>
#include <string>
#include <utility>
#include <vector>

namespace qdmr::imageio {

enum class PixelType : int { UInt8, UInt16, Float };

// What a reader found in a file's header.
struct ReadSpec {
  int width = 0, height = 0, depth = 1, channels = 0;
  std::string format;          // OpenImageIO's format name: "png", "jpeg", "openexr", "tiff", "pnm", ...
  bool uniform = true;         // one pixel type for every channel
  PixelType type = PixelType::Float;  // the file's type when uniform and 8- or 16-bit unsigned, else Float
  std::string bits_version;    // metadata "qdmr:bits_version", or empty
  std::string software;        // metadata "Software", or empty
};

struct WriteSpec {
  int width = 0, height = 0, channels = 0;
  PixelType type = PixelType::Float;  // of the data and of the file
  std::vector<std::string> channel_names;  // empty: the defaults (R, G, B, A)
  std::vector<std::pair<std::string, std::string>> strings;  // metadata
  std::vector<std::pair<std::string, int>> ints;
  int threads = 0;  // at most this many threads compress the file (0: the writer's default, one per core)
};

struct Reader;  // an open file (the backend's)

// Errors come back as messages (possibly several lines); nothing throws across the interface.
struct Backend {
  Reader* (*open)(const std::string& path, ReadSpec& spec, std::string& error);
  // Every pixel as `type`, the file's first row at `first_row` and each next row `row_stride` bytes further
  // (negative: bottom-up). A decoder error or warning is a failure.
  bool (*read)(Reader* reader, PixelType type, void* first_row, std::ptrdiff_t row_stride, std::string& error);
  void (*close)(Reader* reader);
  bool (*write)(const std::string& path, const WriteSpec& spec, const void* data, std::string& error);
  // One channel of `values` in [0, 1] (width x height) through a named colour map ("magma") to RGB.
  void (*color_map)(const float* values, int width, int height, const char* map, float* rgb);
};

// The backend of this program: linked in, or loaded on first use (throws qdmr::Error when it cannot be loaded).
const Backend& backend();

// The OpenImageIO implementation, which backend() returns or the module exports.
const Backend& oiio_backend();

class NativeReader;  // codec/native_reader.hpp

// An open file, closed when it goes: one the native readers claim (codec/native_reader.hpp) read by them, any
// other file by the backend, loaded only then.
class ReadFile {
public:
  // Not open (and `error` set) when the file cannot be opened.
  ReadFile(const std::string& path, std::string& error);
  ~ReadFile();
  ReadFile(const ReadFile&) = delete;
  ReadFile& operator=(const ReadFile&) = delete;

  explicit operator bool() const { return native_ != nullptr || reader_ != nullptr; }
  const ReadSpec& spec() const { return spec_; }
  bool read(PixelType type, void* first_row, std::ptrdiff_t row_stride, std::string& error);

private:
  ReadSpec spec_;
  std::unique_ptr<NativeReader> native_;
  const Backend* backend_ = nullptr;
  Reader* reader_ = nullptr;
};

// The header a ReadFile of `path` would find (true), or false with `error` set where it would not open; no pixel is
// read, and the image module is loaded only for a file that neither the native readers nor libtiff (a TIFF
// OpenImageIO converts: read_tiff_header in codec/tiff_reader.cpp) can answer for.
bool read_header(const std::string& path, ReadSpec& spec, std::string& error);

}  // namespace qdmr::imageio
