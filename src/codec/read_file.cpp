#include "codec/backend.hpp"
#include "codec/native_reader.hpp"

namespace qdmr::imageio {

ReadFile::ReadFile(const std::string& path, std::string& error) {
  bool claimed = false;
  native_ = open_native(path, spec_, error, claimed);
  if (claimed) return;
  backend_ = &backend();
  reader_ = backend_->open(path, spec_, error);
}

ReadFile::~ReadFile() {
  if (reader_) backend_->close(reader_);
}

bool ReadFile::read(PixelType type, void* first_row, std::ptrdiff_t row_stride, std::string& error) {
  if (native_) return native_->read(type, first_row, row_stride, error);
  return backend_->read(reader_, type, first_row, row_stride, error);
}

bool read_header(const std::string& path, ReadSpec& spec, std::string& error) {
  bool claimed = false;
  if (const auto native = open_native(path, spec, error, claimed); claimed) return native != nullptr;
  if (read_tiff_header(path, spec)) return true;  // a TIFF OpenImageIO converts
  const Backend& oiio = backend();
  Reader* const reader = oiio.open(path, spec, error);
  if (reader) oiio.close(reader);
  return reader != nullptr;
}

}  // namespace qdmr::imageio
