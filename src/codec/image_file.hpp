#pragma once
// An image file written whole or not at all (file/atomic_file.hpp): PNG and float OpenEXR by qdmr's own writers
// (codec/png_writer.hpp, codec/exr_writer.hpp), every other file through the image backend.
#include <filesystem>
#include <string>

#include "codec/backend.hpp"

namespace qdmr {

// Writes no wall-clock time unless `spec` carries a DateTime attribute (see image_file.cpp). `data` holds
// spec.width x spec.height pixels of spec.channels values of spec.type, top row first.
void write_image_file(const std::filesystem::path& file, const imageio::WriteSpec& spec, const void* data,
                      const std::string& what);

}  // namespace qdmr
