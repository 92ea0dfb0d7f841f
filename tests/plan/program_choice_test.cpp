// The plan's choice of program (plan/program_choice.hpp): the key is canonical (what a program ignores does not
// make a new key), it prints as the variant `qdmr plan` shows, and the parameters carry the material's numbers.
#include <gtest/gtest.h>

#include "plan/program_choice.hpp"

namespace qdmr {
namespace {

MaterialDesc material(TechniqueKind technique, int layers = 1) {
  MaterialDesc m;
  m.name = "m";
  m.technique.kind = technique;
  m.layers.resize(std::size_t(layers));
  return m;
}

TEST(ProgramChoice, TheKeyIgnoresWhatTheProgramIgnores) {
  // The QDM options of another technique (exact math's fp64 walls; sm3 math's fp32 texel addresses are the
  // samplers' too: SamplerStatesAreKeys).
  MaterialDesc pom = material(TechniqueKind::Pom);
  MaterialDesc pom_qdm_options = pom;
  pom_qdm_options.sampling.math = MathMode::Exact;
  pom_qdm_options.technique.level_up = QdmLevelUp::Aligned;
  EXPECT_EQ(program_key(pom), program_key(pom_qdm_options));
  // The blend of a single layer.
  MaterialDesc single = pom;
  single.blend.op = BlendOperator::Alpha;
  single.blend.weights.mode = WeightMode::Vertex;
  EXPECT_EQ(program_key(pom), program_key(single));
  EXPECT_EQ(program_params(single).blend.width, BlendParams{}.width);
  // But each mode that changes the code does.
  MaterialDesc qdm = material(TechniqueKind::Qdm), qdm_sm3 = qdm;
  qdm_sm3.sampling.math = MathMode::Sm3;
  EXPECT_NE(program_key(qdm), program_key(qdm_sm3));
  MaterialDesc shadowed = pom;
  shadowed.shadow.mode = ShadowMode::Horizon;
  EXPECT_NE(program_key(pom), program_key(shadowed));
  MaterialDesc blended = material(TechniqueKind::Pom, 2), blended_alpha = blended;
  blended_alpha.blend.op = BlendOperator::Alpha;
  EXPECT_NE(program_key(blended), program_key(blended_alpha));
  // Numbers are parameters, not keys.
  MaterialDesc deeper = pom;
  deeper.technique.depth_scale = 0.3f;
  deeper.technique.max_steps = 96;
  EXPECT_EQ(program_key(pom), program_key(deeper));
}

TEST(ProgramChoice, TheVariantIsTheKeyPrinted) {
  EXPECT_EQ(variant_name(program_key(material(TechniqueKind::Normal))), "normal_mapping | blinn_phong | trilinear");
  MaterialDesc qdm = material(TechniqueKind::Qdm);
  qdm.sampling.math = MathMode::Sm3;
  qdm.technique.height_fetch = HeightFetch::Trilinear;
  qdm.technique.level_up = QdmLevelUp::Aligned;
  qdm.sampling.filter = Filter::Bilinear;
  qdm.lighting.model = LightingModel::CookTorrance;
  EXPECT_EQ(variant_name(program_key(qdm)),
            "displacement:qdm<sm3_cells,filtered_max,level_up_aligned> | cook_torrance | bilinear");
  MaterialDesc blend = material(TechniqueKind::Relief, 3);
  blend.blend.op = BlendOperator::HeightWidth;
  blend.blend.weights.mode = WeightMode::Vertex;
  blend.shadow.mode = ShadowMode::QdmSoft;
  blend.ao.mode = AoMode::Baked;
  EXPECT_EQ(variant_name(program_key(blend)),
            "displacement:relief | blend height_width x3 per vertex | shadow qdm_soft | ao baked | blinn_phong | trilinear");
  // Normal mapping of blended layers runs the displacement program (its blend needs the heights).
  EXPECT_EQ(variant_name(program_key(material(TechniqueKind::Normal, 2))),
            "displacement:normal | blend height x2 per pixel | blinn_phong | trilinear");
}

// Every sampler state that changes a program's code is in its key, and printed; the LOD bias and clamp are numbers.
TEST(ProgramChoice, SamplerStatesAreKeys) {
  MaterialDesc pom = material(TechniqueKind::Pom);
  const auto key_with = [&](auto change) {
    MaterialDesc m = pom;
    change(m);
    return program_key(m);
  };
  const ProgramKey plain = program_key(pom);
  EXPECT_EQ(plain.sampler, SamplerModes{});
  EXPECT_EQ(key_with([](MaterialDesc& m) { m.sampling.filter = Filter::PointMipLinear; }).sampler.filter,
            Filter::PointMipLinear);
  EXPECT_EQ(key_with([](MaterialDesc& m) { m.sampling.address = AddressMode::Clamp; }).sampler.address,
            AddressMode::Clamp);
  EXPECT_EQ(key_with([](MaterialDesc& m) { m.sampling.precision = SamplePrecision::Hw6; }).sampler.precision,
            SamplePrecision::Hw6);
  EXPECT_EQ(key_with([](MaterialDesc& m) { m.sampling.lod = LodMode::PerPixel; }).sampler.lod, LodMode::PerPixel);
  EXPECT_TRUE(key_with([](MaterialDesc& m) { m.sampling.math = MathMode::Sm3; }).sampler.fp32_texels);
  EXPECT_EQ(key_with([](MaterialDesc& m) { m.technique.height_fetch = HeightFetch::Point; }).sampler.heights,
            HeightFetch::Point);
  // The LOD bias and clamp are parameters.
  EXPECT_EQ(key_with([](MaterialDesc& m) {
              m.sampling.lod_bias = 1.5f;
              m.sampling.min_lod = 1.0f;
              m.sampling.max_lod = 4.0f;
            }),
            plain);
  // Normal mapping reads no heights.
  MaterialDesc normal = material(TechniqueKind::Normal), normal_point = normal;
  normal_point.technique.height_fetch = HeightFetch::Point;
  EXPECT_EQ(program_key(normal), program_key(normal_point));
  // Printed after the filter where not the default.
  MaterialDesc sampled = pom;
  sampled.sampling = {.filter = Filter::Bilinear,
                      .address = AddressMode::Mirror,
                      .precision = SamplePrecision::Hw8,
                      .lod = LodMode::PerPixel,
                      .math = MathMode::Sm3};
  sampled.technique.height_fetch = HeightFetch::Trilinear;
  EXPECT_EQ(variant_name(program_key(sampled)),
            "displacement:pom | blinn_phong | bilinear mirror hw8 per_pixel_lod sm3_texels trilinear_heights");
  sampled.sampling.address = AddressMode::Clamp;
  sampled.sampling.precision = SamplePrecision::Hw6;
  sampled.technique.height_fetch = HeightFetch::Point;
  EXPECT_EQ(variant_name(program_key(sampled)),
            "displacement:pom | blinn_phong | bilinear clamp hw6 per_pixel_lod sm3_texels point_heights");
  MaterialDesc biased = pom;
  biased.sampling.lod_bias = -2.0f;
  biased.sampling.min_lod = 0.5f;
  biased.sampling.max_lod = 3.0f;
  const SamplerParams p = program_params(biased).sampler;
  EXPECT_EQ(p.lod_bias, -2.0f);
  EXPECT_EQ(p.min_lod, 0.5f);
  EXPECT_EQ(p.max_lod, 3.0f);
}

TEST(ProgramChoice, TheParametersCarryTheMaterialsNumbers) {
  MaterialDesc m = material(TechniqueKind::Pom, 2);
  m.technique.depth_scale = 0.125f;
  m.technique.min_steps = 3;
  m.technique.lod_threshold = 2.5f;
  m.technique.fade_end = 40.0f;
  m.sampling.address = AddressMode::Mirror;
  m.sampling.lod_bias = -0.5f;
  m.lighting.roughness = 0.75f;
  m.layers[1].specular.enabled = true;
  m.layers[1].specular.power = 2.0f;
  m.shadow.tap_weights = {0.5f, 0.25f};
  m.shadow.bias = 0.01f;
  m.ao.radius = 0.2f;
  m.ao.directions = 12;
  m.ao.strength = 0.5f;
  m.blend.width = 0.3f;
  m.blend.weights.scale = 4.0f;
  const ProgramParams p = program_params(m);
  EXPECT_EQ(p.trace.depth_scale, 0.125f);
  EXPECT_EQ(p.trace.min_steps, 3);
  EXPECT_EQ(p.trace.lod_threshold, 2.5f);
  EXPECT_EQ(p.trace.fade_end, 40.0f);
  EXPECT_EQ(p.sampler.lod_bias, -0.5f);
  EXPECT_EQ(program_key(m).sampler.address, AddressMode::Mirror);
  EXPECT_EQ(p.lighting.roughness, 0.75f);
  ASSERT_EQ(p.specular.size(), 2u);
  EXPECT_FALSE(p.specular[0].enabled);
  EXPECT_TRUE(p.specular[1].enabled);
  EXPECT_EQ(p.specular[1].power, 2.0f);
  EXPECT_EQ(p.shadow.tap_weights, (std::vector<float>{0.5f, 0.25f}));
  EXPECT_EQ(p.shadow.bias, 0.01f);
  EXPECT_EQ(p.ao.radius, 0.2f);
  EXPECT_EQ(p.ao.directions, 12);
  EXPECT_EQ(p.ao.strength, 0.5f);
  EXPECT_EQ(p.blend.width, 0.3f);
  EXPECT_EQ(p.blend.weights_scale, 4.0f);
}

}  // namespace
}  // namespace qdmr
