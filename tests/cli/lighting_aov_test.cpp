// The shadow and ao AOVs through the command: exactly 1 where nothing can occlude (a flat height map, the
// plateau around a pit, programs and materials without the feature), below 1 on the floor of a known pit, and
// the shadow AOV follows the scene's first directional light.
#include <gtest/gtest.h>

#include <algorithm>
#include <cstdint>
#include <string>
#include <vector>

#include <OpenImageIO/imageio.h>

#include "cli/cli_test_util.hpp"
#include "kernel/displacement_test_util.hpp"

namespace qdmr::test {
namespace {

constexpr int kSize = 96;            // pixels per side; the plane fills the view
constexpr int kMap = 64;             // height map texels per side
constexpr int kPit0 = 24, kPit1 = 40;  // the pit: texels [24, 40) in x and y are 0, the rest 1
constexpr float kDepthScale = 0.1f;  // 6.4 texels deep, 16 wide

// A 64x64 8-bit height map: 1 (255) everywhere but a 16x16 square pit of 0 in the middle.
void write_pit(const std::filesystem::path& file) {
  std::vector<std::uint8_t> texels(std::size_t(kMap) * kMap, 255);
  for (int y = kPit0; y < kPit1; ++y)
    for (int x = kPit0; x < kPit1; ++x) texels[std::size_t(y) * kMap + std::size_t(x)] = 0;
  auto out = OIIO::ImageOutput::create(file.string());
  ASSERT_TRUE(out);
  ASSERT_TRUE(out->open(file.string(), OIIO::ImageSpec(kMap, kMap, 1, OIIO::TypeDesc::UINT8)));
  ASSERT_TRUE(out->write_image(OIIO::TypeDesc::UINT8, texels.data()));
  ASSERT_TRUE(out->close());
}

struct Aovs {
  FloatImage shadow, ao, hit_depth, depth;
};

// A unit plane seen straight from above (view rays along the normal: the pit's walls are not visible, its
// floor is at depth kDepthScale), lit by `lights` (directions towards the light), with the height `height`
// (JSON), technique `technique` and the shadow and ao blocks given.
Aovs render_aovs(const TempDir& dir, const std::string& height, const std::string& technique, const std::string& shadow,
                 const std::string& ao, const std::vector<std::string>& lights = {"[1, 0, 1]"}) {
  std::string light_list;
  for (const std::string& l : lights)
    light_list += R"({"type": "directional", "direction": )" + l + R"(, "intensity": 1}, )";
  const std::string scene = R"({
  "camera": {"position": [0, 0, 2], "target": [0, 0, 0], "up": [0, 1, 0], "fov_deg": 25},
  "lights": [)" + light_list + R"({"type": "ambient", "intensity": 0.2}],
  "materials": {"pit": {
    "layers": [{"height": )" + height + R"(, "albedo": {"constant": 0.5}}],
    "technique": )" + technique + R"(,
    "shadow": )" + shadow + R"(,
    "ao": )" + ao + R"(}},
  "objects": [{"mesh": {"type": "plane", "size": [1, 1]}, "material": "pit"}]
})";
  write_file(dir.path() / "scene.json", scene);
  const CommandResult result =
      run(cli(), {"render", (dir.path() / "scene.json").string(), "-o", (dir.path() / "image.exr").string(), "--width",
                  std::to_string(kSize), "--height", std::to_string(kSize), "--aov",
                  "shadow=" + (dir.path() / "shadow.exr").string(), "--aov", "ao=" + (dir.path() / "ao.exr").string(),
                  "--aov", "hit_depth=" + (dir.path() / "hit_depth.exr").string(), "--aov",
                  "depth=" + (dir.path() / "depth.exr").string()});
  EXPECT_EQ(result.exit_code, 0) << result.output << "\n" << scene;
  Aovs aovs;
  aovs.shadow = read_float_image(dir.path() / "shadow.exr");
  aovs.ao = read_float_image(dir.path() / "ao.exr");
  aovs.hit_depth = read_float_image(dir.path() / "hit_depth.exr");
  aovs.depth = read_float_image(dir.path() / "depth.exr");
  EXPECT_EQ(aovs.shadow.pixels.size(), std::size_t(kSize) * kSize);
  EXPECT_EQ(aovs.ao.pixels.size(), std::size_t(kSize) * kSize);
  return aovs;
}

const std::string kQdm = R"({"name": "qdm", "depth_scale": 0.1, "refinement": "none"})";
const std::string kPitHeight = R"({"file": "pit.png"})";
const std::string kFlatHeight = R"({"procedural": "flat", "size": 64})";
const char* const kShadowModes[] = {"hard", "horizon", "qdm_soft"};
// AO radius 0.2 UV = 12.8 texels: from every point of the 16-texel pit floor some wall is within reach.
const char* const kAoModes[] = {R"({"mode": "frame", "radius": 0.2})", R"({"mode": "frame", "radius": 0.2, "coarse": false})",
                                R"({"mode": "baked", "radius": 0.2})"};

std::string shadow_block(const char* mode) { return std::string(R"({"mode": ")") + mode + "\"}"; }

// Every pixel the plane covers (the depth AOV is 0 only where nothing is drawn) has `value` exactly.
void expect_all_covered(const FloatImage& image, const FloatImage& depth, float value, const std::string& what) {
  std::size_t covered = 0, wrong = 0;
  for (std::size_t i = 0; i < image.pixels.size(); ++i) {
    if (!(depth.pixels[i] > 0.0f)) continue;
    ++covered;
    wrong += image.pixels[i] != value;
  }
  EXPECT_EQ(covered, image.pixels.size()) << what << ": the plane should fill the view";
  EXPECT_EQ(wrong, 0u) << what << ": pixels not exactly " << value;
}

TEST(CliLightingAovs, OneWhereNothingCanOcclude) {
  const TemporaryConeCache cache;  // baked AO maps go to a temporary cache
  const TempDir dir;
  write_pit(dir.path() / "pit.png");
  // A flat height map: the light ray and the horizon see no surface above the point; exact 1 (the shadow and AO
  // code documents 1 for a flat surface: occlusion max(0, ...) = 0 and 1 - sin(0) = 1).
  for (const char* shadow : kShadowModes)
    for (const char* ao : kAoModes) {
      const Aovs a = render_aovs(dir, kFlatHeight, kQdm, shadow_block(shadow), ao);
      expect_all_covered(a.shadow, a.depth, 1.0f, std::string("flat, shadow ") + shadow);
      expect_all_covered(a.ao, a.depth, 1.0f, std::string("flat, ao ") + ao);
    }
  // The pit with the features off, and with normal mapping (no self-shadowing, no AO): 1 everywhere.
  {
    const Aovs off = render_aovs(dir, kPitHeight, kQdm, R"({"mode": "off"})", R"({"mode": "off"})");
    expect_all_covered(off.shadow, off.depth, 1.0f, "pit, shadow off");
    expect_all_covered(off.ao, off.depth, 1.0f, "pit, ao off");
    const Aovs normal = render_aovs(dir, kPitHeight, R"({"name": "normal"})", R"({"mode": "off"})", R"({"mode": "off"})");
    expect_all_covered(normal.shadow, normal.depth, 1.0f, "pit, normal mapping");
    expect_all_covered(normal.ao, normal.depth, 1.0f, "pit, normal mapping");
  }
}

TEST(CliLightingAovs, BelowOneInAPit) {
  const TemporaryConeCache cache;
  const TempDir dir;
  write_pit(dir.path() / "pit.png");
  for (const char* shadow : kShadowModes)
    for (const char* ao : kAoModes) {
      const std::string what = std::string("shadow ") + shadow + ", ao " + ao;
      const Aovs a = render_aovs(dir, kPitHeight, kQdm, shadow_block(shadow), ao);
      std::size_t floor = 0, plateau = 0, plateau_not_one = 0, floor_ao_not_below_one = 0;
      float floor_shadow_min = 2.0f, floor_shadow_max = -1.0f;
      for (std::size_t i = 0; i < a.hit_depth.pixels.size(); ++i) {
        ASSERT_GT(a.depth.pixels[i], 0.0f) << what << ": the plane should fill the view";
        const float s = a.shadow.pixels[i], o = a.ao.pixels[i];
        EXPECT_TRUE(s >= 0.0f && s <= 1.0f && o >= 0.0f && o <= 1.0f) << what << ": " << s << ", " << o;
        // Seen along the normal the hit is either on the plateau (depth 0) or on the floor (depth 0.1, the box
        // surface without refinement: exactly the depth scale up to the float steps of the ray).
        if (a.hit_depth.pixels[i] == 0.0f) {
          ++plateau;
          plateau_not_one += s != 1.0f || o != 1.0f;  // nothing above the highest texels: exactly 1
        } else if (a.hit_depth.pixels[i] > 0.99f * kDepthScale) {
          ++floor;
          floor_shadow_min = std::min(floor_shadow_min, s);
          floor_shadow_max = std::max(floor_shadow_max, s);
          floor_ao_not_below_one += !(o < 1.0f);
        }
      }
      // The pit is a quarter of the map per side: about 1/16 of the view (which shows 0.89 of the unit plane).
      EXPECT_GT(floor, std::size_t(kSize * kSize / 20)) << what;
      EXPECT_GT(plateau, std::size_t(kSize * kSize / 2)) << what;
      EXPECT_EQ(plateau_not_one, 0u) << what;
      // Light at 45 degrees: the wall on the light's side shadows the 6.4 texels of floor next to it (of 16);
      // the far side of the floor is lit.
      EXPECT_LT(floor_shadow_min, 1.0f) << what;
      if (std::string(shadow) == "hard") {
        EXPECT_EQ(floor_shadow_min, 0.0f) << what;  // binary visibility
        EXPECT_EQ(floor_shadow_max, 1.0f) << what;
      }
      EXPECT_EQ(floor_ao_not_below_one, 0u) << what << ": every floor pixel has a wall within the AO radius";
    }
}

TEST(CliLightingAovs, ShadowFollowsTheFirstDirectionalLight) {
  const TempDir dir;
  write_pit(dir.path() / "pit.png");
  const std::string hard = shadow_block("hard"), off = R"({"mode": "off"})";
  const Aovs east_only = render_aovs(dir, kPitHeight, kQdm, hard, off, {"[1, 0, 1]"});
  const Aovs west_only = render_aovs(dir, kPitHeight, kQdm, hard, off, {"[-1, 0, 1]"});
  const Aovs east_west = render_aovs(dir, kPitHeight, kQdm, hard, off, {"[1, 0, 1]", "[-1, 0, 1]"});
  const Aovs west_east = render_aovs(dir, kPitHeight, kQdm, hard, off, {"[-1, 0, 1]", "[1, 0, 1]"});
  EXPECT_EQ(first_difference(east_west.shadow, east_only.shadow), "");
  EXPECT_EQ(first_difference(west_east.shadow, west_only.shadow), "");
  EXPECT_NE(first_difference(east_only.shadow, west_only.shadow), "");  // the two lights shadow opposite walls
  // A light below the polygon leaves the relief in shadow: 0 everywhere.
  const Aovs below = render_aovs(dir, kPitHeight, kQdm, hard, off, {"[1, 0, -1]"});
  expect_all_covered(below.shadow, below.depth, 0.0f, "light below the polygon");
}

}  // namespace
}  // namespace qdmr::test
