#pragma once
#include <nlohmann/json_fwd.hpp>

#include "qdmr/scene/scene.hpp"
#include "scene/reader.hpp"

namespace qdmr::scene_detail {

// Checks the whole document and converts it; the first problem found throws qdmr::Error.
SceneDesc validate_scene(const nlohmann::json& document, const Context& context);

}  // namespace qdmr::scene_detail
