#pragma once
// The per-ISA work of preparation, behind Kernel::blend_box_values, Kernel::mip_extremum, Kernel::height_rows and
// Kernel::bc3_encode.
#include <cstdint>

#include "core/isa_namespace.hpp"
#include "qdmr/texture/bc3.hpp"
#include "texture/blend_box_values.hpp"
#include "qdmr/texture/format.hpp"
#include "texture/height_rows.hpp"

namespace qdmr::QDMR_ISA_NAMESPACE {

// A blend's level-0 box values into `out` (blend_box_values_bytes() of the source), with the code its QDM walks run
// at a level-0 cell (kernel/blend_box_values.cpp).
void blend_box_values(const BlendBoxSource& source, float* out);

// A MipExtremum (qdmr/texture/mip_texture.hpp) on this kernel's vectors (kernel/mip_reduce.cpp).
void mip_extremum(bool max, TexelFormat format, const std::uint8_t* in, int in_w, int in_h, std::uint8_t* out,
                  int out_w, int out_h);

// The rows of a dynamic height's rebuild on this kernel's vectors (kernel/height_rows.cpp); counts a row table.
const HeightRows& height_rows();

// An encoder of BC3 alpha blocks as encode_bc3_alpha encodes them, on this kernel's vectors
// (kernel/bc3_encode.cpp); counts an encoder.
Bc3Encode bc3_encoder();

}  // namespace qdmr::QDMR_ISA_NAMESPACE
