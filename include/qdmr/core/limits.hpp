#pragma once
// Every hard limit of qdmr in one place.
#include <cstdint>

namespace qdmr::limits {

inline constexpr int kMaxImageSide = 16384;         // output width/height and texture side
inline constexpr std::uint64_t kMaxImagePixels = 1ull << 27;  // output width x height (16384 x 8192, ~8 GiB of buffers)
inline constexpr int kMaxTextureSide = 16384;
inline constexpr int kSubpixelBits = 8;             // fixed-point triangle setup
inline constexpr int kSubpixelScale = 1 << kSubpixelBits;
inline constexpr int kDefaultTileSize = 64;
inline constexpr int kMinTileSize = 8;              // tiles are whole 8x8 coarse blocks
inline constexpr int kMaxTileSize = 1024;
inline constexpr int kCoarseBlockSize = 8;
// Guard band in pixels beyond the viewport: vertices further out are clipped in x/y,
// which keeps fixed-point coordinates (with kSubpixelBits) within +-2^23 and edge functions in int64.
inline constexpr int kGuardBandPixels = 16384;
inline constexpr int kMaxLayers = 4;
inline constexpr int kMaxDirectionalLights = 4;
inline constexpr int kMaxThreads = 256;
// Frames of a scene's animation (/animation/frames): a day at 24 fps, and frame numbers fit printf's %d.
inline constexpr int kMaxAnimationFrames = 24 * 60 * 60 * 24;
inline constexpr std::uint64_t kMaxTriangles = 1ull << 28;

// Inputs (see docs/testing.md, "Bad input"): every file read is a regular file of at most this many bytes,
// checked before it is opened; image dimensions are checked from the header (kMaxTextureSide) before decoding.
inline constexpr std::uint64_t kMaxSceneFileBytes = 16ull << 20;  // JSON scenes are a few KiB
inline constexpr std::uint64_t kMaxObjFileBytes = 1ull << 30;     // ~30 M triangles of text
inline constexpr std::uint64_t kMaxMtlFileBytes = 16ull << 20;
// A .gltf or .glb file, and each external buffer (.bin) it names: tinygltf sizes buffers with 32-bit counts.
inline constexpr std::uint64_t kMaxGltfFileBytes = 1ull << 30;
inline constexpr std::uint64_t kMaxManifestFileBytes = 64ull << 20;  // check manifests: thousands of checks
inline constexpr std::uint64_t kMaxImageFileBytes = 4ull << 30;  // a 16384^2 RGBA float image, uncompressed
inline constexpr int kMaxJsonDepth = 64;                          // nesting of arrays/objects in scenes and --set

}  // namespace qdmr::limits
