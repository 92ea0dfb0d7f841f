// libFuzzer harness: the --set parser and its application to a scene (qdmr::parse_override, then
// load_scene_json). Input: one override per line, applied in order to a small valid scene.
#include <cstddef>
#include <cstdint>
#include <string>
#include <vector>

#include <nlohmann/json.hpp>

#include "fuzz_util.hpp"
#include "qdmr/core/error.hpp"
#include "qdmr/load/load.hpp"

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  static const nlohmann::json scene = nlohmann::json::parse(R"({
    "output": {"width": 64, "height": 48},
    "camera": {"position": [0, -2, 1.5], "target": [0, 0, 0]},
    "lights": [{"type": "directional", "direction": [0, -1, 1]}],
    "materials": {"m": {"layers": [{"height": {"procedural": "noise", "size": 64}, "normal": "from_height"}],
                        "technique": {"name": "qdm"}}},
    "objects": [{"mesh": {"type": "plane"}, "material": "m"}, {"mesh": {"type": "sphere"}}]
  })");
  const std::string text(reinterpret_cast<const char*>(data), size);
  try {
    std::vector<qdmr::SceneOverride> overrides;
    for (std::size_t start = 0; start <= text.size();) {
      std::size_t end = text.find('\n', start);
      if (end == std::string::npos) end = text.size();
      overrides.push_back(qdmr::parse_override(std::string_view(text).substr(start, end - start)));
      start = end + 1;
    }
    static_cast<void>(qdmr::load_scene_json(scene, "fuzz.json", qdmr::fuzz::scratch(), overrides));
  } catch (const qdmr::Error&) {
  }
  return 0;
}
