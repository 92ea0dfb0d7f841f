// Ambient occlusion cost: the per-frame horizon AO (kernel/ambient_occlusion.hpp) per pixel for each mode, and the
// baked map (bake_ao_map) per texel, 1 and 2 threads, its rows by the scalar definition and by each kernel. A plain
// timing program: every case runs --reps times and the median is printed as a markdown row.
//   qdmr_ao_bench [--size 512] [--pixels 512] [--reps 5] [--no-bake]
// Frame: a pixels x pixels grid of points over one repeat of a --size noise height map (R16, bilinear fetch),
// one thread. The point depth s is the surface depth at the point (as after a converged intersection).
#include <tbb/task_arena.h>

#include <algorithm>
#include <chrono>
#include <cstdio>
#include <cstdlib>
#include <string>
#include <utility>
#include <vector>

#include "kernel/kernel.hpp"
#include "bake/ao_map.hpp"
#include "qdmr/core/isa.hpp"
#include "qdmr/texture/mip_texture.hpp"
#include "qdmr/texture/texture_level0.hpp"
#include "kernel/ambient_occlusion.hpp"
#include "kernel/height_surface.hpp"

namespace {

using qdmr::simd::Float;

double median(std::vector<double> v) {
  std::sort(v.begin(), v.end());
  return v[v.size() / 2];
}

template <class F>
double time_median(int reps, F&& run) {
  std::vector<double> times;
  for (int r = 0; r < reps; ++r) {
    const auto start = std::chrono::steady_clock::now();
    run();
    times.push_back(std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count());
  }
  return median(times);
}

}  // namespace

int main(int argc, char** argv) {
  int size = 512, pixels = 512, reps = 5;
  bool bake = true;
  for (int k = 1; k < argc; ++k) {
    const std::string arg = argv[k];
    if (arg == "--size" && k + 1 < argc)
      size = std::atoi(argv[++k]);
    else if (arg == "--pixels" && k + 1 < argc)
      pixels = std::atoi(argv[++k]);
    else if (arg == "--reps" && k + 1 < argc)
      reps = std::max(1, std::atoi(argv[++k]));
    else if (arg == "--no-bake")
      bake = false;
    else {
      std::fprintf(stderr, "usage: %s [--size 512] [--pixels 512] [--reps 5] [--no-bake]\n", argv[0]);
      return 2;
    }
  }
  qdmr::ProceduralDesc noise;
  noise.pattern = qdmr::ProceduralPattern::Noise;
  noise.size = size;
  const qdmr::Image heights = qdmr::generate_procedural(noise);
  const qdmr::Texture height = qdmr::make_mip_texture(heights, qdmr::TexelFormat::R16, false, qdmr::MipReduce::Box);
  const qdmr::Texture tree = qdmr::make_mip_texture(heights, qdmr::TexelFormat::R16, false, qdmr::MipReduce::Max);
  const qdmr::HeightLayerTextures textures(height, &tree, qdmr::SamplerState{}, qdmr::HeightFetch::Bilinear);
  const qdmr::SingleLayerSurface surface(textures);
  const float ds = 0.05f;

  // The points, batch by batch: u, v, s per lane, with the lanes of a batch on one row.
  const int lanes = qdmr::simd::kLanes;
  std::vector<float> u, v, s;
  for (int y = 0; y < pixels; ++y)
    for (int x = 0; x < pixels; ++x) {
      u.push_back((float(x) + 0.5f) / float(pixels));
      v.push_back((float(y) + 0.5f) / float(pixels));
    }
  for (std::size_t k = 0; k < u.size(); k += std::size_t(lanes)) {
    const Float h = surface.height(Float::load_unaligned(&u[k]), Float::load_unaligned(&v[k]), Float(0.0f));
    alignas(64) float depth[qdmr::simd::kLanes];
    (Float(ds) * (Float(1.0f) - h)).store_aligned(depth);
    s.insert(s.end(), depth, depth + lanes);
  }

  std::printf("frame AO, %d² noise R16 bilinear, %d² pixels, 1 thread, median of %d, %d lanes\n\n", size, pixels, reps,
              lanes);
  std::printf("| mode | directions | radius (texels) | jitter | ns / pixel | mean AO |\n|---|---|---|---|---|---|\n");
  for (bool coarse : {true, false})
    for (int directions : {4, 8, 16})
      for (float radius_texels : {16.0f, 64.0f})
        for (bool jitter : {false, true}) {
          if (jitter && directions != 4) continue;  // the talk: jitter lets 4 directions do
          qdmr::AoParams d;
          d.coarse = coarse;
          d.directions = directions;
          d.radius = radius_texels / float(size);
          d.jitter = jitter;
          double sum = 0.0;
          const double seconds = time_median(reps, [&] {
            Float total(0.0f);
            for (std::size_t k = 0; k < u.size(); k += std::size_t(lanes)) {
              const Float px((float(k % std::size_t(pixels)) + 0.5f)), py(float(k / std::size_t(pixels)) + 0.5f);
              total += qdmr::ambient_occlusion(surface, d, Float::load_unaligned(&u[k]), Float::load_unaligned(&v[k]),
                                               Float::load_unaligned(&s[k]), Float(ds), px, py, Float(1.0f) > Float(0.0f));
            }
            sum = double(xsimd::hadd(total));
          });
          std::printf("| %s | %d | %g | %s | %.1f | %.4f |\n", coarse ? "coarse" : "fine", directions, double(radius_texels),
                      jitter ? "yes" : "no", 1e9 * seconds / double(u.size()), sum / double(u.size()));
          std::fflush(stdout);
        }

  if (!bake) return 0;
  qdmr::HeightField field;
  field.width = heights.width;
  field.height = heights.height;
  field.h.assign(heights.texels.begin(), heights.texels.end());
  std::printf("\nbaked AO map, %d² noise, depth scale %g, 8 directions, median of %d; rows by the scalar definition "
              "and by each kernel this CPU runs (the same bits)\n\n",
              size, double(ds), reps);
  std::printf("| rows | mode | radius (texels) | threads | seconds | ns / texel |\n|---|---|---|---|---|---|\n");
  std::vector<std::pair<std::string, qdmr::AoMapRow>> bakes = {{"scalar", qdmr::AoMapRow{}}};
  for (qdmr::Isa isa : qdmr::usable_isas()) bakes.emplace_back(qdmr::isa_name(isa), qdmr::kernel_for(isa).ao_map_row());
  for (bool coarse : {true, false})
    for (const auto& [name, row] : bakes)
      for (int threads : {1, 2}) {
        qdmr::AoDesc d;
        d.mode = qdmr::AoMode::Baked;
        d.coarse = coarse;
        d.radius = 64.0f / float(size);
        const double seconds = time_median(
            reps, [&] { tbb::task_arena(threads).execute([&] { (void)qdmr::bake_ao_map(field, ds, d, row); }); });
        std::printf("| %s | %s | 64 | %d | %.3f | %.1f |\n", name.c_str(), coarse ? "coarse" : "fine", threads, seconds,
                    1e9 * seconds / double(field.h.size()));
        std::fflush(stdout);
      }
  return 0;
}
