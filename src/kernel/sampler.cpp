// The SIMD sampler: its instantiations for the common keys, the generic entry points and TextureSampler
// (the code itself is in sampling_code.hpp).
#include "kernel/sampler.hpp"

#include <algorithm>
#include <iterator>
#include <utility>

#include "core/det_math.hpp"
#include "qdmr/core/error.hpp"
#include "kernel/sampling_code.hpp"

namespace qdmr::QDMR_ISA_NAMESPACE {
namespace {

using simd::FetchPath;
using simd::Float;
using simd::Int;
using simd::kLanes;
using simd::Mask;
using namespace sampling_code;

int fraction_bits(SamplePrecision p) { return p == SamplePrecision::Hw8 ? 8 : p == SamplePrecision::Hw6 ? 6 : 0; }

// For when no texture-cache recorder listens (without its tests, the compiler need not keep the fetches' vector
// values in memory around the calls they guard).
template <SamplerKey K>
void sample_fixed(const TextureView& view, const SamplerState& s, const Float& u, const Float& v, const Float& lod,
                  Float* out) {
  sample_with(K, view, s, u, v, lod, out, false);
}

template <SamplerKey K, bool Wrap>
void load_fixed(const TextureView& view, const Int& level, const Int& x, const Int& y, FetchPath, Float* out) {
  load_with(K, Wrap, view, level, x, y, out);
}

// The common keys, instantiated: the filters programs use for colour and height (point, bilinear, trilinear) with
// wrap addressing, exact or 8-bit weights, either texel-coordinate rounding, the formats textures and height maps
// come in, and this build's default fetch path. Everything else (clamp, mirror, 6-bit weights, the mip-point
// filters, fp32 heights, the portable fetch path on a gather build) runs the generic sampler.
constexpr Filter kCommonFilters[] = {Filter::Point, Filter::Bilinear, Filter::Trilinear};
constexpr int kCommonBits[] = {0, 8};
constexpr std::pair<TexelFormat, bool> kCommonFormats[] = {
    {TexelFormat::R8, false}, {TexelFormat::RG8, false}, {TexelFormat::RGBA8, false}, {TexelFormat::RGBA8, true},
    {TexelFormat::R16, false}};
constexpr FetchPath kDefaultFetch = simd::kHasHardwareGather ? FetchPath::Gather : FetchPath::Portable;
constexpr std::size_t kFormatCount = std::size(kCommonFormats);
constexpr std::size_t kCommonKeys = std::size(kCommonFilters) * std::size(kCommonBits) * 2 * kFormatCount;

// Key i of formats x texel rounding (exact_texel) x fraction bits x filters, with wrap addressing and this build's
// default fetch path.
template <std::size_t F, std::size_t L>
constexpr SamplerKey enumerated_key(std::size_t i, const std::pair<TexelFormat, bool> (&formats)[F],
                                    const Filter (&filters)[L]) {
  SamplerKey k;
  k.format = formats[i % F].first;
  k.srgb = formats[i % F].second;
  i /= F;
  k.exact_texel = i % 2 == 1;
  i /= 2;
  k.fraction_bits = kCommonBits[i % std::size(kCommonBits)];
  i /= std::size(kCommonBits);
  k.filter = filters[i];
  k.address = AddressMode::Wrap;
  k.fetch = kDefaultFetch;
  return k;
}

constexpr SamplerKey common_key(std::size_t i) { return enumerated_key(i, kCommonFormats, kCommonFilters); }

// Twin samples (TwinSampler): the common keys' linear filters for an RGBA8 first texture, sRGB or not, and an
// RGBA8 second one that is not (a normal map).
constexpr Filter kTwinFilters[] = {Filter::Bilinear, Filter::Trilinear};
constexpr std::pair<TexelFormat, bool> kTwinFirstFormats[] = {{TexelFormat::RGBA8, false}, {TexelFormat::RGBA8, true}};
constexpr std::size_t kTwinKeys = std::size(kTwinFilters) * std::size(kCommonBits) * 2 * std::size(kTwinFirstFormats);

constexpr SamplerKey twin_first_key(std::size_t i) { return enumerated_key(i, kTwinFirstFormats, kTwinFilters); }

constexpr SamplerKey twin_second_key(std::size_t i) {
  SamplerKey k = twin_first_key(i);
  k.srgb = false;
  return k;
}

template <SamplerKey KA, SamplerKey KB>
void sample_twin_fixed(const TextureView& a, const TextureView& b, const float* interleaved, const SamplerState& s,
                       const Float& u, const Float& v, const Float& lod, const UvAhead* ahead, Float* out_a,
                       Float* out_b) {
  sample_twin_with(KA, KB, a, b, interleaved, s, u, v, lod, ahead, out_a, out_b);
}

struct TwinEntry {
  SamplerKey first, second;
  TwinSampleFunction sample;
};

template <std::size_t... I>
constexpr std::array<TwinEntry, sizeof...(I)> twin_samplers(std::index_sequence<I...>) {
  return {{{twin_first_key(I), twin_second_key(I), &sample_twin_fixed<twin_first_key(I), twin_second_key(I)>}...}};
}
constexpr std::array<TwinEntry, kTwinKeys> kTwinSamplers = twin_samplers(std::make_index_sequence<kTwinKeys>());

// Both chains laid out alike: the same level count, and per level the same size and byte offset.
bool same_layout(const TextureView& a, const TextureView& b) {
  return a.levels() == b.levels() && std::equal(a.widths(), a.widths() + TextureView::kMaxLevels, b.widths()) &&
         std::equal(a.heights(), a.heights() + TextureView::kMaxLevels, b.heights()) &&
         std::equal(a.offsets(), a.offsets() + TextureView::kMaxLevels, b.offsets());
}

TwinSampleFunction twin_sample_function(const TextureSampler& a, const TextureSampler& b) {
  const SamplerKey ka = a.key(), kb = b.key();
  if (!twin_keys(ka, kb) || !same_layout(a.view(), b.view())) return nullptr;
  for (const TwinEntry& e : kTwinSamplers)
    if (e.first == ka && e.second == kb) return e.sample;
  return nullptr;
}

struct SampleEntry {
  SamplerKey key;
  SampleFunction sample;
};

template <std::size_t... I>
constexpr std::array<SampleEntry, sizeof...(I)> common_samplers(std::index_sequence<I...>) {
  return {{{common_key(I), &sample_fixed<common_key(I)>}...}};
}
constexpr std::array<SampleEntry, kCommonKeys> kCommonSamplers = common_samplers(std::make_index_sequence<kCommonKeys>());

// Loads depend on the format and the fetch path only.
constexpr SamplerKey load_key(TexelFormat format, bool srgb, FetchPath fetch = kDefaultFetch) {
  SamplerKey k;
  k.format = format;
  k.srgb = srgb;
  k.fetch = fetch;
  return k;
}

void load_generic_wrapped(const TextureView& view, const Int& level, const Int& x, const Int& y, FetchPath path,
                          Float* out) {
  load_with(load_key(view.texture().format, view.texture().srgb, path), true, view, level, x, y, out);
}

struct LoadEntry {
  SamplerKey key;
  LoadFunction clamped, wrapped;
};

template <std::size_t... I>
constexpr std::array<LoadEntry, sizeof...(I) + 1> format_loaders(std::index_sequence<I...>) {
  return {{{load_key(kCommonFormats[I].first, kCommonFormats[I].second),
            &load_fixed<load_key(kCommonFormats[I].first, kCommonFormats[I].second), false>,
            &load_fixed<load_key(kCommonFormats[I].first, kCommonFormats[I].second), true>}...,
           {load_key(TexelFormat::R32F, false), &load_fixed<load_key(TexelFormat::R32F, false), false>,
            &load_fixed<load_key(TexelFormat::R32F, false), true>}}};
}
constexpr auto kLoaders = format_loaders(std::make_index_sequence<kFormatCount>());

const LoadEntry* loader_for(const TextureView& view, FetchPath path) {
  if (path != kDefaultFetch) return nullptr;
  for (const LoadEntry& e : kLoaders)
    if (e.key.format == view.texture().format && e.key.srgb == view.texture().srgb) return &e;
  return nullptr;
}

}  // namespace

TextureView::TextureView(const Texture& texture) : texture_(&texture), levels_(texture.level_count()) {
  if (levels_ < 1 || levels_ > kMaxLevels) throw Error("texture", "expected 1 to 16 mip levels");
  for (int i = 0; i < kMaxLevels; ++i) {
    const TextureLevel& l = texture.levels[std::size_t(std::min(i, levels_ - 1))];
    width_[std::size_t(i)] = l.width;
    height_[std::size_t(i)] = l.height;
    offset_[std::size_t(i)] = std::int32_t(l.offset);
  }
  for (int c = 0; c < texture.channels(); ++c) first_texel_[std::size_t(c)] = texture.texel(0, 0, 0, c);
  const auto pow2 = [](int n) { return n > 0 && (n & (n - 1)) == 0; };
  power_of_two_ = pow2(texture.width()) && pow2(texture.height());
}

SamplerKey sampler_key(const TextureView& view, const SamplerState& s) {
  SamplerKey k;
  k.filter = s.filter;
  k.address = s.address;
  k.fraction_bits = fraction_bits(s.precision);
  // Power-of-two sizes make fl(u * n) exact and fp32 floors right without fixed point: every mode agrees there.
  k.exact_texel = s.math != MathMode::Sm3 && (k.fraction_bits > 0 || !view.power_of_two());
  k.format = view.texture().format;
  k.srgb = view.texture().srgb;
  k.fetch = s.fetch;
  return k;
}

void sample(const TextureView& view, const SamplerState& s, const Float& u, const Float& v, const Float& lod,
            Float* out) {
  sample_with(sampler_key(view, s), view, s, u, v, lod, out);
}

void load(const TextureView& view, const Int& level, const Int& x, const Int& y, FetchPath path, Float* out) {
  load_with(load_key(view.texture().format, view.texture().srgb, path), false, view, level, x, y, out);
}

SampleFunction sample_function(const SamplerKey& key, bool recorded) {
  // Recording makes a frame 15-30 times slower (docs/architecture.md, "The texture cache"), so a listening
  // recorder takes the generic sampler: instantiations with the recorder's tests would gain nothing measurable
  // and cost about a third of this file's compile time.
  if (recorded) return &sample;
  for (const SampleEntry& e : kCommonSamplers)
    if (e.key == key) return e.sample;
  return &sample;
}

bool is_specialised(const SamplerKey& key) { return sample_function(key, false) != &sample; }

TextureSampler::TextureSampler(const Texture& texture, const SamplerState& state)
    : view_(texture), state_(state), sample_(sample_function(sampler_key(view_, state_))),
      sample_unrecorded_(sample_function(sampler_key(view_, state_), false)) {
  const LoadEntry* e = loader_for(view_, state_.fetch);
  load_ = e ? e->clamped : static_cast<LoadFunction>(&qdmr::QDMR_ISA::load);
  load_wrapped_ = e ? e->wrapped : &load_generic_wrapped;
}

TwinSampler::TwinSampler(const Texture& first, const Texture& second, const SamplerState& state,
                         const float* interleaved)
    : first_(first, state), second_(second, state), twin_(twin_sample_function(first_, second_)),
      interleaved_(first.srgb && !first.linear.empty() ? interleaved : nullptr) {}

}  // namespace qdmr::QDMR_ISA_NAMESPACE
