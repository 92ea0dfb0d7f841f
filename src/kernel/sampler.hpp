#pragma once
// The SIMD sampler: a faithful emulation of a console-era texture unit over a typed mip Texture, for a batch
// of lanes (private: SIMD types of this build). Texel centres at (i + 0.5) / N; row 0 at v = 0.
// Every operation is lane-wise IEEE or integer, so SSE4.2 and AVX2 builds, and the gather and portable fetch
// paths, give the same bits.
#include <array>
#include <cstdint>

#include "core/det_math.hpp"
#include "kernel/gather.hpp"
#include "core/simd.hpp"
#include "qdmr/core/sampling.hpp"
#include "qdmr/program/program_key.hpp"
#include "qdmr/program/program_params.hpp"
#include "qdmr/texture/mip_texture.hpp"
#include "kernel/fetch_trace.hpp"

namespace qdmr::QDMR_ISA_NAMESPACE {

// A Texture with the per-level tables the sampler looks up per lane.
class TextureView {
public:
  static constexpr int kMaxLevels = 16;
  explicit TextureView(const Texture& texture);

  const Texture& texture() const { return *texture_; }
  int levels() const { return levels_; }
  const std::int32_t* widths() const { return width_.data(); }
  const std::int32_t* heights() const { return height_.data(); }
  const std::int32_t* offsets() const { return offset_.data(); }
  // Level-0 texel (0, 0), decoded: what lanes with non-finite coordinates return.
  const std::array<float, 4>& first_texel() const { return first_texel_; }
  // Both sides of level 0 are powers of two (then so are every level's): fp32 texel coordinates are exact.
  bool power_of_two() const { return power_of_two_; }

private:
  const Texture* texture_;
  int levels_;
  alignas(64) std::array<std::int32_t, kMaxLevels> width_{}, height_{}, offset_{};
  std::array<float, 4> first_texel_{};
  bool power_of_two_ = false;
};

struct SamplerState {
  Filter filter = Filter::Trilinear;
  AddressMode address = AddressMode::Wrap;
  SamplePrecision precision = SamplePrecision::Exact;
  MathMode math = MathMode::Sm4;  // texel addressing: the exact texel coordinate (sm4, exact) or the fp32 one (sm3)
  float lod_bias = 0.0f;
  float min_lod = 0.0f, max_lod = 16.0f;
  simd::FetchPath fetch = simd::kHasHardwareGather ? simd::FetchPath::Gather : simd::FetchPath::Portable;

  // A material's: its key's sampler modes and its parameters' numbers (the plan splits the scene's sampling so).
  static SamplerState from(const SamplerModes& modes, const SamplerParams& params) {
    SamplerState s;
    s.filter = modes.filter;
    s.address = modes.address;
    s.precision = modes.precision;
    s.math = modes.fp32_texels ? MathMode::Sm3 : MathMode::Sm4;
    s.lod_bias = params.lod_bias;
    s.min_lod = params.min_lod;
    s.max_lod = params.max_lod;
    return s;
  }
};

// What the sampling code branches on, from a texture and a sampler state; fixed per material, so a program binds
// it once (TextureSampler) and its inner loops run code specialised for it.
struct SamplerKey {
  Filter filter = Filter::Trilinear;
  AddressMode address = AddressMode::Wrap;
  int fraction_bits = 0;     // of texel coordinates, weights and LOD: 0 (exact floats), 8 or 6 (SamplePrecision)
  bool exact_texel = false;  // floor the exact texel coordinate, not the fp32 one (split() in sampler.cpp)
  TexelFormat format = TexelFormat::RGBA8;
  bool srgb = false;
  simd::FetchPath fetch = simd::FetchPath::Portable;
  constexpr bool operator==(const SamplerKey&) const = default;
};
SamplerKey sampler_key(const TextureView& texture, const SamplerState& state);

// The squared lengths of a pixel's footprint along x and y in level-0 texels: |d(uv*size)/dx|², |d(uv*size)/dy|².
inline void footprint_lengths2(const TextureView& view, const simd::Float& dudx, const simd::Float& dvdx,
                               const simd::Float& dudy, const simd::Float& dvdy, simd::Float& px, simd::Float& py) {
  const simd::Float w(float(view.texture().width())), h(float(view.texture().height()));
  const simd::Float ax = dudx * w, ay = dvdx * h, bx = dudy * w, by = dvdy * h;
  px = ax * ax + ay * ay;
  py = bx * bx + by * by;
}

// LOD in level-0 texels from UV derivatives, GL formula: log2(max(|d(uv*size)/dx|, |d(uv*size)/dy|)).
// A zero footprint gives -64; non-finite derivatives give the last level. Inline: every shading program's
// sample waits on it, and a call would also make the caller store its live vector registers around it.
inline simd::Float lod_from_derivatives(const TextureView& view, const simd::Float& dudx, const simd::Float& dvdx,
                                        const simd::Float& dudy, const simd::Float& dvdy) {
  using simd::Float;
  constexpr float kMinLod = -64.0f;  // LOD of a zero (or denormal) footprint
  Float px, py;
  footprint_lengths2(view, dudx, dvdx, dudy, dvdy, px, py);
  const Float rho2 = xsimd::select(px > py, px, py);
  const simd::Mask tiny = rho2 < Float(1.17549435e-38f);  // zero or denormal
  // 0.5 * log2(rho^2) = log2(rho): exact integers for power-of-two footprints.
  const Float lod = Float(0.5f) * detmath::log2(xsimd::select(tiny, Float(1.0f), rho2));
  const Float last(float(view.levels() - 1));
  const simd::Mask finite = ((px - px) == Float(0.0f)) & ((py - py) == Float(0.0f));  // x - x is 0 unless inf or NaN
  return xsimd::select(finite, xsimd::select(tiny, Float(kMinLod), lod), last);
}

// Samples every channel (1..4) at (u, v) with one LOD per lane (bias and clamps applied here; ignored by the
// level-0 filters point and bilinear); out[c] receives channel c. Lanes with non-finite u or v return
// level-0 texel (0, 0). The generic sampler: it branches on the options per call (TextureSampler does not).
void sample(const TextureView& texture, const SamplerState& state, const simd::Float& u, const simd::Float& v,
            const simd::Float& lod, simd::Float* out);

// Texel fetch without filtering (SM4 Load): level, x, y per lane, clamped into range.
void load(const TextureView& texture, const simd::Int& level, const simd::Int& x, const simd::Int& y,
          simd::FetchPath fetch, simd::Float* out);

using SampleFunction = void (*)(const TextureView&, const SamplerState&, const simd::Float& u, const simd::Float& v,
                                const simd::Float& lod, simd::Float* out);
using LoadFunction = void (*)(const TextureView&, const simd::Int& level, const simd::Int& x, const simd::Int& y,
                              simd::FetchPath fetch, simd::Float* out);

// The sampling code for a key: when no texture-cache recorder listens (recorded false), an instantiation without
// the recorder's tests where sampler.cpp lists the key as common (docs/architecture.md, "Specialised samplers"),
// the generic sampler otherwise; for a listening recorder (recorded true), the generic sampler, which reports
// every fetch. All give the same bits.
SampleFunction sample_function(const SamplerKey& key, bool recorded = true);
bool is_specialised(const SamplerKey& key);

// A texture bound to the sampler state a material fixes for it, with sampling and loading specialised for both:
// what shading programs hold, built once per program, so no per-pixel code tests a per-material option.
class TextureSampler {
public:
  TextureSampler(const Texture& texture, const SamplerState& state);

  const TextureView& view() const { return view_; }
  const Texture& texture() const { return view_.texture(); }
  const SamplerState& state() const { return state_; }
  bool specialised() const { return is_specialised(key()); }
  SamplerKey key() const { return sampler_key(view_, state_); }

  void sample(const simd::Float& u, const simd::Float& v, const simd::Float& lod, simd::Float* out) const {
    (fetch_recorder_listens() ? sample_ : sample_unrecorded_)(view_, state_, u, v, lod, out);
  }
  simd::Float lod(const simd::Float& dudx, const simd::Float& dvdx, const simd::Float& dudy, const simd::Float& dvdy) const {
    return lod_from_derivatives(view_, dudx, dvdx, dudy, dvdy);
  }
  // lod() depends on the level-0 size and the level count only: textures alike in both share one LOD.
  bool same_lod_as(const TextureSampler& other) const {
    return texture().width() == other.texture().width() && texture().height() == other.texture().height() &&
           view_.levels() == other.view_.levels();
  }
  // load() above, with this texture's format fixed.
  void load(const simd::Int& level, const simd::Int& x, const simd::Int& y, simd::Float* out) const {
    load_(view_, level, x, y, state_.fetch, out);
  }
  // load() of cell (x, y) of `level` with the indices wrapped into the level (power-of-two sizes only).
  void load_wrapped(const simd::Int& level, const simd::Int& x, const simd::Int& y, simd::Float* out) const {
    load_wrapped_(view_, level, x, y, state_.fetch, out);
  }
private:
  TextureView view_;
  SamplerState state_;
  SampleFunction sample_, sample_unrecorded_;
  LoadFunction load_, load_wrapped_;
};

// Where the rasterizer samples next near a sample: each lane's UV offset to the same lane of the quad below
// (2 pixel rows down, twice the UV's derivative along y), whose batch comes a few batches later. A sample given
// one prefetches the texels there on its finest level, so that the quad below finds them in cache instead of
// waiting on memory. A hint only: no result depends on it.
struct UvAhead {
  simd::Float du, dv;
};

using TwinSampleFunction = void (*)(const TextureView& a, const TextureView& b, const float* interleaved,
                                    const SamplerState&, const simd::Float& u, const simd::Float& v,
                                    const simd::Float& lod, const UvAhead* ahead, simd::Float* out_a,
                                    simd::Float* out_b);

// Two textures a program samples at the same coordinates under one sampler state, such as its albedo and its
// normal map. Where both are RGBA8 chains of one size and the key is a common one, a texel sits at the same offset
// in both, so one address computation and one offset per lane serve both textures (sample_twin_with in
// sampling_code.hpp), and with the two interleaved (twin_texels.hpp) one load per tap; otherwise, and while a
// texture-cache recorder listens, two samples. The same bits either way.
class TwinSampler {
public:
  // interleaved: interleave_twin_texels(first, second), or null.
  TwinSampler(const Texture& first, const Texture& second, const SamplerState& state,
              const float* interleaved = nullptr);

  const TextureSampler& first() const { return first_; }
  const TextureSampler& second() const { return second_; }
  bool shares_addresses() const { return twin_ != nullptr; }
  // Both textures at (u, v), each with its LOD (equal wherever the two share addresses: one size, same_lod_as):
  // each one's rgb; both alphas are 1, not sampled (an albedo's alpha and a normal map's, which nothing reads: the
  // shared path skips their filters, and the interleaved texels hold no albedo alpha). ahead, if given, where the
  // quad below will sample (a prefetch hint where the two share addresses).
  void sample(const simd::Float& u, const simd::Float& v, const simd::Float& first_lod, const simd::Float& second_lod,
              simd::Float* first_out, simd::Float* second_out, const UvAhead* ahead = nullptr) const {
    if (twin_ != nullptr && !fetch_recorder_listens()) {
      twin_(first_.view(), second_.view(), interleaved_, first_.state(), u, v, first_lod, ahead, first_out,
            second_out);
      return;
    }
    first_.sample(u, v, first_lod, first_out);
    second_.sample(u, v, second_lod, second_out);
    first_out[3] = second_out[3] = simd::Float(1.0f);
  }

private:
  TextureSampler first_, second_;
  TwinSampleFunction twin_;
  const float* interleaved_;
};

}  // namespace qdmr::QDMR_ISA_NAMESPACE
