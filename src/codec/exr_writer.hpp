#pragma once
// 32-bit float OpenEXR files written with the OpenEXR library directly, so that writing a float image (an EXR render,
// an AOV, a study's kept AOVs, a cone map) does not load the OpenImageIO module (~260 shared libraries, about 0.3 s
// of dynamic linking, codec/backend.hpp). The file is byte for byte what the OpenImageIO 2.4 backend writes for the
// same spec (tests/codec/exr_writer_test.cpp compares them): one scanline part, ZIP compression at OpenEXR's
// default level, OpenImageIO's default channel names (Y for one channel; R, G, B, A), DateTime as capDate and the
// other strings as string attributes of their own names.
#include <string>

#include "codec/backend.hpp"

namespace qdmr {

// Whether write_exr takes this spec: float data of 1 to 4 channels (named, or OpenImageIO's default names), no
// integer attributes, a DateTime (write_image_file's empty one, or a time) and no string attributes but DateTime,
// Software and qdmr:bits_version (others, which OpenImageIO renames or converts, stay with it).
bool exr_writes(const imageio::WriteSpec& spec);

// Writes `data` (rows top-down, channels interleaved) into the existing file `path` (truncated); on failure returns
// false with `error` set to the first OS error (a full disk) or OpenEXR's message (the caller removes the file).
bool write_exr(const std::string& path, const imageio::WriteSpec& spec, const void* data, std::string& error);

}  // namespace qdmr
