// The material blocks of self-shadowing, ambient occlusion, height blending and lighting: values as written,
// defaults, and the message of each kind of error.
#include <gtest/gtest.h>

#include "scene/scene_test_util.hpp"

namespace qdmr {
namespace {

using nlohmann::json;
using test::load_error;
using test::minimal_scene;

json displaced_scene() {
  json document = minimal_scene();
  document["materials"]["rock"]["layers"] = json::parse(R"([{"height": {"procedural": "cobbles", "size": 64}}])");
  document["materials"]["rock"]["technique"] = {{"name", "qdm"}};
  return document;
}

TEST(MaterialBlocks, ValuesAsWritten) {
  json document = displaced_scene();
  json& m = document["materials"]["rock"];
  m["layers"].push_back(json::parse(R"({"height": {"procedural": "noise", "size": 64}, "specular": {"power": 2, "scale": 0.3, "invert": true}})"));
  m["shadow"] = json::parse(R"({"mode": "horizon", "strength": 3, "max_iterations": 9, "samples": 12, "length": 0.2,
                               "profile": "average", "penumbra": 2, "tap_weights": [1, 0.5]})");
  m["ao"] = json::parse(R"({"mode": "frame", "directions": 12, "jitter": true, "seed": 4, "radius": 0.1, "coarse": false,
                           "strength": 0.5, "resolution": 128})");
  m["blend"] = json::parse(R"({"operator": "height_width", "width": 0.1,
                              "weights": {"mode": "vertex", "source": "noise", "scale": 8, "resolution": 64, "seed": 3,
                                          "cells": 5, "sharpness": 2}})");
  m["lighting"] = json::parse(R"({"model": "cook_torrance", "specular": 0.04, "roughness": 0.3})");
  const SceneDesc scene = load_scene_json(document, "scene.json", ".");
  const MaterialDesc& d = scene.materials.at(0);
  ASSERT_EQ(d.layers.size(), 2u);
  EXPECT_FALSE(d.layers[0].specular.enabled);
  EXPECT_TRUE(d.layers[1].specular.enabled);
  EXPECT_EQ(d.layers[1].specular.power, 2.0f);
  EXPECT_EQ(d.layers[1].specular.scale, 0.3f);
  EXPECT_TRUE(d.layers[1].specular.invert);
  EXPECT_EQ(d.shadow.mode, ShadowMode::Horizon);
  EXPECT_EQ(d.shadow.strength, 3.0f);
  EXPECT_EQ(d.shadow.max_iterations, 9);
  EXPECT_EQ(d.shadow.samples, 12);
  EXPECT_EQ(d.shadow.length, 0.2f);
  EXPECT_EQ(d.shadow.profile, ProfileOperator::Average);
  EXPECT_EQ(d.shadow.penumbra, 2.0f);
  EXPECT_EQ(d.shadow.tap_weights, (std::vector<float>{1.0f, 0.5f}));
  EXPECT_EQ(d.ao.mode, AoMode::Frame);
  EXPECT_EQ(d.ao.directions, 12);
  EXPECT_TRUE(d.ao.jitter);
  EXPECT_EQ(d.ao.seed, 4u);
  EXPECT_EQ(d.ao.radius, 0.1f);
  EXPECT_FALSE(d.ao.coarse);
  EXPECT_EQ(d.ao.strength, 0.5f);
  EXPECT_EQ(d.ao.resolution, 128);
  EXPECT_EQ(d.blend.op, BlendOperator::HeightWidth);
  EXPECT_EQ(d.blend.width, 0.1f);
  EXPECT_EQ(d.blend.weights.mode, WeightMode::Vertex);
  EXPECT_EQ(d.blend.weights.scale, 8.0f);
  EXPECT_EQ(d.blend.weights.resolution, 64);
  EXPECT_EQ(d.blend.weights.cells, 5);
  EXPECT_EQ(d.blend.weights.sharpness, 2);
  EXPECT_EQ(d.lighting.model, LightingModel::CookTorrance);
  EXPECT_EQ(d.lighting.roughness, 0.3f);
}

TEST(MaterialBlocks, DefaultsAreOff) {
  const SceneDesc scene = load_scene_json(displaced_scene(), "scene.json", ".");
  const MaterialDesc& d = scene.materials.at(0);
  EXPECT_EQ(d.shadow.mode, ShadowMode::Off);
  EXPECT_EQ(d.ao.mode, AoMode::Off);
  EXPECT_EQ(d.blend.op, BlendOperator::Height);
  EXPECT_EQ(d.blend.weights.mode, WeightMode::Pixel);
  EXPECT_EQ(d.lighting.model, LightingModel::BlinnPhong);
}

TEST(MaterialBlocks, Errors) {
  json document = displaced_scene();
  document["materials"]["rock"]["shadow"] = {{"mode", "soft"}};
  EXPECT_EQ(load_error(document), "scene.json: /materials/rock/shadow/mode: unknown value 'soft'; did you mean 'off'?");
  document = displaced_scene();
  document["materials"]["rock"]["ao"] = {{"directions", 3}};
  EXPECT_EQ(load_error(document), "scene.json: /materials/rock/ao/directions: must be an integer from 4 to 16, got 3");
  document = displaced_scene();
  document["materials"]["rock"]["shadow"] = {{"tap_weights", json::array()}};
  EXPECT_EQ(load_error(document), "scene.json: /materials/rock/shadow/tap_weights: expected 1 to 16 weights, got 0");
  document = displaced_scene();
  document["materials"]["rock"]["blend"] = {{"weights", {{"source", "terrain"}}}};
  EXPECT_EQ(load_error(document), "scene.json: /materials/rock/blend/weights: source 'terrain' needs a 'height'");
  document["materials"]["rock"]["blend"] = {{"weights", {{"source", "file"}}}};
  EXPECT_EQ(load_error(document), "scene.json: /materials/rock/blend/weights: source 'file' needs a 'file'");
  document["materials"]["rock"]["blend"] = {{"operater", "alpha"}};
  EXPECT_EQ(load_error(document), "scene.json: /materials/rock/blend: unknown key 'operater'; did you mean 'operator'?");
  document = displaced_scene();
  document["materials"]["rock"]["lighting"] = {{"model", "phong"}};
  EXPECT_EQ(load_error(document),
            "scene.json: /materials/rock/lighting/model: unknown value 'phong'; expected one of: blinn_phong, cook_torrance");
  // Shadows and AO are properties of a displaced surface.
  document = minimal_scene();
  document["materials"]["rock"]["shadow"] = {{"mode", "hard"}};
  EXPECT_EQ(load_error(document),
            "scene.json: /materials/rock/shadow: self-shadowing needs a displacement technique (technique/name is 'normal')");
  document = minimal_scene();
  document["materials"]["rock"]["ao"] = {{"mode", "frame"}};
  EXPECT_EQ(load_error(document),
            "scene.json: /materials/rock/ao: ambient occlusion needs a displacement technique (technique/name is 'normal')");
}

}  // namespace
}  // namespace qdmr
