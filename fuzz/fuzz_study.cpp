// libFuzzer harness: a study spec through what `qdmr study SPEC` does before its first render: read_study_spec
// (every check of the spec), expand_study (the configurations, max_configurations), shard_configurations,
// then (study/study.cpp) the base scene read once, the base camera from it with the spec's overrides, and for
// the first configurations their overrides (study_overrides: --set axes, camera orbits) and those of their
// image-difference baseline applied to the base scene in memory. Input: the spec JSON, written as spec.json next
// to a valid scene.json (fuzz_util.hpp), which the seeds name.
#include <array>
#include <cstddef>
#include <cstdint>
#include <string>
#include <vector>

#include "fuzz_util.hpp"
#include "qdmr/core/error.hpp"
#include "qdmr/load/load.hpp"
#include "qdmr/study/spec.hpp"
#include "qdmr/study/study.hpp"
#include "scene/reader.hpp"

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  static_cast<void>(qdmr::fuzz::base_scene());
  const auto file = qdmr::fuzz::write("spec.json", reinterpret_cast<const char*>(data), size);
  try {
    const qdmr::StudySpec spec = qdmr::read_study_spec(file);
    const std::vector<qdmr::StudyConfig> configs = qdmr::expand_study(spec);
    static_cast<void>(qdmr::shard_configurations(spec, configs, {1, 2}));
    // As SceneSource and base_camera in study/study.cpp.
    const nlohmann::json document = qdmr::scene_detail::parse_json_file(spec.scene, qdmr::InputKind::Scene);
    const auto load = [&](const std::vector<qdmr::SceneOverride>& overrides) {
      return qdmr::load_scene_json(document, spec.scene, spec.scene.parent_path(), overrides);
    };
    const qdmr::CameraDesc c = load(spec.overrides).camera;
    const std::array<double, 9> camera{c.position.x, c.position.y, c.position.z, c.target.x, c.target.y,
                                       c.target.z,   c.up.x,       c.up.y,       c.up.z};
    for (std::size_t i = 0; i < configs.size() && i < 4; ++i) {
      const qdmr::StudyConfig& config = configs[configs.size() - 1 - i];  // the last ones: every axis moved
      static_cast<void>(qdmr::study_label(spec, config));
      static_cast<void>(load(qdmr::study_overrides(spec, config, camera)));
      if (spec.baseline.empty()) continue;
      qdmr::StudyConfig base = config;  // as Measurer::baseline_for
      for (std::size_t a = 0; a < spec.axes.size(); ++a)
        if (auto it = spec.baseline.find(spec.axes[a].name); it != spec.baseline.end()) base.values[a] = it->second;
      static_cast<void>(load(qdmr::study_overrides(spec, base, camera)));
    }
  } catch (const qdmr::Error&) {
  }
  return 0;
}
