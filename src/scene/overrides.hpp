#pragma once
#include <nlohmann/json_fwd.hpp>
#include <string>
#include <vector>

#include "qdmr/scene/overrides.hpp"

namespace qdmr::scene_detail {

// Applies --set overrides in order; errors name `file` and the override's pointer.
void apply_overrides(nlohmann::json& document, const std::vector<SceneOverride>& overrides, const std::string& file);

}  // namespace qdmr::scene_detail
