// libFuzzer harness: image files through qdmr::read_image, the function every texture, weights map and bake
// input is read with. The file name's extension follows the content's magic number, as real files would.
#include <cstddef>
#include <cstdint>
#include <cstring>
#include <string>

#include "fuzz_util.hpp"
#include "qdmr/core/error.hpp"
#include "qdmr/texture/image.hpp"

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  const auto starts = [&](const char* magic) { return size >= std::strlen(magic) && std::memcmp(data, magic, std::strlen(magic)) == 0; };
  const char* name = starts("\x89PNG")                      ? "image.png"
                     : starts("\xFF\xD8")                   ? "image.jpg"
                     : starts("\x76\x2F\x31\x01")           ? "image.exr"
                     : starts("II*") || starts("MM")        ? "image.tif"
                     : size >= 2 && data[0] == 'P'          ? "image.pgm"
                                                            : "image.png";
  const auto file = qdmr::fuzz::write(name, reinterpret_cast<const char*>(data), size);
  try {
    static_cast<void>(qdmr::read_image(file, "fuzz"));
  } catch (const qdmr::Error&) {
  }
  return 0;
}
