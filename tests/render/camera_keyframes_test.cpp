// A camera that follows keyframes (`/camera/keyframes`, issue #58): it passes through every keyframe exactly,
// holds before the first and after the last, moves at constant speed between two (linear) or with a velocity that
// is continuous at every keyframe and zero at the ends (smooth). Frame N of a sequence equals frame N alone on any
// thread count, and the plan says the camera is animated without making anything dynamic.
#include <gtest/gtest.h>

#include <cmath>
#include <string>

#include <nlohmann/json.hpp>

#include "qdmr/plan/plan.hpp"
#include "qdmr/render/render.hpp"
#include "support/frames.hpp"

namespace qdmr::test {
namespace {

// Keyframes along x only: x = values[i] at frames[i].
CameraDesc along_x(std::vector<int> frames, std::vector<float> values, CameraInterpolation interpolation) {
  CameraDesc c;
  c.interpolation = interpolation;
  for (std::size_t i = 0; i < frames.size(); ++i)
    c.keyframes.push_back({frames[i], {values[i], -3.0f, 2.0f}, {values[i], 0.0f, 0.0f}, 40.0f + values[i]});
  return c;
}

float x_at(const CameraDesc& c, int frame) { return camera_at_frame(c, frame).position.x; }

TEST(CameraKeyframes, PassThroughEachKeyframeAndHoldOutsideThem) {
  for (auto interpolation : {CameraInterpolation::Linear, CameraInterpolation::Smooth}) {
    const CameraDesc c = along_x({5, 10, 30}, {1.0f, -2.5f, 7.25f}, interpolation);
    for (const CameraKeyframe& k : c.keyframes) {
      const CameraDesc at = camera_at_frame(c, k.frame);
      EXPECT_EQ(at.position, k.position);
      EXPECT_EQ(at.target, k.target);
      EXPECT_EQ(at.fov_y_deg, k.fov_y_deg);
    }
    EXPECT_EQ(x_at(c, 0), 1.0f);
    EXPECT_EQ(x_at(c, 99), 7.25f);
    EXPECT_EQ(camera_at_frame(c, 0).up, c.up);  // up, near and far are not keyed
  }
}

TEST(CameraKeyframes, LinearMovesAtConstantSpeed) {
  const CameraDesc c = along_x({0, 8}, {0.0f, 4.0f}, CameraInterpolation::Linear);
  // x = frame / 2: every value is a float exactly (one rounding of an exact double).
  for (int f = 0; f <= 8; ++f) EXPECT_EQ(x_at(c, f), 0.5f * float(f)) << f;
  EXPECT_EQ(camera_at_frame(c, 4).fov_y_deg, 42.0f);  // the field of view too
}

TEST(CameraKeyframes, SmoothBetweenTwoKeyframesIsSmoothstep) {
  const CameraDesc c = along_x({0, 8}, {0.0f, 8.0f}, CameraInterpolation::Smooth);
  for (int f = 0; f <= 8; ++f) {
    const double s = f / 8.0;
    // 8 (3s^2 - 2s^3) in double, rounded to float once: within one float rounding (2^-20 at values up to 8).
    EXPECT_NEAR(x_at(c, f), 8.0 * (3.0 * s * s - 2.0 * s * s * s), 1e-5) << f;
  }
}

TEST(CameraKeyframes, SmoothVelocityIsContinuousAndZeroAtTheEnds) {
  // Keyframes 1000 frames apart, so one frame's difference is the velocity up to the curvature term (values of
  // order 10 over 1000² frames: ~1e-5 per frame).
  const std::vector<int> frames{0, 1000, 2000};
  const std::vector<float> values{0.0f, 10.0f, 30.0f};
  const CameraDesc smooth = along_x(frames, values, CameraInterpolation::Smooth);
  const CameraDesc linear = along_x(frames, values, CameraInterpolation::Linear);
  const auto jump = [](const CameraDesc& c) {
    return std::abs((x_at(c, 1001) - x_at(c, 1000)) - (x_at(c, 1000) - x_at(c, 999)));
  };
  // Linear: the speed jumps from 0.01 to 0.02 per frame at the middle keyframe; smooth: no jump beyond the
  // curvature term and float rounding (a float at 10 is 1e-6 apart), well under 1e-4.
  EXPECT_NEAR(jump(linear), 0.01, 1e-4);
  EXPECT_LT(jump(smooth), 1e-4);
  EXPECT_LT(std::abs(x_at(smooth, 1) - x_at(smooth, 0)), 1e-4);        // starts at rest
  EXPECT_LT(std::abs(x_at(smooth, 2000) - x_at(smooth, 1999)), 1e-4);  // stops at rest
  EXPECT_NEAR(x_at(linear, 1) - x_at(linear, 0), 0.01, 1e-5);
}

// scenes/water.json, small, its camera flying past the waves.
SceneDesc flying_water(const std::string& interpolation) {
  return small_scene("water",
                     {{"/materials/water/layers/0/height/size", "64"},
                      {"/camera", R"({"up": [0, 0, 1], "fov_deg": 50, "near": 0.02, "far": 100, "interpolation": ")" + interpolation +
                                      R"(", "keyframes": [
                          {"frame": 0, "position": [0, -2.8, 1.1], "target": [0, 0.8, 0], "fov_deg": 60},
                          {"frame": 2, "position": [1, -2, 0.8], "target": [0.5, 0.5, 0]},
                          {"frame": 5, "position": [2, -1, 0.6], "target": [0.4, 0.9, 0], "fov_deg": 45}]})"}},
                     96, 54);
}

TEST(CameraKeyframes, AFrameOfASequenceEqualsTheFrameAloneOnAnyThreadCount) {
  for (const char* interpolation : {"linear", "smooth"}) {
    const SceneDesc scene = flying_water(interpolation);
    EXPECT_EQ(scene.camera.position, camera_at_frame(scene.camera, 0).position);  // loaded as frame 0
    EXPECT_EQ(scene.camera.keyframes[1].fov_y_deg, 50.0f);  // a keyframe without fov_deg keeps the camera's
    RenderOptions options;
    options.threads = 2;
    Renderer renderer(options);
    renderer.set_scene(scene);
    for (int n = 1; n <= 3; ++n) renderer.set_frame(n);
    renderer.draw();
    for (int threads : {1, 3}) {
      options.threads = threads;
      EXPECT_TRUE(same_bits(renderer.frame().color, render_frame(scene_at_frame(scene, 3), options).color))
          << interpolation << " " << threads;
    }
    // The camera moved: frame 3 is not frame 0.
    EXPECT_FALSE(same_bits(renderer.frame().color, render_frame(scene, options).color)) << interpolation;
  }
}

TEST(CameraKeyframes, ThePlanSaysTheCameraIsAnimatedAndRebuildsNothingForIt) {
  // Still waves under a moving camera: no dynamic item, a camera line in the plan.
  const SceneDesc scene = flying_water("smooth");
  std::vector<SceneOverride> still;
  for (int i = 0; i < 4; ++i) still.push_back({"/materials/water/layers/0/height/waves/" + std::to_string(i) + "/speed", "0"});
  still.push_back({"/materials/water/layers/0/height/size", "64"});
  still.push_back({"/camera", R"({"keyframes": [{"frame": 0, "position": [0, -3, 1], "target": [0, 0, 0]},
                                                {"frame": 9, "position": [1, -3, 1], "target": [0, 0, 0]}]})"});
  const FramePlan plan = plan_frame(small_scene("water", still, 16, 16));
  EXPECT_TRUE(plan.dynamic_items().empty());
  EXPECT_NE(plan.describe().find("camera: animated, 2 keyframes, linear interpolation"), std::string::npos)
      << plan.describe();
  EXPECT_EQ(plan.to_json().at("camera").at("keyframes"), 2);
  EXPECT_NE(plan_frame(scene).describe().find("camera: animated, 3 keyframes, smooth interpolation"), std::string::npos);
}

}  // namespace
}  // namespace qdmr::test
