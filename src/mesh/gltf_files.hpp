#pragma once
// Private to the mesh module: what a glTF asset may read besides itself, checked before tinygltf sees it.
// URIs stay inside the asset's folder (no scheme, no absolute path, no `..`, after percent-decoding), and a .glb
// container's chunk lengths add up to its length. See docs/scene-format.md, "glTF 2.0 assets".
#include <cstdint>
#include <filesystem>
#include <functional>
#include <optional>
#include <string>
#include <string_view>

namespace qdmr::mesh_detail {

// The path a glTF `uri` names, relative to the asset's folder, or nullopt for a `data:` URI. Throws
// qdmr::Error(where, ...) for a URI that names another scheme, an absolute path or a parent folder (`..`), is
// empty, or holds a NUL, a backslash or a bad percent escape.
std::optional<std::filesystem::path> relative_uri(std::string_view uri, const std::string& where);

// Where a .glb container keeps its JSON and its BIN chunk (bytes from the file's start).
struct GlbChunks {
  std::uint64_t json_offset = 0, json_length = 0;
  bool has_bin = false;
  std::uint64_t bin_offset = 0, bin_length = 0;
};

// Checks a .glb container of `size` bytes (magic, version 2, the header's length equal to the file's, a JSON chunk
// first, a BIN chunk second if any, every chunk inside the file and a multiple of 4 bytes long), reading only its
// headers: read(at, n) returns the n bytes at `at`. Throws qdmr::Error(where, ...) naming the field that lies.
GlbChunks glb_chunks(std::uint64_t size, const std::function<std::string(std::uint64_t at, std::size_t n)>& read,
                     const std::string& where);

// True when `bytes` start like a .glb container (its magic "glTF"), else it is read as JSON text.
bool looks_like_glb(std::string_view bytes);

}  // namespace qdmr::mesh_detail
