// Bad input through the qdmr command: each gives one error line naming the file (or option) and the field,
// exit status 2, and writes nothing: no image, no temporary file, the scene untouched. Never a crash.
// (A hang would hit the CTest timeout of the suite.)
#include <gtest/gtest.h>

#include <OpenImageIO/imageio.h>

#include <set>
#include <string>
#include <vector>

#include "support/test_support.hpp"

namespace qdmr::test {
namespace {

namespace fs = std::filesystem;

constexpr const char* kScene = R"({
  "output": {"width": 64, "height": 48},
  "materials": {"rock": {"layers": [{"height": {"procedural": "cobbles", "size": 64}}]}},
  "objects": [{"mesh": {"type": "plane"}, "material": "rock"}]
})";

// A folder with the scene (and the inputs a case adds) and an empty output folder.
class CliBadInput : public testing::Test {
protected:
  void SetUp() override {
    fs::create_directory(out_);
    add_input("scene.json", kScene);
  }

  void add_input(const std::string& name, const std::string& text) {
    write_file(dir_ / name, text);
    inputs_.insert(name);
  }

  // qdmr render scene.json -o out/image.png ARGS...
  std::vector<std::string> render_args(const std::vector<std::string>& args) const {
    std::vector<std::string> all{"render", scene_.string(), "-o", (out_ / "image.png").string()};
    all.insert(all.end(), args.begin(), args.end());
    return all;
  }

  // Runs qdmr with `args`; expects exit status 2, one line "qdmr: error: ..." holding every fragment, and
  // nothing written. `other_lines`: lines a library prints on its own (see the corrupt image case).
  void expect_refused(const std::vector<std::string>& args, const std::vector<std::string>& fragments,
                      std::size_t other_lines = 0) {
    const std::string scene_before = read_file(scene_);
    const CommandResult result = run(cli(), args);
    std::string command = "qdmr";
    for (const std::string& a : args) command += " " + a;
    SCOPED_TRACE(command + "\n" + result.output);
    EXPECT_EQ(result.exit_code, 2);
    const std::vector<std::string> lines = lines_of(result.output);
    ASSERT_EQ(lines.size(), 1 + other_lines);
    const std::string& message = lines.back();
    EXPECT_EQ(message.rfind("qdmr: error: ", 0), 0u);
    for (const std::string& fragment : fragments) EXPECT_NE(message.find(fragment), std::string::npos) << fragment;
    expect_nothing_written();
    EXPECT_EQ(read_file(scene_), scene_before);
  }

  void expect_nothing_written() const {
    EXPECT_TRUE(fs::is_empty(out_)) << "something was written to the output folder";
    std::set<std::string> names;
    for (const auto& entry : fs::directory_iterator(dir_.path())) names.insert(entry.path().filename().string());
    std::set<std::string> expected = inputs_;
    expected.insert("out");
    EXPECT_EQ(names, expected) << "something was written next to the scene";
  }

  TempDir dir_;
  fs::path scene_ = dir_ / "scene.json";
  fs::path out_ = dir_ / "out";
  std::set<std::string> inputs_;
};

// --- the scene file -----------------------------------------------------------------------------------

TEST_F(CliBadInput, MalformedJsonGivesLineAndColumn) {
  add_input("scene.json", "{\n  \"objects\": [,]\n}\n");
  expect_refused(render_args({}), {"scene.json: parse error at line 2, column 15"});
}

TEST_F(CliBadInput, UnknownKeySuggestsTheClosest) {
  add_input("scene.json", R"({"output": {"widht": 64}, "objects": []})");
  expect_refused(render_args({}), {"scene.json: /output: unknown key 'widht'; did you mean 'width'?"});
}

TEST_F(CliBadInput, WrongType) {
  expect_refused(render_args({"--set", "/output/height=\"tall\""}),
                 {"scene.json: /output/height: expected a number, got string"});
}

TEST_F(CliBadInput, MissingTexture) {
  expect_refused(render_args({"--set", "/materials/rock/layers/0/albedo=rock.png"}),
                 {"scene.json: /materials/rock/layers/0/albedo", "file not found: " + (dir_ / "rock.png").string()});
}

TEST_F(CliBadInput, CorruptImage) {
  // A valid 64x64 PNG of noise (so it compresses poorly), cut in the middle of its image data.
  const fs::path png = dir_ / "rock.png";
  std::vector<unsigned char> noise(64 * 64 * 3);
  std::uint32_t state = 1;
  for (unsigned char& value : noise) {
    state ^= state << 13, state ^= state >> 17, state ^= state << 5;  // xorshift32
    value = static_cast<unsigned char>(state >> 24);
  }
  auto writer = OIIO::ImageOutput::create(png.string());
  ASSERT_TRUE(writer && writer->open(png.string(), OIIO::ImageSpec(64, 64, 3, OIIO::TypeDesc::UINT8)));
  ASSERT_TRUE(writer->write_image(OIIO::TypeDesc::UINT8, noise.data()));
  writer->close();
  const std::string bytes = read_file(png);
  ASSERT_GT(bytes.size(), 10000u);
  add_input("rock.png", bytes.substr(0, bytes.size() / 2));
  // Found before any pixel is decoded (the file does not end with IEND), so libpng prints nothing of its own.
  expect_refused(render_args({"--set", "/materials/rock/layers/0/albedo=rock.png"}),
                 {"scene.json: /materials/rock/layers/0/albedo", "cannot read '" + png.string() + "'", "truncated PNG"});
}

TEST_F(CliBadInput, MissingObj) {
  expect_refused(render_args({"--set", R"(/objects/0/mesh={"type": "obj", "file": "model.obj"})"}),
                 {"scene.json: /objects/0/mesh/file: file not found: " + (dir_ / "model.obj").string()});
}

TEST_F(CliBadInput, ObjWithNanVertex) {
  add_input("model.obj", "v 0 0 0\nv 1 0 nan\nv 0 1 0\nf 1 2 3\n");
  expect_refused(render_args({"--set", R"(/objects/0/mesh={"type": "obj", "file": "model.obj"})"}),
                 {"scene.json: /objects/0/mesh/file: line 2: position component 'nan' is not a finite number"});
}

TEST_F(CliBadInput, CameraTargetAtThePosition) {
  expect_refused(render_args({"--set", R"(/camera={"position": [1, 2, 3], "target": [1, 2, 3]})"}),
                 {"scene.json: /camera/target: the target must differ from the position"});
}

TEST_F(CliBadInput, ImageSize) {
  expect_refused(render_args({"--width", "0"}), {"scene.json: /output/width: must be an integer from 1 to 16384, got 0"});
  expect_refused(render_args({"--set", "/output/width=20000"}),
                 {"scene.json: /output/width: must be an integer from 1 to 16384, got 20000"});
  expect_refused(render_args({"--height", "-5"}), {"scene.json: /output/height: must be an integer from 1 to 16384, got -5"});
  expect_refused(render_args({"--width", "16384", "--height", "16384"}),
                 {"scene.json: /output: an output of 16384x16384 has 268435456 pixels, more than the limit"});
}

TEST_F(CliBadInput, SceneFileMissing) {
  const fs::path missing = dir_ / "nope.json";
  expect_refused({"render", missing.string(), "-o", (out_ / "image.png").string()},
                 {missing.string() + ": file not found"});
}

// --- options --------------------------------------------------------------------------------------------

TEST_F(CliBadInput, Threads) {
  expect_refused(render_args({"--threads", "0"}), {"--threads: must be from 1 to 256, got 0 (omit it to use every core)"});
  expect_refused(render_args({"--threads", "many"}), {"--threads"});
}

TEST_F(CliBadInput, Tile) {
  expect_refused(render_args({"--tile", "7"}), {"--tile: must be a multiple of 8 between 8 and 1024, got 7"});
}

TEST_F(CliBadInput, UnknownAov) {
  expect_refused(render_args({"--aov", "albedo=" + (out_ / "albedo.exr").string()}),
                 {"--aov: unknown AOV 'albedo' (valid: depth, normal, uv, iterations, hit_uv, hit_depth, error_texels, missed, "
                  "shadow, ao, cache_misses)"});
  expect_refused(render_args({"--aov", "depth"}), {"--aov depth: expected NAME=FILE"});
}

TEST_F(CliBadInput, BadSetPointer) {
  expect_refused(render_args({"--set", "camera/fov_deg"}), {"--set 'camera/fov_deg': expected POINTER=VALUE"});
  expect_refused(render_args({"--set", "/objects/0/mesh/type/x=1"}),
                 {"scene.json: /objects/0/mesh/type/x: cannot apply --set: /objects/0/mesh/type is a string, not an object or array"});
  expect_refused(render_args({"--set", "/sky/color=1"}), {"scene.json: /: unknown key 'sky'"});
}

// What only preparing the material can tell: the textures' sizes and what a technique can march.
TEST_F(CliBadInput, BlendedLayers) {
  const std::string second = R"(/materials/rock/layers/-={"height": {"procedural": "noise", "size": 32}})";
  expect_refused(render_args({"--set", "/materials/rock/technique/name=qdm", "--set", second}),
                 {"scene.json: /materials/rock/layers/1/height: blended layers need height maps of one size: layer 0 is "
                  "64x64, this one 32x32"});
  const std::string same = R"(/materials/rock/layers/-={"height": {"procedural": "noise", "size": 64}})";
  expect_refused(render_args({"--set", "/materials/rock/technique/name=csm", "--set", same}),
                 {"scene.json: /materials/rock/technique/name: 'csm' needs a cone map of one height map and cannot march "
                  "blended layers (use relief, pom or qdm)"});
  expect_refused(render_args({"--set", "/materials/rock/technique/name=pom", "--set", same, "--set",
                              "/materials/rock/blend/weights/resolution=100"}),
                 {"scene.json: /materials/rock/blend/weights/resolution: must be a power of two, got 100"});
  expect_refused(render_args({"--set", "/materials/rock/layers/-={}", "--set", "/materials/rock/blend/operator=height"}),
                 {"scene.json: /materials/rock/layers/1/height: height blending needs a height map in every layer"});
  expect_refused(render_args({"--set", "/materials/rock/layers/-={}", "--set", "/materials/rock/blend/weights/source=file",
                              "--set", "/materials/rock/blend/weights/file=weights.png"}),
                 {"scene.json: /materials/rock/blend/weights/file: file not found: " + (dir_ / "weights.png").string()});
}

TEST_F(CliBadInput, QuadtreeForShadowsNeedsPowerOfTwo) {
  expect_refused(render_args({"--set", "/materials/rock/layers/0/height/size=48", "--set", "/materials/rock/technique/name=pom",
                              "--set", "/materials/rock/shadow/mode=qdm_soft"}),
                 {"scene.json: /materials/rock/layers/0/height/size"});
}

TEST_F(CliBadInput, UnsupportedOutputType) {
  const fs::path jpg = out_ / "image.jpg";
  expect_refused({"render", scene_.string(), "-o", jpg.string()},
                 {"-o " + jpg.string() + ": unsupported image type '.jpg' (use .png, .exr or .tif)"});
}

TEST_F(CliBadInput, OutputFolderMissing) {
  const fs::path image = dir_ / "missing" / "image.png";
  expect_refused({"render", scene_.string(), "-o", image.string()},
                 {"-o " + image.string() + ": folder does not exist: " + (dir_ / "missing").string()});
}

TEST_F(CliBadInput, NeverOverwritesTheScene) {
  expect_refused({"render", scene_.string(), "-o", scene_.string()}, {"-o " + scene_.string() + ": unsupported image type"});
  expect_refused(render_args({"--stats", scene_.string()}), {"--stats " + scene_.string() + ": refusing to overwrite an input of this job"});
  // A scene file named like an image: only the identity check stops it, also through another spelling.
  add_input("scene.exr", kScene);
  const fs::path scene_exr = dir_ / "scene.exr";
  const std::string other_spelling = (out_ / ".." / "scene.exr").string();
  expect_refused({"render", scene_exr.string(), "-o", other_spelling},
                 {"-o " + other_spelling + ": refusing to overwrite an input of this job"});
  expect_refused({"render", scene_exr.string(), "-o", (out_ / "image.png").string(), "--aov", "depth=" + scene_exr.string()},
                 {"--aov " + scene_exr.string() + ": refusing to overwrite an input of this job"});
  EXPECT_EQ(read_file(scene_exr), kScene);
}

// --- what must work -------------------------------------------------------------------------------------

TEST_F(CliBadInput, DegenerateTrianglesRenderFine) {
  // Three collinear corners and a triangle with a repeated corner: zero area, nothing to draw, no error.
  add_input("flat.obj", "v 0 0 0\nv 1 0 0\nv 2 0 0\nf 1 2 3\nf 1 1 2\n");
  const CommandResult result =
      run(cli(), render_args({"--set", R"(/objects/0/mesh={"type": "obj", "file": "flat.obj"})"}));
  EXPECT_EQ(result.exit_code, 0) << result.output;
  EXPECT_TRUE(fs::is_regular_file(out_ / "image.png")) << result.output;
}

TEST(CliHelp, EveryOptionIsDocumented) {
  const CommandResult top = run(cli(), {"--help"});
  EXPECT_EQ(top.exit_code, 0) << top.output;
  for (const char* text : {"Usage:", "render", "plan", "docs/scene-format.md"})
    EXPECT_NE(top.output.find(text), std::string::npos) << text << "\n" << top.output;

  const CommandResult render = run(cli(), {"render", "--help"});
  EXPECT_EQ(render.exit_code, 0) << render.output;
  for (const char* option : {"scene", "-o,--output", "--width", "--height", "--threads", "--tile", "--set", "--aov",
                             "depth, normal, uv", "shadow, ao", "--stats", "--timestamp", "--help"})
    EXPECT_NE(render.output.find(option), std::string::npos) << option << "\n" << render.output;

  const CommandResult plan = run(cli(), {"plan", "--help"});
  EXPECT_EQ(plan.exit_code, 0) << plan.output;
  for (const char* option : {"scene", "--set", "--aov", "--json", "--help"})
    EXPECT_NE(plan.output.find(option), std::string::npos) << option << "\n" << plan.output;
}

TEST(CliHelp, NoArgumentsPrintsUsage) {
  const CommandResult result = run(cli(), {});
  EXPECT_EQ(result.exit_code, 2);
  for (const char* text : {"Usage:", "render", "plan"})
    EXPECT_NE(result.output.find(text), std::string::npos) << text << "\n" << result.output;
}

TEST(CliHelp, UnknownOptionIsOneLine) {
  const CommandResult result = run(cli(), {"render", "scene.json", "-o", "x.png", "--widht", "5"});
  EXPECT_EQ(result.exit_code, 2);
  EXPECT_EQ(lines_of(result.output).size(), 1u) << result.output;
  EXPECT_NE(result.output.find("qdmr: error: "), std::string::npos) << result.output;
  EXPECT_NE(result.output.find("--widht"), std::string::npos) << result.output;
}

}  // namespace
}  // namespace qdmr::test
