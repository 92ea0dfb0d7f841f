#pragma once
// The vocabulary of texture sampling, shared by the scene description (what a material asks for), the sampler
// emulation that honours it and the fp64 reference: filters, address modes, filter-weight precision, how LOD is
// taken, and the shader math of texel and cell addressing.
namespace qdmr {

// Texture filters, named as in OpenGL/D3D: texel filter (point = nearest, linear = bilinear) and mip filter
// (none = level 0 only, point = nearest level, linear = between the two nearest levels).
enum class Filter {
  Point,           // nearest texel of level 0 (GL_NEAREST)
  Bilinear,        // bilinear on level 0 (GL_LINEAR)
  Trilinear,       // bilinear on two levels, blended (GL_LINEAR_MIPMAP_LINEAR)
  PointMipPoint,   // nearest texel of the nearest level (GL_NEAREST_MIPMAP_NEAREST; tex2Dlod with point sampling)
  PointMipLinear,  // nearest texel on two levels, blended (GL_NEAREST_MIPMAP_LINEAR)
  LinearMipPoint   // bilinear on the nearest level (GL_LINEAR_MIPMAP_NEAREST)
};
enum class AddressMode { Wrap, Clamp, Mirror };
// Filter weights and LOD fraction: exact floats, or quantised to 8 (D3D11 class) or 6 (D3D10 class) bits.
enum class SamplePrecision { Exact, Hw8, Hw6 };
// LOD from the derivatives of the 2x2 quad (what hardware does) or of each pixel's own row/column.
enum class LodMode { PerQuad, PerPixel };
// Shader arithmetic of texel addresses (the sampler) and of QDM's cell walk: exact addresses and integer cells
// (SM4); fp32 addresses and cells found from fp32 positions (SM3); as SM4 with QDM's wall crossings in fp64.
enum class MathMode { Sm4, Sm3, Exact };

// What a material asks of its texture sampling; the kernels' samplers run it (kernel/sampler.hpp).
struct SamplingDesc {
  Filter filter = Filter::Trilinear;
  AddressMode address = AddressMode::Wrap;
  SamplePrecision precision = SamplePrecision::Exact;
  LodMode lod = LodMode::PerQuad;
  float lod_bias = 0.0f;
  float min_lod = 0.0f;    // LOD clamp, in levels
  float max_lod = 16.0f;
  MathMode math = MathMode::Sm4;
};

}  // namespace qdmr
