// Reading check manifests: what a valid one gives, and one clear error naming the field for each kind of mistake.
#include <gtest/gtest.h>

#include "qdmr/check/manifest.hpp"
#include "qdmr/core/error.hpp"
#include "support/test_support.hpp"

namespace qdmr {
namespace {

using test::TempDir;

// Writes `text` as m.json beside an (empty) scene file and reads it; returns the error message or "".
std::string error_of(const std::string& text) {
  TempDir dir;
  test::write_file(dir / "m.json", text);
  try {
    read_manifest(dir / "m.json");
  } catch (const Error& e) {
    const std::string message = e.what();
    return message.substr(message.find("m.json"));
  }
  return "";
}

TEST(Manifest, DefaultsApplyAndPathsResolveAgainstTheManifestFolder) {
  TempDir dir;
  test::write_file(dir / "m.json", R"({
    "bits_version": 1,
    "defaults": {"width": 64, "height": 32, "outputs": ["color", "depth"], "tolerance": {"max_abs": 0.5}},
    "golden_dir": "g",
    "checks": [
      {"name": "a", "scene": "scenes/a.json", "set": {"/camera/fov_deg": 30}},
      {"name": "b", "scene": "b.json", "mode": "tolerance", "width": 8, "outputs": ["color"],
       "set": ["/x=1", "/y=two"], "golden": {"color": "other/b.png"}, "tolerance": {"radius": 1}},
      {"name": "c", "scene": "c.json", "mode": "tolerance", "variants": [{"threads": 1}, {"tile": 16}]}
    ]})");
  const Manifest m = read_manifest(dir / "m.json");
  ASSERT_EQ(m.checks.size(), 3u);
  const CheckSpec& a = m.checks[0];
  EXPECT_EQ(a.scene, dir.path() / "scenes" / "a.json");
  EXPECT_EQ(a.width, 64);
  EXPECT_EQ(a.height, 32);
  EXPECT_EQ(a.mode, CheckMode::Exact);
  EXPECT_EQ(a.outputs, (std::vector<std::string>{"color", "depth"}));
  ASSERT_EQ(a.overrides.size(), 1u);
  EXPECT_EQ(a.overrides[0].pointer, "/camera/fov_deg");
  EXPECT_EQ(a.overrides[0].value, "30");
  ASSERT_EQ(a.variants.size(), 1u);
  EXPECT_EQ(a.variants[0].label(), "");
  const CheckSpec& b = m.checks[1];
  EXPECT_EQ(b.width, 8);
  EXPECT_EQ(b.overrides[1].value, "two");
  EXPECT_EQ(b.goldens.at("color"), dir.path() / "other" / "b.png");
  EXPECT_EQ(b.tolerance.max_abs, 0.5);  // from the defaults
  EXPECT_EQ(b.tolerance.radius, 1);
  const CheckSpec& c = m.checks[2];
  EXPECT_EQ(c.goldens.at("color"), dir.path() / "g" / "c.exr");
  EXPECT_EQ(c.goldens.at("depth"), dir.path() / "g" / "c.depth.exr");
  ASSERT_EQ(c.variants.size(), 2u);
  EXPECT_EQ(c.variants[0].label(), "threads=1");
  EXPECT_EQ(c.variants[1].label(), "tile=16");
}

TEST(Manifest, EachMistakeIsOneErrorNamingItsField) {
  const std::string head = R"({"bits_version": 1, "checks": [)";
  const std::pair<std::string, std::string> cases[] = {
      {R"({"checks": []})", "m.json: /: missing key 'bits_version'"},
      {head + "]}", "m.json: /checks: a manifest needs at least one check"},
      {head + R"({"name": "a", "scene": "s.json", "widht": 3}]})", "m.json: /checks/0: unknown key 'widht'; did you mean 'width'?"},
      {head + R"({"name": "a b", "scene": "s.json"}]})", "m.json: /checks/0/name: a check name is 1 to 128 letters"},
      {head + R"({"name": "a", "scene": "s.json"}, {"name": "a", "scene": "t.json"}]})", "m.json: /checks/1/name: check name 'a' is used twice"},
      {head + R"({"name": "a", "scene": "s.json", "outputs": ["colour"]}]})", "m.json: /checks/0/outputs/0: unknown output 'colour'; did you mean 'color'?"},
      {head + R"({"name": "a", "scene": "s.json", "hash": {"color": "sha1:abc"}}]})", "m.json: /checks/0/hash/color: expected \"sha1:\" and 40 lowercase hex digits"},
      {head + R"({"name": "a", "scene": "s.json", "hash": {"depth": "sha1:0000000000000000000000000000000000000000"}}]})", "m.json: /checks/0/hash/depth: a hash for 'depth', which is not one of this check's outputs"},
      {head + R"({"name": "a", "scene": "s.json", "tolerance": {"max_abs": 1}}]})", "m.json: /checks/0/tolerance: a tolerance applies to mode \"tolerance\" only"},
      {head + R"({"name": "a", "scene": "s.json", "golden": {"color": "a.png"}}]})", "m.json: /checks/0/golden: golden files belong to tolerance checks"},
      {head + R"({"name": "a", "scene": "s.json", "mode": "tolerance", "golden": {"color": "a.jpg"}}]})", "m.json: /checks/0/golden/color: a colour golden is .exr, .png or .tif"},
      {head + R"({"name": "a", "scene": "s.json", "mode": "tolerance", "tolerance": {"max_fraction": 2}}]})", "m.json: /checks/0/tolerance/max_fraction: must be from 0 to 1, got 2"},
      {head + R"({"name": "a", "scene": "s.json", "mode": "fuzzy"}]})", "m.json: /checks/0/mode: unknown value 'fuzzy'"},
      {head + R"({"name": "a", "scene": "s.json", "variants": [{"isa": "mmx"}]}]})", "m.json: /checks/0/variants/0/isa: unknown ISA 'mmx'"},
      {head + R"({"name": "a", "scene": "s.json", "variants": [{"tile": 12}]}]})", "m.json: /checks/0/variants/0/tile: must be a multiple of 8"},
      {head + R"({"name": "a", "scene": "s.json", "set": {"camera": 1}}]})", "m.json: /checks/0/set/camera: --set 'camera=1': the JSON pointer must start with '/'"},
      {R"({"camera": {}, "objects": []})", "m.json: this is a scene, not a check manifest"},
      {"{\"bits_version\": 1,", "m.json: parse error at line 1"},
  };
  for (const auto& [text, expected] : cases) {
    const std::string message = error_of(text);
    EXPECT_EQ(message.substr(0, expected.size()), expected) << "manifest: " << text << "\nmessage: " << message;
  }
}

}  // namespace
}  // namespace qdmr
