#include "qdmr/load/load.hpp"

#include <algorithm>
#include <cctype>
#include <cmath>
#include <glm/common.hpp>
#include <glm/geometric.hpp>
#include <nlohmann/json.hpp>
#include <set>
#include <sstream>

#include <tbb/info.h>
#include <tbb/task_arena.h>

#include "file/input_file.hpp"
#include "qdmr/core/error.hpp"
#include "qdmr/mesh/mesh.hpp"
#include "qdmr/texture/image.hpp"
#include "scene/overrides.hpp"
#include "scene/reader.hpp"
#include "scene/validate.hpp"

namespace qdmr {
namespace {

// OBJ and glTF objects: the mesh is read now, and an object without its own material takes the file's materials,
// added to the scene's as "<object>/<name>" (made unique with a suffix when two objects share a name), each with
// the entry of the object's `mtl` (OBJ) or `materials` (glTF) block named after it applied (`document`: the scene
// after --set). `standalone`: the scene was made for a glTF file rendered on its own, whose messages name it.
void resolve_file_meshes(SceneDesc& scene, const nlohmann::json& document, const scene_detail::Context& context,
                         std::uint64_t max_memory_bytes, bool standalone = false) {
  const std::string file = scene.file.string();
  scene_detail::Context timed = context;  // a glTF material's height may be a file sequence
  timed.frames = scene.animation.frames;
  const scene_detail::Value objects(timed, document.at("objects"), "/objects");
  for (std::size_t i = 0; i < scene.objects.size(); ++i) {
    ObjectDesc& object = scene.objects[i];
    if (object.mesh.kind != MeshKind::Obj && object.mesh.kind != MeshKind::Gltf) continue;
    const bool gltf = object.mesh.kind == MeshKind::Gltf;
    const std::string where = standalone ? std::string() : file + ": /objects/" + std::to_string(i) + "/mesh";
    auto mesh = std::make_shared<MeshData>(build_mesh(object.mesh, where, max_memory_bytes));
    if (object.material.empty()) {
      if (mesh->materials.empty())
        throw Error(file + ": /objects/" + std::to_string(i) + "/material", "required (the mesh has no MTL materials)");
      std::vector<MaterialDesc> materials = mesh->materials;
      if (const auto overrides = objects.element(i).member(gltf ? "materials" : "mtl")) {
        std::vector<std::string> names;
        for (const MaterialDesc& m : materials) names.push_back(m.name);
        for (const auto& item : overrides->json().items()) {
          if (item.key() == "comment") continue;
          const scene_detail::Value entry = *overrides->member(item.key());
          const auto at = std::find(names.begin(), names.end(), item.key());
          if (at == names.end())
            entry.fail(std::string(gltf ? "unknown glTF material '" : "unknown MTL material '") +
                       scene_detail::shorten(item.key()) + "'" +
                       scene_detail::suggestion(item.key(), names, "the mesh's materials are"));
          const auto k = std::size_t(at - names.begin());
          if (gltf)
            scene_detail::read_gltf_override(entry, materials[k]);
          else
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

// Every frame of a height's file sequence has frame 0's size and sample depth: their headers are read now, so a
// sequence is refused before anything is drawn, not at the frame that differs.
void check_file_sequences(const SceneDesc& scene) {
  std::set<std::string> checked;
  const auto check = [&](const TextureDesc& t) {
    const FileSequence& sequence = t.sequence;
    if (t.source != TextureSource::File || sequence.pattern.empty() || !checked.insert(sequence.pattern).second) return;
    const ImageHeader first = read_image_header(sequence_file(sequence, 0), sequence.field);
    const auto describe = [](const ImageHeader& h) {
      return std::to_string(h.width) + "x" + std::to_string(h.height) + " " +
             (h.source_bits == 32 ? std::string("float") : std::to_string(h.source_bits) + "-bit");
    };
    for (int n = 1; n < scene.animation.frames; ++n) {
      const std::filesystem::path path = sequence_file(sequence, n);
      const ImageHeader h = read_image_header(path, sequence.field);
      if (h.width != first.width || h.height != first.height || h.source_bits != first.source_bits)
        throw Error(sequence.field, "frame " + std::to_string(n) + " of the animation, " + shown_path(path) + ", is " +
                                        describe(h) + ", frame 0's is " + describe(first) +
                                        " (every frame of a sequence has one size and sample depth)");
    }
  };
  for (const MaterialDesc& m : scene.materials) {
    for (const LayerDesc& l : m.layers) check(l.height);
    check(m.blend.weights.height);
  }
  for (const ObjectDesc& o : scene.objects) check(o.mesh.height_map);
}

// A camera that frames the mesh: the default camera's direction (from -Y, above), the bounding sphere filling the
// vertical field of view.
CameraDesc framing_camera(const MeshData& mesh) {
  glm::dvec3 lo(mesh.positions.front()), hi(mesh.positions.front());
  for (const glm::vec3& p : mesh.positions) {
    lo = glm::min(lo, glm::dvec3(p));
    hi = glm::max(hi, glm::dvec3(p));
  }
  const glm::dvec3 centre = 0.5 * (lo + hi);
  const double radius = std::max(0.5 * glm::length(hi - lo), 1e-3);
  CameraDesc camera;
  const double half_fov = 0.5 * double(camera.fov_y_deg) * 3.14159265358979323846 / 180.0;
  const double distance = 1.1 * radius / std::sin(half_fov);
  const glm::dvec3 from = glm::normalize(glm::dvec3(camera.position) - glm::dvec3(camera.target));
  camera.position = glm::vec3(centre + distance * from);
  camera.target = glm::vec3(centre);
  camera.near = float(std::max(distance - 2.0 * radius, distance * 1e-3));
  camera.far = float(distance + 2.0 * radius);
  return camera;
}

bool is_gltf_file(const std::filesystem::path& file) {
  std::string ext = file.extension().string();
  std::transform(ext.begin(), ext.end(), ext.begin(), [](unsigned char c) { return char(std::tolower(c)); });
  return ext == ".gltf" || ext == ".glb";
}

// A glTF asset rendered without a scene file: one object drawing its default scene, the default lights, and the
// asset's first camera or one framing it (unless --set gives a camera). Overrides reach /objects/0/materials.
SceneDesc load_gltf_asset(const std::filesystem::path& file, const std::vector<SceneOverride>& overrides,
                          std::uint64_t max_memory_bytes) {
  nlohmann::json document = {
      {"objects", {{{"name", file.stem().string()}, {"mesh", {{"type", "gltf"}, {"file", file.filename().string()}}}}}}};
  const scene_detail::Context context{file.string(), file.parent_path()};
  if (!overrides.empty()) scene_detail::apply_overrides(document, overrides, context.file);
  SceneDesc scene = scene_detail::validate_scene(document, context);
  resolve_file_meshes(scene, document, context, max_memory_bytes, true);
  check_file_sequences(scene);
  if (!document.contains("camera") && !scene.objects.empty() && scene.objects[0].obj_mesh) {
    const MeshData& mesh = *scene.objects[0].obj_mesh;
    scene.camera = mesh.cameras.empty() ? framing_camera(mesh) : mesh.cameras.front();
  }
  return scene;
}

// load() in an arena of `threads` threads (at most the cores: oneTBB would give no more), or in the caller's
// arena (threads 0, or as many as it has).
template <class Load>
SceneDesc on_threads(int threads, const Load& load) {
  if (threads <= 0) return load();
  const int bounded = std::min(threads, tbb::info::default_concurrency());
  if (bounded == tbb::this_task_arena::max_concurrency()) return load();
  return tbb::task_arena(bounded).execute(load);
}

}  // namespace

SceneDesc load_scene(const std::filesystem::path& file, const std::vector<SceneOverride>& overrides,
                     std::uint64_t max_memory_bytes, int threads) {
  return on_threads(threads, [&] {
    if (is_gltf_file(file)) return load_gltf_asset(file, overrides, max_memory_bytes);
    const nlohmann::json document = scene_detail::parse_json_file(file, InputKind::Scene);
    return load_scene_json(document, file, file.parent_path(), overrides, max_memory_bytes);
  });
}

SceneDesc load_scene_json(const nlohmann::json& document, const std::filesystem::path& name,
                          const std::filesystem::path& base_dir, const std::vector<SceneOverride>& overrides,
                          std::uint64_t max_memory_bytes, int threads) {
  return on_threads(threads, [&] {
    const scene_detail::Context context{name.string(), base_dir};
    nlohmann::json overridden;
    if (!overrides.empty()) {
      overridden = document;
      scene_detail::apply_overrides(overridden, overrides, context.file);
    }
    const nlohmann::json& used = overrides.empty() ? document : overridden;
    SceneDesc scene = scene_detail::validate_scene(used, context);
    resolve_file_meshes(scene, used, context, max_memory_bytes);
    check_file_sequences(scene);
    return scene;
  });
}

}  // namespace qdmr
