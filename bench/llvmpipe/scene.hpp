#pragma once
// What llvmpipe_bench renders: the camera, the plane, the textures and the technique knobs of its two scenes
// (scenes/plane.json with synthetic textures; bench/llvmpipe/canonical.json with qdmr's cobbles heights).
#include <cstdint>
#include <string>
#include <vector>

namespace llvmpipe_bench {

struct Vec3 {
  float x, y, z;
};

struct Mat4 {
  float m[16] = {};  // column-major
};

struct Camera {
  Vec3 eye, target, up;
  float fov_deg, near, far;
};

struct Scene {
  Camera camera;
  float background[4];  // the clear colour
};

// scenes/plane.json and bench/llvmpipe/canonical.json (the camera; both have plane.json's light).
Scene plane_scene();
Scene canonical_scene();

// glm::lookAt and glm::perspective (GL conventions), as qdmr builds the camera.
Mat4 view_projection(const Camera& camera, float aspect);

// A 4x4 plane at z = 0 with uv_scale 2, as `resolution`² quads (two triangles each), normal +z, tangent +x:
// qdmr's plane mesh (src/mesh/primitives.cpp) for resolution 1. Vertices are x, y, z, u, v.
struct Mesh {
  std::vector<float> vertices;
  std::vector<std::uint32_t> indices;
};
Mesh make_grid(int resolution);

// Square textures of `side` texels, rows in order of increasing v (texel row y holds v = (y + 0.5) / side).
struct SceneTextures {
  int side = 0;
  std::vector<std::uint8_t> albedo;  // RGBA8
  bool albedo_srgb = false;
  std::vector<std::uint8_t> normal;  // RGBA8, 0.5 + 0.5 n
  // Heights as qdmr samples them (r16 codes / 65535 as float), level 0 first, then the max-reduced levels
  // (qdmr's max-quadtree: each texel the largest of its 2x2 children) down to 1x1. Empty for plane.json.
  std::vector<std::vector<float>> max_chain;
};

// plane.json's case: a bricks-like albedo and a bumpy normal map (1024²); content does not change the cost of
// trilinear fetches.
SceneTextures plane_textures();
// canonical.json's layer (canonical.cpp): the cobbles height map (512², r16), its max chain, its normals and
// albedo generated as qdmr generates them.
SceneTextures canonical_textures();

enum class TechniqueKind { Normal, Pom, Relief, Qdm };

// The knobs of canonical.json's technique (keep in step with it: bench/llvmpipe_compare.py checks).
struct Technique {
  TechniqueKind kind = TechniqueKind::Normal;
  float depth_scale = 0.0f;
  int min_steps = 8, max_steps = 32;       // pom
  int linear_steps = 32, binary_steps = 5; // relief
  int max_iterations = 128;                // qdm (level_up one, refinement linear, sm4 integer cells)
  int height_side = 512;                   // texels per side of the height map
  int top_level = 9;                       // log2(height_side): the max chain's 1x1 level
};

bool technique_known(const std::string& name);
Technique canonical_technique(const std::string& name, float depth_scale);
// The knobs as a JSON object, for the comparison script to check against canonical.json.
std::string technique_json(const Technique& t);

}  // namespace llvmpipe_bench
