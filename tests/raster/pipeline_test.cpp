// The whole draw path against analytic references: perspective-correct interpolation, near-plane and
// guard-band clipping, depth ordering; and determinism across threads and tile sizes.
#include <gtest/gtest.h>

#include <cmath>
#include <cstring>

#include <glm/ext/matrix_clip_space.hpp>
#include <glm/ext/matrix_transform.hpp>
#include <glm/mat4x4.hpp>
#include <nlohmann/json.hpp>

#include "qdmr/render/render.hpp"
#include "qdmr/load/load.hpp"
#include "support/test_support.hpp"

namespace qdmr::test {
namespace {

nlohmann::json base_scene(int width, int height) {
  nlohmann::json doc = nlohmann::json::parse(R"({
    "output": {"width": 0, "height": 0},
    "camera": {"position": [0, -3, 2], "target": [0, 0, 0], "up": [0, 0, 1], "fov_deg": 50, "near": 0.1, "far": 100},
    "materials": {"flat": {"layers": [{"albedo": {"constant": [0.5, 0.5, 0.5]}}]}},
    "objects": []
  })");
  doc["output"] = {{"width", width}, {"height", height}};
  return doc;
}

Frame render(const nlohmann::json& doc, std::vector<Aov> aovs, int threads = 1, int tile = 64) {
  const SceneDesc scene = load_scene_json(doc, "test.json", source_dir());
  RenderOptions options;
  options.threads = threads;
  options.tile_size = tile;
  options.aovs = std::move(aovs);
  return render_frame(scene, options);
}

const AovImage& aov(const Frame& f, Aov which) {
  for (const AovImage& a : f.aovs)
    if (a.aov == which) return a;
  throw std::runtime_error("missing aov");
}

// The view ray through a pixel centre, in double precision, from the same camera definition.
struct Ray {
  glm::dvec3 origin, direction;
};
Ray pixel_ray(const nlohmann::json& doc, double px, double py) {
  const auto& cam = doc["camera"];
  const glm::dvec3 eye(cam["position"][0].get<double>(), cam["position"][1].get<double>(), cam["position"][2].get<double>());
  const glm::dvec3 target(cam["target"][0].get<double>(), cam["target"][1].get<double>(), cam["target"][2].get<double>());
  const glm::dvec3 up(cam["up"][0].get<double>(), cam["up"][1].get<double>(), cam["up"][2].get<double>());
  const double w = doc["output"]["width"].get<double>(), h = doc["output"]["height"].get<double>();
  const glm::dmat4 vp = glm::perspective(glm::radians(cam["fov_deg"].get<double>()), w / h, cam["near"].get<double>(),
                                         cam["far"].get<double>()) *
                        glm::lookAt(eye, target, up);
  const glm::dmat4 inv = glm::inverse(vp);
  const double nx = px / w * 2.0 - 1.0, ny = 1.0 - py / h * 2.0;
  glm::dvec4 a = inv * glm::dvec4(nx, ny, -1.0, 1.0), b = inv * glm::dvec4(nx, ny, 1.0, 1.0);
  const glm::dvec3 pa = glm::dvec3(a) / a.w, pb = glm::dvec3(b) / b.w;
  return {eye, glm::normalize(pb - pa)};
}

glm::dvec3 camera_forward(const nlohmann::json& doc) {
  const auto& cam = doc["camera"];
  return glm::normalize(glm::dvec3(cam["target"][0].get<double>() - cam["position"][0].get<double>(),
                                   cam["target"][1].get<double>() - cam["position"][1].get<double>(),
                                   cam["target"][2].get<double>() - cam["position"][2].get<double>()));
}

TEST(Pipeline, PerspectiveCorrectUvOnTiltedPlaneMatchesRayIntersection) {
  nlohmann::json doc = base_scene(256, 192);
  doc["objects"].push_back({{"mesh", {{"type", "plane"}, {"size", 4}}}, {"material", "flat"}});
  const Frame frame = render(doc, {Aov::UV, Aov::Depth});
  const AovImage& uv = aov(frame, Aov::UV);
  const AovImage& depth = aov(frame, Aov::Depth);
  int covered = 0;
  double worst_uv = 0.0, worst_depth = 0.0;
  for (int y = 0; y < frame.height; ++y)
    for (int x = 0; x < frame.width; ++x) {
      const std::size_t i = std::size_t(y) * frame.width + x;
      if (depth.pixels[i] == 0.0f) continue;
      ++covered;
      const Ray ray = pixel_ray(doc, x + 0.5, y + 0.5);
      const double t = -ray.origin.z / ray.direction.z;
      const glm::dvec3 hit = ray.origin + t * ray.direction;
      // plane of size 4 centred at the origin: uv (0,0) at (-2,-2), (1,1) at (2,2)
      worst_uv = std::max({worst_uv, std::abs(uv.pixels[2 * i] - (hit.x + 2.0) / 4.0),
                           std::abs(uv.pixels[2 * i + 1] - (hit.y + 2.0) / 4.0)});
      const double view_depth = glm::dot(hit - ray.origin, camera_forward(doc));
      worst_depth = std::max(worst_depth, std::abs(depth.pixels[i] - view_depth) / view_depth);
    }
  EXPECT_GT(covered, 256 * 192 / 4);
  // The bound is set by snapping vertices to 1/256 pixel, not by interpolation: a vertex moves by up to
  // 1/512 pixel in x and y, and here one pixel spans at most ~0.015 in uv near the camera, so the surface
  // shifts by up to ~3e-5 in uv (and depth by the same relative amount). Float interpolation adds ~1e-6.
  EXPECT_LT(worst_uv, 5e-5);
  EXPECT_LT(worst_depth, 5e-5);
}

TEST(Pipeline, PlaneCrossingNearPlaneAndGuardBandIsClippedExactly) {
  nlohmann::json doc = base_scene(200, 150);
  doc["camera"]["position"] = {0, 0, 1};
  doc["camera"]["target"] = {0, 10, 0.6};
  // 200 km plane: far beyond the guard band and behind the camera, crossing the near plane.
  doc["objects"].push_back({{"mesh", {{"type", "plane"}, {"size", 200000}, {"uv_scale", 1}}}, {"material", "flat"}});
  const Frame frame = render(doc, {Aov::Depth});
  EXPECT_GT(frame.stats.triangles_clipped, 0u);
  const AovImage& depth = aov(frame, Aov::Depth);
  int wrong = 0;
  for (int y = 0; y < frame.height; ++y)
    for (int x = 0; x < frame.width; ++x) {
      const Ray ray = pixel_ray(doc, x + 0.5, y + 0.5);
      const double t = ray.direction.z < 0 ? -ray.origin.z / ray.direction.z : INFINITY;
      const glm::dvec3 hit = ray.origin + t * ray.direction;
      const double view_depth = std::isfinite(t) ? glm::dot(hit - ray.origin, camera_forward(doc)) : INFINITY;
      // Coverage is exact except within a hair of the far plane (depth 100), where rounding decides.
      if (std::abs(view_depth - 100.0) < 0.5) continue;
      const bool expected = view_depth < 100.0;
      const bool got = depth.pixels[std::size_t(y) * frame.width + x] > 0.0f;
      wrong += expected != got;
    }
  EXPECT_EQ(wrong, 0);
  for (float c : frame.color) ASSERT_TRUE(std::isfinite(c));
}

TEST(Pipeline, GeometryBehindTheCameraDrawsNothing) {
  nlohmann::json doc = base_scene(64, 48);
  doc["objects"].push_back({{"mesh", {{"type", "box"}, {"size", 1}}}, {"material", "flat"}, {"transform", {{"translate", {0, -6, 3}}}}});
  const Frame frame = render(doc, {});
  EXPECT_EQ(frame.stats.pixels_shaded, 0u);
  EXPECT_EQ(frame.stats.triangles_culled, 12u);
}

TEST(Pipeline, IntersectingPlanesKeepTheNearerSurfacePerPixel) {
  nlohmann::json doc = base_scene(192, 144);
  doc["objects"].push_back({{"mesh", {{"type", "plane"}, {"size", 3}}}, {"material", "flat"}});
  doc["objects"].push_back({{"mesh", {{"type", "plane"}, {"size", 3}}}, {"material", "flat"},
                            {"transform", {{"rotate_deg", {-35, 0, 0}}}}});
  const Frame frame = render(doc, {Aov::Depth});
  const AovImage& depth = aov(frame, Aov::Depth);
  const glm::dvec3 n_tilted(0.0, std::sin(glm::radians(35.0)), std::cos(glm::radians(35.0)));  // rotate_x(-35) of +z
  int checked = 0, wrong = 0;
  for (int y = 0; y < frame.height; ++y)
    for (int x = 0; x < frame.width; ++x) {
      const float got = depth.pixels[std::size_t(y) * frame.width + x];
      if (got == 0.0f) continue;
      const Ray ray = pixel_ray(doc, x + 0.5, y + 0.5);
      double best = INFINITY;
      auto consider = [&](const glm::dvec3& n, const glm::dvec3& tangent_u, const glm::dvec3& tangent_v) {
        const double denom = glm::dot(n, ray.direction);
        if (denom >= 0) return;  // back face: culled
        const double t = -glm::dot(n, ray.origin) / denom;
        const glm::dvec3 hit = ray.origin + t * ray.direction;
        if (std::abs(glm::dot(hit, tangent_u)) > 1.5 || std::abs(glm::dot(hit, tangent_v)) > 1.5) return;
        best = std::min(best, glm::dot(hit - ray.origin, camera_forward(doc)));
      };
      consider({0, 0, 1}, {1, 0, 0}, {0, 1, 0});
      consider(n_tilted, {1, 0, 0}, glm::cross(n_tilted, glm::dvec3(1, 0, 0)));
      if (!std::isfinite(best)) continue;  // silhouette pixels: edge rounding
      ++checked;
      // Depth-buffer precision (float window depth) near the intersection line decides ties there.
      wrong += std::abs(got - best) / best > 1e-4;
    }
  EXPECT_GT(checked, 5000);
  EXPECT_EQ(wrong, 0);
}

PixelBuffer color_of(const std::string& scene_name, int threads, int tile, int width = 320, int height = 180) {
  const SceneDesc scene = load_scene(source_dir() / "scenes" / scene_name, {{"/output/width", std::to_string(width)},
                                                                           {"/output/height", std::to_string(height)}});
  RenderOptions options;
  options.threads = threads;
  options.tile_size = tile;
  return render_frame(scene, options).color;
}

TEST(Determinism, SameBitsForAnyThreadCountAndTileSize) {
  for (const char* name : {"objects.json", "terrain.json"}) {
    const PixelBuffer reference = color_of(name, 1, 64);
    for (int threads : {2, 8})
      EXPECT_EQ(0, std::memcmp(color_of(name, threads, 64).data(), reference.data(), reference.size() * sizeof(float)))
          << name << " threads " << threads;
    for (int tile : {16, 32, 128, 256})
      EXPECT_EQ(0, std::memcmp(color_of(name, 2, tile).data(), reference.data(), reference.size() * sizeof(float)))
          << name << " tile " << tile;
  }
}

// Tiles of up to 128x128 pixels draw into a colour plane of their own and stream it to the frame; larger ones draw
// into the frame. An odd frame width puts most rows' first pixel off a 16-byte boundary, where the streaming
// copy starts with plain stores.
TEST(Determinism, SameBitsFromATilesOwnColourPlaneAndFromTheFrame) {
  for (const char* name : {"objects.json", "terrain.json"}) {
    const PixelBuffer own_plane = color_of(name, 2, 64, 317, 179);
    for (int tile : {200, 1024})
      EXPECT_EQ(0, std::memcmp(color_of(name, 2, tile, 317, 179).data(), own_plane.data(),
                               own_plane.size() * sizeof(float)))
          << name << " tile " << tile;
  }
}

}  // namespace
}  // namespace qdmr::test
