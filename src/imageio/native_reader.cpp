#include "imageio/native_reader.hpp"

#include <png.h>

#include <cstdio>

namespace qdmr::imageio {

std::unique_ptr<NativeReader> open_native(const std::string& path, ReadSpec& spec, std::string& error, bool& claimed) {
  unsigned char signature[8] = {};
  std::size_t got = 0;
  if (std::FILE* file = std::fopen(path.c_str(), "rb")) {
    got = std::fread(signature, 1, sizeof signature, file);
    std::fclose(file);
  }
  // The checks of OpenImageIO's readers (valid_file), so no PNG or JPEG ever reaches theirs: PNG's first seven
  // bytes (libpng then checks the eighth), JPEG's SOI marker.
  claimed = true;
  if (got == sizeof signature && png_sig_cmp(signature, 0, 7) == 0) return open_png(path, spec, error);
  if (got >= 2 && signature[0] == 0xFF && signature[1] == 0xD8) return open_jpeg(path, spec, error);
  claimed = false;
  return nullptr;
}

}  // namespace qdmr::imageio
