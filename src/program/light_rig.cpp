#include "program/light_rig.hpp"

#include <glm/ext/matrix_clip_space.hpp>
#include <glm/ext/matrix_transform.hpp>
#include <glm/geometric.hpp>
#include <glm/trigonometric.hpp>

namespace qdmr {

LightRig LightRig::from_scene(const SceneDesc& scene) {
  LightRig rig;
  for (const auto& d : scene.lights.directional)
    rig.directional.push_back({glm::normalize(d.direction), d.color * d.intensity});
  rig.ambient = scene.lights.ambient.color * scene.lights.ambient.intensity;
  rig.camera_position = scene.camera.position;
  rig.view_projection = projection_matrix(scene.camera, scene.output) * view_matrix(scene.camera);
  return rig;
}

glm::mat4 LightRig::view_matrix(const CameraDesc& camera) { return glm::lookAt(camera.position, camera.target, camera.up); }

glm::mat4 LightRig::projection_matrix(const CameraDesc& camera, const OutputDesc& output) {
  return glm::perspective(glm::radians(camera.fov_y_deg), float(output.width) / float(output.height), camera.near,
                          camera.far);
}

}  // namespace qdmr
