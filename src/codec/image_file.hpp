#pragma once
// An image file written whole or not at all (file/atomic_file.hpp): PNG and float OpenEXR by qdmr's own writers
// (codec/png_writer.hpp, codec/exr_writer.hpp), every other file through the image backend.
#include <filesystem>
#include <string>

#include "codec/backend.hpp"

namespace qdmr {

// Writes no wall-clock time unless `spec` carries a DateTime attribute (see image_file.cpp). `data` holds
// spec.width x spec.height pixels of spec.channels values of spec.type, top row first. The write uses the threads
// of the caller's task arena (tbb::this_task_arena::max_concurrency(); spec.threads is replaced by it): PNG's
// bands run on the arena, OpenEXR and OpenImageIO compress on that many threads, 1 being the calling thread alone.
void write_image_file(const std::filesystem::path& file, const imageio::WriteSpec& spec, const void* data,
                      const std::string& what);

}  // namespace qdmr
