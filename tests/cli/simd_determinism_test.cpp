// Same scene, same bits: through the qdmr command, the SSE4.2 twin (qdmr-sse) renders every scene to the
// same float pixels as the AVX2 build, and neither the thread count nor the tile size changes a bit. The
// colour image and the depth, normal, uv, shadow and ao AOVs are all compared exactly (no tolerance: determinism is
// the contract).
#include <gtest/gtest.h>

#include "cli/cli_test_util.hpp"

namespace qdmr::test {
namespace {

namespace fs = std::filesystem;

const std::vector<std::string> kImages{"color", "depth", "normal", "uv", "shadow", "ao"};

// Renders `scene` with every AOV through `binary` into `dir`; returns the file of each image in kImages.
std::vector<fs::path> render_all(const fs::path& binary, const ShippedScene& scene, const fs::path& dir,
                                 std::vector<std::string> extra = {}) {
  std::vector<fs::path> files;
  for (const std::string& image : kImages) files.push_back(dir / (image + ".exr"));
  for (std::size_t i = 1; i < kImages.size(); ++i) extra.insert(extra.end(), {"--aov", kImages[i] + "=" + files[i].string()});
  render_scene(binary, scene, files[0], extra);
  return files;
}

void expect_identical(const std::vector<fs::path>& a, const std::vector<fs::path>& b, const std::string& what) {
  for (std::size_t i = 0; i < kImages.size(); ++i) {
    const std::string difference = first_difference(read_float_image(a[i]), read_float_image(b[i]));
    EXPECT_EQ(difference, "") << what << ", " << kImages[i];
  }
}

class CliSimd : public testing::TestWithParam<ShippedScene> {};

TEST_P(CliSimd, SseTwinRendersTheSameBits) {
  const ShippedScene& scene = GetParam();
  if (cli_sse().empty())
    GTEST_SKIP() << "qdmr-sse is not built (QDMR_BUILD_SSE_TWIN=OFF, or this build is itself SSE4.2)";
  if (scene.needs_data && !have_data())
    GTEST_SKIP() << scene.name << ".json needs the real CC0 maps, not found in QDMR_DATA_DIR=" << data_dir();
  TempDir avx2_dir, sse_dir;
  const auto avx2 = render_all(cli(), scene, avx2_dir.path());
  const auto sse = render_all(cli_sse(), scene, sse_dir.path());
  if (HasFatalFailure()) return;
  expect_identical(avx2, sse, scene.name + ": " + cli().filename().string() + " vs " + cli_sse().filename().string());
}

INSTANTIATE_TEST_SUITE_P(, CliSimd, testing::ValuesIn(shipped_scenes()), scene_name);

// terrain (58k small triangles, many per tile) and objects (overlapping meshes, depth test across tiles)
// are the scenes where scheduling could leak into pixels; plane adds nothing.
const std::vector<ShippedScene> kBusyScenes{{"terrain", false}, {"objects", false}};

TEST(CliDeterminism, ThreadCountDoesNotChangeABit) {
  for (const ShippedScene& scene : kBusyScenes) {
    TempDir one, two;
    const auto a = render_all(cli(), scene, one.path(), {"--threads", "1"});
    const auto b = render_all(cli(), scene, two.path(), {"--threads", "2"});
    if (HasFatalFailure()) return;
    expect_identical(a, b, scene.name + ": --threads 1 vs 2");
  }
}

TEST(CliDeterminism, TileSizeDoesNotChangeABit) {
  for (const ShippedScene& scene : kBusyScenes) {
    TempDir small, large;
    const auto a = render_all(cli(), scene, small.path(), {"--tile", "16"});
    const auto b = render_all(cli(), scene, large.path(), {"--tile", "128"});
    if (HasFatalFailure()) return;
    expect_identical(a, b, scene.name + ": --tile 16 vs 128");
  }
}

}  // namespace
}  // namespace qdmr::test
