// NormalMappingProgram::shade of a pair gives each batch what it gives the batch alone, bit for bit in every covered lane:
// batches dense enough to run side by side, and sparse ones whose covered lanes run packed in one batch (small
// triangles).
#include <gtest/gtest.h>

#include <bit>
#include <cstdint>
#include <random>

#include "kernel/lane_packing.hpp"
#include "qdmr/texture/mip_texture.hpp"
#include "kernel/normal_mapping.hpp"
#include "plan/program_choice.hpp"

namespace qdmr {
namespace {

using simd::Float;
using simd::kLanes;

Image random_image(int size, std::mt19937& rng) {
  Image img(size, size, 4);
  std::uniform_real_distribution<float> unit(0.0f, 1.0f);
  for (float& t : img.texels) t = unit(rng);
  return img;
}

// Per quad: a random UV with random screen derivatives (footprints from magnified to several texels), so the
// quad's LOD varies; per lane: a random frame, tangent sign and world point.
Fragments random_fragments(std::mt19937& rng, std::uint32_t covered) {
  std::uniform_real_distribution<float> unit(0.0f, 1.0f), signed_unit(-1.0f, 1.0f);
  alignas(64) float var[kVaryingCount][kLanes] = {};
  for (int q = 0; q < kLanes / 4; ++q) {
    const float u = 4.0f * unit(rng), v = 4.0f * unit(rng);
    const float scale = 0.002f * std::pow(40.0f, unit(rng));
    const float dudx = scale * signed_unit(rng), dvdx = scale * signed_unit(rng);
    const float dudy = scale * signed_unit(rng), dvdy = scale * signed_unit(rng);
    for (int c = 0; c < 4; ++c) {
      const int l = 4 * q + c;
      const float x = float(c % 2), y = float(c / 2);
      var[kU][l] = u + x * dudx + y * dudy;
      var[kV][l] = v + x * dvdx + y * dvdy;
      for (int k = kWorldX; k <= kTangentZ; ++k) var[k][l] = signed_unit(rng);
      var[kNormalZ][l] += 2.0f;  // away from a degenerate frame
      var[kTangentX][l] += 2.0f;
      var[kTangentW][l] = unit(rng) < 0.5f ? -1.0f : 1.0f;
    }
  }
  Fragments in;
  for (int k = 0; k < kVaryingCount; ++k) in.varyings[k] = Float::load_aligned(var[k]);
  in.pixel_x = in.pixel_y = Float(0.0f);
  in.view_depth = Float(5.0f);
  in.covered = simd::from_bits(covered);
  return in;
}

void expect_same_covered_lanes(const ShadeOutput& alone, const ShadeOutput& paired, std::uint32_t covered,
                               int trial) {
  const auto expect = [&](const Float& x, const Float& y, const char* what) {
    alignas(64) float a[kLanes], b[kLanes];
    x.store_aligned(a);
    y.store_aligned(b);
    for (int l = 0; l < kLanes; ++l) {
      if (!((covered >> l) & 1u)) continue;
      ASSERT_EQ(std::bit_cast<std::uint32_t>(a[l]), std::bit_cast<std::uint32_t>(b[l]))
          << what << " lane " << l << " trial " << trial;
    }
  };
  for (int c = 0; c < 3; ++c) {
    expect(alone.color[c], paired.color[c], "color");
    expect(alone.normal[c], paired.normal[c], "normal");
  }
  expect(alone.hit_u, paired.hit_u, "hit_u");
  expect(alone.hit_v, paired.hit_v, "hit_v");
  expect(alone.iterations, paired.iterations, "iterations");
  expect(alone.shadow, paired.shadow, "shadow");
  expect(alone.ao, paired.ao, "ao");
  EXPECT_EQ(alone.writes_depth, paired.writes_depth);
}

LightRig test_lights() {
  LightRig lights;
  lights.directional.push_back({glm::normalize(glm::vec3(0.3f, 0.5f, 0.8f)), glm::vec3(1.0f, 0.9f, 0.8f)});
  lights.ambient = glm::vec3(0.1f);
  lights.camera_position = glm::vec3(0.2f, -0.4f, 3.0f);
  return lights;
}

// with_orm: a random ORM texture of another size than the albedo (its own LOD) is sampled and applied.
void expect_pairs_as_alone(const LightingDesc& lighting, const SpecularFromAlbedo& specular, unsigned seed,
                           bool with_orm = false) {
  std::mt19937 rng(seed);
  const Texture albedo = make_mip_texture(random_image(64, rng), TexelFormat::RGBA8, true, MipReduce::Box);
  const Texture normal = make_mip_texture(random_image(64, rng), TexelFormat::RGBA8, false, MipReduce::Box);
  const Texture orm = make_mip_texture(random_image(32, rng), TexelFormat::RGBA8, false, MipReduce::Box);
  const LightRig lights = test_lights();
  const NormalMappingProgram program("test", albedo, normal, nullptr, with_orm ? &orm : nullptr,
                                     OrmParams{.metallic = 0.75f, .occlusion_strength = 0.5f}, SamplerModes{}, SamplerParams{},
                                     lighting.model, lighting_params(lighting), specular, lights);
  ASSERT_EQ(program.grouping().batches, 2);
  const std::uint32_t all = (1u << kLanes) - 1u;
  int packed = 0, side_by_side = 0;
  for (int trial = 0; trial < 400; ++trial) {
    // Mostly sparse coverage (a few pixels of small triangles), now and then a full batch.
    const auto coverage = [&] {
      const std::uint32_t m = trial % 5 == 0 ? all : (rng() & rng() & all);
      return m != 0 ? m : 1u << (rng() % kLanes);
    };
    const std::uint32_t covered_a = coverage(), covered_b = coverage();
    const Fragments a = random_fragments(rng, covered_a), b = random_fragments(rng, covered_b);
    ShadeOutput alone_a, alone_b, paired_a, paired_b;
    program.shade_one(a, alone_a);
    program.shade_one(b, alone_b);
    const Fragments* const pair_in[2] = {&a, &b};
    ShadeOutput* const pair_out[2] = {&paired_a, &paired_b};
    program.shade(pair_in, pair_out, 2);
    expect_same_covered_lanes(alone_a, paired_a, covered_a, trial);
    expect_same_covered_lanes(alone_b, paired_b, covered_b, trial);
    ++(simd::LanePacking::fits(covered_a, covered_b) ? packed : side_by_side);
  }
  EXPECT_GT(packed, 100);  // both ways of pairing were taken
  EXPECT_GT(side_by_side, 20);
}

TEST(NormalMappingPair, SameBitsAsEachBatchAloneBlinnPhong) { expect_pairs_as_alone(LightingDesc{}, SpecularFromAlbedo{}, 3); }

TEST(NormalMappingPair, SameBitsAsEachBatchAloneCookTorranceWithSpecularFromAlbedo) {
  LightingDesc lighting;
  lighting.model = LightingModel::CookTorrance;
  SpecularFromAlbedo specular;
  specular.enabled = true;
  specular.power = 2.0f;
  expect_pairs_as_alone(lighting, specular, 4);
}

TEST(NormalMappingPair, SameBitsAsEachBatchAloneWithAnOrmTexture) {
  LightingDesc lighting;
  lighting.model = LightingModel::CookTorrance;
  expect_pairs_as_alone(lighting, SpecularFromAlbedo{}, 5, true);
}

// Shades random batches with and without an ORM texture of one texel `orm` (RGBA8 linear, so each channel is a code
// k / 255) and the given factors.
struct OrmShades {
  std::vector<ShadeOutput> with, without;
};
OrmShades shade_with_and_without_orm(const glm::vec4& orm_texel, const OrmParams& factors, LightRig lights,
                                     LightingModel model) {
  std::mt19937 rng(11);
  const Texture albedo = make_mip_texture(random_image(64, rng), TexelFormat::RGBA8, true, MipReduce::Box);
  const Texture normal = make_mip_texture(random_image(64, rng), TexelFormat::RGBA8, false, MipReduce::Box);
  Image one(1, 1, 4);
  for (int c = 0; c < 4; ++c) one.texels[std::size_t(c)] = orm_texel[c];
  const Texture orm = make_mip_texture(one, TexelFormat::RGBA8, false, MipReduce::Box);
  LightingParams lighting;
  lighting.roughness = 0.37f;
  lighting.specular = 0.04f;
  const NormalMappingProgram plain("test", albedo, normal, nullptr, nullptr, OrmParams{}, SamplerModes{}, SamplerParams{}, model,
                                   lighting, SpecularFromAlbedo{}, lights);
  const NormalMappingProgram textured("test", albedo, normal, nullptr, &orm, factors, SamplerModes{}, SamplerParams{}, model, lighting,
                                      SpecularFromAlbedo{}, lights);
  OrmShades shades;
  for (int trial = 0; trial < 50; ++trial) {
    const Fragments in = random_fragments(rng, (1u << kLanes) - 1u);
    shades.with.emplace_back();
    shades.without.emplace_back();
    textured.shade_one(in, shades.with.back());
    plain.shade_one(in, shades.without.back());
  }
  return shades;
}

// An ORM texture of (1, 1, 1) with metallic 0 changes nothing: the roughness it gives is 1 * roughness, the albedo
// times 1 - 0, F0 plus 0, the occlusion 1 (apply_orm): the same bits as the constant-roughness material.
TEST(NormalMappingOrm, WhiteOrmWithoutMetalGivesTheBitsOfConstantRoughness) {
  for (const LightingModel model : {LightingModel::CookTorrance, LightingModel::BlinnPhong}) {
    const OrmShades s = shade_with_and_without_orm(glm::vec4(1.0f), OrmParams{.metallic = 0.0f, .occlusion_strength = 1.0f},
                                                   test_lights(), model);
    for (std::size_t t = 0; t < s.with.size(); ++t) expect_same_covered_lanes(s.without[t], s.with[t], (1u << kLanes) - 1u, int(t));
  }
}

// Occlusion R = 128/255 (the code nearest 0.5), metalness 0, under ambient light only: the colour is albedo * (ambient *
// ao) with ao = 1 + (R - 1) = R exactly (both steps exact in float), so it is the ORM-less colour times R: with an
// ambient of 0.5 (a power of two) both round the one exact product albedo * R / 2, so the bits are equal.
TEST(NormalMappingOrm, OcclusionScalesTheAmbientTerm) {
  LightRig ambient_only = test_lights();
  ambient_only.directional.clear();
  ambient_only.ambient = glm::vec3(0.5f);
  const float r = 128.0f / 255.0f;
  const OrmShades s = shade_with_and_without_orm(glm::vec4(r, 1.0f, 0.0f, 1.0f), OrmParams{}, ambient_only,
                                                 LightingModel::CookTorrance);
  int lanes = 0;
  for (std::size_t t = 0; t < s.with.size(); ++t)
    for (int c = 0; c < 3; ++c) {
      alignas(64) float with[kLanes], without[kLanes], ao[kLanes];
      s.with[t].color[c].store_aligned(with);
      s.without[t].color[c].store_aligned(without);
      s.with[t].ao.store_aligned(ao);
      for (int l = 0; l < kLanes; ++l, ++lanes) {
        ASSERT_EQ(ao[l], r);  // the AO AOV is the occlusion
        ASSERT_EQ(with[l], without[l] * r) << "trial " << t << " lane " << l;
      }
    }
  EXPECT_GT(lanes, 1000);
}

}  // namespace
}  // namespace qdmr
