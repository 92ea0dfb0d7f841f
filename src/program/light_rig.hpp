#pragma once
// Light sources and camera in the form the shading programs use: world-space unit directions, premultiplied
// colours, the camera position and its view-projection matrix. Made from the scene by make_programs
// (src/draw/draw.cpp): a program never sees the scene's types.
#include <vector>

#include <glm/mat4x4.hpp>
#include <glm/vec3.hpp>

namespace qdmr {

struct LightRig {
  struct Directional {
    glm::vec3 direction;  // unit, towards the light
    glm::vec3 radiance;   // colour * intensity
  };
  std::vector<Directional> directional;
  glm::vec3 ambient{0.0f};
  glm::vec3 camera_position{0.0f};
  glm::mat4 view_projection{1.0f};  // world to clip space, for programs that write displaced depth
};

}  // namespace qdmr
