#pragma once
// A study spec: a base scene and the axes to sweep (docs/studies.md has every field). Reading it checks
// everything before anything renders; expanding it gives the configurations, in a fixed order.
#include <array>
#include <cstddef>
#include <filesystem>
#include <map>
#include <string>
#include <vector>

#include <nlohmann/json.hpp>

#include "qdmr/scene/overrides.hpp"

namespace qdmr {

struct StudyAxis {
  enum class Kind { Set, Elevation, Azimuth };
  std::string name;     // the column name
  Kind kind = Kind::Set;
  std::string pointer;  // Kind::Set: the --set JSON pointer
  std::vector<nlohmann::json> values;
};

// Combination rules. OnlyWhen: `axis` means something only when every condition holds; elsewhere only its first
// value is rendered and its column is empty (e.g. an iteration cap only for QDM). DropWhen: configurations
// matching every condition are dropped.
struct StudyRule {
  enum class Kind { OnlyWhen, DropWhen };
  Kind kind = Kind::DropWhen;
  std::string axis;                                             // OnlyWhen
  std::map<std::string, std::vector<nlohmann::json>> when;      // axis name -> values that match
};

// cache: the emulated texture cache's columns (also when the scene turns texture_cache on); never timed.
enum class StudyMetric { Time, Iterations, Error, ImageDiff, Cache };

struct StudySpec {
  std::filesystem::path file;
  std::string hash;  // "sha1:..." of the spec's canonical JSON: results of another spec are never mixed in
  nlohmann::json document;
  std::filesystem::path scene;
  std::vector<SceneOverride> overrides;  // applied before every configuration's
  int width = 480, height = 270;
  int frames = 3, warmup = 1;             // timed frames per configuration, after untimed ones
  std::vector<StudyAxis> axes;
  std::vector<std::vector<std::string>> zips;  // axes that advance together (equal lengths)
  std::vector<StudyRule> rules;
  std::vector<StudyMetric> metrics;
  // The image-difference baseline of a row: the row's own values with these axis values put in, e.g.
  // {"technique": "relief"} compares every row with relief at the same angle and depth. Empty: no image_diff.
  std::map<std::string, nlohmann::json> baseline;
  double diff_threshold = 1.0 / 255.0;            // a pixel counts as different above this (any channel)
  // Files per configuration: "image", "error_texels", "iterations", "reference" (the image with exact_hits).
  std::vector<std::string> keep;
  std::string group_axis;                          // Pareto fronts per value of this axis ("technique" if present)
  std::size_t max_configurations = 5000;           // a larger product needs --force

  bool wants(StudyMetric m) const;
};

struct StudyConfig {
  std::size_t index = 0;                 // in the expansion order; rows are reported in it
  std::vector<nlohmann::json> values;    // per axis; null where an OnlyWhen rule makes the axis not apply
};

// "technique=qdm cap=32 angle=10" (axes that do not apply left out).
std::string study_label(const StudySpec& spec, const StudyConfig& config);

// Throws qdmr::Error("SPEC: /pointer", what) for any mistake, before anything renders.
StudySpec read_study_spec(const std::filesystem::path& file);
// The same from an in-memory document: relative paths resolve against base_dir, messages name `name`.
StudySpec read_study_spec_json(const nlohmann::json& document, const std::filesystem::path& name,
                               const std::filesystem::path& base_dir);

// Every configuration: the product of the axes (zipped axes as one), with the rules applied. Throws
// qdmr::Error when there are none, or more than max_configurations without `force`.
std::vector<StudyConfig> expand_study(const StudySpec& spec, bool force = false);

// The scene overrides of one configuration (the spec's, then the axes'), camera axes resolved against the base
// camera (position, target, up): the camera orbits the target at the base distance.
std::vector<SceneOverride> study_overrides(const StudySpec& spec, const StudyConfig& config,
                                           const std::array<double, 9>& base_camera);

}  // namespace qdmr
