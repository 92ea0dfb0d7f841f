#pragma once
// Shared by the scene tests: a minimal valid document and the message a load fails with.
#include <nlohmann/json.hpp>
#include <string>
#include <vector>

#include "qdmr/core/error.hpp"
#include "qdmr/load/load.hpp"

namespace qdmr::test {

inline nlohmann::json minimal_scene() {
  return nlohmann::json::parse(R"({
    "materials": {"rock": {"layers": [{}]}},
    "objects": [{"mesh": {"type": "plane"}, "material": "rock"}]
  })");
}

// The qdmr::Error message of loading `document` as "scene.json", or "no error".
inline std::string load_error(const nlohmann::json& document, const std::vector<SceneOverride>& overrides = {},
                              const std::filesystem::path& base_dir = ".") {
  try {
    load_scene_json(document, "scene.json", base_dir, overrides);
  } catch (const Error& e) {
    return e.what();
  }
  return "no error";
}

}  // namespace qdmr::test
