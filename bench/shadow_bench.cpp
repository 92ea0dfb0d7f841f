// Self-shadowing cost per mode (kernel/self_shadow.hpp) on one thread: 2^16 lanes per run, each a random point
// on the box surface of a 1024^2 procedural noise height map (R16, as procedural heights are stored), depth
// scale 0.05, the light at the given elevation (degrees) and a random azimuth per lane. Time per lane x 1e6 =
// ms per million lanes. Counters: fetches per lane (the iterations the mode reports), fraction shadowed (< 1).
#include <benchmark/benchmark.h>

#include <cmath>
#include <cstddef>
#include <numbers>
#include <random>
#include <vector>

#include "qdmr/texture/mip_texture.hpp"
#include "qdmr/texture/texture_level0.hpp"
#include "kernel/height_surface.hpp"
#include "kernel/self_shadow.hpp"

namespace {

using namespace qdmr;

constexpr int kSide = 1024;
constexpr int kLanes = 1 << 16;
constexpr float kDepthScale = 0.05f;

struct Maps {
  Image heights;
  Texture height, tree;
  Maps() {
    ProceduralDesc p;
    p.pattern = ProceduralPattern::Noise;
    p.size = kSide;
    heights = generate_procedural(p);
    height = make_mip_texture(heights, TexelFormat::R16, false, MipReduce::Box);
    tree = make_mip_texture(heights, TexelFormat::R16, false, MipReduce::Max);
  }
};

const Maps& maps() {
  static const Maps m;
  return m;
}

void shadow(benchmark::State& state, ShadowMode mode) {
  const Maps& m = maps();
  const HeightLayerTextures textures(m.height, &m.tree, SamplerState{}, HeightFetch::Bilinear);
  const SingleLayerSurface surface(textures);
  const ShadowParams desc;
  const double elevation = double(state.range(0)) * std::numbers::pi / 180.0;
  // Lanes: point (u, v) on the top of its texel (R16 heights decode to 16-bit steps; the float image's value is
  // within half a step of it, and the start texel never shadows its own point), light slope 1/tan(elevation).
  std::mt19937 rng(1);
  std::uniform_real_distribution<float> unit(0.0f, 1.0f);
  std::vector<float> u(kLanes), v(kLanes), s(kLanes), du(kLanes), dv(kLanes);
  for (int i = 0; i < kLanes; ++i) {
    u[i] = unit(rng), v[i] = unit(rng);
    const float h = m.heights.at(int(u[i] * kSide), int(v[i] * kSide), 0);
    s[i] = kDepthScale * (1.0f - h);
    const double az = 2.0 * std::numbers::pi * unit(rng);
    du[i] = float(std::cos(az) / std::tan(elevation)), dv[i] = float(std::sin(az) / std::tan(elevation));
  }
  const simd::Mask all = simd::Float(0.0f) == simd::Float(0.0f);
  double fetches = 0, shadowed = 0;
  for (auto _ : state) {
    simd::Float it(0.0f), dark(0.0f);
    for (int i = 0; i < kLanes; i += simd::kLanes) {
      const ShadowRay ray{simd::Float::load_unaligned(&u[i]),  simd::Float::load_unaligned(&v[i]),
                          simd::Float::load_unaligned(&s[i]),  simd::Float::load_unaligned(&du[i]),
                          simd::Float::load_unaligned(&dv[i]), simd::Float(kDepthScale)};
      const ShadowResult r = self_shadow(surface, mode, desc, ray, simd::Float(0.0f), all);
      it += r.iterations;
      dark += simd::count(r.visibility < simd::Float(1.0f));
    }
    benchmark::DoNotOptimize(it);
    fetches = double(xsimd::hadd(it)) / kLanes;
    shadowed = double(xsimd::hadd(dark)) / kLanes;
  }
  state.SetItemsProcessed(std::int64_t(state.iterations()) * kLanes);
  state.counters["fetches"] = fetches;
  state.counters["shadowed"] = shadowed;
}

void hard(benchmark::State& state) { shadow(state, ShadowMode::Hard); }
void horizon(benchmark::State& state) { shadow(state, ShadowMode::Horizon); }
void qdm_soft(benchmark::State& state) { shadow(state, ShadowMode::QdmSoft); }

BENCHMARK(hard)->Arg(45)->Arg(15)->Unit(benchmark::kMillisecond);
BENCHMARK(horizon)->Arg(45)->Arg(15)->Unit(benchmark::kMillisecond);
BENCHMARK(qdm_soft)->Arg(45)->Arg(15)->Unit(benchmark::kMillisecond);

}  // namespace

BENCHMARK_MAIN();
