// qdmr bench's trace report: iterations, lane utilisation and the cost per executed lane-iteration, printed and in
// the JSON for a frame that traces, absent for one that does not.
#include <gtest/gtest.h>

#include <fstream>
#include <string>
#include <vector>

#include <nlohmann/json.hpp>

#include "cli/cli_test_util.hpp"

namespace qdmr::test {
namespace {

nlohmann::json bench(const TempDir& dir, const std::string& technique, std::string& output) {
  const std::string scene = (source_dir() / "bench" / "llvmpipe" / "canonical.json").string();
  const std::string json = (dir / (technique + ".json")).string();
  const CommandResult r = run(cli(), {"bench", scene, "--width", "96", "--height", "54", "--frames", "2", "--warmup",
                                      "0", "--threads", "2", "--set", "/materials/cobbles/technique/name=\"" + technique + "\"",
                                      "--json", json, "--image", (dir / (technique + ".png")).string()});
  EXPECT_EQ(r.exit_code, 0) << r.output;
  output = r.output;
  std::ifstream in(json);
  return nlohmann::json::parse(in);
}

TEST(BenchCommand, ReportsTheTracesCostPerLaneIteration) {
  TempDir dir;
  std::string output;
  const nlohmann::json qdm = bench(dir, "qdm", output);
  const nlohmann::json& it = qdm.at("iterations");
  const double mean = it.at("mean").get<double>(), utilisation = it.at("lane_utilisation").get<double>();
  EXPECT_GT(mean, 1.0);
  EXPECT_GT(utilisation, 0.0);
  EXPECT_LE(utilisation, 1.0);
  // Executed lane-iterations: the useful ones (mean x pixels) over the utilisation, so at least the useful ones.
  const double executed = it.at("lane_iterations_executed").get<double>();
  EXPECT_DOUBLE_EQ(executed, mean * qdm.at("pixels_shaded").get<double>() / utilisation);
  EXPECT_GE(executed, mean * qdm.at("pixels_shaded").get<double>());
  const double ns = it.at("ns_per_lane_iteration").get<double>();
  EXPECT_DOUBLE_EQ(ns, qdm.at("raster_shade_ms").at("median").get<double>() * 1e6 * 2 / executed);
  EXPECT_NE(output.find("ns per executed lane-iteration"), std::string::npos) << output;
  EXPECT_NE(output.find("iterations per pixel"), std::string::npos) << output;

  // Normal mapping traces nothing: no cost per iteration, no trace line.
  const nlohmann::json normal = bench(dir, "normal", output);
  EXPECT_EQ(normal.at("iterations").at("mean").get<double>(), 0.0);
  EXPECT_TRUE(normal.at("iterations").at("ns_per_lane_iteration").is_null());
  EXPECT_EQ(output.find("lane-iteration"), std::string::npos) << output;
}

// A dynamic scene's timed frames are warm frames of its sequence: each after set_frame's rebuild (frames 1, 2, ...
// after the warm-up ones), with the rebuild and rebuild + draw reported; a still scene reports neither.
TEST(BenchCommand, TimesWarmFramesOfADynamicScene) {
  TempDir dir;
  const std::string json = (dir / "water.json").string();
  const CommandResult r =
      run(cli(), {"bench", (source_dir() / "scenes" / "water.json").string(), "--width", "64", "--height", "36",
                  "--frames", "3", "--warmup", "1", "--threads", "2", "--set",
                  "/materials/water/layers/0/height/size=64", "--json", json, "--image",
                  (dir / "water.png").string()});
  ASSERT_EQ(r.exit_code, 0) << r.output;
  std::ifstream in(json);
  const nlohmann::json j = nlohmann::json::parse(in);
  EXPECT_EQ(j.at("sequence_frames"), nlohmann::json::array({2, 3, 4}));
  EXPECT_EQ(j.at("rebuild_ms").at("frames").get<int>(), 3);
  EXPECT_EQ(j.at("frame_ms").at("frames").get<int>(), 3);
  EXPECT_GE(j.at("frame_ms").at("min").get<double>(), j.at("draw_ms").at("min").get<double>());
  EXPECT_NE(r.output.find("frames of the animation (rebuild + draw)"), std::string::npos) << r.output;

  std::string output;
  const nlohmann::json still = bench(dir, "qdm", output);
  EXPECT_FALSE(still.contains("rebuild_ms"));
  EXPECT_FALSE(still.contains("sequence_frames"));
}

// A scene whose only animation is its camera's keyframes is timed frame by frame of its sequence too: the image
// bench writes is the last timed frame (4), which `render --frame 4` draws and which differs from frame 0.
TEST(BenchCommand, TimesFramesOfACameraOnKeyframes) {
  TempDir dir;
  const std::string scene = (source_dir() / "bench" / "llvmpipe" / "canonical.json").string();
  const std::vector<std::string> sets = {
      "--width", "64", "--height", "36", "--set", R"(/animation={"frames": 6, "fps": 24})", "--set",
      R"(/camera={"up": [0, 0, 1], "near": 0.05, "far": 50, "keyframes": [
          {"frame": 0, "position": [0, -1.5, 2.6], "target": [0, 0, 0], "fov_deg": 50},
          {"frame": 5, "position": [1.2, -0.8, 1.4], "target": [0.3, 0.2, 0]}]})"};
  const auto command = [&](std::vector<std::string> args) {
    args.insert(args.end(), sets.begin(), sets.end());
    const CommandResult r = run(cli(), args);
    EXPECT_EQ(r.exit_code, 0) << r.output;
  };
  const std::string json = (dir / "camera.json").string();
  command({"bench", scene, "--frames", "3", "--warmup", "1", "--threads", "2", "--json", json, "--image",
           (dir / "bench.png").string()});
  command({"render", scene, "--frame", "4", "-o", (dir / "frame4.png").string()});
  command({"render", scene, "--frame", "0", "-o", (dir / "frame0.png").string()});
  std::ifstream in(json);
  const nlohmann::json j = nlohmann::json::parse(in);
  EXPECT_EQ(j.at("sequence_frames"), nlohmann::json::array({2, 3, 4}));
  const std::uint64_t bench_image = pixel_hash(read_float_image(dir / "bench.png"));
  EXPECT_EQ(bench_image, pixel_hash(read_float_image(dir / "frame4.png")));
  EXPECT_NE(bench_image, pixel_hash(read_float_image(dir / "frame0.png")));
}

}  // namespace
}  // namespace qdmr::test
