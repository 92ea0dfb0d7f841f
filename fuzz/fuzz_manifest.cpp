// libFuzzer harness: a check manifest read and validated by qdmr::read_manifest (the path `qdmr check MANIFEST`
// takes), then, for its first checks, what the check runner does before it renders (check/check.cpp,
// CheckJob::run_check): the check's scene loaded with its overrides and size. Input: the manifest JSON, written
// as manifest.json next to a valid scene.json (fuzz_util.hpp), which the seeds' checks name.
#include <cstddef>
#include <cstdint>
#include <string>
#include <vector>

#include "fuzz_util.hpp"
#include "qdmr/check/manifest.hpp"
#include "qdmr/core/error.hpp"
#include "qdmr/load/load.hpp"

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  static_cast<void>(qdmr::fuzz::base_scene());
  const auto file = qdmr::fuzz::write("manifest.json", reinterpret_cast<const char*>(data), size);
  try {
    const qdmr::Manifest manifest = qdmr::read_manifest(file);
    std::size_t loaded = 0;
    for (const qdmr::CheckSpec& check : manifest.checks) {
      for (const qdmr::CheckVariant& variant : check.variants) static_cast<void>(variant.label());
      if (loaded++ == 4) continue;  // the same code for every check: four are enough, and keep the harness fast
      std::vector<qdmr::SceneOverride> overrides = check.overrides;
      if (check.width > 0) overrides.push_back({"/output/width", std::to_string(check.width)});
      if (check.height > 0) overrides.push_back({"/output/height", std::to_string(check.height)});
      try {
        static_cast<void>(qdmr::load_scene(check.scene, overrides));
      } catch (const qdmr::Error&) {  // the runner reports it as this check's error and goes on
      }
    }
  } catch (const qdmr::Error&) {
  }
  return 0;
}
