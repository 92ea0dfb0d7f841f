#pragma once
// Light sources in the form the shading programs use: world-space unit directions, premultiplied colours.
#include <vector>

#include <glm/vec3.hpp>

#include "qdmr/scene/scene.hpp"

namespace qdmr {

struct LightRig {
  struct Directional {
    glm::vec3 direction;  // unit, towards the light
    glm::vec3 radiance;   // colour * intensity
  };
  std::vector<Directional> directional;
  glm::vec3 ambient{0.0f};
  glm::vec3 camera_position{0.0f};

  static LightRig from_scene(const SceneDesc& scene);
};

}  // namespace qdmr
