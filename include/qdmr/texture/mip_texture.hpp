#pragma once
// Texture: a typed mip chain in one contiguous block (so a SIMD gather can address any level with 32-bit
// byte offsets), built from a float level 0 with a reduction chosen by purpose:
//   Box        colour and data: 2x2 average (in linear light for sRGB), re-quantised per level
//   BoxNormal  normals stored as 0.5 + 0.5 n: averaged, renormalised, re-quantised
//   Max / Min  heights: each texel of level k+1 is the max (min) of the level-k texels it covers — the
//              quadtree of QDM (max height = min depth); exact in the stored integers, so conservative.
// Level k+1 has max(1, floor(n/2)) texels per axis; on an odd axis the last texel also covers the leftover
// row/column (3 taps), so every texel of level k is covered by exactly one parent and Max/Min stay conservative.
#include <cstddef>
#include <cstdint>
#include <vector>

#include "qdmr/texture/format.hpp"
#include "qdmr/texture/image.hpp"

namespace qdmr {

enum class MipReduce : std::uint8_t { Box, BoxNormal, Max, Min };

struct TextureLevel {
  int width = 0, height = 0;
  std::size_t offset = 0;  // byte offset of texel (0, 0) in Texture::storage
};

class Texture {
public:
  // Gathers read 4 bytes at any texel address: storage keeps this many bytes of zero padding at the end.
  static constexpr std::size_t kTailPadding = 4;

  TexelFormat format = TexelFormat::R8;
  bool srgb = false;  // RGBA8/RG8/R8 colour: the rgb channels are sRGB-encoded
  std::vector<TextureLevel> levels;
  std::vector<std::uint8_t> storage;
  // The decoded copy, where add_linear_copy kept one: every texel decoded as texel() decodes it, one float per
  // channel, float i * channels + c for channel c of texel i of `storage`. RGBA8 sRGB (rgb through the sRGB
  // table, alpha / 255: the sampler reads whole texels instead of looking each channel up in a table) and the
  // one-channel height formats R16 and R8 (code / 65535 or / 255: a height fetch, on the critical path of every
  // tracing step, skips the division). The same bits, fewer instructions per fetch.
  std::vector<float> linear;
  // Level 0's bilinear footprints under wrap addressing, where add_wrap_footprints kept them: for texel (x, y) the
  // decoded texels (x, y), (x + 1, y), (x, y + 1) and (x + 1, y + 1), the neighbours' indices wrapped, as floats
  // 4 (y * width + x) to 4 (y * width + x) + 3. A bilinear height fetch with wrap addressing loads a lane's
  // whole footprint with one 16-byte load, where two texel pairs (one per row) cost twice the loads and address
  // extractions. The same floats as `linear`, so the same bits.
  std::vector<float> wrap_footprints;

  int width() const { return levels.empty() ? 0 : levels[0].width; }
  int height() const { return levels.empty() ? 0 : levels[0].height; }
  int level_count() const { return int(levels.size()); }
  int channels() const { return channel_count(format); }
  std::size_t bytes() const { return storage.size() + (linear.size() + wrap_footprints.size()) * sizeof(float); }

  const std::uint8_t* texel_address(int level, int x, int y) const {
    const TextureLevel& l = levels[std::size_t(level)];
    return storage.data() + l.offset + (std::size_t(y) * std::size_t(l.width) + std::size_t(x)) * bytes_per_texel(format);
  }
  // Channel c of a texel as a float (UNORM normalised, sRGB decoded for rgb). Scalar; for tests and tools.
  float texel(int level, int x, int y, int c) const;
  // A level as a float image (decoded like texel()).
  Image level_image(int level) const;
};

// The storage bytes of the chain allocate_texture makes (for memory plans).
std::uint64_t mip_chain_bytes(int width, int height, TexelFormat format);

// The bytes of Texture::linear that add_linear_copy keeps for such a chain: 4 bytes per channel of every texel
// (4x the storage for RGBA8 sRGB colour and R8 heights, 2x for R16 heights) for copies of up to kLinearCopyMaxBytes,
// else 0 (larger chains are decoded per fetch: the memory is too dear there).
inline constexpr std::uint64_t kLinearCopyMaxBytes = std::uint64_t(256) << 20;
std::uint64_t linear_copy_bytes(int width, int height, TexelFormat format, bool srgb);

// Fills Texture::linear from the finished chain when linear_copy_bytes says so; call it after the last change to
// the storage.
void add_linear_copy(Texture& texture);

// The bytes of Texture::wrap_footprints that add_wrap_footprints keeps for such a chain: 16 per level-0 texel of a
// one-channel chain with a decoded copy (the heights: R16, R8), for footprints of up to kWrapFootprintsMaxBytes
// (a 2048² map), else 0 (larger maps are fetched a texel pair per row).
inline constexpr std::uint64_t kWrapFootprintsMaxBytes = std::uint64_t(64) << 20;
std::uint64_t wrap_footprint_bytes(int width, int height, TexelFormat format, bool srgb);

// Fills Texture::wrap_footprints from the decoded copy when wrap_footprint_bytes says so; call it after
// add_linear_copy.
void add_wrap_footprints(Texture& texture);

// Allocates the chain for a w x h level 0 (all levels, zeroed, with the tail padding).
Texture allocate_texture(int width, int height, TexelFormat format, bool srgb);

// The max (or min) of each output texel's taps, level `in` (in_w x in_h) to level `out`: MipReduce::Max / Min.
// Exact in the stored values, so every reducer gives the same bits; a draw kernel's runs on its vectors
// (Kernel::mip_extremum, which preparation passes so that `--isa` holds there too).
using MipExtremum = void (*)(bool max, TexelFormat format, const std::uint8_t* in, int in_w, int in_h,
                             std::uint8_t* out, int out_w, int out_h);

// Quantises level 0 (values in [0,1]; normals as 0.5 + 0.5 n already) into `format` and builds the chain.
// Channels beyond the image's are filled with 0 (alpha with 1). Rounds to nearest; clamps to [0,1]. Max and Min
// run `extremum`; null: the portable reducer (scalar, baseline x86-64).
Texture make_mip_texture(const Image& level0, TexelFormat format, bool srgb, MipReduce reduce,
                         MipExtremum extremum = nullptr);

// Rebuilds levels 1.. from level 0 with the given reduction (level 0 already filled in storage).
void build_mip_levels(Texture& texture, MipReduce reduce, MipExtremum extremum = nullptr);

}  // namespace qdmr
