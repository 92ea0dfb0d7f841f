// libFuzzer harness: a scene file read and validated by qdmr::load_scene (the path `qdmr render` takes), with
// --set overrides. Input: lines "--set POINTER=VALUE" first (optional), then the scene JSON.
#include <cstddef>
#include <cstdint>
#include <string>
#include <vector>

#include "fuzz_util.hpp"
#include "qdmr/core/error.hpp"
#include "qdmr/load/load.hpp"

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  std::string text(reinterpret_cast<const char*>(data), size);
  std::vector<std::string> sets;
  while (text.rfind("--set ", 0) == 0) {
    const std::size_t end = text.find('\n');
    sets.push_back(text.substr(6, end == std::string::npos ? std::string::npos : end - 6));
    text = end == std::string::npos ? "" : text.substr(end + 1);
  }
  const auto file = qdmr::fuzz::write("scene.json", text.data(), text.size());
  try {
    std::vector<qdmr::SceneOverride> overrides;
    for (const std::string& s : sets) overrides.push_back(qdmr::parse_override(s));
    static_cast<void>(qdmr::load_scene(file, overrides));
  } catch (const qdmr::Error&) {
  }
  return 0;
}
