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
// The chunks are compressed on spec.threads threads (ExrThreads).
bool write_exr(const std::string& path, const imageio::WriteSpec& spec, const void* data, std::string& error);

// While it lives, the OpenEXR files this thread writes (write_exr, or OpenImageIO's writer) are compressed, and the
// files it reads (codec/exr_reader.cpp) decompressed, on `threads` threads of their own (0: one per core), and with
// 1 in the calling thread alone: OpenEXR's global pool gets a provider that sends this thread's tasks there
// (exr_writer.cpp), not to the pool other users of OpenEXR in the process share. The bytes and pixels are the same
// on any count.
class ExrThreads {
public:
  explicit ExrThreads(int threads);
  ~ExrThreads();
  ExrThreads(const ExrThreads&) = delete;
  ExrThreads& operator=(const ExrThreads&) = delete;
  int threads() const;  // the count in effect, at least 1: OpenEXR's numThreads for the file (its chunks in flight)

private:
  int previous_;
};

}  // namespace qdmr
