// Study specs: expansion (product, zip, ranges, rules), refusal of bad specs with the field's pointer, shards,
// camera orbits and Pareto fronts on hand-made rows.
#include <gtest/gtest.h>

#include <cmath>

#include "qdmr/core/error.hpp"
#include "qdmr/study/spec.hpp"
#include "qdmr/study/study.hpp"
#include "support/test_support.hpp"

namespace qdmr {
namespace {

using test::TempDir;

std::string scene_path() { return (test::source_dir() / "scenes" / "plane.json").string(); }

StudySpec spec_of(const TempDir& dir, const std::string& rest) {
  test::write_file(dir / "s.json", R"({"scene": ")" + scene_path() + "\", " + rest + "}");
  return read_study_spec(dir / "s.json");
}

std::vector<std::string> labels(const StudySpec& spec, const std::vector<StudyConfig>& configs) {
  std::vector<std::string> out;
  for (const StudyConfig& c : configs) out.push_back(study_label(spec, c));
  return out;
}

TEST(StudySpec, ProductZipRangesAndRules) {
  TempDir dir;
  const StudySpec spec = spec_of(dir, R"("axes": [
      {"name": "technique", "path": "/materials/m/technique/name", "values": ["pom", "qdm"]},
      {"name": "cap", "path": "/materials/m/technique/max_iterations", "range": {"from": 4, "to": 64, "steps": 3, "scale": "log", "integer": true}},
      {"name": "a", "path": "/x", "values": [1, 2]},
      {"name": "b", "path": "/y", "values": ["p", "q"]}],
    "zip": [["a", "b"]],
    "rules": [{"axis": "cap", "only_when": {"technique": "qdm"}}, {"drop_when": {"technique": "pom", "a": 2}}])");
  const std::vector<StudyConfig> configs = expand_study(spec);
  const std::vector<std::string> expected{
      "technique=pom a=1 b=p",
      "technique=qdm cap=4 a=1 b=p", "technique=qdm cap=4 a=2 b=q",
      "technique=qdm cap=16 a=1 b=p", "technique=qdm cap=16 a=2 b=q",
      "technique=qdm cap=64 a=1 b=p", "technique=qdm cap=64 a=2 b=q"};
  EXPECT_EQ(labels(spec, configs), expected);
  for (std::size_t i = 0; i < configs.size(); ++i) EXPECT_EQ(configs[i].index, i);
  EXPECT_TRUE(configs[0].values[1].is_null());  // the cap does not apply to POM: an empty column
  EXPECT_EQ(spec.group_axis, "technique");
  EXPECT_EQ(spec.hash.substr(0, 5), "sha1:");
}

TEST(StudySpec, LinearRangesHitBothEnds) {
  TempDir dir;
  const StudySpec spec = spec_of(dir, R"("axes": [{"name": "d", "path": "/d", "range": {"from": 0, "to": 1, "steps": 5}}])");
  const auto configs = expand_study(spec);
  ASSERT_EQ(configs.size(), 5u);
  EXPECT_EQ(configs[0].values[0].get<double>(), 0.0);
  EXPECT_EQ(configs[2].values[0].get<double>(), 0.5);
  EXPECT_EQ(configs[4].values[0].get<double>(), 1.0);
}

TEST(StudySpec, BadSpecsAreRefusedBeforeAnythingRuns) {
  const std::pair<std::string, std::string> cases[] = {
      {R"("axes": [])", "s.json: /axes: a study needs at least one axis"},
      {R"("axes": [{"name": "t", "path": "/t", "values": []}])", "s.json: /axes/0/values: an axis needs at least one value"},
      {R"("axes": [{"name": "t", "path": "t", "values": [1]}])", "s.json: /axes/0/path: --set 't=0': the JSON pointer must start with '/'"},
      {R"("axes": [{"name": "t", "path": "/t", "values": [1], "step": 2}])", "s.json: /axes/0: unknown key 'step'"},
      {R"("axes": [{"name": "t", "path": "/t", "camera": "elevation", "values": [1]}])", "s.json: /axes/0: an axis has either \"path\""},
      {R"("axes": [{"name": "e", "camera": "elevation", "values": [0]}])", "s.json: /axes/0/values/0: an elevation is above 0"},
      {R"("axes": [{"name": "t", "path": "/t", "range": {"from": 0, "to": 1, "steps": 3, "scale": "log"}}])", "s.json: /axes/0/range: a log range needs from and to above 0"},
      {R"("axes": [{"name": "t", "path": "/t", "values": [1]}, {"name": "t", "path": "/u", "values": [1]}])", "s.json: /axes/1/name: axis name 't' is used twice"},
      {R"("axes": [{"name": "t", "path": "/t", "values": [1, 2]}], "zip": [["t", "u"]])", "s.json: /zip/0/1: no axis named 'u'"},
      {R"("axes": [{"name": "t", "path": "/t", "values": [1, 2]}, {"name": "u", "path": "/u", "values": [1]}], "zip": [["t", "u"]])", "s.json: /zip/0/1: zipped axes need the same number of values"},
      {R"("axes": [{"name": "t", "path": "/t", "values": [1]}], "rules": [{"drop_when": {"tt": 1}}])", "s.json: /rules/0/drop_when/tt: no axis named 'tt'; did you mean 't'?"},
      {R"("axes": [{"name": "t", "path": "/t", "values": [1]}], "baseline": {"t": 2})", "s.json: /baseline/t: not one of the axis's values"},
      {R"("axes": [{"name": "t", "path": "/t", "values": [1]}], "metrics": ["speed"])", "s.json: /metrics/0: unknown value 'speed'"},
      {R"("axes": [{"name": "t", "path": "/t", "values": [1]}], "keep": ["depth"])", "s.json: /keep/0: unknown value 'depth'"},
      {R"("axes": [{"name": "t", "path": "/t", "values": [1]}], "budget": {"per": ["t"]})", "s.json: /budget: missing key 'missed_fraction'"},
      {R"("axes": [{"name": "t", "path": "/t", "values": [1]}], "budget": {"missed_fraction": 2})", "s.json: /budget/missed_fraction: "},
      {R"("axes": [{"name": "t", "path": "/t", "values": [1]}], "budget": {"missed_fraction": 0.1, "per": ["u"]})", "s.json: /budget/per/0: no axis named 'u'"},
      {R"("axes": [{"name": "t", "path": "/t", "values": [1]}], "budget": {"missed_fraction": 0.1, "relative_to": {"t": 3}})", "s.json: /budget/relative_to/t: not one of the axis's values"},
      {R"("axes": [{"name": "t", "path": "/t", "values": [1]}], "metrics": ["time"], "budget": {"missed_fraction": 0.1})", "s.json: /budget: a budget compares time at a missed fraction"},
  };
  for (const auto& [rest, expected] : cases) {
    TempDir dir;
    std::string message;
    try {
      spec_of(dir, rest);
    } catch (const Error& e) {
      message = e.what();
      message = message.substr(message.find("s.json"));
    }
    EXPECT_EQ(message.substr(0, expected.size()), expected) << rest << "\n" << message;
  }
  TempDir dir;
  EXPECT_THROW(spec_of(dir, R"("axes": [{"name": "t", "path": "/t", "values": [1]}], "scene2": 1)"), Error);
}

TEST(StudySpec, TooManyConfigurationsNeedForceAndRulesMayNotDropAll) {
  TempDir dir;
  const StudySpec big = spec_of(dir, R"("max_configurations": 10, "axes": [
      {"name": "a", "path": "/a", "range": {"from": 1, "to": 4, "steps": 4}},
      {"name": "b", "path": "/b", "range": {"from": 1, "to": 3, "steps": 3}}])");
  try {
    expand_study(big);
    ADD_FAILURE() << "12 > 10 configurations accepted";
  } catch (const Error& e) {
    EXPECT_NE(std::string(e.what()).find("make 12 combinations, more than 10 (max_configurations); run with --force"), std::string::npos) << e.what();
  }
  EXPECT_EQ(expand_study(big, true).size(), 12u);
  const StudySpec none = spec_of(dir, R"("axes": [{"name": "a", "path": "/a", "values": [1]}], "rules": [{"drop_when": {"a": 1}}])");
  EXPECT_THROW(expand_study(none), Error);
}

TEST(StudySpec, ShardsCoverEveryConfigurationOnceAndBalanceCost) {
  TempDir dir;
  const StudySpec spec = spec_of(dir, R"("axes": [
      {"name": "technique", "path": "/t", "values": ["normal", "pom", "qdm"]},
      {"name": "cap", "path": "/m/max_iterations", "values": [8, 16, 32, 64, 128]}])");
  const auto configs = expand_study(spec);
  std::vector<int> seen(configs.size(), 0);
  for (int i = 1; i <= 3; ++i)
    for (std::size_t index : shard_configurations(spec, configs, {i, 3})) ++seen[index];
  for (int s : seen) EXPECT_EQ(s, 1);
  // Not by index: the costly QDM configurations (the last five) are spread over the shards.
  for (int i = 1; i <= 3; ++i) {
    int qdm = 0;
    for (std::size_t index : shard_configurations(spec, configs, {i, 3})) qdm += index >= 10 ? 1 : 0;
    EXPECT_GE(qdm, 1) << "shard " << i;
  }
}

TEST(StudySpec, CameraAxesOrbitTheTargetAtTheBaseDistance) {
  TempDir dir;
  const StudySpec spec = spec_of(dir, R"("axes": [{"name": "el", "camera": "elevation", "values": [90, 30]},
                                                   {"name": "az", "camera": "azimuth", "values": [0, 90]}])");
  const auto configs = expand_study(spec);
  // Base camera: at (0, -3, 4) looking at the origin, z up: distance 5, azimuth 0 along -y.
  const std::array<double, 9> base{0, -3, 4, 0, 0, 0, 0, 0, 1};
  const auto position = [&](std::size_t k) {
    for (const SceneOverride& o : study_overrides(spec, configs[k], base))
      if (o.pointer == "/camera/position") return nlohmann::json::parse(o.value).get<std::array<double, 3>>();
    return std::array<double, 3>{};
  };
  const auto p90 = position(0);  // straight above
  EXPECT_NEAR(p90[2], 5, 1e-9);
  EXPECT_NEAR(std::hypot(p90[0], p90[1]), 0, 1e-9);
  const auto p30 = position(2);  // 30 degrees up, towards -y
  EXPECT_NEAR(p30[2], 2.5, 1e-9);
  EXPECT_NEAR(p30[1], -5 * std::cos(30 * M_PI / 180), 1e-9);
  const auto p30_90 = position(3);  // a quarter turn around z
  EXPECT_NEAR(std::hypot(p30_90[0], p30_90[1]), 5 * std::cos(30 * M_PI / 180), 1e-9);
  EXPECT_NEAR(p30_90[1], 0, 1e-9);
}

TEST(StudyPareto, KeepsExactlyTheNonDominatedRows) {
  const auto row = [](double ms, double err, double missed) {
    StudyRow r;
    r["timing"]["draw_ms_median"] = ms;
    r["deterministic"]["error_p99"] = err;
    r["deterministic"]["missed_fraction"] = missed;
    return r;
  };
  const std::vector<StudyRow> rows{row(10, 1.0, 0.0),   // front: fastest of the accurate
                                   row(5, 4.0, 0.1),    // front: fastest
                                   row(12, 1.0, 0.0),   // dominated by the first
                                   row(20, 0.5, 0.0),   // front: most accurate
                                   row(6, 4.0, 0.2),    // dominated by the second
                                   row(10, 1.0, 0.0)};  // equal to the first: neither dominates
  EXPECT_EQ(pareto_front(rows), (std::vector<std::size_t>{0, 1, 3, 5}));
}

}  // namespace
}  // namespace qdmr
