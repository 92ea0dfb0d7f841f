#pragma once
// Files are written next to their target under a temporary name and renamed over it only when complete, so a
// failed write never leaves a partial file behind and never damages an existing one.
#include <filesystem>
#include <functional>
#include <string>

#include <OpenImageIO/imageio.h>

namespace qdmr {

// write(temporary) returns an empty string on success or what went wrong. Throws qdmr::Error(file, what + ...)
// after removing the temporary.
void write_atomically(const std::filesystem::path& file, const std::string& what,
                      const std::function<std::string(const std::filesystem::path& temporary)>& write);

// Writes no wall-clock time unless `spec` carries a DateTime attribute (see atomic_file.cpp).
void write_image_file(const std::filesystem::path& file, const OIIO::ImageSpec& spec, OIIO::TypeDesc format,
                      const void* data, const std::string& what);

void write_text_file(const std::filesystem::path& file, const std::string& text);

}  // namespace qdmr
