// libFuzzer harness: image files through qdmr::read_image, the function every texture, weights map and bake
// input is read with. The file name's extension follows the content's magic number, as real files would.
//
// It reads the header first (read_image_header, as a render's plan does) and the pixels only when the memory the
// plan charges for the read (read_image_bytes) is at most 8 MiB, the check a render makes against `--max-memory`,
// with 8 MiB for this image alone: 512 x 512 RGBA of 16 bits, 1024 x 1024 of one 8-bit channel. Under
// AddressSanitizer an image's cost grows with its size, decoded or not (the shadow of every block is poisoned when
// it is allocated and again when it is freed): mutations of a few small TIFFs whose strips all point at the same
// bytes (254 x 12336 RGBA from 7 KB, 62 MB to read, and their variants under any cap) took most of the run's time.
// A 64 KiB input exercises the same header, row, strip and tile code at 8 MiB as at 2 GB; blocks of gigabytes are
// allocated and freed under AddressSanitizer in CI by the input tests
// (TextureImage.SmallFilesThatDeclareLargeImagesThrowAfterTheirHeader, ZeroedBuffer.*).
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
  constexpr std::uint64_t kMaxReadBytes = std::uint64_t(8) << 20;
  try {
    if (qdmr::read_image_bytes(qdmr::read_image_header(file, "fuzz")) <= kMaxReadBytes)
      static_cast<void>(qdmr::read_image(file, "fuzz"));
  } catch (const qdmr::Error&) {
  }
  return 0;
}
