#include "imageio/native_reader.hpp"

#include <png.h>

#include <cstdio>

namespace qdmr::imageio {

namespace {

enum class Signature { Png, Jpeg, Other };

// The checks of OpenImageIO's readers (valid_file), so no PNG or JPEG ever reaches theirs: PNG's first seven
// bytes (libpng then checks the eighth), JPEG's SOI marker.
Signature signature_of(const std::string& path) {
  unsigned char bytes[8] = {};
  std::size_t got = 0;
  if (std::FILE* file = std::fopen(path.c_str(), "rb")) {
    got = std::fread(bytes, 1, sizeof bytes, file);
    std::fclose(file);
  }
  if (got == sizeof bytes && png_sig_cmp(bytes, 0, 7) == 0) return Signature::Png;
  if (got >= 2 && bytes[0] == 0xFF && bytes[1] == 0xD8) return Signature::Jpeg;
  return Signature::Other;
}

}  // namespace

bool read_natively(const std::string& path) { return signature_of(path) != Signature::Other; }

std::unique_ptr<NativeReader> open_native(const std::string& path, ReadSpec& spec, std::string& error, bool& claimed) {
  const Signature signature = signature_of(path);
  claimed = signature != Signature::Other;
  if (signature == Signature::Png) return open_png(path, spec, error);
  if (signature == Signature::Jpeg) return open_jpeg(path, spec, error);
  return nullptr;
}

}  // namespace qdmr::imageio
