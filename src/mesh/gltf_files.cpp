#include "mesh/gltf_files.hpp"

#include <cstring>

#include "qdmr/core/error.hpp"

namespace qdmr::mesh_detail {

namespace {

std::uint32_t le32(std::string_view bytes, std::size_t at) {
  std::uint32_t v = 0;
  for (int k = 3; k >= 0; --k) v = (v << 8) | static_cast<unsigned char>(bytes[at + std::size_t(k)]);
  return v;
}

int hex_digit(char c) {
  if (c >= '0' && c <= '9') return c - '0';
  if (c >= 'a' && c <= 'f') return c - 'a' + 10;
  if (c >= 'A' && c <= 'F') return c - 'A' + 10;
  return -1;
}

constexpr std::uint32_t kChunkJson = 0x4E4F534A, kChunkBin = 0x004E4942;

}  // namespace

std::optional<std::filesystem::path> relative_uri(std::string_view uri, const std::string& where) {
  if (uri.starts_with("data:")) return std::nullopt;
  const auto fail = [&](const std::string& what) {
    throw Error(where, "the URI '" + std::string(uri.substr(0, 80)) + (uri.size() > 80 ? "..." : "") + "' " + what);
  };
  // A scheme is letters, digits, '+', '-', '.' before the first ':' (RFC 3986); a file name may hold none.
  const std::size_t colon = uri.find(':');
  if (colon != std::string_view::npos && uri.find('/') > colon) fail("names a scheme (only relative paths and data: URIs are read)");
  std::string decoded;
  for (std::size_t i = 0; i < uri.size(); ++i) {
    if (uri[i] != '%') {
      decoded += uri[i];
      continue;
    }
    const int hi = i + 2 < uri.size() ? hex_digit(uri[i + 1]) : -1, lo = i + 2 < uri.size() ? hex_digit(uri[i + 2]) : -1;
    if (hi < 0 || lo < 0) fail("has a '%' not followed by two hex digits");
    decoded += char(hi * 16 + lo);
    i += 2;
  }
  if (decoded.empty()) fail("is empty");
  if (decoded.find('\0') != std::string::npos) fail("holds a NUL character");
  if (decoded.find('\\') != std::string::npos) fail("holds a backslash (URIs separate folders with '/')");
  if (decoded.front() == '/') fail("is an absolute path (files are read from the asset's folder only)");
  if (decoded.find(':') != std::string::npos) fail("names a scheme (only relative paths and data: URIs are read)");
  const std::filesystem::path path(decoded);
  for (const auto& part : path)
    if (part == "..") fail("leaves the asset's folder ('..')");
  return path;
}

bool looks_like_glb(std::string_view bytes) { return bytes.size() >= 4 && bytes.substr(0, 4) == "glTF"; }

GlbChunks glb_chunks(std::uint64_t size, const std::function<std::string(std::uint64_t, std::size_t)>& read,
                     const std::string& where) {
  if (size < 20) throw Error(where, "a .glb file needs a 12-byte header and a chunk; it has " + std::to_string(size) + " bytes");
  const std::string header = read(0, 12);
  if (!looks_like_glb(header)) throw Error(where, "not a .glb file (its first bytes are not 'glTF')");
  if (const std::uint32_t version = le32(header, 4); version != 2)
    throw Error(where, ".glb header: version " + std::to_string(version) + " (qdmr reads glTF 2)");
  if (const std::uint32_t length = le32(header, 8); length != size)
    throw Error(where, ".glb header: length " + std::to_string(length) + " but the file has " + std::to_string(size) + " bytes");
  GlbChunks chunks;
  std::uint64_t at = 12;
  for (int chunk = 0; at < size; ++chunk) {
    const std::string name = ".glb chunk " + std::to_string(chunk);
    if (size - at < 8) throw Error(where, name + ": a chunk header needs 8 bytes, " + std::to_string(size - at) + " are left");
    const std::string chunk_header = read(at, 8);
    const std::uint64_t length = le32(chunk_header, 0), type = le32(chunk_header, 4);
    if (length > size - at - 8)
      throw Error(where, name + ": length " + std::to_string(length) + " runs past the end of the file (" +
                             std::to_string(size - at - 8) + " bytes are left)");
    if (length % 4 != 0) throw Error(where, name + ": length " + std::to_string(length) + " is not a multiple of 4");
    if (chunk == 0 && type != kChunkJson) throw Error(where, name + ": the first chunk must be JSON");
    if (chunk == 1 && type != kChunkBin) throw Error(where, name + ": the second chunk must be BIN");
    if (chunk == 0) chunks.json_offset = at + 8, chunks.json_length = length;
    if (chunk == 1) chunks.has_bin = true, chunks.bin_offset = at + 8, chunks.bin_length = length;
    at += 8 + length;
  }
  return chunks;
}

}  // namespace qdmr::mesh_detail
