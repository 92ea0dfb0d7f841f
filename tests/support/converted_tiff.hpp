#pragma once
// A TIFF the native readers leave to the image module, for the tests of when the module is loaded.
#include <string>

namespace qdmr::test {

// The bytes of a 4x4 8-bit greyscale TIFF stored "min is white": a layout OpenImageIO converts (it inverts the
// samples), so the native readers leave it to the image module (codec/tiff_reader.cpp).
std::string min_is_white_tiff();

}  // namespace qdmr::test
