// glTF 2.0 through the command (the assets of tests/gltf, see make_assets.py): the same quad as OBJ + MTL and as
// glTF renders the same bits; a glTF material displaced from the scene marches (iterations, a height texture in
// the stats); `qdmr render model.glb` needs no scene file and --set reaches its materials; `qdmr plan` lists the
// mesh, materials and the warnings of what is ignored.
#include <gtest/gtest.h>

#include <algorithm>
#include <set>
#include <string>

#include <nlohmann/json.hpp>

#include "cli/cli_test_util.hpp"

namespace qdmr::test {
namespace {

std::filesystem::path gltf_dir() { return source_dir() / "tests/gltf"; }

CommandResult qdmr(std::vector<std::string> args) { return run(cli(), args); }

// The quad as OBJ + MTL and as glTF; and a glTF material with baseColorFactor over its texture and metal
// (quad_tinted_gltf) against the OBJ quad with the qdmr material it maps to (quad_tinted_obj: albedo factor,
// Cook-Torrance F0 and roughness, written by make_assets.py).
TEST(CliGltf, TheSameQuadAsObjAndAsGltfRendersTheSameBits) {
  TempDir dir;
  for (const auto& [obj_scene, gltf_scene] : {std::pair{"quad_obj", "quad_gltf"}, std::pair{"quad_tinted_obj", "quad_tinted_gltf"}}) {
    for (const std::string name : {obj_scene, gltf_scene}) {
      const CommandResult r = qdmr({"render", (gltf_dir() / (name + ".json")).string(), "-o", (dir / (name + ".exr")).string(),
                                    "--aov", "normal=" + (dir / (name + "_n.exr")).string(), "--aov",
                                    "uv=" + (dir / (name + "_uv.exr")).string()});
      ASSERT_EQ(r.exit_code, 0) << r.output;
    }
    for (const char* suffix : {".exr", "_n.exr", "_uv.exr"}) {
      const std::string obj = read_file(dir / (obj_scene + std::string(suffix)));
      const std::string gltf = read_file(dir / (gltf_scene + std::string(suffix)));
      EXPECT_FALSE(obj.empty());
      EXPECT_TRUE(obj == gltf) << gltf_scene << suffix << ": the OBJ and the glTF quad differ";
    }
  }
  // The tint shows: the tinted quad is not the plain one.
  EXPECT_NE(read_file(dir / "quad_gltf.exr"), read_file(dir / "quad_tinted_gltf.exr"));
}

// golden.gltf_assets checks what its name says: every asset make_assets.py writes that qdmr draws (sparse.gltf
// is refused: Gltf.SparseAccessorsAreRefused), on its own, and every scene of tests/gltf, is one of its checks;
// and its checks render under every draw kernel ("isa": "all").
TEST(CliGltf, TheGoldenManifestChecksEveryAssetAndScene) {
  const nlohmann::json manifest = nlohmann::json::parse(read_file(source_dir() / "tests/golden/gltf_assets.json"));
  std::set<std::string> checked;
  for (const auto& check : manifest["checks"]) checked.insert(check["scene"].get<std::string>());
  EXPECT_EQ(manifest["defaults"]["variants"], nlohmann::json::parse(R"([{"isa": "all"}])"));
  std::vector<std::string> expected;
  for (const auto& entry : std::filesystem::directory_iterator(gltf_dir() / "assets")) {
    const std::string name = entry.path().filename().string(), ext = entry.path().extension().string();
    if ((ext == ".gltf" || ext == ".glb") && name != "sparse.gltf") expected.push_back("../gltf/assets/" + name);
  }
  for (const auto& entry : std::filesystem::directory_iterator(gltf_dir()))
    if (entry.path().extension() == ".json") expected.push_back("../gltf/" + entry.path().filename().string());
  EXPECT_GE(expected.size(), 12u);
  for (const std::string& scene : expected) EXPECT_TRUE(checked.count(scene)) << scene << " is not checked";
}

TEST(CliGltf, AGltfMaterialDisplacedFromTheSceneMarches) {
  TempDir dir;
  const CommandResult r = qdmr({"render", (gltf_dir() / "displaced.json").string(), "-o", (dir / "a.png").string(),
                                "--stats", (dir / "stats.json").string()});
  ASSERT_EQ(r.exit_code, 0) << r.output;
  const nlohmann::json stats = nlohmann::json::parse(read_file(dir / "stats.json"));
  EXPECT_GT(stats["iterations"]["max"].get<double>(), 0.0);
  EXPECT_TRUE(stats_have_texture(stats, "'wall/bricks'", "height")) << stats["textures"].dump(1);
  EXPECT_TRUE(stats_have_texture(stats, "'wall/bricks'", "albedo"));
  EXPECT_TRUE(stats_have_texture(stats, "'wall/bricks'", "normal"));  // the glTF normalTexture, not from the height
  // --set reaches the override: normal mapping marches nothing.
  const CommandResult flat = qdmr({"render", (gltf_dir() / "displaced.json").string(), "-o", (dir / "b.png").string(),
                                   "--stats", (dir / "stats_flat.json").string(), "--set",
                                   "/objects/0/materials/bricks/technique/name=normal"});
  ASSERT_EQ(flat.exit_code, 0) << flat.output;
  EXPECT_EQ(nlohmann::json::parse(read_file(dir / "stats_flat.json"))["iterations"]["max"].get<double>(), 0.0);
}

// The override in the documented form (layers[0].height, displaced_layers.json) renders the bits of the shorthand
// (displaced.json: golden.gltf_assets gives both one hash); --set reaches layers[0]; mixing the forms, a second
// layer or a key a glTF override has not is one error line naming it, exit 2, nothing written.
TEST(CliGltf, TheOverridesLayerIsSetAndItsMistakesAreNamed) {
  TempDir dir;
  const std::string scene = (gltf_dir() / "displaced_layers.json").string();
  const auto render = [&](const std::string& out, std::vector<std::string> sets) {
    std::vector<std::string> args = {"render", scene, "-o", (dir / out).string()};
    for (const std::string& s : sets) args.insert(args.end(), {"--set", s});
    return qdmr(args);
  };
  ASSERT_EQ(render("a.png", {}).exit_code, 0);
  const CommandResult halved = render("b.png", {"/objects/0/materials/bricks/layers/0/height_scale=0.5"});
  ASSERT_EQ(halved.exit_code, 0) << halved.output;
  EXPECT_NE(read_file(dir / "a.png"), read_file(dir / "b.png"));  // half the relief: another image
  const std::string at = scene + ": /objects/0/materials/bricks";
  const std::vector<std::pair<std::string, std::string>> mistakes = {
      {"/objects/0/materials/bricks/height=assets/wall_height.png",
       at + "/height: give 'height' in 'layers'[0] or beside 'technique', not both"},
      {"/objects/0/materials/bricks/layers/-={}",
       at + "/layers: a glTF material has one layer: 'layers' takes one element, not 2 (it cannot become a blend; a "
            "blend is a scene material named by the object's 'material')"},
      {"/objects/0/materials/bricks/layers/0/albedo=a.png", at + "/layers/0: unknown key 'albedo'"},
  };
  for (const auto& [set, error] : mistakes) {
    const CommandResult r = render("c.png", {set});
    EXPECT_EQ(r.exit_code, 2) << set;
    EXPECT_NE(r.output.find(error), std::string::npos) << set << "\n" << r.output;
    EXPECT_FALSE(std::filesystem::exists(dir / "c.png")) << set;
  }
}

// A glTF material with a metallic-roughness and an occlusion texture (quad_orm.gltf: its `orm` and `occlusion`)
// overridden into 2, 3 or 4 layers is refused, not drawn with its ORM dropped: one line naming the scene and the
// field, exit 2, nothing written. A blend is a scene material, whose layers cannot carry an `orm` either (the
// blend programs sample each layer's albedo, normal and height, no ORM): the same promise, its own line.
TEST(CliGltf, AnOrmMaterialIsNotBlended) {
  TempDir dir;
  const std::string scene = (gltf_dir() / "displaced_orm.json").string();
  const auto render = [&](const std::string& set) {
    return qdmr({"render", scene, "-o", (dir / "c.png").string(), "--set", set});
  };
  ASSERT_EQ(qdmr({"render", scene, "-o", (dir / "one.png").string()}).exit_code, 0);  // one layer: drawn
  for (int count = 2; count <= 4; ++count) {
    nlohmann::json layers = nlohmann::json::array();
    for (int i = 0; i < count; ++i) layers.push_back({{"height", "assets/wall_height.png"}});
    const nlohmann::json material = {{"layers", layers}, {"technique", {{"name", "qdm"}, {"depth_scale", 0.08}}}};
    const CommandResult r = render("/objects/0/materials/checker=" + material.dump());
    EXPECT_EQ(r.exit_code, 2) << count;
    EXPECT_NE(r.output.find(scene + ": /objects/0/materials/checker/layers: a glTF material has one layer: 'layers' "
                                    "takes one element, not " + std::to_string(count) + " (it cannot become a blend"),
              std::string::npos)
        << r.output;
    EXPECT_EQ(std::count(r.output.begin(), r.output.end(), '\n'), 1) << r.output;  // one line
    EXPECT_FALSE(std::filesystem::exists(dir / "c.png")) << count;
  }
  // The scene material way: a blend whose layer names the asset's ORM texture.
  const nlohmann::json blend = {
      {"layers", {{{"albedo", "assets/checker.png"}, {"height", "assets/wall_height.png"}, {"orm", "assets/orm.png"}},
                  {{"albedo", "assets/white.png"}, {"height", "assets/wall_height.png"}}}},
      {"technique", {{"name", "qdm"}, {"depth_scale", 0.08}}}};
  const nlohmann::json object = {
      {"name", "quad"}, {"mesh", {{"type", "gltf"}, {"file", "assets/quad_orm.gltf"}}}, {"material", "blend"}};
  const CommandResult r = qdmr({"render", scene, "-o", (dir / "c.png").string(), "--set", "/materials/blend=" + blend.dump(),
                                "--set", "/objects/0=" + object.dump()});
  EXPECT_EQ(r.exit_code, 2);
  EXPECT_NE(r.output.find(scene + ": /materials/blend/layers/0/orm: an orm texture is read on a material of one layer, "
                                  "not on a blend"),
            std::string::npos)
      << r.output;
  EXPECT_FALSE(std::filesystem::exists(dir / "c.png"));
}

// --max-memory reaches the glTF reader: 5000 nodes drawing the quad (1.07 MiB of drawn copies) are refused under
// 1 MiB when the scene is loaded, before they are read (tests/mesh/gltf_test.cpp counts them).
TEST(CliGltf, MaxMemoryBoundsTheDrawnCopies) {
  TempDir dir;
  for (const char* f : {"quad.bin", "checker.png"}) std::filesystem::copy_file(gltf_dir() / "assets" / f, dir / f);
  nlohmann::json doc = nlohmann::json::parse(read_file(gltf_dir() / "assets/quad.gltf"));
  doc["nodes"] = nlohmann::json::array({{{"children", nlohmann::json::array()}}});
  for (int n = 1; n <= 5000; ++n) {
    doc["nodes"].push_back({{"mesh", 0}});
    doc["nodes"][0]["children"].push_back(n);
  }
  write_file(dir / "many.gltf", doc.dump());
  const CommandResult r = qdmr({"render", (dir / "many.gltf").string(), "-o", (dir / "x.png").string(), "--max-memory", "1"});
  EXPECT_EQ(r.exit_code, 2);
  EXPECT_NE(r.output.find("the drawn meshes (a mesh drawn by several nodes once per node) take 2 MiB, more than the "
                          "limit of 1 MiB (--max-memory)"),
            std::string::npos)
      << r.output;
  EXPECT_FALSE(std::filesystem::exists(dir / "x.png"));
}

TEST(CliGltf, AnAssetRendersWithoutASceneFile) {
  TempDir dir;
  const std::string wall = (source_dir() / "scenes/assets/wall.glb").string();
  const CommandResult r = qdmr({"render", wall, "-o", (dir / "wall.png").string(), "--width", "96", "--height", "54"});
  ASSERT_EQ(r.exit_code, 0) << r.output;
  EXPECT_FALSE(read_file(dir / "wall.png").empty());
  // Its material displaced by --set alone, with the height beside the asset.
  const CommandResult set = qdmr({"render", wall, "-o", (dir / "pom.png").string(), "--width", "96", "--height", "54",
                                  "--stats", (dir / "stats.json").string(), "--set",
                                  "/objects/0/materials/bricks/height=wall_height.png", "--set",
                                  "/objects/0/materials/bricks/technique/name=pom"});
  ASSERT_EQ(set.exit_code, 0) << set.output;
  EXPECT_GT(nlohmann::json::parse(read_file(dir / "stats.json"))["iterations"]["max"].get<double>(), 0.0);
}

TEST(CliGltf, PlanListsMeshMaterialsAndWarnings) {
  const CommandResult indices = qdmr({"plan", (gltf_dir() / "assets/indices.gltf").string()});
  ASSERT_EQ(indices.exit_code, 0) << indices.output;
  EXPECT_NE(indices.output.find("gltf indices.gltf, 18 vertices, 8 triangles"), std::string::npos) << indices.output;
  EXPECT_NE(indices.output.find("glTF materials: indices/u8 indices/u16 indices/u32 indices/none"), std::string::npos)
      << indices.output;
  EXPECT_NE(indices.output.find("warning: flat normals generated"), std::string::npos) << indices.output;
  const CommandResult quad = qdmr({"plan", (gltf_dir() / "assets/quad.glb").string()});
  ASSERT_EQ(quad.exit_code, 0) << quad.output;
  EXPECT_NE(quad.output.find("warning: tangents generated"), std::string::npos) << quad.output;
  EXPECT_NE(quad.output.find("gltf-image-"), std::string::npos) << quad.output;  // the embedded image's file
}

}  // namespace
}  // namespace qdmr::test
