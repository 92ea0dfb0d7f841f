#pragma once
// The GLSL 3.30 sources of llvmpipe_bench.
#include <string>

#include "scene.hpp"

namespace llvmpipe_bench {

// Position and UV in, world position and UV out (the plane's frame is constant: normal +z, tangent +x).
std::string vertex_shader();

// plane.json's normal mapping (the `grid` case of docs/performance.md, "Mesa llvmpipe vs qdmr").
std::string legacy_fragment_shader();

// canonical.json's material with the technique: the trace of qdmr's program (its knobs compiled in as
// constants), then albedo, normal map and Blinn-Phong at the hit. With `hit_uv` the colour is instead
// (hit u, hit v, loop iterations, 1).
std::string fragment_shader(const Technique& technique, bool hit_uv);

}  // namespace llvmpipe_bench
