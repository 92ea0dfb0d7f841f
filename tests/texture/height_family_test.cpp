// The rebuild of a dynamic height's textures together (texture/height_family.hpp) gives each texture the bits of
// the generic builders: make_height_texture with its decoded copy and wrap footprints, and the from_height normal
// slot through make_mip_texture. For the baseline's rows and every kernel's this CPU runs, on waves and on handed-
// over heights of odd sizes (the generic taps), R8 and R16, and when it refills an earlier frame's textures.
#include <gtest/gtest.h>

#include <memory>
#include <random>
#include <string>
#include <vector>

#include "kernel/kernel.hpp"
#include "qdmr/core/isa.hpp"
#include "texture/height_texture.hpp"
#include "qdmr/texture/texture_level0.hpp"
#include "texture/height_family.hpp"

namespace qdmr {
namespace {

// The waves of scenes/water.json at 64² (its shortest wave has 17 cycles per repeat), at `time` seconds.
LayerDesc waves_layer(double time) {
  LayerDesc layer;
  TextureDesc& h = layer.height;
  h.source = TextureSource::Procedural;
  h.procedural.pattern = ProceduralPattern::Waves;
  h.procedural.size = 64;
  h.procedural.time = time;
  const int cycles[4][2] = {{2, 1}, {2, -2}, {2, 7}, {-14, 8}};
  const int sharpness[4] = {3, 2, 2, 1};
  const float amplitude[4] = {1.0f, 0.6f, 0.35f, 0.2f};
  for (int i = 0; i < 4; ++i) {
    WaveDesc w;
    w.amplitude = amplitude[i];
    w.speed = 0.1f;
    w.sharpness = sharpness[i];
    w.cycles_u = cycles[i][0], w.cycles_v = cycles[i][1];
    h.procedural.waves.push_back(w);
  }
  layer.normal_strength = 0.6f;
  return layer;
}

// Heights handed over as pixels, w x h, some outside [0, 1] (the layer's transform clamps them).
LayerDesc pixels_layer(int w, int h, TextureFormatChoice format, unsigned seed) {
  auto image = std::make_shared<Image>(w, h, 1);
  std::mt19937 rng(seed);
  std::uniform_real_distribution<float> u(-0.2f, 1.2f);
  for (float& v : image->texels) v = u(rng);
  LayerDesc layer;
  layer.height.source = TextureSource::Pixels;
  layer.height.format = format;
  layer.height.pixels = image;
  layer.height_scale = 0.9f;
  layer.height_offset = 0.05f;
  layer.normal_strength = 2.5f;
  return layer;
}

// The generic builders' textures, as prepare made them before the family rebuild.
std::vector<Texture> generic(const LayerDesc& layer, const std::vector<HeightFamilyMember>& members, TexelFormat& format) {
  const Image heights = make_layer_height(layer, "test");
  format = height_format(layer.height, heights.source_bits);
  std::vector<Texture> out;
  for (const HeightFamilyMember& m : members) {
    Texture t;
    if (m.normals) {
      LayerDesc normal_layer = layer;
      normal_layer.normal_strength = m.normal_strength;
      TextureDesc from_height;
      from_height.source = TextureSource::FromHeight;
      const Image stored = make_height_texture(heights, layer.height, MipReduce::Box).texture.level_image(0);
      Image level0 = make_texture(from_height, TexturePurpose::Normal, normal_layer, &stored, "test");
      for (float& v : level0.texels) v = 0.5f + 0.5f * v;
      t = make_mip_texture(level0, TexelFormat::RGBA8, false, MipReduce::BoxNormal);
    } else {
      t = make_height_texture(heights, layer.height, m.reduce).texture;
    }
    add_linear_copy(t);
    if (m.wrap_footprints) add_wrap_footprints(t);
    out.push_back(std::move(t));
  }
  return out;
}

std::vector<HeightFamilyMember> members() {
  std::vector<HeightFamilyMember> m(4);
  m[0].wrap_footprints = true;
  m[1].reduce = MipReduce::Max;
  m[2].normals = true;
  m[2].normal_strength = 0.6f;
  m[3].normals = true;
  m[3].normal_strength = 3.0f;
  return m;
}

struct Rows {
  std::string name;
  const HeightRows* rows;
  MipExtremum extremum;
};

std::vector<Rows> every_rows() {
  std::vector<Rows> out{{"baseline", &baseline_height_rows(), nullptr}};
  for (Isa isa : usable_isas())
    out.push_back({isa_name(isa), &kernel_for(isa).height_rows(), kernel_for(isa).mip_extremum()});
  return out;
}

void expect_generic_bits(const LayerDesc& layer, std::vector<HeightFamilyMember>& built, const Rows& rows,
                         const std::string& what) {
  TexelFormat format;
  const std::vector<Texture> expected = generic(layer, built, format);
  build_height_family(layer, format, "test", built, *rows.rows, rows.extremum);
  for (std::size_t i = 0; i < built.size(); ++i) {
    const Texture &a = built[i].texture, &b = expected[i];
    EXPECT_EQ(a.format, b.format) << what << " " << rows.name << " member " << i;
    ASSERT_EQ(a.levels.size(), b.levels.size()) << what << " " << rows.name << " member " << i;
    EXPECT_TRUE(a.storage == b.storage) << what << " " << rows.name << " member " << i;
    EXPECT_TRUE(a.linear == b.linear) << what << " " << rows.name << " member " << i;
    EXPECT_TRUE(a.wrap_footprints == b.wrap_footprints) << what << " " << rows.name << " member " << i;
  }
}

TEST(HeightFamily, EveryTextureHasTheGenericBuildersBits) {
  const struct {
    std::string what;
    LayerDesc layer;
  } cases[] = {
      {"waves", waves_layer(0.75)},
      {"waves r8", [] {
         LayerDesc l = waves_layer(1.5);
         l.height.format = TextureFormatChoice::R8;
         l.height_scale = 1.2f;  // clamps the crests
         return l;
       }()},
      {"pixels 37x23 r16", pixels_layer(37, 23, TextureFormatChoice::R16, 1)},
      {"pixels 5x64 r8", pixels_layer(5, 64, TextureFormatChoice::R8, 2)},
      {"pixels 1x1", pixels_layer(1, 1, TextureFormatChoice::R16, 3)},
      {"pixels 2x1", pixels_layer(2, 1, TextureFormatChoice::R16, 4)},
      {"pixels 1x3", pixels_layer(1, 3, TextureFormatChoice::R8, 5)},
  };
  for (const Rows& rows : every_rows())
    for (const auto& c : cases) {
      std::vector<HeightFamilyMember> built = members();
      expect_generic_bits(c.layer, built, rows, c.what);
    }
}

// The normals and their BoxNormal levels are made in float first and the texels whose float codes might differ
// from the exact ones redone exactly (texture/height_rows_code.hpp): about 0.6 % of the texels of a 512 x 384 field
// of random heights (so thousands, of which a margin too small would get hundreds wrong), at strengths whose float
// scale is subnormal (1e-40), ordinary (0.6, 40), makes the float squares overflow (1e17) or exceeds a float's range
// (3e38: the exact texel's infinite length gives (0, 0, 1)).
TEST(HeightFamily, FloatNormalsAreRedoneExactlyWhereTheirCodesMightDiffer) {
  const LayerDesc layer = pixels_layer(512, 384, TextureFormatChoice::R16, 7);
  for (const Rows& rows : every_rows()) {
    std::vector<HeightFamilyMember> built(1);
    for (float strength : {1e-40f, 0.6f, 40.0f, 1e17f, 3e38f}) {
      HeightFamilyMember m;
      m.normals = true;
      m.normal_strength = strength;
      built.push_back(std::move(m));
    }
    expect_generic_bits(layer, built, rows, "random 512x384");
  }
}

TEST(HeightFamily, RefillingAnEarlierFramesTexturesGivesTheSameBits) {
  for (const Rows& rows : every_rows()) {
    // Frame 1's textures refilled with frame 2's heights, and textures of another size (reallocated).
    std::vector<HeightFamilyMember> built = members();
    expect_generic_bits(waves_layer(1.0 / 24), built, rows, "frame 1");
    expect_generic_bits(waves_layer(2.0 / 24), built, rows, "frame 2");
    expect_generic_bits(pixels_layer(9, 9, TextureFormatChoice::R16, 6), built, rows, "resized");
  }
}

}  // namespace
}  // namespace qdmr
