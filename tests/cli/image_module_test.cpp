// The command loads OpenImageIO (libqdmr_imageio.so, src/imageio/lazy.cpp) only when a job reads or writes an
// image: a missing module must not matter to anything else, and must be one clear error where an image is needed.
#include <gtest/gtest.h>

#include <cstdlib>
#include <optional>
#include <string>

#include "cli/cli_test_util.hpp"

namespace qdmr::test {
namespace {

// QDMR_IMAGEIO_MODULE set for the life of the object (the command inherits the environment).
class ModulePath {
public:
  explicit ModulePath(const std::string& path) {
    if (const char* old = std::getenv("QDMR_IMAGEIO_MODULE")) saved_ = old;
    ::setenv("QDMR_IMAGEIO_MODULE", path.c_str(), 1);
  }
  ~ModulePath() { saved_ ? ::setenv("QDMR_IMAGEIO_MODULE", saved_->c_str(), 1) : ::unsetenv("QDMR_IMAGEIO_MODULE"); }
  ModulePath(const ModulePath&) = delete;
  ModulePath& operator=(const ModulePath&) = delete;

private:
  std::optional<std::string> saved_;
};

TEST(ImageModule, OnlyJobsWithImagesLoadIt) {
  TempDir dir;
  const ModulePath missing((dir / "no-such-module.so").string());
  const std::string plane = (source_dir() / "scenes" / "plane.json").string();
  // Procedural textures, no image written: nothing to load.
  EXPECT_EQ(run(cli(), {"--help"}).exit_code, 0);
  const CommandResult plan = run(cli(), {"plan", plane});
  EXPECT_EQ(plan.exit_code, 0) << plan.output;
  const CommandResult bench = run(cli(), {"bench", plane, "--width", "32", "--height", "18", "--frames", "1",
                                               "--warmup", "0", "--json", (dir / "b.json").string(), "--image",
                                               (dir / "b.bin").string()});
  // bench writes its one image through the module: without it, a clear error and nothing written.
  EXPECT_EQ(bench.exit_code, 2) << bench.output;
  const CommandResult render = run(cli(), {"render", plane, "-o", (dir / "p.png").string(), "--width", "32",
                                                "--height", "18"});
  EXPECT_EQ(render.exit_code, 2) << render.output;
  EXPECT_NE(render.output.find("image I/O: cannot load libqdmr_imageio.so"), std::string::npos) << render.output;
  EXPECT_NE(render.output.find("QDMR_IMAGEIO_MODULE"), std::string::npos) << render.output;
  EXPECT_FALSE(std::filesystem::exists(dir / "p.png"));
}

TEST(ImageModule, TheBuiltModuleWritesAndReadsImages) {
  TempDir dir;
  const std::string plane = (source_dir() / "scenes" / "plane.json").string();
  const CommandResult render = run(cli(), {"render", plane, "-o", (dir / "p.exr").string(), "--width", "32",
                                                "--height", "18"});
  ASSERT_EQ(render.exit_code, 0) << render.output;
  const CommandResult diff = run(cli(), {"diff", (dir / "p.exr").string(), (dir / "p.exr").string()});
  EXPECT_EQ(diff.exit_code, 0) << diff.output;
}

}  // namespace
}  // namespace qdmr::test
