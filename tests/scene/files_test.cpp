// Reading scene files and resolving the paths they name.
#include <gtest/gtest.h>

#include "qdmr/mesh/mesh.hpp"
#include "scene/scene_test_util.hpp"
#include "support/test_support.hpp"

namespace qdmr {
namespace {

namespace fs = std::filesystem;
using nlohmann::json;

std::string file_error(const fs::path& file, const std::vector<SceneOverride>& overrides = {}) {
  try {
    load_scene(file, overrides);
  } catch (const Error& e) {
    return e.what();
  }
  return "no error";
}

TEST(SceneFiles, LoadsAFileWithOverrides) {
  test::TempDir dir;
  test::write_file(dir / "scene.json", test::minimal_scene().dump());
  const SceneDesc scene = load_scene(dir / "scene.json", {parse_override("/objects/0/mesh/type=box")});
  EXPECT_EQ(scene.file, dir / "scene.json");
  EXPECT_EQ(scene.objects.at(0).mesh.kind, MeshKind::Box);
}

TEST(SceneFiles, MissingFileAndDirectory) {
  test::TempDir dir;
  const fs::path missing = dir / "nope.json";
  EXPECT_EQ(file_error(missing), missing.string() + ": file not found");
  EXPECT_EQ(file_error(dir.path()), dir.path().string() + ": is a directory, not a file");
}

TEST(SceneFiles, ParseErrorGivesLineAndColumn) {
  test::TempDir dir;
  const fs::path file = dir / "broken.json";
  test::write_file(file, "{\n  \"objects\": [],\n}\n");
  const std::string message = file_error(file);
  EXPECT_EQ(message.rfind(file.string() + ": parse error at line 3, column 1: ", 0), 0u) << message;
}

TEST(SceneFiles, ErrorsNameTheFileAsGiven) {
  test::TempDir dir;
  json document = test::minimal_scene();
  document["camera"] = {{"fov_deg", -1}};
  test::write_file(dir / "scene.json", document.dump());
  EXPECT_EQ(file_error(dir / "scene.json"),
            (dir / "scene.json").string() + ": /camera/fov_deg: must be greater than 0 and less than 180, got -1");
}

TEST(SceneFiles, PathsResolveAgainstTheSceneDirectory) {
  test::TempDir dir;
  fs::create_directories(dir / "scenes" / "textures");
  test::write_file(dir / "scenes" / "textures" / "rock_h.png", "not really a png");
  test::write_file(dir / "scenes" / "textures" / "rock_a.png", "");
  // Loading reads the OBJ: one triangle without a material (it gets the OBJ's "default" material).
  test::write_file(dir / "model.obj", "v 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 3\n");
  json document = test::minimal_scene();
  document["materials"]["rock"]["layers"][0] = {
      {"albedo", {{"file", "textures/rock_a.png"}, {"srgb", false}}},
      {"height", {{"file", "textures/../textures/rock_h.png"}, {"channel", "g"}}}};
  document["objects"].push_back({{"mesh", {{"type", "obj"}, {"file", "../model.obj"}}}});
  test::write_file(dir / "scenes" / "scene.json", document.dump());

  const SceneDesc scene = load_scene(dir / "scenes" / "scene.json");
  const LayerDesc& layer = scene.materials.at(0).layers.at(0);
  const fs::path root = fs::absolute(dir.path()).lexically_normal();
  EXPECT_EQ(layer.albedo.source, TextureSource::File);
  EXPECT_EQ(layer.albedo.file, root / "scenes" / "textures" / "rock_a.png");
  EXPECT_FALSE(layer.albedo.srgb);
  EXPECT_EQ(layer.height.file, root / "scenes" / "textures" / "rock_h.png");
  EXPECT_EQ(layer.height.channel, Channel::G);
  EXPECT_EQ(layer.normal.source, TextureSource::FromHeight);
  EXPECT_EQ(scene.objects.at(1).mesh.file, root / "model.obj");
  EXPECT_TRUE(scene.objects.at(1).material.empty());
  // The OBJ is read when the scene is loaded, and its materials join the scene's, after them.
  ASSERT_TRUE(scene.objects.at(1).obj_mesh);
  EXPECT_EQ(scene.objects.at(1).obj_mesh->triangle_count(), 1u);
  EXPECT_EQ(scene.objects.at(1).mtl_materials, std::vector<std::string>{"object 1/default"});
  EXPECT_EQ(scene.materials.back().name, "object 1/default");

  // The same document in memory, resolved against an explicit base directory; absolute paths stay as they are.
  document["materials"]["rock"]["layers"][0]["albedo"] = (root / "scenes" / "textures" / "rock_a.png").string();
  const SceneDesc in_memory = load_scene_json(document, "mem.json", dir / "scenes");
  EXPECT_EQ(in_memory.materials.at(0).layers.at(0).albedo.file, root / "scenes" / "textures" / "rock_a.png");
  EXPECT_EQ(in_memory.materials.at(0).layers.at(0).height.file, root / "scenes" / "textures" / "rock_h.png");
}

TEST(SceneFiles, MissingTextureOrMeshFile) {
  test::TempDir dir;
  json document = test::minimal_scene();
  document["materials"]["rock"]["layers"][0] = {{"height", {{"file", "h.png"}}}};
  const fs::path expected = fs::absolute(dir / "h.png").lexically_normal();
  EXPECT_EQ(test::load_error(document, {}, dir.path()),
            "scene.json: /materials/rock/layers/0/height/file: file not found: " + expected.string());

  document = test::minimal_scene();
  document["objects"][0] = {{"mesh", {{"type", "obj"}, {"file", ""}}}};
  EXPECT_EQ(test::load_error(document, {}, dir.path()),
            "scene.json: /objects/0/mesh/file: expected a file path, got an empty string");
  document["objects"][0]["mesh"]["file"] = ".";
  EXPECT_EQ(test::load_error(document, {}, dir.path()),
            "scene.json: /objects/0/mesh/file: is a directory, not a file: " +
                fs::absolute(dir.path()).lexically_normal().string());
}

TEST(SceneFiles, HeightFilesReadOneChannel) {
  test::TempDir dir;
  test::write_file(dir / "h.png", "");
  json document = test::minimal_scene();
  document["materials"]["rock"]["layers"][0] = {{"height", {{"file", "h.png"}, {"channel", "rgb"}}}};
  EXPECT_EQ(test::load_error(document, {}, dir.path()),
            "scene.json: /materials/rock/layers/0/height/channel: a height reads one channel: r, g, b or a");
  document["materials"]["rock"]["layers"][0] = {{"height", {{"file", "h.png"}, {"srgb", true}}}};
  EXPECT_EQ(test::load_error(document, {}, dir.path()),
            "scene.json: /materials/rock/layers/0/height: unknown key 'srgb'; valid keys are: file, frames, channel, format, compression");
}

}  // namespace
}  // namespace qdmr
