// Micro benchmarks of one frame's draw stages, each on its own: geometry (transform, clip, cull),
// setup + binning, raster + shade. Scenes: the 1M-triangle grid (scenes/plane.json with its plane
// replaced by a 710x710 grid: 1,008,200 triangles, ~1.4 pixels each) and the plane itself (2 triangles,
// 1.36 M pixels shaded). The argument is the thread count. Items per second = triangles in; the B/...
// counters are the per-triangle and per-vertex record sizes, which set the memory of a many-triangle frame.
#include <benchmark/benchmark.h>

#include <cstddef>
#include <string>
#include <vector>

#include <glm/ext/matrix_clip_space.hpp>
#include <glm/ext/matrix_transform.hpp>
#include <glm/trigonometric.hpp>
#include <tbb/blocked_range.h>
#include <tbb/parallel_for.h>
#include <tbb/task_arena.h>

#include "draw/draw.hpp"
#include "qdmr/load/load.hpp"
#include "qdmr/plan/plan.hpp"
#include "raster/binner.hpp"
#include "kernel/tile_raster.hpp"

namespace {

using namespace qdmr;

// Everything before the draw stages, built once per scene: assets, draw items, camera matrices.
struct Workload {
  SceneDesc scene;
  FramePlan plan;
  Assets assets;
  std::vector<std::unique_ptr<Program>> programs;
  std::vector<DrawItem> draws;
  glm::mat4 view{1.0f}, projection{1.0f};
  Viewport viewport;
};

Workload make_workload(const std::vector<SceneOverride>& overrides) {
  Workload w;
  w.scene = load_scene(std::string(QDMR_SOURCE_DIR) + "/scenes/plane.json", overrides);
  w.plan = plan_frame(w.scene);
  const Kernel& kernel = kernel_for(Isa::QDMR_ISA_ENUM);  // this benchmark's own kernel
  w.assets = prepare(w.plan, kernel);
  w.programs = make_programs(w.plan, w.assets, kernel);
  // The plane scene's single object has the identity transform.
  w.draws.push_back({w.assets.meshes[0].get(), glm::mat4(1.0f), w.plan.meshes[0].material, {}});
  const CameraDesc& cam = w.scene.camera;
  w.viewport = {w.scene.output.width, w.scene.output.height};
  w.view = glm::lookAt(cam.position, cam.target, cam.up);
  w.projection = glm::perspective(glm::radians(cam.fov_y_deg), float(w.viewport.width) / float(w.viewport.height),
                                  cam.near, cam.far);
  return w;
}

const Workload& workload(int which) {
  static const Workload grid = make_workload(
      {parse_override(R"(/objects/0/mesh={"type":"grid","size":[4,4],"resolution":710,"uv_scale":[2,2]})")});
  static const Workload plane = make_workload({});
  return which == 0 ? grid : plane;
}

void report(benchmark::State& state, const Workload& w, int threads) {
  state.SetItemsProcessed(std::int64_t(state.iterations()) * std::int64_t(w.draws[0].mesh->triangle_count()));
  state.counters["threads"] = threads;
}

GeometryResult geometry_of(const Workload& w, tbb::task_arena& arena) {
  GeometryScratch scratch;
  GeometryResult geometry;
  arena.execute([&] { run_geometry(w.draws, w.view, w.projection, w.viewport, scratch, geometry); });
  return geometry;
}

void BM_Geometry(benchmark::State& state, int which) {
  const Workload& w = workload(which);
  const int threads = int(state.range(0));
  tbb::task_arena arena(threads);
  GeometryScratch scratch;  // kept between iterations, as the renderer keeps it between frames
  GeometryResult geometry;
  for (auto _ : state) {
    arena.execute([&] {
      run_geometry(w.draws, w.view, w.projection, w.viewport, scratch, geometry);
      benchmark::DoNotOptimize(geometry.triangles.data());
    });
  }
  report(state, w, threads);
  state.counters["B/screen_triangle"] = double(sizeof(ScreenTriangle));
  state.counters["B/screen_vertex"] = double(sizeof(ScreenVertex));
}

void BM_Binning(benchmark::State& state, int which) {
  const Workload& w = workload(which);
  const int threads = int(state.range(0));
  tbb::task_arena arena(threads);
  const GeometryResult geometry = geometry_of(w, arena);
  const TileGrid grid(w.viewport.width, w.viewport.height, 64);
  TileBins bins;  // kept between iterations, as the renderer keeps them between frames
  for (auto _ : state) {
    arena.execute([&] {
      bin_triangles(geometry, w.viewport, grid, bins);
      benchmark::DoNotOptimize(bins.bins.data());
    });
  }
  report(state, w, threads);
}

// As a draw does it: clear the colour and depth targets, then rasterize and shade every tile.
void BM_RasterShade(benchmark::State& state, int which) {
  const Workload& w = workload(which);
  const int threads = int(state.range(0));
  tbb::task_arena arena(threads);
  const GeometryResult geometry = geometry_of(w, arena);
  const TileGrid grid(w.viewport.width, w.viewport.height, 64);
  TileBins bins;
  arena.execute([&] { bin_triangles(geometry, w.viewport, grid, bins); });
  const std::size_t pixels = std::size_t(w.viewport.width) * std::size_t(w.viewport.height);
  std::uint64_t shaded = 0;
  for (auto _ : state) {
    Framebuffer fb;
    fb.width = w.viewport.width;
    fb.height = w.viewport.height;
    fb.color.resize(pixels * 3);
    fb.depth.resize(pixels);
    RasterContext context;
    context.geometry = &geometry;
    context.framebuffer = &fb;
    for (const auto& program : w.programs) context.programs.push_back(program.get());
    std::vector<TileCounters> counters(std::size_t(grid.count()));
    arena.execute([&] {
      tbb::parallel_for(tbb::blocked_range<int>(0, grid.count(), 1), [&](const auto& range) {
        for (int tile = range.begin(); tile != range.end(); ++tile)
          raster_tile(context, tile, grid.rect(tile), bins, counters[std::size_t(tile)]);
      });
    });
    for (const TileCounters& c : counters) shaded += c.pixels_shaded;
    benchmark::DoNotOptimize(fb.color.data());
  }
  report(state, w, threads);
  state.counters["Mpixels_shaded/s"] = benchmark::Counter(double(shaded) * 1e-6, benchmark::Counter::kIsRate);
}

}  // namespace

BENCHMARK_CAPTURE(BM_Geometry, grid1m, 0)->Arg(1)->Arg(2)->Unit(benchmark::kMillisecond)->UseRealTime();
BENCHMARK_CAPTURE(BM_Binning, grid1m, 0)->Arg(1)->Arg(2)->Unit(benchmark::kMillisecond)->UseRealTime();
BENCHMARK_CAPTURE(BM_RasterShade, grid1m, 0)->Arg(1)->Arg(2)->Unit(benchmark::kMillisecond)->UseRealTime();
BENCHMARK_CAPTURE(BM_RasterShade, plane, 1)->Arg(1)->Arg(2)->Unit(benchmark::kMillisecond)->UseRealTime();

BENCHMARK_MAIN();
