#pragma once
// Helpers of the tests that render: a shipped scene at a small size, and bit-exact comparison of planes.
#include <algorithm>
#include <bit>
#include <cstdint>
#include <string>
#include <vector>

#include "qdmr/core/pixel_buffer.hpp"
#include "qdmr/load/load.hpp"
#include "qdmr/render/render.hpp"
#include "support/test_support.hpp"

namespace qdmr::test {

// scenes/<name>.json at width x height, with the overrides applied.
inline SceneDesc small_scene(const std::string& name, std::vector<SceneOverride> overrides, int width, int height) {
  overrides.push_back({"/output/width", std::to_string(width)});
  overrides.push_back({"/output/height", std::to_string(height)});
  return load_scene(source_dir() / "scenes" / (name + ".json"), overrides);
}

// One frame of `scene` on `threads` threads.
inline Frame render_with_threads(const SceneDesc& scene, int threads) {
  RenderOptions options;
  options.threads = threads;
  return render_frame(scene, options);
}

inline bool same_bits(const PixelBuffer& a, const PixelBuffer& b) {
  return a.size() == b.size() && std::equal(a.begin(), a.end(), b.begin(), [](float x, float y) {
           return std::bit_cast<std::uint32_t>(x) == std::bit_cast<std::uint32_t>(y);
         });
}

}  // namespace qdmr::test
