#pragma once
#include <nlohmann/json_fwd.hpp>

#include "qdmr/scene/scene.hpp"
#include "scene/reader.hpp"

namespace qdmr::scene_detail {

// Checks the whole document and converts it; the first problem found throws qdmr::Error.
SceneDesc validate_scene(const nlohmann::json& document, const Context& context);

// One entry of an OBJ object's `mtl` block (value: /objects/N/mtl/NAME) applied over `material`, the mapping of
// that MTL material (mesh/obj.cpp); `bump` is its bump map file, empty if it has none.
void read_mtl_override(const Value& value, MaterialDesc& material, const std::filesystem::path& bump);

// One entry of a glTF object's `materials` block (value: /objects/N/materials/NAME) applied over `material`, the
// mapping of that glTF material (mesh/gltf.cpp): the keys of an MTL override but `bump`, and `height`, a TEX
// of the height forms (relative to the scene) that displacement techniques march.
void read_gltf_override(const Value& value, MaterialDesc& material);

}  // namespace qdmr::scene_detail
