// OBJ + MTL through the command: a disp map renders displaced (iterations, a height texture in the stats), each
// map kind gets its program, the object's `mtl` block and --set choose another technique, `qdmr plan` lists
// the MTL materials with their textures, and a wrong block is one line and exit 2.
#include <gtest/gtest.h>

#include <string>

#include <nlohmann/json.hpp>

#include "cli/cli_test_util.hpp"
#include "load/mtl_assets.hpp"

namespace qdmr::test {
namespace {

// Renders the quads (small) with --stats; returns the stats.
nlohmann::json render_stats(const TempDir& dir, const std::vector<std::string>& extra = {}) {
  write_file(dir / "scene.json", mtl_scene());
  std::vector<std::string> args{"render", (dir / "scene.json").string(), "-o", (dir / "image.png").string(),
                                "--width", "160", "--height", "90", "--stats", (dir / "stats.json").string()};
  args.insert(args.end(), extra.begin(), extra.end());
  const CommandResult result = run(cli(), args);
  EXPECT_EQ(result.exit_code, 0) << result.output;
  return result.exit_code == 0 ? nlohmann::json::parse(read_file(dir / "stats.json")) : nlohmann::json();
}

std::string variant_of(const nlohmann::json& stats, const std::string& material) {
  for (const auto& m : stats["materials"])
    if (m["name"] == material) {  // "displacement:pom | blinn_phong | trilinear": the program
      const std::string variant = m["variant"];
      return variant.substr(0, variant.find(" |"));
    }
  return "(not drawn)";
}

TEST(CliObjMtl, DispRendersDisplacedAndEachMapKindGetsItsProgram) {
  TempDir dir;
  write_mtl_assets(dir.path());
  const nlohmann::json stats = render_stats(dir);
  ASSERT_FALSE(stats.is_null());
  EXPECT_GT(stats["iterations"]["max"].get<double>(), 0.0);
  EXPECT_EQ(variant_of(stats, "quads/displaced"), "displacement:pom");
  EXPECT_TRUE(stats_have_texture(stats, "'quads/displaced'", "height")) << stats["textures"].dump(1);
  EXPECT_TRUE(stats_have_texture(stats, "'quads/displaced'", "albedo"));
  EXPECT_EQ(variant_of(stats, "quads/bumped"), "normal_mapping");
  EXPECT_TRUE(stats_have_texture(stats, "'quads/bumped'", "normal"));  // derived from the bump height
  EXPECT_EQ(variant_of(stats, "quads/normal_mapped"), "normal_mapping");
  EXPECT_TRUE(stats_have_texture(stats, "'quads/normal_mapped'", "normal"));
  EXPECT_EQ(variant_of(stats, "quads/plain"), "normal_mapping");
}

TEST(CliObjMtl, SetChoosesTheTechniqueOfAnMtlMaterial) {
  TempDir dir;
  write_mtl_assets(dir.path());
  const nlohmann::json flat = render_stats(dir, {"--set", "/objects/0/mtl/displaced/technique/name=normal"});
  EXPECT_EQ(flat["iterations"]["max"].get<double>(), 0.0);
  const nlohmann::json qdm = render_stats(dir, {"--set", "/objects/0/mtl/displaced/technique/name=qdm", "--set",
                                                "/objects/0/mtl/bumped/technique/name=relief"});
  EXPECT_EQ(variant_of(qdm, "quads/displaced").rfind("displacement:qdm<", 0), 0u) << variant_of(qdm, "quads/displaced");
  EXPECT_EQ(variant_of(qdm, "quads/bumped"), "displacement:relief");
  EXPECT_GT(qdm["iterations"]["max"].get<double>(), 0.0);
}

TEST(CliObjMtl, PlanListsTheMtlMaterialsAndTheirTextures) {
  TempDir dir;
  write_mtl_assets(dir.path());
  write_file(dir / "scene.json", mtl_scene());
  const CommandResult result = run(cli(), {"plan", (dir / "scene.json").string()});
  ASSERT_EQ(result.exit_code, 0) << result.output;
  const std::string& plan = result.output;
  EXPECT_NE(plan.find("  quads/displaced: displacement:pom"), std::string::npos) << plan;
  EXPECT_NE(plan.find("  quads/bumped: normal_mapping"), std::string::npos) << plan;
  EXPECT_NE(plan.find("  quads/normal_mapped: normal_mapping"), std::string::npos) << plan;
  EXPECT_NE(plan.find("  quads/plain: normal_mapping"), std::string::npos) << plan;
  EXPECT_NE(plan.find("MTL material 'quads/displaced'/layers/0/height (height.png)"), std::string::npos) << plan;
  EXPECT_NE(plan.find("MTL material 'quads/displaced'/layers/0/albedo (albedo.png)"), std::string::npos) << plan;
  EXPECT_NE(plan.find("MTL material 'quads/normal_mapped'/layers/0/normal (normal.png)"), std::string::npos) << plan;
  EXPECT_NE(plan.find("MTL materials: quads/displaced quads/bumped quads/normal_mapped quads/plain"), std::string::npos)
      << plan;
}

TEST(CliObjMtl, AWrongBlockIsOneLineAndExitTwo) {
  TempDir dir;
  write_mtl_assets(dir.path());
  write_file(dir / "scene.json", mtl_scene());
  const CommandResult result =
      run(cli(), {"plan", (dir / "scene.json").string(), "--set", "/objects/0/mtl/displace/technique/name=qdm"});
  EXPECT_EQ(result.exit_code, 2);
  EXPECT_EQ(result.output, "qdmr: error: " + (dir / "scene.json").string() +
                               ": /objects/0/mtl/displace: unknown MTL material 'displace'; did you mean 'displaced'?\n");
}

}  // namespace
}  // namespace qdmr::test
