// Time in a scene: which textures change with it, and the scene at one frame.
#include <algorithm>

#include "qdmr/scene/scene.hpp"

namespace qdmr {

bool time_dependent(const ProceduralDesc& p) {
  if (p.scroll.x != 0.0f || p.scroll.y != 0.0f) return true;
  return p.pattern == ProceduralPattern::Waves &&
         std::any_of(p.waves.begin(), p.waves.end(), [](const WaveDesc& w) { return w.speed != 0.0f; });
}

bool time_dependent(const TextureDesc& t) { return t.source == TextureSource::Procedural && time_dependent(t.procedural); }

namespace {

// Calls f on every texture slot of the scene that may hold a procedural pattern.
template <class Scene, class F>
void for_each_texture(Scene& scene, F&& f) {
  for (auto& m : scene.materials) {
    for (auto& l : m.layers) {
      f(l.albedo);
      f(l.height);
    }
    f(m.blend.weights.height);
  }
  for (auto& o : scene.objects) f(o.mesh.height_map);
}

}  // namespace

bool SceneDesc::time_dependent() const {
  bool any = false;
  for_each_texture(*this, [&](const TextureDesc& t) { any = any || qdmr::time_dependent(t); });
  return any;
}

SceneDesc scene_at_time(const SceneDesc& scene, double seconds) {
  SceneDesc out = scene;
  for_each_texture(out, [&](TextureDesc& t) {
    if (qdmr::time_dependent(t)) t.procedural.time = seconds;
  });
  return out;
}

SceneDesc scene_at_frame(const SceneDesc& scene, int frame) {
  SceneDesc out = scene_at_time(scene, double(frame) / scene.animation.fps);
  out.frame = frame;
  return out;
}

}  // namespace qdmr
