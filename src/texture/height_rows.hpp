#pragma once
// The row operations of a dynamic height's rebuild (texture/height_family.hpp): each gives, texel for texel, the
// bits of the generic builders it stands for (make_mip_texture's quantisation and Box / BoxNormal reductions,
// add_linear_copy, add_wrap_footprints, from_height normals, the waves pattern). A kernel's run on its vectors
// (Kernel::height_rows); the baseline's are the same code compiled for x86-64.
#include <cstdint>

#include "qdmr/texture/format.hpp"

namespace qdmr {

struct HeightRows {
  // row[x] += weight * (0.5 + 0.5 (su[x] cv + cu[x] sv))^sharpness (1..8), in float: one wave of a waves row.
  void (*add_wave)(int sharpness, float* row, int n, const float* su, const float* cu, float sv, float cv,
                   float weight);
  // h = clamp(clamp(row, 0, 1) * scale + offset, 0, 1): a waves row as the layer stores it (in place).
  void (*finish_waves)(float* row, int n, float scale, float offset);
  // Heights in [0, 1] to codes of `format` (R8 or R16) and the codes decoded (Texture::linear's floats).
  void (*quantise)(TexelFormat format, const float* h, int n, std::uint8_t* codes, float* decoded);
  // Codes of `format` (R8 or R16) decoded.
  void (*decode)(TexelFormat format, const std::uint8_t* codes, int n, float* decoded);
  // One output row of a Box level of `format` (R8 or R16) from the decoded rows of the level below it: `rows`
  // (1, 2 or 3) input rows of in_w texels, out_w output texels; codes and their decoded floats out.
  void (*box)(TexelFormat format, const float* const* in, int rows, int in_w, int out_w, std::uint8_t* codes,
              float* decoded);
  // Level-0 normals (RGBA8 codes) of row y from the decoded heights of rows y - 1, y and y + 1 (wrapped), w wide:
  // central differences scaled by kx and ky, normalised, stored as 0.5 + 0.5 n.
  void (*normals)(const float* up, const float* row, const float* down, int w, double kx, double ky,
                  std::uint8_t* rgba);
  // One output row of a BoxNormal level (RGBA8) from `rows` (1, 2 or 3) input rows of in_w texels.
  void (*box_normals)(const std::uint8_t* const* in, int rows, int in_w, int out_w, std::uint8_t* rgba);
  // Level 0's wrap footprints of one row (Texture::wrap_footprints): row and the row below it, decoded.
  void (*footprints)(const float* row, const float* below, int w, float* out);
};

}  // namespace qdmr
