// sampling/math through the command, on a point-sampled strip of random colours (docs/sampling.md, "Math
// modes"): 16383 texels wide, sm3's fp32 texel coordinates pick the neighbouring texel on some pixels where sm4
// and exact do not; 16384 wide (a power of two), the three modes render the same bits; sm4 and exact always do.
#include <gtest/gtest.h>

#include <cstdint>
#include <cstring>
#include <random>
#include <string>
#include <vector>

#include "cli/cli_test_util.hpp"
#include "qdmr/core/isa.hpp"

namespace qdmr::test {
namespace {

// Renders the strip (width texels by 1, 0.93 of a repeat across a plane seen at an angle) with `math`; the EXR
// pixels. (Seen straight from above, the interpolated u of the pixels happened to miss every edge.)
FloatImage render_strip(const TempDir& dir, int width, const std::string& math) {
  const std::string strip = "strip" + std::to_string(width) + ".png";
  if (!std::filesystem::exists(dir / strip)) {
    std::mt19937 rng{std::uint32_t(width)};
    std::vector<std::uint8_t> texels(std::size_t(width) * 3);
    for (std::uint8_t& t : texels) t = std::uint8_t(rng() & 0xFF);
    auto out = OIIO::ImageOutput::create((dir / strip).string());
    EXPECT_TRUE(out && out->open((dir / strip).string(), OIIO::ImageSpec(width, 1, 3, OIIO::TypeDesc::UINT8)) &&
                out->write_image(OIIO::TypeDesc::UINT8, texels.data()) && out->close());
  }
  write_file(dir / "scene.json", R"({
  "camera": {"position": [0.37, -0.71, 1.3], "target": [0, 0, 0], "up": [0, 0, 1], "fov_deg": 45},
  "lights": [{"type": "ambient", "intensity": 1}],
  "materials": {"m": {"layers": [{"albedo": {"file": ")" + strip + R"(", "srgb": false}}],
                      "sampling": {"filter": "point", "math": ")" + math + R"("}}},
  "objects": [{"mesh": {"type": "plane", "size": [1, 1], "uv_scale": [0.93, 1]}, "material": "m"}]
})");
  const std::filesystem::path image = dir / (math + ".exr");
  const CommandResult result = run(cli(), {"render", (dir / "scene.json").string(), "-o", image.string(), "--width",
                                           std::to_string(kCliWidth), "--height", std::to_string(kCliHeight)});
  EXPECT_EQ(result.exit_code, 0) << result.output;
  return read_float_image(image);
}

std::size_t differing_pixels(const FloatImage& a, const FloatImage& b) {
  std::size_t n = 0;
  for (std::size_t i = 0; i < a.pixels.size(); i += std::size_t(a.channels))
    n += std::memcmp(&a.pixels[i], &b.pixels[i], sizeof(float) * std::size_t(a.channels)) != 0;
  return n;
}

TEST(CliMathModes, Fp32AddressingPicksOtherTexelsOnANonPowerOfTwoMap) {
  TempDir dir;
  const FloatImage sm4 = render_strip(dir, 16383, "sm4"), sm3 = render_strip(dir, 16383, "sm3"),
                   exact = render_strip(dir, 16383, "exact");
  ASSERT_EQ(sm4.pixels.size(), sm3.pixels.size());
  const std::size_t differ = differing_pixels(sm4, sm3);
  EXPECT_GT(differ, 0u);
  EXPECT_LT(differ, sm4.pixels.size() / 3 / 100);  // a texel edge within an fp32 rounding: rare
  EXPECT_EQ(first_difference(sm4, exact), "");
}

TEST(CliMathModes, EveryModeRendersTheSameBitsOnAPowerOfTwoMap) {
  TempDir dir;
  const FloatImage sm4 = render_strip(dir, 16384, "sm4");
  EXPECT_EQ(first_difference(sm4, render_strip(dir, 16384, "sm3")), "");
  EXPECT_EQ(first_difference(sm4, render_strip(dir, 16384, "exact")), "");
}

// The modes' own arithmetic (the exact texel address on a map that is not a power of two, exact's fp64 crossings,
// sm3's cells) gives the same bits on every draw kernel this CPU runs.
TEST(CliMathModes, EveryKernelRendersTheSameBitsInEveryMode) {
  const std::vector<Isa> isas = usable_isas();
  if (isas.size() < 2) GTEST_SKIP() << "this CPU runs only one of the binary's kernels: nothing to compare";
  TempDir dir;
  render_strip(dir, 16383, "sm4");  // writes the strip and its scene
  for (const std::string math : {"sm4", "sm3", "exact"}) {
    std::vector<FloatImage> strip, qdm;
    for (Isa isa : isas) {
      const std::string name = math + "_" + isa_name(isa);
      const std::vector<std::string> set{"--isa", isa_name(isa), "--set", "/materials/m/sampling/math=" + math};
      std::vector<std::string> args{"render", (dir / "scene.json").string(), "-o", (dir / (name + ".exr")).string(),
                                    "--width", "240", "--height", "135"};
      args.insert(args.end(), set.begin(), set.end());
      const CommandResult result = run(cli(), args);
      ASSERT_EQ(result.exit_code, 0) << result.output;
      strip.push_back(read_float_image(dir / (name + ".exr")));
      render_scene(cli(), {"pom_vs_qdm_depth_5.0", false}, dir / ("qdm_" + name + ".exr"),
                   {"--isa", isa_name(isa), "--set", "/materials/surface/sampling/math=" + math});
      qdm.push_back(read_float_image(dir / ("qdm_" + name + ".exr")));
    }
    for (std::size_t k = 1; k < isas.size(); ++k) {
      EXPECT_EQ(first_difference(strip[0], strip[k]), "") << math << ": strip, " << isa_name(isas[k]);
      EXPECT_EQ(first_difference(qdm[0], qdm[k]), "") << math << ": pom_vs_qdm_depth_5.0, " << isa_name(isas[k]);
    }
  }
}

}  // namespace
}  // namespace qdmr::test
