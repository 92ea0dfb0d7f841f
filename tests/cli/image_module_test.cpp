// The command loads OpenImageIO (libqdmr_imageio.so, src/codec/lazy.cpp) only when a job reads or writes an
// image: a missing module must not matter to anything else, and must be one clear error where an image is needed.
#include <gtest/gtest.h>

#include <cstdint>
#include <cstdlib>
#include <filesystem>
#include <optional>
#include <string>
#include <vector>

#include "cli/cli_test_util.hpp"
#include "support/converted_tiff.hpp"
#include "codec/backend.hpp"
#include "qdmr/core/version.hpp"
#include "write/srgb_encode.hpp"

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
  // 8-bit PNG output is written with libpng directly (codec/png_writer.hpp): no module needed.
  const CommandResult png = run(cli(), {"render", plane, "-o", (dir / "p.png").string(), "--width", "32",
                                             "--height", "18"});
  EXPECT_EQ(png.exit_code, 0) << png.output;
  EXPECT_TRUE(std::filesystem::exists(dir / "p.png"));
  // Float OpenEXR too, a float AOV with it (codec/exr_writer.hpp).
  const CommandResult exr = run(cli(), {"render", plane, "-o", (dir / "p.exr").string(), "--width", "32", "--height",
                                        "18", "--aov", "depth=" + (dir / "d.exr").string()});
  EXPECT_EQ(exr.exit_code, 0) << exr.output;
  EXPECT_TRUE(std::filesystem::exists(dir / "p.exr"));
  EXPECT_TRUE(std::filesystem::exists(dir / "d.exr"));
  // Any other format goes through the module.
  const CommandResult render = run(cli(), {"render", plane, "-o", (dir / "p.tif").string(), "--width", "32",
                                                "--height", "18"});
  EXPECT_EQ(render.exit_code, 2) << render.output;
  EXPECT_NE(render.output.find("image I/O: cannot load libqdmr_imageio.so"), std::string::npos) << render.output;
  EXPECT_NE(render.output.find("QDMR_IMAGEIO_MODULE"), std::string::npos) << render.output;
  EXPECT_FALSE(std::filesystem::exists(dir / "p.tif"));
  // PNG, JPEG, OpenEXR, PGM, PFM and TIFF (of the layouts OpenImageIO passes through) textures are read in process
  // (codec/native_reader.hpp): planned and rendered without the module. A TIFF that OpenImageIO converts needs
  // it, and says so.
  const std::filesystem::path images = source_dir() / "tests/bad_inputs/files/images";
  const auto albedo = [&](const char* file) { return "/materials/bricks/layers/0/albedo=" + (images / file).string(); };
  for (const char* file : {"good.png", "noise.jpg", "noise.tif", "noise.exr"}) {
    const CommandResult textured_plan = run(cli(), {"plan", plane, "--set", albedo(file)});
    EXPECT_EQ(textured_plan.exit_code, 0) << file << ": " << textured_plan.output;
    const CommandResult textured = run(cli(), {"render", plane, "-o", (dir / "t.png").string(), "--width", "32",
                                               "--height", "18", "--set", albedo(file)});
    EXPECT_EQ(textured.exit_code, 0) << file << ": " << textured.output;
  }
  write_file(dir / "t.pgm", "P5\n4 4\n255\n" + std::string(16, char(100)));
  const CommandResult pgm = run(cli(), {"render", plane, "-o", (dir / "pgm.png").string(), "--width", "32",
                                        "--height", "18", "--set",
                                        "/materials/bricks/layers/0/albedo=" + (dir / "t.pgm").string()});
  EXPECT_EQ(pgm.exit_code, 0) << pgm.output;
  write_file(dir / "t.pfm", "Pf\n4 4\n-1.0\n" + std::string(64, char(0)));
  const CommandResult pfm = run(cli(), {"render", plane, "-o", (dir / "pfm.png").string(), "--width", "32",
                                        "--height", "18", "--set",
                                        "/materials/bricks/layers/0/albedo=" + (dir / "t.pfm").string()});
  EXPECT_EQ(pfm.exit_code, 0) << pfm.output;
  write_file(dir / "white.tif", min_is_white_tiff());
  const CommandResult converted = run(cli(), {"render", plane, "-o", (dir / "white.png").string(), "--width", "32",
                                              "--height", "18", "--set",
                                              "/materials/bricks/layers/0/albedo=" + (dir / "white.tif").string()});
  EXPECT_EQ(converted.exit_code, 2) << converted.output;
  EXPECT_NE(converted.output.find("cannot load libqdmr_imageio.so"), std::string::npos) << converted.output;
  EXPECT_FALSE(std::filesystem::exists(dir / "white.png"));
}

// The PNG written without the module holds what qdmr means to write: every byte the sRGB code of the linear
// value the same render writes to an EXR (through the module), and the metadata qdmr stamps (bits version,
// Software), which `qdmr check` and `qdmr diff` read back.
TEST(ImageModule, DirectPngHoldsTheCodesOfTheLinearRender) {
  TempDir dir;
  const std::string plane = (source_dir() / "scenes" / "plane.json").string();
  for (const char* name : {"p.png", "p.exr"}) {
    const CommandResult r = run(cli(), {"render", plane, "-o", (dir / name).string(), "--width", "48", "--height", "27"});
    ASSERT_EQ(r.exit_code, 0) << r.output;
  }
  std::string error;
  imageio::ReadFile png((dir / "p.png").string(), error);
  ASSERT_TRUE(png) << error;
  EXPECT_EQ(png.spec().width, 48);
  EXPECT_EQ(png.spec().height, 27);
  ASSERT_EQ(png.spec().channels, 3);
  EXPECT_EQ(png.spec().type, imageio::PixelType::UInt8);
  EXPECT_EQ(png.spec().bits_version, std::to_string(kBitsVersion));
  EXPECT_NE(png.spec().software.find("qdmr"), std::string::npos);
  std::vector<std::uint8_t> codes(48 * 27 * 3);
  ASSERT_TRUE(png.read(imageio::PixelType::UInt8, codes.data(), 48 * 3, error)) << error;
  imageio::ReadFile exr((dir / "p.exr").string(), error);
  ASSERT_TRUE(exr) << error;
  ASSERT_EQ(exr.spec().channels, 3);
  std::vector<float> linear(48 * 27 * 3);
  ASSERT_TRUE(exr.read(imageio::PixelType::Float, linear.data(), 48 * 3 * sizeof(float), error)) << error;
  for (std::size_t i = 0; i < codes.size(); ++i)
    ASSERT_EQ(std::uint32_t(codes[i]), srgb_code(linear[i], 255.0f)) << "value " << i << ": linear " << linear[i];
}

// --smallest-png: libdeflate's smallest level instead of igzip's fast one; the same pixels in a smaller file. (The
// plane at 192x108: a frame small enough to render in a moment, large enough that the levels' sizes differ.)
TEST(ImageModule, SmallestPngHoldsTheSamePixelsInFewerBytes) {
  TempDir dir;
  const std::string plane = (source_dir() / "scenes" / "plane.json").string();
  for (const bool smallest : {false, true}) {
    std::vector<std::string> args = {"render", plane, "-o", (dir / (smallest ? "s.png" : "f.png")).string(),
                                     "--width", "192", "--height", "108"};
    if (smallest) args.push_back("--smallest-png");
    const CommandResult r = run(cli(), args);
    ASSERT_EQ(r.exit_code, 0) << r.output;
  }
  const auto codes = [&](const char* name) {
    std::string error;
    imageio::ReadFile png((dir / name).string(), error);
    EXPECT_TRUE(png) << error;
    std::vector<std::uint8_t> pixels(192 * 108 * 3);
    EXPECT_TRUE(png.read(imageio::PixelType::UInt8, pixels.data(), 192 * 3, error)) << error;
    return pixels;
  };
  EXPECT_EQ(codes("f.png"), codes("s.png"));
  EXPECT_LT(std::filesystem::file_size(dir / "s.png"), std::filesystem::file_size(dir / "f.png"));
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
