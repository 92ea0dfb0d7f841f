#include "cli/bench.hpp"

#include <sys/resource.h>
#include <unistd.h>

#include <algorithm>
#include <chrono>
#include <cstdio>
#include <filesystem>

#include <nlohmann/json.hpp>

#include "qdmr/core/error.hpp"
#include "qdmr/core/limits.hpp"
#include "qdmr/load/load.hpp"
#include "qdmr/plan/plan.hpp"
#include "qdmr/render/render.hpp"
#include "qdmr/write/write.hpp"

namespace qdmr::cli {
namespace {

using Clock = std::chrono::steady_clock;

double ms_since(Clock::time_point start) {
  return std::chrono::duration<double, std::milli>(Clock::now() - start).count();
}

// The value at quantile q (0..1) of sorted samples, by linear interpolation between the nearest ranks.
double quantile(const std::vector<double>& sorted, double q) {
  if (sorted.empty()) return 0.0;
  const double position = q * double(sorted.size() - 1);
  const std::size_t lo = std::size_t(position), hi = std::min(lo + 1, sorted.size() - 1);
  return sorted[lo] + (sorted[hi] - sorted[lo]) * (position - double(lo));
}

nlohmann::json summary(std::vector<double> samples) {
  std::sort(samples.begin(), samples.end());
  return {{"median", quantile(samples, 0.5)}, {"min", samples.empty() ? 0.0 : samples.front()},
          {"p10", quantile(samples, 0.1)},    {"p90", quantile(samples, 0.9)},
          {"frames", samples.size()}};
}

std::uint64_t peak_rss_bytes() {
  rusage usage{};
  getrusage(RUSAGE_SELF, &usage);
  return std::uint64_t(usage.ru_maxrss) * 1024;
}

double load_average() {
  double load[1] = {0.0};
  return getloadavg(load, 1) == 1 ? load[0] : -1.0;
}

}  // namespace

int run_bench(const BenchArgs& args) {
  if (args.frames < 1 || args.frames > 100000)
    throw Error("--frames", "must be between 1 and 100000, got " + std::to_string(args.frames));
  if (args.warmup < 0 || args.warmup > 100000)
    throw Error("--warmup", "must be between 0 and 100000, got " + std::to_string(args.warmup));
  if (args.threads && (*args.threads < 1 || *args.threads > limits::kMaxThreads))
    throw Error("--threads", "must be from 1 to " + std::to_string(limits::kMaxThreads) + ", got " +
                                 std::to_string(*args.threads) + " (omit it to use every core)");
  RenderOptions options;
  options.threads = args.threads.value_or(0);
  options.tile_size = args.tile;
  const std::optional<Isa> isa = parse_isa(args.isa);
  if (!isa) throw Error("--isa", "unknown ISA '" + args.isa + "' (valid: auto, sse4.2, avx2, avx512)");
  options.isa = *isa;
  for (const std::string& name : args.aovs) {
    const std::optional<Aov> aov = parse_aov(name);
    if (!aov) throw Error("--aov " + name, "unknown AOV");
    if (std::find(options.aovs.begin(), options.aovs.end(), *aov) == options.aovs.end()) options.aovs.push_back(*aov);
  }
  validate_options(options);
  std::vector<SceneOverride> overrides;
  for (const std::string& s : args.sets) overrides.push_back(parse_override(s));
  if (args.width) overrides.push_back({"/output/width", std::to_string(*args.width)});
  if (args.height) overrides.push_back({"/output/height", std::to_string(*args.height)});
  const std::filesystem::path image =
      args.image.empty() ? std::filesystem::temp_directory_path() / ("qdmr-bench-" + std::to_string(::getpid()) + ".png")
                         : std::filesystem::path(args.image);

  auto start = Clock::now();
  const SceneDesc scene = load_scene(args.scene, overrides, 0, options.threads);  // on the draw's threads
  const double load_ms = ms_since(start);

  Renderer renderer(options);
  renderer.set_scene(scene, options.aovs);
  const bool tty = ::isatty(STDERR_FILENO);
  std::vector<double> draw_ms, geometry_ms, binning_ms, raster_ms;
  // An animated scene (a texture that changes with time, or a camera on keyframes) steps through its animation:
  // each draw is of the next frame (1, 2, ... wrapping to 0), after a warm rebuild of its dynamic items (set_frame;
  // none for a moving camera), so every timed frame is a frame of the sequence.
  const bool animated = scene.time_dependent() || !scene.camera.keyframes.empty();
  std::vector<double> rebuild_ms, frame_ms;
  std::vector<int> sequence_frames;
  double plan_ms = 0, prepare_ms = 0;
  const int total = args.warmup + args.frames;
  const auto wall = Clock::now();
  for (int i = 0; i < total; ++i) {
    const int sequence_frame = (i + 1) % scene.animation.frames;
    const auto rebuild_start = Clock::now();
    if (animated) renderer.set_frame(sequence_frame);
    const double rebuild = ms_since(rebuild_start);
    const RenderStats& stats = renderer.draw().stats;
    if (i == 0) {
      plan_ms = stats.plan_ms;
      prepare_ms = stats.prepare_ms;
    }
    if (i >= args.warmup) {
      draw_ms.push_back(stats.draw_ms());
      geometry_ms.push_back(stats.geometry_ms);
      binning_ms.push_back(stats.binning_ms);
      raster_ms.push_back(stats.raster_shade_ms);
      if (animated) {
        rebuild_ms.push_back(rebuild);
        frame_ms.push_back(rebuild + stats.draw_ms());
        sequence_frames.push_back(sequence_frame);
      }
    }
    // Progress on a terminal only; logs stay quiet.
    if (tty) std::fprintf(stderr, "\rframe %d/%d  %.1f ms", i + 1, total, stats.draw_ms());
  }
  if (tty) std::fprintf(stderr, "\r%40s\r", "");
  const double frames_wall_ms = ms_since(wall);

  start = Clock::now();
  write_frame(renderer.frame(), image, {.threads = options.threads});
  const double write_ms = ms_since(start);
  if (args.image.empty()) std::filesystem::remove(image);

  const RenderStats& last = renderer.frame().stats;
  nlohmann::json j;
  j["scene"] = args.scene;
  j["width"] = renderer.frame().width;
  j["height"] = renderer.frame().height;
  j["isa"] = isa_name(renderer.isa());
  j["threads"] = renderer.threads();
  j["tile_size"] = args.tile;
  j["warmup"] = args.warmup;
  j["load_ms"] = load_ms;
  j["plan_ms"] = plan_ms;
  j["prepare_ms"] = prepare_ms;
  j["draw_ms"] = summary(draw_ms);
  j["geometry_ms"] = summary(geometry_ms);
  j["binning_ms"] = summary(binning_ms);
  j["raster_shade_ms"] = summary(raster_ms);
  if (animated) {
    j["rebuild_ms"] = summary(rebuild_ms);
    j["frame_ms"] = summary(frame_ms);  // rebuild + draw of each timed frame
    j["sequence_frames"] = sequence_frames;
  }
  j["write_ms"] = write_ms;
  j["frames_wall_ms"] = frames_wall_ms;
  j["peak_rss_bytes"] = peak_rss_bytes();
  j["load_average_1min"] = load_average();
  j["pixels_shaded"] = last.pixels_shaded;
  // The trace's cost per unit of SIMD work: lane-iterations executed (useful ones / lane utilisation, so the idle
  // lanes of a batch count), against the median raster+shade time of all threads. That time includes everything
  // else a pixel costs, so this is an upper bound on what one iteration of the tracing loop costs.
  const double lane_iterations =
      last.lane_utilisation > 0 ? last.iterations_mean * double(last.pixels_shaded) / last.lane_utilisation : 0.0;
  const double raster_median_ms = j["raster_shade_ms"]["median"].get<double>();
  const bool traced = lane_iterations > 0;
  const double ns_per_lane_iteration =
      traced ? raster_median_ms * 1e6 * double(renderer.threads()) / lane_iterations : 0.0;
  j["iterations"] = {{"mean", last.iterations_mean}, {"p99", last.iterations_p99}, {"max", last.iterations_max},
                     {"lane_utilisation", last.lane_utilisation}, {"lane_iterations_executed", lane_iterations},
                     {"ns_per_lane_iteration", traced ? nlohmann::json(ns_per_lane_iteration) : nlohmann::json(nullptr)}};
  j["materials"] = nlohmann::json::array();
  for (const MaterialStat& m : last.materials) j["materials"].push_back({{"name", m.name}, {"variant", m.variant}});

  const nlohmann::json& d = j["draw_ms"];
  std::printf("%s: %dx%d, %s, %d threads, %d frames after %d warm-up\n", args.scene.c_str(), renderer.frame().width,
              renderer.frame().height, isa_name(renderer.isa()), renderer.threads(), args.frames, args.warmup);
  std::printf("  load %.1f ms, plan %.1f ms, prepare %.1f ms, write %.1f ms (%s)\n", load_ms, plan_ms, prepare_ms,
              write_ms, image.extension().string().c_str());
  std::printf("  draw: median %.2f ms, min %.2f, p10 %.2f, p90 %.2f\n", d["median"].get<double>(), d["min"].get<double>(),
              d["p10"].get<double>(), d["p90"].get<double>());
  if (animated)
    std::printf("  frames of the animation (rebuild + draw): median %.2f ms, rebuild median %.2f ms\n",
                j["frame_ms"]["median"].get<double>(), j["rebuild_ms"]["median"].get<double>());
  if (traced)
    std::printf("  trace: %.2f iterations per pixel (p99 %.0f, max %.0f), lane utilisation %.3f, %.2f ns per executed "
                "lane-iteration (raster+shade time of all threads / %.3g lane-iterations: an upper bound)\n",
                last.iterations_mean, last.iterations_p99, last.iterations_max, last.lane_utilisation,
                ns_per_lane_iteration, lane_iterations);
  std::printf("  peak RSS %.1f MiB, load average %.2f\n", double(peak_rss_bytes()) / (1024.0 * 1024.0), load_average());
  if (!args.json.empty()) write_json(j, args.json);
  return 0;
}

}  // namespace qdmr::cli
