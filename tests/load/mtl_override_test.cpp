// OBJ + MTL materials at load time: what each MTL map becomes (docs/scene-format.md, "OBJ and MTL files"), the
// object's `mtl` block over it (also through --set), and the errors of a wrong block.
#include <gtest/gtest.h>

#include "load/mtl_assets.hpp"
#include "qdmr/core/error.hpp"
#include "qdmr/load/load.hpp"

namespace qdmr {
namespace {

namespace fs = std::filesystem;

SceneDesc load(const test::TempDir& dir, const std::string& object_extra = "",
               const std::vector<SceneOverride>& overrides = {}) {
  test::write_file(dir / "scene.json", test::mtl_scene(object_extra));
  return load_scene(dir / "scene.json", overrides);
}

std::string load_error(const test::TempDir& dir, const std::string& object_extra,
                       const std::vector<SceneOverride>& overrides = {}) {
  try {
    load(dir, object_extra, overrides);
  } catch (const Error& e) {
    const std::string message = e.what(), prefix = (dir / "scene.json").string() + ": ";
    return message.rfind(prefix, 0) == 0 ? message.substr(prefix.size()) : message;
  }
  return "no error";
}

const MaterialDesc& material(const SceneDesc& scene, const std::string& name) {
  const MaterialDesc* m = scene.find_material("quads/" + name);
  if (!m) throw std::runtime_error("no material quads/" + name);
  return *m;
}

TEST(MtlMaterials, EachMapKindHasItsMeaning) {
  test::TempDir dir;
  test::write_mtl_assets(dir.path());
  const SceneDesc scene = load(dir);
  const fs::path tex = fs::absolute(dir.path()).lexically_normal() / "tex";

  // disp: the height of a displacement technique (POM), normals from it.
  const MaterialDesc& displaced = material(scene, "displaced");
  EXPECT_EQ(displaced.technique.kind, TechniqueKind::Pom);
  EXPECT_EQ(displaced.technique.depth_scale, 0.05f);
  EXPECT_EQ(displaced.layers.at(0).albedo.file, tex / "albedo.png");
  EXPECT_EQ(displaced.layers.at(0).height.file, tex / "height.png");
  EXPECT_EQ(displaced.layers.at(0).normal.source, TextureSource::FromHeight);
  // bump: a height for normals only (bump mapping).
  const MaterialDesc& bumped = material(scene, "bumped");
  EXPECT_EQ(bumped.technique.kind, TechniqueKind::Normal);
  EXPECT_EQ(bumped.layers.at(0).height.file, tex / "bump.png");
  EXPECT_EQ(bumped.layers.at(0).normal.source, TextureSource::FromHeight);
  EXPECT_EQ(bumped.layers.at(0).normal_strength, 1.0f);  // texture options (-bm 0.3) are ignored
  // norm: a tangent-space normal map.
  const MaterialDesc& normal_mapped = material(scene, "normal_mapped");
  EXPECT_EQ(normal_mapped.technique.kind, TechniqueKind::Normal);
  EXPECT_EQ(normal_mapped.layers.at(0).normal.source, TextureSource::File);
  EXPECT_EQ(normal_mapped.layers.at(0).normal.file, tex / "normal.png");
  EXPECT_EQ(normal_mapped.layers.at(0).height.source, TextureSource::None);
  // Kd only: a constant colour, flat.
  const MaterialDesc& plain = material(scene, "plain");
  EXPECT_EQ(plain.layers.at(0).albedo.source, TextureSource::Constant);
  EXPECT_EQ(plain.layers.at(0).albedo.constant, glm::vec4(0.5f, 0.6f, 0.7f, 1.0f));
  EXPECT_EQ(plain.layers.at(0).normal.source, TextureSource::None);
}

TEST(MtlMaterials, TheObjectsMtlBlockChoosesTechniqueAndKnobs) {
  test::TempDir dir;
  test::write_mtl_assets(dir.path());
  const SceneDesc scene = load(dir, R"(, "mtl": {
      "displaced": {"technique": {"name": "qdm", "depth_scale": 0.1, "max_iterations": 64},
                    "sampling": {"filter": "bilinear"}, "shadow": {"mode": "hard"}, "height_scale": 0.5},
      "bumped": {"technique": {"name": "relief"}, "normal_strength": 2, "lighting": {"shininess": 8}},
      "comment": "ignored"})");
  const MaterialDesc& displaced = material(scene, "displaced");
  EXPECT_EQ(displaced.technique.kind, TechniqueKind::Qdm);
  EXPECT_EQ(displaced.technique.depth_scale, 0.1f);
  EXPECT_EQ(displaced.technique.max_iterations, 64);
  EXPECT_EQ(displaced.technique.linear_steps, TechniqueDesc{}.linear_steps);  // what the block does not name stays
  EXPECT_EQ(displaced.sampling.filter, Filter::Bilinear);
  EXPECT_EQ(displaced.shadow.mode, ShadowMode::Hard);
  EXPECT_EQ(displaced.layers.at(0).height_scale, 0.5f);
  const MaterialDesc& bumped = material(scene, "bumped");
  EXPECT_EQ(bumped.technique.kind, TechniqueKind::Relief);  // a bump height may be displaced too
  EXPECT_EQ(bumped.layers.at(0).normal_strength, 2.0f);
  EXPECT_EQ(bumped.lighting.shininess, 8.0f);
  EXPECT_EQ(material(scene, "plain").technique.kind, TechniqueKind::Normal);  // no entry: the mapping as is
}

TEST(MtlMaterials, BumpMayBeReadAsANormalMap) {
  test::TempDir dir;
  test::write_mtl_assets(dir.path());
  const SceneDesc scene = load(dir, R"(, "mtl": {"bumped": {"bump": "normal", "normal_convention": "dx"}})");
  const LayerDesc& layer = material(scene, "bumped").layers.at(0);
  EXPECT_EQ(layer.normal.source, TextureSource::File);
  EXPECT_EQ(layer.normal.file, fs::absolute(dir.path()).lexically_normal() / "tex/bump.png");
  EXPECT_EQ(layer.height.source, TextureSource::None);
  EXPECT_EQ(layer.normal_convention, NormalConvention::DX);
}

TEST(MtlMaterials, SetReachesTheMtlBlock) {
  test::TempDir dir;
  test::write_mtl_assets(dir.path());
  const SceneDesc scene = load(dir, "", {parse_override("/objects/0/mtl/displaced/technique/name=relief"),
                                         parse_override("/objects/0/mtl/displaced/technique/depth_scale=0.2")});
  EXPECT_EQ(material(scene, "displaced").technique.kind, TechniqueKind::Relief);
  EXPECT_EQ(material(scene, "displaced").technique.depth_scale, 0.2f);
  // A block naming only a knob keeps the mapping's technique.
  const SceneDesc deeper = load(dir, "", {parse_override("/objects/0/mtl/displaced/technique/depth_scale=0.1")});
  EXPECT_EQ(material(deeper, "displaced").technique.kind, TechniqueKind::Pom);
  EXPECT_EQ(material(deeper, "displaced").technique.depth_scale, 0.1f);
}

TEST(MtlMaterials, ErrorsNameTheFieldAtFault) {
  test::TempDir dir;
  test::write_mtl_assets(dir.path());
  EXPECT_EQ(load_error(dir, R"(, "mtl": {"displace": {}})"),
            "/objects/0/mtl/displace: unknown MTL material 'displace'; did you mean 'displaced'?");
  EXPECT_EQ(load_error(dir, R"(, "mtl": {"stone": {}})"),
            "/objects/0/mtl/stone: unknown MTL material 'stone'; the mesh's materials are: displaced, bumped, "
            "normal_mapped, plain");
  EXPECT_EQ(load_error(dir, R"(, "mtl": {"displaced": {"techniqe": {}}})"),
            "/objects/0/mtl/displaced: unknown key 'techniqe'; did you mean 'technique'?");
  EXPECT_EQ(load_error(dir, R"(, "mtl": {"displaced": {"layers": []}})").rfind("/objects/0/mtl/displaced: unknown key 'layers'", 0), 0u);
  EXPECT_EQ(load_error(dir, R"(, "mtl": {"displaced": {"technique": {"name": "qdn"}}})"),
            "/objects/0/mtl/displaced/technique/name: unknown value 'qdn'; did you mean 'qdm'?");
  EXPECT_EQ(load_error(dir, R"(, "mtl": {"plain": {"technique": {"name": "pom"}}})"),
            "/objects/0/mtl/plain/technique: a displacement technique needs a height: this MTL material has no disp "
            "map, and no bump map read as a height");
  EXPECT_EQ(load_error(dir, R"(, "mtl": {"bumped": {"bump": "normal", "technique": {"name": "pom"}}})"),
            "/objects/0/mtl/bumped/technique: a displacement technique needs a height: this MTL material has no disp "
            "map, and no bump map read as a height");
  EXPECT_EQ(load_error(dir, R"(, "mtl": {"plain": {"bump": "normal"}})"),
            "/objects/0/mtl/plain/bump: the MTL material has no bump map");
  EXPECT_EQ(load_error(dir, R"(, "mtl": {"bumped": {"ao": {"mode": "frame"}}})"),
            "/objects/0/mtl/bumped/ao: ambient occlusion needs a displacement technique (technique/name is 'normal')");
  EXPECT_EQ(load_error(dir, R"(, "mtl": [])"),
            "/objects/0/mtl: expected an object mapping MTL material names to overrides, got array");
  EXPECT_EQ(load_error(dir, "", {parse_override(R"(/materials/m={"layers": [{}]})"), parse_override("/objects/0/material=m"),
                                 parse_override("/objects/0/mtl/plain/technique/name=pom")}),
            "/objects/0/mtl: only an obj mesh without 'material' has MTL materials to override");
}

}  // namespace
}  // namespace qdmr
