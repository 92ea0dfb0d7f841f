// Validation of scene documents: defaults, a full round trip, and the message of each kind of error.
#include <gtest/gtest.h>

#include <cmath>
#include <glm/geometric.hpp>

#include "scene/scene_test_util.hpp"

namespace qdmr {
namespace {

using nlohmann::json;
using test::load_error;
using test::minimal_scene;

SceneDesc load(const json& document) { return load_scene_json(document, "scene.json", "."); }

TEST(SceneLoader, MinimalSceneGetsDefaults) {
  const SceneDesc scene = load(minimal_scene());
  EXPECT_EQ(scene.file, "scene.json");
  EXPECT_EQ(scene.output.width, 1920);
  EXPECT_EQ(scene.output.height, 1080);
  EXPECT_EQ(scene.camera.position, CameraDesc{}.position);
  EXPECT_FLOAT_EQ(scene.camera.fov_y_deg, 45.0f);
  ASSERT_EQ(scene.lights.directional.size(), 1u);
  EXPECT_NEAR(glm::length(scene.lights.directional[0].direction), 1.0f, 1e-6f);
  EXPECT_FLOAT_EQ(scene.lights.ambient.intensity, 0.2f);

  ASSERT_EQ(scene.materials.size(), 1u);
  const MaterialDesc& rock = scene.materials[0];
  EXPECT_EQ(rock.name, "rock");
  ASSERT_EQ(rock.layers.size(), 1u);
  EXPECT_EQ(rock.layers[0].albedo.source, TextureSource::Constant);
  EXPECT_EQ(rock.layers[0].albedo.constant, glm::vec4(1.0f));
  EXPECT_EQ(rock.layers[0].normal.source, TextureSource::None);
  EXPECT_EQ(rock.layers[0].height.source, TextureSource::None);
  EXPECT_EQ(rock.technique.kind, TechniqueKind::Normal);
  EXPECT_EQ(rock.sampling.filter, Filter::Trilinear);
  EXPECT_EQ(rock.sampling.address, AddressMode::Wrap);
  EXPECT_EQ(rock.lighting.model, LightingModel::BlinnPhong);

  ASSERT_EQ(scene.objects.size(), 1u);
  EXPECT_EQ(scene.objects[0].name, "object 0");
  EXPECT_EQ(scene.objects[0].mesh.kind, MeshKind::Plane);
  EXPECT_EQ(scene.objects[0].mesh.size, glm::vec2(2.0f));
  EXPECT_EQ(scene.objects[0].material, "rock");
  EXPECT_EQ(scene.objects[0].transform.scale, glm::vec3(1.0f));
  EXPECT_EQ(scene.find_material("rock"), &scene.materials[0]);
}

TEST(SceneLoader, FullSceneRoundTrip) {
  const json document = json::parse(R"({
    "comment": "every field set",
    "output": {"width": 640, "height": 480, "background": [0.1, 0.2, 0.3]},
    "camera": {"position": [1, 2, 3], "target": [0, 0, 1], "up": [0, 0, 1], "fov_deg": 30, "near": 0.1, "far": 50},
    "lights": [
      {"type": "directional", "direction": [0, 0, 2], "color": [1, 0.9, 0.8], "intensity": 2},
      {"type": "ambient", "color": [0.5, 0.5, 1], "intensity": 0.1, "comment": "sky"}
    ],
    "materials": {
      "bricks": {
        "layers": [{
          "albedo": {"procedural": "bricks", "size": 256, "seed": 7, "cells": 4, "mortar": 0.1,
                     "color_low": [0.1, 0.1, 0.1], "color_high": [0.9, 0.5, 0.4], "variation": 0.3},
          "normal_convention": "dx", "normal_strength": 0.5,
          "height": {"procedural": "noise", "octaves": 3, "gain": 0.6},
          "height_scale": 0.8, "height_offset": 0.1
        }, {
          "albedo": {"constant": [0.2, 0.3, 0.4, 0.5]},
          "height": {"constant": 0.25}
        }],
        "technique": {"name": "normal", "depth_scale": 0.08},
        "sampling": {"filter": "point", "address": "mirror", "lod_bias": -0.5},
        "lighting": {"model": "blinn_phong", "specular": 0.5, "shininess": 64}
      }
    },
    "objects": [
      {"name": "wall", "mesh": {"type": "plane", "size": [4, 2], "uv_scale": [2, 1]}, "material": "bricks",
       "transform": {"translate": [0, 1, 0], "rotate_deg": [90, 0, 0], "scale": 2}},
      {"mesh": {"type": "box", "size": 0.5, "uv_scale": 3}, "material": "bricks",
       "transform": {"scale": [1, 2, -1]}},
      {"mesh": {"type": "sphere", "size": 1.5, "segments": 16}, "material": "bricks"},
      {"mesh": {"type": "grid", "size": 8, "resolution": 128, "height_map": {"procedural": "sine"}, "height": 0.5},
       "material": "bricks"}
    ]
  })");
  const SceneDesc scene = load(document);
  EXPECT_EQ(scene.output.width, 640);
  EXPECT_EQ(scene.output.height, 480);
  EXPECT_EQ(scene.output.background, glm::vec3(0.1f, 0.2f, 0.3f));
  EXPECT_EQ(scene.camera.position, glm::vec3(1, 2, 3));
  EXPECT_FLOAT_EQ(scene.camera.fov_y_deg, 30.0f);
  EXPECT_FLOAT_EQ(scene.camera.near, 0.1f);
  EXPECT_FLOAT_EQ(scene.camera.far, 50.0f);

  ASSERT_EQ(scene.lights.directional.size(), 1u);
  EXPECT_EQ(scene.lights.directional[0].direction, glm::vec3(0, 0, 1));
  EXPECT_FLOAT_EQ(scene.lights.directional[0].intensity, 2.0f);
  EXPECT_EQ(scene.lights.ambient.color, glm::vec3(0.5f, 0.5f, 1.0f));
  EXPECT_FLOAT_EQ(scene.lights.ambient.intensity, 0.1f);

  const MaterialDesc& bricks = scene.materials.at(0);
  ASSERT_EQ(bricks.layers.size(), 2u);
  const LayerDesc& top = bricks.layers[0];
  EXPECT_EQ(top.albedo.source, TextureSource::Procedural);
  EXPECT_EQ(top.albedo.procedural.pattern, ProceduralPattern::Bricks);
  EXPECT_EQ(top.albedo.procedural.size, 256);
  EXPECT_EQ(top.albedo.procedural.seed, 7u);
  EXPECT_EQ(top.albedo.procedural.cells, 4);
  EXPECT_FLOAT_EQ(top.albedo.procedural.mortar, 0.1f);
  EXPECT_EQ(top.albedo.color_high, glm::vec3(0.9f, 0.5f, 0.4f));
  EXPECT_FLOAT_EQ(top.albedo.variation, 0.3f);
  EXPECT_EQ(top.normal.source, TextureSource::FromHeight);  // height and no normal
  EXPECT_EQ(top.normal_convention, NormalConvention::DX);
  EXPECT_FLOAT_EQ(top.normal_strength, 0.5f);
  EXPECT_EQ(top.height.procedural.pattern, ProceduralPattern::Noise);
  EXPECT_EQ(top.height.procedural.octaves, 3);
  EXPECT_FLOAT_EQ(top.height.procedural.gain, 0.6f);
  EXPECT_FLOAT_EQ(top.height_scale, 0.8f);
  EXPECT_FLOAT_EQ(top.height_offset, 0.1f);
  EXPECT_EQ(bricks.layers[1].albedo.constant, glm::vec4(0.2f, 0.3f, 0.4f, 0.5f));
  EXPECT_EQ(bricks.layers[1].height.source, TextureSource::Constant);
  EXPECT_FLOAT_EQ(bricks.layers[1].height.constant.x, 0.25f);
  EXPECT_FLOAT_EQ(bricks.technique.depth_scale, 0.08f);
  EXPECT_EQ(bricks.sampling.filter, Filter::Point);
  EXPECT_EQ(bricks.sampling.address, AddressMode::Mirror);
  EXPECT_FLOAT_EQ(bricks.sampling.lod_bias, -0.5f);
  EXPECT_FLOAT_EQ(bricks.lighting.specular, 0.5f);
  EXPECT_FLOAT_EQ(bricks.lighting.shininess, 64.0f);

  ASSERT_EQ(scene.objects.size(), 4u);
  const ObjectDesc& wall = scene.objects[0];
  EXPECT_EQ(wall.name, "wall");
  EXPECT_EQ(wall.mesh.size, glm::vec2(4, 2));
  EXPECT_EQ(wall.mesh.uv_scale, glm::vec2(2, 1));
  EXPECT_EQ(wall.transform.translate, glm::vec3(0, 1, 0));
  EXPECT_EQ(wall.transform.rotate_deg, glm::vec3(90, 0, 0));
  EXPECT_EQ(wall.transform.scale, glm::vec3(2));
  EXPECT_EQ(scene.objects[1].mesh.kind, MeshKind::Box);
  EXPECT_EQ(scene.objects[1].mesh.size, glm::vec2(0.5f));
  EXPECT_EQ(scene.objects[1].mesh.uv_scale, glm::vec2(3));
  EXPECT_EQ(scene.objects[1].transform.scale, glm::vec3(1, 2, -1));
  EXPECT_EQ(scene.objects[2].mesh.kind, MeshKind::Sphere);
  EXPECT_EQ(scene.objects[2].mesh.segments, 16);
  EXPECT_EQ(scene.objects[3].mesh.kind, MeshKind::Grid);
  EXPECT_EQ(scene.objects[3].mesh.resolution, 128);
  EXPECT_EQ(scene.objects[3].mesh.height_map.procedural.pattern, ProceduralPattern::Sine);
  EXPECT_FLOAT_EQ(scene.objects[3].mesh.height, 0.5f);
}

TEST(SceneLoader, ListedLightsReplaceTheDefaults) {
  json document = minimal_scene();
  document["lights"] = json::parse(R"([{"type": "directional"}, {"type": "directional", "direction": [1, 0, 0]}])");
  const SceneDesc scene = load(document);
  EXPECT_EQ(scene.lights.directional.size(), 2u);
  EXPECT_FLOAT_EQ(scene.lights.ambient.intensity, 0.0f);
  document["lights"] = json::array();
  EXPECT_TRUE(load(document).lights.directional.empty());
}

TEST(SceneLoader, CommentsAreIgnoredAtEveryObjectLevel) {
  json document = minimal_scene();
  document["comment"] = "top";
  document["materials"]["comment"] = "not a material";
  document["materials"]["rock"]["comment"] = {{"any", "json"}};
  document["materials"]["rock"]["layers"][0]["comment"] = 1;
  document["objects"][0]["mesh"]["comment"] = "flat";
  const SceneDesc scene = load(document);
  EXPECT_EQ(scene.materials.size(), 1u);
}

TEST(SceneLoader, UnknownKeysSuggestTheClosestKey) {
  json document = minimal_scene();
  document["output"] = {{"widht", 5}};
  EXPECT_EQ(load_error(document), "scene.json: /output: unknown key 'widht'; did you mean 'width'?");

  document = minimal_scene();
  document["objetcs"] = json::array();
  EXPECT_EQ(load_error(document), "scene.json: /: unknown key 'objetcs'; did you mean 'objects'?");

  document = minimal_scene();
  document["camera"] = {{"pos", json::array({0, 0, 1})}};
  EXPECT_EQ(load_error(document), "scene.json: /camera: unknown key 'pos'; did you mean 'position'?");

  document = minimal_scene();
  document["materials"]["rock"]["sampling"] = {{"zzzz", 1}};
  EXPECT_EQ(load_error(document),
            "scene.json: /materials/rock/sampling: unknown key 'zzzz'; valid keys are: filter, address, precision, lod, lod_bias, min_lod, max_lod, math");
}

TEST(SceneLoader, KeysDependOnTheMeshType) {
  json document = minimal_scene();
  document["objects"][0]["mesh"]["segmnets"] = 8;
  EXPECT_EQ(load_error(document),
            "scene.json: /objects/0/mesh: unknown key 'segmnets'; valid keys are: type, size, uv_scale");
  document["objects"][0]["mesh"]["type"] = "sphere";
  EXPECT_EQ(load_error(document), "scene.json: /objects/0/mesh: unknown key 'segmnets'; did you mean 'segments'?");
  document["objects"][0]["mesh"] = {{"type", "cube"}};
  EXPECT_EQ(load_error(document),
            "scene.json: /objects/0/mesh/type: unknown value 'cube'; expected one of: plane, box, sphere, grid, obj, gltf");
  document["objects"][0]["mesh"] = json::object();
  EXPECT_EQ(load_error(document), "scene.json: /objects/0/mesh: missing key 'type' (plane, box, sphere, grid, obj or gltf)");
}

TEST(SceneLoader, WrongTypesNameTheExpectedType) {
  json document = minimal_scene();
  document["camera"] = {{"fov_deg", "wide"}};
  EXPECT_EQ(load_error(document), "scene.json: /camera/fov_deg: expected a number, got string");
  document = minimal_scene();
  document["objects"] = json::object();
  EXPECT_EQ(load_error(document), "scene.json: /objects: expected an array, got object");
  document = minimal_scene();
  document["output"] = {{"background", json::array({1, 2})}};
  EXPECT_EQ(load_error(document), "scene.json: /output/background: expected an array of 3 numbers, got an array of 2");
  document["output"] = {{"background", json::array({1, "2", 3})}};
  EXPECT_EQ(load_error(document), "scene.json: /output/background/1: expected a number, got string");
  document = minimal_scene();
  document["objects"][0]["material"] = 3;
  EXPECT_EQ(load_error(document), "scene.json: /objects/0/material: expected a string, got number");
  document = json::array();
  EXPECT_EQ(load_error(document), "scene.json: /: expected an object, got array");
}

TEST(SceneLoader, MissingRequiredKeys) {
  json document = minimal_scene();
  document.erase("objects");
  EXPECT_EQ(load_error(document), "scene.json: /: missing key 'objects'");
  document = minimal_scene();
  document["materials"]["rock"].erase("layers");
  EXPECT_EQ(load_error(document), "scene.json: /materials/rock: missing key 'layers'");
}

TEST(SceneLoader, OutputSizeLimits) {
  json document = minimal_scene();
  document["output"] = {{"width", 0}};
  EXPECT_EQ(load_error(document), "scene.json: /output/width: must be an integer from 1 to 16384, got 0");
  document["output"] = {{"height", 16385}};
  EXPECT_EQ(load_error(document), "scene.json: /output/height: must be an integer from 1 to 16384, got 16385");
  document["output"] = {{"width", 640.5}};
  EXPECT_EQ(load_error(document), "scene.json: /output/width: expected an integer, got 640.5");
  document["output"] = {{"width", 640.0}};
  EXPECT_EQ(load(document).output.width, 640);
}

TEST(SceneLoader, NumbersMustBeFiniteFloats) {
  json document = minimal_scene();
  document["camera"] = {{"far", 1e39}};
  EXPECT_EQ(load_error(document), "scene.json: /camera/far: expected a finite number, got 1e+39");
  document["camera"] = {{"far", std::nan("")}};  // a json value can hold NaN even though the text format cannot
  EXPECT_EQ(load_error(document), "scene.json: /camera/far: expected a finite number, got nan");
}

TEST(SceneLoader, CameraChecks) {
  json document = minimal_scene();
  document["camera"] = {{"position", {1, 1, 1}}, {"target", {1, 1, 1}}};
  EXPECT_EQ(load_error(document), "scene.json: /camera/target: the target must differ from the position");
  document["camera"] = {{"position", {0, 0, 5}}, {"target", {0, 0, 0}}};
  EXPECT_EQ(load_error(document),
            "scene.json: /camera: the up vector must not be parallel to the view direction (target - position)");
  document["camera"] = {{"up", {0, 0, 0}}};
  EXPECT_EQ(load_error(document), "scene.json: /camera/up: the up vector must not be zero");
  document["camera"] = {{"fov_deg", 180}};
  EXPECT_EQ(load_error(document), "scene.json: /camera/fov_deg: must be greater than 0 and less than 180, got 180");
  document["camera"] = {{"near", 0}};
  EXPECT_EQ(load_error(document), "scene.json: /camera/near: must be greater than 0, got 0");
  document["camera"] = {{"near", 2}, {"far", 2}};
  EXPECT_EQ(load_error(document), "scene.json: /camera/far: far (2) must be greater than near (2)");
  document["camera"] = {{"near", 2000}};
  EXPECT_EQ(load_error(document), "scene.json: /camera: far (1000) must be greater than near (2000)");
}

TEST(SceneLoader, LightChecks) {
  json document = minimal_scene();
  document["lights"] = json::parse(R"([{"type": "directional", "direction": [0, 0, 0]}])");
  EXPECT_EQ(load_error(document), "scene.json: /lights/0/direction: the direction must not be zero");
  document["lights"] = json::parse(R"([{"type": "directonal"}])");
  EXPECT_EQ(load_error(document),
            "scene.json: /lights/0/type: unknown value 'directonal'; did you mean 'directional'?");
  document["lights"] = json::parse(R"([{"type": "ambient", "color": [1, -1, 1]}])");
  EXPECT_EQ(load_error(document), "scene.json: /lights/0/color/1: must not be negative, got -1");
  document["lights"] = json::parse(R"([{"type": "ambient"}, {"type": "ambient"}])");
  EXPECT_EQ(load_error(document), "scene.json: /lights/1: only one ambient light is allowed");
  document["lights"] = json::parse(R"([{"type": "ambient", "direction": [0, 0, 1]}])");
  EXPECT_EQ(load_error(document),
            "scene.json: /lights/0: unknown key 'direction'; valid keys are: type, color, intensity");
  document["lights"] = json::array();
  for (int i = 0; i <= 4; ++i) document["lights"].push_back({{"type", "directional"}});
  EXPECT_EQ(load_error(document), "scene.json: /lights/4: at most 4 directional lights are supported");
}

TEST(SceneLoader, MaterialChecks) {
  json document = minimal_scene();
  document["materials"]["rock"]["layers"] = json::array();
  EXPECT_EQ(load_error(document), "scene.json: /materials/rock/layers: expected 1 to 4 layers, got 0");
  document["materials"]["rock"]["layers"] = json(std::vector<json>(5, json::object()));
  EXPECT_EQ(load_error(document), "scene.json: /materials/rock/layers: expected 1 to 4 layers, got 5");
  document = minimal_scene();
  document["materials"]["rock"]["sampling"] = {{"filter", "pont"}};
  EXPECT_EQ(load_error(document),
            "scene.json: /materials/rock/sampling/filter: unknown value 'pont'; did you mean 'point'?");
  document = minimal_scene();
  document["materials"]["rock"]["technique"] = {{"depth_scale", -0.1}};
  EXPECT_EQ(load_error(document),
            "scene.json: /materials/rock/technique/depth_scale: must be from 0 to 100, got -0.1");
  document = minimal_scene();
  document["materials"]["a/b"] = document["materials"]["rock"];
  document["materials"]["a/b"]["lighting"] = {{"shininess", 0}};
  EXPECT_EQ(load_error(document), "scene.json: /materials/a~1b/lighting/shininess: must be greater than 0, got 0");
}

TEST(SceneLoader, ObjectsReferenceExistingMaterials) {
  json document = minimal_scene();
  document["objects"][0]["material"] = "rok";
  EXPECT_EQ(load_error(document), "scene.json: /objects/0/material: unknown material 'rok'; did you mean 'rock'?");
  document["objects"][0]["material"] = "marble";
  EXPECT_EQ(load_error(document),
            "scene.json: /objects/0/material: unknown material 'marble'; defined materials are: rock");
  document["materials"] = json::object();
  EXPECT_EQ(load_error(document),
            "scene.json: /objects/0/material: unknown material 'marble'; no materials are defined");
  document["objects"][0].erase("material");
  EXPECT_EQ(load_error(document),
            "scene.json: /objects/0: missing key 'material' (only obj and gltf meshes may leave it out to use their "
            "own materials)");
}

TEST(SceneLoader, HeightNormalDefaultsAndTextureForms) {
  json document = minimal_scene();
  json& layer = document["materials"]["rock"]["layers"][0];
  layer = {{"height", {{"procedural", "cobbles"}}}};
  EXPECT_EQ(load(document).materials[0].layers[0].normal.source, TextureSource::FromHeight);
  layer = {{"height", {{"procedural", "cobbles"}}}, {"normal", "from_height"}};
  EXPECT_EQ(load(document).materials[0].layers[0].normal.source, TextureSource::FromHeight);
  layer = {{"albedo", {{"constant", 0.5}}}};
  EXPECT_EQ(load(document).materials[0].layers[0].albedo.constant, glm::vec4(0.5f, 0.5f, 0.5f, 1.0f));

  layer = {{"normal", "from_height"}};
  EXPECT_EQ(load_error(document),
            "scene.json: /materials/rock/layers/0/normal: 'from_height' needs a 'height' in the same layer");
  layer = {{"albedo", "from_height"}};
  EXPECT_EQ(load_error(document),
            "scene.json: /materials/rock/layers/0/albedo: 'from_height' is only valid for a normal map");
  layer = {{"normal", {{"procedural", "bricks"}}}};
  EXPECT_EQ(load_error(document),
            "scene.json: /materials/rock/layers/0/normal: a normal map is a file path or \"from_height\"");
  layer = {{"albedo", {{"constant", 1}, {"procedural", "noise"}}}};
  EXPECT_EQ(load_error(document),
            "scene.json: /materials/rock/layers/0/albedo: expected exactly one of the keys 'file', 'procedural' or "
            "'constant'");
  layer = {{"albedo", 3}};
  EXPECT_EQ(
      load_error(document),
      "scene.json: /materials/rock/layers/0/albedo: expected a file path or an object with 'file', 'procedural' or "
      "'constant', got number");
  layer = {{"height", {{"constant", 2}}}};
  EXPECT_EQ(load_error(document), "scene.json: /materials/rock/layers/0/height/constant: must be from 0 to 1, got 2");
  layer = {{"albedo", {{"constant", {1, 1}}}}};
  EXPECT_EQ(
      load_error(document),
      "scene.json: /materials/rock/layers/0/albedo/constant: expected a number or an array of 3 or 4 numbers, got an "
      "array of 2");
  layer = {{"height", {{"procedural", "noise"}, {"color_low", {0, 0, 0}}}}};
  EXPECT_EQ(
      load_error(document),
      "scene.json: /materials/rock/layers/0/height: unknown key 'color_low'; valid keys are: procedural, size, seed, "
      "cells, octaves, gain, mortar, waves, scroll, format, compression");
}

TEST(SceneLoader, ProceduralAndMeshRanges) {
  json document = minimal_scene();
  json& layer = document["materials"]["rock"]["layers"][0];
  layer = {{"height", {{"procedural", "noise"}, {"size", 300}}}};
  EXPECT_EQ(load_error(document), "scene.json: /materials/rock/layers/0/height/size: must be a power of two, got 300");
  layer = {{"height", {{"procedural", "noise"}, {"size", 32768}}}};
  EXPECT_EQ(load_error(document),
            "scene.json: /materials/rock/layers/0/height/size: must be an integer from 1 to 16384, got 32768");
  layer = {{"height", {{"procedural", "noies"}}}};
  EXPECT_EQ(load_error(document),
            "scene.json: /materials/rock/layers/0/height/procedural: unknown value 'noies'; did you mean 'noise'?");
  layer = json::object();

  json& object = document["objects"][0];
  object["mesh"] = {{"type", "grid"}, {"resolution", 0}};
  EXPECT_EQ(load_error(document), "scene.json: /objects/0/mesh/resolution: must be an integer from 1 to 4096, got 0");
  object["mesh"] = {{"type", "grid"}, {"resolution", 4097}};
  EXPECT_EQ(load_error(document),
            "scene.json: /objects/0/mesh/resolution: must be an integer from 1 to 4096, got 4097");
  object["mesh"] = {{"type", "sphere"}, {"segments", 2}};
  EXPECT_EQ(load_error(document), "scene.json: /objects/0/mesh/segments: must be an integer from 3 to 4096, got 2");
  object["mesh"] = {{"type", "box"}, {"size", {1, 2}}};
  EXPECT_EQ(load_error(document), "scene.json: /objects/0/mesh/size: expected a number, got array");
  object["mesh"] = {{"type", "plane"}, {"size", {1, -2}}};
  EXPECT_EQ(load_error(document), "scene.json: /objects/0/mesh/size/1: must be greater than 0, got -2");
  object["mesh"] = {{"type", "plane"}, {"uv_scale", 0}};
  EXPECT_EQ(load_error(document), "scene.json: /objects/0/mesh/uv_scale: must not be 0");
  object["mesh"] = {{"type", "plane"}};
  object["transform"] = {{"scale", {1, 0, 1}}};
  EXPECT_EQ(load_error(document), "scene.json: /objects/0/transform/scale/1: must not be 0");
  object["transform"] = {{"scale", 0}};
  EXPECT_EQ(load_error(document), "scene.json: /objects/0/transform/scale: must not be 0");
}

}  // namespace
}  // namespace qdmr

namespace qdmr {
namespace {

TEST(SceneLoader, SamplingAndHeightStorageSettings) {
  nlohmann::json document = nlohmann::json::parse(R"({
    "materials": {"rock": {"layers": [{"height": {"procedural": "noise", "format": "r8", "compression": "bc3"}}],
                           "sampling": {"filter": "point_mip_linear", "address": "mirror", "precision": "hw6",
                                        "lod": "per_pixel", "lod_bias": -0.5, "min_lod": 1, "max_lod": 3, "math": "sm3"}}},
    "objects": [{"mesh": {"type": "plane"}, "material": "rock"}]})");
  const SceneDesc scene = load_scene_json(document, "scene.json", ".");
  const MaterialDesc& m = scene.materials.at(0);
  EXPECT_EQ(m.sampling.filter, Filter::PointMipLinear);
  EXPECT_EQ(m.sampling.address, AddressMode::Mirror);
  EXPECT_EQ(m.sampling.precision, SamplePrecision::Hw6);
  EXPECT_EQ(m.sampling.lod, LodMode::PerPixel);
  EXPECT_EQ(m.sampling.lod_bias, -0.5f);
  EXPECT_EQ(m.sampling.min_lod, 1.0f);
  EXPECT_EQ(m.sampling.max_lod, 3.0f);
  EXPECT_EQ(m.sampling.math, MathMode::Sm3);
  EXPECT_EQ(m.layers.at(0).height.format, TextureFormatChoice::R8);
  EXPECT_EQ(m.layers.at(0).height.compression, Compression::Bc3);

  document["materials"]["rock"]["sampling"]["max_lod"] = 0.5;
  EXPECT_THROW(load_scene_json(document, "scene.json", "."), Error);
  document["materials"]["rock"]["sampling"].erase("max_lod");
  document["materials"]["rock"]["layers"][0]["height"]["format"] = "r16";
  try {
    load_scene_json(document, "scene.json", ".");
    FAIL() << "bc3 with r16 accepted";
  } catch (const Error& e) {
    EXPECT_STREQ(e.what(), "scene.json: /materials/rock/layers/0/height/compression: bc3 stores 8-bit heights: use format r8 or auto");
  }
}

}  // namespace
}  // namespace qdmr
