#pragma once
// A JPEG file's marker segments, walked before libjpeg reads the file (codec/jpeg_reader.cpp). Damaged segments
// before the first scan are refused with what is wrong. The segments that only carry metadata (Exif, XMP, IPTC,
// ICC profile, comments) are dropped from the bytes the decoder sees: qdmr uses none of it and the pixels do not
// depend on it. (This began in front of OpenImageIO's JPEG reader, which decodes that metadata when it opens a
// file, and whose 2.4 IPTC decoder read past the segment it was given: found by fuzz_image, fixed upstream after
// 2.4. JPEG files no longer reach OpenImageIO.)
#include <string>
#include <vector>

namespace qdmr::imageio {

// Walks the JPEG `path` from its start (SOI, FF D8) to its first scan: every segment must be whole (its declared
// length within the file) and start with a marker. Returns false with `error` set when not. Otherwise `stripped`
// is the file without its metadata segments before the first scan (APP1 to APP13, APP15, COM; APP0 and APP14
// stay: libjpeg reads them), or empty when it has none or `path` does not start with SOI (libjpeg refuses such a
// file before it reads a segment), so the file can be read as it is.
bool jpeg_without_metadata(const std::string& path, std::vector<unsigned char>& stripped, std::string& error);

}  // namespace qdmr::imageio
