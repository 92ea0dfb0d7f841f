// Time in a scene: which textures change with it, and the scene at one frame.
#include <algorithm>
#include <sstream>
#include <string>
#include <tuple>

#include <glm/vec3.hpp>
#include <glm/ext/vector_double3.hpp>

#include "core/frame_pattern.hpp"
#include "qdmr/scene/scene.hpp"

namespace qdmr {

bool time_dependent(const ProceduralDesc& p) {
  if (p.scroll.x != 0.0f || p.scroll.y != 0.0f) return true;
  return p.pattern == ProceduralPattern::Waves &&
         std::any_of(p.waves.begin(), p.waves.end(), [](const WaveDesc& w) { return w.speed != 0.0f; });
}

std::string procedural_key(const ProceduralDesc& p) {
  std::ostringstream k;
  k << std::hexfloat << int(p.pattern) << ":" << p.size << ":" << p.seed << ":" << p.cells << ":" << p.octaves << ":"
    << p.gain << ":" << p.mortar;
  for (const WaveDesc& w : p.waves)
    k << ":wave" << w.amplitude << "," << w.speed << "," << w.sharpness << "," << w.cycles_u << "," << w.cycles_v;
  if (time_dependent(p)) k << ":scroll" << p.scroll.x << "," << p.scroll.y << ":t" << p.time;
  return k.str();
}

bool time_dependent(const TextureDesc& t) {
  if (t.source == TextureSource::File) return !t.sequence.pattern.empty();
  return t.source == TextureSource::Procedural && time_dependent(t.procedural);
}

std::filesystem::path sequence_file(const FileSequence& sequence, int frame) {
  return frame_name(sequence.pattern, int(sequence.first + static_cast<long long>(frame) * sequence.step));
}

CameraDesc camera_at_frame(const CameraDesc& camera, int frame) {
  const std::vector<CameraKeyframe>& keys = camera.keyframes;
  if (keys.empty()) return camera;
  // The keyframe at or before the frame, held before the first and after the last.
  const auto after = std::upper_bound(keys.begin(), keys.end(), frame,
                                      [](int f, const CameraKeyframe& k) { return f < k.frame; });
  const std::size_t k = after == keys.begin() ? 0 : std::size_t(after - keys.begin()) - 1;
  CameraDesc out = camera;
  const auto set = [&out](glm::dvec3 position, glm::dvec3 target, double fov) {
    out.position = glm::vec3(position);
    out.target = glm::vec3(target);
    out.fov_y_deg = float(fov);
  };
  const auto value = [&](std::size_t i) {
    return std::make_tuple(glm::dvec3(keys[i].position), glm::dvec3(keys[i].target), double(keys[i].fov_y_deg));
  };
  if (frame <= keys.front().frame || k + 1 == keys.size()) {
    const auto [p, t, f] = value(frame <= keys.front().frame ? 0 : k);
    set(p, t, f);
    return out;
  }
  const double f0 = keys[k].frame, f1 = keys[k + 1].frame, h = f1 - f0;
  const double s = (double(frame) - f0) / h;
  const auto [p0, t0, v0] = value(k);
  const auto [p1, t1, v1] = value(k + 1);
  if (camera.interpolation == CameraInterpolation::Linear) {
    set(p0 + s * (p1 - p0), t0 + s * (t1 - t0), v0 + s * (v1 - v0));
    return out;
  }
  // Cubic Hermite: tangents per frame from the neighbouring keyframes (zero at the ends), scaled by the span.
  const auto tangent = [&](std::size_t i) {
    if (i == 0 || i + 1 == keys.size()) return std::make_tuple(glm::dvec3(0.0), glm::dvec3(0.0), 0.0);
    const auto [pa, ta, va] = value(i - 1);
    const auto [pb, tb, vb] = value(i + 1);
    const double span = double(keys[i + 1].frame) - double(keys[i - 1].frame);
    return std::make_tuple((pb - pa) / span, (tb - ta) / span, (vb - va) / span);
  };
  const auto [mp0, mt0, mv0] = tangent(k);
  const auto [mp1, mt1, mv1] = tangent(k + 1);
  const double s2 = s * s, s3 = s2 * s;
  const double a0 = 2.0 * s3 - 3.0 * s2 + 1.0, b0 = (s3 - 2.0 * s2 + s) * h;
  const double a1 = 3.0 * s2 - 2.0 * s3, b1 = (s3 - s2) * h;
  set(a0 * p0 + b0 * mp0 + a1 * p1 + b1 * mp1, a0 * t0 + b0 * mt0 + a1 * t1 + b1 * mt1,
      a0 * v0 + b0 * mv0 + a1 * v1 + b1 * mv1);
  return out;
}

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
  for_each_texture(out, [&](TextureDesc& t) {
    if (t.source == TextureSource::File && !t.sequence.pattern.empty()) t.file = sequence_file(t.sequence, frame);
  });
  out.camera = camera_at_frame(scene.camera, frame);
  return out;
}

}  // namespace qdmr
