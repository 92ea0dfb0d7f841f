#include "qdmr/scene/load.hpp"

#include <fstream>
#include <nlohmann/json.hpp>
#include <sstream>

#include "io/input_file.hpp"
#include "qdmr/core/error.hpp"
#include "scene/overrides.hpp"
#include "scene/reader.hpp"
#include "scene/validate.hpp"

namespace qdmr {

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
  if (overrides.empty()) return scene_detail::validate_scene(document, context);
  nlohmann::json overridden = document;
  scene_detail::apply_overrides(overridden, overrides, context.file);
  return scene_detail::validate_scene(overridden, context);
}

}  // namespace qdmr
