#pragma once
// The load stage: a scene file in, a validated SceneDesc out, with --set overrides applied first. Everything the
// scene refers to is resolved here: paths made absolute, and OBJ and glTF meshes read with their materials, which
// join the scene's materials (named "<object>/<material>"), so the plan sees every material of the frame.
#include <cstdint>
#include <filesystem>
#include <vector>

#include <nlohmann/json_fwd.hpp>

#include "qdmr/scene/overrides.hpp"
#include "qdmr/scene/scene.hpp"

namespace qdmr {

// Reads, overrides, validates, resolves OBJ and glTF meshes. A .gltf or .glb file is rendered on its own: one
// object drawing the asset's default scene, the default lights, its first camera or one framing it. Throws qdmr::Error("FILE: /pointer", "what is wrong [; did
// you mean 'x'?]").
// max_memory_bytes (0: none): a glTF mesh whose drawn copies would take more (counted before they are read, each
// node drawing a mesh with its own copy) is refused, with a message ending "more than the limit of N MiB".
// threads (0: the caller's oneTBB arena, every core outside one): the load's parallel parts (a glTF mesh's reads,
// MikkTSpace's tangents) run on at most that many threads (and at most the cores), as a Renderer of that many
// threads draws; the same SceneDesc, every bit, for any count.
SceneDesc load_scene(const std::filesystem::path& file, const std::vector<SceneOverride>& overrides = {},
                     std::uint64_t max_memory_bytes = 0, int threads = 0);

// The same from an in-memory document; relative paths resolve against base_dir, messages name `name`.
SceneDesc load_scene_json(const nlohmann::json& document, const std::filesystem::path& name,
                          const std::filesystem::path& base_dir, const std::vector<SceneOverride>& overrides = {},
                          std::uint64_t max_memory_bytes = 0, int threads = 0);

}  // namespace qdmr
