#pragma once
// Shared by the sampler tests: every setting to sweep, lanes as arrays, and float bits for exact comparisons.
#include <array>
#include <cstdint>
#include <cstring>
#include <limits>

#include "kernel/sampler.hpp"
#include "plan/program_choice.hpp"

namespace qdmr::test {

using Lanes = std::array<float, simd::kLanes>;

inline constexpr float kNaN = std::numeric_limits<float>::quiet_NaN();
inline constexpr float kInf = std::numeric_limits<float>::infinity();

inline constexpr Filter kFilters[] = {Filter::Point,         Filter::Bilinear,       Filter::Trilinear,
                                      Filter::PointMipPoint, Filter::PointMipLinear, Filter::LinearMipPoint};
inline constexpr AddressMode kAddressModes[] = {AddressMode::Wrap, AddressMode::Clamp, AddressMode::Mirror};
inline constexpr SamplePrecision kPrecisions[] = {SamplePrecision::Exact, SamplePrecision::Hw8, SamplePrecision::Hw6};
inline constexpr MathMode kMathModes[] = {MathMode::Sm4, MathMode::Sm3, MathMode::Exact};

// The sampler state of a material's sampling, split into key and parameters as the plan splits it.
inline SamplerState sampler_state(const SamplingDesc& d) {
  return SamplerState::from(sampler_modes(d, HeightFetch::Bilinear), sampler_params(d));
}

inline std::uint32_t bits(float f) {
  std::uint32_t b;
  std::memcpy(&b, &f, 4);
  return b;
}

}  // namespace qdmr::test
