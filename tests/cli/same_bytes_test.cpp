// Same scene, same bytes: two renders of every shipped scene, with different thread counts, write byte-identical
// PNG, EXR and TIFF files (no wall-clock time in them), and --timestamp puts the time back.
#include <gtest/gtest.h>

#include <chrono>
#include <thread>

#include <OpenImageIO/imageio.h>

#include "cli/cli_test_util.hpp"

namespace qdmr::test {
namespace {

// Small: the point is the file bytes, not the pixels (the golden test covers those at 480x270).
constexpr int kSameBytesWidth = 96, kSameBytesHeight = 54;

void render_small(const ShippedScene& scene, const std::vector<std::string>& extra) {
  std::vector<std::string> args{"render"};
  const std::vector<std::string> scene_part = scene_args(scene);
  args.insert(args.end(), scene_part.begin(), scene_part.end());
  args.insert(args.end(), {"--width", std::to_string(kSameBytesWidth), "--height", std::to_string(kSameBytesHeight)});
  args.insert(args.end(), extra.begin(), extra.end());
  const CommandResult result = run(cli(), args);
  ASSERT_EQ(result.exit_code, 0) << scene.name << ":\n" << result.output;
}

// The DateTime OpenImageIO reads back (EXR capDate, TIFF tag 306, PNG tIME), empty when there is none.
std::string date_time(const std::filesystem::path& file) {
  auto in = OIIO::ImageInput::open(file.string());
  if (!in) {
    ADD_FAILURE() << "cannot open " << file << ": " << OIIO::geterror();
    return {};
  }
  return in->spec().get_string_attribute("DateTime");
}

// Two sets of outputs: the colour image as PNG (8-bit sRGB) with AOVs as EXR and TIFF, then the colour image as
// EXR with an AOV as PNG.
const std::vector<std::vector<std::string>> kOutputs = {
    {"image.png", "depth=depth.exr", "normal=normal.tif"},
    {"image.exr", "uv=uv.png"},
};

std::vector<std::string> output_args(const std::filesystem::path& dir, const std::vector<std::string>& outputs) {
  std::vector<std::string> args{"-o", (dir / outputs[0]).string()};
  for (std::size_t i = 1; i < outputs.size(); ++i) {
    const std::string& spec = outputs[i];
    const std::size_t eq = spec.find('=');
    args.insert(args.end(), {"--aov", spec.substr(0, eq + 1) + (dir / spec.substr(eq + 1)).string()});
  }
  return args;
}

std::vector<std::string> files_of(const std::vector<std::string>& outputs) {
  std::vector<std::string> files{outputs[0]};
  for (std::size_t i = 1; i < outputs.size(); ++i) files.push_back(outputs[i].substr(outputs[i].find('=') + 1));
  return files;
}

class CliSameBytes : public testing::TestWithParam<ShippedScene> {};

TEST_P(CliSameBytes, TwoRendersWriteTheSameFiles) {
  const ShippedScene& scene = GetParam();
  if (scene.needs_data && !have_data()) GTEST_SKIP() << "no data at " << data_dir();
  for (const std::vector<std::string>& outputs : kOutputs) {
    const TempDir first, second;
    std::vector<std::string> args = output_args(first.path(), outputs);
    args.insert(args.end(), {"--threads", "1"});
    render_small(scene, args);
    // No wait between the two: a time with one-second resolution could agree by chance, so date_time() below
    // checks that the files hold no time at all (the control test shows it finds one when there is).
    args = output_args(second.path(), outputs);
    args.insert(args.end(), {"--threads", "2"});
    render_small(scene, args);
    for (const std::string& file : files_of(outputs)) {
      const std::string a = read_file(first.path() / file), b = read_file(second.path() / file);
      EXPECT_FALSE(a.empty()) << scene.name << " " << file;
      EXPECT_TRUE(a == b) << scene.name << " " << file << ": the two renders wrote different bytes ("
                          << a.size() << " and " << b.size() << " bytes)";
      EXPECT_EQ(date_time(first.path() / file), "") << scene.name << " " << file << " holds a time";
    }
  }
}

INSTANTIATE_TEST_SUITE_P(Scenes, CliSameBytes, testing::ValuesIn(shipped_scenes()), scene_name);

// The control: with --timestamp every format holds the current time, so renders a second apart differ, which
// is what the test above would see without the fix (OpenImageIO stamps EXR and TIFF by default).
TEST(CliSameBytesControl, TimestampWritesTheTime) {
  const ShippedScene plane{"plane", false};
  const TempDir first, second;
  const std::vector<std::string> outputs = {"image.png", "depth=depth.exr", "normal=normal.tif"};
  std::vector<std::string> args = output_args(first.path(), outputs);
  args.push_back("--timestamp");
  render_small(plane, args);
  std::this_thread::sleep_for(std::chrono::milliseconds(1100));  // DateTime counts whole seconds
  args = output_args(second.path(), outputs);
  args.push_back("--timestamp");
  render_small(plane, args);
  for (const std::string& file : files_of(outputs)) {
    const std::string stamp = date_time(first.path() / file);
    EXPECT_EQ(stamp.size(), std::string("YYYY:MM:DD hh:mm:ss").size()) << file << ": '" << stamp << "'";
    EXPECT_NE(stamp, date_time(second.path() / file)) << file;
    EXPECT_NE(read_file(first.path() / file), read_file(second.path() / file)) << file;
  }
  // PNG's own time chunk (tIME: 7 bytes, the length 0x00000007 before the type), not a text entry.
  const std::string png = read_file(first.path() / "image.png");
  EXPECT_NE(png.find(std::string("\0\0\0\x07tIME", 8)), std::string::npos);
  EXPECT_EQ(png.find("DateTime"), std::string::npos);
}

}  // namespace
}  // namespace qdmr::test
