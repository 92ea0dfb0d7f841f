#include "scene.hpp"

#include <cmath>
#include <cstring>
#include <stdexcept>

namespace llvmpipe_bench {
namespace {

Vec3 sub(Vec3 a, Vec3 b) { return {a.x - b.x, a.y - b.y, a.z - b.z}; }
Vec3 cross(Vec3 a, Vec3 b) { return {a.y * b.z - a.z * b.y, a.z * b.x - a.x * b.z, a.x * b.y - a.y * b.x}; }
float dot(Vec3 a, Vec3 b) { return a.x * b.x + a.y * b.y + a.z * b.z; }
Vec3 normalize(Vec3 a) {
  const float l = std::sqrt(dot(a, a));
  return {a.x / l, a.y / l, a.z / l};
}

Mat4 mul(const Mat4& a, const Mat4& b) {
  Mat4 r;
  for (int c = 0; c < 4; ++c)
    for (int row = 0; row < 4; ++row)
      for (int k = 0; k < 4; ++k) r.m[c * 4 + row] += a.m[k * 4 + row] * b.m[c * 4 + k];
  return r;
}

}  // namespace

// Black, as llvmpipe_bench always cleared for plane.json.
Scene plane_scene() { return {{{0, -2.2f, 1.6f}, {0, 0.2f, 0}, {0, 0, 1}, 50.0f, 0.05f, 50.0f}, {0, 0, 0, 1}}; }

// 3 units from the origin at 60 degrees elevation: (0, -3 cos 60°, 3 sin 60°), as canonical.json has it.
// The background is qdmr's default output/background.
Scene canonical_scene() {
  return {{{0, -1.5f, 2.598076f}, {0, 0, 0}, {0, 0, 1}, 50.0f, 0.05f, 50.0f}, {0.05f, 0.06f, 0.08f, 1}};
}

Mat4 view_projection(const Camera& camera, float aspect) {
  const Vec3 eye = camera.eye;
  const Vec3 f = normalize(sub(camera.target, eye)), s = normalize(cross(f, camera.up)), u = cross(s, f);
  Mat4 view;
  const float v[16] = {s.x, u.x, -f.x, 0, s.y, u.y, -f.y, 0, s.z, u.z, -f.z, 0, -dot(s, eye), -dot(u, eye), dot(f, eye), 1};
  std::memcpy(view.m, v, sizeof v);
  const float fov = camera.fov_deg * 3.14159265f / 180.0f, n = camera.near, fa = camera.far;
  const float t = 1.0f / std::tan(fov / 2);
  Mat4 proj;
  proj.m[0] = t / aspect;
  proj.m[5] = t;
  proj.m[10] = -(fa + n) / (fa - n);
  proj.m[11] = -1;
  proj.m[14] = -2 * fa * n / (fa - n);
  return mul(proj, view);
}

Mesh make_grid(int resolution) {
  Mesh m;
  const int n = resolution + 1;
  for (int j = 0; j < n; ++j)
    for (int i = 0; i < n; ++i) {
      const float u = float(i) / float(resolution), v = float(j) / float(resolution);
      m.vertices.insert(m.vertices.end(), {-2 + 4 * u, -2 + 4 * v, 0, 2 * u, 2 * v});
    }
  for (int j = 0; j < resolution; ++j)
    for (int i = 0; i < resolution; ++i) {
      const std::uint32_t a = std::uint32_t(j * n + i), b = a + 1, c = a + std::uint32_t(n), d = c + 1;
      m.indices.insert(m.indices.end(), {a, b, d, a, d, c});
    }
  return m;
}

SceneTextures plane_textures() {
  constexpr int kSide = 1024;
  SceneTextures t;
  t.side = kSide;
  t.albedo.resize(std::size_t(kSide) * kSide * 4);
  t.normal.resize(t.albedo.size());
  for (int y = 0; y < kSide; ++y)
    for (int x = 0; x < kSide; ++x) {
      const std::size_t i = (std::size_t(y) * kSide + std::size_t(x)) * 4;
      const float a = std::sin(float(x) * 0.05f), b = std::cos(float(y) * 0.07f);
      const Vec3 nrm = normalize({0.4f * a, 0.4f * b, 1.0f});
      t.normal[i] = std::uint8_t(127.5f + 127.5f * nrm.x);
      t.normal[i + 1] = std::uint8_t(127.5f + 127.5f * nrm.y);
      t.normal[i + 2] = std::uint8_t(127.5f + 127.5f * nrm.z);
      t.normal[i + 3] = 255;
      t.albedo[i] = std::uint8_t(120 + 60 * a);
      t.albedo[i + 1] = std::uint8_t(70 + 30 * b);
      t.albedo[i + 2] = 50;
      t.albedo[i + 3] = 255;
    }
  return t;
}

bool technique_known(const std::string& name) {
  return name == "normal" || name == "pom" || name == "relief" || name == "qdm";
}

Technique canonical_technique(const std::string& name, float depth_scale) {
  Technique t;
  if (name == "normal") t.kind = TechniqueKind::Normal;
  else if (name == "pom") t.kind = TechniqueKind::Pom;
  else if (name == "relief") t.kind = TechniqueKind::Relief;
  else if (name == "qdm") t.kind = TechniqueKind::Qdm;
  else throw std::runtime_error("unknown technique " + name);
  t.depth_scale = depth_scale;
  return t;
}

std::string technique_json(const Technique& t) {
  return "{\"min_steps\": " + std::to_string(t.min_steps) + ", \"max_steps\": " + std::to_string(t.max_steps) +
         ", \"linear_steps\": " + std::to_string(t.linear_steps) +
         ", \"binary_steps\": " + std::to_string(t.binary_steps) +
         ", \"max_iterations\": " + std::to_string(t.max_iterations) +
         ", \"level_up\": \"one\", \"refinement\": \"linear\", \"height_fetch\": \"bilinear\", \"math\": \"sm4\"" +
         ", \"height_side\": " + std::to_string(t.height_side) + "}";
}

}  // namespace llvmpipe_bench
