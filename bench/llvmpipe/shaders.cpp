#include "shaders.hpp"

#include <cstdio>

namespace llvmpipe_bench {
namespace {

const char* kVertexShader = R"(#version 330 core
layout(location = 0) in vec3 position;
layout(location = 1) in vec2 uv;
uniform mat4 view_projection;
out vec3 world;
out vec2 tex;
void main() {
  world = position;
  tex = uv;
  gl_Position = view_projection * vec4(position, 1.0);
}
)";

const char* kLegacyFragmentShader = R"(#version 330 core
in vec3 world;
in vec2 tex;
uniform sampler2D albedo_map;
uniform sampler2D normal_map;
uniform vec3 eye;
out vec4 color;
const vec3 N = vec3(0, 0, 1), T = vec3(1, 0, 0), B = vec3(0, 1, 0);
const vec3 light_dir = normalize(vec3(-0.5, -0.4, 0.75));
const vec3 light = vec3(1.0, 0.96, 0.9) * 1.1, ambient = vec3(0.55, 0.65, 0.9) * 0.18;
void main() {
  vec3 albedo = texture(albedo_map, tex).rgb;
  vec3 nt = texture(normal_map, tex).xyz * 2.0 - 1.0;
  vec3 n = normalize(nt.x * T + nt.y * B + nt.z * N);
  vec3 v = normalize(eye - world);
  vec3 h = normalize(light_dir + v);
  float diffuse = max(dot(n, light_dir), 0.0);
  float specular = diffuse > 0.0 ? 0.15 * pow(max(dot(n, h), 0.0), 24.0) : 0.0;
  color = vec4(albedo * (ambient + light * diffuse) + light * specular, 1.0);
}
)";

// The canonical scene's fragment shader, after the #defines of its technique and knobs. Each trace function
// follows qdmr's SIMD code lane by lane (file named above it); `iterations` counts what qdmr's `iterations` AOV
// counts. The plane's tangent frame is the world's axes (tangent +x, bitangent +y, normal +z), so tangent-space
// vectors are world vectors here.
const char* kCanonicalBody = R"(
in vec3 world;
in vec2 tex;
uniform sampler2D albedo_map;  // RGBA8 sRGB, trilinear
uniform sampler2D normal_map;  // RGBA8, trilinear
#ifndef TECHNIQUE_NORMAL
uniform sampler2D height_map;  // R32F level 0, bilinear (qdmr's height_fetch "bilinear")
uniform sampler2D max_tree;    // R32F max chain, texelFetch only
#endif
uniform vec3 eye;
out vec4 color;

// canonical.json's lights and lighting (plane.json's).
const vec3 light_dir = normalize(vec3(-0.5, -0.4, 0.75));
const vec3 radiance = vec3(1.0, 0.96, 0.9) * 1.1, ambient = vec3(0.55, 0.65, 0.9) * 0.18;
const float specular_scale = 0.15, shininess = 24.0;

#ifndef TECHNIQUE_NORMAL
float height_at(vec2 uv) { return textureLod(height_map, uv, 0.0).r; }
#endif

#ifdef TECHNIQUE_POM
// src/kernel/pom.hpp: step count lerped from MAX_STEPS (grazing) to MIN_STEPS (along the normal), then the
// intersection of the ray with the line through the last two samples. gap = surface depth - ray depth.
float trace(vec2 uv0, vec2 duv, float ds, float cos_view, inout float iterations) {
  float n = floor(float(MAX_STEPS) + float(MIN_STEPS - MAX_STEPS) * clamp(cos_view, 0.0, 1.0) + 0.5);
  float step = ds / n;
  float prev_gap = ds * (1.0 - height_at(uv0));
  iterations += 1.0;
  if (prev_gap <= 0.0) return 0.0;
  float prev_s = 0.0;
  for (int i = 1; i <= MAX_STEPS; ++i) {
    float fi = float(i);
    if (fi > n) break;
    float s = step * fi;
    float gap = ds * (1.0 - height_at(uv0 + duv * s)) - s;
    iterations += 1.0;
    if (gap <= 0.0) return prev_s + (s - prev_s) * (prev_gap / (prev_gap - gap));
    prev_s = s;
    prev_gap = gap;
  }
  return ds;
}
#endif

#ifdef TECHNIQUE_RELIEF
// src/kernel/relief.hpp: LINEAR_STEPS + 1 samples from the top, then BINARY_STEPS bisections of the last step.
float trace(vec2 uv0, vec2 duv, float ds, float cos_view, inout float iterations) {
  float step = ds / float(LINEAR_STEPS);
  float lo = ds - step, hi = ds;  // not found: the bottom (h >= 0 everywhere) is the hit
  for (int i = 0; i <= LINEAR_STEPS; ++i) {
    float s = step * float(i);
    iterations += 1.0;
    if (s >= ds * (1.0 - height_at(uv0 + duv * s))) {
      hi = s;
      lo = max(s - step, 0.0);
      break;
    }
  }
  if (lo < hi) {
    for (int i = 0; i < BINARY_STEPS; ++i) {
      float mid = (lo + hi) * 0.5;
      iterations += 1.0;
      if (mid >= ds * (1.0 - height_at(uv0 + duv * mid))) hi = mid;
      else lo = mid;
    }
  }
  return hi;
}
#endif

#ifdef TECHNIQUE_QDM
// src/kernel/qdm.hpp and traversal.hpp, sm4 math (integer cells stepped across walls, fp32 crossings), plain
// max fetches (texelFetch), level_up "one", no lod_stop (the hit is at level 0), then linear refinement
// (refine.hpp). Positions in level-0 texels: p(t) = p0 + d t at depth t.
const float INF = uintBitsToFloat(0x7F800000u);

// traversal.hpp descend_to_child: the child of `cell` holding the ray at t, by where the ray crosses the
// parent's mid lines (computed as wall crossings are).
void descend(float t, vec2 p0, vec2 d, inout int level, inout ivec2 cell) {
  int child = max(level - 1, 0);
  vec2 mid = vec2(cell * 2 + 1) * float(1 << child);
  vec2 tm = (mid - p0) / d;
  bvec2 high = bvec2((d.x > 0.0 && t >= tm.x) || (d.x < 0.0 && t < tm.x) || (d.x == 0.0 && p0.x >= mid.x),
                     (d.y > 0.0 && t >= tm.y) || (d.y < 0.0 && t < tm.y) || (d.y == 0.0 && p0.y >= mid.y));
  cell = cell * 2 + ivec2(high);
  level = child;
}

// traversal.hpp exit_walls: where the ray crosses the walls ahead of the cell, per axis.
vec2 exit_walls(int level, ivec2 cell, vec2 p0, vec2 d, bvec2 positive) {
  vec2 wall = vec2(cell + ivec2(positive)) * float(1 << level);
  vec2 t = (wall - p0) / d;
  return vec2(d.x != 0.0 ? t.x : INF, d.y != 0.0 ? t.y : INF);
}

float trace_box(vec2 uv0, vec2 duv, float ds, inout float iterations) {
  vec2 p0 = uv0 * float(HEIGHT_SIDE), d = duv * float(HEIGHT_SIDE);
  bvec2 positive = greaterThan(d, vec2(0.0));
  int level = TOP_LEVEL;
  ivec2 cell = ivec2(floor(p0)) >> TOP_LEVEL;
  float s = 0.0;
  for (int i = 0; i < MAX_ITERATIONS; ++i) {
    iterations += 1.0;
    int wrap = (HEIGHT_SIDE >> level) - 1;  // power-of-two levels: wrap addressing by mask
    float top_depth = ds * (1.0 - texelFetch(max_tree, cell & wrap, level).r);
    if (s >= top_depth) {  // below the cell's highest point: the hit at level 0, else descend
      if (level == 0) break;
      descend(s, p0, d, level, cell);
      continue;
    }
    vec2 t = exit_walls(level, cell, p0, d, positive);
    float t_wall = max(min(t.x, t.y), s);
    if (top_depth <= t_wall) {  // onto the cell's top plane: the hit at level 0, else descend now
      s = top_depth;
      if (level == 0) break;
      descend(s, p0, d, level, cell);
      continue;
    }
    s = t_wall;  // across the nearer wall (both at a corner), then up one level
    if (t.x <= t.y) cell.x += positive.x ? 1 : -1;
    if (t.y <= t.x) cell.y += positive.y ? 1 : -1;
    if (level < TOP_LEVEL) {
      level += 1;
      cell >>= 1;
    }
  }
  return min(s, ds);
}

// refine.hpp, refinement "linear": the line through the bilinear surface's gaps one texel step before the
// box-surface hit and at it.
float refine_linear(vec2 uv0, vec2 duv, float ds, float s_hit, inout float iterations) {
  float reach = max(abs(duv.x) * float(HEIGHT_SIDE), abs(duv.y) * float(HEIGHT_SIDE));
  float step = 1.0 / max(reach, 1e-6);
  float lo = max(s_hit - step, 0.0), hi = s_hit;
  float gap_lo = ds * (1.0 - height_at(uv0 + duv * lo)) - lo;
  float gap_hi = ds * (1.0 - height_at(uv0 + duv * hi)) - hi;
  iterations += 2.0;
  if (gap_lo > 0.0 && gap_hi <= 0.0) return lo + (hi - lo) * (gap_lo / (gap_lo - gap_hi));
  return gap_lo <= 0.0 ? lo : hi;
}

float trace(vec2 uv0, vec2 duv, float ds, float cos_view, inout float iterations) {
  return refine_linear(uv0, duv, ds, trace_box(uv0, duv, ds, iterations), iterations);
}
#endif

#ifdef TECHNIQUE_NORMAL
float trace(vec2 uv0, vec2 duv, float ds, float cos_view, inout float iterations) { return 0.0; }
#endif

void main() {
  vec3 view = normalize(eye - world);
  // src/kernel/displacement.cpp: the ray leaves the polygon along -view, uv(s) = uv0 + duv s for depth s.
  float vz = max(view.z, 1e-4);
  vec2 duv = -view.xy / vz;
  float iterations = 0.0;
  float s = trace(tex, duv, DEPTH_SCALE, view.z, iterations);
  vec2 hit = tex + duv * s;
#ifdef HIT_UV_OUTPUT
  color = vec4(hit, iterations, 1.0);
#else
#ifdef TECHNIQUE_NORMAL
  vec3 albedo = texture(albedo_map, hit).rgb;
  vec3 n = normalize(texture(normal_map, hit).xyz * 2.0 - 1.0);
#else
  // qdmr takes the LOD of the surface fetches from the polygon's UV derivatives, not the hit's.
  vec2 gx = dFdx(tex), gy = dFdy(tex);
  vec3 albedo = textureGrad(albedo_map, hit, gx, gy).rgb;
  vec3 n = normalize(textureGrad(normal_map, hit, gx, gy).xyz * 2.0 - 1.0);
#endif
  // src/kernel/lighting_models.cpp, Blinn-Phong, one directional light (above the plane: facing = 1).
  float n_dot_l = max(dot(n, light_dir), 0.0);
  vec3 h = normalize(light_dir + view);
  float spec = pow(max(dot(n, h), 0.0), shininess) * specular_scale * min(n_dot_l * 8.0, 1.0);
  color = vec4(albedo * (ambient + radiance * n_dot_l) + radiance * spec, 1.0);
#endif
}
)";

std::string define(const char* name, int value) {
  return std::string("#define ") + name + " " + std::to_string(value) + "\n";
}

const char* technique_macro(TechniqueKind kind) {
  switch (kind) {
    case TechniqueKind::Normal: return "TECHNIQUE_NORMAL";
    case TechniqueKind::Pom: return "TECHNIQUE_POM";
    case TechniqueKind::Relief: return "TECHNIQUE_RELIEF";
    case TechniqueKind::Qdm: return "TECHNIQUE_QDM";
  }
  return "TECHNIQUE_NORMAL";
}

}  // namespace

std::string vertex_shader() { return kVertexShader; }

std::string legacy_fragment_shader() { return kLegacyFragmentShader; }

std::string fragment_shader(const Technique& t, bool hit_uv) {
  // The knobs as compile-time constants: loop bounds llvmpipe can see (qdmr specialises its programs per
  // technique too, but reads the step counts at run time).
  char depth[64];
  std::snprintf(depth, sizeof depth, "#define DEPTH_SCALE float(%.9g)\n", double(t.depth_scale));  // the float exactly
  std::string s = "#version 330 core\n";
  s += std::string("#define ") + technique_macro(t.kind) + "\n";
  if (hit_uv) s += "#define HIT_UV_OUTPUT\n";
  s += depth;
  s += define("MIN_STEPS", t.min_steps) + define("MAX_STEPS", t.max_steps) + define("LINEAR_STEPS", t.linear_steps) +
       define("BINARY_STEPS", t.binary_steps) + define("MAX_ITERATIONS", t.max_iterations) +
       define("HEIGHT_SIDE", t.height_side) + define("TOP_LEVEL", t.top_level);
  return s + kCanonicalBody;
}

}  // namespace llvmpipe_bench
