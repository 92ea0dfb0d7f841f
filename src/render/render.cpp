#include "qdmr/render/render.hpp"

#include <sys/resource.h>

#include <atomic>
#include <chrono>
#include <memory>
#include <mutex>
#include <thread>

#include <glm/ext/matrix_clip_space.hpp>
#include <glm/ext/matrix_transform.hpp>
#include <glm/trigonometric.hpp>
#include <nlohmann/json.hpp>
#include <tbb/global_control.h>
#include <tbb/parallel_for.h>
#include <tbb/task_arena.h>

#include "core/simd.hpp"
#include "qdmr/core/error.hpp"
#include "qdmr/core/limits.hpp"
#include "qdmr/plan/plan.hpp"
#include "raster/binner.hpp"
#include "raster/tile_raster.hpp"
#include "render/assets.hpp"

namespace qdmr {
namespace {

using Clock = std::chrono::steady_clock;

double ms_since(Clock::time_point start) {
  return std::chrono::duration<double, std::milli>(Clock::now() - start).count();
}

std::uint64_t peak_rss_bytes() {
  rusage usage{};
  getrusage(RUSAGE_SELF, &usage);
  return std::uint64_t(usage.ru_maxrss) * 1024;  // Linux reports KiB
}

glm::mat4 model_matrix(const TransformDesc& t) {
  glm::mat4 m = glm::translate(glm::mat4(1.0f), t.translate);
  m = glm::rotate(m, glm::radians(t.rotate_deg.z), glm::vec3(0, 0, 1));
  m = glm::rotate(m, glm::radians(t.rotate_deg.y), glm::vec3(0, 1, 0));
  m = glm::rotate(m, glm::radians(t.rotate_deg.x), glm::vec3(1, 0, 0));
  return glm::scale(m, t.scale);
}

Framebuffer make_framebuffer(const SceneDesc& scene, const RenderOptions& options) {
  Framebuffer fb;
  fb.width = scene.output.width;
  fb.height = scene.output.height;
  fb.background = scene.output.background;
  const std::size_t pixels = std::size_t(fb.width) * std::size_t(fb.height);
  fb.color.resize(pixels * 3);
  fb.depth.resize(pixels);
  for (Aov aov : options.aovs) fb.aov[std::size_t(aov)].resize(pixels * std::size_t(aov_channels(aov)));
  return fb;
}

}  // namespace

namespace {
struct AovInfo {
  Aov aov;
  const char* name;
  int channels;
};
constexpr AovInfo kAovs[kAovCount] = {
    {Aov::Depth, "depth", 1},          {Aov::Normal, "normal", 3},        {Aov::UV, "uv", 2},
    {Aov::Iterations, "iterations", 1}, {Aov::HitUV, "hit_uv", 2},         {Aov::HitDepth, "hit_depth", 1},
    {Aov::ErrorTexels, "error_texels", 1}, {Aov::Missed, "missed", 1},    {Aov::Shadow, "shadow", 1},
    {Aov::Ao, "ao", 1}};
}  // namespace

std::optional<Aov> parse_aov(const std::string& name) {
  for (const AovInfo& a : kAovs)
    if (name == a.name) return a.aov;
  return std::nullopt;
}

std::string aov_name(Aov aov) { return kAovs[int(aov)].name; }
int aov_channels(Aov aov) { return kAovs[int(aov)].channels; }

std::vector<std::string> aov_names() {
  std::vector<std::string> names;
  for (const AovInfo& a : kAovs) names.push_back(a.name);
  return names;
}

void validate_options(const RenderOptions& options) {
  if (options.threads < 0 || options.threads > limits::kMaxThreads)
    throw Error("--threads", "must be between 1 and " + std::to_string(limits::kMaxThreads) + " (or 0 for every core), got " +
                                 std::to_string(options.threads));
  if (options.tile_size < limits::kMinTileSize || options.tile_size > limits::kMaxTileSize ||
      options.tile_size % limits::kCoarseBlockSize != 0)
    throw Error("--tile", "must be a multiple of 8 between " + std::to_string(limits::kMinTileSize) + " and " +
                              std::to_string(limits::kMaxTileSize) + ", got " + std::to_string(options.tile_size));
}

namespace {

// The error AOVs summarised over the pixels some triangle covers (depth below the clear value), in pixel order.
void summarise_reference(const Framebuffer& fb, RenderStats& stats) {
  const PixelBuffer& error = fb.aov[std::size_t(Aov::ErrorTexels)];
  const PixelBuffer& missed = fb.aov[std::size_t(Aov::Missed)];
  if (error.empty() && missed.empty()) return;
  stats.reference = true;
  double error_sum = 0.0, missed_sum = 0.0;
  for (std::size_t i = 0; i < fb.depth.size(); ++i) {
    if (!(fb.depth[i] < 1.0f)) continue;
    ++stats.reference_pixels;
    if (!error.empty()) {
      error_sum += error[i];
      stats.error_texels_max = std::max(stats.error_texels_max, double(error[i]));
    }
    if (!missed.empty()) missed_sum += missed[i];
  }
  if (stats.reference_pixels == 0) return;
  stats.error_texels_mean = error_sum / double(stats.reference_pixels);
  stats.missed_fraction = missed_sum / double(stats.reference_pixels);
}

}  // namespace

nlohmann::json RenderStats::to_json() const {
  nlohmann::json j;
  j["time_ms"] = {{"load", load_ms},         {"prepare", prepare_ms},          {"geometry", geometry_ms},
                  {"binning", binning_ms},   {"raster_shade", raster_shade_ms}, {"write", write_ms},
                  {"total", load_ms + prepare_ms + geometry_ms + binning_ms + raster_shade_ms + write_ms}};
  j["triangles"] = {{"in", triangles_in}, {"culled", triangles_culled}, {"clipped", triangles_clipped},
                    {"rasterized", triangles_rasterized}};
  j["tiles"] = {{"count", tiles}, {"size", tile_size}, {"bin_entries", tile_bin_entries}};
  j["blocks"] = {{"rejected", blocks_rejected}, {"full", blocks_full}, {"partial", blocks_partial}};
  j["shading"] = {{"batches", batches}, {"quads", quads}, {"pixels_shaded", pixels_shaded},
                  {"pixels_depth_failed", pixels_depth_failed}, {"simd_lanes", simd_lanes}, {"simd_arch", simd_arch}};
  j["iterations"] = {{"mean", iterations_mean}, {"p99", iterations_p99}, {"max", iterations_max},
                     {"lane_utilisation", lane_utilisation}};
  if (reference)
    j["reference"] = {{"pixels", reference_pixels}, {"error_texels_mean", error_texels_mean},
                      {"error_texels_max", error_texels_max}, {"missed_fraction", missed_fraction}};
  j["threads"] = threads;
  j["memory"] = {{"framebuffer_bytes", framebuffer_bytes}, {"texture_bytes", texture_bytes},
                 {"mesh_bytes", mesh_bytes}, {"peak_rss_bytes", peak_rss_bytes}};
  j["textures"] = nlohmann::json::array();
  for (const TextureStat& t : textures) {
    nlohmann::json entry = {{"where", t.where},   {"purpose", t.purpose}, {"format", t.format}, {"width", t.width},
                            {"height", t.height}, {"levels", t.levels},   {"bytes", t.bytes}};
    if (!t.height_format.empty()) entry["height_format"] = t.height_format;
    if (t.bc3) entry["bc3"] = {{"max_error", t.bc3_max_error}, {"rms_error", t.bc3_rms_error}};
    j["textures"].push_back(entry);
  }
  return j;
}

Frame render_frame(const SceneDesc& scene, const RenderOptions& options) {
  validate_options(options);
  const int threads = options.threads > 0 ? options.threads : int(std::max(1u, std::thread::hardware_concurrency()));
  // Lets an arena larger than the core count run without oneTBB's warning.
  tbb::global_control parallelism(tbb::global_control::max_allowed_parallelism, std::size_t(threads));
  tbb::task_arena arena(threads);

  Frame frame;
  RenderStats& stats = frame.stats;
  stats.threads = threads;
  stats.tile_size = options.tile_size;
  stats.simd_lanes = simd::kLanes;
  stats.simd_arch = simd::Arch::name();

  std::mutex progress_mutex;
  const auto report = [&](const char* stage, double fraction) {
    if (!options.progress) return;
    std::lock_guard lock(progress_mutex);
    options.progress(stage, fraction);
  };

  arena.execute([&] {
    auto start = Clock::now();
    report("prepare", 0.0);
    const LightRig lights = LightRig::from_scene(scene);
    const Assets assets = prepare_assets(scene, lights, options);
    stats.prepare_ms = ms_since(start);
    report("prepare", 1.0);
    stats.texture_bytes = assets.texture_bytes();
    stats.textures = assets.texture_stats;
    stats.mesh_bytes = assets.mesh_bytes();

    start = Clock::now();
    const Viewport viewport{scene.output.width, scene.output.height};
    std::vector<DrawItem> draws = assets.draw_items();
    for (std::size_t i = 0; i < draws.size(); ++i) draws[i].model = model_matrix(scene.objects[i].transform);
    const glm::mat4 view = LightRig::view_matrix(scene.camera);
    const glm::mat4 projection = LightRig::projection_matrix(scene.camera, scene.output);
    const GeometryResult geometry = run_geometry(draws, view, projection, viewport);
    stats.geometry_ms = ms_since(start);
    stats.triangles_in = geometry.counters.triangles_in;
    stats.triangles_culled = geometry.counters.culled_backface + geometry.counters.culled_outside;
    stats.triangles_clipped = geometry.counters.clipped;
    stats.triangles_rasterized = geometry.counters.triangles_out;

    start = Clock::now();
    TriangleSetups setups(geometry.triangles.size());
    tbb::parallel_for(tbb::blocked_range<std::size_t>(0, setups.size(), 4096), [&](const auto& range) {
      for (std::size_t i = range.begin(); i != range.end(); ++i)
        setups[i] = setup_triangle(geometry.triangles[i], geometry, viewport);
    });
    const TileGrid grid(viewport.width, viewport.height, options.tile_size);
    const TileBins bins = bin_triangles(setups, grid);
    stats.binning_ms = ms_since(start);
    stats.tiles = std::uint64_t(grid.count());

    start = Clock::now();
    Framebuffer fb = make_framebuffer(scene, options);
    stats.framebuffer_bytes = fb.bytes();
    RasterContext context;
    context.geometry = &geometry;
    context.setups = &setups;
    context.framebuffer = &fb;
    for (const auto& program : assets.programs) context.programs.push_back(program.get());
    std::vector<TileCounters> tile_counters(std::size_t(grid.count()));
    std::atomic<int> tiles_done{0};
    const int report_every = std::max(1, grid.count() / 100);
    report("raster", 0.0);
    tbb::parallel_for(tbb::blocked_range<int>(0, grid.count(), 1), [&](const auto& range) {
      for (int tile = range.begin(); tile != range.end(); ++tile) {
        raster_tile(context, tile, grid.rect(tile), bins, tile_counters[std::size_t(tile)]);
        const int done = ++tiles_done;
        if (done % report_every == 0) report("raster", double(done) / grid.count());
      }
    });
    report("raster", 1.0);
    TileCounters total;
    for (const TileCounters& c : tile_counters) total += c;  // in tile order
    stats.raster_shade_ms = ms_since(start);
    stats.tile_bin_entries = total.bin_entries;
    stats.blocks_rejected = total.blocks_rejected;
    stats.blocks_full = total.blocks_full;
    stats.blocks_partial = total.blocks_partial;
    stats.batches = total.batches_shaded;
    stats.quads = total.quads_shaded;
    stats.pixels_shaded = total.pixels_shaded;
    stats.pixels_depth_failed = total.pixels_depth_failed;
    if (total.pixels_shaded > 0) {
      stats.iterations_mean = double(total.iterations_useful) / double(total.pixels_shaded);
      std::uint64_t seen = 0;
      const std::uint64_t p99_rank = (total.pixels_shaded * 99 + 99) / 100;  // ceil(0.99 n)
      bool p99_found = false;
      for (std::size_t i = 0; i < total.iteration_histogram.size(); ++i) {
        if (total.iteration_histogram[i] == 0) continue;
        seen += total.iteration_histogram[i];
        if (!p99_found && seen >= p99_rank) {
          stats.iterations_p99 = double(i);
          p99_found = true;
        }
        stats.iterations_max = double(i);
      }
    }
    if (total.iterations_executed > 0)
      stats.lane_utilisation = double(total.iterations_useful) / double(total.iterations_executed);

    summarise_reference(fb, stats);
    frame.width = fb.width;
    frame.height = fb.height;
    frame.color = std::move(fb.color);
    for (Aov aov : options.aovs) frame.aovs.push_back({aov, aov_channels(aov), std::move(fb.aov[std::size_t(aov)])});
  });
  stats.peak_rss_bytes = peak_rss_bytes();
  return frame;
}

}  // namespace qdmr
