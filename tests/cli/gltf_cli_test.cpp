// glTF 2.0 through the command (the assets of tests/gltf, see make_assets.py): the same quad as OBJ + MTL and as
// glTF renders the same bits; a glTF material displaced from the scene marches (iterations, a height texture in
// the stats); `qdmr render model.glb` needs no scene file and --set reaches its materials; `qdmr plan` lists the
// mesh, materials and the warnings of what is ignored.
#include <gtest/gtest.h>

#include <string>

#include <nlohmann/json.hpp>

#include "cli/cli_test_util.hpp"

namespace qdmr::test {
namespace {

std::filesystem::path gltf_dir() { return source_dir() / "tests/gltf"; }

CommandResult qdmr(std::vector<std::string> args) { return run(cli(), args); }

TEST(CliGltf, TheSameQuadAsObjAndAsGltfRendersTheSameBits) {
  TempDir dir;
  for (const char* name : {"quad_obj", "quad_gltf"}) {
    const CommandResult r = qdmr({"render", (gltf_dir() / (std::string(name) + ".json")).string(), "-o",
                                  (dir / (std::string(name) + ".exr")).string(), "--aov",
                                  "normal=" + (dir / (std::string(name) + "_n.exr")).string(), "--aov",
                                  "uv=" + (dir / (std::string(name) + "_uv.exr")).string()});
    ASSERT_EQ(r.exit_code, 0) << r.output;
  }
  for (const char* suffix : {".exr", "_n.exr", "_uv.exr"}) {
    const std::string obj = read_file(dir / ("quad_obj" + std::string(suffix)));
    const std::string gltf = read_file(dir / ("quad_gltf" + std::string(suffix)));
    EXPECT_FALSE(obj.empty());
    EXPECT_TRUE(obj == gltf) << suffix << ": the OBJ and the glTF quad differ";
  }
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
