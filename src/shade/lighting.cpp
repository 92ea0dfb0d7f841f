#include "shade/lighting.hpp"

#include <glm/geometric.hpp>

namespace qdmr {

LightRig LightRig::from_scene(const SceneDesc& scene) {
  LightRig rig;
  for (const auto& d : scene.lights.directional)
    rig.directional.push_back({glm::normalize(d.direction), d.color * d.intensity});
  rig.ambient = scene.lights.ambient.color * scene.lights.ambient.intensity;
  rig.camera_position = scene.camera.position;
  return rig;
}

}  // namespace qdmr
