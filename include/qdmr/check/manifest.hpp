#pragma once
// A check manifest: the golden-image checks of a project, read from JSON (the format is docs/checks.md).
// Every path in it is relative to the manifest's folder.
#include <filesystem>
#include <map>
#include <optional>
#include <string>
#include <vector>

#include <nlohmann/json.hpp>

#include "qdmr/check/compare.hpp"
#include "qdmr/core/isa.hpp"
#include "qdmr/scene/overrides.hpp"

namespace qdmr {

enum class CheckMode {
  Exact,      // the canonical hash (check/canonical_hash.hpp) of every output, stored in the manifest
  Tolerance,  // every output against a golden image file, within a Tolerance
};

// A way of rendering the same check that must give the same bits: other thread counts, tile sizes, ISAs.
struct CheckVariant {
  std::optional<int> threads;
  std::optional<int> tile;
  std::optional<Isa> isa;
  std::string label() const;  // "threads=3 tile=16 isa=sse4.2", "" for the default
};

struct CheckSpec {
  std::string name;     // unique in the manifest; letters, digits, '.', '-', '_'
  std::string pointer;  // where it is in the manifest, e.g. "/checks/3", for messages
  std::filesystem::path scene;
  std::vector<SceneOverride> overrides;
  int width = 0, height = 0;  // 0: the scene's
  std::vector<std::string> outputs;  // "color" and AOV names, in order
  CheckMode mode = CheckMode::Exact;
  std::map<std::string, std::string> hashes;                 // exact: output -> "sha1:..." (missing: no golden yet)
  std::map<std::string, std::filesystem::path> goldens;      // tolerance: output -> image file (may not exist yet)
  Tolerance tolerance;
  // Each variant must render the same bits as the first; the first is compared with the golden.
  std::vector<CheckVariant> variants;
  std::vector<std::filesystem::path> skip_if_missing;  // the check is skipped when one of these does not exist
};

struct Manifest {
  std::filesystem::path file;
  int bits_version = 0;  // the bits version its goldens were made with
  std::vector<CheckSpec> checks;
  nlohmann::json document;  // as read
  std::string text;         // the file's text, for --update to rewrite hashes keeping the key order; empty for a
                            // manifest built in memory, which --update does not write
};

// Reads and validates a manifest. Throws qdmr::Error("FILE: /pointer", what) for anything wrong with it; the
// scenes and goldens it names are read only when the checks run.
Manifest read_manifest(const std::filesystem::path& file);

// The names `outputs` may hold: "color" and every AOV.
std::vector<std::string> check_output_names();

}  // namespace qdmr
