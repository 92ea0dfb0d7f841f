// Sampler throughput (samples per second, one thread): every filter, R8 / R32F / RGBA8 sRGB textures of
// 256², 1024² and 4096² (Box chains of random texels), the SIMD sampler on the gather and the portable fetch
// paths, and the scalar reference sampler. Wrap addressing. Each iteration samples kPoints points:
//   random    kPoints fixed random (u, v) in [0,1)² and LODs in [0, last level], shifted by a new random offset
//             every iteration, so the texels touched change and large textures miss the caches as they would
//   coherent  a sweep over the texel centres of level 0 in row order (kPoints consecutive texels, then the next
//             rows on the next iteration), LOD 0.25: the cache-friendly order of a magnified 1:1 screen mapping
// Name: sample/<filter>/<format>/<size>/<random|coherent>/<gather|portable|reference>; items/s = samples/s.
// And an albedo (RGBA8 sRGB with its decoded copy, as the renderer prepares it) and a normal map (RGBA8) of one size
// sampled at the same points, as the shading programs do: two TextureSamplers, or one TwinSampler that addresses
// both at once. Name: twin/<filter>/<size>/<random|coherent>/<separate|twin>; items/s = points/s (two samples each).
#include <benchmark/benchmark.h>

#include <array>
#include <cstddef>
#include <map>
#include <random>
#include <string>
#include <utility>
#include <vector>

#include "qdmr/texture/mip_texture.hpp"
#include "texture/reference_sampler.hpp"
#include "kernel/sampler.hpp"

namespace {

using namespace qdmr;
using simd::Float;
using simd::kLanes;

constexpr int kPoints = 4096;

// gather, portable: the generic sampler on either fetch path; specialised: a TextureSampler (the instantiation for
// the key where one exists, e.g. not for r32f); reference: the scalar fp64 sampler.
enum class Impl { Gather, Portable, Specialised, Reference };
enum class Access { Random, Coherent };

struct Format {
  TexelFormat format;
  bool srgb;
  const char* name;
};

// One texture per (format, side), built on first use and kept for the whole run.
const Texture& texture_for(const Format& f, int side) {
  static std::map<std::pair<int, int>, Texture> cache;
  const auto key = std::pair{int(f.format), side};
  auto it = cache.find(key);
  if (it == cache.end()) {
    Image img(side, side, channel_count(f.format));
    std::mt19937 rng{unsigned(side)};
    std::uniform_real_distribution<float> unit(0.0f, 1.0f);
    for (float& t : img.texels) t = unit(rng);
    it = cache.emplace(key, make_mip_texture(img, f.format, f.srgb, MipReduce::Box)).first;
  }
  return it->second;
}

struct Points {
  alignas(64) std::array<float, kPoints> u, v, lod;
};

// The points of one iteration before its offset, and the offset of iteration k.
Points make_points(const Texture& t, Access access) {
  Points p;
  std::mt19937 rng(1);
  std::uniform_real_distribution<float> unit(0.0f, 1.0f), lod(0.0f, float(t.level_count() - 1));
  const int w = t.width();
  for (int i = 0; i < kPoints; ++i) {
    if (access == Access::Random) {
      p.u[std::size_t(i)] = unit(rng), p.v[std::size_t(i)] = unit(rng), p.lod[std::size_t(i)] = lod(rng);
    } else {
      p.u[std::size_t(i)] = (float(i % w) + 0.5f) / float(w);
      p.v[std::size_t(i)] = (float(i / w) + 0.5f) / float(t.height());
      p.lod[std::size_t(i)] = 0.25f;
    }
  }
  return p;
}

std::pair<float, float> offset(const Texture& t, Access access, std::mt19937& rng, long iteration) {
  if (access == Access::Random) {
    std::uniform_real_distribution<float> unit(0.0f, 1.0f);
    return {unit(rng), unit(rng)};
  }
  const long rows = kPoints / t.width() > 0 ? kPoints / t.width() : 1;  // rows swept per iteration
  return {0.0f, float((iteration * rows) % t.height()) / float(t.height())};
}

void bench_sample(benchmark::State& state, Filter filter, Format format, int side, Access access, Impl impl) {
  const Texture& texture = texture_for(format, side);
  const TextureView view(texture);
  SamplingDesc desc;
  desc.filter = filter;
  desc.address = AddressMode::Wrap;
  SamplerState simd_state;  // desc's
  simd_state.filter = filter;
  if (impl == Impl::Portable) simd_state.fetch = simd::FetchPath::Portable;
  const TextureSampler bound(texture, simd_state);
  const Points points = make_points(texture, access);
  std::mt19937 rng(2);
  long iteration = 0;
  for (auto _ : state) {
    const auto [du, dv] = offset(texture, access, rng, iteration++);
    if (impl == Impl::Reference) {
      float sum = 0.0f;
      for (std::size_t i = 0; i < std::size_t(kPoints); ++i) {
        float out[4];
        reference_sample(texture, desc, points.u[i] + du, points.v[i] + dv, points.lod[i], out);
        sum += out[0];
      }
      benchmark::DoNotOptimize(sum);
    } else {
      Float sum(0.0f);
      const Float fu(du), fv(dv);
      for (std::size_t i = 0; i < std::size_t(kPoints); i += std::size_t(kLanes)) {
        Float out[4];
        const Float u = Float::load_aligned(&points.u[i]) + fu, v = Float::load_aligned(&points.v[i]) + fv;
        if (impl == Impl::Specialised)
          bound.sample(u, v, Float::load_aligned(&points.lod[i]), out);
        else
          sample(view, simd_state, u, v, Float::load_aligned(&points.lod[i]), out);
        sum += out[0];
      }
      benchmark::DoNotOptimize(sum);
    }
  }
  state.SetItemsProcessed(std::int64_t(state.iterations()) * kPoints);
}

// The albedo and normal map of twin/...: random texels, the albedo with its decoded sRGB copy.
const std::pair<Texture, Texture>& albedo_and_normal(int side) {
  static std::map<int, std::pair<Texture, Texture>> cache;
  auto it = cache.find(side);
  if (it == cache.end()) {
    Image img(side, side, 4);
    std::mt19937 rng{unsigned(side) + 7u};
    std::uniform_real_distribution<float> unit(0.0f, 1.0f);
    for (float& t : img.texels) t = unit(rng);
    Texture albedo = make_mip_texture(img, TexelFormat::RGBA8, true, MipReduce::Box);
    add_linear_copy(albedo);
    for (float& t : img.texels) t = unit(rng);
    it = cache.emplace(side, std::pair{std::move(albedo), make_mip_texture(img, TexelFormat::RGBA8, false, MipReduce::Box)})
             .first;
  }
  return it->second;
}

void bench_twin(benchmark::State& state, Filter filter, int side, Access access, bool twin) {
  const auto& [albedo, normal] = albedo_and_normal(side);
  SamplerState sampler_state;
  sampler_state.filter = filter;
  sampler_state.address = AddressMode::Wrap;
  const TwinSampler both(albedo, normal, sampler_state);
  if (!both.shares_addresses()) {
    state.SkipWithError("the two textures do not share addresses");
    return;
  }
  const Points points = make_points(albedo, access);
  std::mt19937 rng(2);
  long iteration = 0;
  for (auto _ : state) {
    const auto [du, dv] = offset(albedo, access, rng, iteration++);
    Float sum(0.0f);
    const Float fu(du), fv(dv);
    for (std::size_t i = 0; i < std::size_t(kPoints); i += std::size_t(kLanes)) {
      Float a[4], n[4];
      const Float u = Float::load_aligned(&points.u[i]) + fu, v = Float::load_aligned(&points.v[i]) + fv;
      const Float lod = Float::load_aligned(&points.lod[i]);
      if (twin) {
        both.sample(u, v, lod, lod, a, n);
      } else {
        both.first().sample(u, v, lod, a);
        both.second().sample(u, v, lod, n);
      }
      sum += a[0] + n[0];
    }
    benchmark::DoNotOptimize(sum);
  }
  state.SetItemsProcessed(std::int64_t(state.iterations()) * kPoints);
}

}  // namespace

int main(int argc, char** argv) {
  const std::pair<Filter, const char*> filters[] = {
      {Filter::Point, "point"},          {Filter::Bilinear, "bilinear"},           {Filter::Trilinear, "trilinear"},
      {Filter::PointMipPoint, "point_mip_point"}, {Filter::PointMipLinear, "point_mip_linear"},
      {Filter::LinearMipPoint, "linear_mip_point"}};
  const Format formats[] = {{TexelFormat::R8, false, "r8"}, {TexelFormat::R32F, false, "r32f"},
                            {TexelFormat::RGBA8, true, "rgba8_srgb"}};
  const std::pair<Access, const char*> accesses[] = {{Access::Random, "random"}, {Access::Coherent, "coherent"}};
  const std::pair<Impl, const char*> impls[] = {
      {Impl::Gather, "gather"}, {Impl::Portable, "portable"}, {Impl::Specialised, "specialised"},
      {Impl::Reference, "reference"}};
  for (const auto& [filter, filter_name] : filters)
    for (const Format& format : formats)
      for (int side : {256, 1024, 4096})
        for (const auto& [access, access_name] : accesses)
          for (const auto& [impl, impl_name] : impls) {
            // On a build without hardware gathers (SSE4.2) the gather path is the portable one: not repeated.
            if (impl == Impl::Gather && !simd::kHasHardwareGather) continue;
            const std::string name = std::string("sample/") + filter_name + "/" + format.name + "/" +
                                     std::to_string(side) + "/" + access_name + "/" + impl_name;
            benchmark::RegisterBenchmark(name.c_str(), bench_sample, filter, format, side, access, impl)
                ->Unit(benchmark::kMicrosecond)
                ->MinTime(0.03);  // 30+ iterations even for the slowest case; 432 cases x 3 repetitions in ~3 minutes
          }
  for (const auto& [filter, filter_name] : {filters[1], filters[2]})
    for (int side : {512, 2048})
      for (const auto& [access, access_name] : accesses)
        for (const bool twin : {false, true}) {
          const std::string name = std::string("twin/") + filter_name + "/" + std::to_string(side) + "/" + access_name +
                                   (twin ? "/twin" : "/separate");
          benchmark::RegisterBenchmark(name.c_str(), bench_twin, filter, side, access, twin)
              ->Unit(benchmark::kMicrosecond)
              ->MinTime(0.05);
        }
  benchmark::Initialize(&argc, argv);
  if (benchmark::ReportUnrecognizedArguments(argc, argv)) return 1;
  benchmark::RunSpecifiedBenchmarks();
  benchmark::Shutdown();
  return 0;
}
