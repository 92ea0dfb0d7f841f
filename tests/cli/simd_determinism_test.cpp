// Same scene, same bits: through the qdmr command, every draw kernel this machine can run (--isa sse4.2, avx2,
// ...) renders every scene to the same float pixels, and neither the thread count nor the tile size changes a
// bit. The colour image and the depth, normal, uv, iterations, shadow and ao AOVs are all compared exactly (no tolerance:
// determinism is the contract).
#include <gtest/gtest.h>

#include "cli/cli_test_util.hpp"
#include "qdmr/core/isa.hpp"

namespace qdmr::test {
namespace {

namespace fs = std::filesystem;

const std::vector<std::string> kImages{"color", "depth", "normal", "uv", "iterations", "shadow", "ao"};

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

class CliIsa : public testing::TestWithParam<ShippedScene> {};

TEST_P(CliIsa, EveryKernelRendersTheSameBits) {
  const ShippedScene& scene = GetParam();
  const std::vector<Isa> isas = usable_isas();
  if (isas.size() < 2) GTEST_SKIP() << "this CPU runs only one of the binary's kernels: nothing to compare";
  if (scene.needs_data && !have_data())
    GTEST_SKIP() << scene.name << ".json needs the real CC0 maps, not found in QDMR_DATA_DIR=" << data_dir();
  TempDir first_dir;
  const auto first = render_all(cli(), scene, first_dir.path(), {"--isa", isa_name(isas[0])});
  for (std::size_t k = 1; k < isas.size(); ++k) {
    TempDir dir;
    const auto other = render_all(cli(), scene, dir.path(), {"--isa", isa_name(isas[k])});
    if (HasFatalFailure()) return;
    expect_identical(first, other, scene.name + ": --isa " + isa_name(isas[0]) + " vs " + isa_name(isas[k]));
  }
}

INSTANTIATE_TEST_SUITE_P(, CliIsa, testing::ValuesIn(shipped_scenes()), scene_name);

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
