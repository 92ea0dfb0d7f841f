#include "qdmr/load/load.hpp"

#include <algorithm>
#include <nlohmann/json.hpp>
#include <sstream>

#include "io/input_file.hpp"
#include "qdmr/core/error.hpp"
#include "qdmr/mesh/mesh.hpp"
#include "scene/overrides.hpp"
#include "scene/reader.hpp"
#include "scene/validate.hpp"

namespace qdmr {
namespace {

// OBJ objects: the mesh is read now, and an object without its own material takes the MTL materials, added
// to the scene's as "<object>/<mtl name>" (made unique with a suffix when two objects share a name), each with
// the entry of the object's `mtl` block named after it applied (`document`: the scene after --set).
void resolve_obj_meshes(SceneDesc& scene, const nlohmann::json& document, const scene_detail::Context& context) {
  const std::string file = scene.file.string();
  const scene_detail::Value objects(context, document.at("objects"), "/objects");
  for (std::size_t i = 0; i < scene.objects.size(); ++i) {
    ObjectDesc& object = scene.objects[i];
    if (object.mesh.kind != MeshKind::Obj) continue;
    const std::string where = file + ": /objects/" + std::to_string(i) + "/mesh";
    auto mesh = std::make_shared<MeshData>(build_mesh(object.mesh, where));
    if (object.material.empty()) {
      if (mesh->materials.empty())
        throw Error(file + ": /objects/" + std::to_string(i) + "/material", "required (the mesh has no MTL materials)");
      std::vector<MaterialDesc> materials = mesh->materials;
      if (const auto overrides = objects.element(i).member("mtl")) {
        std::vector<std::string> names;
        for (const MaterialDesc& m : materials) names.push_back(m.name);
        for (const auto& item : overrides->json().items()) {
          if (item.key() == "comment") continue;
          const scene_detail::Value entry = *overrides->member(item.key());
          const auto at = std::find(names.begin(), names.end(), item.key());
          if (at == names.end())
            entry.fail("unknown MTL material '" + scene_detail::shorten(item.key()) + "'" +
                       scene_detail::suggestion(item.key(), names, "the mesh's materials are"));
          const auto k = std::size_t(at - names.begin());
          scene_detail::read_mtl_override(entry, materials[k], mesh->bump_maps[k]);
        }
      }
      for (MaterialDesc& material : materials) {
        material.name = object.name + "/" + material.name;
        while (scene.find_material(material.name)) material.name += "'";
        object.mtl_materials.push_back(material.name);
        scene.materials.push_back(std::move(material));
      }
    }
    object.obj_mesh = std::move(mesh);
  }
}

}  // namespace

SceneDesc load_scene(const std::filesystem::path& file, const std::vector<SceneOverride>& overrides) {
  const nlohmann::json document = scene_detail::parse_json_file(file, InputKind::Scene);
  return load_scene_json(document, file, file.parent_path(), overrides);
}

SceneDesc load_scene_json(const nlohmann::json& document, const std::filesystem::path& name,
                          const std::filesystem::path& base_dir, const std::vector<SceneOverride>& overrides) {
  const scene_detail::Context context{name.string(), base_dir};
  if (overrides.empty()) {
    SceneDesc scene = scene_detail::validate_scene(document, context);
    resolve_obj_meshes(scene, document, context);
    return scene;
  }
  nlohmann::json overridden = document;
  scene_detail::apply_overrides(overridden, overrides, context.file);
  SceneDesc scene = scene_detail::validate_scene(overridden, context);
  resolve_obj_meshes(scene, overridden, context);
  return scene;
}

}  // namespace qdmr
