// Height blending: QDM over blended layers (QDMHB) never skips an intersection of the blended surface, its
// iteration overhead over QDM on the combined surface, and the per-vertex "floating" artifact.
#include <gtest/gtest.h>

#include <algorithm>
#include <bit>
#include <cmath>
#include <cstdio>
#include <cstring>
#include <random>

#include "displacement_test_util.hpp"
#include "kernel/kernel.hpp"
#include "kernel/self_shadow.hpp"
#include "texture/blend_box_values.hpp"
#include "texture/blend_weights.hpp"
#include "plan/program_choice.hpp"

namespace qdmr::test {
namespace {

constexpr int kLayers = 4;

// Runs the displacement program over blended layers on per-lane rays, as TechniqueHarness does for one layer.
class BlendHarness {
public:
  // heights: one power-of-two image per layer (same size); weights: RGBA level 0 of the weight texture (the
  // map spans `scale` texture repeats).
  // combined: QDM walks the precomputed combined quadtree instead of bounding cells by max(hmax_i * wmax_i).
  BlendHarness(const std::vector<Image>& heights, const Image& weights, float scale, const TechniqueDesc& technique,
               BlendOperator op, WeightMode mode, bool combined = false)
      : weights_(make_mip_texture(weights, TexelFormat::RGBA8, false, MipReduce::Max)),
        flat_(make_mip_texture(Image(1, 1, 4), TexelFormat::RGBA8, false, MipReduce::Box)) {
    for (const Image& h : heights) {
      heights_.push_back(make_mip_texture(h, TexelFormat::R32F, false, MipReduce::Box));
      maxima_.push_back(make_mip_texture(h, TexelFormat::R32F, false, MipReduce::Max));
    }
    material_.technique = technique;
    material_.sampling.filter = Filter::Bilinear;
    material_.layers.resize(heights.size());
    material_.blend.op = op;
    material_.blend.weights.mode = mode;
    material_.blend.weights.scale = scale;
    if (combined) {
      std::vector<const Texture*> layers;
      for (const Texture& h : heights_) layers.push_back(&h);
      combined_ = combined_quadtree(combined_surface(layers, weights_, int(scale), op));
      period_u_ = heights[0].width * int(scale);
      period_v_ = heights[0].height * int(scale);
    }
  }

  // The stored weight of layer i in texel (x, y) of the weight texture (RGBA8: quantised).
  float weight(int x, int y, int i) const { return weights_.texel(0, x, y, i); }

  // vertex_weights: per ray, the weights the vertices would give (used in vertex mode).
  std::vector<TechniqueResult> run(const std::vector<TechniqueRay>& rays,
                                   const std::vector<std::array<float, kLayers>>& vertex_weights = {}) const {
    DisplacementInputs inputs;
    for (std::size_t i = 0; i < heights_.size(); ++i) inputs.layers.push_back({&flat_, &flat_, &heights_[i], &maxima_[i]});
    inputs.weights = &weights_;
    if (period_u_ > 0) {
      inputs.combined = &combined_;
      inputs.combined_period_u = period_u_;
      inputs.combined_period_v = period_v_;
    }
    LightRig rig;
    rig.camera_position = glm::vec3(0.0f);
    return trace_rays(DisplacementProgram(inputs, program_key(material_), program_params(material_), rig), rays, vertex_weights);
  }

private:
  std::vector<Texture> heights_, maxima_;
  Texture weights_, flat_, combined_;
  int period_u_ = 0, period_v_ = 0;
  MaterialDesc material_;
};

Image random_heights(int width, int height, std::uint32_t seed) {
  std::mt19937 rng(seed);
  std::uniform_real_distribution<float> unit(0.0f, 1.0f);
  Image img(width, height, 1);
  for (float& t : img.texels) t = unit(rng);
  return img;
}

Image random_heights(int size, std::uint32_t seed) { return random_heights(size, size, seed); }

Image random_weights(int width, int height, std::uint32_t seed) {
  std::mt19937 rng(seed);
  std::uniform_real_distribution<float> unit(0.0f, 1.0f);
  Image img(width, height, 4);
  for (float& t : img.texels) t = unit(rng) < 0.3f ? 0.0f : unit(rng);  // some layers absent
  return img;
}

Image random_weights(int size, std::uint32_t seed) { return random_weights(size, size, seed); }

TechniqueDesc qdm_box() {
  TechniqueDesc t;
  t.kind = TechniqueKind::Qdm;
  t.refinement = QdmRefinement::None;
  t.height_fetch = HeightFetch::Point;
  t.max_iterations = 1 << 14;
  return t;
}

// Every texel centre and corner as an origin, 16 azimuths, 5 elevations: all the ways into a small map.
std::vector<TechniqueRay> exhaustive_rays(int width, int height) {
  std::vector<TechniqueRay> rays;
  for (int y = 0; y < 2 * height; ++y)
    for (int x = 0; x < 2 * width; ++x)
      for (double elevation : {80.0, 45.0, 20.0, 8.0, 2.0})
        for (int a = 0; a < 16; ++a) {
          const double azimuth = 2.0 * std::numbers::pi * (a + 0.25) / 16.0;
          const double reach = 1.0 / std::tan(elevation * std::numbers::pi / 180.0);
          rays.push_back({(x * 0.5 + 0.25) / width, (y * 0.5 + 0.25) / height, reach * std::cos(azimuth),
                          reach * std::sin(azimuth)});
        }
  return rays;
}

std::vector<TechniqueRay> exhaustive_rays(int size) { return exhaustive_rays(size, size); }

// The height-blend box surface the weight texture defines when it matches the layers texel for texel (scale 1,
// same size): bilinear weights at a texel centre are that texel's stored weights, so H0 = max_i(w_i h_i) exactly.
HeightField combined_field(const std::vector<Image>& heights, const BlendHarness& harness) {
  HeightField f;
  f.width = heights[0].width;
  f.height = heights[0].height;
  f.h = ZeroedBuffer<double>(std::size_t(f.width) * std::size_t(f.height));
  for (int y = 0; y < f.height; ++y)
    for (int x = 0; x < f.width; ++x) {
      float top = 0.0f;
      for (int i = 0; i < kLayers; ++i) top = std::max(top, harness.weight(x, y, i) * heights[std::size_t(i)].at(x, y, 0));
      f.h[std::size_t(y) * std::size_t(f.width) + std::size_t(x)] = top;
    }
  return f;
}

// Square layers, and layers twice as wide as high (whose combined quadtree repeats with another period in v).
TEST(HeightBlend, QdmhbNeverSkipsAnIntersectionOfTheBlendedSurface) {
  for (const auto& [width, height] : {std::pair{8, 8}, std::pair{16, 16}, std::pair{16, 8}}) {
    std::vector<Image> heights;
    for (int i = 0; i < kLayers; ++i) heights.push_back(random_heights(width, height, 100u + std::uint32_t(width + i)));
    const Image weights = random_weights(width, height, 7u + std::uint32_t(width));
    for (const auto& [ds, combined] : {std::pair{0.05, false}, std::pair{0.3, false}, std::pair{0.05, true}, std::pair{0.3, true}}) {
      TechniqueDesc t = qdm_box();
      t.depth_scale = float(ds);
      const BlendHarness harness(heights, weights, 1.0f, t, BlendOperator::Height, WeightMode::Pixel, combined);
      const HeightField field = combined_field(heights, harness);
      const std::vector<TechniqueRay> rays = exhaustive_rays(width, height);
      const std::vector<TechniqueResult> results = harness.run(rays);
      int wrong = 0;
      double worst = 0.0;
      for (std::size_t k = 0; k < rays.size(); ++k) {
        const SurfaceRay r{{rays[k].u0, rays[k].v0, 0.0}, {rays[k].du, rays[k].dv, 1.0}};
        const ReferenceHit ref = intersect_reference(field, ds, r, ReferenceSurface::Box);
        ASSERT_TRUE(ref.hit);
        const double e = error_texels(field, results[k], ref);
        worst = std::max(worst, e);
        // 1e-3 texel: fp32 positions of a hit on a wall or top face against the fp64 reference (the same bound
        // as single-layer QDM); a skipped column would be off by at least a texel.
        if (e > 1e-3) ++wrong;
      }
      EXPECT_EQ(wrong, 0) << width << "x" << height << ", depth " << ds
                          << (combined ? ", combined quadtree" : ", product bound") << ": "
                          << rays.size() << " rays, worst " << worst << " texels";
    }
  }
}

TEST(HeightBlend, QdmhbWithVertexWeightsIsExactOverItsConstantWeights) {
  const int size = 16;
  std::vector<Image> heights;
  for (int i = 0; i < kLayers; ++i) heights.push_back(random_heights(size, 300u + std::uint32_t(i)));
  TechniqueDesc t = qdm_box();
  t.depth_scale = 0.2f;
  const BlendHarness harness(heights, random_weights(size, 5), 1.0f, t, BlendOperator::Height, WeightMode::Vertex);
  const std::array<float, kLayers> w{0.25f, 1.0f, 0.0f, 0.75f};
  const std::vector<TechniqueRay> rays = exhaustive_rays(size);
  const std::vector<TechniqueResult> results = harness.run(rays, std::vector<std::array<float, kLayers>>(rays.size(), w));
  HeightField field;
  field.width = field.height = size;
  field.h = ZeroedBuffer<double>(std::size_t(size) * std::size_t(size));
  for (int y = 0; y < size; ++y)
    for (int x = 0; x < size; ++x) {
      float top = 0.0f;
      for (int i = 0; i < kLayers; ++i) top = std::max(top, w[std::size_t(i)] * heights[std::size_t(i)].at(x, y, 0));
      field.h[std::size_t(y * size + x)] = top;
    }
  for (std::size_t k = 0; k < rays.size(); ++k) {
    const ReferenceHit ref = intersect_reference(field, 0.2, {{rays[k].u0, rays[k].v0, 0.0}, {rays[k].du, rays[k].dv, 1.0}},
                                                 ReferenceSurface::Box);
    ASSERT_LE(error_texels(field, results[k], ref), 1e-3) << "ray " << k;  // as above
  }
}

// The conservative bound costs iterations: QDMHB against QDM on one height map holding the exact combined
// surface (same hits, tighter quadtree). The talk reports under 10% more in practice.
TEST(HeightBlend, QdmhbIterationOverheadOverQdmOnTheCombinedSurface) {
  const int size = 128;
  std::vector<Image> heights;
  for (int i = 0; i < kLayers; ++i) heights.push_back(pattern(i % 2 ? ProceduralPattern::Noise : ProceduralPattern::Sine, size, 4 + i));
  // Smooth weights, as terrain maps have: noise fields at 2 cells per side, strongest layer 1.
  WeightsDesc w;
  w.resolution = size;
  w.cells = 2;
  const Image map = make_weight_map(w, kLayers, "test");
  Image weights(size, size, 4);
  for (int y = 0; y < size; ++y)
    for (int x = 0; x < size; ++x)
      for (int c = 0; c < 4; ++c) weights.at(x, y, c) = map.at(x * map.width / size, y * map.height / size, c);
  TechniqueDesc t = qdm_box();
  t.depth_scale = 0.1f;
  const BlendHarness blended(heights, weights, 1.0f, t, BlendOperator::Height, WeightMode::Pixel);
  const BlendHarness precomputed(heights, weights, 1.0f, t, BlendOperator::Height, WeightMode::Pixel, true);
  const HeightField field = combined_field(heights, blended);
  Image combined(size, size, 1);
  for (std::size_t k = 0; k < field.h.size(); ++k) combined.texels[k] = float(field.h[k]);
  const TechniqueHarness single(combined, t, Filter::Bilinear);
  const std::vector<TechniqueRay> rays = test::rays(400, 11);
  const std::vector<TechniqueResult> a = blended.run(rays), b = single.run(rays), c = precomputed.run(rays);
  double ia = 0.0, ib = 0.0, ic = 0.0;
  for (std::size_t k = 0; k < rays.size(); ++k) {
    ia += a[k].iterations;
    ib += b[k].iterations;
    ic += c[k].iterations;
    EXPECT_NEAR(a[k].hit_depth, b[k].hit_depth, 1e-6) << "ray " << k;  // same surface, same hits (fp32 depths)
    EXPECT_NEAR(c[k].hit_depth, b[k].hit_depth, 1e-6) << "ray " << k;
  }
  const double overhead = ia / ib - 1.0, combined_overhead = ic / ib - 1.0;
  std::printf("QDM on the combined surface %.2f iterations per ray; QDMHB with the product bound %.2f (%+.1f%%), "
              "with the precomputed combined quadtree %.2f (%+.1f%%)\n",
              ib / double(rays.size()), ia / double(rays.size()), 100.0 * overhead, ic / double(rays.size()),
              100.0 * combined_overhead);
  // The combined quadtree is the max-quadtree of the same surface, its values rounded up to 16 bits: the same
  // walk but for the rare cell whose top the rounding lifts above the ray (measured below 1%).
  EXPECT_LT(std::abs(combined_overhead), 0.01);
  EXPECT_GE(overhead, 0.0);  // a looser quadtree can only cost iterations
  // Measured +12% here (the talk: under 10% in practice). The overhead grows with how fast the weights change
  // per cell; 25% guards against the bound degenerating (per-batch maxima alone gave +44%, global ones +100%).
  EXPECT_LT(overhead, 0.25);
}

// Per-vertex weights are constant along each view ray (taken where it enters the polygon), so the reconstructed
// surface floats with the view; per-pixel weights are read where the ray is. Both against the exact surface
// with per-pixel weights, on a ramp from layer 0 to layer 1 across the map.
TEST(HeightBlend, VertexWeightsFloatAtHighDepthScalePixelWeightsDoNot) {
  const int size = 64;
  const std::vector<Image> heights = {pattern(ProceduralPattern::Sine, size, 4), pattern(ProceduralPattern::Steps, size, 4),
                                      filled(size, 0.0f), filled(size, 0.0f)};
  Image weights(size, size, 4);
  for (int y = 0; y < size; ++y)
    for (int x = 0; x < size; ++x) {
      weights.at(x, y, 0) = float(x) / float(size - 1);
      weights.at(x, y, 1) = 1.0f - float(x) / float(size - 1);
    }
  // Views 30 degrees and more above the surface: the drift of the weights along a ray is its reach times ds.
  std::vector<TechniqueRay> rays;
  for (const TechniqueRay& r : test::rays(300, 23))
    if (std::hypot(r.du, r.dv) < 1.8) rays.push_back(r);
  for (double ds : {0.02, 0.3}) {
    TechniqueDesc t = qdm_box();
    t.depth_scale = float(ds);
    const BlendHarness pixel(heights, weights, 1.0f, t, BlendOperator::Height, WeightMode::Pixel);
    const BlendHarness vertex(heights, weights, 1.0f, t, BlendOperator::Height, WeightMode::Vertex);
    const HeightField field = combined_field(heights, pixel);
    // What interpolated vertex weights give at the pixel: the (linear) ramp at the entry point.
    std::vector<std::array<float, kLayers>> entry;
    for (const TechniqueRay& r : rays) {
      const double x = std::clamp((r.u0 - std::floor(r.u0)) * size - 0.5, 0.0, double(size - 1));
      entry.push_back({float(x / (size - 1)), float(1.0 - x / (size - 1)), 0.0f, 0.0f});
    }
    const std::vector<TechniqueResult> p = pixel.run(rays), v = vertex.run(rays, entry);
    double pixel_worst = 0.0, vertex_mean = 0.0;
    int vertex_missed = 0;
    for (std::size_t k = 0; k < rays.size(); ++k) {
      const ReferenceHit ref =
          intersect_reference(field, ds, {{rays[k].u0, rays[k].v0, 0.0}, {rays[k].du, rays[k].dv, 1.0}}, ReferenceSurface::Box);
      pixel_worst = std::max(pixel_worst, error_texels(field, p[k], ref));
      const double e = error_texels(field, v[k], ref);
      vertex_mean += e / double(rays.size());
      if (e > 1.0) ++vertex_missed;
    }
    std::printf("depth %.2f: per-pixel worst error %.2g texels; per-vertex mean %.3f texels, %.1f%% of rays off by > 1 texel\n",
                ds, pixel_worst, vertex_mean, 100.0 * vertex_missed / double(rays.size()));
    EXPECT_LE(pixel_worst, 1e-3);  // exact, as in the exhaustive test
    if (ds > 0.1) {
      EXPECT_GT(vertex_missed, int(rays.size() / 50));  // the artifact is there at high depth scale ...
    } else {
      EXPECT_LT(vertex_mean, 0.1);  // ... and negligible at low depth scale (measured 0.008 texels)
    }
  }
}

}  // namespace
}  // namespace qdmr::test

namespace qdmr::test {
namespace {

// Self-shadowing over a blend reads the weights where the light ray is, in whichever texture repeat: the hard
// shadow over a per-pixel blend whose weights span two repeats equals the exact visibility of the combined box
// surface over those two repeats, for starts in both.
TEST(HeightBlend, HardShadowOverABlendIsTheExactShadowOfTheCombinedSurface) {
  const int n = 16;
  std::vector<Image> heights;
  for (int i = 0; i < kLayers; ++i) heights.push_back(random_heights(n, 500u + std::uint32_t(i)));
  // Weights over two repeats at one weight texel per layer texel: bilinear weights at a layer texel's centre are
  // the stored ones, so the combined surface is max_i(w_i h_i) texel by texel.
  const Texture weights = make_mip_texture(random_weights(2 * n, 77), TexelFormat::RGBA8, false, MipReduce::Max);
  std::vector<Texture> box, maxima;
  for (const Image& h : heights) {
    box.push_back(make_mip_texture(h, TexelFormat::R32F, false, MipReduce::Box));
    maxima.push_back(make_mip_texture(h, TexelFormat::R32F, false, MipReduce::Max));
  }
  SamplerState sampler;
  sampler.filter = Filter::Point;
  std::vector<HeightLayerTextures> layer_textures;
  for (int i = 0; i < kLayers; ++i)
    layer_textures.emplace_back(box[std::size_t(i)], &maxima[std::size_t(i)], sampler, HeightFetch::Point);
  std::vector<SingleLayerSurface> layers(layer_textures.begin(), layer_textures.end());
  const TextureSampler weight_view(weights, weight_sampler_state(sampler));
  std::vector<const Texture*> box_pointers;
  for (const Texture& t : box) box_pointers.push_back(&t);
  const Texture combined = combined_quadtree(combined_surface(box_pointers, weights, 2, BlendOperator::Height));
  const TextureSampler combined_view(combined, sampler);

  HeightField field;  // the two repeats, as one map
  field.width = field.height = 2 * n;
  field.h = ZeroedBuffer<double>(std::size_t(4 * n * n));
  for (int y = 0; y < 2 * n; ++y)
    for (int x = 0; x < 2 * n; ++x) {
      float top = 0.0f;
      for (int i = 0; i < kLayers; ++i) top = std::max(top, weights.texel(0, x, y, i) * heights[std::size_t(i)].at(x % n, y % n, 0));
      field.h[std::size_t(y * 2 * n + x)] = top;
    }
  const double ds = 0.2;
  ShadowDesc desc;
  desc.mode = ShadowMode::Hard;
  desc.max_iterations = 1 << 12;
  int checked = 0, wrong = 0;
  for (bool precomputed : {false, true})
  for (double elevation : {60.0, 25.0, 10.0})
    for (int a = 0; a < 8; ++a) {
      const double azimuth = 2.0 * std::numbers::pi * (a + 0.3) / 8.0, slope = 1.0 / std::tan(elevation * std::numbers::pi / 180.0);
      const double du = slope * std::cos(azimuth) * (1.0 / n) * 4.0, dv = slope * std::sin(azimuth) * (1.0 / n) * 4.0;
      for (int first = 0; first < 4 * n * n; first += simd::kLanes) {
        alignas(64) float u[simd::kLanes], v[simd::kLanes], s[simd::kLanes];
        for (int l = 0; l < simd::kLanes; ++l) {
          const int k = first + l, x = k % (2 * n), y = k / (2 * n);
          u[l] = (float(x) + 0.5f) / float(n);  // UV of the blend: two repeats
          v[l] = (float(y) + 0.5f) / float(n);
          s[l] = float(ds * (1.0 - field.h[std::size_t(k)]));  // on the top face of its texel
        }
        const simd::Float fu = simd::Float::load_aligned(u), fv = simd::Float::load_aligned(v), fs = simd::Float::load_aligned(s);
        const simd::Float fdu = simd::Float(static_cast<float>(du)), fdv = simd::Float(static_cast<float>(dv));
        const simd::Float u1 = fu + fdu * fs, v1 = fv + fdv * fs;
        const WeightTexture w{&weight_view, 2.0f, precomputed ? &combined_view : nullptr, 2 * n, 2 * n};
        const BlendedSurface surface(layers.data(), kLayers, BlendOperator::Height, w,
                                     xsimd::min(fu, u1), xsimd::max(fu, u1), xsimd::min(fv, v1), xsimd::max(fv, v1));
        const ShadowResult r = self_shadow(surface, desc.mode, shadow_params(desc), ShadowRay{fu, fv, fs, fdu, fdv, simd::Float(float(ds))}, simd::Float(0.0f),
                                           simd::Float(0.0f) == simd::Float(0.0f));
        alignas(64) float vis[simd::kLanes];
        r.visibility.store_aligned(vis);
        for (int l = 0; l < simd::kLanes; ++l) {
          // The combined map spans two repeats, so its UV is half the blend's.
          const LightVisibility ref =
              light_visibility(field, ds, {u[l] * 0.5, v[l] * 0.5, double(s[l])}, {du * 0.5, dv * 0.5});
          ++checked;
          if ((vis[l] > 0.5f) != ref.visible) ++wrong;
        }
      }
    }
  EXPECT_EQ(wrong, 0) << "of " << checked << " starts";
}

// The blend's level-0 box values over one period (Kernel::blend_box_values, of every kernel this CPU runs) are
// the values a walk computes at its level-0 cells, bit for bit, for every operator: a walk reading them keeps its
// bits. Checked over every cell of the period, on the surface without the table (layer chains, and the interleaved
// heights) and with it, in batches that mix level-0 cells inside the period, outside it and coarse cells.
TEST(HeightBlend, BoxValuesAreTheLevelZeroValuesAWalkComputes) {
  const int n = 16, repeats = 3, period = n * repeats;
  std::vector<Image> heights;
  for (int i = 0; i < kLayers; ++i) heights.push_back(random_heights(n, 900u + std::uint32_t(i)));
  // 8 weight texels over 48 layer texels: cell centres fall between weight texels, so the weights are filtered.
  const Texture weights = make_weight_texture(random_weights(8, 91));
  std::vector<Texture> box, maxima;
  for (const Image& h : heights) {
    box.push_back(make_mip_texture(h, TexelFormat::R16, false, MipReduce::Box));
    maxima.push_back(make_mip_texture(h, TexelFormat::R16, false, MipReduce::Max));
    add_linear_copy(maxima.back());
  }
  std::vector<const Texture*> chains;
  for (const Texture& t : maxima) chains.push_back(&t);
  const LayerHeights interleaved = interleave_layer_heights(chains);
  ASSERT_EQ(interleaved.width, n);
  SamplerState sampler;
  sampler.filter = Filter::Point;
  std::vector<HeightLayerTextures> layer_textures;
  for (int i = 0; i < kLayers; ++i)
    layer_textures.emplace_back(box[std::size_t(i)], &maxima[std::size_t(i)], sampler, HeightFetch::Point);
  const std::vector<SingleLayerSurface> layers(layer_textures.begin(), layer_textures.end());
  const TextureSampler weight_view(weights, weight_sampler_state(sampler));
  std::vector<const Texture*> box_pointers;
  for (const Texture& t : box) box_pointers.push_back(&t);
  for (BlendOperator op : {BlendOperator::Height, BlendOperator::Alpha, BlendOperator::HeightWidth}) {
    const BlendBoxSource source{&weights, repeats, &interleaved, op, kLayers};
    ASSERT_EQ(blend_box_value_count(source), std::size_t(period) * std::size_t(period));
    std::vector<float> values(blend_box_value_count(source));
    kernel_for(resolve_isa(Isa::Auto)).blend_box_values(source, values.data());
    for (const Isa isa : usable_isas()) {  // every kernel: the same bits
      std::vector<float> again(values.size());
      kernel_for(isa).blend_box_values(source, again.data());
      ASSERT_EQ(std::memcmp(again.data(), values.data(), values.size() * sizeof(float)), 0) << isa_name(isa);
    }
    const Texture tree = combined_quadtree(combined_surface(box_pointers, weights, repeats, op));
    {
      // Preparation makes a blend's tree from these values as floats (no fp64 copy): the same tree as from the copy.
      HeightField copy;
      copy.width = copy.height = period;
      copy.h.assign(values.begin(), values.end());
      const Texture from_copy = combined_quadtree(copy);
      const Texture from_floats = combined_quadtree(HeightView<float>{period, period, AddressMode::Wrap, values.data()});
      ASSERT_EQ(from_floats.level_count(), from_copy.level_count());
      for (int k = 0; k < from_copy.level_count(); ++k)
        ASSERT_EQ(from_floats.level_image(k).texels, from_copy.level_image(k).texels) << "level " << k;
    }
    const TextureSampler tree_view(tree, sampler);
    const WeightTexture chains_only{&weight_view, float(repeats), &tree_view, period, period};
    const WeightTexture with_heights{&weight_view, float(repeats), &tree_view, period, period, &interleaved};
    const WeightTexture with_values{&weight_view, float(repeats), &tree_view, period, period, &interleaved,
                                    values.data()};
    // Every query of the batches stays in the whole weight span (all layers present wherever they have weight).
    const simd::Float lo(-1.0f), hi(float(repeats) + 1.0f);
    const auto surface = [&](const WeightTexture& w) {
      return BlendedSurface(layers.data(), kLayers, op, w, lo, hi, lo, hi);
    };
    const BlendedSurface a = surface(chains_only), b = surface(with_heights), c = surface(with_values);
    const auto bits = [](float f) { return std::bit_cast<std::uint32_t>(f); };
    int checked = 0;
    for (int y = -1; y <= period; ++y)
      for (int x = -simd::kLanes; x < period + simd::kLanes; x += simd::kLanes) {
        alignas(64) std::int32_t cx[simd::kLanes], levels[simd::kLanes];
        for (int l = 0; l < simd::kLanes; ++l) {
          cx[l] = x + l;
          levels[l] = (x + l + y) % 7 == 3 ? 1 : 0;  // now and then a coarse lane, whose cell is cx / 2
          if (levels[l] == 1) cx[l] = (x + l) / 2;
        }
        const simd::Int level = simd::Int::load_aligned(levels), cells = simd::Int::load_aligned(cx);
        const simd::Int row = xsimd::select(level == simd::Int(1), simd::Int(y / 2), simd::Int(y));
        alignas(64) float va[simd::kLanes], vb[simd::kLanes], vc[simd::kLanes];
        a.cell_max(level, cells, row).store_aligned(va);
        b.cell_max(level, cells, row).store_aligned(vb);
        c.cell_max(level, cells, row).store_aligned(vc);
        for (int l = 0; l < simd::kLanes; ++l) {
          ASSERT_EQ(bits(vb[l]), bits(va[l])) << "cell " << cx[l] << ", " << y << " level " << levels[l];
          ASSERT_EQ(bits(vc[l]), bits(va[l])) << "cell " << cx[l] << ", " << y << " level " << levels[l];
          const bool in_period = levels[l] == 0 && cx[l] >= 0 && cx[l] < period && y >= 0 && y < period;
          if (in_period) {
            ASSERT_EQ(bits(values[std::size_t(y) * std::size_t(period) + std::size_t(cx[l])]), bits(va[l]));
            ++checked;
          }
        }
      }
    EXPECT_GT(checked, period * period / 2) << "most of the period's cells were compared";
  }
}

}  // namespace
}  // namespace qdmr::test
