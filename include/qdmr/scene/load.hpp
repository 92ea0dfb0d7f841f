#pragma once
// Loading a scene file: JSON in, validated SceneDesc out, with --set overrides applied first.
#include <filesystem>
#include <string>
#include <string_view>
#include <vector>

#include <nlohmann/json_fwd.hpp>

#include "qdmr/scene/scene.hpp"

namespace qdmr {

// One --set /json/pointer=value override; value is JSON (a bare word that is not JSON is taken as a string).
struct SceneOverride {
  std::string pointer;
  std::string value;
};

// Parses "POINTER=VALUE"; throws qdmr::Error naming the option on malformed text.
SceneOverride parse_override(std::string_view text);

// Reads, overrides, validates. Throws qdmr::Error("FILE: /pointer", "what is wrong [; did you mean 'x'?]").
SceneDesc load_scene(const std::filesystem::path& file, const std::vector<SceneOverride>& overrides = {});

// The same from an in-memory document; relative paths resolve against base_dir, messages name `name`.
SceneDesc load_scene_json(const nlohmann::json& document, const std::filesystem::path& name,
                          const std::filesystem::path& base_dir, const std::vector<SceneOverride>& overrides = {});

}  // namespace qdmr
