#include <sys/resource.h>

#include <atomic>
#include <chrono>
#include <cmath>
#include <mutex>
#include <optional>
#include <set>
#include <string>
#include <thread>
#include <vector>

#include <tbb/global_control.h>
#include <tbb/info.h>
#include <tbb/task_arena.h>

#include "draw/draw.hpp"
#include "prepare/assets.hpp"
#include "qdmr/core/error.hpp"
#include "qdmr/core/limits.hpp"
#include "qdmr/plan/plan.hpp"
#include "qdmr/render/render.hpp"
#include "raster/framebuffer.hpp"

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

// Bytes of the previous plan's items (textures, derived data, meshes) that the next plan does not share: prepare
// builds the next scene's items while they are still held.
std::uint64_t unshared_bytes(const FramePlan& previous, const FramePlan& next) {
  std::set<std::string> keys;
  for (const TextureRequest& t : next.textures) keys.insert("texture " + t.key);
  for (const DerivedPlan& d : next.derived) keys.insert("derived " + d.key);
  for (const MeshPlan& m : next.meshes) keys.insert("mesh " + m.key);
  std::uint64_t bytes = 0;
  for (const TextureRequest& t : previous.textures) bytes += keys.count("texture " + t.key) ? 0 : t.bytes;
  for (const DerivedPlan& d : previous.derived) bytes += keys.count("derived " + d.key) ? 0 : d.bytes;
  for (const MeshPlan& m : previous.meshes) bytes += keys.count("mesh " + m.key) ? 0 : m.bytes;
  return bytes;
}

// The most frames a dynamic baked AO map of the plan is amortized over (AoDesc::amortize_frames), else 1.
int ao_window(const FramePlan& plan) {
  int window = 1;
  for (const DerivedPlan& d : plan.derived)
    if (d.dynamic && (d.kind == DerivedKind::LayerAoMap || d.kind == DerivedKind::BlendAoMap))
      window = std::max(window, plan.materials[std::size_t(d.material)].desc.ao.amortize_frames);
  return window;
}

// Whether two plans make the same AO maps in the same places.
bool same_ao_maps(const FramePlan& a, const FramePlan& b) {
  if (a.derived.size() != b.derived.size()) return false;
  for (std::size_t i = 0; i < a.derived.size(); ++i) {
    const DerivedKind kind = b.derived[i].kind;
    if ((kind == DerivedKind::LayerAoMap || kind == DerivedKind::BlendAoMap) && a.derived[i].key != b.derived[i].key)
      return false;
  }
  return true;
}

std::uint64_t capacity_bytes(const PixelBuffer& plane) { return plane.capacity() * sizeof(float); }

int thread_count(const RenderOptions& options) {
  return options.threads > 0 ? options.threads : int(std::max(1u, std::thread::hardware_concurrency()));
}

}  // namespace

void validate_options(const RenderOptions& options) {
  if (options.threads < 0 || options.threads > limits::kMaxThreads)
    throw Error("--threads", "must be between 1 and " + std::to_string(limits::kMaxThreads) + " (or 0 for every core), got " +
                                 std::to_string(options.threads));
  if (options.tile_size < limits::kMinTileSize || options.tile_size > limits::kMaxTileSize ||
      options.tile_size % limits::kCoarseBlockSize != 0)
    throw Error("--tile", "must be a multiple of 8 between " + std::to_string(limits::kMinTileSize) + " and " +
                              std::to_string(limits::kMaxTileSize) + ", got " + std::to_string(options.tile_size));
  resolve_isa(options.isa);
}

struct Renderer::State {
  RenderOptions options;
  int threads;
  const Kernel* kernel;
  // Lets an arena larger than the core count run without oneTBB's warning. Only then: the limit is process-wide
  // (the smallest of the active ones wins), so a one-thread renderer must not set it for every other renderer.
  std::optional<tbb::global_control> parallelism;
  tbb::task_arena arena;
  std::optional<FramePlan> plan;
  std::optional<SceneDesc> scene;  // as given to set_scene (with heights handed over since), before any frame's time
  std::vector<Aov> aovs;           // of the last set_scene
  Assets assets;
  SpareTextures spares;  // the dynamic textures the last prepare replaced: the next one refills their buffers
  std::vector<std::unique_ptr<Program>> programs;
  Framebuffer fb;
  DrawScratch scratch;  // the per-triangle arrays, kept between draws of one scene
  Frame frame;
  double pending_plan_ms = 0, pending_prepare_ms = 0;
  std::uint64_t pending_built = 0, pending_reused = 0;
  std::vector<PrepareStep> pending_steps;  // the next frame's stats: what the last prepare built

  // The memory of the framebuffer's planes, those lent to the last frame included, and of the draw's arrays.
  std::uint64_t frame_bytes() const {
    std::uint64_t bytes = capacity_bytes(fb.color) + capacity_bytes(fb.depth) + capacity_bytes(frame.color) +
                          scratch.bytes();
    for (const PixelBuffer& plane : fb.aov) bytes += capacity_bytes(plane);
    for (const AovImage& a : frame.aovs) bytes += capacity_bytes(a.pixels);
    return bytes;
  }

  explicit State(const RenderOptions& o)
      : options(o), threads(thread_count(o)), kernel(&kernel_for(resolve_isa(o.isa))),
        arena(threads) {
    if (threads > tbb::info::default_concurrency())
      parallelism.emplace(tbb::global_control::max_allowed_parallelism, std::size_t(threads));
  }
};

Renderer::Renderer(const RenderOptions& options) {
  validate_options(options);
  state_ = std::make_unique<State>(options);
}

Renderer::~Renderer() = default;

std::vector<Aov> Renderer::options_aovs() const { return state_->options.aovs; }
Isa Renderer::isa() const { return state_->kernel->isa(); }
int Renderer::threads() const { return state_->threads; }

const FramePlan& Renderer::plan() const {
  if (!state_->plan) throw Error("renderer", "no scene set");
  return *state_->plan;
}

void Renderer::set_scene(const SceneDesc& scene, const std::vector<Aov>& aovs) {
  prepare_scene(scene, aovs);
  state_->scene = scene;
  state_->aovs = aovs;
}

void Renderer::set_frame(int frame) {
  State& s = *state_;
  if (!s.scene) throw Error("renderer", "no scene set");
  const AnimationDesc& a = s.scene->animation;
  if (frame < 0 || frame >= a.frames)
    throw Error(s.scene->file.string() + ": /animation/frames",
                "frame " + std::to_string(frame) + " is outside the animation's frames 0 to " + std::to_string(a.frames - 1));
  prepare_scene(scene_at_frame(*s.scene, frame), s.aovs);
}

void Renderer::update_height(const std::string& material, int layer, Image heights) {
  State& s = *state_;
  const auto fail = [](const std::string& what) { return Error("update_height", what); };
  if (!s.scene || !s.plan) throw fail("no scene set");
  // The scene as last prepared (its frame's time included), and the one whose frames set_frame takes from.
  SceneDesc now = s.plan->scene, base = *s.scene;
  MaterialDesc* m = nullptr;
  for (MaterialDesc& candidate : base.materials)
    if (candidate.name == material) m = &candidate;
  if (!m) throw fail("the scene has no material '" + material + "'");
  if (layer < 0 || std::size_t(layer) >= m->layers.size())
    throw fail("material '" + material + "' has layers 0 to " + std::to_string(m->layers.size() - 1) + ", not " +
               std::to_string(layer));
  if (heights.width < 1 || heights.height < 1 || heights.channels < 1) throw fail("the heights are an empty image");
  if (heights.width > limits::kMaxTextureSide || heights.height > limits::kMaxTextureSide)
    throw fail("the heights are " + std::to_string(heights.width) + "x" + std::to_string(heights.height) +
               ", more than " + std::to_string(limits::kMaxTextureSide) + " a side");
  for (int y = 0; y < heights.height; ++y)
    for (int x = 0; x < heights.width; ++x)
      if (!std::isfinite(heights.at(x, y, 0)))
        throw fail("the height at (" + std::to_string(x) + ", " + std::to_string(y) + ") is not finite");
  static std::atomic<std::uint64_t> versions{0};
  TextureDesc handed;
  handed.source = TextureSource::Pixels;
  handed.format = m->layers[std::size_t(layer)].height.format;
  handed.compression = m->layers[std::size_t(layer)].height.compression;
  handed.pixels = std::make_shared<const Image>(std::move(heights));
  handed.pixels_version = ++versions;
  m->layers[std::size_t(layer)].height = handed;
  for (MaterialDesc& candidate : now.materials)
    if (candidate.name == material) candidate.layers[std::size_t(layer)].height = handed;
  now.texture_cache = base.texture_cache;  // the plan turns the cache on for its AOV; set_scene does that again
  prepare_scene(now, s.aovs);
  s.scene = std::move(base);
}

void Renderer::prepare_scene(const SceneDesc& scene, const std::vector<Aov>& aovs) {
  State& s = *state_;
  auto start = Clock::now();
  FramePlan plan = plan_frame(scene, PlanOptions{aovs});
  const double plan_ms = ms_since(start);
  // Baked AO amortized over K frames on heights that change with time: frame N's map holds rows of frames N-K+1 .. N,
  // so unless the scene prepared last was frame N - 1 of this sequence (the previous scene moved to frame N plans
  // the same AO maps), those frames are prepared first, the first of them baking every row.
  double replay_ms = 0;
  if (const int window = ao_window(plan); window > 1 && scene.time_dependent()) {
    const int n = scene.frame;
    const bool continues = s.plan && s.plan->scene.frame == n - 1 &&
                           same_ao_maps(plan_frame(scene_at_frame(s.plan->scene, n), PlanOptions{aovs}), plan);
    if (!continues) {
      for (DerivedAsset& d : s.assets.derived) d.ao_history.reset();
      for (int f = std::max(0, n - window + 1); f < n; ++f) {
        start = Clock::now();
        prepare_plan(plan_frame(scene_at_frame(scene, f), PlanOptions{aovs}), 0.0);
        replay_ms += ms_since(start);
      }
    }
  }
  prepare_plan(std::move(plan), plan_ms);
  s.pending_prepare_ms += replay_ms;  // a frame's preparation includes the frames it replayed
}

void Renderer::prepare_plan(FramePlan plan, double plan_ms) {
  State& s = *state_;
  const SceneDesc& scene = plan.scene;
  s.pending_plan_ms = plan_ms;
  if (const TextureCacheDesc& cache = plan.scene.texture_cache; cache.enabled && s.options.tile_size % cache.region != 0)
    throw Error(scene.file.string() + ": /texture_cache/region",
                "the texture cache replays regions of " + std::to_string(cache.region) +
                    " pixels inside each tile: the tile size (--tile " + std::to_string(s.options.tile_size) +
                    ") must be a multiple of it");
  const std::uint64_t needed = plan.total_bytes(), limit = s.options.max_memory_bytes;
  if (limit > 0 && needed > limit)
    throw Error(scene.file.string(), "the job needs an estimated " + std::to_string((needed + (1 << 20) - 1) >> 20) +
                                         " MiB (see qdmr plan), more than the limit of " + std::to_string(limit >> 20) +
                                         " MiB");
  // While the new scene is prepared the previous frame's planes and the previous items it does not share are
  // still held. When that is over the limit (the new scene alone is not), the previous scene goes first: then a
  // failure to prepare leaves the renderer without a scene.
  if (limit > 0 && s.plan &&
      needed - plan.framebuffer_bytes + s.frame_bytes() + unshared_bytes(*s.plan, plan) > limit) {
    s.programs.clear();
    s.assets = Assets{};
    s.spares = SpareTextures{};
    s.plan.reset();
    s.fb = Framebuffer{};
    s.scratch = DrawScratch{};
    s.frame = Frame{};
  }
  const auto start = Clock::now();
  if (s.options.progress) s.options.progress("prepare", 0.0);
  std::function<void(double)> prepare_progress;
  if (s.options.progress) prepare_progress = [&report = s.options.progress](double f) { report("prepare", f); };
  s.arena.execute([&] {
    Assets assets = prepare(plan, *s.kernel, &s.assets, s.plan ? &*s.plan : nullptr, prepare_progress, &s.spares);
    // Programs point into the new assets: make them before the old assets go.
    std::vector<std::unique_ptr<Program>> programs = make_programs(plan, assets, *s.kernel, s.options.reference_memo.get());
    s.programs = std::move(programs);
    // The previous frame's dynamic textures that nothing holds any more become the next frame's spares (the
    // spares this prepare did not take go).
    SpareTextures released;
    for (std::size_t i = 0; s.plan && i < s.plan->textures.size() && i < s.assets.textures.size(); ++i)
      if (s.plan->textures[i].dynamic) released.textures.push_back(s.assets.textures[i]);
    s.assets = std::move(assets);
    std::erase_if(released.textures, [](const auto& t) { return t.use_count() != 1; });
    s.spares = std::move(released);
  });
  s.plan = std::move(plan);
  if (s.options.progress) s.options.progress("prepare", 1.0);
  s.pending_prepare_ms = ms_since(start);
  s.pending_built = s.assets.built.size();
  s.pending_steps = s.assets.steps;
  s.pending_reused = s.assets.reused.size();
}

const Frame& Renderer::draw() {
  State& s = *state_;
  const FramePlan& plan = this->plan();
  Frame& frame = s.frame;
  // The frame's buffers are the framebuffer's planes, lent to it between draws (no copy, no new pages).
  s.fb.color.swap(frame.color);
  for (AovImage& a : frame.aovs) s.fb.aov[std::size_t(a.aov)].swap(a.pixels);
  frame.aovs.clear();

  RenderStats& stats = frame.stats;
  stats = RenderStats{};
  stats.plan_ms = std::exchange(s.pending_plan_ms, 0.0);
  stats.prepare_ms = std::exchange(s.pending_prepare_ms, 0.0);
  stats.items_built = std::exchange(s.pending_built, 0);
  stats.items_reused = std::exchange(s.pending_reused, 0);
  stats.prepare_steps = std::exchange(s.pending_steps, {});
  stats.threads = s.threads;
  stats.texture_bytes = s.assets.texture_bytes();
  stats.textures = s.assets.texture_stats;
  stats.mesh_bytes = s.assets.mesh_bytes();
  DrawOptions options;
  options.tile_size = s.options.tile_size;
  if (s.options.progress) {
    const auto& report = s.options.progress;
    options.progress = [&report](double fraction) { report("raster", fraction); };
  }
  s.arena.execute([&] { qdmr::draw(plan, s.assets, *s.kernel, s.programs, s.fb, s.scratch, options, stats); });
  if (s.options.progress) s.options.progress("raster", 1.0);

  frame.width = s.fb.width;
  frame.height = s.fb.height;
  s.fb.color.swap(frame.color);
  for (Aov aov : plan.aovs) {
    frame.aovs.push_back({aov, aov_channels(aov), {}});
    frame.aovs.back().pixels.swap(s.fb.aov[std::size_t(aov)]);
  }
  stats.peak_rss_bytes = peak_rss_bytes();
  return frame;
}

const Frame& Renderer::frame() const { return state_->frame; }

Frame Renderer::take_frame() { return std::move(state_->frame); }

void Renderer::recycle_frame(Frame frame) { state_->frame = std::move(frame); }

Frame render_frame(const SceneDesc& scene, const RenderOptions& options) {
  Renderer renderer(options);
  renderer.set_scene(scene, options.aovs);
  renderer.draw();
  return renderer.take_frame();
}

}  // namespace qdmr
