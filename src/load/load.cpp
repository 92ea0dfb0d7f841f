#include "qdmr/load/load.hpp"

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
// to the scene's as "<object>/<mtl name>" (made unique with a suffix when two objects share a name).
void resolve_obj_meshes(SceneDesc& scene) {
  const std::string file = scene.file.string();
  for (std::size_t i = 0; i < scene.objects.size(); ++i) {
    ObjectDesc& object = scene.objects[i];
    if (object.mesh.kind != MeshKind::Obj) continue;
    const std::string where = file + ": /objects/" + std::to_string(i) + "/mesh";
    auto mesh = std::make_shared<MeshData>(build_mesh(object.mesh, where));
    if (object.material.empty()) {
      if (mesh->materials.empty())
        throw Error(file + ": /objects/" + std::to_string(i) + "/material", "required (the mesh has no MTL materials)");
      for (const MaterialDesc& mtl : mesh->materials) {
        MaterialDesc material = mtl;
        material.name = object.name + "/" + mtl.name;
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
  const std::string name = file.string();
  const std::string text = read_input_file(file, name, InputKind::Scene);
  nlohmann::json document;
  try {
    document = scene_detail::parse_json_bounded(text);
  } catch (const Error& e) {
    throw Error(name, e.what());
  } catch (const nlohmann::json::exception& e) {
    // what() is "[json.exception.parse_error.N] parse error at line L, column C: ..."; keep from "parse error".
    // Other exceptions of the parser (a number too large for a double: out_of_range.406) lose the bracket.
    const std::string what = e.what();
    const auto start = what.find("parse error");
    const auto bracket = what.find("] ");
    throw Error(name, start != std::string::npos ? what.substr(start)
                      : bracket != std::string::npos ? what.substr(bracket + 2) : what);
  }
  return load_scene_json(document, file, file.parent_path(), overrides);
}

SceneDesc load_scene_json(const nlohmann::json& document, const std::filesystem::path& name,
                          const std::filesystem::path& base_dir, const std::vector<SceneOverride>& overrides) {
  const scene_detail::Context context{name.string(), base_dir};
  SceneDesc scene;
  if (overrides.empty()) {
    scene = scene_detail::validate_scene(document, context);
  } else {
    nlohmann::json overridden = document;
    scene_detail::apply_overrides(overridden, overrides, context.file);
    scene = scene_detail::validate_scene(overridden, context);
  }
  resolve_obj_meshes(scene);
  return scene;
}

}  // namespace qdmr
