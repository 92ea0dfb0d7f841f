// The qdmr command: a thin layer over the library (scene loading, planning, rendering, writing).
#include <unistd.h>

#include <algorithm>
#include <chrono>
#include <ctime>
#include <cstdint>
#include <cstdio>
#include <fstream>
#include <iostream>
#include <optional>
#include <set>
#include <string_view>

#include <CLI/CLI.hpp>
#include <nlohmann/json.hpp>
#include <tbb/task_arena.h>

#include "cli/bench.hpp"
#include "cli/check.hpp"
#include "cli/interrupt.hpp"
#include "file/os_error.hpp"
#include "cli/report.hpp"
#include "cli/step_progress.hpp"
#include "cli/study.hpp"
#include "core/frame_pattern.hpp"
#include "file/atomic_file.hpp"
#include "file/output_check.hpp"
#include "qdmr/bake/bake_cache.hpp"
#include "qdmr/bake/cone_map.hpp"
#include "qdmr/core/limits.hpp"
#include "qdmr/core/error.hpp"
#include "qdmr/core/progress.hpp"
#include "qdmr/core/version.hpp"
#include "qdmr/plan/plan.hpp"
#include "qdmr/render/render.hpp"
#include "qdmr/load/load.hpp"
#include "qdmr/texture/image.hpp"
#include "qdmr/write/write.hpp"

namespace {

constexpr int kExitBadInput = 2;

qdmr::cli::StepProgress steps(::isatty(STDERR_FILENO));  // long preparation steps (qdmr/core/progress.hpp)

struct SceneArgs {
  std::string scene;
  std::vector<std::string> sets;
  std::vector<std::string> aovs;  // NAME=FILE for render, NAME for plan
};

struct RenderArgs {
  std::string output;
  std::optional<int> width, height;  // absent: the scene's; checked like the scene's values
  std::optional<int> threads;  // absent: every core
  int tile = qdmr::RenderOptions{}.tile_size;
  std::string isa = "auto";
  std::string stats;
  bool timestamp = false;  // write the current time into the images
  bool smallest_png = false;
  std::optional<std::int64_t> max_memory_mib;  // absent: half the RAM
  std::string frames;          // --frames A:B[:STEP] of the scene's animation
  std::optional<int> frame;    // --frame N
};

// The default of --max-memory: half the machine's physical memory, in MiB.
std::int64_t default_max_memory_mib() {
  const long pages = ::sysconf(_SC_PHYS_PAGES), page = ::sysconf(_SC_PAGE_SIZE);
  if (pages <= 0 || page <= 0) return std::int64_t(1) << 14;  // unknown: 16 GiB
  return std::int64_t(std::uint64_t(pages) * std::uint64_t(page) / 2 >> 20);
}

// --max-memory in bytes: the flag's value (checked: 1 MiB to 1 PiB) or the default.
std::uint64_t max_memory_bytes(const std::optional<std::int64_t>& mib) {
  if (mib && (*mib < 1 || *mib > (std::int64_t(1) << 30)))
    throw qdmr::Error("--max-memory", "must be from 1 to 1073741824 (MiB), got " + std::to_string(*mib));
  return std::uint64_t(mib.value_or(default_max_memory_mib())) << 20;
}

// Which limit refused a job, for the end of its message.
const char* max_memory_source(const std::optional<std::int64_t>& mib) {
  return mib ? " (--max-memory)" : " (half the RAM; raise it with --max-memory)";
}

std::vector<qdmr::SceneOverride> overrides(const SceneArgs& args, const RenderArgs* render) {
  std::vector<qdmr::SceneOverride> result;
  for (const std::string& s : args.sets) result.push_back(qdmr::parse_override(s));
  if (render && render->width) result.push_back({"/output/width", std::to_string(*render->width)});
  if (render && render->height) result.push_back({"/output/height", std::to_string(*render->height)});
  return result;
}

qdmr::Aov aov_from(const std::string& name) {
  if (auto aov = qdmr::parse_aov(name)) return *aov;
  std::string valid;
  for (const std::string& n : qdmr::aov_names()) valid += (valid.empty() ? "" : ", ") + n;
  throw qdmr::Error("--aov", "unknown AOV '" + name + "' (valid: " + valid + ")");
}

// The image type of an output; where it may be written is checked by check_outputs (file/output_check.hpp).
void check_output_type(const std::string& option, const std::filesystem::path& out) {
  std::string ext = out.extension().string();
  for (char& c : ext) c = char(std::tolower(static_cast<unsigned char>(c)));
  if (ext != ".png" && ext != ".exr" && ext != ".tif" && ext != ".tiff")
    throw qdmr::Error(option + " " + out.string(), "unsupported image type '" + ext + "' (use .png, .exr or .tif)");
}


qdmr::RenderOptions render_options(const RenderArgs& render) {
  qdmr::RenderOptions options;
  if (render.threads && (*render.threads < 1 || *render.threads > qdmr::limits::kMaxThreads))
    throw qdmr::Error("--threads", "must be from 1 to " + std::to_string(qdmr::limits::kMaxThreads) + ", got " +
                                       std::to_string(*render.threads) + " (omit it to use every core)");
  options.threads = render.threads.value_or(0);
  options.max_memory_bytes = max_memory_bytes(render.max_memory_mib);
  options.tile_size = render.tile;
  const std::optional<qdmr::Isa> isa = qdmr::parse_isa(render.isa);
  if (!isa) throw qdmr::Error("--isa", "unknown ISA '" + render.isa + "' (valid: auto, sse4.2, avx2, avx512)");
  options.isa = *isa;
  qdmr::validate_options(options);
  return options;
}

// One output of every frame: its option, and its name with or without a frame number.
struct FrameOutput {
  std::string option, pattern;
  // Frame -1 (a render without --frames or --frame) takes the name as it is.
  std::filesystem::path at(int frame) const { return frame < 0 ? pattern : qdmr::frame_name(pattern, frame); }
};

// The frames a render draws: --frames or --frame of the scene's animation, else the scene as it is (frame -1).
std::vector<int> frames_to_render(const RenderArgs& render, const qdmr::SceneDesc& scene) {
  const bool sequence = !render.frames.empty();
  if (!sequence && !render.frame) return {-1};
  const std::string option = sequence ? "--frames " + render.frames : "--frame " + std::to_string(*render.frame);
  if (!scene.animation.present)
    throw qdmr::Error(option, scene.file.string() + " has no /animation (frames and fps) to take frames from");
  const qdmr::FrameRange range =
      sequence ? qdmr::parse_frame_range(option, render.frames) : qdmr::FrameRange{*render.frame, *render.frame, 1};
  if (range.first < 0 || range.last >= scene.animation.frames)
    throw qdmr::Error(option, "the scene's animation has frames 0 to " + std::to_string(scene.animation.frames - 1));
  return range.frames();
}

int run_render(const SceneArgs& args, const RenderArgs& render) {
  using Clock = std::chrono::steady_clock;
  qdmr::RenderOptions options = render_options(render);
  if (!render.frames.empty() && render.frame) throw qdmr::Error("--frame", "give --frames or --frame, not both");
  check_output_type("-o", render.output);
  std::vector<FrameOutput> outputs{{"-o", render.output}};
  std::vector<qdmr::Aov> aov_kinds;
  std::set<std::string> seen;
  for (const std::string& spec : args.aovs) {
    const auto eq = spec.find('=');
    if (eq == std::string::npos || eq == 0 || eq + 1 == spec.size())
      throw qdmr::Error("--aov " + spec, "expected NAME=FILE, e.g. --aov depth=depth.exr");
    const std::string name = spec.substr(0, eq);
    if (!seen.insert(name).second) throw qdmr::Error("--aov " + spec, "AOV '" + name + "' given twice");
    aov_kinds.push_back(aov_from(name));
    outputs.push_back({"--aov", spec.substr(eq + 1)});
    check_output_type("--aov", outputs.back().pattern);
    options.aovs.push_back(aov_kinds.back());
  }
  if (!render.stats.empty()) outputs.push_back({"--stats", render.stats});
  // A sequence names every output per frame; one frame may (or may not) number its names.
  const bool animated = !render.frames.empty() || render.frame;
  for (const FrameOutput& o : outputs)
    if (animated && !qdmr::has_frame_number(o.option + " " + o.pattern, o.pattern) && !render.frames.empty())
      throw qdmr::Error(o.option + " " + o.pattern,
                        "names no frame number: a sequence (--frames) needs one, e.g. out_%04d.png");
  // Folders, and outputs equal to each other, before the scene is read (the frames are known after it).
  const auto all_outputs = [&](const std::vector<int>& frames) {
    std::vector<qdmr::OutputPath> paths;
    for (int f : frames)
      for (const FrameOutput& o : outputs) paths.push_back({o.option, o.at(f)});
    return paths;
  };
  qdmr::check_outputs(all_outputs({animated ? 0 : -1}));

  auto start = Clock::now();
  const qdmr::SceneDesc scene = [&] {
    try {  // a glTF mesh's drawn copies are held to the limit before they are read; --threads bounds the load too
      return qdmr::load_scene(args.scene, overrides(args, &render), options.max_memory_bytes, options.threads);
    } catch (const qdmr::Error& e) {
      const std::string what = e.what();
      if (what.find("MiB, more than the limit of") == std::string::npos) throw;
      throw qdmr::Error(what + max_memory_source(render.max_memory_mib));
    }
  }();
  const double load_ms = std::chrono::duration<double, std::milli>(Clock::now() - start).count();
  const std::vector<int> frames = frames_to_render(render, scene);
  const std::vector<qdmr::OutputPath> paths = all_outputs(frames);
  qdmr::check_outputs(paths);  // the scene, its textures and OBJ files are known inputs now
  // The plan's estimate (`qdmr plan` prints it part by part) is checked by set_scene (against
  // options.max_memory_bytes) before anything is built.

  // Progress only on a terminal: logs and CI stay quiet.
  std::string frame_text;  // "frame 3 (2/120) " while a sequence renders
  if (::isatty(STDERR_FILENO))
    options.progress = [&frame_text](const char* stage, double fraction) {
      std::fprintf(stderr, "\r%s%-8s %3d%%", frame_text.c_str(), stage, int(fraction * 100.0 + 0.5));
      if (fraction >= 1.0 && std::string_view(stage) == "raster")
        std::fprintf(stderr, "\r%*s\r", int(frame_text.size()) + 15, "");
      std::fflush(stderr);
    };
  // load -> plan -> prepare (set_scene) -> draw -> write, for each frame through one renderer: a frame after the
  // first prepares only the plan's dynamic items (those whose content changes with time).
  qdmr::Renderer renderer(options);
  for (std::size_t i = 0; i < frames.size(); ++i) {
    const int n = frames[i];
    if (frames.size() > 1)
      frame_text = "frame " + std::to_string(n) + " (" + std::to_string(i + 1) + "/" + std::to_string(frames.size()) + ") ";
    try {
      renderer.set_scene(n >= 0 ? qdmr::scene_at_frame(scene, n) : scene, options.aovs);
    } catch (const qdmr::Error& e) {
      const std::string what = e.what();
      if (what.find("MiB (see qdmr plan), more than the limit of") == std::string::npos) throw;
      throw qdmr::Error(what + max_memory_source(render.max_memory_mib));
    }
    qdmr::Frame frame = (renderer.draw(), renderer.take_frame());
    frame.stats.load_ms = i == 0 ? load_ms : 0.0;
    if (n >= 0) {
      frame.stats.frame = n;
      frame.stats.time_s = double(n) / scene.animation.fps;
    }
    qdmr::check_outputs(paths);  // and now also the MTL files, the maps they name and the caches read

    qdmr::throw_if_stop_requested();  // Ctrl-C while drawing: nothing of this frame is written
    // Every output of the frame written to a temporary first, then all renamed: all of them or none.
    qdmr::OutputBatch batch;
    start = Clock::now();
    const qdmr::WriteOptions write{
        .timestamp = render.timestamp, .smallest_png = render.smallest_png, .threads = options.threads};
    const int at = n;
    qdmr::write_frame(frame, outputs[0].at(at), write);
    for (std::size_t a = 0; a < aov_kinds.size(); ++a) qdmr::write_aov(frame, aov_kinds[a], outputs[1 + a].at(at), write);
    frame.stats.write_ms = std::chrono::duration<double, std::milli>(Clock::now() - start).count();
    if (!render.stats.empty()) qdmr::write_stats(frame.stats, outputs.back().at(at));
    qdmr::throw_if_stop_requested();  // and while writing: the batch removes its temporaries
    batch.commit();
    const qdmr::RenderStats& s = frame.stats;
    std::printf("%s: %dx%d, %llu triangles, %llu pixels shaded, %.1f ms (%d threads, %s)\n",
                outputs[0].at(at).c_str(), frame.width, frame.height,
                static_cast<unsigned long long>(s.triangles_rasterized), static_cast<unsigned long long>(s.pixels_shaded),
                s.load_ms + s.plan_ms + s.prepare_ms + s.draw_ms() + s.write_ms, s.threads, s.simd_arch.c_str());
    renderer.recycle_frame(std::move(frame));  // the next frame draws into its buffers
  }
  return 0;
}

int run_plan(const SceneArgs& args, bool as_json) {
  qdmr::PlanOptions options;
  std::set<std::string> seen;
  for (const std::string& name : args.aovs) {
    if (!seen.insert(name).second) throw qdmr::Error("--aov " + name, "AOV given twice");
    options.aovs.push_back(aov_from(name));
  }
  const qdmr::SceneDesc scene = qdmr::load_scene(args.scene, overrides(args, nullptr));
  const qdmr::FramePlan plan = qdmr::plan_frame(scene, options);
  if (as_json)
    std::cout << plan.to_json().dump(2) << "\n";
  else
    std::cout << plan.describe();
  return 0;
}

struct ConeArgs {
  std::string height, output, kind = "conservative", channel = "r", address = "wrap";
  std::optional<std::int64_t> max_memory_mib;  // absent: half the RAM
  std::optional<int> threads;                  // absent: every core
};

// The most `qdmr bake cone` holds at once, from the image's header: reading (the image as floats, and its 8- or
// 16-bit samples while they are converted), copying the channel (the image and the field of doubles), baking
// (the field and the baker's own, qdmr::cone_bake_bytes; the image is freed by then), writing (the map and its
// rows in file order; the field is freed by then).
std::uint64_t cone_command_bytes(const qdmr::ImageHeader& header, qdmr::ConeKind kind, qdmr::AddressMode address) {
  const std::uint64_t texels = std::uint64_t(header.width) * std::uint64_t(header.height);
  const std::uint64_t image = texels * std::uint64_t(header.channels) * sizeof(float);
  const std::uint64_t samples = texels * std::uint64_t(header.channels) * std::uint64_t(header.source_bits == 8    ? 1
                                                                                         : header.source_bits == 16 ? 2
                                                                                                                    : 0);
  const std::uint64_t field = texels * sizeof(double);
  return std::max({image + samples, image + field,
                   field + qdmr::cone_bake_bytes(header.width, header.height, kind, address), 2 * texels * sizeof(float)});
}

// The pixels of `qdmr bake cone`, once its arguments and the header are checked: read, bake, write.
int bake_cone_in_arena(const ConeArgs& args, const qdmr::ImageHeader& header, qdmr::ConeKind kind,
                       qdmr::AddressMode mode, int channel, const std::filesystem::path& out) {
  qdmr::HeightField field;
  {
    const qdmr::Image image = qdmr::read_image(args.height, args.height);
    if (image.width != header.width || image.height != header.height || image.channels != header.channels)
      throw qdmr::Error(args.height, "changed while it was read");
    field.width = image.width;
    field.height = image.height;
    field.address = mode;
    field.h = qdmr::ZeroedBuffer<double>(std::size_t(image.width) * std::size_t(image.height));
    for (std::size_t k = 0; k < field.h.size(); ++k)
      field.h[k] = image.texels[k * std::size_t(image.channels) + std::size_t(channel)];
  }  // the image is freed before the bake
  const auto start = std::chrono::steady_clock::now();
  qdmr::ConeMap map;
  try {
    map = qdmr::bake_cone_map(field, kind);
  } catch (const qdmr::Error& e) {
    throw qdmr::Error(args.height, e.what());
  }
  const double bake_ms = std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - start).count();
  field = {};  // and the field before the write
  qdmr::throw_if_stop_requested();
  qdmr::write_cone_map_exr(map, out);
  std::printf("%s: %dx%d %s cone map, %.1f ms\n", args.output.c_str(), map.width, map.height,
              qdmr::cone_kind_name(kind), bake_ms);
  return 0;
}

// qdmr bake cone: the cone map of one channel of a height image, as a 32-bit float EXR.
int run_bake_cone(const ConeArgs& args) {
  if (args.kind != "conservative" && args.kind != "relaxed")
    throw qdmr::Error("--kind " + args.kind, "unknown cone kind (valid: conservative, relaxed)");
  const std::string addresses[] = {"wrap", "clamp", "mirror"};
  const auto address = std::find(std::begin(addresses), std::end(addresses), args.address);
  if (address == std::end(addresses))
    throw qdmr::Error("--address " + args.address, "unknown address mode (valid: wrap, clamp, mirror)");
  const std::string channels = "rgba";
  if (args.channel.size() != 1 || channels.find(args.channel[0]) == std::string::npos)
    throw qdmr::Error("--channel " + args.channel, "unknown channel (valid: r, g, b, a)");
  if (args.threads && (*args.threads < 1 || *args.threads > qdmr::limits::kMaxThreads))
    throw qdmr::Error("--threads", "must be from 1 to " + std::to_string(qdmr::limits::kMaxThreads) + ", got " +
                                       std::to_string(*args.threads) + " (omit it to use every core)");
  const std::uint64_t limit = max_memory_bytes(args.max_memory_mib);
  const std::filesystem::path out = args.output;
  if (out.extension() != ".exr") throw qdmr::Error("-o " + args.output, "the cone map is written as .exr");
  const std::vector<qdmr::OutputPath> outputs{{"-o", out}};
  qdmr::check_outputs(outputs);
  const qdmr::ConeKind kind = args.kind == "relaxed" ? qdmr::ConeKind::Relaxed : qdmr::ConeKind::Conservative;
  const qdmr::AddressMode mode = qdmr::AddressMode(address - std::begin(addresses));
  // Everything that can refuse the job is checked from the header, before any pixel is decoded.
  const qdmr::ImageHeader header = qdmr::read_image_header(args.height, args.height);
  qdmr::check_outputs(outputs);  // the height image is a known input now
  const int channel = int(channels.find(args.channel[0]));
  if (channel >= header.channels)
    throw qdmr::Error(args.height,
                      "has " + std::to_string(header.channels) + " channel(s), no channel '" + args.channel + "'");
  if (const std::uint64_t needed = cone_command_bytes(header, kind, mode); needed > limit)
    throw qdmr::Error(args.height, "baking its " + std::to_string(header.width) + "x" + std::to_string(header.height) +
                                       " " + qdmr::cone_kind_name(kind) + " cone map (address " + args.address +
                                       ") needs an estimated " + std::to_string((needed + (1 << 20) - 1) >> 20) +
                                       " MiB, more than the limit of " + std::to_string(limit >> 20) + " MiB" +
                                       max_memory_source(args.max_memory_mib));
  // Reading, baking and writing on --threads threads: the height file's decoding (an OpenEXR file's chunks), the
  // bake's rows and the cone map's chunks run on this arena or pools of its size (the same bits on any count).
  // (automatic by value: value_or binds a reference, and oneTBB's static const member has no definition to bind to.)
  tbb::task_arena arena(args.threads ? *args.threads : int(tbb::task_arena::automatic));
  return arena.execute([&] { return bake_cone_in_arena(args, header, kind, mode, channel, out); });
}

std::string mib_text(std::uint64_t bytes) {
  char text[32];
  std::snprintf(text, sizeof text, "%.1f MiB", double(bytes) / double(1 << 20));
  return text;
}

// qdmr cache: where the bake cache is, its limit, and what it holds (most recently used first).
int run_cache(bool clear) {
  const std::filesystem::path folder = qdmr::default_cache_dir();
  if (clear) {
    const auto [count, bytes] = qdmr::clear_bake_cache(folder);
    std::printf("%s: removed %zu entries, %s\n", folder.c_str(), count, mib_text(bytes).c_str());
    return 0;
  }
  const std::uint64_t limit = qdmr::bake_cache_limit_bytes();
  std::printf("bake cache: %s\n  (QDMR_CACHE_DIR, else $XDG_CACHE_HOME/qdmr, else ~/.cache/qdmr)\n", folder.c_str());
  std::printf("limit: %s (%s; least recently used entries are removed past it)\n", mib_text(limit).c_str(),
              qdmr::kBakeCacheLimitVariable);
  const std::vector<qdmr::BakeCacheEntry> entries = qdmr::bake_cache_entries(folder);
  std::uint64_t total = 0;
  for (const qdmr::BakeCacheEntry& e : entries) total += e.bytes;
  std::printf("%zu entries, %s\n", entries.size(), mib_text(total).c_str());
  for (auto e = entries.rbegin(); e != entries.rend(); ++e) {
    const std::time_t used = std::chrono::system_clock::to_time_t(std::chrono::file_clock::to_sys(e->last_used));
    std::tm local{};
    ::localtime_r(&used, &local);
    char when[32];
    std::strftime(when, sizeof when, "%Y-%m-%d %H:%M", &local);
    std::printf("  %s  %10s  %-24s  used %s\n", e->file.filename().c_str(), mib_text(e->bytes).c_str(), e->kind.c_str(), when);
  }
  return 0;
}

}  // namespace

int main(int argc, char** argv) {
  CLI::App app{
      "qdmr: a CPU rasterizer for per-pixel displacement mapping (quadtree displacement mapping and friends).\n"
      "Renders a JSON scene to an image, the same bits on any machine and thread count.\n\n"
      "  qdmr render scenes/plane.json -o plane.png\n"
      "  qdmr render scenes/terrain.json -o t.exr --set /camera/fov_deg=30 --aov depth=depth.exr --stats stats.json\n"
      "  qdmr plan scenes/terrain.json\n"
      "  qdmr bench scenes/terrain.json --frames 20 --json bench.json\n"
      "  qdmr check tests/golden/shipped_scenes.json --junit junit.xml --report check-report\n"
      "  qdmr diff a.exr b.exr --max-abs 0.01 --heatmap diff.png\n\n"
      "The scene format is described in docs/scene-format.md."};
  app.require_subcommand(1);
  app.set_version_flag("--version", std::string("qdmr ") + qdmr::version() + " (bits version " +
                                        std::to_string(qdmr::kBitsVersion) + ")");

  SceneArgs render_scene;
  RenderArgs render;
  CLI::App* render_cmd = app.add_subcommand("render", "Render a scene to an image");
  render_cmd->add_option("scene", render_scene.scene, "Scene file (JSON)")->required();
  render_cmd->add_option("-o,--output", render.output, "Output image: .png (8-bit sRGB), .tif (16-bit sRGB) or .exr (linear float)")
      ->required();
  render_cmd->add_option("--width", render.width, "Override /output/width (pixels)");
  render_cmd->add_option("--height", render.height, "Override /output/height (pixels)");
  render_cmd->add_option("--frames", render.frames,
                         "Render frames FIRST:LAST[:STEP] (inclusive) of the scene's animation through one renderer; "
                         "-o, --aov and --stats then name a frame number, e.g. -o out_%04d.png");
  render_cmd->add_option("--frame", render.frame, "Render frame N of the scene's animation (names may hold %04d)");
  render_cmd->add_option("--threads", render.threads, "Worker threads, 1 to 256 (default: every core)");
  render_cmd->add_option("--tile", render.tile, "Screen tile size in pixels, a multiple of 8 (default 64)");
  render_cmd->add_option("--isa", render.isa,
                         "Draw kernel: auto (default: $QDMR_ISA, else the best this CPU has), sse4.2, avx2 or avx512. "
                         "Every ISA gives the same bits");
  render_cmd->add_option("--set", render_scene.sets,
                         "Override a scene value before validation: /json/pointer=VALUE (VALUE is JSON; a bare word is a "
                         "string). Repeatable, e.g. --set /camera/fov_deg=30");
  std::string aov_list;
  for (const std::string& n : qdmr::aov_names()) aov_list += (aov_list.empty() ? "" : ", ") + n;
  render_cmd->add_option("--aov", render_scene.aovs, "Also write an AOV: NAME=FILE with NAME one of " + aov_list + ". Repeatable");
  render_cmd->add_option("--stats", render.stats, "Write timings and counters as JSON to this file");
  render_cmd->add_flag("--timestamp", render.timestamp,
                       "Write the current local time into the images (EXR capDate, TIFF DateTime, PNG tIME). Off by "
                       "default: the same scene gives byte-identical files");
  render_cmd->add_flag("--smallest-png", render.smallest_png,
                       "Compress PNG outputs as small as possible (libdeflate's level 12: 10-25 % smaller, seconds for a "
                       "1080p frame) instead of as fast as possible (ISA-L's igzip: about 15 ms). The same pixels "
                       "either way");
  render_cmd->add_option("--max-memory", render.max_memory_mib,
                         "Refuse a job whose estimated memory (see qdmr plan) exceeds this many MiB (default: half the RAM)");

  SceneArgs plan_scene;
  bool plan_json = false;
  CLI::App* plan_cmd = app.add_subcommand("plan", "Print what a scene requires: programs, textures, derived data, memory");
  plan_cmd->add_option("scene", plan_scene.scene, "Scene file (JSON)")->required();
  plan_cmd->add_option("--set", plan_scene.sets, "Override a scene value: /json/pointer=VALUE (repeatable)");
  plan_cmd->add_option("--aov", plan_scene.aovs, "AOV names to plan for (repeatable)");
  plan_cmd->add_flag("--json", plan_json, "Print the plan as JSON");

  qdmr::cli::BenchArgs bench;
  CLI::App* bench_cmd = app.add_subcommand(
      "bench", "Time warm frames of a scene with one persistent renderer: load, plan, prepare once, draw N frames");
  bench_cmd->add_option("scene", bench.scene, "Scene file (JSON)")->required();
  bench_cmd->add_option("--frames", bench.frames, "Timed frames (default 10)");
  bench_cmd->add_option("--warmup", bench.warmup, "Untimed frames first (default 2)");
  bench_cmd->add_option("--threads", bench.threads, "Worker threads (default: every core)");
  bench_cmd->add_option("--tile", bench.tile, "Screen tile size in pixels, a multiple of 8 (default 64)");
  bench_cmd->add_option("--isa", bench.isa, "Draw kernel: auto (default), sse4.2, avx2 or avx512");
  bench_cmd->add_option("--width", bench.width, "Override /output/width (pixels)");
  bench_cmd->add_option("--height", bench.height, "Override /output/height (pixels)");
  bench_cmd->add_option("--set", bench.sets, "Override a scene value: /json/pointer=VALUE (repeatable)");
  bench_cmd->add_option("--aov", bench.aovs, "Also render this AOV in every frame (repeatable)");
  bench_cmd->add_option("--json", bench.json, "Write the results as JSON to this file");
  bench_cmd->add_option("--image", bench.image, "Write the last frame here (timed once as write_ms; default: a temporary file)");

  ConeArgs cone;
  CLI::App* bake_cmd = app.add_subcommand("bake", "Bake derived data of a height map");
  bake_cmd->require_subcommand(1);
  CLI::App* cone_cmd =
      bake_cmd->add_subcommand("cone", "Bake a cone map for cone step mapping (csm, rcsm) to a 32-bit float EXR");
  cone_cmd->add_option("height", cone.height, "Height image (h in [0,1], 1 = top)")->required();
  cone_cmd->add_option("-o,--output", cone.output, "Output cone map (.exr, one float channel: the cone ratio)")
      ->required();
  cone_cmd->add_option("--kind", cone.kind, "conservative (csm, default) or relaxed (rcsm)");
  cone_cmd->add_option("--channel", cone.channel, "Channel holding the heights: r (default), g, b or a");
  cone_cmd->add_option("--address", cone.address, "Address mode of the map: wrap (default), clamp or mirror");
  cone_cmd->add_option("--max-memory", cone.max_memory_mib,
                       "Refuse a bake whose estimated memory exceeds this many MiB (default: half the RAM)");
  cone_cmd->add_option("--threads", cone.threads,
                       "Worker threads reading, baking and writing, 1 to 256 (default: every core). Every count gives "
                       "the same bits");

  qdmr::cli::CheckArgs check;
  CLI::App* check_cmd = app.add_subcommand(
      "check", "Golden-image checks: render every check of a manifest (or one scene) and compare with its golden "
               "hash or image (docs/checks.md). Exit 0: all pass, 1: some fail, 2: cannot run");
  check_cmd->add_option("target", check.target, "Check manifest (JSON), or a scene with --golden or --hash")->required();
  check_cmd->add_option("--golden", check.golden, "One-off form: compare the scene's image with this golden image");
  check_cmd->add_option("--hash", check.hash, "One-off form: the scene's image must have this canonical hash (sha1:...)");
  check_cmd->add_option("--set", check.sets, "One-off form: override a scene value, /json/pointer=VALUE (repeatable)");
  check_cmd->add_option("--width", check.width, "One-off form: override /output/width");
  check_cmd->add_option("--height", check.height, "One-off form: override /output/height");
  check.tolerance.add_to(*check_cmd);
  check_cmd->add_flag("--update", check.update,
                      "Rewrite the goldens (or hashes) of failing and missing checks, atomically, and print what changed");
  check_cmd->add_option("--junit", check.junit, "Write JUnit XML here (one test case per check)");
  check_cmd->add_option("--json", check.json, "Write every result (status, hashes, prepare and draw times) as JSON here");
  check_cmd->add_option("--report", check.report,
                        "Write an HTML page of every failure to DIR/index.html (the diff folders go into DIR)");
  check_cmd->add_option("--diff-dir", check.diff_dir, "Where the diff folder of each failed check goes (default qdmr-check-failures)");
  check_cmd->add_option("--jobs", check.jobs, "Checks rendered at once, each with its own renderer (default 1)");
  check_cmd->add_option("--threads", check.threads, "Worker threads over all jobs (default: every core)");

  qdmr::cli::DiffArgs diff;
  CLI::App* diff_cmd = app.add_subcommand(
      "diff", "Compare two images (any format OpenImageIO reads) with the check metrics. Exit 0: within the "
              "tolerance, 1: not, 2: unreadable");
  diff_cmd->add_option("a", diff.a, "First image (e.g. the new render)")->required();
  diff_cmd->add_option("b", diff.b, "Second image (e.g. the golden)")->required();
  diff.tolerance.add_to(*diff_cmd);
  diff_cmd->add_option("--heatmap", diff.heatmap, "Write the difference heatmap (largest channel, magma) to this .png");

  qdmr::cli::StudyArgs study;
  CLI::App* study_cmd = app.add_subcommand(
      "study", "Sweep a scene's settings in one process: time, iterations and error against the exact reference per "
               "configuration, and the Pareto fronts (docs/studies.md)");
  study_cmd->add_option("spec", study.spec, "Study spec (JSON)");
  study_cmd->add_option("-o,--output", study.output, "Results folder (created)");
  study_cmd->add_option("--shard", study.shard, "Run shard I of N (I/N), balanced by estimated cost; merge with qdmr study merge");
  study_cmd->add_flag("--resume", study.resume, "Continue an interrupted run of the same spec in the same folder");
  study_cmd->add_flag("--force", study.force, "Run more configurations than the spec's max_configurations");
  study_cmd->add_option("--threads", study.threads, "Worker threads per configuration (default: every core / jobs)");
  study_cmd->add_option("--jobs", study.jobs, "Configurations drawn at once, each with its own renderers (default 1; "
                                              "rows are the same, times include the contention)");
  qdmr::cli::StudyMergeArgs merge;
  CLI::App* merge_cmd = study_cmd->add_subcommand("merge", "Merge the folders of every shard of a study");
  merge_cmd->add_option("folders", merge.folders, "The shard folders")->required();
  merge_cmd->add_option("-o,--output", merge.output, "Merged results folder")->required();
  study_cmd->add_flag("--report", study.report, "When the study is done, write its report (qdmr report) to FOLDER-report");
  study_cmd->require_subcommand(0, 1);

  qdmr::cli::ReportArgs report;
  CLI::App* report_cmd = app.add_subcommand(
      "report", "Write an HTML page of a study's results: Pareto fronts, metrics along each numeric axis, the worst "
                "artifacts beside the exact reference, every row sortable; opens from disk (docs/studies.md)");
  report_cmd->add_option("results", report.results, "Results folder of qdmr study (or qdmr study merge)")->required();
  report_cmd->add_option("-o,--output", report.output, "Report folder (default: RESULTS-report); replaces an earlier report there");
  report_cmd->add_option("--worst", report.worst, "How many worst artifacts to crop (0 to 100, default 6)");
  report_cmd->add_option("--crop", report.crop, "Crop size in pixels (8 to 1024, default 96)");
  report_cmd->add_flag("--partial", report.partial, "Report an unfinished study or one shard instead of refusing it");

  CLI::App* cache_cmd = app.add_subcommand(
      "cache", "Show the bake cache of cone and AO maps: where it is, its size limit, what it holds (docs/scene-format.md)");
  CLI::App* cache_clear_cmd = cache_cmd->add_subcommand("clear", "Remove every entry of the bake cache");
  cache_cmd->require_subcommand(0, 1);

  // Errors of the command line are one line, like every other error; `qdmr` alone prints the usage.
  app.failure_message([](const CLI::App*, const CLI::Error& e) {
    return std::string("qdmr: error: ") + e.what() + " (see qdmr --help)\n";
  });
  if (argc < 2) {
    std::fputs(app.help().c_str(), stderr);
    return kExitBadInput;
  }
  try {
    app.parse(argc, argv);
  } catch (const CLI::ParseError& e) {
    const int code = app.exit(e);
    return code == 0 ? 0 : kExitBadInput;
  }
  qdmr::cli::stop_on_signals();
  qdmr::set_progress_sink(&steps);  // lines on a terminal only (logs and CI stay quiet)
  qdmr::set_warning_sink(&steps);   // "qdmr: warning: ..." lines on stderr, terminal or not
  try {
    if (render_cmd->parsed()) return run_render(render_scene, render);
    if (plan_cmd->parsed()) return run_plan(plan_scene, plan_json);
    if (bench_cmd->parsed()) return qdmr::cli::run_bench(bench);
    if (cone_cmd->parsed()) return run_bake_cone(cone);
    if (check_cmd->parsed()) return qdmr::cli::run_check(check);
    if (merge_cmd->parsed()) return qdmr::cli::run_study_merge(merge);
    if (study_cmd->parsed()) {
      if (study.spec.empty() || study.output.empty())
        throw qdmr::Error("qdmr study", "expected SPEC.json -o FOLDER (or: qdmr study merge FOLDER... -o FOLDER)");
      return qdmr::cli::run_study(study);
    }
    if (diff_cmd->parsed()) return qdmr::cli::run_diff(diff);
    if (report_cmd->parsed()) return qdmr::cli::run_report(report);
    if (cache_cmd->parsed()) return run_cache(cache_clear_cmd->parsed());
  } catch (const qdmr::Interrupted&) {
    std::fprintf(stderr, "qdmr: interrupted (SIGINT or SIGTERM): stopped, nothing half-written\n");
    return qdmr::cli::kExitInterrupted;
  } catch (const qdmr::Error& e) {
    std::fprintf(stderr, "qdmr: error: %s\n", e.what());
    return kExitBadInput;
  } catch (const std::filesystem::filesystem_error& e) {
    std::fprintf(stderr, "qdmr: error: %s\n", qdmr::os_error_line(e).c_str());
    return kExitBadInput;
  } catch (const std::bad_alloc&) {
    std::fprintf(stderr, "qdmr: error: out of memory (try a smaller --width/--height or textures)\n");
    return kExitBadInput;
  } catch (const std::exception& e) {
    std::fprintf(stderr, "qdmr: error: %s\n", e.what());
    return 1;
  }
  return 0;
}
