#pragma once
// Rendering a scene: the library's front door. A Renderer prepares a scene once and draws it many times;
// render_frame() is the one-shot form. The qdmr command is a thin layer over these calls.
//
//   qdmr::SceneDesc scene = qdmr::load_scene("scenes/plane.json");
//   qdmr::Renderer renderer;
//   renderer.set_scene(scene);
//   const qdmr::Frame& frame = renderer.draw();
//   qdmr::write_frame(frame, "plane.png");
#include <cstdint>
#include <functional>
#include <memory>
#include <string>
#include <vector>

#include "qdmr/core/aov.hpp"
#include "qdmr/core/isa.hpp"
#include "qdmr/core/pixel_buffer.hpp"
#include "qdmr/core/stats.hpp"
#include "qdmr/scene/scene.hpp"
#include "qdmr/texture/image.hpp"

namespace qdmr {

struct FramePlan;
class ReferenceMemo;

struct RenderOptions {
  int threads = 0;       // 0 = every core
  int tile_size = 64;    // pixels, a multiple of 8 in [8, 1024]
  Isa isa = Isa::Auto;   // draw kernel; Auto: $QDMR_ISA, else the best this CPU supports
  std::vector<Aov> aovs;
  // set_scene refuses a scene whose planned memory (FramePlan::total_bytes, what `qdmr plan` prints) exceeds
  // this, before anything is built. 0: no limit.
  std::uint64_t max_memory_bytes = 0;
  // Called with a stage name ("prepare", "raster") and the fraction done, from any worker thread,
  // never concurrently with itself. Optional.
  std::function<void(const char* stage, double fraction)> progress;
  // Remembers the exact reference's hits (error AOVs, exact_hits) across frames and renderers that share it
  // (qdmr/reference/reference_memo.hpp): the same bits, computed once. Optional.
  std::shared_ptr<ReferenceMemo> reference_memo;
};

// Throws qdmr::Error("--threads" / "--tile" / "--isa", ...) when options are out of range or the ISA is unusable.
void validate_options(const RenderOptions& options);

struct AovImage {
  Aov aov;
  int channels = 0;
  PixelBuffer pixels;  // width * height * channels
};

struct Frame {
  int width = 0, height = 0;
  PixelBuffer color;  // linear RGB, row 0 at the top
  std::vector<AovImage> aovs;
  RenderStats stats;
};

// Prepares scenes and draws frames, keeping what it built: the assets of the last scene (a new scene re-uses
// every item whose content key is unchanged, so a new camera, output size or lighting re-prepares nothing),
// the programs, the framebuffer and the AOV planes (no per-frame allocation once sizes settle), a task arena
// of `threads` workers and the draw kernel of the chosen ISA. Not thread-safe: one frame at a time.
class Renderer {
public:
  explicit Renderer(const RenderOptions& options = {});  // throws qdmr::Error on invalid options
  ~Renderer();
  Renderer(const Renderer&) = delete;
  Renderer& operator=(const Renderer&) = delete;

  // Plans the scene with these AOVs and prepares what the previous scene did not already have. Throws
  // qdmr::Error(scene file, ...) when the plan needs more than max_memory_bytes. The previous scene stays until
  // the new one is ready (a failure leaves it in place), unless its frame and the items the new scene does not
  // share, held meanwhile, would take the renderer over max_memory_bytes: then it is released first.
  void set_scene(const SceneDesc& scene, const std::vector<Aov>& aovs);
  void set_scene(const SceneDesc& scene) { set_scene(scene, options_aovs()); }
  const FramePlan& plan() const;  // of the current scene (throws if none)

  // Frame `frame` of the current scene's animation (qdmr/scene/scene.hpp, scene_at_frame): what set_scene gets, so
  // only the plan's dynamic items (made from time-dependent textures) are rebuilt. Throws qdmr::Error without a
  // scene or for a frame outside the animation.
  void set_frame(int frame);

  // New heights for layer `layer` of material `material`, drawn from the next draw on: level 0 of the layer's
  // height (one channel of `heights`, channel 0; row 0 at v = 0), through the storage the scene's height asks for
  // (format, compression), scale and offset. Everything made from it — its mip chain and max-quadtree, normals
  // from_height, height fields, AO maps — is rebuilt, nothing else. The heights stay the layer's for later
  // set_frame calls, until the next set_scene. Throws qdmr::Error("update_height", ...) without a scene, for an
  // unknown material or layer, an empty image, a value that is not finite, or a cone-stepping material (unless
  // /animation/rebake_cones).
  void update_height(const std::string& material, int layer, Image heights);

  // Draws one frame of the current scene. The frame's buffers belong to the renderer and are overwritten by the
  // next draw; its stats carry plan_ms and prepare_ms of the set_scene() before the first draw of a scene only.
  const Frame& draw();
  const Frame& frame() const;
  Frame take_frame();  // moves the last frame out (the next draw allocates again)
  // Hands back a frame that take_frame() returned and nobody needs any more: the next draw draws into its
  // buffers instead of allocating new ones (the last frame, if not taken, is dropped).
  void recycle_frame(Frame frame);

  Isa isa() const;
  int threads() const;

private:
  void prepare_scene(const SceneDesc& scene, const std::vector<Aov>& aovs);  // plan and prepare, the scene kept as is
  void prepare_plan(FramePlan plan, double plan_ms);  // prepare a planned scene
  std::vector<Aov> options_aovs() const;
  struct State;
  std::unique_ptr<State> state_;
};

// One frame, one shot: a Renderer for one draw.
Frame render_frame(const SceneDesc& scene, const RenderOptions& options);

}  // namespace qdmr
