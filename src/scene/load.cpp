#include "qdmr/scene/load.hpp"

#include <fstream>
#include <nlohmann/json.hpp>
#include <sstream>

#include "qdmr/core/error.hpp"
#include "scene/overrides.hpp"
#include "scene/reader.hpp"
#include "scene/validate.hpp"

namespace qdmr {

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
  if (overrides.empty()) return scene_detail::validate_scene(document, context);
  nlohmann::json overridden = document;
  scene_detail::apply_overrides(overridden, overrides, context.file);
  return scene_detail::validate_scene(overridden, context);
}

}  // namespace qdmr
