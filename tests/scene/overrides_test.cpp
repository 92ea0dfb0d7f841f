// --set overrides: parsing POINTER=VALUE and applying it to the document before validation.
#include <gtest/gtest.h>

#include "scene/scene_test_util.hpp"

namespace qdmr {
namespace {

using nlohmann::json;
using test::load_error;
using test::minimal_scene;

SceneDesc load(const json& document, const std::vector<SceneOverride>& overrides) {
  return load_scene_json(document, "scene.json", ".", overrides);
}

std::string parse_error(std::string_view text) {
  try {
    parse_override(text);
  } catch (const Error& e) {
    return e.what();
  }
  return "no error";
}

TEST(SceneOverride, ParseSplitsAtTheFirstEquals) {
  const SceneOverride o = parse_override("/objects/0/name=a=b");
  EXPECT_EQ(o.pointer, "/objects/0/name");
  EXPECT_EQ(o.value, "a=b");
  EXPECT_EQ(parse_override("/camera/fov_deg=").value, "");
}

TEST(SceneOverride, ParseRejectsMalformedText) {
  EXPECT_EQ(parse_error("/camera/fov_deg"), "--set '/camera/fov_deg': expected POINTER=VALUE, e.g. /camera/fov_deg=30");
  EXPECT_EQ(parse_error("camera/fov_deg=3"),
            "--set 'camera/fov_deg=3': the JSON pointer must start with '/', e.g. /camera/fov_deg=30");
  EXPECT_EQ(parse_error("/a~2=3"),
            "--set '/a~2=3': invalid JSON pointer '/a~2' ('~' must be written ~0, '/' in a key ~1)");
}

TEST(SceneOverride, SetsAnExistingValue) {
  json document = minimal_scene();
  document["camera"] = {{"fov_deg", 45}};
  EXPECT_FLOAT_EQ(load(document, {parse_override("/camera/fov_deg=30")}).camera.fov_y_deg, 30.0f);
  // Later overrides win.
  EXPECT_FLOAT_EQ(load(document, {{"/camera/fov_deg", "30"}, {"/camera/fov_deg", "60"}}).camera.fov_y_deg, 60.0f);
}

TEST(SceneOverride, AddsANewKeyToAnExistingObject) {
  const SceneDesc scene = load(minimal_scene(), {{"/output", R"({"width": 320, "height": 200})"},
                                                 {"/materials/rock/sampling", "{}"},
                                                 {"/materials/rock/sampling/filter", R"("point")"}});
  EXPECT_EQ(scene.output.width, 320);
  EXPECT_EQ(scene.materials[0].sampling.filter, Filter::Point);
}

TEST(SceneOverride, ValueThatIsNotJsonIsAString) {
  const SceneDesc scene = load(minimal_scene(), {{"/materials/rock/sampling", "{}"},
                                                 {"/materials/rock/sampling/address", "clamp"},
                                                 {"/objects/0/name", "my wall"}});
  EXPECT_EQ(scene.materials[0].sampling.address, AddressMode::Clamp);
  EXPECT_EQ(scene.objects[0].name, "my wall");
}

TEST(SceneOverride, DashAppendsToAnArray) {
  const SceneDesc scene =
      load(minimal_scene(), {{"/objects/-", R"({"name": "ball", "mesh": {"type": "sphere"}, "material": "rock"})"}});
  ASSERT_EQ(scene.objects.size(), 2u);
  EXPECT_EQ(scene.objects[1].name, "ball");
  EXPECT_EQ(load(minimal_scene(), {{"/objects/0/mesh/type", "box"}}).objects[0].mesh.kind, MeshKind::Box);
}

TEST(SceneOverride, MissingOptionalBlocksAreCreated) {
  const SceneDesc scene = load(minimal_scene(), {{"/camera/fov_deg", "30"},
                                                  {"/materials/rock/sampling/filter", "point"},
                                                  {"/materials/rock/technique/name", "qdm"}});
  EXPECT_EQ(scene.camera.fov_y_deg, 30.0f);
  EXPECT_EQ(scene.materials[0].sampling.filter, Filter::Point);
  EXPECT_EQ(scene.materials[0].technique.kind, TechniqueKind::Qdm);
  // What is created is validated like the file: a misspelt block is reported with a suggestion.
  EXPECT_EQ(load_error(minimal_scene(), {{"/camra/fov_deg", "30"}}), "scene.json: /: unknown key 'camra'; did you mean 'camera'?");
}

TEST(SceneOverride, BadPointersAreErrorsNamingThePointer) {
  EXPECT_EQ(
      load_error(minimal_scene(), {{"/objects/3", "{}"}}),
      "scene.json: /objects/3: cannot apply --set: no element '3' in /objects (it has 1 elements; use '-' to append)");
  EXPECT_EQ(
      load_error(minimal_scene(), {{"/objects/x", "{}"}}),
      "scene.json: /objects/x: cannot apply --set: no element 'x' in /objects (it has 1 elements; use '-' to append)");
  EXPECT_EQ(
      load_error(minimal_scene(), {{"/objects/0/material/x", "1"}}),
      "scene.json: /objects/0/material/x: cannot apply --set: /objects/0/material is a string, not an object or array");
}

TEST(SceneOverride, OverriddenValuesAreValidated) {
  EXPECT_EQ(
      load_error(minimal_scene(), {{"/objects/0/mesh/type", "cylinder"}}),
      "scene.json: /objects/0/mesh/type: unknown value 'cylinder'; expected one of: plane, box, sphere, grid, obj, gltf");
  EXPECT_EQ(load_error(minimal_scene(), {{"/objects/0/materal", "rock"}}),
            "scene.json: /objects/0: unknown key 'materal'; did you mean 'material'?");
}

TEST(SceneOverride, TheGivenDocumentIsNotModified) {
  const json document = minimal_scene();
  load(document, {{"/objects/-", R"({"mesh": {"type": "box"}, "material": "rock"})"}});
  EXPECT_EQ(document, minimal_scene());
}

}  // namespace
}  // namespace qdmr
