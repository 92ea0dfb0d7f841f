#include "codec/native_reader.hpp"

#include <png.h>

#include <cstdio>

namespace qdmr::imageio {

namespace {

enum class Signature { Png, Jpeg, Tiff, Exr, Pnm, Other };

// The checks of OpenImageIO's readers (valid_file), so no PNG or JPEG ever reaches theirs: PNG's first seven
// bytes (libpng then checks the eighth), JPEG's SOI marker; TIFF's byte order and version (42, or 43 for
// BigTIFF); OpenEXR's magic number; "P1" to "P6" of PBM, PGM and PPM, "Pf" and "PF" of PFM.
Signature signature_of(const std::string& path) {
  unsigned char bytes[8] = {};
  std::size_t got = 0;
  if (std::FILE* file = std::fopen(path.c_str(), "rb")) {
    got = std::fread(bytes, 1, sizeof bytes, file);
    std::fclose(file);
  }
  if (got == sizeof bytes && png_sig_cmp(bytes, 0, 7) == 0) return Signature::Png;
  if (got >= 2 && bytes[0] == 0xFF && bytes[1] == 0xD8) return Signature::Jpeg;
  if (got >= 4 && ((bytes[0] == 'I' && bytes[1] == 'I' && (bytes[2] == 42 || bytes[2] == 43) && bytes[3] == 0) ||
                   (bytes[0] == 'M' && bytes[1] == 'M' && bytes[2] == 0 && (bytes[3] == 42 || bytes[3] == 43))))
    return Signature::Tiff;
  if (got >= 4 && bytes[0] == 0x76 && bytes[1] == 0x2F && bytes[2] == 0x31 && bytes[3] == 0x01) return Signature::Exr;
  if (got >= 2 && bytes[0] == 'P' && ((bytes[1] >= '1' && bytes[1] <= '6') || bytes[1] == 'f' || bytes[1] == 'F'))
    return Signature::Pnm;
  return Signature::Other;
}

}  // namespace

bool read_natively(const std::string& path) {
  const Signature signature = signature_of(path);
  if (signature != Signature::Tiff) return signature != Signature::Other;
  ReadSpec spec;
  bool claimed = false;
  open_tiff(path, spec, claimed);
  return claimed;
}

std::unique_ptr<NativeReader> open_native(const std::string& path, ReadSpec& spec, std::string& error, bool& claimed) {
  const Signature signature = signature_of(path);
  claimed = signature == Signature::Png || signature == Signature::Jpeg || signature == Signature::Exr ||
            signature == Signature::Pnm;
  if (signature == Signature::Png) return open_png(path, spec, error);
  if (signature == Signature::Jpeg) return open_jpeg(path, spec, error);
  if (signature == Signature::Exr) return open_exr(path, spec, error);
  if (signature == Signature::Pnm) return open_pnm(path, spec, error);
  if (signature == Signature::Tiff) return open_tiff(path, spec, claimed);
  return nullptr;
}

}  // namespace qdmr::imageio
