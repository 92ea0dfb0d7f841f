#include "codec/jpeg_segments.hpp"

#include <algorithm>
#include <cstdint>
#include <fstream>
#include <utility>

namespace qdmr::imageio {
namespace {

// Markers that carry metadata only: APP1 (Exif, XMP), APP2 (ICC) ... APP13 (Photoshop IPTC), APP15, COM.
bool metadata_only(int marker) { return (marker >= 0xE1 && marker <= 0xED) || marker == 0xEF || marker == 0xFE; }

// Markers without a length: TEM, RST0-7, SOI.
bool standalone(int marker) { return marker == 0x01 || (marker >= 0xD0 && marker <= 0xD8); }

std::string hex(int marker) {
  const char* digits = "0123456789ABCDEF";
  return std::string("FF") + digits[(marker >> 4) & 15] + digits[marker & 15];
}

}  // namespace

bool jpeg_without_metadata(const std::string& path, std::vector<unsigned char>& stripped, std::string& error) {
  stripped.clear();
  std::ifstream in(path, std::ios::binary);
  // Not a JPEG (no SOI): libjpeg refuses it before it reads any segment.
  if (in.get() != 0xFF || in.get() != 0xD8) return true;
  in.seekg(0, std::ios::end);
  const std::uint64_t size = std::uint64_t(std::max<std::streamoff>(in.tellg(), 0));
  in.seekg(2);
  std::uint64_t at = 2;
  std::vector<std::pair<std::uint64_t, std::uint64_t>> drop;  // [begin, end) of each metadata segment
  const auto next = [&]() -> int {
    const int c = in.get();
    if (c != std::char_traits<char>::eof()) ++at;
    return c;
  };
  const auto ends_early = [&] {
    error = "truncated JPEG (it ends at byte " + std::to_string(at) + ", before its first scan)";
    return false;
  };
  for (;;) {
    const std::uint64_t start = at;
    const auto not_a_marker = [&] {
      error = "damaged JPEG (byte " + std::to_string(start) + " is not a marker, before the first scan)";
      return false;
    };
    int c = next();
    if (c == std::char_traits<char>::eof()) return ends_early();
    if (c != 0xFF) return not_a_marker();
    while ((c = next()) == 0xFF) {  // fill bytes
    }
    if (c == std::char_traits<char>::eof()) return ends_early();
    if (c == 0x00) return not_a_marker();  // FF 00 is a stuffed zero byte of scan data
    const int marker = c;
    if (marker == 0xDA || marker == 0xD9) break;  // the first scan (SOS), or EOI: no header segment follows
    if (standalone(marker)) continue;
    const int high = next(), low = next();
    if (low == std::char_traits<char>::eof() || high == std::char_traits<char>::eof()) {
      error = "truncated JPEG (the " + hex(marker) + " segment at byte " + std::to_string(start) + " has no length)";
      return false;
    }
    const std::uint64_t length = std::uint64_t(high) << 8 | std::uint64_t(low);  // including its own two bytes
    if (length < 2) {
      error = "damaged JPEG (the " + hex(marker) + " segment at byte " + std::to_string(start) + " declares " +
              std::to_string(length) + " bytes, less than its length field)";
      return false;
    }
    if (at - 2 + length > size) {
      error = "truncated JPEG (the " + hex(marker) + " segment at byte " + std::to_string(start) + " claims " +
              std::to_string(length) + " bytes after its marker, the file has " + std::to_string(size - (at - 2)) + ")";
      return false;
    }
    in.ignore(std::streamsize(length - 2));
    at += length - 2;
    if (metadata_only(marker)) drop.emplace_back(start, at);
  }
  if (drop.empty()) return true;
  in.clear();
  in.seekg(0);
  std::vector<unsigned char> bytes(size);
  if (!in.read(reinterpret_cast<char*>(bytes.data()), std::streamsize(size))) {
    error = "cannot read the file";
    return false;
  }
  stripped.reserve(size);
  std::uint64_t from = 0;
  for (const auto& [begin, end] : drop) {
    stripped.insert(stripped.end(), bytes.begin() + std::ptrdiff_t(from), bytes.begin() + std::ptrdiff_t(begin));
    from = end;
  }
  stripped.insert(stripped.end(), bytes.begin() + std::ptrdiff_t(from), bytes.end());
  return true;
}

}  // namespace qdmr::imageio
