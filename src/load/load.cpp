#include "qdmr/load/load.hpp"

#include <fstream>
#include <nlohmann/json.hpp>
#include <sstream>

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
  std::error_code ec;
  const auto status = std::filesystem::status(file, ec);
  if (!std::filesystem::exists(status)) throw Error(name, "file not found");
  if (std::filesystem::is_directory(status)) throw Error(name, "is a directory, not a scene file");
  std::ifstream in(file, std::ios::binary);
  std::ostringstream text;
  if (!(in && text << in.rdbuf())) throw Error(name, "cannot read the file");

  nlohmann::json document;
  try {
    document = nlohmann::json::parse(text.str());
  } catch (const nlohmann::json::parse_error& e) {
    // what() is "[json.exception.parse_error.N] parse error at line L, column C: ..."; keep from "parse error".
    const std::string what = e.what();
    const auto start = what.find("parse error");
    throw Error(name, start == std::string::npos ? what : what.substr(start));
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
