#pragma once
// BC3 (DXT5) alpha block compression of an 8-bit height channel. The decoded texels are what gets sampled
// and what the max quadtree is built from, so the hierarchy stays conservative for the compressed surface.
// Decoding rounds interpolated values to nearest, as the D3D reference decoder does (docs/sampling.md).
#include <array>
#include <cstddef>
#include <cstdint>

namespace qdmr {

// One 8-byte BC3 alpha block: a0, a1, then 16 3-bit indices, little-endian, texel i = (x + 4y) at bits 16+3i.
// a0 > a1: 8 values (a0, a1 and 6 interpolated); a0 <= a1: 6 values (a0, a1, 4 interpolated) plus 0 and 255.
using Bc3AlphaBlock = std::array<std::uint8_t, 8>;

// Best of both modes (least squared error; ties: 8-value mode). Deterministic. This is the definition, one candidate
// at a time; each draw kernel has an encoder that gives the same blocks (Kernel::bc3_encode).
Bc3AlphaBlock encode_bc3_alpha(const std::uint8_t texels[16]);
using Bc3Encode = Bc3AlphaBlock (*)(const std::uint8_t texels[16]);
void decode_bc3_alpha(const Bc3AlphaBlock& block, std::uint8_t texels[16]);

struct Bc3Report {
  double max_error = 0, rms_error = 0;  // in 8-bit steps, over the texels that exist
  std::size_t blocks = 0;
};

// Compresses a w x h 8-bit channel (row-major, stride w bytes) block by block and replaces it with the decoded
// values. Partial edge blocks (w or h not multiples of 4) replicate edge texels for encoding and decode only the
// texels that exist. Runs over block rows in parallel; the result does not depend on the thread count. `encode`:
// a kernel's encoder (Kernel::bc3_encode), or nullptr for encode_bc3_alpha; the same blocks either way.
Bc3Report bc3_roundtrip(std::uint8_t* texels, int width, int height, Bc3Encode encode = nullptr);

}  // namespace qdmr
