#pragma once
// A JPEG file's marker segments, walked before OpenImageIO's JPEG reader opens the file. OpenImageIO 2.4 decodes
// the metadata segments (Exif, XMP, IPTC, ICC profile, comments) when it opens a JPEG, and its IPTC decoder
// reads past the segment it is given (found by fuzz_image: a heap-buffer-overflow in decode_iptc_iim; fixed
// upstream after 2.4). qdmr uses none of that metadata, so the segments that only carry it are dropped from the
// bytes the reader sees; the pixels do not depend on them.
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
