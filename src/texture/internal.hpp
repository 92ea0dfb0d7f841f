#pragma once
// Texture module internals shared between its .cpp files and tests.
#include <vector>

#include "qdmr/scene/scene.hpp"
#include "qdmr/texture/image.hpp"
#include "texture/srgb_decode.hpp"

namespace qdmr::texture_detail {

// The pattern of `desc`: channel 0 the height in [0,1]; with_cells adds channel 1, for patterns made of cells
// (bricks, stones, spikes, steps, checker squares) a per-cell value in [0,1) for colour variation, else 0.5.
Image generate_pattern(const ProceduralDesc& desc, bool with_cells);

// The waves pattern (ProceduralPattern::Waves) row by row: per wave, tables of its phase's sine and cosine along
// u and v, and its weight. Row y's raw sum of the waves (before the clamp to [0, 1]) goes into out[0 .. size),
// each wave added by `add` (HeightRows::add_wave: the baseline's or a kernel's, the same bits).
struct WaveRows {
  using AddWave = void (*)(int sharpness, float* row, int n, const float* su, const float* cu, float sv, float cv,
                           float weight);
  struct Wave {
    std::vector<float> su, cu, sv, cv;
    float weight;
    int sharpness;
  };
  int size = 0;
  std::vector<Wave> waves;
  void row(int y, float* out, AddWave add) const;
};
// Validates the pattern (as generate_pattern does) and makes its tables at the pattern's time and scroll.
WaveRows wave_rows(const ProceduralDesc& desc);

// Strength 1 of a from_height normal map: the surface of h in [0,1] is this deep in UV units of one repeat.
inline constexpr double kFromHeightDepth = 1.0 / 16.0;

}  // namespace qdmr::texture_detail
