#include "codec/image_file.hpp"

#include <algorithm>
#include <cctype>

#include <tbb/task_arena.h>

#include "codec/exr_writer.hpp"
#include "codec/png_writer.hpp"
#include "file/atomic_file.hpp"

namespace qdmr {

void write_image_file(const std::filesystem::path& file, const imageio::WriteSpec& spec, const void* data,
                      const std::string& what) {
  // Same pixels, same bytes: OpenImageIO 2.4 stamps EXR (capDate) and TIFF (tag 306) files with the current time
  // when the spec has no DateTime; an empty DateTime is written as an empty string instead. A caller that wants a
  // time in the file sets DateTime itself (write_frame's WriteOptions::timestamp).
  imageio::WriteSpec stamped = spec;
  // The caller's task arena gives the threads: PNG's bands run on it, OpenEXR and OpenImageIO get its size.
  stamped.threads = tbb::this_task_arena::max_concurrency();
  if (std::none_of(spec.strings.begin(), spec.strings.end(), [](const auto& s) { return s.first == "DateTime"; }))
    stamped.strings.emplace_back("DateTime", "");
  std::string extension = file.extension().string();
  for (char& c : extension) c = char(std::tolower(static_cast<unsigned char>(c)));
  if (extension == ".png" && png_writes(stamped)) {  // no image module needed
    write_atomically(file, what, [&](const std::filesystem::path& temporary) -> std::string {
      std::string error;
      return write_png(temporary.string(), stamped, data, error) ? "" : error;
    });
    return;
  }
  if (extension == ".exr" && exr_writes(stamped)) {  // float EXR: OpenEXR directly, the same bytes
    write_atomically(file, what, [&](const std::filesystem::path& temporary) -> std::string {
      std::string error;
      return write_exr(temporary.string(), stamped, data, error) ? "" : error;
    });
    return;
  }
  const imageio::Backend& backend = imageio::backend();  // loaded before the temporary exists
  write_atomically(file, what, [&](const std::filesystem::path& temporary) -> std::string {
    const ExrThreads threads(stamped.threads);  // an EXR that write_exr leaves to OpenImageIO
    std::string error;
    return backend.write(temporary.string(), stamped, data, error) ? "" : error;
  });
}

}  // namespace qdmr
