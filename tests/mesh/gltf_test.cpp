// glTF 2.0 assets through mesh_detail::load_gltf: what is read (the generated assets of tests/gltf/assets, see
// tests/gltf/make_assets.py) and what is refused, each refusal naming the file and the element at fault.
#include <gtest/gtest.h>

#include <algorithm>
#include <cstring>
#include <filesystem>
#include <functional>
#include <random>
#include <string>
#include <vector>

#include <glm/geometric.hpp>
#include <glm/matrix.hpp>
#include <nlohmann/json.hpp>

#include "mesh/builders.hpp"
#include "qdmr/bake/bake_cache.hpp"
#include "mesh/gltf_files.hpp"
#include "mesh/to_frame.hpp"
#include "qdmr/core/error.hpp"
#include "support/test_support.hpp"

namespace qdmr {
namespace {

namespace fs = std::filesystem;

fs::path asset(const std::string& name) { return test::source_dir() / "tests/gltf/assets" / name; }

MeshData load(const fs::path& file, GltfPick scene = {}, GltfPick node = {}) {
  MeshDesc desc;
  desc.kind = MeshKind::Gltf;
  desc.file = file;
  desc.gltf_scene = scene;
  desc.gltf_node = node;
  return mesh_detail::load_gltf(desc, "scene.json: /objects/0/mesh/file");
}

std::string load_error(const fs::path& file) {
  try {
    load(file);
  } catch (const Error& e) {
    return e.what();
  }
  return "no error";
}

// The quad of quad.gltf, as tests/gltf/make_assets.py writes it: glTF positions (x, 0, -y) land on qdmr's
// (x, y, 0) exactly (the +Y-up to +Z-up turn has entries 0 and +-1), UVs (u, 1 - v) on (u, v).
TEST(Gltf, TheQuadLandsOnQdmrsAxes) {
  const MeshData m = load(asset("quad.gltf"));
  ASSERT_EQ(m.vertex_count(), 4u);
  ASSERT_EQ(m.triangle_count(), 2u);
  EXPECT_EQ(m.positions[0], glm::vec3(-1, -1, 0));
  EXPECT_EQ(m.positions[2], glm::vec3(1, 1, 0));
  EXPECT_EQ(m.uvs[0], glm::vec2(0, 0));
  EXPECT_EQ(m.uvs[2], glm::vec2(1, 1));
  EXPECT_EQ(m.normals[0], glm::vec3(0, 0, 1));
  EXPECT_EQ(m.tangents[0], glm::vec4(1, 0, 0, 1));  // generated: +u is +x, +v is +y
  ASSERT_EQ(m.materials.size(), 1u);
  const MaterialDesc& material = m.materials[0];
  EXPECT_EQ(material.name, "checker");
  EXPECT_EQ(material.layers[0].albedo.source, TextureSource::File);
  EXPECT_EQ(material.layers[0].albedo.file, fs::absolute(asset("checker.png")).lexically_normal());
  EXPECT_EQ(material.lighting.model, LightingModel::CookTorrance);
  EXPECT_FLOAT_EQ(material.lighting.roughness, 0.6f);
  EXPECT_FLOAT_EQ(material.lighting.specular, 0.04f);  // a dielectric's F0 (metallicFactor 0)
  EXPECT_EQ(material.technique.kind, TechniqueKind::Normal);
  EXPECT_EQ(m.triangle_materials, std::vector<std::uint32_t>({0, 0}));
}

// The same asset with its buffer and image embedded (data: URIs), and as one .glb (BIN chunk, image in a buffer
// view): the same mesh, and an albedo file with the same bytes as checker.png.
TEST(Gltf, EmbeddedExternalAndBinaryAreTheSameAsset) {
  const MeshData external = load(asset("quad.gltf"));
  for (const char* name : {"quad_embedded.gltf", "quad.glb"}) {
    const MeshData m = load(asset(name));
    EXPECT_EQ(m.positions, external.positions) << name;
    EXPECT_EQ(m.normals, external.normals) << name;
    EXPECT_EQ(m.tangents, external.tangents) << name;
    EXPECT_EQ(m.uvs, external.uvs) << name;
    EXPECT_EQ(m.indices, external.indices) << name;
    const fs::path albedo = m.materials.at(0).layers[0].albedo.file;
    EXPECT_NE(albedo, external.materials[0].layers[0].albedo.file) << name << ": stored in the cache folder";
    EXPECT_EQ(test::read_file(albedo), test::read_file(asset("checker.png"))) << name;
    // An entry of the bake cache (listed by `qdmr cache`, trimmed with it).
    const auto entries = bake_cache_entries(albedo.parent_path());
    EXPECT_TRUE(std::any_of(entries.begin(), entries.end(), [&](const BakeCacheEntry& e) {
      return e.file == albedo && e.kind == "glTF embedded image";
    })) << name;
  }
}

// Node hierarchy: root (translate (0, 0.5, 0), a quarter turn about +Y, scale 0.5) with children by TRS and by
// matrix, a grandchild, and a camera node. Expected corners are worked out by hand in glTF space, then turned
// +Z up ((x, y, z) -> (x, -z, y)).
TEST(Gltf, NodeHierarchyPlacesEveryMesh) {
  const MeshData m = load(asset("hierarchy.gltf"));
  ASSERT_EQ(m.triangle_count(), 6u);
  // Tolerance: the quaternion's sqrt(0.5) components round in double; 1e-6 is far below any wrong transform.
  const auto near = [](glm::vec3 a, glm::vec3 b) { return glm::length(a - b) < 1e-6f; };
  // "left": corner (-1, 0, 1) + (-2.5, 0, 0) = (-3.5, 0, 1); scale 0.5: (-1.75, 0, 0.5); a quarter turn about Y
  // maps (x, y, z) to (z, y, -x): (0.5, 0, 1.75); + (0, 0.5, 0): (0.5, 0.5, 1.75); +Z up: (0.5, -1.75, 0.5).
  EXPECT_TRUE(near(m.positions[0], glm::vec3(0.5f, -1.75f, 0.5f))) << m.positions[0].x << " " << m.positions[0].y << " " << m.positions[0].z;
  // Its normal (0, 1, 0) stays +Y in glTF: +Z in qdmr.
  EXPECT_TRUE(near(m.normals[0], glm::vec3(0, 0, 1)));
  // Every material was read, by name.
  ASSERT_EQ(m.materials.size(), 3u);
  EXPECT_EQ(m.materials[1].name, "green");
  EXPECT_FLOAT_EQ(m.materials[1].layers[0].albedo.constant.g, 0.7f);
  // The camera node: at glTF (0, 6, 6) looking down 45 degrees towards -Z; qdmr (0, -6, 6) looking towards +Y.
  ASSERT_EQ(m.cameras.size(), 1u);
  EXPECT_TRUE(near(m.cameras[0].position, glm::vec3(0, -6, 6)));
  const glm::vec3 view = glm::normalize(m.cameras[0].target - m.cameras[0].position);
  EXPECT_TRUE(near(view, glm::normalize(glm::vec3(0, 1, -1))));
  EXPECT_NEAR(m.cameras[0].fov_y_deg, 0.8 * 180 / 3.14159265358979, 1e-4);  // float degrees of 0.8 rad
  // One node and its subtree, by name: "left" and its grandchild "lifted".
  EXPECT_EQ(load(asset("hierarchy.gltf"), {}, {-1, "left"}).triangle_count(), 4u);
  EXPECT_EQ(load(asset("hierarchy.gltf"), {}, {2, ""}).triangle_count(), 2u);
}

// 8-, 16- and 32-bit indices and none; the last primitive has no normals: flat ones, per triangle.
TEST(Gltf, EveryIndexTypeAndFlatNormals) {
  const MeshData m = load(asset("indices.gltf"));
  EXPECT_EQ(m.triangle_count(), 8u);
  EXPECT_EQ(m.vertex_count(), 4u * 3 + 6u);
  EXPECT_EQ(m.triangle_materials, std::vector<std::uint32_t>({0, 0, 1, 1, 2, 2, 3, 3}));
  for (std::size_t i = 0; i < m.indices.size(); ++i) {
    // The three indexed quads index the same corners, offset by their vertices; x by their offsets.
    const std::size_t quad = i / 6;
    EXPECT_NEAR(m.positions[m.indices[i]].x, -4.5f + 3.0f * float(quad), 1.0f + 1e-6f);
  }
  EXPECT_EQ(m.normals[12], glm::vec3(0, 0, 1));  // flat: the face normal
  EXPECT_FALSE(m.notes.empty());
}

TEST(Gltf, SparseAccessorsAreRefused) {
  EXPECT_NE(load_error(asset("sparse.gltf")).find("/accessors/0/sparse: sparse accessors are not supported"),
            std::string::npos)
      << load_error(asset("sparse.gltf"));
}

// A copy of quad.gltf (with its buffer and image) edited by `edit`, loaded: the error message.
std::string edited_error(const std::function<void(nlohmann::json&)>& edit) {
  test::TempDir dir;
  fs::create_directories(dir / "asset");
  fs::copy_file(asset("quad.bin"), dir / "asset/quad.bin");
  fs::copy_file(asset("checker.png"), dir / "asset/checker.png");
  nlohmann::json doc = nlohmann::json::parse(test::read_file(asset("quad.gltf")));
  edit(doc);
  test::write_file(dir / "asset/quad.gltf", doc.dump());
  test::write_file(dir / "secret.bin", std::string(140, 'x'));
  const std::string error = load_error(dir / "asset/quad.gltf");
  const std::string prefix = "scene.json: /objects/0/mesh/file: " + (dir / "asset/quad.gltf").string() + ": ";
  return error.rfind(prefix, 0) == 0 ? error.substr(prefix.size()) : error;
}

bool has_note(const MeshData& m, const std::string& part) {
  return std::any_of(m.notes.begin(), m.notes.end(), [&](const std::string& n) { return n.find(part) != std::string::npos; });
}

// A copy of quad.gltf edited by `edit`, loaded.
MeshData edited(const std::function<void(nlohmann::json&)>& edit) {
  test::TempDir dir;
  fs::copy_file(asset("quad.bin"), dir / "quad.bin");
  fs::copy_file(asset("checker.png"), dir / "checker.png");
  nlohmann::json doc = nlohmann::json::parse(test::read_file(asset("quad.gltf")));
  edit(doc);
  test::write_file(dir / "quad.gltf", doc.dump());
  return load(dir / "quad.gltf");
}

TEST(Gltf, TextureTransformSamplerAndFactors) {
  using J = nlohmann::json;
  // KHR_texture_transform: uv' = offset + rotation(scale * uv) in glTF's UVs, then v flipped: glTF (0, 1) becomes
  // (2 * 0 + 0.5, 2 * 1 + 0) = (0.5, 2), qdmr (0.5, 1 - 2).
  const MeshData moved = edited([](J& d) {
    d["materials"][0]["pbrMetallicRoughness"]["baseColorTexture"]["extensions"] = {
        {"KHR_texture_transform", {{"offset", {0.5, 0.0}}, {"scale", {2.0, 2.0}}}}};
    d["extensionsUsed"] = {"KHR_texture_transform"};
    d["extensionsRequired"] = {"KHR_texture_transform"};
  });
  EXPECT_EQ(moved.uvs[0], glm::vec2(0.5f, -1.0f));
  EXPECT_EQ(moved.uvs[2], glm::vec2(2.5f, 1.0f));
  // The base colour texture's sampler: NEAREST_MIPMAP_LINEAR, clamp; a wrapT unlike wrapS is a warning.
  const MeshData sampled = edited([](J& d) {
    d["samplers"] = J::array({{{"minFilter", 9986}, {"magFilter", 9728}, {"wrapS", 33071}, {"wrapT", 33648}}});
    d["textures"][0]["sampler"] = 0;
  });
  EXPECT_EQ(sampled.materials[0].sampling.filter, Filter::PointMipLinear);
  EXPECT_EQ(sampled.materials[0].sampling.address, AddressMode::Clamp);
  EXPECT_TRUE(has_note(sampled, "wrapT differs from wrapS"));
  EXPECT_FALSE(has_note(sampled, "magFilter"));  // NEAREST, as NEAREST_MIPMAP_LINEAR's texels: they agree
  // One texel filter for both (minFilter's): a magFilter asking for the other is a warning, either way round.
  const auto mag_note = [&](int min_filter, int mag_filter) {
    return has_note(edited([&](J& d) {
                      d["samplers"] = J::array({{{"minFilter", min_filter}, {"magFilter", mag_filter}}});
                      d["textures"][0]["sampler"] = 0;
                    }),
                    "magFilter");
  };
  EXPECT_TRUE(mag_note(9987, 9728));   // LINEAR_MIPMAP_LINEAR, NEAREST
  EXPECT_TRUE(mag_note(9728, 9729));   // NEAREST, LINEAR
  EXPECT_FALSE(mag_note(9985, 9729));  // LINEAR_MIPMAP_NEAREST, LINEAR
  // Factors without a texture: albedo = baseColor x (1 - metallic), F0 from metallic, roughness clamped.
  const MeshData metal = edited([](J& d) {
    d["materials"][0]["pbrMetallicRoughness"] = {{"baseColorFactor", {1.0, 0.5, 0.0, 1.0}}, {"metallicFactor", 0.5},
                                                 {"roughnessFactor", 0.0}};
    d["materials"][0]["extensions"] = {{"KHR_materials_emissive_strength", {{"emissiveStrength", 2.0}}}};
    d["materials"][0]["emissiveFactor"] = {1.0, 1.0, 1.0};
  });
  const MaterialDesc& m = metal.materials[0];
  EXPECT_EQ(m.layers[0].albedo.source, TextureSource::Constant);
  EXPECT_FLOAT_EQ(m.layers[0].albedo.constant.r, 0.5f);
  EXPECT_FLOAT_EQ(m.layers[0].albedo.constant.g, 0.25f);
  EXPECT_FLOAT_EQ(m.lighting.roughness, 0.02f);
  // F0 = 0.04 + (luminance - 0.04) * metallic, luminance = 0.2126 + 0.7152 * 0.5
  EXPECT_NEAR(m.lighting.specular, 0.04 + (0.2126 + 0.7152 * 0.5 - 0.04) * 0.5, 1e-6);  // float of a double
  EXPECT_TRUE(has_note(metal, "emission not drawn"));
}

// Read but not drawn, each a plan warning: animations (drawn at rest) and an extension used but not required.
TEST(Gltf, AnimationsAndUnusedExtensionsAreWarnings) {
  using J = nlohmann::json;
  const MeshData m = edited([](J& d) {
    d["animations"] = J::array({{{"channels", J::array()}, {"samplers", J::array()}}});
    d["extensionsUsed"] = {"EXT_lights_image_based"};
  });
  EXPECT_TRUE(has_note(m, "1 animation ignored (drawn at rest)"));
  EXPECT_TRUE(has_note(m, "extension EXT_lights_image_based ignored"));
  EXPECT_FALSE(has_note(edited([](J&) {}), "ignored"));  // the quad as it is: no such warning
}

// Over a base colour texture, baseColorFactor x (1 - metallic) multiplies the texture's linear colour (the
// texture build applies it: TextureImage.AlbedoFactorMultipliesTheLinearColour), and nothing is left unapplied.
TEST(Gltf, BaseColorFactorTintsTheTexture) {
  using J = nlohmann::json;
  const MeshData tinted = edited([](J& d) {
    d["materials"][0]["pbrMetallicRoughness"]["baseColorFactor"] = {0.5, 0.25, 1.0, 1.0};
    d["materials"][0]["pbrMetallicRoughness"]["metallicFactor"] = 0.5;
  });
  const TextureDesc& albedo = tinted.materials[0].layers[0].albedo;
  EXPECT_EQ(albedo.source, TextureSource::File);
  EXPECT_EQ(albedo.factor, glm::vec3(0.25f, 0.125f, 0.5f));  // exact: halves of exact binary fractions
  EXPECT_FALSE(has_note(tinted, "baseColorFactor"));
  EXPECT_FALSE(has_note(tinted, "metallic"));
  EXPECT_EQ(load(asset("quad.gltf")).materials[0].layers[0].albedo.factor, glm::vec3(1.0f));
}

TEST(Gltf, EachBadElementIsNamed) {
  using J = nlohmann::json;
  const auto has = [](const std::string& error, const std::string& part) {
    return error.find(part) != std::string::npos ? testing::AssertionSuccess()
                                                 : testing::AssertionFailure() << "'" << error << "' lacks '" << part << "'";
  };
  // URIs that leave the folder or name a scheme: refused before anything is opened.
  EXPECT_TRUE(has(edited_error([](J& d) { d["buffers"][0]["uri"] = "../secret.bin"; }), "/buffers/0/uri: the URI '../secret.bin' leaves the asset's folder"));
  EXPECT_TRUE(has(edited_error([](J& d) { d["buffers"][0]["uri"] = "%2e%2e/secret.bin"; }), "leaves the asset's folder"));
  EXPECT_TRUE(has(edited_error([](J& d) { d["buffers"][0]["uri"] = "/etc/passwd"; }), "is an absolute path"));
  EXPECT_TRUE(has(edited_error([](J& d) { d["images"][0]["uri"] = "https://example.com/a.png"; }), "/images/0/uri: the URI 'https://example.com/a.png' names a scheme"));
  EXPECT_TRUE(has(edited_error([](J& d) { d["images"][0]["uri"] = "file:checker.png"; }), "names a scheme"));
  // What qdmr cannot draw.
  EXPECT_TRUE(has(edited_error([](J& d) { d["meshes"][0]["primitives"][0]["mode"] = 0; }), "/meshes/0/primitives/0/mode: points cannot be drawn"));
  EXPECT_TRUE(has(edited_error([](J& d) { d["meshes"][0]["primitives"][0]["mode"] = 1; }), "lines cannot be drawn"));
  EXPECT_TRUE(has(edited_error([](J& d) { d["meshes"][0]["primitives"][0]["targets"] = J::array({{{"POSITION", 0}}}); }), "/meshes/0/primitives/0/targets: morph targets"));
  EXPECT_TRUE(has(edited_error([](J& d) { d["nodes"][0]["skin"] = 0; d["skins"] = J::array({{{"joints", {0}}, {"inverseBindMatrices", 0}}}); }), "/nodes/0/skin: skinned meshes cannot be drawn"));
  EXPECT_TRUE(has(edited_error([](J& d) { d["extensionsRequired"] = {"KHR_draco_mesh_compression"}; d["extensionsUsed"] = d["extensionsRequired"]; }),
                  "/extensionsRequired/0: the asset requires KHR_draco_mesh_compression, which qdmr does not read"));
  // Accessors and views that lie.
  EXPECT_TRUE(has(edited_error([](J& d) { d["accessors"][0]["count"] = 5; }), "/accessors/0/count: 5 elements of 12 bytes"));
  EXPECT_TRUE(has(edited_error([](J& d) { d["accessors"][0]["count"] = 4000000000u; }), "/accessors/0/count"));
  EXPECT_TRUE(has(edited_error([](J& d) { d["accessors"][1]["bufferView"] = 9; }), "/accessors/1/bufferView: buffer view 9 does not exist"));
  EXPECT_TRUE(has(edited_error([](J& d) { d["bufferViews"][0]["byteLength"] = 4000; }), "/bufferViews/0: bytes 0 + 4000 run past the end of buffer 0"));
  EXPECT_TRUE(has(edited_error([](J& d) { d["bufferViews"][0]["byteStride"] = 8; }), "/bufferViews/0/byteStride: 8 is less than an element (12 bytes)"));
  EXPECT_TRUE(has(edited_error([](J& d) { d["accessors"][0]["componentType"] = 5123; }), "/accessors/0/componentType"));
  EXPECT_TRUE(has(edited_error([](J& d) { d["accessors"][1]["count"] = 3; }), "/meshes/0/primitives/0/attributes/TEXCOORD_0: 3 elements, but POSITION has 4"));
  EXPECT_TRUE(has(edited_error([](J& d) { d["buffers"][0]["byteLength"] = 1000; }), "quad.bin"));
  // Indices past the vertices, and a node graph with a cycle.
  EXPECT_TRUE(has(edited_error([](J& d) {
                    const int accessor = d["meshes"][0]["primitives"][0]["indices"];
                    d["accessors"][accessor]["count"] = 3;
                    d["accessors"][0]["count"] = 2;
                    d["accessors"][1]["count"] = 2;
                    d["accessors"][2]["count"] = 2;
                  }),
                  "/accessors/3: index 2 is 2, past the primitive's 2 vertices"));
  EXPECT_TRUE(has(edited_error([](J& d) {
                    d["nodes"] = J::array({{{"mesh", 0}}, {{"children", {2}}}, {{"children", {1}}}});
                  }),
                  "the node graph has a cycle"));
  EXPECT_TRUE(has(edited_error([](J& d) { d["nodes"][0]["children"] = {0}; }), "cycle"));
  EXPECT_TRUE(has(edited_error([](J& d) { d["nodes"][0]["children"] = {7}; }), "/nodes/0/children/0: node 7 does not exist"));
  // A data: URI tinygltf cannot decode stays a URI (found by fuzz_gltf: it was taken for a file name).
  EXPECT_TRUE(has(edited_error([](J& d) { d["images"][0]["uri"] = "data:image/png;base28,iVBO"; }),
                  "/images/0: a data: URI that is not base64 data of a known media type"));
  // A mesh drawn by many nodes is copied for each: 1000 nodes drawing one mesh whose indices claim 2^19 triangles
  // make 524 M triangles, refused from the counts before anything is read.
  EXPECT_TRUE(has(edited_error([](J& d) {
                    const int indices = d["meshes"][0]["primitives"][0]["indices"];
                    d["accessors"][indices]["count"] = 3 << 19;  // a lie, refused later by name: here only counted
                    d["bufferViews"][d["accessors"][indices]["bufferView"].get<int>()]["byteLength"] = 1 << 22;
                    J root = J::object(), nodes = J::array();
                    root["children"] = J::array();
                    nodes.push_back(root);
                    for (int n = 1; n <= 1000; ++n) {
                      nodes.push_back(J::object({{"mesh", 0}}));
                      nodes[0]["children"].push_back(n);
                    }
                    d["nodes"] = nodes;
                    d["scenes"][0]["nodes"] = {0};
                  }),
                  "the drawn nodes hold more than 268435456 triangles"));
  // An image that is not one.
  EXPECT_TRUE(has(edited_error([](J& d) { d["images"][0]["uri"] = "quad.bin"; }), "quad.bin"));
}

// --max-memory bounds a mesh's drawn copies, counted per drawing node before anything is read: the quad (4
// vertices, 2 triangles: 4 x 48 + 2 x 16 = 224 bytes as the plan counts a mesh) drawn by 5000 nodes takes 1.07 MiB.
TEST(Gltf, InstancesAreCountedAgainstTheMemoryLimit) {
  using J = nlohmann::json;
  test::TempDir dir;
  fs::copy_file(asset("quad.bin"), dir / "quad.bin");
  fs::copy_file(asset("checker.png"), dir / "checker.png");
  J doc = J::parse(test::read_file(asset("quad.gltf")));
  J root = {{"children", J::array()}}, nodes = J::array({root});
  for (int n = 1; n <= 5000; ++n) {
    nodes.push_back({{"mesh", 0}, {"translation", {3.0 * n, 0.0, 0.0}}});
    nodes[0]["children"].push_back(n);
  }
  doc["nodes"] = nodes;
  test::write_file(dir / "quad.gltf", doc.dump());
  MeshDesc desc;
  desc.kind = MeshKind::Gltf;
  desc.file = dir / "quad.gltf";
  try {
    mesh_detail::load_gltf(desc, "s.json: /objects/0/mesh/file", std::uint64_t(1) << 20);
    ADD_FAILURE() << "5000 quads were read under 1 MiB";
  } catch (const Error& e) {
    EXPECT_NE(std::string(e.what()).find("take 2 MiB, more than the limit of 1 MiB"), std::string::npos) << e.what();
  }
  const MeshData fits = mesh_detail::load_gltf(desc, "s.json: /objects/0/mesh/file", std::uint64_t(2) << 20);
  EXPECT_EQ(fits.triangle_count(), 10000u);
  EXPECT_EQ(fits.vertex_count(), 20000u);
}

std::string glb_error(std::string bytes) {
  try {
    static_cast<void>(mesh_detail::glb_chunks(
        bytes.size(), [&](std::uint64_t at, std::size_t n) { return bytes.substr(std::size_t(at), n); }, "a.glb"));
  } catch (const Error& e) {
    return e.what();
  }
  return "no error";
}

void put32(std::string& s, std::size_t at, std::uint32_t v) { std::memcpy(s.data() + at, &v, 4); }

TEST(Gltf, GlbChunkLengthsThatLieAreRefused) {
  const std::string good = test::read_file(asset("quad.glb"));
  EXPECT_EQ(glb_error(good), "no error");
  // Where the chunks are: the JSON right after the two headers, the BIN after the JSON and its own header.
  const mesh_detail::GlbChunks chunks = mesh_detail::glb_chunks(
      good.size(), [&](std::uint64_t at, std::size_t n) { return good.substr(std::size_t(at), n); }, "a.glb");
  EXPECT_EQ(chunks.json_offset, 20u);
  EXPECT_TRUE(chunks.has_bin);
  EXPECT_EQ(chunks.bin_offset, 20 + chunks.json_length + 8);
  EXPECT_EQ(chunks.bin_offset + chunks.bin_length, good.size());
  std::string s = good;
  put32(s, 8, std::uint32_t(good.size() + 4));
  EXPECT_NE(glb_error(s).find(".glb header: length"), std::string::npos) << glb_error(s);
  s = good;
  put32(s, 12, 0x7ffffff0u);
  EXPECT_NE(glb_error(s).find(".glb chunk 0: length 2147483632 runs past the end of the file"), std::string::npos) << glb_error(s);
  s = good;
  std::uint32_t json_length = 0;
  std::memcpy(&json_length, good.data() + 12, 4);
  put32(s, 20 + json_length, std::uint32_t(good.size()));
  EXPECT_NE(glb_error(s).find(".glb chunk 1: length"), std::string::npos) << glb_error(s);
  s = good;
  put32(s, 4, 1);
  EXPECT_NE(glb_error(s).find("version 1"), std::string::npos);
  EXPECT_NE(glb_error(good.substr(0, 16)).find("needs a 12-byte header and a chunk"), std::string::npos);
}

TEST(Gltf, UrisStayInTheFolder) {
  EXPECT_EQ(*mesh_detail::relative_uri("textures/a%20b.png", "w"), fs::path("textures/a b.png"));
  EXPECT_FALSE(mesh_detail::relative_uri("data:image/png;base64,AAAA", "w"));
  for (const char* bad : {"../a.png", "a/../../b.png", "/abs.png", "http://x/y.png", "C:/x.png", "a\\b.png", "%00.png",
                          "%2", "", "ftp:x"})
    EXPECT_THROW(mesh_detail::relative_uri(bad, "w"), Error) << bad;
}

// The frame move of add_smooth in SSE2's double lanes (to_frame) has the bits of glm's scalar code (to_frame_one,
// add_smooth's former loop) on every vertex: random matrices (rotations, mirrors, uneven scales, translations, the
// quarter turn every asset takes), random vertices with zero, -0 and tiny normals and tangents (the fallbacks), odd
// and even counts and offsets, and counts that split over threads.
TEST(Gltf, TheFrameMoveHasTheBitsOfGlm) {
  std::mt19937 random(55);
  const auto uniform = [&](double lo, double hi) { return std::uniform_real_distribution<double>(lo, hi)(random); };
  const auto component = [&]() -> float {
    switch (random() % 8) {
      case 0: return 0.0f;
      case 1: return -0.0f;
      case 2: return float(uniform(-1e-30, 1e-30));  // squares underflow in float, not in double
      default: return float(uniform(-3.0, 3.0));
    }
  };
  const glm::dmat4 quarter_turn(1, 0, 0, 0, 0, 0, 1, 0, 0, -1, 0, 0, 0, 0, 0, 1);  // (x, y, z) -> (x, -z, y)
  for (int round = 0; round < 60; ++round) {
    glm::dmat4 world = quarter_turn;
    if (round % 3 != 0) {
      for (int c = 0; c < 4; ++c)
        for (int r = 0; r < 3; ++r) world[c][r] = uniform(-2.0, 2.0);
      if (round % 5 == 0) world[0] *= -1.0;  // mirrored
    }
    const glm::dmat3 linear(world);
    const glm::dmat3 normal_matrix = glm::transpose(glm::inverse(linear));
    const bool mirrored = glm::determinant(linear) < 0.0;
    const std::size_t count = round == 59 ? 70001 : random() % 40, offset = random() % 3;
    std::vector<glm::vec3> positions(offset + count), normals(offset + count);
    std::vector<glm::vec4> tangents(offset + count);
    for (std::size_t v = 0; v < positions.size(); ++v) {
      positions[v] = glm::vec3(float(uniform(-100.0, 100.0)), component(), float(uniform(-1.0, 1.0)));
      normals[v] = glm::vec3(component(), component(), component());
      tangents[v] = glm::vec4(component(), component(), component(), random() % 2 ? 1.0f : -1.0f);
    }
    std::vector<glm::vec3> want_p = positions, want_n = normals;
    std::vector<glm::vec4> want_t = tangents;
    for (std::size_t v = offset; v < positions.size(); ++v)
      mesh_detail::to_frame_one(want_p[v], want_n[v], want_t[v], world, normal_matrix, mirrored);
    mesh_detail::to_frame({positions.data() + offset, count}, {normals.data() + offset, count},
                          {tangents.data() + offset, count}, world, normal_matrix, mirrored);
    ASSERT_EQ(std::memcmp(positions.data(), want_p.data(), positions.size() * sizeof positions[0]), 0) << round;
    ASSERT_EQ(std::memcmp(normals.data(), want_n.data(), normals.size() * sizeof normals[0]), 0) << round;
    ASSERT_EQ(std::memcmp(tangents.data(), want_t.data(), tangents.size() * sizeof tangents[0]), 0) << round;
  }
}

}  // namespace
}  // namespace qdmr
