// What amortizing a baked AO map over K frames (AoDesc::amortize_frames) costs in accuracy while the surface moves:
// scenes/water.json with baked AO, its frames prepared in sequence with each K, every stored map (level 0, R16)
// compared with the map baked whole from the same frame's heights. Prints, per K, the mean and the largest
// |amortized - whole| over the texels of every frame from K on (the first K - 1 frames still hold frame 0's rows),
// the worst frame's mean, the mean occlusion 1 - ao for scale, and the AO map's share of a frame's preparation.
// Usage: qdmr_ao_amortize_error [side (64..1024, default 256)] [frames (default 48)] [K ... (default 2 4 8)]
#include <algorithm>
#include <cstdio>
#include <cstdlib>
#include <string>
#include <vector>

#include "kernel/kernel.hpp"
#include "prepare/assets.hpp"
#include "qdmr/core/isa.hpp"
#include "qdmr/load/load.hpp"

namespace {

using namespace qdmr;

SceneDesc water(int side, int window) {
  return load_scene(std::string(QDMR_SOURCE_DIR) + "/scenes/water.json",
                    {{"/materials/water/layers/0/height/size", std::to_string(side)},
                     {"/materials/water/ao", R"({"mode": "baked", "amortize_frames": )" + std::to_string(window) + "}"},
                     {"/output/width", "64"},
                     {"/output/height", "36"}});
}

std::size_t ao_index(const FramePlan& plan) {
  for (std::size_t i = 0; i < plan.derived.size(); ++i)
    if (plan.derived[i].kind == DerivedKind::LayerAoMap) return i;
  std::fprintf(stderr, "no layer AO map\n");
  std::exit(1);
}

// The AO map of each frame 0 .. frames - 1, prepared in sequence, as floats (level 0 decoded), and the AO map's
// build time per frame.
struct Sequence {
  std::vector<Image> maps;
  std::vector<double> ao_ms;
};

Sequence run(int side, int window, int frames, const Kernel& kernel) {
  const SceneDesc scene = water(side, window);
  Sequence out;
  FramePlan last_plan;
  Assets last;
  for (int n = 0; n < frames; ++n) {
    FramePlan plan = plan_frame(scene_at_frame(scene, n));
    Assets assets = n == 0 ? prepare(plan, kernel) : prepare(plan, kernel, &last, &last_plan);
    const std::size_t i = ao_index(plan);
    out.maps.push_back(assets.derived[i].texture->level_image(0));
    for (const PrepareStep& step : assets.steps)
      if (step.what == "layer_ao_map") out.ao_ms.push_back(step.ms);
    last_plan = std::move(plan);
    last = std::move(assets);
  }
  return out;
}

double median(std::vector<double> v) {
  std::sort(v.begin(), v.end());
  return v.empty() ? 0.0 : v[v.size() / 2];
}

}  // namespace

int main(int argc, char** argv) {
  const int side = argc > 1 ? std::atoi(argv[1]) : 256, frames = argc > 2 ? std::atoi(argv[2]) : 48;
  std::vector<int> windows;
  for (int a = 3; a < argc; ++a) windows.push_back(std::atoi(argv[a]));
  if (windows.empty()) windows = {2, 4, 8};
  const Kernel& kernel = kernel_for(resolve_isa(Isa::Auto));
  const Sequence whole = run(side, 1, frames, kernel);
  double occlusion = 0.0;
  for (const Image& m : whole.maps)
    for (float v : m.texels) occlusion += 1.0 - v;
  occlusion /= double(whole.maps.size()) * double(whole.maps[0].texels.size());
  std::printf("scenes/water.json, %d² waves, baked AO, frames 0..%d, %s kernel; mean occlusion 1 - ao = %.4f; "
              "AO map per frame baked whole: median %.1f ms\n",
              side, frames - 1, isa_name(kernel.isa()), occlusion, median(whole.ao_ms));
  std::printf("K  mean |error|  worst frame's mean  largest |error|  AO map per frame (median)\n");
  for (int k : windows) {
    const Sequence amortized = run(side, k, frames, kernel);
    double sum = 0.0, worst_frame = 0.0, largest = 0.0;
    std::size_t count = 0;
    for (int n = k; n < frames; ++n) {
      const Image &a = amortized.maps[std::size_t(n)], &b = whole.maps[std::size_t(n)];
      double frame_sum = 0.0;
      for (std::size_t t = 0; t < a.texels.size(); ++t) {
        const double e = std::abs(double(a.texels[t]) - double(b.texels[t]));
        frame_sum += e;
        largest = std::max(largest, e);
      }
      sum += frame_sum;
      count += a.texels.size();
      worst_frame = std::max(worst_frame, frame_sum / double(a.texels.size()));
    }
    std::printf("%-2d %.5f       %.5f             %.4f           %.1f ms\n", k, sum / double(count), worst_frame,
                largest, median(amortized.ao_ms));
  }
  return 0;
}
